//! The friction's Coulomb transition widths refined on a simulated log
//! (`aras_dyn::sim`, whose friction is `Fc tanh(θ̇ / 0.03)`): the refined
//! width against the truth within 3σ, the all-row fitness against the
//! noise ceiling, and `rows = "away_from_reversals"` (no refinement).

use std::path::PathBuf;

use aras_dyn::Params;
use aras_dyn::sim::{SimConfig, simulate, write_log};
use aras_excite::FourierTrajectory;
use aras_ident::ReducedLs;
use aras_ident::validate::{fitness, predict};
use aras_kin::Workspace;
use aras_log::{ReadOptions, read_log};
use aras_pipeline::friction_width::{WidthRefinement, WidthSearch, WidthStatus, refine_widths};
use aras_pipeline::prepare::{Prepared, RegressorColumns, prepare};
use aras_pipeline::robot::{FilterMode, base_parameters, keep_rows};
use aras_signal::{Bandwidth, FilterSpec, PeriodSource, ProcessOptions};

/// The simulator's friction smoothing (rad/s): the truth of the widths.
const TRUE_W: f64 = 0.03;

struct Run {
    prepared: Prepared,
    clean: Vec<[f64; 2]>,
    log: aras_log::Log,
}

/// `duration_s` of the committed default excitation, simulated with the
/// default sensors and `seed`, written and read back, processed with a
/// 10 Hz zero-phase filter on torques and columns alike.
fn run(seed: u64, duration_s: f64) -> Run {
    let truth = Params::aras_diamond();
    let model = truth.model().unwrap();
    let geometry = truth.geometry().unwrap();
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/trajectories/default-excitation.json");
    let traj = FourierTrajectory::load(&path).unwrap();
    let cfg = SimConfig {
        duration_s,
        seed,
        ..SimConfig::default()
    };
    assert_eq!(cfg.friction_smoothing, TRUE_W);
    let sim = simulate(&truth, &traj, &cfg).unwrap();
    let dir = aras_testkit::Scratch::new(&format!("width-{seed}"));
    let file = dir.join("log.csv");
    write_log(&file, &sim, true).unwrap();
    let log = read_log(&file, &ReadOptions::default()).unwrap();
    let opts = ProcessOptions {
        filter: Bandwidth::Fixed(FilterSpec {
            order: 4,
            cutoff_hz: 10.0,
        }),
        period: PeriodSource::Off,
        ..ProcessOptions::default()
    };
    let prepared = prepare(
        &log,
        &opts,
        &model,
        &geometry,
        FilterMode::Parallel,
        RegressorColumns::Standard,
        true,
    )
    .unwrap();
    Run {
        prepared,
        clean: sim.tau_clean,
        log,
    }
}

/// Refines the widths; returns them and the all-row fitness per joint of
/// the OLS fit with them against the raw torques, and the noise ceiling
/// (the truth's noise-free torques against the same rows).
fn refine_and_fit(r: &mut Run) -> (WidthRefinement, [f64; 2], [f64; 2]) {
    let truth = Params::aras_diamond();
    let model = truth.model().unwrap();
    let geometry = truth.geometry().unwrap();
    let base = base_parameters(&model, &geometry, &Workspace::paper(), 400).unwrap();
    let refinement = refine_widths(
        &mut r.prepared,
        &model,
        &base,
        FilterMode::Parallel,
        &WidthSearch::default(),
    )
    .unwrap();
    let p = &r.prepared;
    let all = vec![true; 2 * p.n()];
    let fit = keep_rows(&p.stacked, &all).unwrap();
    let wb = base.base_regressor(fit.w.as_ref()).unwrap();
    let ols = ReducedLs::new(wb.as_ref(), &fit.t, &base.base_names())
        .unwrap()
        .ols()
        .unwrap();
    let raw = base
        .base_regressor(p.unfiltered.as_ref().unwrap().w.as_ref())
        .unwrap();
    let pred = predict(raw.as_ref(), &ols.estimate).unwrap();
    let n = p.n();
    let mut ours = [0.0; 2];
    let mut ceiling = [0.0; 2];
    for j in 0..2 {
        let rows: Vec<usize> = (0..r.log.len())
            .filter(|&row| p.processed.sample_of_row(row).is_some())
            .collect();
        let measured: Vec<f64> = rows.iter().map(|&row| r.log.tau[j][row]).collect();
        let predicted: Vec<f64> = rows
            .iter()
            .map(|&row| pred[j * n + p.processed.sample_of_row(row).unwrap()])
            .collect();
        let clean: Vec<f64> = rows.iter().map(|&row| r.clean[row][j]).collect();
        ours[j] = fitness(&measured, &predicted).unwrap();
        ceiling[j] = fitness(&measured, &clean).unwrap();
    }
    (refinement, ours, ceiling)
}

