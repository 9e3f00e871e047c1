//! The simulated robot: consistency with the model, determinism, sensors,
//! the log format.

use aras_dyn::sim::{LuGre, SimConfig, simulate, write_log};
use aras_dyn::{Cogging, Params, Sinusoid, Stribeck, Trajectory};
use aras_kin::Motion;
use aras_kin::{AssemblyMode, evaluate, forward};
use aras_log::sidecar_path;
use aras_testkit::error_chain as chain;
use nalgebra::Vector2;

fn short(duration_s: f64) -> SimConfig {
    SimConfig {
        duration_s,
        ..SimConfig::default()
    }
}

/// Ideal sensors: no noise, encoder resolution ~1.5e-10 rad.
fn ideal(duration_s: f64) -> SimConfig {
    let mut c = short(duration_s);
    c.sensors.counts_per_rev = [u32::MAX; 2];
    c.sensors.current_noise_std = [0.0; 2];
    c
}

fn with_extras() -> Params {
    let mut p = Params::aras_diamond();
    p.extra.torque_offset = Some([0.02, -0.01]);
    p.extra.stribeck_friction = Some(Stribeck {
        v_s: 0.2,
        level: [0.03, 0.04],
    });
    p.extra.passive_joint_viscous = Some([0.002, 0.002, 0.001]);
    p.extra.cogging = Some(Cogging {
        cycles_per_rev: 20.0,
        sin: [vec![0.005], vec![0.004]],
        cos: [vec![0.002], vec![-0.003]],
    });
    p.extra.quadratic_damping = Some([0.003, 0.002]);
    p.extra.coulomb_asymmetry = Some([0.01, -0.02]);
    p
}

/// The kinematic sample of logged joint angles, rates and accelerations:
/// `X` by the forward kinematics, `Ẋ = J⁻¹ θ̇`, `Ẍ = J⁻¹ (θ̈ − J̇ Ẋ)`.
fn logged_sample(
    g: &aras_kin::Geometry,
    th: Vector2<f64>,
    td: Vector2<f64>,
    tdd: Vector2<f64>,
) -> aras_kin::KinematicSample {
    let x = forward(g, &th, AssemblyMode::Plus).unwrap();
    let s0 = evaluate(g, &Motion::new(x, Vector2::zeros(), Vector2::zeros())).unwrap();
    let ji = s0.jacobian.inverse();
    let xd = ji * td;
    let s1 = evaluate(g, &Motion::new(x, xd, Vector2::zeros())).unwrap();
    let xdd = ji * (tdd - s1.jacobian_dot * xd);
    evaluate(g, &Motion::new(x, xd, xdd)).unwrap()
}

/// The logged data satisfy the truth model: rebuilding `(X, Ẋ, Ẍ)` from the
/// logged angles and exact derivatives, `τ = Y β` reproduces the measured
/// torque wherever both joints move faster than 0.5 rad/s (there
/// `tanh(θ̇/0.03)` equals `sign` to 1e-14). Remaining error: encoder
/// resolution ~1e-10 rad times `∂τ/∂θ` (≲ 1 N·m/rad), so 1e-8 N·m.
#[test]
fn logged_data_satisfy_the_model() {
    for truth in [Params::aras_diamond(), with_extras()] {
        let traj = Sinusoid::paper_79(0.7).unwrap();
        let log = simulate(&truth, &traj, &ideal(2.0)).unwrap();
        let model = truth.model().unwrap();
        let beta = truth.standard_vector(&model).unwrap();
        let g = truth.geometry().unwrap();
        let mut checked = 0;
        for i in 0..log.len() {
            let th = Vector2::from(log.theta[i]);
            let td = Vector2::from(log.theta_dot[i]);
            let tdd = Vector2::from(log.theta_ddot[i]);
            if td.amin() < 0.5 {
                continue;
            }
            let tau = model.regressor(&logged_sample(&g, th, td, tdd)) * &beta;
            let err = (tau - Vector2::from(log.tau[i])).amax();
            assert!(
                err < 1e-8,
                "sample {i}: {tau} vs {:?} (err {err:e})",
                log.tau[i]
            );
            checked += 1;
        }
        assert!(checked > 300, "only {checked} samples checked");
    }
}

