//! End-to-end tests of the `aras` binary on a short configuration.

use std::path::Path;
use std::process::{Command, Output};

fn aras(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(args)
        .output()
        .expect("the aras binary runs")
}

/// A fresh scratch directory, removed when the test passes.
fn scratch(name: &str) -> aras_testkit::Scratch {
    aras_testkit::Scratch::new(&format!("cli-test-{name}"))
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A short but still meaningful run: 6 periods, 2 design starts, two
/// validation frequencies (the slowest and the fastest of Table 2).
const SHORT: &str = "[trajectory]\nstarts = 2\n[simulation]\nperiods = 6\n\
                     [validation]\nfrequencies_hz = [0.5, 2.5]\nperiods = 6\npd_grid = 21\npd_random = 2000\n";

/// The paper's route: the fixed 10 Hz low-pass, rows away from reversals.
const PAPER_ROUTE: &str =
    "[signal]\nbandwidth = \"fixed\"\n[identification]\nrows = \"away_from_reversals\"\n";

/// The default run (`aras pipeline`, the default configuration: the
/// data-chosen bandwidth, every row with the Coulomb widths refined): the
/// fitness (78) on every row against the raw torques lies within 1 point of
/// its noise ceiling per joint on the excitation and at 0.5 and 0.7 Hz, OLS
/// and SDP, and never above it by more than in-sample fitting of noise is
/// worth; σ is the harmonic sandwich; the refined widths hold the
/// simulator's 0.03 rad/s within 3 σ. Measured (seed 1): gaps 0.91 / 0.75
/// (excitation), 0.99 / 0.85 (0.5 Hz), 0.89 / 0.91 (0.7 Hz) points, most
/// of them the controller's reaction to encoder quantisation that the
/// angles cannot show (`docs/processing.md`); about 5 s.
#[test]
fn default_pipeline_fits_every_row_near_its_ceiling() {
    let dir = scratch("pipeline-default");
    let out = dir.join("out");
    let r = aras(&[
        "pipeline",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--reproducible",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s = json(&out.join("summary.json"));
    for f in s["fitness"].as_array().unwrap() {
        let set = f["dataset"].as_str().unwrap();
        let ceiling = f["noise_ceiling"].as_array().unwrap();
        for est in ["ols", "sdp"] {
            for j in 0..2 {
                let (ours, c) = (f[est][j].as_f64().unwrap(), ceiling[j].as_f64().unwrap());
                eprintln!("{set} {est} τ{}: {ours:.2} vs ceiling {c:.2}", j + 1);
                assert!(
                    ours <= c + 0.5,
                    "{set} {est} τ{}: {ours} vs ceiling {c}",
                    j + 1
                );
                if ["excitation", "xv_0.5hz", "xv_0.7hz"].contains(&set) {
                    assert!(
                        c - ours <= 1.0,
                        "{set} {est} τ{}: {ours} vs ceiling {c}",
                        j + 1
                    );
                }
            }
        }
    }
    assert_eq!(
        json(&out.join("base.json"))["sigma_method"],
        "harmonic_sandwich"
    );
    let w_true = aras_dyn::sim::SimConfig::default().friction_smoothing;
    for w in s["friction_width"]["joints"].as_array().unwrap() {
        assert_eq!(w["status"], "refined", "{w}");
        let (v, sd) = (w["w"].as_f64().unwrap(), w["std_dev"].as_f64().unwrap());
        assert!(
            sd > 0.0 && (v - w_true).abs() < 3.0 * sd,
            "w {v} ± {sd} vs the simulator's {w_true}"
        );
    }
}

#[test]
fn pipeline_identify_predict_end_to_end() {
    let dir = scratch("pipeline");
    let cfg = dir.join("short.toml");
    std::fs::write(&cfg, format!("{SHORT}{PAPER_ROUTE}")).unwrap();
    let out = dir.join("out");
    let (c, o) = (cfg.to_str().unwrap(), out.to_str().unwrap());
    let r = aras(&[
        "pipeline",
        "--config",
        c,
        "--out",
        o,
        "--quiet",
        "--reproducible",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(stdout.contains("xv_2.5hz"), "terminal table: {stdout}");
    for f in [
        "trajectory.json",
        "log.csv",
        "log.json",
        "params.json",
        "robot.xml",
        "params_ols.json",
        "base.json",
        "summary.json",
        "report.md",
        "report.html",
        "excitation.svg",
        "mass_eigen.svg",
        "torque1.svg",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("at 1000 Hz logged after a 2 s lead-in"),
        "{report}"
    );
    assert_eq!(json(&out.join("log.json"))["torques"], "held");
    let s = json(&out.join("summary.json"));
    assert!(
        s.get("timings_s").is_none(),
        "--reproducible leaves timings out"
    );
    // With g ⟂ a the paper model has 23 base parameters (`docs/model.md`, "Base parameters").
    assert_eq!(s["base_parameters"], 23);
    // Our fitness is read against the noise ceiling (the simulated motors'
    // noise-free torques against the same log: a perfect model with
    // perfect states), never against the paper's real-robot figures, which
    // are only carried along, labelled.
    //  * Never above the ceiling by more than in-sample fitting of noise is
    //    worth (≈ b/N ≪ 0.5 %; measured ≤ 0 on every set).
    //  * The excitation's kept rows (in-sample, away from reversals, where
    //    the model's friction holds) are within 0.5 point of their ceiling:
    //    measured 0.00 / 0.01 (τ1 / τ2) with the 10 Hz filter.
    //  * Cross-validation sits well below its ceiling (measured: kept rows
    //    8.9 / 5.9 points at 0.5 Hz, 12.1 / 9.4 at 2.5 Hz): the ceiling uses the
    //    exact states, ours the states processed from quantised angles and
    //    the paper's sign-Coulomb friction for the simulator's smooth one
    //    (`docs/processing.md`). That gap is the processing's to close; it
    //    is reported, not asserted.
    let fit = s["fitness"].as_array().unwrap();
    assert_eq!(fit.len(), 3);
    for f in fit {
        assert_eq!(f["data"], "simulated", "{f}");
        assert!(f["paper_real_robot"].is_array(), "{f}");
        assert!(f.get("paper").is_none(), "unlabelled paper figures: {f}");
        let ceiling = f["noise_ceiling"].as_array().unwrap();
        let ceiling_kept = f["noise_ceiling_kept"].as_array().unwrap();
        for (est, kept) in [("ols", "ols_kept"), ("sdp", "sdp_kept")] {
            for j in 0..2 {
                let (ours, c) = (f[est][j].as_f64().unwrap(), ceiling[j].as_f64().unwrap());
                let (ours_k, ck) = (
                    f[kept][j].as_f64().unwrap(),
                    ceiling_kept[j].as_f64().unwrap(),
                );
                assert!(
                    c <= 100.0 && ours <= c + 0.5,
                    "{} {est} τ{}: {ours} vs ceiling {c}",
                    f["dataset"],
                    j + 1
                );
                assert!(
                    ours_k <= ck + 0.5,
                    "{} {kept} τ{}: {ours_k} vs kept ceiling {ck}",
                    f["dataset"],
                    j + 1
                );
                if f["dataset"] == "excitation" {
                    assert!(
                        (ours_k - ck).abs() <= 0.5,
                        "{} {kept} τ{}: {ours_k} vs kept ceiling {ck}",
                        f["dataset"],
                        j + 1
                    );
                }
            }
        }
    }
    let table = String::from_utf8_lossy(&r.stdout);
    assert!(
        table.contains("SIMULATED") && table.contains("REAL robot") && table.contains("ceiling"),
        "{table}"
    );
    // The SDP's mass matrix is PD over the workspace, its links consistent.
    assert_eq!(s["pd_check"]["sdp"]["positive_definite"], true);
    for v in s["pseudo_inertia_min_eigenvalue"]["sdp"]
        .as_array()
        .unwrap()
    {
        assert!(v.as_f64().unwrap() > 0.0);
    }
    // The well-excited base parameters are close to the truth: the
    // friction levels within 25 % (the near-rest creep of the smooth
    // simulated friction biases them a little), the gravity terms within 5 %.
    let base = json(&out.join("base.json"));
    for p in base["parameters"].as_array().unwrap() {
        let def = p["definition"].as_str().unwrap();
        let (sdp, truth) = (p["sdp"].as_f64().unwrap(), p["truth"].as_f64().unwrap());
        let tol = if def.ends_with("Fc1") || def.ends_with("Fc2") {
            0.25
        } else if def.contains(".hx") {
            0.05
        } else {
            continue;
        };
        assert!(
            (sdp - truth).abs() <= tol * truth.abs(),
            "{def}: {sdp} vs {truth}"
        );
    }
    let params =
        aras_dyn::Params::load(out.join("params.json")).expect("params.json is a parameter file");
    assert!(params.links.iter().all(|l| l.mass > 0.0));
    // robot.xml is the MJCF of exactly this (physically consistent) set.
    let xml = std::fs::read_to_string(out.join("robot.xml")).unwrap();
    assert_eq!(
        xml,
        aras_dyn::mjcf::to_mjcf(&params, &Default::default()).unwrap()
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains("<svg") && !html.contains("src=\""),
        "self-contained HTML"
    );

    // identify on the pipeline's log, as a lab would on its own log.
    let ident = dir.join("ident");
    let log = out.join("log.csv");
    let r = aras(&[
        "identify",
        "--data",
        log.to_str().unwrap(),
        "--out",
        ident.to_str().unwrap(),
        "-q",
        "--config",
        c,
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let si = json(&ident.join("summary.json"));
    let ex = &si["fitness"][0];
    assert_eq!(ex["dataset"], "excitation");
    assert_eq!(
        ex["sdp"], s["fitness"][0]["sdp"],
        "identify and pipeline agree on the same log"
    );
    assert!(
        si["parameter_errors"]["sdp"].is_object(),
        "truth found in the sidecar"
    );

    // predict with the identified parameters on a cross-validation log.
    let pred = dir.join("pred.csv");
    let xv = out.join("validation").join("xv_0.5hz.csv");
    let p = ident.join("params.json");
    let r = aras(&[
        "predict",
        "--params",
        p.to_str().unwrap(),
        "--data",
        xv.to_str().unwrap(),
        "--out",
        pred.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let text = std::fs::read_to_string(&pred).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,tau1,tau2"));
    assert_eq!(
        lines.count(),
        12000,
        "one row per log row (6 periods of 2 s at 1 kHz)"
    );
    let msg = String::from_utf8_lossy(&r.stdout);
    let fit1: f64 = msg
        .split("τ1 ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        fit1 > 85.2,
        "predict fitness {fit1} on (79) at 0.5 Hz: {msg}"
    );
    // An existing output is refused without --force.
    let r = aras(&[
        "predict",
        "--params",
        p.to_str().unwrap(),
        "--data",
        xv.to_str().unwrap(),
        "--out",
        pred.to_str().unwrap(),
    ]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("--force"));
}

#[test]
fn existing_output_directory_is_refused_without_force() {
    let dir = scratch("force");
    let out = dir.join("out");
    // A previous run of the tool (with its manifest).
    let first = aras_cli::output::OutDir::create(&out, false, &[]).unwrap();
    first.write("old.txt", "x").unwrap();
    first.commit().unwrap();
    let err = aras_cli::output::OutDir::create(&out, false, &[])
        .err()
        .expect("refused");
    assert!(err.to_string().contains("--force"), "{err}");
    let o = aras_cli::output::OutDir::create(&out, true, &[]).unwrap();
    o.write("new.txt", "x").unwrap();
    assert!(
        out.join("old.txt").exists(),
        "nothing is removed before commit"
    );
    o.commit().unwrap();
    assert!(out.join("new.txt").exists() && !out.join("old.txt").exists());
    let r = aras(&["pipeline", "--out", out.to_str().unwrap(), "-q"]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("already exists"));
}

#[test]
fn print_config_prints_parseable_defaults() {
    let r = aras(&["pipeline", "--print-config"]);
    assert!(r.status.success());
    let text = String::from_utf8(r.stdout).unwrap();
    let c =
        aras_cli::config::Config::parse(&text, aras_cli::config::Format::Toml, "printed").unwrap();
    assert_eq!(c, aras_cli::config::Config::default());
    // Every setting is in the file, the diagnosis's too, with the library's
    // defaults.
    assert!(
        text.contains("[diagnose]") && text.contains("[diagnose.grid]"),
        "{text}"
    );
    let lib = aras_pipeline::diagnose::DiagnoseOptions::default();
    assert_eq!(
        (c.diagnose.alpha, c.diagnose.min_gain, &c.diagnose.grid),
        (lib.alpha, lib.min_gain, &lib.grid)
    );
    assert_eq!(
        c.identification,
        aras_pipeline::identify::IdentifySettings::default()
    );
}

/// `--torques` and `log.torques` reach the log reader: the simulator's log
/// states held torques, a contradicting `--torques sampled` is refused
/// naming both, `--torques held` on a log without a sidecar is taken (with
/// a note) and is what `Log::torque_timing` says; an invalid value names the
/// valid ones.
#[test]
fn torques_option_reaches_the_log_reader() {
    use aras_cli::cli::{Cli, Command};
    use aras_cli::config::{Config, Format};
    use aras_log::TorqueTiming;
    let dir = scratch("torques");
    let cfg = dir.join("short.toml");
    std::fs::write(&cfg, "[simulation]\nperiods = 1\n").unwrap();
    let (c, log) = (cfg.to_str().unwrap(), dir.join("log.csv"));
    let l = log.to_str().unwrap();
    let r = aras(&[
        "simulate",
        "--config",
        c,
        "--frequency",
        "2.5",
        "--out",
        l,
        "-q",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_eq!(json(&dir.join("log.json"))["torques"], "held");
    let sim = aras_log::read_log(&log, &aras_log::ReadOptions::default()).unwrap();
    assert_eq!(sim.torque_timing(), TorqueTiming::Held);
    assert_eq!(sim.len(), 400);

    let params = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/robots/aras-diamond.json"
    );
    let pred = dir.join("pred.csv");
    let p = pred.to_str().unwrap();
    let predict = |extra: &[&str]| {
        let mut args = vec!["predict", "--params", params, "--data", l, "--out", p, "-q"];
        args.extend(extra);
        aras(&args)
    };
    let r = predict(&["--torques", "sampled"]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(
        err.contains("the torques are given as `sampled`")
            && err.contains("log.json states \"torques\": \"held\""),
        "{err}"
    );
    let r = predict(&["--torques", "held", "--force"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let r = predict(&["--torques", "held", "--sidecar", "none", "--force"]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("torques taken as held (from the options)"),
        "{err}"
    );
    let r = predict(&["--torques", "hold"]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(
        err.contains("invalid value 'hold' for '--torques <TIMING>'")
            && err.contains("[possible values: sampled, held]"),
        "{err}"
    );

    // The parsed command line and the config give the reader's options.
    let timing = |argv: &[&str], config: &str| {
        let cli = <Cli as clap::Parser>::try_parse_from(argv).unwrap();
        let Command::Predict(args) = cli.command else {
            panic!("not predict")
        };
        let config = Config::parse(config, Format::Toml, "t.toml").unwrap();
        let mut opts = args.log.read_options(&config.log).unwrap();
        opts.sidecar = aras_log::SidecarSource::None;
        aras_log::read_log(&log, &opts).unwrap().torque_timing()
    };
    let base = [
        "aras", "predict", "--params", params, "--data", l, "--out", p,
    ];
    assert_eq!(timing(&base, ""), TorqueTiming::Sampled);
    let mut held = base.to_vec();
    held.extend(["--torques", "held"]);
    assert_eq!(timing(&held, ""), TorqueTiming::Held);
    assert_eq!(
        timing(&base, "[log]\ntorques = \"held\"\n"),
        TorqueTiming::Held
    );
    let mut sampled = base.to_vec();
    sampled.extend(["--torques", "sampled"]);
    assert_eq!(
        timing(&sampled, "[log]\ntorques = \"held\"\n"),
        TorqueTiming::Sampled
    );
    let e = Config::parse("[log]\ntorques = \"hold\"\n", Format::Toml, "t.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("t.toml") && e.contains("unknown variant `hold`"),
        "{e}"
    );
}
