//! Time stamps as labs log them (jitter, clock epochs, milliseconds) and
//! isolated glitches: the reader's rate estimate, its warnings and refusals,
//! and the glitch detector with its four actions.

use aras_log::{
    GlitchAction, GlitchKind, GlitchOptions, LogError, ReadOptions, TimeUnit, Warning,
    apply_glitches, find_glitches, read_log_from,
};
use rand::{RngExt, SeedableRng};

/// A log of `n` rows with times `time(i)` (printed with `{}`), smooth
/// angles quantised like a 4096-count encoder behind a 10:1 gear, and
/// torques with Coulomb-like reversals and Gaussian noise.
fn csv(n: usize, time: impl Fn(usize) -> String, seed: u64) -> String {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let q = std::f64::consts::TAU / 40960.0;
    let mut s = String::from("t,theta1,theta2,tau1,tau2\n");
    for i in 0..n {
        let x = i as f64 * 1e-3;
        let th1 = 2.0 + 0.3 * (std::f64::consts::TAU * 0.5 * x).sin();
        let th2 = 0.6 + 0.2 * (std::f64::consts::TAU * 0.3 * x).cos();
        let w1 = (std::f64::consts::TAU * 0.5 * x).cos();
        let noise = |r: &mut rand::rngs::StdRng| {
            let u: f64 = r.random::<f64>() + r.random::<f64>() + r.random::<f64>() - 1.5;
            0.01 * u * 2.0
        };
        let tau1 = 0.4 * w1.signum() + 0.5 * w1 + noise(&mut rng);
        let tau2 = -0.3 * (std::f64::consts::TAU * 0.3 * x).sin() + noise(&mut rng);
        s += &format!(
            "{},{},{},{tau1},{tau2}\n",
            time(i),
            (th1 / q).round() * q,
            (th2 / q).round() * q
        );
    }
    s
}

fn read(text: &str, opts: &ReadOptions) -> Result<aras_log::Log, LogError> {
    read_log_from(text.as_bytes(), "lab.csv", opts)
}

#[test]
fn jittered_stamps_give_the_true_rate_and_a_jitter_warning() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let jitter: Vec<f64> = (0..20_000)
        .map(|_| (rng.random::<f64>() - 0.5) * 4e-4)
        .collect();
    let text = csv(20_000, |i| format!("{}", i as f64 * 1e-3 + jitter[i]), 1);
    let log = read(&text, &ReadOptions::default()).unwrap();
    // The span over the whole intervals: the error is the two end stamps'
    // jitter over 19 999 steps, at most 0.4 ms / 19 999 = 2·10⁻⁸ s.
    // (The median of the jittered steps is off by microseconds.)
    let dt = log.summary.nominal_step_s;
    assert!((dt - 1e-3).abs() < 2.1e-8, "{dt}");
    // Steps u_i − u_{i−1} of uniform ±0.2 ms stamp jitter: RMS 0.4/√6 ms.
    let rms = log.summary.timing.jitter_rms_s;
    let expected = 4e-4 / 6f64.sqrt();
    assert!((rms / expected - 1.0).abs() < 0.03, "{rms} vs {expected}");
    assert!(log.summary.timing.jitter_max_s <= 4e-4);
    let w = log
        .warnings
        .iter()
        .find(|w| matches!(w, Warning::Jitter { .. }))
        .expect("a jitter warning");
    let msg = w.to_string();
    assert!(msg.contains(&format!("{:.3} ms RMS", rms * 1e3)), "{msg}");
    // A clean log has no jitter warning.
    let clean = read(
        &csv(2000, |i| format!("{}", i as f64 * 1e-3), 1),
        &Default::default(),
    )
    .unwrap();
    assert!(clean.warnings.is_empty(), "{:?}", clean.warnings);
    assert!(clean.summary.timing.jitter_rms_s < 1e-15);
}

#[test]
fn epoch_stamps_keep_every_row_and_warn_about_precision() {
    let n = 20_000;
    let text = csv(n, |i| format!("{:.6}", 1.7e9 + i as f64 * 1e-3), 2);
    let log = read(&text, &ReadOptions::default()).unwrap();
    assert_eq!(log.len(), n);
    assert_eq!(log.t[0], 0.0);
    assert_eq!(log.summary.timing.offset_s, 1.7e9);
    // f64 spacing at 1.7e9 is 2^-22 s = 0.238 µs: each stamp is within half
    // of it, and so is every time counted from the first row.
    let ulp = 2f64.powi(-22);
    for (i, t) in log.t.iter().enumerate() {
        assert!((t - i as f64 * 1e-3).abs() <= ulp, "row {i}: {t}");
    }
    let dt = log.summary.nominal_step_s;
    // The end stamps' rounding (≤ one spacing) over the 20 s span: 1.2e-8
    // relative; the median of the quantised steps is off by up to 2.4e-4.
    assert!((dt / 1e-3 - 1.0).abs() < 1.2e-8, "{dt}");
    let w = log.warnings[0].to_string();
    assert!(matches!(log.warnings[0], Warning::TimeOffset { .. }), "{w}");
    assert!(w.contains("0.238 µs"), "{w}");
    // Quantised epoch steps are not jitter worth a warning.
    assert!(
        !log.warnings
            .iter()
            .any(|w| matches!(w, Warning::Jitter { .. }))
    );
}