/// LuGre friction with a presliding displacement `Fc/σ0` of 5e-4 rad and a
/// Stribeck hump (`Fs = 1.3 Fc`, `v_s = 0.03 rad/s`).
fn lugre() -> LuGre {
    let fc = Params::aras_diamond().friction.coulomb;
    LuGre {
        static_level: [1.3 * fc[0], 1.3 * fc[1]],
        stribeck_velocity: [0.03; 2],
        stiffness: [fc[0] / 5e-4, fc[1] / 5e-4],
        damping: [0.2, 0.4],
    }
}

/// With LuGre friction the log still satisfies the sign model (49) where
/// both joints move faster than 0.5 rad/s and have moved 0.015 rad (30
/// presliding lengths) since their last reversal: there the bristle has
/// settled (the transient decays at least as `exp(−σ0 Δθ / Fs)`, below
/// 1e-10 of Fc) and the Stribeck term is `exp(−(0.5/0.03)²) ≈ 0`. Near reversals it differs from the `tanh` law
/// by far more than the noise (breakaway and presliding): the state is
/// really integrated, not replaced by a column.
#[test]
fn lugre_friction_equals_coulomb_when_sliding_and_differs_at_reversals() {
    let truth = Params::aras_diamond();
    let traj = Sinusoid::paper_79(0.7).unwrap();
    let mut cfg = ideal(3.0);
    cfg.substeps = 4;
    cfg.lugre = Some(lugre());
    let log = simulate(&truth, &traj, &cfg).unwrap();
    let smooth = simulate(
        &truth,
        &traj,
        &SimConfig {
            lugre: None,
            ..cfg.clone()
        },
    )
    .unwrap();
    let model = truth.model().unwrap();
    let beta = truth.standard_vector(&model).unwrap();
    let g = truth.geometry().unwrap();
    let (mut checked, mut slow_gap) = (0, 0.0f64);
    // Angle of each joint at its last reversal.
    let mut turned = log.theta[0];
    for i in 0..log.len() {
        let td = Vector2::from(log.theta_dot[i]);
        for j in 0..2 {
            if i > 0 && td[j] * log.theta_dot[i - 1][j] <= 0.0 {
                turned[j] = log.theta[i][j];
            }
        }
        if td.amin() < 0.1 {
            let d = (Vector2::from(log.tau[i]) - Vector2::from(smooth.tau[i])).amax();
            slow_gap = slow_gap.max(d);
        }
        let moved = (0..2).all(|j| (log.theta[i][j] - turned[j]).abs() >= 0.015);
        if td.amin() < 0.5 || !moved || i == 0 {
            continue;
        }
        let th = Vector2::from(log.theta[i]);
        let tdd = Vector2::from(log.theta_ddot[i]);
        let s = logged_sample(&g, th, td, tdd);
        let err = (model.regressor(&s) * &beta - Vector2::from(log.tau[i])).amax();
        assert!(err < 1e-8, "sample {i}: err {err:e}");
        checked += 1;
    }
    assert!(checked > 300, "only {checked} samples checked");
    println!("largest |τ_LuGre − τ_tanh| below 0.1 rad/s: {slow_gap:.4} N·m");
    assert!(slow_gap > 0.02, "{slow_gap}");
}

/// A bristle too stiff for the step is refused with the setting to change.
#[test]
fn too_stiff_lugre_names_substeps() {
    let error = |l: LuGre| {
        let cfg = SimConfig {
            lugre: Some(l),
            ..ideal(1.0)
        };
        let traj = Sinusoid::paper_79(0.7).unwrap();
        simulate(&Params::aras_diamond(), &traj, &cfg)
            .unwrap_err()
            .to_string()
    };
    let mut l = lugre();
    l.stiffness = [1e6; 2];
    let e = error(l);
    assert!(e.contains("substeps"), "{e}");
    let mut l = lugre();
    l.static_level[0] = 0.0;
    let e = error(l);
    assert!(e.contains("lugre.static_level"), "{e}");
}

