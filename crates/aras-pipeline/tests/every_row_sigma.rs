//! σ of the identification that fits every row of the averaged excitation
//! with the data-chosen bandwidth, against the truth over noise seeds
//! (`docs/model.md`, "σ on every row").
//!
//! Simulated against simulated: the default robot and excitation, 4
//! periods, the simulator's default sensors. The plant's motion is the same
//! on every seed (sensor noise does not act on it), so most of an
//! estimate's error is a bias of the processing shared by the seeds (the
//! controller's reaction to quantised angles, which the angles cannot
//! show); an honest σ covers that error, not only the seed-to-seed spread.

use std::path::PathBuf;

use aras_dyn::Params;
use aras_dyn::sim::{SimConfig, simulate, write_log};
use aras_excite::FourierTrajectory;
use aras_kin::Workspace;
use aras_log::{ReadOptions, read_log};
use aras_pipeline::friction_width::FitRows;
use aras_pipeline::identify::{IdentifySettings, SigmaMethod, friction_widths, identify};
use aras_pipeline::prepare::{RegressorColumns, prepare};
use aras_pipeline::robot::{FilterMode, base_parameters};
use aras_signal::{Bandwidth, PeriodSource, ProcessOptions};
use rayon::prelude::*;

/// Errors over the base parameters' σ for `seeds` noise seeds: per seed,
/// `(error_i / σ_i)` of every base parameter, and the method of σ.
fn z_scores(tag: &str, seeds: u64) -> (Vec<Vec<f64>>, Vec<SigmaMethod>) {
    let truth = Params::aras_diamond();
    let model = truth.model().unwrap();
    let geometry = truth.geometry().unwrap();
    let base = base_parameters(&model, &geometry, &Workspace::paper(), 400).unwrap();
    let beta = truth.standard_vector(&model).unwrap();
    let truth_b = base.to_base(beta.as_slice()).unwrap();
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/trajectories/default-excitation.json");
    let traj = FourierTrajectory::load(&path).unwrap();
    let period = traj.period();
    (1..=seeds)
        .into_par_iter()
        .map(|seed| {
            let cfg = SimConfig {
                duration_s: 4.0 * period,
                seed,
                ..SimConfig::default()
            };
            let sim = simulate(&truth, &traj, &cfg).unwrap();
            let dir = aras_testkit::Scratch::new(&format!("every-row-sigma-{tag}-{seed}"));
            let file = dir.join("log.csv");
            write_log(&file, &sim, true).unwrap();
            let log = read_log(&file, &ReadOptions::default()).unwrap();
            let opts = ProcessOptions {
                filter: Bandwidth::Auto,
                period: PeriodSource::Seconds(period),
                ..ProcessOptions::default()
            };
            let mut prepared = prepare(
                &log,
                &opts,
                &model,
                &geometry,
                FilterMode::Parallel,
                RegressorColumns::Standard,
                true,
            )
            .unwrap();
            let settings = IdentifySettings {
                rows: FitRows::All,
                ..IdentifySettings::default()
            };
            let (m, _, keep) = friction_widths(&mut prepared, &base, &model, &settings).unwrap();
            let id = identify(&prepared, &base, &m, &truth, &settings, &keep).unwrap();
            let z = (0..truth_b.len())
                .map(|i| (id.ols.estimate[i] - truth_b[i]) / id.ols.std_dev[i])
                .collect();
            (z, id.sigma_method)
        })
        .unzip()
}

/// Mean of z² over the parameters and seeds, and the largest per-parameter
/// RMS z over the seeds.
fn summary(z: &[Vec<f64>]) -> (f64, f64) {
    let (s, b) = (z.len() as f64, z[0].len());
    let rms: Vec<f64> = (0..b)
        .map(|i| (z.iter().map(|v| v[i] * v[i]).sum::<f64>() / s).sqrt())
        .collect();
    let mean_z2 = rms.iter().map(|r| r * r).sum::<f64>() / b as f64;
    (mean_z2, rms.iter().copied().fold(0.0, f64::max))
}

/// Reduced form of `harmonic_sandwich_over_24_seeds` (4 seeds, in CI): on
/// every row of one averaged period σ is the harmonic sandwich, and the
/// errors' mean z² over the 23 base parameters lies in [0.5, 2]. Measured
/// over 8 seeds: mean z² 1.13, the worst parameter (b11) at RMS z 2.3;
/// the time-domain HAC with the filter model's floor gave 0.17 on the same
/// logs (σ 2.4 times too wide), the HAC alone 0.31. The bounds: 23
/// parameters whose errors are mostly one shared bias hold mean z² to
/// about ±0.3 of 1 (√(2/23)); [0.5, 2] fails both a σ twice too wide and
/// one 1.4 times too narrow.
#[test]
fn harmonic_sandwich_is_honest_on_every_row() {
    let (z, methods) = z_scores("ci", 4);
    assert!(
        methods.iter().all(|m| *m == SigmaMethod::HarmonicSandwich),
        "{methods:?}"
    );
    let (mean_z2, worst) = summary(&z);
    assert!((0.5..=2.0).contains(&mean_z2), "mean z² {mean_z2}");
    assert!(worst < 3.5, "worst RMS z {worst}");
}

/// The study behind the figures in `docs/model.md` (24 seeds, ≈ 20 s).
#[test]
#[ignore]
fn harmonic_sandwich_over_24_seeds() {
    let (z, _) = z_scores("study", 24);
    let (mean_z2, worst) = summary(&z);
    eprintln!("24 seeds: mean z² {mean_z2:.3}, worst parameter RMS z {worst:.2}");
    assert!((0.5..=2.0).contains(&mean_z2), "mean z² {mean_z2}");
}