#[test]
fn a_step_of_one_asks_whether_t_is_in_seconds() {
    let ms = csv(2000, |i| format!("{i}"), 4);
    let e = read(&ms, &ReadOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, LogError::TimeUnit { flag: "ms", .. }), "{msg}");
    assert!(msg.contains("is t in seconds?"), "{msg}");
    assert!(msg.contains("a step of 1 looks like milliseconds"), "{msg}");
    assert!(msg.contains("--time-unit ms"), "{msg}");
    let as_ms = ReadOptions {
        time_unit: Some(TimeUnit::Milliseconds),
        ..Default::default()
    };
    let log = read(&ms, &as_ms).unwrap();
    assert!((log.summary.sample_rate_hz - 1000.0).abs() < 1e-9);
    assert!((log.t[1999] - 1.999).abs() < 1e-12);
    // Said to be seconds: accepted as 1 Hz.
    let as_s = ReadOptions {
        time_unit: Some(TimeUnit::Seconds),
        ..Default::default()
    };
    assert_eq!(read(&ms, &as_s).unwrap().summary.sample_rate_hz, 1.0);
    // Microseconds and nanoseconds are named as such.
    let us = csv(100, |i| format!("{}", i * 1000), 4);
    assert!(matches!(
        read(&us, &Default::default()),
        Err(LogError::TimeUnit { flag: "us", .. })
    ));
    let ns = csv(100, |i| format!("{}", i * 1_000_000), 4);
    assert!(matches!(
        read(&ns, &Default::default()),
        Err(LogError::TimeUnit { flag: "ns", .. })
    ));
    let log = read(
        &ns,
        &ReadOptions {
            time_unit: Some(TimeUnit::Nanoseconds),
            ..Default::default()
        },
    )
    .unwrap();
    assert!((log.summary.nominal_step_s - 1e-3).abs() < 1e-15);
    // Epoch milliseconds: the offset goes first, then the unit question.
    let epoch_ms = csv(100, |i| format!("{}", 1_700_000_000_000u64 + i as u64), 4);
    assert!(matches!(
        read(&epoch_ms, &Default::default()),
        Err(LogError::TimeUnit { flag: "ms", .. })
    ));
    // A slow log whose step is not a whole number is not questioned.
    let slow = csv(100, |i| format!("{}", i as f64 * 0.25), 4);
    assert!(read(&slow, &Default::default()).is_ok());
}

fn uniform(n: usize, seed: u64) -> String {
    csv(n, |i| format!("{}", i as f64 * 1e-3), seed)
}

/// Replaces field `col` (0-based) of data row `row` by `value`.
fn corrupt(text: &str, row: usize, col: usize, value: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut f: Vec<String> = lines[row + 1].split(',').map(String::from).collect();
    f[col] = value.into();
    lines[row + 1] = f.join(",");
    lines.join("\n") + "\n"
}