/// PD tracking on (79) at 0.5 Hz stays within 2.5° (pure PD against
/// 0.29 N·m Coulomb friction and gravity with Kp = 30 N·m/rad), torques
/// within limits.
#[test]
fn pd_tracks_the_trajectory() {
    let traj = Sinusoid::paper_79(0.5).unwrap();
    let cfg = short(4.0);
    let log = simulate(&Params::aras_diamond(), &traj, &cfg).unwrap();
    assert_eq!(log.len(), 4000);
    assert_eq!((log.t[0], log.t[3999]), (0.0, 3.999));
    let g = aras_kin::Geometry::aras_diamond();
    let mut worst = 0.0f64;
    for i in 0..log.len() {
        let Motion { pos: x, .. } = traj.eval(log.t[i]);
        let th_d = aras_kin::inverse(&g, &x).unwrap().theta;
        worst = worst.max((th_d - Vector2::from(log.theta[i])).amax());
        for j in 0..2 {
            assert!(log.tau[i][j].abs() <= cfg.torque_limit[j] + 0.05);
        }
    }
    println!("worst tracking error {:.3}°", worst.to_degrees());
    assert!(worst < 2.5f64.to_radians());
    // Angles are multiples of the encoder resolution.
    let res = cfg.sensors.resolution();
    for th in &log.theta[..50] {
        for j in 0..2 {
            let c = th[j] / res[j];
            assert!((c - c.round()).abs() < 1e-6);
        }
    }
}

#[test]
fn torque_noise_has_the_configured_level() {
    let traj = Sinusoid::paper_79(0.5).unwrap();
    let mut quiet = short(3.0);
    quiet.sensors.current_noise_std = [0.0; 2];
    let noisy = short(3.0);
    let a = simulate(&Params::aras_diamond(), &traj, &quiet).unwrap();
    let b = simulate(&Params::aras_diamond(), &traj, &noisy).unwrap();
    // Same plant trajectory (noise only affects the measurement).
    assert_eq!(a.theta, b.theta);
    let sd = noisy.sensors.torque_noise_std();
    for j in 0..2 {
        let n = a.len() as f64;
        let var = a
            .tau
            .iter()
            .zip(&b.tau)
            .map(|(x, y)| (y[j] - x[j]).powi(2))
            .sum::<f64>()
            / n;
        // 3000 samples: the sample std is within ±6 % at 3σ.
        assert!(
            (var.sqrt() / sd[j] - 1.0).abs() < 0.06,
            "joint {j}: {} vs {}",
            var.sqrt(),
            sd[j]
        );
    }
    assert!((sd[0] - 0.00302).abs() < 1e-12);
}

