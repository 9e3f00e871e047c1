//! A lab's log as it comes, through the `aras` binary: time in
//! milliseconds, clock-epoch time stamps, jitter, missing samples, isolated
//! glitches; the options `--time-unit`, `--glitches`, `--resample`,
//! `--max-gap` and the config's `[log]` section; and no false glitches on
//! the simulator's healthy logs.

mod common;

use std::path::Path;

use common::{aras, fixture, scratch};

/// A validation log of the simulator (1 Hz, 16 s at 1 kHz): `(header, rows)`.
fn simulated(dir: &Path, name: &str, freq: &str, seed: &str) -> (String, Vec<Vec<String>>) {
    let log = dir.join(name);
    let r = aras(&[
        "simulate",
        "--frequency",
        freq,
        "--seed",
        seed,
        "--out",
        log.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

/// Writes `rows` as a log (without a sidecar) and returns its path.
fn write(dir: &Path, name: &str, header: &str, rows: &[Vec<String>]) -> String {
    let mut s = format!("{header}\n");
    for r in rows {
        s += &r.join(",");
        s.push('\n');
    }
    let p = dir.join(name);
    std::fs::write(&p, s).unwrap();
    p.display().to_string()
}

/// `aras predict` on `log` with `extra` options: `(success, stderr)`.
fn predict(dir: &Path, log: &str, extra: &[&str]) -> (bool, String) {
    let out = dir.join("pred.csv");
    let _ = std::fs::remove_file(&out);
    let params = fixture("robots/aras-diamond.json");
    let mut args = vec![
        "predict",
        "--params",
        params.to_str().unwrap(),
        "--data",
        log,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let r = aras(&args);
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(!err.contains("panicked"), "{err}");
    (r.status.success(), err)
}

fn map_t(rows: &[Vec<String>], f: impl Fn(f64) -> String) -> Vec<Vec<String>> {
    rows.iter()
        .map(|r| {
            let mut r = r.clone();
            r[0] = f(r[0].parse().unwrap());
            r
        })
        .collect()
}

#[test]
fn time_in_milliseconds_is_questioned_and_read_with_the_option() {
    let dir = scratch("lab-timing", "ms");
    let (h, rows) = simulated(dir.path(), "sim.csv", "1", "1");
    let ms = write(
        dir.path(),
        "ms.csv",
        &h,
        &map_t(&rows, |t| format!("{}", (t * 1e3).round())),
    );
    let (ok, err) = predict(dir.path(), &ms, &[]);
    assert!(!ok);
    for e in [
        "is t in seconds?",
        "a step of 1 looks like milliseconds",
        "--time-unit ms",
    ] {
        assert!(err.contains(e), "missing {e:?}: {err}");
    }
    let (ok, err) = predict(dir.path(), &ms, &["--time-unit", "ms"]);
    assert!(ok, "{err}");
    // The same through the config file.
    let cfg = dir.path().join("c.toml");
    std::fs::write(&cfg, "[log]\ntime_unit = \"ms\"\n").unwrap();
    let (ok, err) = predict(dir.path(), &ms, &["--config", cfg.to_str().unwrap()]);
    assert!(ok, "{err}");
    std::fs::write(&cfg, "[log]\ntime_unit = \"minutes\"\n").unwrap();
    let (ok, err) = predict(dir.path(), &ms, &["--config", cfg.to_str().unwrap()]);
    assert!(!ok && err.contains("log.time_unit"), "{err}");
}

#[test]
fn epoch_and_jittered_stamps_keep_every_row_with_a_warning() {
    let dir = scratch("lab-timing", "epoch");
    let (h, rows) = simulated(dir.path(), "sim.csv", "1", "2");
    let epoch = write(
        dir.path(),
        "epoch.csv",
        &h,
        &map_t(&rows, |t| format!("{:.6}", 1.7e9 + t)),
    );
    let (ok, err) = predict(dir.path(), &epoch, &[]);
    assert!(ok, "{err}");
    assert!(
        err.contains("time stamps start at t = 1700000000 s (a clock epoch?)")
            && err.contains("0.238 µs"),
        "{err}"
    );
    let pred = std::fs::read_to_string(dir.path().join("pred.csv")).unwrap();
    assert_eq!(pred.lines().count(), rows.len() + 1, "every row predicted");
    // ±0.2 ms of jitter (a deterministic pattern, max 0.2 ms).
    let jit: Vec<Vec<String>> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let mut r = r.clone();
            let t: f64 = r[0].parse().unwrap();
            r[0] = format!("{}", t + 2e-4 * ((i * 7919 % 1000) as f64 / 500.0 - 1.0));
            r
        })
        .collect();
    let jit = write(dir.path(), "jit.csv", &h, &jit);
    let (ok, err) = predict(dir.path(), &jit, &[]);
    assert!(ok, "{err}");
    assert!(
        err.contains("time stamps jitter") && err.contains("ms RMS"),
        "{err}"
    );
    // Resampled explicitly: no jitter left to warn about.
    let (ok, err) = predict(dir.path(), &jit, &["--resample"]);
    assert!(ok && !err.contains("time stamps jitter"), "{err}");
}

#[test]
fn missing_samples_are_resampled_up_to_the_stated_gap() {
    let dir = scratch("lab-timing", "gaps");
    let (h, rows) = simulated(dir.path(), "sim.csv", "1", "3");
    // Rows 2000–2002 missing (a 4 ms step), then rows 6000–6019 (21 ms).
    let gappy: Vec<Vec<String>> = rows
        .iter()
        .enumerate()
        .filter(|(i, _)| !(2000..2003).contains(i) && !(6000..6020).contains(i))
        .map(|(_, r)| r.clone())
        .collect();
    let log = write(dir.path(), "gappy.csv", &h, &gappy);
    let (ok, err) = predict(dir.path(), &log, &[]);
    assert!(
        !ok && err.contains("irregular sampling") && err.contains("--resample"),
        "{err}"
    );
    let (ok, err) = predict(dir.path(), &log, &["--resample"]);
    assert!(!ok, "{err}");
    // Line of the row after the second gap: 2 + 5997 rows kept before it.
    for e in [
        "1 gap(s) in the time stamps longer than the 0.005 s",
        "line 5999: t = 5.999000 → 6.020000 s",
        "--max-gap",
    ] {
        assert!(err.contains(e), "missing {e:?}: {err}");
    }
    let (ok, err) = predict(dir.path(), &log, &["--resample", "--max-gap", "0.05"]);
    assert!(ok, "{err}");
    assert!(
        err.contains("2 gap(s) in the time stamps interpolated by the resampling"),
        "{err}"
    );
    let pred = std::fs::read_to_string(dir.path().join("pred.csv")).unwrap();
    assert_eq!(pred.lines().count(), rows.len() + 1, "the uniform grid");
}

#[test]
fn a_bad_sample_is_refused_by_line_then_repaired_or_dropped_on_request() {
    let dir = scratch("lab-timing", "glitch");
    let (h, rows) = simulated(dir.path(), "sim.csv", "1", "4");
    let mut bad = rows.clone();
    let th: f64 = bad[799][1].parse().unwrap();
    bad[799][1] = format!("{}", th + 0.05);
    let tau: f64 = bad[5000][4].parse().unwrap();
    bad[5000][4] = format!("{}", tau + 5.0);
    let log = write(dir.path(), "glitch.csv", &h, &bad);
    // The default warns by line and goes on.
    let (ok, err) = predict(dir.path(), &log, &[]);
    assert!(ok, "{err}");
    assert!(err.contains("line 801, column 2: theta1 = "), "{err}");
    let (ok, err) = predict(dir.path(), &log, &["--glitches", "refuse"]);
    assert!(!ok);
    for e in [
        "2 isolated glitch(es)",
        "line 801, column 2: theta1 = ",
        "line 5002, column 5: tau2 = ",
        "--glitches repair",
    ] {
        assert!(err.contains(e), "missing {e:?}: {err}");
    }
    for action in ["repair", "drop", "warn"] {
        let (ok, err) = predict(dir.path(), &log, &["--glitches", action]);
        assert!(ok, "{action}: {err}");
        assert!(err.contains("line 801, column 2"), "{action}: {err}");
    }
    // A torque limit in the config flags a sustained torque beyond 1.5× it.
    let cfg = dir.path().join("c.toml");
    std::fs::write(&cfg, "[log]\ntorque_limit = [0.05, 0.05]\n").unwrap();
    let clean = write(dir.path(), "clean.csv", &h, &rows);
    let (ok, err) = predict(dir.path(), &clean, &["--config", cfg.to_str().unwrap()]);
    assert!(
        ok && err.contains("beyond the stated torque limit"),
        "{err}"
    );
    let (ok, err) = predict(
        dir.path(),
        &clean,
        &["--config", cfg.to_str().unwrap(), "--glitches", "refuse"],
    );
    assert!(
        !ok && err.contains("beyond the stated torque limit"),
        "{err}"
    );
    // Streaming cannot repair: refused, not ignored.
    let out = dir.path().join("id");
    let r = aras(&[
        "identify",
        "--data",
        &log,
        "--streaming",
        "on",
        "--glitches",
        "repair",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        !r.status.success() && err.contains("use --streaming off"),
        "{err}"
    );
}

#[test]
fn healthy_simulated_logs_have_no_glitches() {
    let dir = scratch("lab-timing", "healthy");
    for (freq, seed) in [("0.3", "5"), ("1", "6"), ("2.5", "7")] {
        let name = format!("sim{freq}.csv");
        simulated(dir.path(), &name, freq, seed);
        let log = dir.path().join(&name).display().to_string();
        let (ok, err) = predict(dir.path(), &log, &[]);
        assert!(ok && !err.contains("glitch"), "{freq} Hz: {err}");
    }
}
