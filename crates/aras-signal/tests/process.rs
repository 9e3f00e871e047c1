//! End-to-end `process` on synthetic logs generated from a known task-space
//! trajectory (finite Fourier series, (74)–(76)) through `aras-kin`.

use std::f64::consts::TAU;

use aras_kin::{Geometry, Motion, evaluate, inverse};
use aras_log::{ReadOptions, read_log_from};
use aras_signal::{
    Bandwidth, BandwidthMethod, DerivativeMethod, FilterSpec, PeriodSource, ProcessError,
    ProcessOptions, process,
};
use aras_testkit::error_chain as chain;
use nalgebra::Vector2;

const PERIOD: f64 = 2.0;
const DT: f64 = 0.001;

/// X, Ẋ, Ẍ of a 3-harmonic trajectory inside the workspace (77).
fn trajectory(t: f64) -> Motion {
    let w = TAU / PERIOD;
    let mut x = Vector2::new(85f64.to_radians(), 60f64.to_radians());
    let mut xd = Vector2::zeros();
    let mut xdd = Vector2::zeros();
    let amp = [[0.3, 0.1, 0.05], [0.12, 0.05, 0.02]];
    for (c, a) in amp.iter().enumerate() {
        for (l, al) in a.iter().enumerate() {
            let wl = w * (l + 1) as f64;
            let ph = 0.4 * (l + c) as f64;
            x[c] += al * (wl * t + ph).sin();
            xd[c] += al * wl * (wl * t + ph).cos();
            xdd[c] -= al * wl * wl * (wl * t + ph).sin();
        }
    }
    Motion::new(x, xd, xdd)
}

/// A log of `periods` periods; optional logged derivative columns.
fn log_text(periods: usize, with_derivatives: bool) -> String {
    let g = Geometry::aras_diamond();
    let mut s = String::from("t,theta1,theta2,tau1,tau2");
    if with_derivatives {
        s += ",dtheta1,dtheta2,ddtheta1,ddtheta2";
    }
    s += "\n";
    let n = (periods as f64 * PERIOD / DT).round() as usize;
    for i in 0..n {
        let t = i as f64 * DT;
        let m = trajectory(t);
        let k = evaluate(&g, &m).unwrap();
        let th = inverse(&g, &m.pos).unwrap().theta;
        s += &format!(
            "{t},{},{},{},{}",
            th[0],
            th[1],
            0.3 * m.acc[0],
            -0.2 * m.vel[1]
        );
        if with_derivatives {
            let (a, b) = (k.joint.vel, k.joint.acc);
            s += &format!(",{},{},{},{}", a[0], a[1], b[0], b[1]);
        }
        s += "\n";
    }
    s
}