#[test]
fn deterministic_for_a_seed_and_byte_identical_logs() {
    let traj = Sinusoid::paper_79(0.7).unwrap();
    let truth = with_extras();
    let a = simulate(&truth, &traj, &short(1.5)).unwrap();
    let b = simulate(&truth, &traj, &short(1.5)).unwrap();
    assert_eq!(a, b);
    let mut other = short(1.5);
    other.seed = 2;
    assert_ne!(simulate(&truth, &traj, &other).unwrap().tau, a.tau);

    let dir = aras_testkit::Scratch::new("dyn-sim");
    let (p1, p2) = (dir.join("a.csv"), dir.join("b.csv"));
    write_log(&p1, &a, true).unwrap();
    write_log(&p2, &b, true).unwrap();
    assert_eq!(std::fs::read(&p1).unwrap(), std::fs::read(&p2).unwrap());
    assert_eq!(
        std::fs::read(sidecar_path(&p1)).unwrap(),
        std::fs::read(sidecar_path(&p2)).unwrap()
    );

    // CSV: header, full-precision round trip.
    let text = std::fs::read_to_string(&p1).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,theta1,theta2,tau1,tau2,dtheta1,dtheta2,ddtheta1,ddtheta2"
    );
    let row: Vec<f64> = lines
        .nth(10)
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(
        row[..5],
        [
            a.t[10],
            a.theta[10][0],
            a.theta[10][1],
            a.tau[10][0],
            a.tau[10][1]
        ]
    );
    assert_eq!(text.lines().count(), a.len() + 1);
    write_log(&p1, &a, false).unwrap();
    assert!(
        std::fs::read_to_string(&p1)
            .unwrap()
            .starts_with("t,theta1,theta2,tau1,tau2\n0,")
    );

    // Sidecar: format, sensors, excitation, truth.
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sidecar_path(&p1)).unwrap()).unwrap();
    assert_eq!(v["format"], "aras-log/1");
    assert_eq!(v["torques"], "held");
    assert_eq!(v["truth"]["simulator"]["lead_in_s"], 2.0);
    let read = aras_log::read_log(&p1, &aras_log::ReadOptions::default()).unwrap();
    assert_eq!(read.torque_timing(), aras_log::TorqueTiming::Held);
    assert_eq!(v["sensors"]["counts_per_rev"][0], 4096);
    assert_eq!(v["sensors"]["gear_ratios"][1], 10.0);
    assert_eq!(v["sensors"]["torque_constants"][0], 0.0302);
    assert_eq!(v["excitation"]["period_s"].as_f64().unwrap(), 1.0 / 0.7);
    assert_eq!(v["truth"]["seed"], 1);
    let back: Params = serde_json::from_value(v["truth"]["params"].clone()).unwrap();
    assert_eq!(back, truth);
    let effects: Vec<aras_dyn::Effect> =
        serde_json::from_value(v["truth"]["effects"].clone()).unwrap();
    assert_eq!(effects, truth.model().unwrap().effects());
    assert_eq!(v["truth"]["effects"][5]["id"], "stribeck_friction");
    assert!(v["truth"]["noise"]["torque_std_nm"][0].as_f64().unwrap() > 0.0);
    assert_eq!(v["truth"]["simulator"]["output_rate_hz"], 1000.0);
}

#[test]
fn aperiodic_trajectory_has_no_excitation_section() {
    struct Hold;
    impl Trajectory for Hold {
        fn eval(&self, _t: f64) -> Motion {
            Motion::new(Vector2::new(1.4, 1.0), Vector2::zeros(), Vector2::zeros())
        }
        fn period(&self) -> Option<f64> {
            None
        }
    }
    let log = simulate(&Params::aras_diamond(), &Hold, &short(0.5)).unwrap();
    let v = serde_json::to_value(&log.sidecar).unwrap();
    assert!(v.get("excitation").is_none());
    // Holding still against gravity, the spring and Coulomb friction with
    // ideal sensors: no chattering (which would flip the torque back and
    // forth by ~Fc = 0.1–0.3 N·m). The torque creeps monotonically to rest:
    // its total variation over the second second after the start equals
    // its net change. (Later, at rest, the creep falls below single counts
    // of the ideal encoder, 1.5e-10 rad × Kp = 4.5e-9 N·m, whose flips then
    // dominate the variation; hence no lead-in here.)
    let mut cfg = ideal(2.0);
    cfg.lead_in_s = 0.0;
    let log = simulate(&Params::aras_diamond(), &Hold, &cfg).unwrap();
    for j in 0..2 {
        let last: Vec<f64> = log.tau[log.len() - 1000..].iter().map(|t| t[j]).collect();
        let tv: f64 = last.windows(2).map(|w| (w[1] - w[0]).abs()).sum();
        let net = (last[last.len() - 1] - last[0]).abs();
        assert!(
            tv <= 1.01 * net + 1e-9,
            "joint {j}: variation {tv:e} vs net {net:e}"
        );
    }
}

