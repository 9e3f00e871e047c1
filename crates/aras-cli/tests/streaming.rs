//! `aras identify --streaming on` gives the in-memory estimates (
//! "Scale"): the same rows (reversal exclusion), the same OLS, σ and SDP.

use std::path::Path;
use std::process::Command;

/// A fresh scratch directory, removed when the test passes.
fn scratch(name: &str) -> aras_testkit::Scratch {
    aras_testkit::Scratch::new(&format!("stream-{name}"))
}

const SHORT: &str = "[trajectory]\nstarts = 1\n[simulation]\nperiods = 4\n\
                     [validation]\nfrequencies_hz = [2.5]\nperiods = 4\npd_grid = 11\npd_random = 500\n";

fn identify(cfg: &Path, log: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let r = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["identify", "--config", cfg.to_str().unwrap(), "--data"])
        .arg(log)
        .arg("--out")
        .arg(out)
        .args(["--quiet", "--reproducible"])
        .args(extra)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    serde_json::from_str(&std::fs::read_to_string(out.join("base.json")).unwrap()).unwrap()
}

fn column(v: &serde_json::Value, key: &str) -> Vec<f64> {
    v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p[key].as_f64().unwrap())
        .collect()
}

fn rel(a: &[f64], b: &[f64]) -> f64 {
    let s = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0, |m, (x, y)| m.max((x - y).abs() / s))
}

#[test]
fn streaming_on_and_off_give_the_same_estimates() {
    let dir = scratch("onoff");
    let cfg = dir.join("short.toml");
    std::fs::write(&cfg, SHORT).unwrap();
    let sim = dir.join("sim");
    let r = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["pipeline", "--config", cfg.to_str().unwrap(), "--out"])
        .arg(&sim)
        .args(["--seed", "3", "--reproducible", "--quiet"])
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let log = sim.join("log.csv");
    // The paper's route: the fixed low-pass, rows away from reversals.
    let away = dir.join("away.toml");
    std::fs::write(
        &away,
        format!(
            "{SHORT}[signal]\nbandwidth = \"fixed\"\n[identification]\nrows = \"away_from_reversals\"\n"
        ),
    )
    .unwrap();
    same_estimates(&dir, &away, &log, "", "larger_of_hac_and_white_filtered");
    // Every row with the Coulomb widths refined on the averaged period, and
    // the data-chosen bandwidth (a harmonic series, projected on both
    // sides): the same widths, rows and estimates.
    let all = dir.join("all.toml");
    std::fs::write(
        &all,
        format!("{SHORT}[signal]\nbandwidth = \"auto\"\n[identification]\nrows = \"all\"\n"),
    )
    .unwrap();
    // In memory every row of the averaged period gives the harmonic
    // sandwich's σ; the white-noise σ is still the streamed one.
    let (mem, qr) = same_estimates(&dir, &all, &log, "all-", "harmonic_sandwich");
    let n = mem["rows_fitted"].clone();
    assert_eq!(n[0], n[1], "{n}");
    assert_eq!(qr["rows_fitted"], n);
    let widths = |d: &str| {
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(d).join("summary.json")).unwrap(),
        )
        .unwrap();
        s["friction_width"]["joints"].clone()
    };
    let (wm, wq) = (widths("all-off"), widths("all-qr"));
    for j in 0..2 {
        assert_eq!(wm[j]["status"], "refined", "{wm}");
        // The same record up to the rounding of the period sums.
        let (a, b) = (wm[j]["w"].as_f64().unwrap(), wq[j]["w"].as_f64().unwrap());
        assert!((a - b).abs() < 1e-9 * a, "in memory {wm} vs streamed {wq}");
    }
}

/// Identifies `log` with `cfg` in memory and streamed (QR and Gram) into
/// `prefix`-named directories, checks that they agree, and returns the
/// in-memory and the QR `base.json`.
fn same_estimates(
    dir: &Path,
    cfg: &Path,
    log: &Path,
    prefix: &str,
    in_memory_sigma: &str,
) -> (serde_json::Value, serde_json::Value) {
    let out = |d: &str| dir.join(format!("{prefix}{d}"));
    let mem = identify(cfg, log, &out("off"), &["--streaming", "off"]);
    let qr = identify(
        cfg,
        log,
        &out("qr"),
        &["--streaming", "on", "--accumulation", "qr"],
    );
    let gram = identify(cfg, log, &out("gram"), &["--streaming", "on"]);
    // The same rows and operations up to rounding: QR agrees to ≈ κ ε.
    let (m, q, g) = (
        column(&mem, "ols"),
        column(&qr, "ols"),
        column(&gram, "ols"),
    );
    assert!(
        rel(&q, &m) < 1e-9,
        "QR streaming vs in memory: {:e}",
        rel(&q, &m)
    );
    // Normal equations: within their checked bound κ² ε ≤ 1e-6.
    assert!(
        rel(&g, &m) < 1e-6,
        "Gram streaming vs in memory: {:e}",
        rel(&g, &m)
    );
    // σ: the streaming route keeps no residuals, so it reports the
    // white-noise σ corrected for the filter; in memory the same figure is
    // `sigma_white` (the floor of the in-memory `sigma` on masked rows).
    assert_eq!(mem["sigma_method"], in_memory_sigma);
    assert_eq!(qr["sigma_method"], "white_filtered");
    let (ms, qs) = (column(&mem, "sigma_white"), column(&qr, "sigma"));
    assert!(rel(&qs, &ms) < 1e-9, "σ: {:e}", rel(&qs, &ms));
    let rv = |v: &serde_json::Value| v["residual_variance"].as_f64().unwrap();
    assert!((rv(&qr) / rv(&mem) - 1.0).abs() < 1e-9);
    // The SDP solves the same reduced problem (to its solver tolerance).
    let (md, qd) = (column(&mem, "sdp"), column(&qr, "sdp"));
    assert!(rel(&qd, &md) < 1e-5, "SDP: {:e}", rel(&qd, &md));
    for d in ["qr", "gram"] {
        for f in [
            "params.json",
            "robot.xml",
            "params_ols.json",
            "summary.json",
            "report.md",
        ] {
            assert!(out(d).join(f).is_file(), "{d}/{f} missing");
        }
    }
    (mem, qr)
}
