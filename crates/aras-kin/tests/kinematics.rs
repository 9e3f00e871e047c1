//! Invariants of the kinematics over the whole reachable set, and edge cases.
//!
//! Tolerances: round trips are exact up to a few ulps of the trig functions
//! (1e-12 rad). Finite-difference checks use central differences with step
//! h = 1e-5, whose truncation error is O(h²) ≈ 1e-10 times the third
//! derivative and whose rounding error is ≈ 1e-16/h ≈ 1e-11, so a relative
//! error of 1e-7 is a strict but safe bound away from singularities.

use aras_kin::Motion;
use aras_kin::{
    AssemblyMode, Geometry, KinError, Singularity, Workspace, evaluate, forward, inverse, jacobian,
    link_frames, link_jacobians, singularity_distance,
};
use nalgebra::{Matrix3, Vector2, Vector3};
use proptest::prelude::*;

const H: f64 = 1e-5;

fn deg(v: f64) -> f64 {
    v.to_radians()
}

/// Poses well inside the reachable set of the 45°/45° robot (γ ∈ [5°, 85°]),
/// wider than the workspace box (77), plus any azimuth.
fn pose() -> impl Strategy<Value = Vector2<f64>> {
    (-180.0..180.0f64, 5.0..85.0f64).prop_map(|(p, g)| Vector2::new(deg(p), deg(g)))
}

fn rate() -> impl Strategy<Value = Vector2<f64>> {
    (-3.0..3.0f64, -3.0..3.0f64).prop_map(|(a, b)| Vector2::new(a, b))
}

/// Geometries other than the built one, with a reachable band of γ.
fn geometry() -> impl Strategy<Value = Geometry> {
    (20.0..70.0f64, 20.0..70.0f64).prop_map(|(a, b)| Geometry::from_degrees(a, b).unwrap())
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / (1.0 + b.abs())
}

fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5
}

fn d_of(x: &Vector2<f64>) -> Vector3<f64> {
    Vector3::new(x[1].sin() * x[0].cos(), x[1].sin() * x[0].sin(), x[1].cos())
}