/// The delay shifts torque samples against angle samples by whole samples.
/// After a lead-in the first rows' delayed torques are the lead-in's, so
/// the log keeps every row; without one, the first rows are dropped.
#[test]
fn torque_delay_shifts_samples() {
    let traj = Sinusoid::paper_79(0.5).unwrap();
    let a = simulate(&Params::aras_diamond(), &traj, &short(0.5)).unwrap();
    let mut cfg = short(0.5);
    cfg.torque_delay_samples = 3;
    let b = simulate(&Params::aras_diamond(), &traj, &cfg).unwrap();
    assert_eq!(b.len(), a.len());
    assert_eq!(b.t, a.t);
    assert_eq!(b.theta, a.theta);
    for i in 3..b.len() {
        assert_eq!(b.tau_clean[i], a.tau_clean[i - 3]);
    }
    // The first rows hold the lead-in's last torques, not zeros.
    assert!(b.tau_clean[0][0] != 0.0 && b.tau_clean[0][0] != a.tau_clean[0][0]);

    let no_lead = |delay| {
        let mut c = short(0.5);
        c.lead_in_s = 0.0;
        c.torque_delay_samples = delay;
        simulate(&Params::aras_diamond(), &traj, &c).unwrap()
    };
    let (a, b) = (no_lead(0), no_lead(3));
    assert_eq!(b.len(), a.len() - 3);
    for i in 0..b.len() {
        assert_eq!(b.t[i], a.t[i + 3]);
        assert_eq!(b.theta[i], a.theta[i + 3]);
        assert_eq!(b.tau[i], a.tau[i]);
    }
}

/// RK4 at the default internal rate against a 16× finer reference: the
/// exact rates agree to 1e-4 rad/s (the smoothed friction is stiff near
/// velocity reversals), three orders below the encoder's velocity
/// resolution at 1 kHz (0.15 rad/s). The log stays exactly consistent with
/// the model either way (`logged_data_satisfy_the_model`).
/// A fractional delay `d + φ` logs `(1 − φ) τ_{k−d} + φ τ_{k−d−1}` of the
/// undelayed run's clean torques, with the noise of sample `k − d`, and
/// (without a lead-in) drops one more row; `φ = 0` is the whole-sample
/// delay.
#[test]
fn fractional_torque_delay_interpolates_between_samples() {
    let traj = Sinusoid::paper_79(0.5).unwrap();
    let mut cfg = short(0.5);
    cfg.lead_in_s = 0.0;
    let a = simulate(&Params::aras_diamond(), &traj, &cfg).unwrap();
    cfg.torque_delay_samples = 3;
    cfg.torque_delay_fraction = 0.4;
    let b = simulate(&Params::aras_diamond(), &traj, &cfg).unwrap();
    assert_eq!(b.len(), a.len() - 4);
    for i in 0..b.len() {
        let k = i + 4;
        assert_eq!(b.t[i], a.t[k]);
        assert_eq!(b.theta[i], a.theta[k]);
        for j in 0..2 {
            let clean = 0.6 * a.tau_clean[k - 3][j] + 0.4 * a.tau_clean[k - 4][j];
            assert!((b.tau_clean[i][j] - clean).abs() < 1e-15, "{i}");
            let noise = a.tau[k - 3][j] - a.tau_clean[k - 3][j];
            assert!((b.tau[i][j] - (clean + noise)).abs() < 1e-15, "{i}");
        }
    }
    cfg.torque_delay_fraction = 1.0;
    let e = simulate(&Params::aras_diamond(), &traj, &cfg)
        .unwrap_err()
        .to_string();
    assert!(e.contains("torque_delay_fraction"), "{e}");
}

