//! Malformed inputs through the `aras` command line: every file kind
//! (logs, sidecars, parameter files, config files, trajectory files) and
//! bad option values. Each case asserts the specific message: what is
//! wrong, where (file, line, column or key) and how to fix it. The corpus
//! is `fixtures/bad/` (written by its `make_fixtures.py`) plus the log
//! reader's own `fixtures/logs/bad/`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn fixture(rel: &str) -> String {
    root().join("fixtures").join(rel).display().to_string()
}

/// A fresh scratch directory, removed when the test passes.
fn scratch(name: &str) -> aras_testkit::Scratch {
    aras_testkit::Scratch::new(&format!("bad-{name}"))
}

fn aras(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(args)
        .output()
        .expect("the aras binary runs")
}

/// Runs `args`, which must fail without a panic, and returns stderr, which
/// must contain every one of `expected`.
fn fails_with(args: &[&str], expected: &[&str]) -> String {
    let r = aras(args);
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(!r.status.success(), "{args:?} was accepted: {err}");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    for e in expected {
        assert!(err.contains(e), "{args:?}: missing {e:?} in:\n{err}");
    }
    err
}

/// `predict` with the default robot: the cheapest command that reads a log.
fn predict_log(log: &str, dir: &Path) -> Vec<String> {
    let out = dir.join("p.csv");
    let _ = std::fs::remove_file(&out);
    vec![
        "predict".into(),
        "--params".into(),
        fixture("robots/aras-diamond.json"),
        "--data".into(),
        log.into(),
        "--out".into(),
        out.display().to_string(),
        "--quiet".into(),
    ]
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

#[test]
fn parameter_files() {
    let dir = scratch("params");
    let cases: &[(&str, &[&str])] = &[
        (
            "empty.json",
            &[
                "empty.json",
                "invalid JSON at line 1, column 0",
                "fix the syntax",
            ],
        ),
        (
            "trailing_comma.json",
            &["trailing_comma.json", "line 71, column 1: trailing comma"],
        ),
        ("missing_links.json", &["missing key `links`: add it"]),
        (
            "misspelled_key.json",
            &["unknown key `links.2.masss`: remove or rename it; allowed here: Ixx"],
        ),
        (
            "string_value.json",
            &["`links.3.Izz` must be a number, found \"heavy\""],
        ),
        (
            "alpha_out_of_range.json",
            &[
                "`geometry.alpha_deg` = 200 is invalid: arc angles must lie strictly between 0 and 180",
            ],
        ),
        (
            "unknown_effect.json",
            &[
                "unknown key `extra.gear_backlash`",
                "allowed here: torque_offset",
            ],
        ),
    ];
    for (file, expected) in cases {
        let p = fixture(&format!("bad/params/{file}"));
        let mut args = predict_log(&fixture("bad/logs/saturated_torque.csv"), &dir);
        args[2] = p;
        fails_with(&strs(&args), expected);
    }
}

/// A negative mass or a non-positive-definite inertia: accepted where an
/// OLS estimate is legitimate (`predict`), rejected with the reason where
/// real bodies are required (`validate`, the SDP's reference).
#[test]
fn physically_inconsistent_parameters() {
    let dir = scratch("physical");
    for (file, why) in [
        (
            "negative_mass.json",
            "link 2 is not physically consistent: mass = -0.11 kg is not positive",
        ),
        (
            "non_pd_inertia.json",
            "link 1 is not physically consistent: its pseudo-inertia has the negative eigenvalue",
        ),
    ] {
        let p = fixture(&format!("bad/params/{file}"));
        let mut args = predict_log(&fixture("bad/logs/saturated_torque.csv"), &dir);
        args[2] = p.clone();
        let r = aras(&strs(&args));
        assert!(
            r.status.success(),
            "predict rejected {file}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let out = dir.join(format!("v-{file}"));
        fails_with(
            &[
                "validate",
                "--params",
                &p,
                "--out",
                out.to_str().unwrap(),
                "-q",
            ],
            &[
                why,
                "`validate` checks a model for control",
                "`predict` accepts it",
            ],
        );
        assert!(!out.exists(), "a rejected validate left {}", out.display());
    }
    for (cfg, why) in [
        (
            "negative_mass_reference.toml",
            "mass = -0.11 kg is not positive",
        ),
        (
            "non_pd_reference.toml",
            "pseudo-inertia has the negative eigenvalue",
        ),
    ] {
        let out = dir.join("t.json");
        fails_with(
            &[
                "excite",
                "--config",
                &fixture(&format!("bad/config/{cfg}")),
                "--out",
                out.to_str().unwrap(),
                "-q",
            ],
            &[
                "key `robot.params`",
                "reference of the physically consistent fit",
                why,
            ],
        );
    }
}

#[test]
fn config_files() {
    let dir = scratch("config");
    let cases: &[(&str, &[&str])] = &[
        (
            "misspelled_key.toml",
            &[
                "misspelled_key.toml:2:1: key `signal.cutof_hz`: unknown field `cutof_hz`",
                "remove or rename it",
            ],
        ),
        (
            "wrong_type.toml",
            &[
                "wrong_type.toml:2:13: key `trajectory.harmonics`: invalid type: string \"five\"",
                "docs/config.md",
            ],
        ),
        (
            "negative_cutoff.toml",
            &[
                "negative_cutoff.toml:2:1: key `signal.cutoff_hz`: must be a finite number ≥ 0, found -5",
            ],
        ),
        (
            "diagnose_alpha.toml",
            &[
                "key `diagnose.alpha`: must be a significance level in (0, 1) such as 0.01, found 1.5",
            ],
        ),
        ("syntax.toml", &["syntax.toml:1:12: unclosed table"]),
        (
            "trailing_comma.json",
            &["trailing_comma.json:1:30: key `simulation.periods`: trailing comma"],
        ),
        (
            "unsupported.yaml",
            &[
                "unsupported.yaml: unknown config format",
                "must end in .toml or .json",
            ],
        ),
        (
            "missing_params_file.toml",
            &["key `robot.params`", "no-such-robot.json", "No such file"],
        ),
        // An unreachable workspace box: γ up to 200° is beyond the arcs' reach.
        (
            "unreachable_box.toml",
            &[
                "is unreachable: the arcs reach only",
                "trajectory.min_deg/max_deg",
            ],
        ),
    ];
    for (file, expected) in cases {
        let out = dir.join("t.json");
        fails_with(
            &[
                "excite",
                "--config",
                &fixture(&format!("bad/config/{file}")),
                "--out",
                out.to_str().unwrap(),
                "-q",
            ],
            expected,
        );
        assert!(!out.exists());
    }
}

#[test]
fn trajectory_files() {
    let dir = scratch("trajectory");
    let cfg = dir.join("short.toml");
    std::fs::write(&cfg, "[simulation]\nperiods = 1\n").unwrap();
    let cases: &[(&str, &[&str])] = &[
        (
            "empty.json",
            &[
                "empty.json: line 1, column 1: the file is empty",
                "aras excite",
            ],
        ),
        (
            "negative_frequency.json",
            &["omega_f = -0.6283185307179586 is invalid: the base frequency must be positive"],
        ),
        (
            "short_coefficients.json",
            &["coefficient list a[1] has 3 entries but the trajectory has 5 harmonics"],
        ),
        (
            "wrong_format.json",
            &[
                "key `format`: \"aras-fourier/9\" is not a trajectory format",
                "expected \"aras-fourier/1\"",
            ],
        ),
        (
            "unreachable_pose.json",
            &[
                "leaves the workspace box (77): φ = 228.11° at t = 0.0000 s, outside [30, 140]°",
                "trajectory.min_deg",
            ],
        ),
    ];
    for (file, expected) in cases {
        let out = dir.join("l.csv");
        let err = fails_with(
            &[
                "simulate",
                "--trajectory",
                &fixture(&format!("bad/trajectory/{file}")),
                "--config",
                cfg.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "-q",
            ],
            expected,
        );
        assert!(err.contains(file), "{file}: {err}");
        assert!(!out.exists());
    }
}

#[test]
fn logs_and_sidecars() {
    let dir = scratch("logs");
    let cases: &[(&str, &[&str])] = &[
        (
            "bad/logs/empty.csv",
            &[
                "empty.csv: no header line: the log is empty",
                "must name the columns",
            ],
        ),
        (
            "bad/logs/header_only.csv",
            &["header_only.csv: only 0 data rows, at least 16 are needed"],
        ),
        (
            "bad/logs/gap_10s.csv",
            &[
                "gap_10s.csv:202: irregular sampling: the worst step, 10.001 s ending at t = 10.2 s",
                "resample",
            ],
        ),
        (
            "logs/bad/semicolon.csv",
            &[
                "semicolon.csv:1: the header is separated by ';'",
                "replace every ';' by ','",
            ],
        ),
        (
            "logs/bad/degrees.csv",
            &["angles look like degrees", "convert to radians"],
        ),
        (
            "logs/bad/nan_value.csv",
            &["nan_value.csv:6:4: `tau1` value \"NaN\" is not finite"],
        ),
        (
            "logs/bad/infinite_value.csv",
            &["infinite_value.csv:8:5: `tau2` value \"inf\" is not finite"],
        ),
        (
            "logs/bad/repeated_time.csv",
            &["repeated_time.csv:14:1: time does not increase"],
        ),
        (
            "logs/bad/time_backwards.csv",
            &["time_backwards.csv:12:1: time does not increase"],
        ),
        (
            "bad/sidecar/nan_torque_constant.csv",
            &["nan_torque_constant.json:1:59", "JSON has no NaN"],
        ),
        (
            "bad/sidecar/period_string.csv",
            &[
                "period_string.json:1:57: invalid type: string \"ten\"",
                "docs/log-format.md",
            ],
        ),
    ];
    for (file, expected) in cases {
        let args = predict_log(&fixture(file), &dir);
        fails_with(&strs(&args), expected);
        assert!(!dir.join("p.csv").exists());
    }
    // An empty file or a JSON array declares no format: beside the log it is
    // not read (a note says so); given with --sidecar it is an error.
    for (file, expected) in [
        (
            "bad/sidecar/empty_sidecar",
            "empty_sidecar.json:1:1: the file is empty; the sidecar must be one JSON object",
        ),
        (
            "bad/sidecar/sidecar_array",
            "sidecar_array.json:1:1: it starts with '['",
        ),
    ] {
        let mut args = predict_log(&fixture(&format!("{file}.csv")), &dir);
        let ok = aras(&strs(&args));
        let stderr = String::from_utf8_lossy(&ok.stderr);
        assert!(ok.status.success(), "{file}: {stderr}");
        assert!(
            stderr.contains(&format!(
                "{}.json does not declare the aras-log/1 format",
                fixture(file)
            )) && stderr.contains("not read as a sidecar"),
            "{file}: {stderr}"
        );
        let _ = std::fs::remove_file(dir.join("p.csv"));
        args.extend(["--sidecar".into(), fixture(&format!("{file}.json"))]);
        fails_with(&strs(&args), &[expected]);
        // `--sidecar none` reads none: no note either.
        let n = args.len();
        args[n - 1] = "none".into();
        let _ = std::fs::remove_file(dir.join("p.csv"));
        let ok = aras(&strs(&args));
        let stderr = String::from_utf8_lossy(&ok.stderr);
        assert!(
            ok.status.success() && !stderr.contains("sidecar"),
            "{file}: {stderr}"
        );
    }
    // Every log of the reader's own corpus fails through the CLI too, naming its file.
    let bad = root().join("fixtures/logs/bad");
    let mut n = 0;
    for e in std::fs::read_dir(&bad).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "csv") {
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            let args = predict_log(&p.display().to_string(), &dir);
            fails_with(&strs(&args), &[&stem]);
            n += 1;
        }
    }
    assert!(n >= 26, "only {n} logs in fixtures/logs/bad");
}