/// One 10 s period: both widths refined on every row, within 3σ of the
/// simulator's 0.03 rad/s, σ informative (below a third of the width).
#[test]
fn width_is_recovered_on_every_row() {
    let mut r = run(7, 10.0);
    let (refinement, ours, ceiling) = refine_and_fit(&mut r);
    for (j, x) in refinement.joints.iter().enumerate() {
        assert_eq!(x.status, WidthStatus::Refined, "joint {}: {x:?}", j + 1);
        assert!(x.all_rows);
        assert!(
            x.std_dev > 0.0 && x.std_dev < x.w / 3.0,
            "joint {}: {x:?}",
            j + 1
        );
        assert!(
            (x.w - TRUE_W).abs() <= 3.0 * x.std_dev,
            "joint {}: w = {} ± {}",
            j + 1,
            x.w,
            x.std_dev
        );
    }
    assert!(refinement.fallback.is_empty());
    // The all-row fitness rises with the widths but stays short of the
    // ceiling (joint 1 94.9 against 98.6 % on this log): see
    // `all_row_fitness_reaches_the_ceiling`.
    assert!(
        ours[0] > 90.0 && ours[1] > 90.0,
        "{ours:?} (ceiling {ceiling:?})"
    );
}

/// The all-row fitness within 1 point of the noise ceiling per joint. Not
/// met: on this log joint 1 reaches 94.9 % against a ceiling of 98.6 %
/// (the default pipeline: 97.0 / 94.9 against 98.6 / 99.0 %); the rest of
/// the gap near reversals is not the Coulomb law's width.
#[test]
#[ignore = "open: the all-row fitness stays 1.6–4 points below the ceiling"]
fn all_row_fitness_reaches_the_ceiling() {
    let mut r = run(7, 10.0);
    let (_, ours, ceiling) = refine_and_fit(&mut r);
    for j in 0..2 {
        assert!(
            ours[j] >= ceiling[j] - 1.0,
            "joint {}: fitness {} vs ceiling {}",
            j + 1,
            ours[j],
            ceiling[j]
        );
    }
}

/// σ is honest: over seeds, the standardised errors `(w − 0.03) / σ` have
/// an RMS near 1 (below 2; a σ far too small would give several). Slow
/// (`--ignored`): 8 simulations.
#[test]
#[ignore]
fn width_sigma_is_honest_over_seeds() {
    let mut z = Vec::new();
    for seed in 1..=8 {
        let mut r = run(seed, 10.0);
        let (refinement, _, _) = refine_and_fit(&mut r);
        for x in refinement.joints {
            assert_eq!(x.status, WidthStatus::Refined);
            z.push((x.w - TRUE_W) / x.std_dev);
        }
    }
    let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
    eprintln!("standardised errors {z:?}, rms {rms}");
    assert!(rms < 2.0, "rms {rms}: {z:?}");
}

