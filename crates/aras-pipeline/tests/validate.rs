//! Validation (`aras_pipeline::validate`): the cross-validation of the true
//! parameters on a simulated log of (79) against its noise ceiling and
//! processing loss, scoring a log without its noise-free torques, the
//! workspace checks, and the `[validation]` settings' defaults; the
//! prediction of the same log (`aras_pipeline::predict`).

use aras_dyn::Params;
use aras_dyn::sim::SimConfig;
use aras_ident::validate::PdRegion;
use aras_pipeline::predict::{Route, predict_log};
use aras_pipeline::robot::DEFAULT_MIN_SPEED;
use aras_pipeline::validate::{
    ScoredModel, ValidationSettings, cross_validate, min_eigen_grid, parameter_errors, pd_check,
    pseudo_inertia_min, score_log,
};
use aras_signal::{Bandwidth, ProcessOptions};

/// The true parameters scored on their own simulated log: the files are
/// written and read back, the seed is `base_seed + 1000 + i`, the noise
/// ceiling is known, the logged-derivative route matches it (the truth is
/// a perfect model), the angles-only fitness is below it by the processing
/// loss, and scoring the read-back log again without the noise-free torques
/// gives the same figures and no ceiling.
#[test]
fn truth_scores_at_its_noise_ceiling_less_the_processing_loss() {
    let dir = aras_testkit::Scratch::new("validate-xv");
    let truth = Params::aras_diamond();
    // The simulated robot's model: its Coulomb friction is smoothed with
    // `tanh(θ̇ / w)`, w = the simulator's friction smoothing.
    let mut perfect = truth.clone();
    perfect.friction.width = [SimConfig::default().friction_smoothing; 2];
    let model = perfect.model().unwrap();
    let geometry = perfect.geometry().unwrap();
    let beta = perfect.standard_vector(&model).unwrap().as_slice().to_vec();
    let settings = ValidationSettings {
        frequencies_hz: vec![1.0],
        periods: 4,
        ..ValidationSettings::default()
    };
    let seeds = std::cell::RefCell::new(Vec::new());
    let sim = |duration_s: f64, seed: u64| {
        seeds.borrow_mut().push((duration_s, seed));
        SimConfig {
            duration_s,
            seed,
            ..SimConfig::default()
        }
    };
    let mut done = Vec::new();
    let scored = ScoredModel {
        geometry: &geometry,
        model: &model,
    };
    // The data-chosen bandwidth (the `aras` default): a harmonic series in
    // the sidecar's period.
    let process = ProcessOptions {
        filter: Bandwidth::Auto,
        ..ProcessOptions::default()
    };
    let xv = cross_validate(
        &truth,
        &sim,
        &settings,
        7,
        &process,
        scored,
        std::slice::from_ref(&beta),
        DEFAULT_MIN_SPEED,
        dir.path(),
        &mut |k| done.push(k),
    )
    .unwrap();
    assert_eq!(seeds.into_inner(), [(4.0, 1007)]);
    assert_eq!(done, [1]);
    assert!(dir.path().join("xv_1hz.csv").is_file());
    assert_eq!(xv.len(), 1);
    let x = &xv[0];
    assert_eq!(x.frequency_hz, 1.0);
    let ceiling = x.ceiling.expect("a simulated log has its noise ceiling");
    let loss = x.processing_loss[0];
    for j in 0..2 {
        let (fit, c) = (x.fitness[0][j], ceiling.all[j]);
        eprintln!(
            "τ{}: fitness {fit:.3} ceiling {c:.3} kept {:.3} / {:.3} loss {:.3} logged {:.3}",
            j + 1,
            x.fitness_kept[0][j],
            ceiling.kept[j],
            loss.loss[j],
            loss.fitness_logged[j]
        );
        assert!(c > 90.0 && c < 100.0, "τ{}: ceiling {c}", j + 1);
        assert!(fit <= c + 0.01, "τ{}: {fit} above the ceiling {c}", j + 1);
        assert!(
            (loss.fitness_logged[j] - c).abs() <= 0.01,
            "τ{}: the exact derivatives score {} against the ceiling {c}",
            j + 1,
            loss.fitness_logged[j]
        );
        assert_eq!(loss.fitness_angles[j], fit);
        assert!(loss.loss[j] > 0.0, "τ{}: loss {}", j + 1, loss.loss[j]);
    }
    let n = x.traces.t.len();
    assert!(n > 0 && x.traces.measured.len() == 2 * n);
    assert_eq!(x.traces.predicted[0].len(), 2 * n);

    let read = aras_log::read_log(
        &dir.path().join("xv_1hz.csv"),
        &aras_log::ReadOptions::default(),
    )
    .unwrap();
    let again = score_log(
        &read,
        None,
        &process,
        scored,
        &[beta],
        DEFAULT_MIN_SPEED,
        1.0,
    )
    .unwrap();
    assert!(again.ceiling.is_none());
    assert_eq!(again.fitness, x.fitness);
    assert_eq!(again.fitness_kept, x.fitness_kept);
    assert_eq!(again.processing_loss, x.processing_loss);

    // `predict` on the same log: the logged derivatives (the simulator
    // writes them), every row scored at the noise ceiling, and the same
    // processing loss; without the derivative columns, the angles' route
    // with the cross-validation's fitness and no loss.
    let p = predict_log(&read, &perfect, &process).unwrap();
    assert_eq!(p.route, Route::LoggedDerivatives);
    assert_eq!(p.processed.samples.len(), read.len());
    let l = p
        .processing_loss
        .expect("a log with derivatives has a loss");
    assert!(p.loss_unavailable.is_none());
    for j in 0..2 {
        assert!(
            (p.fitness[j] - ceiling.all[j]).abs() <= 0.01,
            "τ{}: {} against the ceiling {}",
            j + 1,
            p.fitness[j],
            ceiling.all[j]
        );
        assert!((l.loss[j] - loss.loss[j]).abs() < 1e-9, "{l:?} vs {loss:?}");
    }
    let mut plain = read.clone();
    plain.theta_dot = None;
    plain.theta_ddot = None;
    let p = predict_log(&plain, &perfect, &process).unwrap();
    assert_eq!(p.route, Route::Angles);
    assert!(p.processing_loss.is_none() && p.loss_unavailable.is_none());
    for j in 0..2 {
        assert!(
            (p.fitness[j] - x.fitness[0][j]).abs() < 1e-9,
            "τ{}: {} vs {}",
            j + 1,
            p.fitness[j],
            x.fitness[0][j]
        );
    }
}