#[test]
fn accepted_with_a_warning_or_as_is() {
    let dir = scratch("accepted");
    // Saturated torque: a warning with the time spans, and the run goes on.
    let r = aras(&strs(&predict_log(
        &fixture("bad/logs/saturated_torque.csv"),
        &dir,
    )));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("warning: ")
            && err.contains(
                "tau1 sits flat at its maximum 0.25 N·m (saturation?) at t = 0.1870–0.5590 s"
            ),
        "{err}"
    );
    // BOM, CRLF, comments and reordered columns are accepted.
    let log = fixture("logs/good/bom_crlf_reordered.csv");
    let r = aras(&[
        "identify",
        "--data",
        &log,
        "--out",
        dir.join("o").to_str().unwrap(),
        "-q",
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    // The log is valid but too short to identify: the failure is about its length, not its format.
    assert!(
        err.contains("fewer than twice the 42 parameters; record a longer log"),
        "{err}"
    );
}

/// A log whose motion is one sinusoid cannot excite every base parameter:
/// the error names the ones it loses.
///
/// The one-sine motion excites b23 at about 1e-8 relative, right at the
/// rank tolerance: the 10 Hz filter puts it just below (refused), the exact
/// harmonic derivatives of the automatic bandwidth just above (accepted with
/// κ ≈ 6.6e7 and σ% up to 150 %). The filter is fixed here so that the test
/// checks the refusal and its message, not which side of the boundary the
/// processing lands on.
#[test]
fn excitation_that_cannot_excite() {
    let dir = scratch("rank");
    let out = dir.join("o");
    let config = dir.join("filter10.toml");
    std::fs::write(
        &config,
        "[signal]\nbandwidth = \"fixed\"\ncutoff_hz = 10.0\n",
    )
    .unwrap();
    fails_with(
        &[
            "identify",
            "--data",
            &fixture("bad/logs/one_sine.csv"),
            "--config",
            config.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ],
        &[
            "the data do not excite 1 of 23 parameters (rank 22",
            ": b23; use a richer excitation trajectory",
        ],
    );
    assert!(!out.exists());
}

#[test]
fn bad_command_line_values() {
    let dir = scratch("cli");
    let log = fixture("bad/logs/saturated_torque.csv");
    let o = dir.join("o");
    let o = o.to_str().unwrap();
    fails_with(
        &["identify", "--data", &log, "--period", "-2", "--out", o],
        &["invalid value '-2' for '--period <S>': -2 is not a positive finite number"],
    );
    fails_with(
        &["identify", "--data", &log, "--period", "0", "--out", o],
        &["invalid value '0' for '--period <S>'"],
    );
    fails_with(
        &["identify", "--data", &log, "--period", "ten", "--out", o],
        &["`ten` is not a number"],
    );
    fails_with(
        &["simulate", "--frequency", "NaN", "--out", o],
        &["invalid value 'NaN' for '--frequency <HZ>': NaN is not a positive finite number"],
    );
    fails_with(
        &[
            "identify",
            "--data",
            dir.join("missing.csv").to_str().unwrap(),
            "--out",
            o,
            "-q",
        ],
        &["missing.csv", "No such file"],
    );
    fails_with(
        &[
            "predict",
            "--params",
            "no-such.json",
            "--data",
            &log,
            "--out",
            dir.join("p.csv").to_str().unwrap(),
        ],
        &["cannot access parameter file no-such.json"],
    );
    let nowhere = dir.join("no/such/dir/t.json");
    fails_with(
        &["excite", "--out", nowhere.to_str().unwrap(), "-q"],
        &[
            "the directory",
            "does not exist; create it first or choose another --out",
        ],
    );
    fails_with(
        &[
            "simulate",
            "--frequency",
            "1",
            "--out",
            dir.join("no/l.csv").to_str().unwrap(),
            "-q",
        ],
        &["does not exist; create it first"],
    );
    fails_with(
        &["identify", "--data", &log, "--frobnicate"],
        &["unexpected argument '--frobnicate'"],
    );
    // An unknown effect id in a parameter file's `extra` section.
    fails_with(
        &[
            "validate",
            "--params",
            &fixture("bad/params/unknown_effect.json"),
            "--out",
            o,
            "-q",
        ],
        &["unknown key `extra.gear_backlash`"],
    );
}

/// The first `rows` rows of a simulated 0.5 Hz log (with its logged
/// derivatives, no sidecar), each row passed through `edit` (which may
/// drop trailing columns).
fn simulated_log(dir: &Path, name: &str, rows: usize, edit: impl Fn(&mut Vec<f64>)) -> String {
    let sim = dir.join("sim.csv");
    if !sim.exists() {
        let r = aras(&[
            "simulate",
            "--frequency",
            "0.5",
            "--out",
            sim.to_str().unwrap(),
            "-q",
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    let text = std::fs::read_to_string(&sim).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut out = String::new();
    let mut width = header.len();
    for l in lines.take(rows) {
        let mut v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        edit(&mut v);
        let f: Vec<String> = v
            .iter()
            .map(|x| {
                if x.abs() > 1e12 {
                    format!("{x:e}")
                } else {
                    x.to_string()
                }
            })
            .collect();
        width = f.len();
        out += &f.join(",");
        out.push('\n');
    }
    // A row cut short by `edit` drops the same trailing columns.
    let out = format!("{}\n{out}", header[..width].join(","));
    let p = dir.join(name);
    std::fs::write(&p, out).unwrap();
    p.display().to_string()
}

/// Messages that point at the cause: constant angles, a 1e300 cell, a
/// tab-separated file, the streaming threshold of `diagnose --help`, the
/// printed configuration, the filter's origin and the friction summary
/// without validation logs.
#[test]
fn messages_point_at_the_cause() {
    let dir = scratch("pointing");
    let o = dir.join("o");
    let o = o.to_str().unwrap();
    // Joints that never move: the reason, not an empty row group.
    let still = simulated_log(&dir, "still.csv", 3000, |v| {
        v[1] = 2.9;
        v[2] = 1.05;
        v[5..9].fill(0.0);
    });
    let err = fails_with(
        &["identify", "--data", &still, "--out", o, "-q"],
        &[
            "only 0 (joint 1) and 0 (joint 2) samples are away from velocity reversals",
            "the joints reach at most |θ̇| = 0.000 / 0.000 rad/s",
            "log a motion that excites both joints",
        ],
    );
    assert!(!err.contains("row groups"), "{err}");
    // A huge cell is named where it is, not as a NaN of the regressor.
    let huge = simulated_log(&dir, "huge.csv", 3000, |v| {
        if v[0] == 0.01 {
            v[3] = 1e300;
        }
    });
    let err = fails_with(
        &strs(&predict_log(&huge, &dir)),
        &["huge.csv:12:4: `tau1` value \"1e300\" is beyond ±1e12"],
    );
    assert!(!err.contains("NaN"), "{err}");
    // Tabs: said so, not "required column `t` is missing".
    let tabs = dir.join("tabs.csv");
    let text = std::fs::read_to_string(&huge).unwrap().replace(',', "\t");
    std::fs::write(&tabs, text).unwrap();
    let err = fails_with(
        &strs(&predict_log(tabs.to_str().unwrap(), &dir)),
        &[
            "tabs.csv:1: the header is separated by tabs",
            "replace every tab by ','",
        ],
    );
    assert!(!err.contains("is missing"), "{err}");
    // `diagnose --help` gives its own streaming threshold only.
    let help = String::from_utf8_lossy(&aras(&["diagnose", "--help"]).stdout).into_owned();
    assert!(help.contains("larger than 64 MB"), "{help}");
    assert!(!help.contains("256 MB"), "{help}");
    // --print-config prints the given configuration.
    let cfg = dir.join("seven.toml");
    std::fs::write(&cfg, "[signal]\ncutoff_hz = 7.5\n").unwrap();
    let r = aras(&[
        "pipeline",
        "--print-config",
        "--config",
        cfg.to_str().unwrap(),
    ]);
    let printed = String::from_utf8_lossy(&r.stdout).into_owned();
    assert!(
        r.status.success() && printed.contains("cutoff_hz = 7.5"),
        "{printed}"
    );
    let r = aras(&["pipeline", "--print-config"]);
    assert!(String::from_utf8_lossy(&r.stdout).contains("cutoff_hz = 10.0"));
    // A fixed filter is the settings', not the user's; the data-chosen
    // bandwidth (the default) says from what it was chosen.
    let plain = simulated_log(&dir, "plain.csv", 3000, |v| v.truncate(5));
    let fixed = dir.join("fixed.toml");
    std::fs::write(&fixed, "[signal]\nbandwidth = \"fixed\"\n").unwrap();
    let mut args = predict_log(&plain, &dir);
    args.extend(["--config".into(), fixed.display().to_string()]);
    let r = aras(&strs(&args));
    let said = String::from_utf8_lossy(&r.stdout).into_owned();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(
        said.contains("at 10.000 Hz: a fixed cut-off from the settings, not chosen from the data"),
        "{said}"
    );
    assert!(!said.contains("by the user"), "{said}");
    let r = aras(&strs(&predict_log(&plain, &dir)));
    let said = String::from_utf8_lossy(&r.stdout).into_owned();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(
        said.contains("the angles' motion reaches") && said.contains("above the noise floor"),
        "{said}"
    );
    assert!(!said.contains("from the settings"), "{said}");
}

/// Logged derivatives: `predict` uses them only when they are the angles'
/// derivatives; `identify` says that it ignores them.
#[test]
fn logged_derivatives_are_checked_or_said_to_be_ignored() {
    let dir = scratch("derivatives");
    // dtheta1 in degrees per second.
    let deg = simulated_log(&dir, "deg.csv", 3000, |v| v[5] = v[5].to_degrees());
    fails_with(
        &strs(&predict_log(&deg, &dir)),
        &[
            "deg.csv: `dtheta1` is not the derivative of `theta1`: integrated, it is 57.2",
            "degrees per second",
            "convert `dtheta1` to radians",
        ],
    );
    // ddtheta2 of the other joint.
    let swapped = simulated_log(&dir, "swapped.csv", 3000, |v| v[8] = v[7]);
    fails_with(
        &strs(&predict_log(&swapped, &dir)),
        &["swapped.csv: `ddtheta2` is not the derivative of `dtheta2`"],
    );
    // Consistent columns are used.
    let good = simulated_log(&dir, "good.csv", 3000, |_| {});
    let r = aras(&strs(&predict_log(&good, &dir)));
    let said = String::from_utf8_lossy(&r.stdout).into_owned();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(
        said.contains("dtheta/ddtheta columns are used exactly as given"),
        "{said}"
    );
    // identify ignores them and says so, on stderr and in summary.json.
    let long = simulated_log(&dir, "long.csv", 8000, |_| {});
    let out = dir.join("id");
    let r = aras(&[
        "identify",
        "--data",
        &long,
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("note: ") && err.contains("logged dtheta/ddtheta columns are ignored"),
        "{err}"
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert!(
        v["logged_derivatives"]
            .as_str()
            .is_some_and(|s| s.contains("ignored")),
        "{summary}"
    );
}