/// A pose in the middle of the reachable γ band of `g`.
fn mid_pose(g: &Geometry, phi: f64, frac: f64) -> Vector2<f64> {
    let (lo, hi) = g.reachable_gamma();
    Vector2::new(phi, lo + (hi - lo) * (0.1 + 0.8 * frac))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn fk_of_ik_is_identity(x in pose()) {
        let g = Geometry::aras_diamond();
        let th = inverse(&g, &x).unwrap().theta;
        let back = forward(&g, &th, AssemblyMode::Plus).unwrap();
        prop_assert!((back - x).norm() < 1e-12, "{x} -> {th} -> {back}");
    }

    #[test]
    fn ik_of_fk_is_identity(phi in -3.0..3.0f64, a in 10.0..85.0f64) {
        let g = Geometry::aras_diamond();
        let th = Vector2::new(phi + deg(a), phi - deg(a));
        let x = forward(&g, &th, AssemblyMode::Plus).unwrap();
        let back = inverse(&g, &x).unwrap().theta;
        prop_assert!((back - th).norm() < 1e-12, "{th} -> {x} -> {back}");
    }

    #[test]
    fn round_trip_on_other_geometries(g in geometry(), phi in -3.0..3.0f64, f in 0.0..1.0f64) {
        let x = mid_pose(&g, phi, f);
        let Ok(ik) = inverse(&g, &x) else { return Ok(()) };
        // Either branch may be the working one for α ≠ β: one of them closes.
        let ok = [AssemblyMode::Plus, AssemblyMode::Minus].iter().any(|m| {
            forward(&g, &ik.theta, *m).map(|b| (b - x).norm() < 1e-11).unwrap_or(false)
        });
        prop_assert!(ok, "no assembly mode reproduces {x}");
    }

    #[test]
    fn loop_closure_and_frames(g in geometry(), phi in -3.0..3.0f64, f in 0.0..1.0f64) {
        let x = mid_pose(&g, phi, f);
        let Ok(r) = link_frames(&g, &x) else { return Ok(()) };
        let (ca, cb) = (g.alpha().cos(), g.beta().cos());
        let a = Vector3::z();
        let d = d_of(&x);
        let b = r[2].column(2).into_owned();
        let c = r[3].column(2).into_owned();
        // Closure: b·d = c·d = cos β, and the elbows sit at arc α from a.
        prop_assert!((b.dot(&d) - cb).abs() < 1e-12);
        prop_assert!((c.dot(&d) - cb).abs() < 1e-12);
        prop_assert!((b.dot(&a) - ca).abs() < 1e-12 && (c.dot(&a) - ca).abs() < 1e-12);
        // Frames are rotations; z is the joint axis, x points along the arc to n.
        for (k, (z, n, arc)) in [(a, b, g.alpha()), (a, c, g.alpha()), (b, d, g.beta()), (c, d, g.beta())]
            .into_iter()
            .enumerate()
        {
            let rk = r[k];
            prop_assert!((rk.transpose() * rk - Matrix3::identity()).norm() < 1e-12);
            prop_assert!((rk.determinant() - 1.0).abs() < 1e-12);
            prop_assert!((rk.column(2) - z).norm() < 1e-12);
            let along = rk.column(2) * arc.cos() + rk.column(0) * arc.sin();
            prop_assert!((along - n).norm() < 1e-12, "link {}", k + 1);
        }
        // Proximal frames are Rz(θ2) for link 1 and Rz(θ1) for link 2.
        let th = inverse(&g, &x).unwrap().theta;
        prop_assert!((r[0][(1, 0)] - th[1].sin()).abs() < 1e-12 && (r[0][(0, 0)] - th[1].cos()).abs() < 1e-12);
        prop_assert!((r[1][(1, 0)] - th[0].sin()).abs() < 1e-12 && (r[1][(0, 0)] - th[0].cos()).abs() < 1e-12);
    }

    #[test]
    fn jacobian_matches_finite_differences(x in pose()) {
        let g = Geometry::aras_diamond();
        let j = jacobian(&g, &x).unwrap().matrix();
        for col in 0..2 {
            let e = Vector2::ith(col, H);
            let fd = (inverse(&g, &(x + e)).unwrap().theta - inverse(&g, &(x - e)).unwrap().theta) / (2.0 * H);
            for row in 0..2 {
                prop_assert!(rel(j[(row, col)], fd[row]) < 1e-7, "J[{row},{col}] = {} vs {}", j[(row, col)], fd[row]);
            }
        }
        let inv = jacobian(&g, &x).unwrap().inverse();
        prop_assert!((inv * j - nalgebra::Matrix2::identity()).norm() < 1e-12);
    }

    #[test]
    fn link_jacobians_match_rotation_rates(g in geometry(), phi in -3.0..3.0f64, f in 0.0..1.0f64, xd in rate()) {
        let x = mid_pose(&g, phi, f);
        let Ok(jw) = link_jacobians(&g, &x) else { return Ok(()) };
        if singularity_distance(&g, &x).unwrap().min().1 < 0.05 { return Ok(()) }
        // Fourth-order central difference: near the parallel singularity of
        // α ≠ β geometries the third derivative of R is large enough that
        // the second-order difference alone misses 1e-7 (seen: 3.7e-7).
        let at = |s: f64| link_frames(&g, &(x + xd * (s * H))).unwrap();
        let (r1, m1, r2, m2) = (at(1.0), at(-1.0), at(2.0), at(-2.0));
        let r0 = link_frames(&g, &x).unwrap();
        for k in 0..4 {
            // [Ω]× = Ṙ Rᵀ
            let r_dot = ((r1[k] - m1[k]) * 8.0 - (r2[k] - m2[k])) / (12.0 * H);
            let omega_fd = vee(&(r_dot * r0[k].transpose()));
            let omega = jw[k] * xd;
            prop_assert!((omega - omega_fd).norm() <= 1e-7 * (1.0 + omega.norm()), "link {}: {omega} vs {omega_fd}", k + 1);
        }
    }

    #[test]
    fn accelerations_match_finite_differences(x in pose(), xd in rate(), xdd in rate()) {
        let g = Geometry::aras_diamond();
        // Along the parabola X(t) = X + Ẋ t + ½ Ẍ t², the derivative of Ω_k and θ̇ at t = 0.
        let at = |t: f64| evaluate(&g, &Motion::new(x + xd * t + xdd * (0.5 * t * t), xd + xdd * t, xdd)).unwrap();
        let (p, m, s) = (at(H), at(-H), at(0.0));
        for k in 0..4 {
            let fd = (p.omega[k] - m.omega[k]) / (2.0 * H);
            prop_assert!((s.omega_dot[k] - fd).norm() <= 1e-7 * (1.0 + fd.norm()), "link {}", k + 1);
            let jfd = (p.link_jacobians[k] - m.link_jacobians[k]) / (2.0 * H);
            prop_assert!((s.link_jacobian_dots[k] - jfd).norm() <= 1e-7 * (1.0 + jfd.norm()));
        }
        let fd = (p.joint.vel - m.joint.vel) / (2.0 * H);
        prop_assert!((s.joint.acc - fd).norm() <= 1e-7 * (1.0 + fd.norm()));
        let fd = (p.joint.pos - m.joint.pos) / (2.0 * H);
        prop_assert!((s.joint.vel - fd).norm() <= 1e-7 * (1.0 + fd.norm()));
    }

    #[test]
    fn forward_motion_inverts_the_motor_motion(x in pose(), xd in rate(), xdd in rate()) {
        let g = Geometry::aras_diamond();
        let s = evaluate(&g, &Motion::new(x, xd, xdd)).unwrap();
        let back = aras_kin::forward_motion(&g, &s.joint, AssemblyMode::Plus).unwrap();
        prop_assert!((back.pos - x).norm() < 1e-12);
        prop_assert!((back.vel - xd).norm() < 1e-11 * (1.0 + xd.norm()));
        prop_assert!((back.acc - xdd).norm() < 1e-10 * (1.0 + xdd.norm() + xd.norm_squared()));
    }

    #[test]
    fn sample_agrees_with_single_functions(x in pose(), xd in rate(), xdd in rate()) {
        let g = Geometry::aras_diamond();
        let s = evaluate(&g, &Motion::new(x, xd, xdd)).unwrap();
        prop_assert_eq!(s.joint.pos, inverse(&g, &x).unwrap().theta);
        prop_assert_eq!(s.rotations, link_frames(&g, &x).unwrap());
        prop_assert_eq!(s.link_jacobians, link_jacobians(&g, &x).unwrap());
        prop_assert_eq!(s.jacobian, jacobian(&g, &x).unwrap());
    }

    #[test]
    fn non_finite_inputs_are_named(x in pose(), which in 0usize..6, bad in prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)]) {
        let g = Geometry::aras_diamond();
        let mut v = [x[0], x[1], 0.1, 0.2, 0.3, 0.4];
        v[which] = bad;
        let names = ["phi", "gamma", "phi_dot", "gamma_dot", "phi_ddot", "gamma_ddot"];
        let err = evaluate(&g, &Motion::new(Vector2::new(v[0], v[1]), Vector2::new(v[2], v[3]), Vector2::new(v[4], v[5]))).unwrap_err();
        prop_assert!(matches!(err, KinError::NonFinite { name, .. } if name == names[which]), "{err}");
    }
}

