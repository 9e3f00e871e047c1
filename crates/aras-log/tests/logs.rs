//! The log reader on the committed fixtures: every file in
//! `fixtures/logs/bad/` must fail with its specific message, every file in
//! `fixtures/logs/good/` must read; plus saturation, chunked reading and
//! streaming input.

use std::path::PathBuf;

use aras_log::{
    Columns, LogReader, ReadOptions, Sensors, SidecarSource, Warning, read_log, read_log_from,
};
use aras_testkit::{assert_source_not_repeated, io_source_kind};

fn fixture(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/logs")
        .join(rel)
}

fn error_of(name: &str) -> String {
    let path = fixture(&format!("bad/{name}"));
    match read_log(&path, &ReadOptions::default()) {
        Ok(_) => panic!("{name} was accepted"),
        Err(e) => {
            let msg = e.to_string();
            // Every message names the file it is about.
            assert!(msg.contains(name.trim_end_matches(".csv")), "{name}: {msg}");
            msg
        }
    }
}

/// (file, substrings its message must contain).
const CORPUS: &[(&str, &[&str])] = &[
    (
        "missing_time.csv",
        &[
            ":1: required column `t` is missing",
            "name the time column `t`",
        ],
    ),
    (
        "missing_theta2.csv",
        &[
            ":1: required column `theta2` is missing",
            "(the header has: t, theta1, tau1, tau2)",
        ],
    ),
    (
        "missing_torque.csv",
        &["required column `tau1` is missing", "motor currents i1, i2"],
    ),
    (
        "duplicate_column.csv",
        &[":1:5: column `tau1` appears twice (columns 4 and 5)"],
    ),
    (
        "empty_column_name.csv",
        &[":1:3: column 3 of the header has no name"],
    ),
    (
        "semicolon.csv",
        &[
            ":1: the header is separated by ';'",
            "replace every ';' by ','",
        ],
    ),
    (
        "tab_separated.csv",
        &[
            ":1: the header is separated by tabs",
            "replace every tab by ','",
        ],
    ),
    (
        "huge_value.csv",
        &[
            ":7:4: `tau1` value \"1e300\" is beyond ±1e12",
            "drop or repair the row",
        ],
    ),
    (
        "unpaired_derivative.csv",
        &["column `dtheta1` is present but `dtheta2` is not"],
    ),
    (
        "not_a_number.csv",
        &[":3:2: `theta1` value \"abc\" is not a number"],
    ),
    (
        "nan_value.csv",
        &[":6:4: `tau1` value \"NaN\" is not finite"],
    ),
    (
        "infinite_value.csv",
        &[":8:5: `tau2` value \"inf\" is not finite"],
    ),
    (
        "empty_field.csv",
        &[":4:3: `theta2` value \"\" is not a number: the field is empty"],
    ),
    (
        "too_few_fields.csv",
        &[":5: the row has 4 fields but the header has 5"],
    ),
    (
        "time_backwards.csv",
        &[":12:1: time does not increase: t = 0.009 s follows t = 0.01 s"],
    ),
    (
        "repeated_time.csv",
        &[":14:1: time does not increase: t = 0.011 s follows t = 0.011 s"],
    ),
    (
        "irregular_sampling.csv",
        &[
            ":22: irregular sampling: the worst step, 0.004 s ending at t = 0.023 s",
            "4.000× the nominal step 0.001 s (tolerance ±50%)",
        ],
    ),
    (
        "degrees.csv",
        &["angles look like degrees (max |theta1| = 116.7): convert to radians"],
    ),
    (
        "counts_in_theta.csv",
        &[
            "`theta1` reaches",
            "neither a plausible angle",
            "enc1, enc2",
        ],
    ),
    (
        "too_few_rows.csv",
        &["only 3 data rows, at least 16 are needed"],
    ),
    ("no_header.csv", &["no header line"]),
    (
        "currents_without_constants.csv",
        &["columns i1, i2 but no sensors.torque_constants is given"],
    ),
    (
        "unknown_sidecar_key.csv",
        &[
            "unknown_sidecar_key.json:2:",
            "unknown field `gear_ratio`",
            "remove or rename the key",
        ],
    ),
    (
        "wrong_format.csv",
        &["format = \"aras-log/2\" is invalid: this reader understands only \"aras-log/1\""],
    ),
    (
        "negative_gear_ratio.csv",
        &["sensors.gear_ratios[1] = -3 is invalid: it must be a positive finite number"],
    ),
    (
        "sidecar_syntax.csv",
        &[
            "sidecar_syntax.json:1:",
            "trailing comma",
            "one JSON object",
        ],
    ),
    (
        "zero_torque_constant.csv",
        &["sensors.torque_constants[0] = 0 is invalid", "N·m/A"],
    ),
    (
        "negative_period.csv",
        &["excitation.period_s = -10 is invalid"],
    ),
];