#[test]
fn healthy_noisy_quantised_logs_with_reversals_have_no_glitches() {
    for seed in 0..5 {
        let log = read(&uniform(20_000, seed), &Default::default()).unwrap();
        let g = find_glitches(&log, &GlitchOptions::default());
        assert!(g.is_empty(), "seed {seed}: {:?}", &g[..g.len().min(3)]);
        // Also motionless, quantised (a MAD of 0).
        let still = csv(3000, |i| format!("{}", i as f64 * 1e-3), seed)
            .lines()
            .enumerate()
            .map(|(k, l)| {
                if k == 0 {
                    l.to_string()
                } else {
                    let f: Vec<&str> = l.split(',').collect();
                    format!("{},2.0,0.6,{},{}", f[0], f[3], f[4])
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let log = read(&still, &Default::default()).unwrap();
        assert!(find_glitches(&log, &GlitchOptions::default()).is_empty());
    }
}

#[test]
fn one_bad_encoder_sample_is_refused_by_line_and_column() {
    let good = uniform(20_000, 9);
    let log0 = read(&good, &Default::default()).unwrap();
    // Row 799 is on line 801 (the header is line 1). One encoder count is
    // 1.5e-4 rad; the bad sample is 0.02 rad (130 counts) off.
    let bad_value = log0.theta[0][799] + 0.02;
    let text = corrupt(&good, 799, 1, &format!("{bad_value}"));
    let log = read(&text, &Default::default()).unwrap();
    let g = find_glitches(&log, &GlitchOptions::default());
    assert_eq!(g.len(), 1, "{g:?}");
    assert_eq!((g[0].row, g[0].line, g[0].column), (799, Some(801), 2));
    assert_eq!(g[0].channel, "theta1");
    assert_eq!(g[0].kind, GlitchKind::Spike);
    // The neighbours' cubic gives the true value to within an encoder count.
    assert!((g[0].expected - log0.theta[0][799]).abs() < 1.6e-4);

    let refuse = GlitchOptions {
        action: GlitchAction::Refuse,
        ..Default::default()
    };
    let e = apply_glitches(log.clone(), &refuse).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("line 801, column 2: theta1 = "), "{msg}");
    assert!(msg.contains("--glitches repair"), "{msg}");

    let repair = GlitchOptions {
        action: GlitchAction::Repair,
        ..Default::default()
    };
    let (fixed, found) = apply_glitches(log.clone(), &repair).unwrap();
    assert_eq!(found.len(), 1);
    assert!((fixed.theta[0][799] - log0.theta[0][799]).abs() < 1.6e-4);
    assert_eq!(fixed.theta[0][800], log0.theta[0][800]);
    assert!(matches!(
        fixed.warnings.last(),
        Some(Warning::Glitches { count: 1, .. })
    ));

    let drop = GlitchOptions {
        action: GlitchAction::Drop,
        ..Default::default()
    };
    let (dropped, _) = apply_glitches(log.clone(), &drop).unwrap();
    assert_eq!(dropped.len(), 19_999);
    assert_eq!(dropped.t[799], log0.t[800]);
    assert_eq!(dropped.summary.lines.line(799), Some(802));
    let w = dropped.summary.worst_step.unwrap();
    assert!((w.ratio - 2.0).abs() < 1e-9 && w.line == 802, "{w:?}");

    let warn = GlitchOptions {
        action: GlitchAction::Warn,
        ..Default::default()
    };
    let (kept, _) = apply_glitches(log, &warn).unwrap();
    assert_eq!(kept.theta[0][799], bad_value);
    assert!(
        kept.warnings
            .last()
            .unwrap()
            .to_string()
            .contains("line 801")
    );
}

#[test]
fn a_torque_spike_and_a_torque_beyond_the_limit_are_found() {
    let good = uniform(5000, 5);
    // A 5 N·m spike on a joint whose torques stay within ±1 N·m.
    let text = corrupt(&good, 2500, 4, "5.0");
    let log = read(&text, &Default::default()).unwrap();
    let g = find_glitches(&log, &GlitchOptions::default());
    assert_eq!(g.len(), 1, "{g:?}");
    assert_eq!(
        (g[0].channel.as_str(), g[0].line, g[0].column),
        ("tau2", Some(2502), 5)
    );
    // Stated limits: 0.8 N·m; a sustained 1.3 N·m (1.6×) is beyond 1.5×.
    let mut text = good.clone();
    for r in 1000..1010 {
        text = corrupt(&text, r, 3, "1.3");
    }
    let log = read(&text, &Default::default()).unwrap();
    let opts = GlitchOptions {
        torque_limit: Some(vec![0.8, 0.8]),
        ..Default::default()
    };
    let g = find_glitches(&log, &opts);
    assert_eq!(g.len(), 10, "{g:?}");
    assert!(
        g.iter()
            .all(|g| g.kind == GlitchKind::BeyondLimit && g.channel == "tau1")
    );
    // Without the limit, a sustained plateau is not an isolated glitch.
    assert!(find_glitches(&log, &GlitchOptions::default()).is_empty());
    // Off finds nothing; bad options are refused.
    let off = GlitchOptions {
        action: GlitchAction::Off,
        ..Default::default()
    };
    assert!(find_glitches(&log, &off).is_empty());
    let bad = GlitchOptions {
        threshold: f64::NAN,
        ..Default::default()
    };
    assert!(matches!(
        apply_glitches(log, &bad),
        Err(LogError::InvalidOption { .. })
    ));
}

#[test]
fn jitter_and_missing_samples_are_not_glitches() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(8);
    let jitter: Vec<f64> = (0..20_000)
        .map(|_| (rng.random::<f64>() - 0.5) * 4e-4)
        .collect();
    let text = csv(20_000, |i| format!("{}", i as f64 * 1e-3 + jitter[i]), 8);
    let log = read(&text, &Default::default()).unwrap();
    assert!(find_glitches(&log, &GlitchOptions::default()).is_empty());
    // Rows 5000–5002 and 9000–9019 missing: the neighbours' cubic at their
    // logged times bridges them.
    let gappy: String = uniform(20_000, 8)
        .lines()
        .enumerate()
        .filter(|(k, _)| !(5001..5004).contains(k) && !(9001..9021).contains(k))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    let opts = ReadOptions {
        step_tolerance: 100.0,
        ..Default::default()
    };
    let log = read(&gappy, &opts).unwrap();
    let g = find_glitches(&log, &GlitchOptions::default());
    assert!(g.is_empty(), "{g:?}");
}