fn max_err(got: &[f64], t: &[f64], f: impl Fn(f64) -> f64) -> f64 {
    got.iter()
        .zip(t)
        .map(|(g, &t)| (g - f(t)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn periodic_record_without_filter_is_exact() {
    let log = read_log_from(
        log_text(3, false).as_bytes(),
        "p.csv",
        &ReadOptions::default(),
    )
    .unwrap();
    let opts = ProcessOptions {
        filter: Bandwidth::Off,
        period: PeriodSource::Seconds(PERIOD),
        ..ProcessOptions::default()
    };
    let out = process(
        &log,
        &opts,
        &aras_kin::task_motion(&Geometry::aras_diamond()),
    )
    .unwrap();
    let s = &out.samples;
    assert_eq!(s.len(), 2000);
    assert_eq!(out.summary.derivative, DerivativeMethod::Spectral);
    let p = out.summary.periods.as_ref().unwrap();
    assert_eq!(
        (
            p.periods_averaged,
            p.periods_per_block,
            p.samples_per_block,
            out.summary.samples_dropped
        ),
        (3, 1, 2000, 0)
    );
    // The logged θ are exact to ~1e-16: averaging identical periods, spectral
    // derivatives and the Jacobian keep X to 1e-12, Ẋ to 1e-9 (×ω ≈ 10),
    // Ẍ to 1e-7 (×ω² ≈ 100, and J⁻¹ with |K| ≈ 0.8).
    for c in 0..2 {
        assert!(max_err(&s.x[c], &s.t, |t| trajectory(t).pos[c]) < 1e-12);
        assert!(max_err(&s.x_dot[c], &s.t, |t| trajectory(t).vel[c]) < 1e-9);
        assert!(max_err(&s.x_ddot[c], &s.t, |t| trajectory(t).acc[c]) < 1e-7);
    }
    // τ passes unchanged (no filter) and θ̇ = J Ẋ holds sample by sample.
    assert!(max_err(&s.tau[0], &s.t, |t| 0.3 * trajectory(t).acc[0]) < 1e-12);
    let serialized = serde_json::to_string(&out.summary).unwrap();
    assert!(
        serialized.contains("\"periods_averaged\":3"),
        "{serialized}"
    );
}

#[test]
fn ten_hz_filter_barely_touches_the_dynamics() {
    let log = read_log_from(
        log_text(2, false).as_bytes(),
        "f.csv",
        &ReadOptions::default(),
    )
    .unwrap();
    let opts = ProcessOptions {
        filter: Bandwidth::Fixed(FilterSpec::default()),
        period: PeriodSource::Seconds(PERIOD),
        ..ProcessOptions::default()
    };
    let out = process(
        &log,
        &opts,
        &aras_kin::task_motion(&Geometry::aras_diamond()),
    )
    .unwrap();
    let f = out.summary.filter.as_ref().unwrap();
    assert_eq!((f.order, f.cutoff_hz), (4, 10.0));
    // X's fastest harmonic is 1.5 Hz (|H|² = 1 − 3e-7 there), but θ = IK(X)
    // is nonlinear and carries product harmonics up to a few Hz (|H|² = 1 −
    // 7e-5 at 3 Hz), which the filter trims slightly: observed 2.9e-5 rad/s²
    // on Ẍ of amplitude ≈ 5 rad/s², so 1e-4 (2e-5 relative).
    let s = &out.samples;
    for c in 0..2 {
        let e = max_err(&s.x_ddot[c], &s.t, |t| trajectory(t).acc[c]);
        assert!(e < 1e-4, "{e}");
    }
}

#[test]
fn non_periodic_record_uses_central_differences_and_drops_edges() {
    let log = read_log_from(
        log_text(1, false).as_bytes(),
        "n.csv",
        &ReadOptions::default(),
    )
    .unwrap();
    let opts = ProcessOptions {
        filter: Bandwidth::Fixed(FilterSpec::default()),
        period: PeriodSource::Off,
        derivative: DerivativeMethod::CentralDifference,
        ..ProcessOptions::default()
    };
    let out = process(
        &log,
        &opts,
        &aras_kin::task_motion(&Geometry::aras_diamond()),
    )
    .unwrap();
    assert_eq!(out.summary.derivative, DerivativeMethod::CentralDifference);
    assert_eq!(out.samples.len(), 1998);
    assert_eq!(out.summary.samples_dropped, 2);
    assert_eq!(out.samples.t[0], 0.001);
    // The odd extension flips the curvature at the ends, so filtering a
    // non-periodic record distorts about 3/fc = 0.3 s at each end (measured:
    // 4e-2 rad/s at the very ends, 3e-4 at 0.2 s). Inside, central
    // differences at h = 1 ms are accurate to h^2/6 |x'''| ~ 1e-5 (observed
    // 5e-6); 1e-4 leaves room yet catches a one-sample misalignment (~1e-3).
    let s = &out.samples;
    let mid = 400..1600;
    for c in 0..2 {
        let e = max_err(&s.x_dot[c][mid.clone()], &s.t[mid.clone()], |t| {
            trajectory(t).vel[c]
        });
        assert!(e < 1e-4, "{e}");
    }
}

#[test]
fn logged_derivatives_are_used_when_asked() {
    let log = read_log_from(
        log_text(1, true).as_bytes(),
        "d.csv",
        &ReadOptions::default(),
    )
    .unwrap();
    let opts = ProcessOptions {
        filter: Bandwidth::Off,
        period: PeriodSource::Off,
        use_logged_derivatives: true,
        ..ProcessOptions::default()
    };
    let out = process(
        &log,
        &opts,
        &aras_kin::task_motion(&Geometry::aras_diamond()),
    )
    .unwrap();
    assert_eq!(out.samples.len(), 2000);
    assert_eq!(
        out.summary.derivative_source,
        "logged dtheta/ddtheta columns"
    );
    let s = &out.samples;
    for c in 0..2 {
        assert!(max_err(&s.x_dot[c], &s.t, |t| trajectory(t).vel[c]) < 1e-12);
        assert!(max_err(&s.x_ddot[c], &s.t, |t| trajectory(t).acc[c]) < 1e-10);
    }
    // By default they are ignored, with a note.
    let opts = ProcessOptions {
        period: PeriodSource::Off,
        ..ProcessOptions::default()
    };
    let out = process(
        &log,
        &opts,
        &aras_kin::task_motion(&Geometry::aras_diamond()),
    )
    .unwrap();
    assert!(
        out.notes
            .iter()
            .any(|n| n.contains("logged derivative columns ignored"))
    );
}

#[test]
fn wrong_period_is_a_clear_error() {
    let log = read_log_from(
        log_text(3, false).as_bytes(),
        "w.csv",
        &ReadOptions::default(),
    )
    .unwrap();
    let opts = ProcessOptions {
        period: PeriodSource::Seconds(1.5),
        ..ProcessOptions::default()
    };
    let e = process(
        &log,
        &opts,
        &aras_kin::task_motion(&Geometry::aras_diamond()),
    )
    .unwrap_err();
    assert!(matches!(e, ProcessError::PeriodsDisagree { .. }), "{e}");
    let m = e.to_string();
    assert!(m.contains("differs from the average period by"), "{m}");
    assert!(m.contains("not periodic with period 1.5 s"), "{m}");
    let opts = ProcessOptions {
        filter: Bandwidth::Fixed(FilterSpec {
            order: 4,
            cutoff_hz: 800.0,
        }),
        period: PeriodSource::Off,
        ..ProcessOptions::default()
    };
    let m = chain(
        &process(
            &log,
            &opts,
            &aras_kin::task_motion(&Geometry::aras_diamond()),
        )
        .unwrap_err(),
    );
    assert!(m.contains("cut-off 800 Hz is invalid"), "{m}");
}

#[test]
fn automatic_bandwidth_on_a_periodic_record_is_the_exact_series() {
    let log = read_log_from(
        log_text(2, false).as_bytes(),
        "a.csv",
        &ReadOptions::default(),
    )
    .unwrap();
    let opts = ProcessOptions {
        filter: Bandwidth::Auto,
        period: PeriodSource::Seconds(PERIOD),
        ..ProcessOptions::default()
    };
    let out = process(
        &log,
        &opts,
        &aras_kin::task_motion(&Geometry::aras_diamond()),
    )
    .unwrap();
    let bw = &out.summary.bandwidth;
    assert_eq!(bw.method, BandwidthMethod::HarmonicSeries, "{bw:?}");
    assert!(out.summary.filter.is_none());
    // Noise-free: the series keeps every harmonic above rounding, so Ẍ is
    // as exact as with no filter at all (the unfiltered test's 1e-7).
    let s = &out.samples;
    for c in 0..2 {
        let e = max_err(&s.x_ddot[c], &s.t, |t| trajectory(t).acc[c]);
        assert!(e < 1e-7, "{e}");
    }
    let json = serde_json::to_string(&out.summary).unwrap();
    assert!(json.contains("\"method\":\"harmonic_series\""), "{json}");
}

/// A sample the caller's coordinates reject is an error naming the sample,
/// with the mapping's own error as its source; the identity maps anything.
#[test]
fn a_coordinate_failure_names_the_sample_and_keeps_its_cause() {
    let log = read_log_from(
        log_text(1, false).as_bytes(),
        "c.csv",
        &ReadOptions::default(),
    )
    .unwrap();
    // A "robot" whose coordinates are undefined once θ1 passes a value the
    // trajectory reaches only after the first sample.
    let limit = log.theta[0][0]
        + 0.05 * (log.theta[0].iter().cloned().fold(f64::MIN, f64::max) - log.theta[0][0]);
    let picky = |m: aras_signal::Motion| -> Result<aras_signal::Motion, std::fmt::Error> {
        if m.pos[0] > limit {
            Err(std::fmt::Error)
        } else {
            Ok(m)
        }
    };
    let e = process(&log, &ProcessOptions::default(), &picky).unwrap_err();
    let ProcessError::Coordinates { index, t, .. } = &e else {
        panic!("{e}");
    };
    assert!(*index > 0 && *t > 0.0, "{e}");
    let c = chain(&e);
    assert!(
        c.contains(&format!("sample {index}")) && c.contains("an error occurred when formatting"),
        "{c}"
    );
    let ok = process(
        &log,
        &ProcessOptions::default(),
        &aras_signal::JointCoordinates,
    )
    .unwrap();
    assert_eq!(ok.samples.x, ok.samples.theta);
    assert_eq!(ok.samples.x_ddot, ok.samples.theta_ddot);

    // The samples are mapped in parallel chunks (4096 samples each); the
    // one named is the first that fails, as a sequential map would name
    // it, though samples in later chunks fail too: 8 periods, not averaged.
    let long = read_log_from(
        log_text(8, false).as_bytes(),
        "long.csv",
        &ReadOptions::default(),
    )
    .unwrap();
    let plain = ProcessOptions {
        period: PeriodSource::Off,
        ..ProcessOptions::default()
    };
    let theta1 = process(&long, &plain, &aras_signal::JointCoordinates)
        .unwrap()
        .samples
        .theta[0]
        .clone();
    let e = process(&long, &plain, &picky).unwrap_err();
    let ProcessError::Coordinates { index, .. } = &e else {
        panic!("{e}");
    };
    let first = theta1.iter().position(|&q| q > limit).unwrap();
    let failing = theta1.iter().filter(|&&q| q > limit).count();
    assert!(
        theta1.len() > 3 * 4096 && theta1[4096..].iter().any(|&q| q > limit),
        "{failing} of {} samples fail",
        theta1.len()
    );
    assert_eq!(*index, first, "{e}");
}

/// Held torques (`aras_log::TorqueTiming::Held`): every route evaluates the
/// motion half a step after each sample, the hold's midpoint; sampled
/// torques keep the motion at the samples.
#[test]
fn held_torques_move_the_motion_to_the_holds_midpoint() {
    let g = Geometry::aras_diamond();
    let truth = |t: f64, j: usize| inverse(&g, &trajectory(t).pos).unwrap().theta[j];
    let fixed = Bandwidth::Fixed(FilterSpec {
        order: 4,
        cutoff_hz: 40.0,
    });
    for (filter, period, rows) in [
        (
            Bandwidth::Auto,
            PeriodSource::Seconds(PERIOD),
            aras_signal::OutputRows::EveryRow,
        ),
        (
            Bandwidth::Auto,
            PeriodSource::Seconds(PERIOD),
            aras_signal::OutputRows::Averaged,
        ),
        (fixed, PeriodSource::Off, aras_signal::OutputRows::EveryRow),
    ] {
        let opts = ProcessOptions {
            filter,
            period,
            rows,
            ..ProcessOptions::default()
        };
        let mut log = read_log_from(
            log_text(3, false).as_bytes(),
            "x.csv",
            &ReadOptions::default(),
        )
        .unwrap();
        let sampled = process(&log, &opts, &aras_signal::JointCoordinates).unwrap();
        log.sidecar.torques = Some(aras_log::TorqueTiming::Held);
        let held = process(&log, &opts, &aras_signal::JointCoordinates).unwrap();
        // Rows away from the filter's edges.
        let n = held.samples.len();
        let inner = n / 10..n - n / 10;
        for j in 0..2 {
            let err = |s: &aras_signal::Processed, lag: f64| -> f64 {
                inner
                    .clone()
                    .map(|i| (s.samples.theta[j][i] - truth(s.samples.t[i] + lag, j)).abs())
                    .fold(0.0, f64::max)
            };
            // The half-step move is ≈ |θ̇| h/2 ≈ 3e-4 rad here; both routes
            // land on their own instant to 1 % of it.
            let (at_mid, at_sample) = (err(&held, DT / 2.0), err(&sampled, 0.0));
            assert!(
                at_mid < 3e-6 && at_sample < 3e-6,
                "{filter:?} {rows:?} joint {j}: {at_mid:e} {at_sample:e}"
            );
            assert!(
                err(&held, 0.0) > 30.0 * at_mid,
                "{filter:?} {rows:?} joint {j}: the motion did not move"
            );
        }
        assert!(
            held.summary.bandwidth.reason.contains("midpoint"),
            "{}",
            held.summary.bandwidth.reason
        );
        assert_eq!(held.summary.torque_timing, aras_log::TorqueTiming::Held);
        assert_eq!(held.summary.motion_shift_steps, 0.5);
        assert_eq!(
            sampled.summary.torque_timing,
            aras_log::TorqueTiming::Sampled
        );
        assert_eq!(sampled.summary.motion_shift_steps, 0.0);
    }
}

/// A log of three joints: processed in three coordinates with the same
/// period and bandwidth for all (each joint's samples as if it were alone),
/// refused by the two-coordinate `process` with the joint counts named.
#[test]
fn any_number_of_joints_is_processed_and_a_wrong_dimension_refused() {
    use aras_signal::{Bandwidth, JointCoordinates, PeriodSource, ProcessOptions, process_in};
    let fs = 1000.0;
    let mut csv = String::from("t,theta1,theta2,theta3,tau1,tau2,tau3\n");
    for i in 0..6000 {
        let t = i as f64 / fs;
        let w = TAU * 0.5;
        let q = [
            0.3 * (w * t).sin(),
            -0.2 * (2.0 * w * t).cos(),
            0.1 * (3.0 * w * t).sin(),
        ];
        csv += &format!(
            "{t},{},{},{},{},{},{}\n",
            q[0],
            q[1],
            q[2],
            2.0 * q[0],
            -q[1],
            0.5 * q[2]
        );
    }
    let log = read_log_from(csv.as_bytes(), "three.csv", &ReadOptions::default()).unwrap();
    let opts = ProcessOptions {
        filter: Bandwidth::Auto,
        period: PeriodSource::Seconds(2.0),
        ..ProcessOptions::default()
    };
    let out = process_in::<nalgebra::Dyn>(&log, &opts, &JointCoordinates).unwrap();
    assert_eq!((out.samples.joints(), out.samples.len()), (3, 2000));
    let h = out.summary.bandwidth.harmonics.as_ref().unwrap();
    assert_eq!(h.len(), 3);
    // Exact series: θ̈ of the third joint is −(3ω)² θ to rounding.
    let w3 = 3.0 * TAU * 0.5;
    for i in (0..2000).step_by(97) {
        let (x, a) = (out.samples.x[2][i], out.samples.x_ddot[2][i]);
        assert!(
            (a + w3 * w3 * x).abs() < 1e-6,
            "{i}: {a} vs {}",
            -w3 * w3 * x
        );
    }
    // One joint's processing does not depend on the others': joint 3 alone.
    let mut one = String::from("t,theta1,tau1\n");
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        one += &format!("{},{},{}\n", f[0], f[3], f[6]);
    }
    let single = read_log_from(one.as_bytes(), "one.csv", &ReadOptions::default()).unwrap();
    let alone = process_in::<nalgebra::Dyn>(&single, &opts, &JointCoordinates).unwrap();
    assert_eq!(alone.samples.x_ddot[0], out.samples.x_ddot[2]);
    let e = process(&log, &opts, &JointCoordinates).unwrap_err();
    assert!(
        matches!(
            e,
            ProcessError::Joints {
                joints: 3,
                expected: 2,
                ..
            }
        ),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("has 3 joint(s) but the model's coordinates take 2"),
        "{e}"
    );
}
