//! The diagnosis recipe on the default route (`diagnose_with_widths`):
//! every row fitted, the Coulomb widths of `Fc tanh(θ̇/w)` refined on TRAIN
//! together with the effects the diagnosis names.
//!
//! Simulated against simulated: TRAIN is the designed excitation (4
//! periods of 10 s), the validation sets (79) at 0.5 and 1.0 Hz; default
//! sensors and the simulator's own friction `Fc tanh(θ̇/0.03)`; every log
//! written as CSV + sidecar and read back, processed with the library's
//! default processing (the data-chosen bandwidth).

use std::path::PathBuf;

use aras_dyn::sim::{SimConfig, simulate, write_log};
use aras_dyn::{Model, Params, Sinusoid, Trajectory};
use aras_excite::FourierTrajectory;
use aras_log::{Log, ReadOptions, read_log};
use aras_pipeline::diagnose::{
    Dataset, DiagnoseOptions, PassRows, PassStage, WidthSource, diagnose_with_widths,
};
use aras_pipeline::friction_width::WidthStatus;
use aras_pipeline::identify::IdentifySettings;
use aras_signal::{PeriodSource, ProcessOptions, process};

/// The simulator's Coulomb transition width (rad/s).
const SIM_WIDTH: f64 = 0.03;

fn read_back(truth: &Params, traj: &dyn Trajectory, secs: f64, tag: &str) -> Log {
    let cfg = SimConfig {
        duration_s: secs,
        ..SimConfig::default()
    };
    let log = simulate(truth, traj, &cfg).unwrap();
    let dir = aras_testkit::Scratch::new(&format!("diag-widths-{tag}"));
    let path: PathBuf = dir.join(format!("{tag}.csv"));
    write_log(&path, &log, true).unwrap();
    read_log(&path, &ReadOptions::default()).unwrap()
}

fn options(period: f64) -> ProcessOptions {
    ProcessOptions {
        period: PeriodSource::Seconds(period),
        ..ProcessOptions::default()
    }
}

fn dataset(log: &Log, period: f64, truth: &Params, tag: &str) -> Dataset {
    let geometry = truth.geometry().unwrap();
    let p = process(log, &options(period), &aras_kin::task_motion(&geometry)).unwrap();
    Dataset::from_processed(tag, &p).unwrap()
}

/// Each joint's width status, width and σ (rad/s).
type Widths = [(WidthStatus, f64, f64); 2];

/// Runs the recipe on a robot simulated with `truth`: the effects named
/// (ids), the stages reported, and the widths' statuses and values with σ.
fn run(truth: &Params, tag: &str) -> (Vec<&'static str>, Vec<PassStage>, Widths) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/trajectories/default-excitation.json");
    let excitation = FourierTrajectory::load(&path).unwrap();
    let period = excitation.period();
    let train_log = read_back(truth, &excitation, 4.0 * period, &format!("{tag}-train"));
    let train = dataset(&train_log, period, truth, "train");
    let vals: Vec<Dataset> = [0.5, 1.0]
        .iter()
        .map(|&f| {
            let traj = Sinusoid::paper_79(f).unwrap();
            let log = read_back(truth, &traj, 10.0 / f, &format!("{tag}-val{f}"));
            dataset(&log, 1.0 / f, truth, &format!("val{f}"))
        })
        .collect();
    let nominal = Params::aras_diamond();
    let start = Model::paper(nominal.gravity).unwrap();
    let process = options(period);
    let source = WidthSource::Log {
        log: &train_log,
        process: &process,
    };
    let mut stages = Vec::new();
    let r = diagnose_with_widths(
        &start,
        &nominal.geometry().unwrap(),
        &train,
        &vals,
        &DiagnoseOptions::default(),
        &source,
        &IdentifySettings::default(),
        &mut |s| stages.push(s),
    )
    .unwrap();
    assert_eq!(
        stages
            .iter()
            .filter(|s| matches!(s, PassStage::Widths { .. }))
            .count(),
        r.passes,
        "one width refinement per pass: {stages:?}"
    );
    let named = r.diagnosis.steps.iter().map(|s| s.candidate.id()).collect();
    let widths = r.widths.joints.map(|j| (j.status, j.w, j.std_dev));
    (named, stages, widths)
}

/// A hidden passive-joint damping is named alone on every row; the widths
/// are refined again with it (a second pass, which names it again and is
/// kept), and they recover the simulator's 0.03 rad/s within 3σ.
#[test]
fn the_recipe_refines_the_widths_with_the_named_effect() {
    let mut truth = Params::aras_diamond();
    truth.extra.passive_joint_viscous = Some([0.005; 3]);
    let (named, stages, widths) = run(&truth, "viscous");
    assert_eq!(named, ["passive_joint_viscous"], "stages {stages:?}");
    assert_eq!(
        stages,
        [
            PassStage::Widths { pass: 1 },
            PassStage::Diagnose {
                pass: 1,
                rows: PassRows::Fitted
            },
            PassStage::Widths { pass: 2 },
            PassStage::Diagnose {
                pass: 2,
                rows: PassRows::Fitted
            },
        ]
    );
    for (j, (status, w, sigma)) in widths.into_iter().enumerate() {
        assert_eq!(status, WidthStatus::Refined, "joint {}", j + 1);
        assert!(
            (w - SIM_WIDTH).abs() <= 3.0 * sigma,
            "joint {}: width {w} ± {sigma} against the simulator's {SIM_WIDTH}",
            j + 1
        );
    }
}

/// Without a hidden effect nothing is named and one pass is run.
#[test]
fn the_recipe_names_nothing_on_the_control() {
    let (named, stages, _) = run(&Params::aras_diamond(), "control");
    assert!(named.is_empty(), "named {named:?}");
    assert_eq!(stages.len(), 2, "{stages:?}");
}
