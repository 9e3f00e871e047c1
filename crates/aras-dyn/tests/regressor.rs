//! The regressor against the direct dynamics, its layout, and its exact
//! derivatives.

use aras_dyn::{Cogging, Dynamics, Effect, Model, Params, Sign, Stribeck};
use aras_kin::Motion;
use aras_kin::{Geometry, evaluate};
use nalgebra::{DVector, Vector2, Vector3};
use num_dual::Dual64;
use proptest::prelude::*;

fn all_extras(mut p: Params) -> Params {
    p.extra.torque_offset = Some([0.012, -0.021]);
    p.extra.coulomb_asymmetry = Some([0.01, -0.015]);
    p.extra.stribeck_friction = Some(Stribeck {
        v_s: 0.08,
        level: [0.03, 0.05],
    });
    p.extra.passive_joint_viscous = Some([0.002, 0.003, 0.0015]);
    p.extra.cogging = Some(Cogging {
        cycles_per_rev: 12.0,
        sin: [vec![0.004, 0.001], vec![0.003, -0.002]],
        cos: [vec![-0.002, 0.0005], vec![0.001, 0.0007]],
    });
    p.extra.quadratic_damping = Some([0.004, 0.006]);
    p
}

fn random_params(v: &[f64]) -> Params {
    let mut p = Params::aras_diamond();
    let model = Model::paper(p.gravity).unwrap();
    let mut beta = p.standard_vector(&model).unwrap();
    for (b, r) in beta.iter_mut().zip(v) {
        *b *= 1.0 + r;
        *b += 1e-3 * r;
    }
    p.set_standard_vector(&model, beta.as_slice()).unwrap();
    p
}

fn state() -> impl Strategy<Value = ([f64; 6], Vec<f64>)> {
    let d = f64::to_radians;
    (
        [
            d(30.0)..d(140.0),
            d(40.0)..d(80.0),
            -3.5f64..3.5,
            -3.5f64..3.5,
            -60f64..60.0,
            -60f64..60.0,
        ],
        proptest::collection::vec(-0.5f64..0.5, 42),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// `Y β` equals the direct virtual-work evaluation (33) + (49) + (50)
    /// (+ extras). Both are sums of O(1) N·m terms in double precision, so
    /// rounding is ~1e-15 relative; 1e-12 leaves room for the 1/K factors.
    #[test]
    fn y_beta_equals_direct(([phi, gamma, pd, gd, pdd, gdd], r) in state()) {
        let g = Geometry::aras_diamond();
        let s = evaluate(&g, &Motion::new(Vector2::new(phi, gamma), Vector2::new(pd, gd), Vector2::new(pdd, gdd))).unwrap();
        for p in [random_params(&r), all_extras(random_params(&r))] {
            let model = p.model().unwrap();
            let beta = p.standard_vector(&model).unwrap();
            let y = model.regressor(&s);
            let tau_y = y * &beta;
            let tau_d = Dynamics::new(&p).unwrap().inverse(&s);
            let err = (tau_y - tau_d).norm();
            prop_assert!(err <= 1e-12 * (1.0 + tau_d.norm()), "err {err:e} at {tau_d:?}");
        }
    }

    /// Tilted gravity and other geometries: the identity holds for any
    /// gravity vector and arc angles.
    #[test]
    fn y_beta_any_gravity_and_geometry(gx in -10f64..10.0, gy in -10f64..10.0, gz in -10f64..10.0,
                                       al in 35f64..60.0, be in 35f64..60.0, pd in -2f64..2.0, gdd in -20f64..20.0) {
        let mut p = all_extras(Params::aras_diamond());
        p.gravity = Vector3::new(gx, gy, gz);
        p.alpha_deg = al;
        p.beta_deg = be;
        let g = p.geometry().unwrap();
        let x = Vector2::new(1.2, 0.5 * (al + be).to_radians().min(1.4));
        let Ok(s) = evaluate(&g, &Motion::new(x, Vector2::new(pd, 0.7), Vector2::new(3.0, gdd))) else { return Ok(()) };
        let model = p.model().unwrap();
        let tau_y = model.regressor(&s) * p.standard_vector(&model).unwrap();
        let tau_d = Dynamics::new(&p).unwrap().inverse(&s);
        prop_assert!((tau_y - tau_d).norm() <= 1e-12 * (1.0 + tau_d.norm()));
    }
}

#[test]
fn paper_model_has_42_named_columns() {
    let m = Model::paper(Vector3::new(0.0, -9.81, 0.0)).unwrap();
    let names = m.names();
    assert_eq!(m.columns(), 42);
    assert_eq!(names.len(), 42);
    assert_eq!(
        &names[..10],
        &[
            "L1.Ixx", "L1.Ixy", "L1.Ixz", "L1.Iyy", "L1.Iyz", "L1.Izz", "L1.hx", "L1.hy", "L1.hz",
            "L2.Ixx"
        ]
    );
    assert_eq!(
        &names[35..],
        &["L4.hz", "Fv1", "Fc1", "Fv2", "Fc2", "Ke1", "Ke2"]
    );
    assert_eq!(m.column_range("friction"), Some(36..40));
    let full = all_extras(Params::aras_diamond()).model().unwrap();
    assert_eq!(full.columns(), 42 + 2 + 2 + 2 + 3 + 8 + 2);
    let mut sorted = full.names();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), full.columns(), "names are unique");
}