/// A joint whose friction has an internal state (LuGre: bristle presliding
/// over `Fc/σ0 = 5e-4 rad`, a Stribeck hump `Fs = 1.3 Fc` at 0.03 rad/s,
/// simulated as a state) sticks at its reversals, where no width of
/// `Fc tanh(θ̇/w)` follows it. Fitting every row there trades the moving
/// rows for the reversals: the check measures that cost and both joints
/// fall back to the rows away from their reversals, whose fit is far
/// closer to the truth. The same check on the simulator's own `tanh`
/// friction costs next to nothing and keeps every row. Default route
/// (`bandwidth = "auto"`, two periods averaged, every row).
#[test]
fn a_sticking_joint_falls_back_to_the_rows_away_from_reversals() {
    use aras_dyn::sim::LuGre;
    use aras_pipeline::identify::{IdentifySettings, friction_widths, identify};
    let truth = Params::aras_diamond();
    let model = truth.model().unwrap();
    let geometry = truth.geometry().unwrap();
    let fc = truth.friction.coulomb;
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/trajectories/default-excitation.json");
    let traj = FourierTrajectory::load(&path).unwrap();
    let base = base_parameters(&model, &geometry, &Workspace::paper(), 400).unwrap();
    let beta_true = base
        .to_base(truth.standard_vector(&model).unwrap().as_slice())
        .unwrap();
    let dir = aras_testkit::Scratch::new("width-lugre");
    let prepared_log = |tag: &str, lugre: Option<LuGre>, model: &aras_dyn::Model| {
        let cfg = SimConfig {
            duration_s: 2.0 * traj.period(),
            substeps: 4,
            lugre,
            ..SimConfig::default()
        };
        let file = dir.join(format!("{tag}.csv"));
        write_log(&file, &simulate(&truth, &traj, &cfg).unwrap(), true).unwrap();
        let log = read_log(&file, &ReadOptions::default()).unwrap();
        prepare(
            &log,
            &ProcessOptions::default(),
            model,
            &geometry,
            FilterMode::Parallel,
            RegressorColumns::Standard,
            true,
        )
        .unwrap()
    };
    // Relative error of the base parameters, ‖β̂ − β‖ / ‖β‖.
    let error = |settings: &IdentifySettings, p: &mut Prepared| {
        let (m, refinement, keep) = friction_widths(p, &base, &model, settings).unwrap();
        let id = identify(p, &base, &m, &truth, settings, &keep).unwrap();
        let e: f64 = id
            .ols
            .estimate
            .iter()
            .zip(&beta_true)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        let norm = beta_true.iter().map(|b| b * b).sum::<f64>().sqrt();
        (refinement, e / norm)
    };
    let settings = IdentifySettings::default();
    let mut control = prepared_log("control", None, &model);
    let (r, _) = error(&settings, &mut control);
    for (j, x) in r.joints.iter().enumerate() {
        eprintln!("control joint {}: {x:?}", j + 1);
        assert_eq!(x.status, WidthStatus::Refined, "joint {}: {x:?}", j + 1);
        assert!(x.all_rows && x.moving_rows_cost < 0.05, "{x:?}");
    }
    let lugre = LuGre {
        static_level: [1.3 * fc[0], 1.3 * fc[1]],
        stribeck_velocity: [0.03; 2],
        stiffness: [fc[0] / 5e-4, fc[1] / 5e-4],
        damping: [0.2, 0.4],
    };
    let mut sticking = prepared_log("lugre", Some(lugre), &model);
    let (r, checked) = error(&settings, &mut sticking.clone());
    let mut every = settings.clone();
    every.width.max_moving_rows_cost = 1e9;
    let (r_every, unchecked) = error(&every, &mut sticking);
    eprintln!("LuGre: {r:?}\nparameter error {checked:.4} checked, {unchecked:.4} on every row");
    for (j, x) in r.joints.iter().enumerate() {
        assert_eq!(
            x.status,
            WidthStatus::ReversalsNotDescribed,
            "joint {}: {x:?}",
            j + 1
        );
        assert!(!x.all_rows && x.moving_rows_cost > 2.0, "{x:?}");
        assert!(r_every.joints[j].all_rows);
    }
    assert_eq!(r.fallback.len(), 2, "{:?}", r.fallback);
    // Measured 0.058 against 2.12 (b1 0.013 ± 0.008 against 0.20 ± 0.52,
    // truth 0.0085): the every-row fit is unusable.
    assert!(
        checked < 0.1 && checked < unchecked / 10.0,
        "relative base-parameter error {checked} (fallback) vs {unchecked} (every row)"
    );
    // With the bristle in the model (`presliding_friction` at the
    // simulated displacement) the reversals are described: every row is
    // fitted again.
    let bristle = model
        .with_effect(aras_dyn::Effect::PreslidingFriction { displacement: 5e-4 })
        .unwrap();
    let base_b = base_parameters(&bristle, &geometry, &Workspace::paper(), 400).unwrap();
    let mut p = prepared_log("lugre-bristle", Some(lugre), &bristle);
    let (_, r, _) = friction_widths(&mut p, &base_b, &bristle, &settings).unwrap();
    eprintln!("LuGre, bristle in the model: {r:?}");
    for (j, x) in r.joints.iter().enumerate() {
        assert!(
            x.all_rows && x.moving_rows_cost < 1.0,
            "joint {}: {x:?}",
            j + 1
        );
    }
}
