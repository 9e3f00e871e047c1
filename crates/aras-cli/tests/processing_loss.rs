//! The processing loss (`docs/processing.md`, "Fitness figures"): `predict`
//! reports the fitness (78) with the logged θ̇, θ̈ minus the fitness from
//! the angles alone, on the rows both cover, and `validate` per frequency.

mod common;

use std::collections::HashMap;
use std::path::Path;

use aras_cli::identify::process_options;
use aras_pipeline::validate::loss::{loss_between, predict_route};
use common::{aras, columns, fitness, fixture, scratch, short_validate_config};

/// A simulated log with exact derivative columns (3 periods at 1 Hz).
fn simulated(dir: &Path) -> std::path::PathBuf {
    simulated_at(dir, "1", 3)
}

/// A simulated log of `periods` periods of (79) at `frequency` Hz.
fn simulated_at(dir: &Path, frequency: &str, periods: usize) -> std::path::PathBuf {
    let cfg = dir.join("short.toml");
    std::fs::write(&cfg, format!("[simulation]\nperiods = {periods}\n")).unwrap();
    let sim = dir.join("sim.csv");
    let r = aras(&[
        "simulate",
        "--frequency",
        frequency,
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        sim.to_str().unwrap(),
        "-q",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    sim
}

/// The simulated robot's own parameters, written in `dir`: the fixture with
/// the simulator's 0.03 rad/s Coulomb width (`simulation.friction_smoothing`),
/// so that the exact derivatives give the perfect prediction.
fn simulated_robot(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(fixture("robots/aras-diamond.json")).unwrap();
    let with_width = text.replacen(
        "\"Fc2\": 0.28876",
        "\"Fc2\": 0.28876,\n    \"w\": [0.03, 0.03]",
        1,
    );
    assert_ne!(text, with_width, "the fixture's friction section changed");
    let params = dir.join("simulated-robot.json");
    std::fs::write(&params, with_width).unwrap();
    params
}

/// Runs `predict --summary` with the simulated robot's parameters and
/// returns its stdout and the summary JSON.
fn predict(log: &Path, out: &Path) -> (String, serde_json::Value) {
    let json = out.with_extension("json");
    let params = simulated_robot(out.parent().unwrap());
    let r = aras(&[
        "predict",
        "--params",
        params.to_str().unwrap(),
        "--data",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--summary",
        json.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let v = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    (String::from_utf8_lossy(&r.stdout).into_owned(), v)
}

fn pair(v: &serde_json::Value) -> [f64; 2] {
    [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()]
}

#[test]
fn predict_reports_the_loss_recomputed_from_both_routes_files() {
    let dir = scratch("loss", "predict");
    let sim = simulated(&dir);
    // The same log without its derivative columns: the angles-only route.
    let c = columns(&sim);
    let base = ["t", "theta1", "theta2", "tau1", "tau2"];
    let angles = dir.join("angles.csv");
    let mut text = base.join(",") + "\n";
    for (i, _) in c["t"].iter().enumerate() {
        let row: Vec<String> = base.iter().map(|k| format!("{}", c[*k][i])).collect();
        text += &(row.join(",") + "\n");
    }
    std::fs::write(&angles, text).unwrap();
    std::fs::copy(
        aras_log::sidecar_path(&sim),
        aras_log::sidecar_path(&angles),
    )
    .unwrap();

    let (said, with) = predict(&sim, &dir.join("logged_pred.csv"));
    let (said_angles, without) = predict(&angles, &dir.join("angles_pred.csv"));
    assert!(said.contains("processing loss"), "{said}");
    assert!(!said_angles.contains("processing loss"), "{said_angles}");
    assert_eq!(with["route"], "logged_derivatives");
    assert_eq!(without["route"], "angles");
    // The key exists on both; null without derivative columns.
    assert!(without.get("processing_loss").is_some_and(|v| v.is_null()));
    let loss = &with["processing_loss"];
    assert!(loss.is_object(), "{with}");

    // Recomputed from the two written files, on the rows both cover,
    // against the log's raw torques.
    let lp = columns(&dir.join("logged_pred.csv"));
    let ap = columns(&dir.join("angles_pred.csv"));
    let row_of = |p: &HashMap<String, Vec<f64>>| -> HashMap<u64, usize> {
        p["t"]
            .iter()
            .enumerate()
            .map(|(i, t)| (t.to_bits(), i))
            .collect()
    };
    let (lr, ar) = (row_of(&lp), row_of(&ap));
    let both: Vec<(usize, usize, usize)> = c["t"]
        .iter()
        .enumerate()
        .filter_map(|(r, t)| Some((r, *lr.get(&t.to_bits())?, *ar.get(&t.to_bits())?)))
        .collect();
    assert_eq!(loss["rows"].as_u64().unwrap() as usize, both.len());
    let (fl, fa, d) = (
        pair(&loss["fitness_logged"]),
        pair(&loss["fitness_angles"]),
        pair(&loss["loss"]),
    );
    for j in 0..2 {
        let tau = format!("tau{}", j + 1);
        let m: Vec<f64> = both.iter().map(|&(r, _, _)| c[&tau][r]).collect();
        let l: Vec<f64> = both.iter().map(|&(_, i, _)| lp[&tau][i]).collect();
        let a: Vec<f64> = both.iter().map(|&(_, _, i)| ap[&tau][i]).collect();
        // Shortest round-trip numbers in the files: the figures agree to
        // the sums' rounding.
        assert!(
            (fitness(&m, &l) - fl[j]).abs() < 1e-9,
            "τ{}: {} vs {}",
            j + 1,
            fitness(&m, &l),
            fl[j]
        );
        assert!(
            (fitness(&m, &a) - fa[j]).abs() < 1e-9,
            "τ{}: {} vs {}",
            j + 1,
            fitness(&m, &a),
            fa[j]
        );
        assert_eq!(d[j], fl[j] - fa[j]);
        // The exact derivatives predict better than the filtered angles.
        assert!(d[j] > 0.0, "τ{}: loss {}", j + 1, d[j]);
    }
}

#[test]
fn the_loss_of_the_logged_route_against_itself_is_exactly_zero() {
    let dir = scratch("loss", "itself");
    let sim = simulated(&dir);
    let log = aras_log::read_log(&sim, &aras_log::ReadOptions::default()).unwrap();
    let params = aras_dyn::Params::load(simulated_robot(&dir)).unwrap();
    let model = params.model().unwrap();
    let geometry = params.geometry().unwrap();
    let beta = params.standard_vector(&model).unwrap().as_slice().to_vec();
    let cfg = aras_cli::config::Config::default();
    let logged = process_options(&cfg, None, true);
    // Two independent runs of the logged-derivative route.
    let (a, pa) = predict_route(&log, &logged, &model, &geometry, &beta).unwrap();
    let (b, pb) = predict_route(&log, &logged, &model, &geometry, &beta).unwrap();
    let l = loss_between(&a, &pa, &b, &pb).unwrap();
    assert_eq!(l.loss, [0.0, 0.0]);
    assert_eq!(l.rows, log.len());
    assert_eq!(l.fitness_logged, l.fitness_angles);
    // And the figure is the one predict prints for PRED.csv.
    let (_, with) = predict(&sim, &dir.join("pred.csv"));
    assert_eq!(l.fitness_logged, pair(&with["fitness"]));
}

#[test]
fn validate_reports_the_loss_per_frequency() {
    let dir = scratch("loss", "validate");
    let cfg = short_validate_config(&dir);
    let out = dir.join("validate");
    let params = simulated_robot(&dir);
    let r = aras(&[
        "validate",
        "--params",
        params.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let f = &s["fitness"][0];
    let loss = pair(&f["processing_loss"]);
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("loss τ1"), "{report}");
    for (j, &loss_j) in loss.iter().enumerate() {
        assert!(loss_j.is_finite());
        // The true model with the exact derivatives is the perfect
        // prediction up to the logged angles' quantisation (1.5e-4 rad, a
        // gravity torque error near 1e-4 N·m against the 5 mN·m noise):
        // its fitness is the ceiling's on the same rows to 0.01 points, so
        // the loss is the gap between the ceiling and the angles-only
        // fitness.
        let (sim, ceiling) = (pair(&f["simulated"])[j], pair(&f["noise_ceiling"])[j]);
        assert!(
            (sim + loss[j] - ceiling).abs() <= 0.01,
            "τ{}: {sim} + {} vs {ceiling}",
            j + 1,
            loss[j]
        );
        assert!(loss[j] > 0.0);
    }
}

/// A log the angles alone cannot process (its sidecar's period, 1/0.7 s,
/// is no whole number of 1 ms samples, and two periods leave no block that
/// is) still gets its logged-derivative prediction: the loss is `null` and
/// a note says why.
#[test]
fn a_log_the_angles_cannot_process_gets_its_prediction_without_a_loss() {
    let dir = scratch("loss", "no-angles");
    let sim = simulated_at(&dir, "0.7", 2);
    let out = dir.join("pred.csv");
    let json = dir.join("pred.json");
    let r = aras(&[
        "predict",
        "--params",
        fixture("robots/aras-diamond.json").to_str().unwrap(),
        "--data",
        sim.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--summary",
        json.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    assert!(
        err.contains("note: no processing loss") && err.contains("whole number"),
        "{err}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["route"], "logged_derivatives");
    assert!(v["processing_loss"].is_null(), "{v}");
    assert_eq!(columns(&out)["t"].len(), 2 * 1000 * 10 / 7);
}