/// The nominal robot's mass matrix is positive definite over the paper's
/// workspace, on the check's points and on the heat map's cells; its links
/// are physically consistent; its parameters have no error against
/// themselves.
#[test]
fn workspace_checks_of_the_nominal_robot() {
    let p = Params::aras_diamond();
    let ws = aras_kin::Workspace::paper();
    let (lower, upper) = ([ws.min()[0], ws.min()[1]], [ws.max()[0], ws.max()[1]]);
    let region = PdRegion {
        lower,
        upper,
        grid_per_axis: 11,
        random: 200,
        seed: 3,
    };
    let pd = pd_check(&p, &region).unwrap();
    assert_eq!(pd.points, 11 * 11 + 200);
    assert!(pd.positive_definite && pd.failures == 0 && pd.non_positive == 0);
    assert!(pd.min_eigenvalue > 0.0 && pd.min_eigenvalue <= pd.max_eigenvalue);
    for k in 0..2 {
        let (lo, hi) = (lower[k].to_degrees(), upper[k].to_degrees());
        assert!((lo..=hi).contains(&pd.argmin_deg[k]), "{pd:?}");
    }

    let (phi, gamma, values) = min_eigen_grid(&p, lower, upper, [5, 4]).unwrap();
    assert_eq!((phi.len(), gamma.len(), values.len()), (5, 4, 5));
    assert!(values.iter().all(|c| c.len() == 4));
    assert!(
        values
            .iter()
            .flatten()
            .all(|v| *v >= pd.min_eigenvalue * 0.999)
    );
    assert!(phi.windows(2).all(|w| w[0] < w[1]));

    assert!(pseudo_inertia_min(&p).iter().all(|v| *v > 0.0));

    let model = p.model().unwrap();
    let geometry = p.geometry().unwrap();
    let ws_states = aras_kin::Workspace::paper();
    let base = aras_pipeline::robot::base_parameters(&model, &geometry, &ws_states, 200).unwrap();
    let beta = p.standard_vector(&model).unwrap().as_slice().to_vec();
    let b = base.to_base(&beta).unwrap();
    let e = parameter_errors(&base, &b, &vec![1.0; b.len()], &beta).unwrap();
    assert_eq!(e.entries.len(), base.n_base());
    assert!(
        e.max_relative_percent < 1e-9 && e.rms_in_sigma < 1e-9,
        "{e:?}"
    );
}

/// `[validation]` reads an empty section as the defaults and refuses an
/// unknown key.
#[test]
fn settings_default_and_strictness() {
    let d: ValidationSettings = serde_json::from_str("{}").unwrap();
    assert_eq!(d, ValidationSettings::default());
    assert_eq!(d.frequencies_hz, [0.5, 0.7, 1.8, 2.5]);
    assert_eq!(
        d.reversal_reach,
        aras_pipeline::robot::DEFAULT_VALIDATION_REACH
    );
    let e = serde_json::from_str::<ValidationSettings>(r#"{"periods": 4, "perods": 5}"#);
    assert!(e.is_err());
    let p: ValidationSettings = serde_json::from_str(r#"{"periods": 4}"#).unwrap();
    assert_eq!(p.periods, 4);
    assert_eq!(p.pd_grid, d.pd_grid);
}