#[test]
fn model_rejects_duplicates_and_bad_settings() {
    let g = Vector3::new(0.0, -9.81, 0.0);
    let m = Model::paper(g).unwrap();
    let e = m.with_effect(Effect::FRICTION_SIGN_LAW).unwrap_err();
    assert!(e.to_string().contains("`friction` appears twice"), "{e}");
    let e = m
        .with_effect(Effect::StribeckFriction { v_s: 0.0 })
        .unwrap_err();
    assert!(e.to_string().contains("v_s"), "{e}");
    let e = m
        .with_effect(Effect::Cogging {
            cycles_per_rev: 4.0,
            order: 0,
        })
        .unwrap_err();
    assert!(e.to_string().contains("order"), "{e}");
    assert!(Model::paper(Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
}

#[test]
fn fill_checks_buffer_length() {
    let p = Params::aras_diamond();
    let m = p.model().unwrap();
    let s = evaluate(
        &p.geometry().unwrap(),
        &Motion::new(
            Vector2::new(1.4, 1.0),
            Vector2::new(0.1, 0.2),
            Vector2::zeros(),
        ),
    )
    .unwrap();
    let mut short = vec![0.0; 83];
    let e = m.fill(&s, &mut short).unwrap_err();
    assert!(e.to_string().contains("needs 84"), "{e}");
    let mut ok = vec![0.0; 84];
    m.fill(&s, &mut ok).unwrap();
    assert_eq!(ok.as_slice(), m.regressor(&s).as_slice());
}

/// The stacked matrix is joint-major and matches the per-sample regressor.
#[test]
fn stacked_layout_is_joint_major() {
    let p = all_extras(Params::aras_diamond());
    let m = p.model().unwrap();
    let g = p.geometry().unwrap();
    let n = 5000; // spans several rayon blocks
    let xs: Vec<_> = (0..n)
        .map(|i| {
            let t = i as f64 * 1e-3;
            Vector2::new(1.4 + 0.5 * t.sin(), 1.0 + 0.2 * (2.0 * t).cos())
        })
        .collect();
    let vs: Vec<_> = (0..n)
        .map(|i| Vector2::new((i as f64 * 0.01).sin(), 0.3))
        .collect();
    let as_: Vec<_> = (0..n)
        .map(|i| Vector2::new(2.0, (i as f64 * 0.02).cos()))
        .collect();
    let task: Vec<_> = (0..n).map(|i| Motion::new(xs[i], vs[i], as_[i])).collect();
    let samples: Vec<_> = task.iter().map(|t| evaluate(&g, t).unwrap()).collect();
    let w = m.stacked(&samples).unwrap();
    let w2 = m.stacked_from_states(&g, &task).unwrap();
    assert_eq!(w, w2);
    assert_eq!(w.shape(), (2 * n, m.columns()));
    for i in [0, 1, 2047, 2048, 4999] {
        let y = m.regressor(&samples[i]);
        for j in 0..m.columns() {
            assert_eq!(w[(i, j)], y[(0, j)]);
            assert_eq!(w[(n + i, j)], y[(1, j)]);
        }
    }
    // Errors name the failing kinematics.
    let mut bad = task.clone();
    bad[3].pos[1] = 2.0; // γ beyond α + β
    let e = m.stacked_from_states(&g, &bad).unwrap_err();
    assert!(e.to_string().contains("unreachable"), "{e}");
}

/// The regressor in dual numbers gives the exact derivative: compare with
/// central differences (step 1e-6: truncation ~1e-12·Y''', rounding
/// ~1e-16/1e-6 = 1e-10, so 1e-7 relative is a safe bound).
#[test]
fn dual_regressor_matches_finite_differences() {
    let p = all_extras(Params::aras_diamond());
    let m = p.model().unwrap();
    let g = p.geometry().unwrap();
    let (x0, v0, a0) = (
        Vector2::new(1.3, 1.05),
        Vector2::new(0.6, -0.4),
        Vector2::new(3.0, -2.0),
    );
    for dir in 0..6 {
        let mut e = [0.0; 6];
        e[dir] = 1.0;
        let lift = |x: &Vector2<f64>, o: usize| {
            Vector2::new(Dual64::new(x[0], e[o]), Dual64::new(x[1], e[o + 1]))
        };
        let s = evaluate(&g, &Motion::new(lift(&x0, 0), lift(&v0, 2), lift(&a0, 4))).unwrap();
        let mut yd = vec![Dual64::from(0.0); 2 * m.columns()];
        m.fill(&s, &mut yd).unwrap();
        let h = 1e-6;
        let at = |sgn: f64| {
            let d = |o: usize| Vector2::new(e[o], e[o + 1]) * (sgn * h);
            m.regressor(&evaluate(&g, &Motion::new(x0 + d(0), v0 + d(2), a0 + d(4))).unwrap())
        };
        let fd = (at(1.0) - at(-1.0)) / (2.0 * h);
        let y0 = m.regressor(&evaluate(&g, &Motion::new(x0, v0, a0)).unwrap());
        for (i, ydi) in yd.iter().enumerate() {
            assert!((ydi.re - y0.as_slice()[i]).abs() <= 1e-15 * (1.0 + y0.as_slice()[i].abs()));
            let f = fd.as_slice()[i];
            assert!(
                (ydi.eps - f).abs() <= 1e-7 * (1.0 + f.abs()),
                "dir {dir} entry {i}: {} vs {f}",
                ydi.eps
            );
        }
    }
}

/// Standard vector round trip for every effect, and setting mismatches.
#[test]
fn standard_vector_round_trip() {
    let p = all_extras(Params::aras_diamond());
    let m = p.model().unwrap();
    let beta = p.standard_vector(&m).unwrap();
    let mut q = Params::aras_diamond();
    q.set_standard_vector(&m, beta.as_slice()).unwrap();
    assert_eq!(q, p);
    // Absent extras are zero columns.
    let b2 = Params::aras_diamond().standard_vector(&m).unwrap();
    assert_eq!(b2.rows(42, b2.len() - 42).norm(), 0.0);
    // Different Stribeck velocity in model and parameters.
    let other = Model::paper(p.gravity)
        .unwrap()
        .with_effect(Effect::StribeckFriction { v_s: 0.5 })
        .unwrap();
    let e = p.standard_vector(&other).unwrap_err();
    assert!(
        e.to_string().contains("v_s = 0.08") && e.to_string().contains("0.5"),
        "{e}"
    );
    let e = q
        .set_standard_vector(&m, &beta.as_slice()[1..])
        .unwrap_err();
    assert!(e.to_string().contains("length"), "{e}");
    let mut bad = beta.clone();
    bad[40] = f64::NAN;
    let e = q.set_standard_vector(&m, bad.as_slice()).unwrap_err();
    assert!(e.to_string().contains("Ke1"), "{e}");
}

/// Smooth sign: `tanh` columns approach the exact ones away from rest.
#[test]
fn smooth_sign_converges() {
    let p = Params::aras_diamond();
    let m = p.model().unwrap();
    let s = evaluate(
        &p.geometry().unwrap(),
        &Motion::new(
            Vector2::new(1.4, 1.0),
            Vector2::new(0.5, 0.2),
            Vector2::zeros(),
        ),
    )
    .unwrap();
    let mut a = vec![0.0; 84];
    let mut b = vec![0.0; 84];
    m.fill_with(&s, Sign::Exact, &mut a).unwrap();
    m.fill_with(&s, Sign::Tanh(1e-3), &mut b).unwrap();
    let d = DVector::from_vec(a) - DVector::from_vec(b);
    assert!(d.norm() < 1e-12);
}

/// One spelling of every effect identifier: `EffectId` parses what it
/// prints, serialises to the same string, and is the serde tag of the
/// matching `Effect`; the parameter file's `extra` sections use it too.
#[test]
fn effect_ids_are_spelled_once() {
    use aras_dyn::EffectId;
    let examples = [
        Effect::RigidLinks,
        Effect::FRICTION_SIGN_LAW,
        Effect::Elasticity,
        Effect::TorqueOffset,
        Effect::CoulombAsymmetry,
        Effect::StribeckFriction { v_s: 0.1 },
        Effect::PassiveJointViscous,
        Effect::Cogging {
            cycles_per_rev: 12.0,
            order: 2,
        },
        Effect::QuadraticDamping,
        Effect::PreslidingFriction { displacement: 5e-4 },
    ];
    assert_eq!(examples.map(|e| e.kind()), EffectId::ALL);
    for (e, id) in examples.iter().zip(EffectId::ALL) {
        assert_eq!(id.to_string(), id.as_str());
        assert_eq!(id.as_str().parse::<EffectId>().unwrap(), id);
        assert_eq!(
            serde_json::to_value(id).unwrap(),
            serde_json::json!(id.as_str())
        );
        assert_eq!(serde_json::to_value(e).unwrap()["id"], id.as_str());
        assert_eq!(e.id(), id.as_str());
    }
    assert_eq!(
        EffectId::StribeckFriction.as_str(),
        "stribeck_friction",
        "identifiers are stable: parameter files and reports use them"
    );
    let e = "stribeck".parse::<EffectId>().unwrap_err();
    assert!(
        e.to_string().contains("unknown effect `stribeck`")
            && e.to_string().contains("stribeck_friction"),
        "{e}"
    );
    // Every extra effect has its section in the parameter file, by its id.
    let mut p = Params::aras_diamond();
    p.extra.torque_offset = Some([0.1, -0.1]);
    p.extra.coulomb_asymmetry = Some([0.01, 0.02]);
    p.extra.stribeck_friction = Some(Stribeck {
        v_s: 0.1,
        level: [0.03, 0.04],
    });
    p.extra.passive_joint_viscous = Some([1e-3, 2e-3, 3e-3]);
    p.extra.cogging = Some(Cogging {
        cycles_per_rev: 12.0,
        sin: [vec![0.01], vec![0.0]],
        cos: [vec![0.0], vec![0.02]],
    });
    p.extra.quadratic_damping = Some([1e-4, 2e-4]);
    p.extra.presliding_friction = Some(aras_dyn::Presliding {
        displacement: 5e-4,
        level: [0.05, 0.2],
        damping: [0.1, 0.2],
    });
    let v = serde_json::to_value(&p).unwrap();
    let extra = v["extra"].as_object().unwrap();
    let keys: Vec<&str> = extra.keys().map(String::as_str).collect();
    let mut want = EffectId::EXTRA.map(EffectId::as_str).to_vec();
    let mut got = keys.clone();
    want.sort_unstable();
    got.sort_unstable();
    assert_eq!(got, want);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Cogging's harmonics come from the first by the angle-addition
    /// formulas; each column equals `sin/cos(h n_c θ_j)` evaluated directly,
    /// on its joint's row only. Either value carries the rounding of its
    /// argument, `ε |h n_c θ|` (up to 1e-13 at 80 cycles and order 16),
    /// and the recurrence adds a few ulps per harmonic: the bound is
    /// `8 ε h (1 + |n_c θ|)`.
    #[test]
    fn cogging_harmonics_match_direct_evaluation(
        phi in -0.8f64..0.8, gamma in 0.3f64..1.2, cycles in 0.5f64..80.0,
    ) {
        let g = Geometry::aras_diamond();
        let s = evaluate(&g, &Motion::new(Vector2::new(phi, gamma), Vector2::zeros(), Vector2::zeros())).unwrap();
        let order = 16;
        let model = Model::new(vec![Effect::Cogging { cycles_per_rev: cycles, order }], Vector3::new(0.0, 0.0, -9.81)).unwrap();
        let y = model.regressor(&s);
        let names = model.names();
        for j in 0..2 {
            let th = s.joint.pos[j];
            for h in 1..=order {
                let (sn, cs) = (th * h as f64 * cycles).sin_cos();
                let tol = 8.0 * f64::EPSILON * h as f64 * (1.0 + (cycles * th).abs());
                for (name, want) in [(format!("Cs{}_{h}", j + 1), sn), (format!("Cc{}_{h}", j + 1), cs)] {
                    let c = names.iter().position(|n| *n == name).unwrap();
                    prop_assert!((y[(j, c)] - want).abs() <= tol, "{name}: {} vs {want} (tol {tol:e})", y[(j, c)]);
                    prop_assert_eq!(y[(1 - j, c)], 0.0);
                }
            }
        }
    }
}

/// The presliding effect's columns along a stacked sequence equal the
/// bristle equation `ż = θ̇ − |θ̇| z / δ` integrated in time by a fine RK4
/// (an independent path: the effect advances along the angles with the
/// exact solution), on a motion with reversals; its damping column is `ż`.
/// One sample alone is refused, and the per-sample regressor leaves it 0.
#[test]
fn presliding_columns_follow_the_bristle_equation() {
    let g = Geometry::aras_diamond();
    let delta = 4e-4;
    let model = Model::new(
        vec![Effect::PreslidingFriction {
            displacement: delta,
        }],
        Vector3::new(0.0, -9.81, 0.0),
    )
    .unwrap();
    // A task motion with reversals of both joints, 1 kHz.
    let x = |t: f64| Vector2::new(0.3 * (2.0 * t).sin(), 0.7 + 0.2 * (3.0 * t).cos());
    let xd = |t: f64| Vector2::new(0.6 * (2.0 * t).cos(), -0.6 * (3.0 * t).sin());
    let xdd = |t: f64| Vector2::new(-1.2 * (2.0 * t).sin(), -1.8 * (3.0 * t).cos());
    let n = 4000;
    let dt = 1e-3;
    let samples: Vec<_> = (0..n)
        .map(|i| {
            let t = i as f64 * dt;
            evaluate(&g, &Motion::new(x(t), xd(t), xdd(t))).unwrap()
        })
        .collect();
    let w = model.stacked(&samples).unwrap();
    // Joint rates at any time from the kinematics, for RK4 in time.
    let rate = |t: f64, j: usize| {
        evaluate(&g, &Motion::new(x(t), xd(t), xdd(t)))
            .unwrap()
            .joint
            .vel[j]
    };
    for j in 0..2 {
        let v0 = samples[0].joint.vel[j];
        let mut z = v0.signum() * delta;
        let f = |t: f64, z: f64| {
            let v = rate(t, j);
            v - v.abs() * z / delta
        };
        let sub = 20;
        let h = dt / sub as f64;
        let mut worst: f64 = 0.0;
        for i in 0..n {
            if i > 0 {
                for k in 0..sub {
                    let t = (i - 1) as f64 * dt + k as f64 * h;
                    let k1 = f(t, z);
                    let k2 = f(t + h / 2.0, z + h / 2.0 * k1);
                    let k3 = f(t + h / 2.0, z + h / 2.0 * k2);
                    let k4 = f(t + h, z + h * k3);
                    z += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                }
            }
            let s = w[(j * n + i, j)];
            let zd = w[(j * n + i, 2 + j)];
            assert_eq!(w[((1 - j) * n + i, j)], 0.0);
            worst = worst.max((s - z / delta).abs());
            let want_rate = f(i as f64 * dt, z);
            assert!(
                (zd - want_rate).abs() < 2e-3 * (1.0 + want_rate.abs()),
                "joint {} sample {i}: rate {zd} vs {want_rate}",
                j + 1
            );
        }
        // The exact path solution against RK4 in time: they differ where a
        // reversal falls between two samples, whose excursion out and back
        // (≈ 2 · θ̈ Δt²/8 of path) the chord between the samples misses; the
        // state is off by at most that over δ (bound with a factor 2).
        let acc = samples
            .iter()
            .map(|s| s.joint.acc[j].abs())
            .fold(0.0, f64::max);
        let bound = 2.0 * acc * dt * dt / (4.0 * delta);
        eprintln!(
            "joint {}: worst |s − z/δ| = {worst:.2e} (bound {bound:.2e})",
            j + 1
        );
        assert!(worst < bound, "joint {}: {worst} vs {bound}", j + 1);
    }
    let mut buf = vec![0.0; 2 * model.columns()];
    let e = model.fill(&samples[0], &mut buf).unwrap_err().to_string();
    assert!(
        e.contains("presliding_friction") && e.contains("stacked"),
        "{e}"
    );
    assert!(model.regressor(&samples[0]).iter().all(|v| *v == 0.0));
}