#[test]
fn spec_numeric_check() {
    // docs/kinematics.md, "Jacobian": at φ = 85°, γ = 60°, α = β = 45°: A = 54.7356°, |dA/dγ| = 0.816497.
    let g = Geometry::aras_diamond();
    let x = Vector2::new(deg(85.0), deg(60.0));
    let ik = inverse(&g, &x).unwrap();
    assert!((ik.passive.a.to_degrees() - 54.7356).abs() < 5e-5);
    let k = jacobian(&g, &x).unwrap().k();
    assert!((k.abs() - 0.816497).abs() < 5e-7);
    // Sign (docs/kinematics.md): our K is dA/dγ, which is negative here.
    assert!(k < 0.0);
    assert_eq!(
        ik.theta,
        Vector2::new(x[0] + ik.passive.a, x[0] - ik.passive.a)
    );
    // B = C, and Ω3 from docs/kinematics.md (link angular velocities).
    assert_eq!(ik.passive.b, ik.passive.c);
    let s = evaluate(
        &g,
        &Motion::new(x, Vector2::new(0.3, -0.7), Vector2::zeros()),
    )
    .unwrap();
    assert!((s.omega[2] - Vector3::new(0.74048, 0.43208, 0.58577)).norm() < 1e-5);
    // Our elbow rate μ equals −G of (17): G = sin γ/(sin β sin α sin B).
    let gg = x[1].sin() / (g.beta().sin() * g.alpha().sin() * ik.passive.b.sin());
    let b = s.rotations[2].column(2);
    // Ω3 − Ω1 = μ γ̇ b, so its component along b divided by γ̇:
    let rel_rate = (s.omega[2] - s.omega[0]).dot(&b) / -0.7;
    assert!((rel_rate + gg).abs() < 1e-12, "μ = {rel_rate}, G = {gg}");
}