#[test]
fn every_bad_fixture_fails_with_its_own_message() {
    for (name, needles) in CORPUS {
        let msg = error_of(name);
        for n in *needles {
            assert!(msg.contains(n), "{name}:\n  message: {msg}\n  missing: {n}");
        }
    }
}

#[test]
fn corpus_covers_every_bad_file() {
    let dir = fixture("bad");
    let mut csvs: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".csv"))
        .collect();
    csvs.sort();
    let mut listed: Vec<String> = CORPUS.iter().map(|(n, _)| n.to_string()).collect();
    listed.sort();
    assert_eq!(csvs, listed);
    assert!(listed.len() >= 15);
}

#[test]
fn bom_crlf_comments_reordered_and_extra_columns_are_accepted() {
    let log = read_log(
        &fixture("good/bom_crlf_reordered.csv"),
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(log.len(), 40);
    assert_eq!(log.t[1], 0.001);
    assert_eq!(log.theta[0][0], 2.0);
    assert_eq!(log.theta[1][0], 0.6);
    assert_eq!(log.tau[1][1], -0.002513208);
    assert!(
        log.notes
            .iter()
            .any(|n| n == "extra columns ignored: temperature"),
        "{:?}",
        log.notes
    );
    assert!((log.summary.nominal_step_s - 0.001).abs() < 1e-15);
    assert!(log.theta_dot.is_none());
}

#[test]
fn encoder_counts_and_currents_convert_with_sidecar_constants() {
    let path = fixture("good/counts_currents.csv");
    let log = read_log(&path, &ReadOptions::default()).unwrap();
    let reference = read_log(
        &fixture("good/bom_crlf_reordered.csv"),
        &ReadOptions::default(),
    )
    .unwrap();
    // One count is 2π/(4096·10) rad: angles agree to half a count.
    let count = std::f64::consts::TAU / 40960.0;
    for c in 0..2 {
        for (a, b) in log.theta[c].iter().zip(&reference.theta[c]) {
            assert!((a - b).abs() <= 0.5 * count + 1e-12);
        }
        // τ = i·kt·N with currents rounded to 1e-9 A: error ≤ 0.5e-9·0.5.
        for (a, b) in log.tau[c].iter().zip(&reference.tau[c]) {
            assert!((a - b).abs() < 1e-9);
        }
    }
    assert_eq!(log.sidecar.excitation.period_s, Some(0.02));
    assert_eq!(log.summary.angle_source, "encoder counts");
    assert!(
        log.summary
            .sidecar
            .as_deref()
            .unwrap()
            .ends_with("counts_currents.json")
    );
    // Command-line constants override the sidecar.
    let opts = ReadOptions {
        sensors: Sensors {
            torque_constants: Some(vec![0.1, 0.1]),
            ..Sensors::default()
        },
        ..ReadOptions::default()
    };
    let doubled = read_log(&path, &opts).unwrap();
    assert!((doubled.tau[0][5] - 2.0 * log.tau[0][5]).abs() < 1e-15);
    assert!(doubled.notes.iter().any(|n| n.contains("override")));
}

fn synthetic(n: usize, tau: impl Fn(usize) -> f64) -> String {
    let mut s = String::from("t,theta1,theta2,tau1,tau2\n");
    for i in 0..n {
        let t = i as f64 * 0.001;
        s += &format!(
            "{t},{},{},{},0.5\n",
            2.0 + 0.1 * (t * 3.0).sin(),
            0.6,
            tau(i)
        );
    }
    s
}

#[test]
fn saturation_is_a_warning_with_time_spans() {
    // τ1 follows a sine clipped at ±0.8: flat at both extremes for long runs.
    let csv = synthetic(3000, |i| (i as f64 * 0.004).sin().clamp(-0.8, 0.8));
    let log = read_log_from(csv.as_bytes(), "sat.csv", &ReadOptions::default()).unwrap();
    let sats: Vec<&Warning> = log
        .warnings
        .iter()
        .filter(|w| matches!(w, Warning::Saturation { channel, .. } if channel == "tau1"))
        .collect();
    assert_eq!(sats.len(), 2, "{:?}", log.warnings);
    let Warning::Saturation { value, spans, .. } = sats[0] else {
        unreachable!()
    };
    assert_eq!(*value, 0.8);
    // sin(0.004 i) ≥ 0.8 for i in [232, 553] and one period (1571 samples) later.
    assert_eq!(spans.len(), 2);
    assert!((spans[1].t_start - spans[0].t_start - 1.571).abs() < 0.002);
    assert_eq!(spans[0].samples, 554 - 232);
    assert!((spans[0].t_start - 0.232).abs() < 1e-12);
    let text = sats[0].to_string();
    assert!(
        text.contains("tau1 sits flat at its maximum 0.8 N·m"),
        "{text}"
    );
    assert!(
        text.contains("0.2320–0.5530 s (322 samples from line 234)"),
        "{text}"
    );
    // The constant τ2 = 0.5 is flat too (at its maximum only, no duplicate).
    let flat2: Vec<_> = log
        .warnings
        .iter()
        .filter(|w| matches!(w, Warning::Saturation { channel, .. } if channel == "tau2"))
        .collect();
    assert_eq!(flat2.len(), 1);
    // A smooth torque raises no warning.
    let csv = synthetic(3000, |i| (i as f64 * 0.004).sin());
    let log = read_log_from(csv.as_bytes(), "ok.csv", &ReadOptions::default()).unwrap();
    assert!(
        log.warnings
            .iter()
            .all(|w| !matches!(w, Warning::Saturation { channel, .. } if channel == "tau1"))
    );
}

#[test]
fn chunked_reading_equals_whole_reading() {
    let csv = synthetic(10_000, |i| (i as f64 * 0.01).cos());
    let whole = read_log_from(csv.as_bytes(), "w.csv", &ReadOptions::default()).unwrap();
    let mut reader = LogReader::new(csv.as_bytes(), "w.csv", &ReadOptions::default()).unwrap();
    let mut chunk = Columns::default();
    let mut t = Vec::new();
    let mut tau = Vec::new();
    let mut calls = 0;
    while reader.read_rows(&mut chunk, 777).unwrap() > 0 {
        assert!(chunk.len() <= 777);
        t.extend_from_slice(&chunk.t);
        tau.extend_from_slice(&chunk.tau[0]);
        chunk.clear();
        calls += 1;
    }
    let report = reader.finish().unwrap();
    assert_eq!(calls, 10_000usize.div_ceil(777));
    assert_eq!(t, whole.t);
    assert_eq!(tau, whole.tau[0]);
    assert_eq!(report.summary, whole.summary);
}

#[test]
fn inline_sidecar_and_stream_names() {
    let csv = synthetic(100, |_| 0.0);
    let opts = ReadOptions {
        sidecar: SidecarSource::Text {
            name: "inline.json".into(),
            json: r#"{"excitation": {"period_s": 0.05}, "bogus": 1}"#.into(),
        },
        ..ReadOptions::default()
    };
    let e = read_log_from(csv.as_bytes(), "s.csv", &opts)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("inline.json:1:"), "{e}");
    assert!(e.contains("unknown field `bogus`"), "{e}");
    // Degree detection can be switched off for continuously rotating joints.
    let mut deg = String::from("t,theta1,theta2,tau1,tau2\n");
    for i in 0..20 {
        deg += &format!("{},{},1.0,0,0\n", i as f64 * 0.01, 100.0 + i as f64);
    }
    assert!(read_log_from(deg.as_bytes(), "d.csv", &ReadOptions::default()).is_err());
    let opts = ReadOptions {
        check_degrees: false,
        ..ReadOptions::default()
    };
    assert!(read_log_from(deg.as_bytes(), "d.csv", &opts).is_ok());
}

