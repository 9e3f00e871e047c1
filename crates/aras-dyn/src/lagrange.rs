//! An independent second formulation of the rigid-body dynamics: Lagrange's
//! equations with every derivative taken exactly by dual numbers.
//!
//! Nothing here uses `aras-kin`'s Jacobians or the virtual-work code. The
//! link rotations are rebuilt from `docs/kinematics.md` (unit vectors `b`, `c`, `d` from
//! the inverse kinematics (1)–(2), frames `y = z×n/|z×n|`, `x = y×z`); the
//! body angular velocity is `vee(Rᵀ Ṙ)` with `Ṙ` from a first-order dual
//! number along `Ẋ`; the kinetic energy `T = ½ Σ ωᵀ I ω` and the potential
//! `V = −Σ gᵀ R h` are then differentiated with second-order duals:
//!
//! * `M = ∂²T/∂Ẋ²` (the Hessian of the kinetic energy),
//! * `c = (∂²T/∂Ẋ∂X) Ẋ − ∂T/∂X` (the Christoffel terms, as in
//!   `d/dt ∂T/∂Ẋ − ∂T/∂X = M Ẍ + c`),
//! * `g = ∂V/∂X`,
//!
//! so that `M Ẍ + c + g = Jᵀ τ_links` must match (33) and (80).

use nalgebra::{Matrix2, SVector, Vector2};
use num_dual::{Dual, Dual2SVec64, DualNum, DualSVec64, gradient, hessian};

use crate::{DynError, Params};

/// The terms of `M(X) Ẍ + c(X, Ẋ) + g(X) = Jᵀ τ_links` in task space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LagrangeTerms {
    /// Mass matrix `∂²T/∂Ẋ²`.
    pub mass: Matrix2<f64>,
    /// Coriolis/centrifugal term.
    pub coriolis: Vector2<f64>,
    /// Gravity term `∂V/∂X`.
    pub gravity: Vector2<f64>,
    /// Kinetic energy (J).
    pub kinetic: f64,
    /// Potential energy (J).
    pub potential: f64,
}

type M3<D> = [[D; 3]; 3];
type V3<D> = [D; 3];

fn cross<D: DualNum<Primitive = f64> + Copy>(a: &V3<D>, b: &V3<D>) -> V3<D> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `R = [x y z]` from a joint axis `z` and the next axis `n`.
fn frame<D: DualNum<Primitive = f64> + Copy>(z: &V3<D>, n: &V3<D>) -> M3<D> {
    let y = cross(z, n);
    let norm = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
    let y = [y[0] / norm, y[1] / norm, y[2] / norm];
    let x = cross(&y, z);
    let mut r = [[D::from(0.0); 3]; 3];
    for i in 0..3 {
        r[i] = [x[i], y[i], z[i]];
    }
    r
}

/// Link rotations 1–4 from `docs/kinematics.md` at `X = [φ, γ]`.
fn rotations<D: DualNum<Primitive = f64> + Copy>(
    alpha: f64,
    beta: f64,
    phi: D,
    gamma: D,
) -> [M3<D>; 4] {
    let (sa, ca, cb) = (alpha.sin(), alpha.cos(), beta.cos());
    let cos_big_a = (-gamma.cos() * ca + cb) / (gamma.sin() * sa);
    let big_a = cos_big_a.acos();
    let (t1, t2) = (phi + big_a, phi - big_a);
    let c = D::from(ca);
    let a = [D::from(0.0), D::from(0.0), D::from(1.0)];
    let b = [t2.cos() * sa, t2.sin() * sa, c];
    let cv = [t1.cos() * sa, t1.sin() * sa, c];
    let d = [
        gamma.sin() * phi.cos(),
        gamma.sin() * phi.sin(),
        gamma.cos(),
    ];
    [frame(&a, &b), frame(&a, &cv), frame(&b, &d), frame(&cv, &d)]
}

/// Kinetic and potential energy at `(X, Ẋ)` (generic, so it can be
/// differentiated), with `Ṙ` from a dual number along `Ẋ`.
fn energies<D: DualNum<Primitive = f64> + Copy>(p: &Params, x: [D; 2], xd: [D; 2]) -> (D, D) {
    let (alpha, beta) = (p.alpha_deg.to_radians(), p.beta_deg.to_radians());
    let rs = rotations(alpha, beta, Dual::new(x[0], xd[0]), Dual::new(x[1], xd[1]));
    let mut t = D::from(0.0);
    let mut v = D::from(0.0);
    for (k, r) in rs.iter().enumerate() {
        // Body angular velocity: S = Rᵀ Ṙ is skew, ω = vee(S).
        let s =
            |i: usize, j: usize| (0..3).fold(D::from(0.0), |acc, m| acc + r[m][i].re * r[m][j].eps);
        let w = [
            (s(2, 1) - s(1, 2)) * 0.5,
            (s(0, 2) - s(2, 0)) * 0.5,
            (s(1, 0) - s(0, 1)) * 0.5,
        ];
        let inertia = p.links[k].inertia();
        for i in 0..3 {
            for j in 0..3 {
                t += w[i] * w[j] * (0.5 * inertia[(i, j)]);
            }
        }
        let h = p.links[k].h;
        for (row, g) in r.iter().zip(p.gravity.iter()) {
            let rh = row[0].re * h.x + row[1].re * h.y + row[2].re * h.z;
            v -= rh * *g;
        }
    }
    (t, v)
}

/// `M`, `c`, `g` and the energies by Lagrange's equations at `(X, Ẋ)`.
pub fn lagrange_terms(
    params: &Params,
    x: &Vector2<f64>,
    x_dot: &Vector2<f64>,
) -> Result<LagrangeTerms, DynError> {
    params.validate()?;
    // Reject what the kinematics would reject (unreachable / singular).
    aras_kin::evaluate(
        &params.geometry()?,
        &aras_kin::Motion::new(*x, *x_dot, Vector2::zeros()),
    )?;
    let z = SVector::<f64, 4>::new(x[0], x[1], x_dot[0], x_dot[1]);
    let (kinetic, grad, h) = hessian(
        |z: SVector<Dual2SVec64<4>, 4>| energies(params, [z[0], z[1]], [z[2], z[3]]).0,
        &z,
    );
    let q = SVector::<f64, 2>::new(x[0], x[1]);
    let zero = *x_dot * 0.0;
    let (potential, dv) = gradient(
        |q: SVector<DualSVec64<2>, 2>| {
            let c = |v: f64| DualSVec64::<2>::from_re(v);
            energies(params, [q[0], q[1]], [c(zero[0]), c(zero[1])]).1
        },
        &q,
    );
    let mass = h.fixed_view::<2, 2>(2, 2).into_owned();
    let mixed = h.fixed_view::<2, 2>(2, 0).into_owned();
    let coriolis = mixed * x_dot - Vector2::new(grad[0], grad[1]);
    Ok(LagrangeTerms {
        mass,
        coriolis,
        gravity: Vector2::new(dv[0], dv[1]),
        kinetic,
        potential,
    })
}
