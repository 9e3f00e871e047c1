//! The friction effect's Coulomb transition width `w`: the sign law (49) at
//! `w = 0`, `Y β` against the direct dynamics for `w > 0`, the width's
//! derivative, and its place in the parameter file.

use aras_dyn::{Dynamics, Effect, Model, Params, Sign, coulomb_law, coulomb_law_dw};
use aras_kin::{Geometry, Motion, evaluate};
use nalgebra::Vector2;
use proptest::prelude::*;

fn sample(phi: f64, gamma: f64, pd: f64, gd: f64) -> aras_kin::KinematicSample {
    let g = Geometry::aras_diamond();
    evaluate(
        &g,
        &Motion::new(
            Vector2::new(phi, gamma),
            Vector2::new(pd, gd),
            Vector2::new(1.5, -2.0),
        ),
    )
    .unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// `w = 0` is the sign law exactly: every column, bit for bit, equal to
    /// the paper's model with the exact sign.
    #[test]
    fn zero_width_is_the_sign_law(phi in 0.6f64..2.4, gamma in 0.75f64..1.3,
                                  pd in -3f64..3.0, gd in -3f64..3.0) {
        let s = sample(phi, gamma, pd, gd);
        let paper = Model::paper(Params::aras_diamond().gravity).unwrap();
        let zero = Model::new(
            vec![Effect::RigidLinks, Effect::Friction { w: [0.0, 0.0] }, Effect::Elasticity],
            paper.gravity(),
        ).unwrap();
        let (a, b) = (paper.regressor(&s), zero.regressor(&s));
        prop_assert_eq!(a.as_slice(), b.as_slice());
        let r = paper.column_range("friction").unwrap();
        prop_assert_eq!(a[(0, r.start + 1)], s.joint.vel[0].signum());
        prop_assert_eq!(a[(1, r.start + 3)], s.joint.vel[1].signum());
    }

    /// `Y β` equals `Dynamics::inverse` with widths > 0 on both joints (and
    /// the tanh law in both): two evaluations of O(1) N·m sums, 1e-12.
    #[test]
    fn y_beta_equals_direct_with_width(phi in 0.6f64..2.4, gamma in 0.75f64..1.3,
                                       pd in -0.3f64..0.3, gd in -0.3f64..0.3,
                                       w1 in 1e-4f64..1.0, w2 in 1e-4f64..1.0) {
        let s = sample(phi, gamma, pd, gd);
        let mut p = Params::aras_diamond();
        p.friction.width = [w1, w2];
        let model = p.model().unwrap();
        prop_assert_eq!(model.effects()[1], Effect::Friction { w: [w1, w2] });
        let tau_y = model.regressor(&s) * p.standard_vector(&model).unwrap();
        let dy = Dynamics::new(&p).unwrap();
        let tau_d = dy.inverse(&s);
        prop_assert!((tau_y - tau_d).norm() <= 1e-12 * (1.0 + tau_d.norm()));
        // The width changes the torque (the test would see a model that
        // ignores it): against the sign law, by Fc (1 − tanh(|v|/w)).
        let mut sign = p.clone();
        sign.friction.width = [0.0; 2];
        let d = tau_d - Dynamics::new(&sign).unwrap().inverse(&s);
        for j in 0..2 {
            let v = s.joint.vel[j];
            let expect = p.friction.coulomb[j] * ((v / p.friction.width[j]).tanh() - v.signum());
            prop_assert!((d[j] - expect).abs() <= 1e-12);
        }
    }

    /// The columns' derivative in `w_j`: the `Fc_j` entry of joint `j`'s
    /// row by `coulomb_law_dw`, every other entry 0, against central
    /// differences (step 1e-6 w: truncation ~1e-12 relative, rounding
    /// ~1e-10 of the entry's scale).
    #[test]
    fn width_derivative_matches_finite_differences(pd in -0.5f64..0.5, gd in -0.5f64..0.5,
                                                    w in 1e-3f64..0.5, j in 0usize..2) {
        let s = sample(1.2, 1.0, pd, gd);
        let g = Params::aras_diamond().gravity;
        let at = |wj: f64| {
            let mut ws = [0.02, 0.07];
            ws[j] = wj;
            Model::new(vec![Effect::RigidLinks, Effect::Friction { w: ws }, Effect::Elasticity], g)
                .unwrap()
                .regressor(&s)
        };
        let h = 1e-6 * w;
        let fd = (at(w + h) - at(w - h)) / (2.0 * h);
        let c = 36 + 1 + 2 * j;
        let v = s.joint.vel[j];
        let analytic = coulomb_law_dw(v, w);
        let scale = (v / (w * w)).abs().max(1.0 / w);
        prop_assert!((fd[(j, c)] - analytic).abs() <= 1e-6 * scale, "{} vs {}", fd[(j, c)], analytic);
        let mut rest = fd.clone();
        rest[(j, c)] = 0.0;
        prop_assert!(rest.norm() == 0.0);
        prop_assert_eq!(coulomb_law(v, w), (v / w).tanh());
    }
}

/// A width overrides the caller's sign model on its joint only; a joint
/// with width 0 takes the caller's (the simulator's smoothing).
#[test]
fn width_overrides_the_sign_model_per_joint() {
    let s = sample(1.2, 1.0, 0.01, -0.02);
    let m = Model::new(
        vec![Effect::Friction { w: [0.05, 0.0] }],
        Params::aras_diamond().gravity,
    )
    .unwrap();
    let mut a = vec![0.0; 8];
    m.fill_with(&s, Sign::Tanh(0.03), &mut a).unwrap();
    let (v1, v2) = (s.joint.vel[0], s.joint.vel[1]);
    assert_eq!(a[2], (v1 / 0.05).tanh());
    assert_eq!(a[7], (v2 / 0.03).tanh());
    assert_eq!(coulomb_law_dw(v1, 0.0), 0.0);
    assert_eq!(coulomb_law(-0.0, 0.0), 0.0);
}

/// The parameter file: `friction.w` round-trips, an absent `w` is the sign
/// law and the file keeps its old form, a bad width names its key.
#[test]
fn width_in_the_parameter_file() {
    let mut p = Params::aras_diamond();
    let old = p.to_json_string();
    assert!(!old.contains("\"w\""), "{old}");
    assert_eq!(
        Params::from_json_str(&old).unwrap().friction.width,
        [0.0; 2]
    );
    p.friction.width = [0.03, 0.012];
    let text = p.to_json_string();
    let back = Params::from_json_str(&text).unwrap();
    assert_eq!(back, p);
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["friction"]["w"][1] = serde_json::json!(-0.01);
    let e = Params::from_value(&v).unwrap_err().to_string();
    assert!(e.contains("friction.w[1]") && e.contains("≥ 0"), "{e}");
    v["friction"]["w"] = serde_json::json!([0.01]);
    let e = Params::from_value(&v).unwrap_err().to_string();
    assert!(e.contains("friction.w"), "{e}");
    // The effect's serde form: `{"id": "friction", "w": [..]}`, `w` optional.
    let e: Effect = serde_json::from_str(r#"{"id": "friction"}"#).unwrap();
    assert_eq!(e, Effect::FRICTION_SIGN_LAW);
    let e: Effect = serde_json::from_str(r#"{"id": "friction", "w": [0.03, 0.01]}"#).unwrap();
    assert_eq!(e, Effect::Friction { w: [0.03, 0.01] });
}