#[test]
fn integration_converged() {
    let traj = Sinusoid::paper_79(1.8).unwrap();
    let coarse = simulate(&Params::aras_diamond(), &traj, &ideal(1.0)).unwrap();
    let mut fine_cfg = ideal(1.0);
    fine_cfg.substeps = 32;
    let fine = simulate(&Params::aras_diamond(), &traj, &fine_cfg).unwrap();
    let err = coarse
        .theta_dot
        .iter()
        .zip(&fine.theta_dot)
        .map(|(a, b)| (a[0] - b[0]).abs().max((a[1] - b[1]).abs()))
        .fold(0.0, f64::max);
    println!("max |Δθ̇| coarse vs fine: {err:e} rad/s");
    assert!(err < 1e-4);
}

#[test]
fn feedforward_reduces_tracking_error() {
    let traj = Sinusoid::paper_79(1.8).unwrap();
    let g = aras_kin::Geometry::aras_diamond();
    let err = |cfg: &SimConfig| {
        let log = simulate(&Params::aras_diamond(), &traj, cfg).unwrap();
        log.t
            .iter()
            .zip(&log.theta)
            .map(|(t, th)| {
                let th_d = aras_kin::inverse(&g, &traj.eval(*t).pos).unwrap().theta;
                (th_d - Vector2::from(*th)).amax()
            })
            .fold(0.0, f64::max)
    };
    let pd = err(&short(2.0));
    let mut cfg = short(2.0);
    cfg.controller.feedforward = Some(Params::aras_diamond());
    let ff = err(&cfg);
    println!(
        "tracking error at 1.8 Hz: PD {:.3}°, PD+FF {:.3}°",
        pd.to_degrees(),
        ff.to_degrees()
    );
    assert!(ff < 0.5 * pd);
}

#[test]
fn bad_settings_are_named() {
    let traj = Sinusoid::paper_79(0.5).unwrap();
    let p = Params::aras_diamond();
    let mut c = short(1.0);
    c.friction_smoothing = 0.0;
    let e = simulate(&p, &traj, &c).unwrap_err().to_string();
    assert!(e.contains("friction_smoothing"), "{e}");
    let mut c = short(1.0);
    c.sensors.torque_constants[1] = f64::NAN;
    assert!(
        simulate(&p, &traj, &c)
            .unwrap_err()
            .to_string()
            .contains("sensors.torque_constants")
    );
    let mut c = short(1.0);
    c.substeps = 0;
    assert!(
        simulate(&p, &traj, &c)
            .unwrap_err()
            .to_string()
            .contains("substeps")
    );
    let mut c = short(0.001);
    c.torque_delay_samples = 0;
    assert!(
        simulate(&p, &traj, &c)
            .unwrap_err()
            .to_string()
            .contains("duration_s")
    );
    // A trajectory that leaves the reachable workspace.
    let bad = Sinusoid::new(
        Vector2::new(0.1, 1.0),
        Vector2::new(1.4, 1.0),
        Vector2::zeros(),
        3.0,
    )
    .unwrap();
    let e = chain(&simulate(&p, &bad, &short(1.0)).unwrap_err());
    assert!(e.contains("t = ") && e.contains("gamma"), "{e}");
}

/// Trajectory (79): derivatives against central differences (step 1e-5:
/// error ~1e-10·|X'''|, so 1e-7 is safe), period and paper values.
#[test]
fn trajectory_79_and_47() {
    let tr = Sinusoid::paper_79(0.7).unwrap();
    assert!((tr.period().unwrap() - 1.0 / 0.7).abs() < 1e-15);
    let Motion { pos: x0, .. } = tr.eval(0.0);
    assert!((x0 - Vector2::new(115f64.to_radians(), 60f64.to_radians())).norm() < 1e-15);
    for t in [0.1, 0.77, 3.0] {
        let h = 1e-5;
        let Motion { vel: v, acc: a, .. } = tr.eval(t);
        let Motion {
            pos: xp, vel: vp, ..
        } = tr.eval(t + h);
        let Motion {
            pos: xm, vel: vm, ..
        } = tr.eval(t - h);
        assert!(((xp - xm) / (2.0 * h) - v).norm() < 1e-7 * (1.0 + v.norm()));
        assert!(((vp - vm) / (2.0 * h) - a).norm() < 1e-7 * (1.0 + a.norm()));
    }
    let Motion { pos: x, .. } = Sinusoid::paper_47().eval(std::f64::consts::FRAC_PI_4);
    assert!((x - Vector2::new(170f64.to_radians(), 85f64.to_radians())).norm() < 1e-14);
    assert!(Sinusoid::paper_79(-1.0).is_err());
}