#[test]
fn invalid_options_are_reported() {
    let csv = synthetic(100, |_| 0.0);
    let opts = ReadOptions {
        step_tolerance: -1.0,
        ..ReadOptions::default()
    };
    let e = read_log_from(csv.as_bytes(), "o.csv", &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("invalid read option step_tolerance = -1"), "{e}");
}

#[test]
fn a_missing_log_names_the_file_and_keeps_the_io_error_as_source() {
    let path = std::env::temp_dir().join(format!("aras-absent-{}.csv", std::process::id()));
    let e = read_log(&path, &ReadOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("{}: cannot read the file", path.display())
    );
    assert_eq!(io_source_kind(&e), std::io::ErrorKind::NotFound);
    assert_source_not_repeated(&e);
}

/// `torques` in the sidecar: written and read back, the log's torque
/// timing; a plain CSV's torques are sampled; `ReadOptions::torques`
/// fills in what the sidecar does not state, agrees with it, or is refused
/// naming both; an unknown value names the allowed ones.
#[test]
fn torque_timing_from_sidecar_and_options() {
    use aras_log::{Sidecar, TorqueTiming};
    let held = Sidecar {
        format: Some(aras_log::FORMAT.into()),
        torques: Some(TorqueTiming::Held),
        ..Sidecar::default()
    };
    let json = serde_json::to_string(&held).unwrap();
    assert_eq!(json, r#"{"format":"aras-log/1","torques":"held"}"#);
    assert_eq!(Sidecar::parse(&json, "h.json").unwrap(), held);

    let csv = synthetic(100, |_| 0.0);
    let read = |sidecar: Option<&str>, torques| {
        let opts = ReadOptions {
            sidecar: sidecar.map_or(SidecarSource::None, |json| SidecarSource::Text {
                name: "side.json".into(),
                json: json.into(),
            }),
            torques,
            ..ReadOptions::default()
        };
        read_log_from(csv.as_bytes(), "tt.csv", &opts)
    };
    let plain = read(None, None).unwrap();
    assert_eq!(plain.torque_timing(), TorqueTiming::Sampled);
    let unstated = r#"{"format": "aras-log/1"}"#;
    assert_eq!(
        read(Some(unstated), None).unwrap().torque_timing(),
        TorqueTiming::Sampled
    );
    let overridden = read(Some(unstated), Some(TorqueTiming::Held)).unwrap();
    assert_eq!(overridden.torque_timing(), TorqueTiming::Held);
    assert!(
        overridden
            .notes
            .iter()
            .any(|n| n == "torques taken as held (from the options)"),
        "{:?}",
        overridden.notes
    );
    assert_eq!(
        read(None, Some(TorqueTiming::Held))
            .unwrap()
            .torque_timing(),
        TorqueTiming::Held
    );
    let stated = r#"{"format": "aras-log/1", "torques": "held"}"#;
    assert_eq!(
        read(Some(stated), None).unwrap().torque_timing(),
        TorqueTiming::Held
    );
    assert_eq!(
        read(Some(stated), Some(TorqueTiming::Held))
            .unwrap()
            .torque_timing(),
        TorqueTiming::Held
    );
    let e = read(Some(stated), Some(TorqueTiming::Sampled))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("tt.csv: the torques are given as `sampled`")
            && e.contains("the sidecar side.json states \"torques\": \"held\""),
        "{e}"
    );
    // The streaming reader states the same.
    let opts = ReadOptions {
        sidecar: SidecarSource::Text {
            name: "side.json".into(),
            json: stated.into(),
        },
        ..ReadOptions::default()
    };
    let reader = LogReader::new(csv.as_bytes(), "tt.csv", &opts).unwrap();
    assert_eq!(reader.torque_timing(), TorqueTiming::Held);

    let e = read(Some(r#"{"format": "aras-log/1", "torques": "hold"}"#), None)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("side.json:1:")
            && e.contains("unknown variant `hold`, expected `sampled` or `held`"),
        "{e}"
    );
}
