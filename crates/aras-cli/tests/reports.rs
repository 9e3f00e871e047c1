//! What the reports show a robotics engineer: the identify report on a
//! measured log says what was run (no simulator paragraph), and the
//! diagnosis plots one marker per step on axes zoomed to the values.

use std::path::Path;
use std::process::Command;

use aras_dyn::sim::{SimConfig, simulate, write_log};
use aras_dyn::{Params, Sinusoid, Trajectory};
use aras_excite::FourierTrajectory;

mod common;

use common::scratch;

fn default_excitation() -> FourierTrajectory {
    FourierTrajectory::load(&common::fixture("trajectories/default-excitation.json")).unwrap()
}

fn log(truth: &Params, traj: &dyn Trajectory, secs: f64, path: &Path) {
    let cfg = SimConfig {
        duration_s: secs,
        ..SimConfig::default()
    };
    write_log(path, &simulate(truth, traj, &cfg).unwrap(), true).unwrap();
}

/// Removes the simulation's truth from a log's sidecar: the log then reads
/// as a lab's measured log.
fn as_measured(csv: &Path) {
    let side = aras_log::sidecar_path(csv);
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&side).unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("truth");
    std::fs::write(&side, serde_json::to_string_pretty(&v).unwrap()).unwrap();
}

fn identify(data: &Path, out: &Path) -> String {
    identify_with(data, out, &[])
}

fn identify_with(data: &Path, out: &Path, extra: &[&str]) -> String {
    let r = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["identify", "--quiet", "--data"])
        .arg(data)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    std::fs::read_to_string(out.join("report.md")).unwrap()
}

#[test]
fn identify_report_on_a_measured_log_has_no_simulator_paragraph() {
    let dir = scratch("reports", "measured");
    let exc = default_excitation();
    let data = dir.join("lab.csv");
    log(&Params::aras_diamond(), &exc, 2.0 * exc.period(), &data);
    // With the truth: parameter errors, and no ceiling (this run has not
    // the noise-free torques).
    let sim = identify(&data, &dir.join("sim"));
    assert!(
        sim.contains("Parameter errors against the simulation's truth"),
        "{sim}"
    );
    assert!(
        sim.contains("no noise ceiling") && !sim.contains("simulated motors"),
        "{sim}"
    );
    as_measured(&data);
    let md = identify(&data, &dir.join("lab"));
    for simulator in [
        "simulated motors",
        "simulated robot",
        "ceiling τ1",
        "not comparable with a simulation",
        "simulation's truth",
    ] {
        assert!(!md.contains(simulator), "`{simulator}` in:\n{md}");
    }
    assert!(
        md.contains("a measured log (its sidecar holds no simulation truth)"),
        "the intro says what was run:\n{md}"
    );
    assert!(md.contains("no noise ceiling"), "{md}");
    let html = std::fs::read_to_string(dir.join("lab").join("report.html")).unwrap();
    assert!(!html.contains("simulated motors"));
    assert!(
        html.contains("<title>ARAS-Diamond identification report (aras identify)</title>"),
        "no Markdown markup in the page title"
    );
}

/// The SVG's `<circle>` markers.
fn markers(svg: &str) -> usize {
    svg.matches("<circle").count()
}

#[test]
fn diagnosis_plots_steps_as_points_and_residuals_as_binned_clouds() {
    let dir = scratch("reports", "diagnose");
    let mut truth = Params::aras_diamond();
    truth.extra.passive_joint_viscous = Some([0.005; 3]);
    let exc = default_excitation();
    let (train, val) = (dir.join("train.csv"), dir.join("val.csv"));
    log(&truth, &exc, 2.0 * exc.period(), &train);
    log(&truth, &Sinusoid::paper_79(0.5).unwrap(), 10.0, &val);
    let out = dir.join("out");
    let r = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["diagnose", "--quiet", "--data"])
        .arg(&train)
        .arg("--validate")
        .arg(&val)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("diagnosis.json")).unwrap())
            .unwrap();
    let rows = j["fitness"].as_array().unwrap();
    assert!(rows.len() >= 2, "{rows:?}");
    let svg = std::fs::read_to_string(out.join("fitness_steps.svg")).unwrap();
    // One panel per joint of the one validation set, one marker per step.
    assert_eq!(
        markers(&svg),
        2 * rows.len(),
        "one marker per step and panel"
    );
    assert!(svg.contains("+ passive_joint_viscous"), "steps named");
    assert!(svg.contains(">\nstart\n<") || svg.contains(">start<"));
    // Every tick label of a panel lies within its values' range with a
    // margin (no axis from −70 % for a change of tenths).
    let lo = rows
        .iter()
        .flat_map(|r| r["fitness"][0].as_array().unwrap().clone())
        .filter_map(|v| v.as_f64())
        .fold(f64::INFINITY, f64::min);
    let ticks: Vec<f64> = svg
        .split("</text>")
        .filter_map(|t| t.rsplit('>').next()?.trim().parse::<f64>().ok())
        .collect();
    assert!(!ticks.is_empty());
    let span = 100.0 - lo;
    assert!(
        ticks.iter().all(|t| *t >= lo - 0.1 * span && *t <= 100.0),
        "ticks {ticks:?}, lowest value {lo}"
    );
    assert!(!svg.contains("-0.0") && !svg.contains('`'));
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    for axis in ["velocity", "position"] {
        for jn in [1, 2] {
            let f = format!("residual_{axis}_val_csv_j{jn}.svg");
            assert!(names.contains(&f), "{f} missing: {names:?}");
            let s = std::fs::read_to_string(out.join(&f)).unwrap();
            let n = markers(&s);
            assert!(
                n > 200 && n <= 2 * aras_pipeline::diagnose::SAMPLE_ROWS,
                "{f}: {n} points"
            );
        }
    }
    // The viscous friction found: a hysteresis figure near reversals.
    assert!(
        names.iter().any(|n| n.starts_with("hysteresis_")),
        "{names:?}"
    );
}

/// The report says which rows were fitted: every row by default, away from
/// velocity reversals with `identification.rows = "away_from_reversals"`.
#[test]
fn identify_report_says_which_rows_were_fitted() {
    let dir = scratch("reports", "rows");
    let exc = default_excitation();
    let data = dir.join("run.csv");
    log(&Params::aras_diamond(), &exc, 2.0 * exc.period(), &data);
    let away_cfg = dir.join("away.toml");
    std::fs::write(
        &away_cfg,
        "[identification]\nrows = \"away_from_reversals\"\n",
    )
    .unwrap();
    let away = identify_with(
        &data,
        &dir.join("away"),
        &["--config", away_cfg.to_str().unwrap()],
    );
    assert!(
        away.contains("rows each, away from velocity reversals;"),
        "{away}"
    );
    // summary.json records the processing: the simulator's held torques,
    // the motion evaluated half a step after each row.
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("away").join("summary.json")).unwrap(),
    )
    .unwrap();
    let p = &summary["processing"];
    assert_eq!(p["torque_timing"], "held", "{p}");
    assert_eq!(p["motion_shift_steps"], 0.5, "{p}");
    assert!(p["reason"].as_str().unwrap().contains("midpoint"), "{p}");
    let all = identify(&data, &dir.join("all"));
    assert!(
        all.contains("rows each, every row, with the Coulomb transition widths refined;"),
        "{all}"
    );
}