/// FNV-1a, to pin a log's bytes in a test.
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Lead-in 0 is the simulator without a lead-in: the CSV bytes are those
/// the simulator wrote before the lead-in existed (pinned by their hash,
/// row count and size), with and without a torque delay.
#[test]
fn no_lead_in_gives_the_start_up_log_byte_for_byte() {
    let traj = Sinusoid::paper_79(0.7).unwrap();
    let dir = aras_testkit::Scratch::new("dyn-sim-lead0");
    let mut cfg = SimConfig {
        duration_s: 0.3,
        lead_in_s: 0.0,
        ..SimConfig::default()
    };
    for (delay, fraction, rows, bytes, hash) in [
        (0, 0.0, 300, 49010, 0x4ca5_d25d_b3c8_65c5_u64),
        (2, 0.25, 297, 48543, 0xd077_0020_b6d6_38a6),
    ] {
        cfg.torque_delay_samples = delay;
        cfg.torque_delay_fraction = fraction;
        let log = simulate(&Params::aras_diamond(), &traj, &cfg).unwrap();
        let p = dir.join("a.csv");
        write_log(&p, &log, true).unwrap();
        let b = std::fs::read(&p).unwrap();
        assert_eq!(
            (log.len(), b.len(), fnv(&b)),
            (rows, bytes, hash),
            "delay {delay}"
        );
    }
}

/// The start-up transient stays in the lead-in. Robot on (79) at 0.5 Hz:
/// without a lead-in it starts with zero velocity error but the PD torque
/// is still building, and falls at ≈ 70 rad/s² off the desired
/// acceleration in the first 0.1 s; after the default 2 s lead-in the
/// first 0.1 s is steady tracking. The bound, 5 rad/s²: the steady PD
/// loop's acceleration error in this phase is ≈ 1.3 rad/s² (measured with
/// lead-ins from 0.5 s to 20 s, `docs/simulator.md`), and its whole-period
/// maximum, at the velocity reversals, ≈ 17 rad/s², never occurs here.
#[test]
fn lead_in_keeps_the_start_up_out_of_the_log() {
    let traj = Sinusoid::paper_79(0.5).unwrap();
    let g = aras_kin::Geometry::aras_diamond();
    let worst = |cfg: &SimConfig| {
        let log = simulate(&Params::aras_diamond(), &traj, cfg).unwrap();
        assert_eq!((log.len(), log.t[0]), (200, 0.0));
        (0..100)
            .map(|i| {
                let d = evaluate(&g, &traj.eval(log.t[i])).unwrap();
                (d.joint.acc - Vector2::from(log.theta_ddot[i])).amax()
            })
            .fold(0.0, f64::max)
    };
    let with = worst(&short(0.2));
    let mut cfg = short(0.2);
    cfg.lead_in_s = 0.0;
    let without = worst(&cfg);
    println!("first 0.1 s: |θ̈ − θ̈_d| ≤ {with:.2} rad/s² (without lead-in {without:.1})");
    assert!(with < 5.0, "{with}");
    assert!(without > 50.0, "{without}");
    // Defaults and checks.
    assert_eq!(SimConfig::default().lead_in_s, 2.0);
    assert_eq!(short(1.0).lead_in_samples(), 2000);
    let mut c = short(1.0);
    c.lead_in_s = -1.0;
    let e = simulate(&Params::aras_diamond(), &traj, &c)
        .unwrap_err()
        .to_string();
    assert!(e.contains("lead_in_s"), "{e}");
}
