//! Independent validation of the dynamics: Lagrange formulation, energy
//! balance, mass-matrix properties, forward/inverse consistency.

use aras_dyn::{Dynamics, Params, Sinusoid, Trajectory, lagrange_terms};
use aras_kin::Motion;
use aras_kin::{Geometry, Workspace, evaluate};
use nalgebra::{Matrix2, Vector2, Vector3};
use proptest::prelude::*;

fn rel(a: f64, b: f64, scale: f64) -> f64 {
    (a - b).abs() / scale
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Lagrange (Hessian of T, Christoffel terms by exact differentiation,
    /// rotations rebuilt from `docs/kinematics.md`) against virtual work (33)/(80).
    /// Both are exact formulas evaluated in double precision, so they agree
    /// to rounding (~1e-14); 1e-10 relative is the bound.
    #[test]
    fn lagrange_matches_virtual_work(phi in 0.3f64..2.8, gamma in 0.25f64..1.45,
                                     pd in -4f64..4.0, gd in -4f64..4.0,
                                     gx in -10f64..10.0, gz in -10f64..10.0) {
        let mut p = Params::aras_diamond();
        p.gravity = Vector3::new(gx, -9.81, gz);
        let dy = Dynamics::new(&p).unwrap();
        let (x, xd) = (Vector2::new(phi, gamma), Vector2::new(pd, gd));
        let Ok(s) = evaluate(dy.geometry(), &Motion::new(x, xd, Vector2::zeros())) else { return Ok(()) };
        let l = lagrange_terms(&p, &x, &xd).unwrap();
        let m = dy.mass_matrix(&s);
        let mscale = m.norm();
        prop_assert!((l.mass - m).norm() <= 1e-10 * mscale, "M {} vs {}", l.mass, m);
        let c = dy.coriolis(&s);
        let cscale = m.norm() * xd.norm_squared() + 1e-12;
        prop_assert!((l.coriolis - c).norm() <= 1e-10 * cscale, "c {} vs {}", l.coriolis, c);
        let g = dy.gravity_torque(&s);
        let gscale = p.links.iter().map(|l| l.h.norm()).sum::<f64>() * p.gravity.norm();
        prop_assert!((l.gravity - g).norm() <= 1e-10 * gscale, "g {} vs {}", l.gravity, g);
        prop_assert!(rel(l.kinetic, dy.kinetic_energy(&s), 0.5 * cscale) <= 1e-10);
        prop_assert!(rel(l.potential, dy.potential_energy(&s), gscale) <= 1e-10);
    }

    /// Forward dynamics inverts inverse dynamics (with friction and
    /// elasticity). Solving a 2×2 SPD system loses at most cond(M) ≈ 1e2
    /// digits of 1e-16, so 1e-10 is generous.
    #[test]
    fn forward_inverts_inverse(phi in 0.6f64..2.4, gamma in 0.7f64..1.4,
                               pd in -3f64..3.0, gd in -3f64..3.0, pdd in -40f64..40.0, gdd in -40f64..40.0) {
        let dy = Dynamics::new(&Params::aras_diamond()).unwrap();
        let (x, xd, xdd) = (Vector2::new(phi, gamma), Vector2::new(pd, gd), Vector2::new(pdd, gdd));
        let s = dy.sample(&Motion::new(x, xd, xdd)).unwrap();
        let tau = dy.inverse(&s);
        let back = dy.forward(&x, &xd, &tau).unwrap();
        prop_assert!((back - xdd).norm() <= 1e-10 * (1.0 + xdd.norm()), "{back} vs {xdd}");
    }
}

/// `M(X)` is symmetric positive definite over the workspace (77), in task
/// and motor space, with bounded eigenvalues (reported).
#[test]
fn mass_matrix_spd_over_workspace() {
    let dy = Dynamics::new(&Params::aras_diamond()).unwrap();
    let w = Workspace::paper();
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for i in 0..=40 {
        for j in 0..=40 {
            let x = w.min()
                + (w.max() - w.min())
                    .component_mul(&Vector2::new(i as f64 / 40.0, j as f64 / 40.0));
            let s = dy
                .sample(&Motion::new(x, Vector2::zeros(), Vector2::zeros()))
                .unwrap();
            for m in [dy.mass_matrix(&s), dy.mass_matrix_motor(&s)] {
                assert!((m - m.transpose()).norm() <= 1e-15 * m.norm());
                let e = m.symmetric_eigenvalues();
                assert!(e.min() > 0.0, "not PD at {x}: {e}");
            }
            let e = dy.mass_matrix_motor(&s).symmetric_eigenvalues();
            lo = lo.min(e.min());
            hi = hi.max(e.max());
        }
    }
    println!("motor-space mass matrix eigenvalues over (77): [{lo:.4e}, {hi:.4e}] kg·m²");
    assert!(lo > 1e-4 && hi < 1.0);
}

/// Gauss–Legendre 5-point weights on [−1, 1].
const GL5: [(f64, f64); 5] = [
    (0.0, 0.5688888888888889),
    (-0.5384693101056831, 0.4786286704993665),
    (0.5384693101056831, 0.4786286704993665),
    (-0.906179845938664, 0.23692688505618908),
    (0.906179845938664, 0.23692688505618908),
];

/// `∫ τᵀ θ̇ dt` and `ΔE` along a trajectory on [0, t_end] without friction
/// or elasticity. Composite 5-point Gauss–Legendre on 2000 panels is exact
/// to ~1e-15 relative for these analytic integrands.
fn energy_balance(traj: &dyn Trajectory, t_end: f64) -> (f64, f64, f64) {
    let mut p = Params::aras_diamond();
    p.friction = Default::default();
    p.elasticity = [0.0; 2];
    let dy = Dynamics::new(&p).unwrap();
    let energy = |t: f64| {
        let s = dy.sample(&traj.eval(t)).unwrap();
        dy.kinetic_energy(&s) + dy.potential_energy(&s)
    };
    let panels = 2000;
    let h = t_end / panels as f64;
    let (mut work, mut abs_work) = (0.0, 0.0);
    for k in 0..panels {
        let mid = (k as f64 + 0.5) * h;
        for (xi, wi) in GL5 {
            let t = mid + 0.5 * h * xi;
            let s = dy.sample(&traj.eval(t)).unwrap();
            let pw = dy.inverse(&s).dot(&s.joint.vel);
            work += 0.5 * h * wi * pw;
            abs_work += 0.5 * h * wi * pw.abs();
        }
    }
    (work, energy(t_end) - energy(0.0), abs_work)
}

/// A random finite Fourier series (74)–(76) around the workspace centre.
struct Fourier {
    a: [[f64; 5]; 2],
    b: [[f64; 5]; 2],
    x0: [f64; 2],
    wf: f64,
}

impl Trajectory for Fourier {
    fn eval(&self, t: f64) -> Motion {
        let mut out = Motion::default();
        for i in 0..2 {
            out.pos[i] = self.x0[i];
            for l in 0..5 {
                let wl = self.wf * (l + 1) as f64;
                let (s, c) = (wl * t).sin_cos();
                out.pos[i] += self.a[i][l] / wl * s - self.b[i][l] / wl * c;
                out.vel[i] += self.a[i][l] * c + self.b[i][l] * s;
                out.acc[i] += -self.a[i][l] * wl * s + self.b[i][l] * wl * c;
            }
        }
        out
    }
    fn period(&self) -> Option<f64> {
        Some(2.0 * std::f64::consts::PI / self.wf)
    }
}

#[test]
fn energy_balance_trajectory_47() {
    // Not a whole period (π s), where ΔE would be zero.
    for t_end in [0.9, 2.3] {
        let (work, de, abs_work) = energy_balance(&Sinusoid::paper_47(), t_end);
        let err = (work - de).abs() / abs_work;
        println!("(47) to {t_end} s: work {work:.12e}, ΔE {de:.12e}, rel {err:.2e}");
        assert!(err <= 1e-8, "relative error {err:e}");
    }
}

#[test]
fn energy_balance_random_fourier() {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    for _ in 0..5 {
        let mut f = Fourier {
            a: [[0.0; 5]; 2],
            b: [[0.0; 5]; 2],
            x0: [85f64.to_radians(), 60f64.to_radians()],
            wf: 2.0 * std::f64::consts::PI / 10.0,
        };
        for i in 0..2 {
            for l in 0..5 {
                // Amplitude ≤ Σ|a|/(ω l) keeps γ within ~±15° of 60°.
                f.a[i][l] = rng.random_range(-0.12..0.12);
                f.b[i][l] = rng.random_range(-0.12..0.12);
            }
        }
        let (work, de, abs_work) = energy_balance(&f, 7.3);
        let err = (work - de).abs() / abs_work;
        assert!(err <= 1e-8, "relative error {err:e}");
    }
}

/// Mass matrix scales with inertia and is the Hessian of the kinetic energy
/// along any direction: `T = ½ Ẋᵀ M Ẋ`.
#[test]
fn kinetic_energy_is_quadratic_form() {
    let dy = Dynamics::new(&Params::aras_diamond()).unwrap();
    let g = Geometry::aras_diamond();
    let x = Vector2::new(1.5, 1.1);
    let xd = Vector2::new(0.7, -1.3);
    let s = evaluate(&g, &Motion::new(x, xd, Vector2::zeros())).unwrap();
    let m: Matrix2<f64> = dy.mass_matrix(&s);
    let t = 0.5 * xd.dot(&(m * xd));
    assert!((t - dy.kinetic_energy(&s)).abs() <= 1e-14 * t);
}

#[test]
fn forward_rejects_inconsistent_inertia() {
    let mut p = Params::aras_diamond();
    for l in &mut p.links {
        l.ixx = -1.0;
        l.iyy = -1.0;
        l.izz = -1.0;
    }
    let dy = Dynamics::new(&p).unwrap();
    let e = dy
        .forward(
            &Vector2::new(1.4, 1.0),
            &Vector2::zeros(),
            &Vector2::zeros(),
        )
        .unwrap_err();
    assert!(e.to_string().contains("not positive definite"), "{e}");
    let e = dy
        .forward(
            &Vector2::new(1.4, 3.0),
            &Vector2::zeros(),
            &Vector2::zeros(),
        )
        .unwrap_err();
    assert!(e.to_string().contains("unreachable"), "{e}");
}
