//! An implausible identification is flagged loudly (stderr, `summary.json`,
//! the report), and a believable one is not: torques logged in mN·m and
//! filtering switched off against the same log as it should be read.

mod common;

use std::path::{Path, PathBuf};

use common::{aras, fixture, scratch};

/// A short simulated excitation log in `dir`.
fn excitation_log(dir: &Path) -> PathBuf {
    let cfg = dir.join("sim.toml");
    std::fs::write(&cfg, "[simulation]\nperiods = 2\n").unwrap();
    let log = dir.join("log.csv");
    let r = aras(&[
        "simulate",
        "--trajectory",
        fixture("trajectories/default-excitation.json")
            .to_str()
            .unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        log.to_str().unwrap(),
        "-q",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    log
}

/// `identify` on `log` (with `extra` options): (stderr, the findings'
/// checks in summary.json, report.md).
fn identify(log: &Path, out: &Path, extra: &[&str]) -> (String, Vec<String>, String) {
    let mut args = vec![
        "identify",
        "--data",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ];
    args.extend_from_slice(extra);
    let r = aras(&args);
    let stderr = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(r.status.success(), "{stderr}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let checks = s["implausible"]
        .as_array()
        .expect("summary.json lists the findings, even none")
        .iter()
        .map(|f| f["check"].as_str().unwrap().to_owned())
        .collect();
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    (stderr, checks, report)
}

#[test]
fn implausible_results_are_flagged_and_plausible_ones_are_not() {
    let dir = scratch("plausibility", "flags");
    let log = excitation_log(&dir);
    let (stderr, checks, report) = identify(&log, &dir.join("ok"), &[]);
    assert!(checks.is_empty(), "{checks:?}");
    assert!(!stderr.contains("IMPLAUSIBLE") && !report.contains("implausible"));

    // The same log with its torques in mN·m (and no derivative columns).
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let tau: Vec<usize> = ["tau1", "tau2"]
        .iter()
        .map(|c| header.iter().position(|h| h == c).unwrap())
        .collect();
    let mut scaled = String::from("t,theta1,theta2,tau1,tau2\n");
    for line in lines {
        let mut v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        for &c in &tau {
            v[c] *= 1000.0;
        }
        scaled += &format!("{},{},{},{},{}\n", v[0], v[1], v[2], v[tau[0]], v[tau[1]]);
    }
    let mnm = dir.join("mnm.csv");
    std::fs::write(&mnm, scaled).unwrap();
    std::fs::copy(aras_log::sidecar_path(&log), dir.join("mnm.json")).unwrap();
    let (stderr, checks, report) = identify(&mnm, &dir.join("mnm"), &[]);
    for want in [
        "sdp_far_below_ols",
        "torque_beyond_limit",
        "mass_matrix_out_of_scale",
    ] {
        assert!(checks.iter().any(|c| c == want), "{want} not in {checks:?}");
    }
    assert!(
        stderr.contains("IMPLAUSIBLE RESULT") && stderr.contains("mN·m"),
        "{stderr}"
    );
    assert!(report.contains("WARNING: implausible result"), "{report}");

    // Filtering switched off: the derivatives of raw encoder angles.
    let cfg = dir.join("nofilter.toml");
    std::fs::write(&cfg, "[signal]\nbandwidth = \"fixed\"\ncutoff_hz = 0\n").unwrap();
    let (_, checks, _) = identify(
        &without_derivatives(&log, &dir),
        &dir.join("c0"),
        &["--config", cfg.to_str().unwrap()],
    );
    assert!(
        checks.iter().any(|c| c == "sdp_far_below_ols"),
        "{checks:?}"
    );
}

/// `log` without its derivative columns (so the angles are differentiated).
fn without_derivatives(log: &Path, dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(log).unwrap();
    let out: String = text
        .lines()
        .map(|l| l.split(',').take(5).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    let p = dir.join("plain.csv");
    std::fs::write(&p, out).unwrap();
    std::fs::copy(aras_log::sidecar_path(log), dir.join("plain.json")).unwrap();
    p
}