#[test]
fn passive_angles_satisfy_the_cosine_rules() {
    let g = Geometry::aras_diamond();
    let x = Vector2::new(deg(100.0), deg(70.0));
    let p = inverse(&g, &x).unwrap().passive;
    let (sa, ca, sb, cb, sg, cg) = (
        g.alpha().sin(),
        g.alpha().cos(),
        g.beta().sin(),
        g.beta().cos(),
        x[1].sin(),
        x[1].cos(),
    );
    assert!((p.a.cos() - (cb - cg * ca) / (sg * sa)).abs() < 1e-14);
    assert!((p.b.cos() - (cg - cb * ca) / (sb * sa)).abs() < 1e-14);
    assert!((p.d.cos() - (ca - cg * cb) / (sg * sb)).abs() < 1e-14);
}

#[test]
fn unreachable_gamma_is_an_error() {
    let g = Geometry::aras_diamond();
    for gamma in [deg(95.0), deg(-10.0), 4.0] {
        let err = inverse(&g, &Vector2::new(1.0, gamma)).unwrap_err();
        assert!(matches!(err, KinError::Unreachable { .. }), "{err}");
        assert!(
            err.to_string().contains("unreachable") && err.to_string().contains("90.000000°"),
            "{err}"
        );
    }
}

#[test]
fn singular_poses_are_named() {
    let g = Geometry::aras_diamond();
    // γ = α + β: elbows stretched, A = 0.
    let err = evaluate(
        &g,
        &Motion::new(
            Vector2::new(1.0, deg(90.0)),
            Vector2::zeros(),
            Vector2::zeros(),
        ),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            KinError::Singular {
                which: Singularity::ProximalAligned | Singularity::ElbowStretched,
                ..
            }
        ),
        "{err}"
    );
    // γ = 0: end-effector on the motor axis (0/0 in the cosine rule must not leak NaN).
    let err = inverse(&g, &Vector2::new(1.0, 0.0)).unwrap_err();
    assert!(matches!(err, KinError::Singular { .. }), "{err}");
    let err = jacobian(&g, &Vector2::new(1.0, 1e-7)).unwrap_err();
    assert!(matches!(err, KinError::Singular { .. }), "{err}");
    assert!(err.to_string().contains("below the tolerance"), "{err}");
    // A tighter tolerance rejects poses the default accepts.
    let near = Vector2::new(1.0, deg(89.99));
    assert!(inverse(&g, &near).is_ok());
    let strict = g.with_singularity_tolerance(0.1).unwrap();
    assert!(matches!(
        inverse(&strict, &near),
        Err(KinError::Singular { .. })
    ));
    // α ≠ β with a parallel singularity inside the reach band: cos γ = cos α / cos β.
    let g2 = Geometry::from_degrees(60.0, 30.0).unwrap();
    let gamma = (g2.alpha().cos() / g2.beta().cos()).acos();
    let err = jacobian(&g2, &Vector2::new(0.0, gamma)).unwrap_err();
    assert!(
        matches!(
            err,
            KinError::Singular {
                which: Singularity::Parallel,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn invalid_geometry_is_an_error() {
    for (a, b, name) in [
        (0.0, 45.0, "alpha"),
        (180.0, 45.0, "alpha"),
        (45.0, -3.0, "beta"),
        (45.0, 200.0, "beta"),
    ] {
        let err = Geometry::from_degrees(a, b).unwrap_err();
        assert!(
            matches!(err, KinError::InvalidGeometry { name: n, .. } if n == name),
            "{err}"
        );
        assert!(err.to_string().contains("strictly between 0° and 180°"));
    }
    assert!(matches!(
        Geometry::new(f64::NAN, 1.0),
        Err(KinError::NonFinite { name: "alpha", .. })
    ));
    assert!(
        Geometry::aras_diamond()
            .with_singularity_tolerance(0.0)
            .is_err()
    );
    assert!(
        Geometry::aras_diamond()
            .with_singularity_tolerance(f64::NAN)
            .is_err()
    );
}

#[test]
fn forward_rejects_crossed_or_unassemblable_motors() {
    let g = Geometry::aras_diamond();
    // θ1 < θ2: A < 0 is the mirrored configuration, not this assembly.
    let err = forward(&g, &Vector2::new(0.0, 1.0), AssemblyMode::Plus).unwrap_err();
    assert!(matches!(err, KinError::NoAssembly { .. }), "{err}");
    // Elbows 180° apart cannot be joined by two 45° arcs.
    let g2 = Geometry::from_degrees(80.0, 30.0).unwrap();
    let err = forward(&g2, &Vector2::new(1.5, -1.5), AssemblyMode::Plus).unwrap_err();
    assert!(matches!(err, KinError::NoAssembly { .. }), "{err}");
    // Degenerate branch for α = β is γ = 0: singular.
    let err = forward(&g, &Vector2::new(0.8, -0.8), AssemblyMode::Minus).unwrap_err();
    assert!(matches!(err, KinError::Singular { .. }), "{err}");
    assert!(matches!(
        forward(&g, &Vector2::new(f64::NAN, 0.0), AssemblyMode::Plus),
        Err(KinError::NonFinite { name: "theta1", .. })
    ));
}

#[test]
fn workspace_box_and_rates() {
    let w = Workspace::paper();
    assert!(w.check_pose(&Vector2::new(deg(85.0), deg(60.0))).is_ok());
    let err = w
        .check_pose(&Vector2::new(deg(85.0), deg(85.0)))
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "gamma = 85.000000° is outside the workspace [40.000000°, 80.000000°] (the paper's (77))"
    );
    let err = w.check_rate(&Vector2::new(deg(250.0), 0.0)).unwrap_err();
    assert!(
        err.to_string()
            .starts_with("phi_dot = 250.000000°/s is outside"),
        "{err}"
    );
    assert!(
        Workspace::new(
            Vector2::new(1.0, 1.0),
            Vector2::new(0.0, 2.0),
            Vector2::new(1.0, 1.0)
        )
        .is_err()
    );
    assert!(
        Workspace::new(
            Vector2::new(0.0, 1.0),
            Vector2::new(1.0, 2.0),
            Vector2::new(0.0, 1.0)
        )
        .is_err()
    );
}

#[test]
fn workspace_is_far_from_singularities() {
    // The paper's box has no singularity: every distance stays above 0.2.
    let g = Geometry::aras_diamond();
    let w = Workspace::paper();
    for i in 0..=20 {
        for j in 0..=20 {
            let x = w.min()
                + (w.max() - w.min())
                    .component_mul(&Vector2::new(i as f64 / 20.0, j as f64 / 20.0));
            let (which, d) = singularity_distance(&g, &x).unwrap().min();
            assert!(d > 0.2, "{which} = {d} at {x}");
        }
    }
}

#[test]
fn condition_number_of_j() {
    let g = Geometry::aras_diamond();
    let j = jacobian(&g, &Vector2::new(1.0, deg(60.0))).unwrap();
    let sv = j.matrix().singular_values();
    let cond = sv.max() / sv.min();
    assert!((j.condition_number() - cond).abs() < 1e-12 * cond);
}

#[cfg(feature = "dual")]
#[test]
fn dual_numbers_give_exact_derivatives() {
    use num_dual::DualSVec64;
    type D = DualSVec64<2>;
    let g = Geometry::aras_diamond();
    let x0 = Vector2::new(deg(85.0), deg(60.0));
    let xd = Vector2::new(0.3, -0.7);
    let x = Vector2::new(D::from(x0[0]).derivative(0), D::from(x0[1]).derivative(1));
    let lift = |v: &Vector2<f64>| v.map(D::from);
    let s = evaluate(&g, &Motion::new(x, lift(&xd), lift(&Vector2::zeros()))).unwrap();
    // dθ/dX from the dual part equals the Jacobian.
    let j = jacobian(&g, &x0).unwrap().matrix();
    for r in 0..2 {
        let eps = s.joint.pos[r]
            .eps
            .unwrap_generic(nalgebra::Const::<2>, nalgebra::Const::<1>);
        for c in 0..2 {
            assert!((eps[c] - j[(r, c)]).abs() < 1e-13);
        }
    }
    // Real parts equal the f64 evaluation.
    let f = evaluate(&g, &Motion::new(x0, xd, Vector2::zeros())).unwrap();
    for k in 0..4 {
        for i in 0..3 {
            assert!((s.omega[k][i].re - f.omega[k][i]).abs() < 1e-15);
        }
    }
}
