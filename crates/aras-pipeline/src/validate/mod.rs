//! Validation (`docs/validation.md`): cross-validation on the trajectories
//! (79) of the simulated robot, with the noise ceiling ([`ceiling`]) and the
//! processing loss ([`loss`]) of each log; positive definiteness of the
//! mass matrix (80) over the workspace; the links' pseudo-inertia
//! eigenvalues; and parameter errors against a known truth. The settings
//! are one serialisable struct with its defaults ([`ValidationSettings`]),
//! which the `aras` configuration's `[validation]` section is.

pub mod ceiling;
pub mod loss;

use crate::PipelineError;
use std::path::Path;

use aras_dyn::sim::SimConfig;
use aras_dyn::{Dynamics, Model, Params, Sinusoid};
use aras_ident::validate::{PdRegion, check_positive_definite};
use aras_ident::{BaseParameters, IdentError};
use aras_log::{Log, ReadOptions, read_log};
use aras_signal::{OutputRows, ProcessOptions};
use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::identify::fitness_per_joint;
use crate::prepare::Prepared;
use crate::robot::{Stacked, keep_rows, reversal_mask, stack};
use ceiling::{Ceiling, noise_ceiling};
use loss::{ProcessingLoss, has_derivatives, loss_between};

/// Settings of validation. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ValidationSettings {
    /// Frequencies of the cross-validation trajectories (79) (Hz).
    pub frequencies_hz: Vec<f64>,
    /// Periods simulated per cross-validation trajectory.
    pub periods: usize,
    /// Grid points per axis of the workspace PD check.
    pub pd_grid: usize,
    /// Additional random points of the PD check.
    pub pd_random: usize,
    /// Seed of the PD check's random points.
    pub pd_seed: u64,
    /// Heat-map resolution `[φ, γ]` (cells).
    pub heatmap: [usize; 2],
    /// Reach of the reversal exclusion on the validation logs of
    /// `aras diagnose` (fraction of the filter's peak; only its main lobe
    /// by default, since at 2.5 Hz the joints reverse every 0.2 s). The
    /// cross-validation here stacks its logs unfiltered, so its kept rows
    /// are not widened.
    pub reversal_reach: f64,
}

impl Default for ValidationSettings {
    fn default() -> Self {
        Self {
            frequencies_hz: vec![0.5, 0.7, 1.8, 2.5],
            periods: 16,
            pd_grid: 101,
            pd_random: 100_000,
            pd_seed: 0,
            heatmap: [56, 41],
            reversal_reach: crate::robot::DEFAULT_VALIDATION_REACH,
        }
    }
}

/// Fitness of each candidate on one cross-validation trajectory.
#[derive(Debug, Clone, Serialize)]
pub struct CrossValidation {
    /// Frequency of (79) (Hz).
    pub frequency_hz: f64,
    /// Fitness (78) per joint for each candidate, in the order given,
    /// against the log's raw torques on every row.
    pub fitness: Vec<[f64; 2]>,
    /// The same on the rows away from velocity reversals (`|θ̇_j|` at
    /// least `min_speed`, not widened).
    pub fitness_kept: Vec<[f64; 2]>,
    /// Noise ceiling (78) per joint: the true robot's noise-free torques
    /// against the same log ([`ceiling`]); `None` when they are not known.
    pub ceiling: Option<Ceiling>,
    /// Processing loss of each candidate ([`loss`]): its fitness with the
    /// log's exact θ̇, θ̈ minus its fitness from the angles alone (the
    /// `fitness` above), on the rows both cover; empty for a log without
    /// derivative columns.
    pub processing_loss: Vec<ProcessingLoss>,
    /// Time, raw measured and predicted torques of the first two periods,
    /// for plots.
    #[serde(skip)]
    pub traces: Traces,
}

/// Torque traces of one dataset.
#[derive(Debug, Clone, Default)]
pub struct Traces {
    /// Time (s).
    pub t: Vec<f64>,
    /// Measured stacked torques.
    pub measured: Vec<f64>,
    /// Predicted stacked torques, per candidate.
    pub predicted: Vec<Vec<f64>>,
}

/// `W β` for a standard parameter vector.
pub fn predict_standard(prep: &Prepared, beta: &[f64]) -> Result<Vec<f64>, PipelineError> {
    aras_ident::validate::predict(prep.w_ref(), beta).map_err(PipelineError::from)
}

/// Fitness (78) per joint of a standard parameter vector on the rows of `st`.
fn fitness_standard(st: &Stacked, beta: &[f64]) -> Result<[f64; 2], PipelineError> {
    let p = aras_ident::validate::predict(st.w.as_ref(), beta)?;
    let f = aras_ident::validate::fitness_per_group(&st.t, &p, &st.groups)?;
    Ok([f[0], f[1]])
}

/// The model a cross-validation scores: its kinematics (X from the logged
/// angles) and its regressor (effects and gravity).
#[derive(Debug, Clone, Copy)]
pub struct ScoredModel<'a> {
    /// The model's geometry.
    pub geometry: &'a aras_kin::Geometry,
    /// The model's effects and gravity.
    pub model: &'a Model,
}

/// Scores each candidate parameter vector (standard parameters of
/// `scored.model`) on one log of the trajectory (79) at `frequency_hz`.
///
/// The log is processed on every row with `process` (its `rows` and
/// `use_logged_derivatives` are set here: θ, θ̇, θ̈ from the angles with the
/// data-chosen bandwidth), the prediction from the unfiltered regressor is
/// band-limited as the angles were and compared with the raw torques (78),
/// on every row and on the rows away from velocity reversals
/// (`|θ̇_j| ≥ min_speed`). A log with exact derivative columns also gets
/// each candidate's processing loss ([`loss`]); `clean`, the noise-free
/// torques of a simulated log (one per row), gives the noise ceiling
/// ([`ceiling`]). The traces hold the first two periods.
pub fn score_log(
    log: &Log,
    clean: Option<&[[f64; 2]]>,
    process: &ProcessOptions,
    scored: ScoredModel,
    candidates: &[Vec<f64>],
    min_speed: f64,
    frequency_hz: f64,
) -> Result<CrossValidation, PipelineError> {
    let ScoredModel { geometry, model } = scored;
    let f = frequency_hz;
    let task = aras_kin::task_motion(geometry);
    // θ, θ̇, θ̈ on every row with the data-chosen bandwidth (a harmonic
    // series in the sidecar's period), the prediction from the unfiltered
    // regressor, compared with the raw torques (78).
    let mut opts = process.clone();
    opts.rows = OutputRows::EveryRow;
    opts.use_logged_derivatives = false;
    let processed = aras_signal::process(log, &opts, &task)
        .map_err(|e| IdentError::external(format!("processing {}", log.name), e))?;
    let stacked = stack(model, geometry, &processed.samples)?;
    let prep = Prepared {
        processed,
        stacked,
        filter: None,
        unfiltered: None,
    };
    let keep = reversal_mask(&prep.processed.samples.theta_dot, min_speed, 0, false)?;
    let kept = keep_rows(&prep.stacked, &keep)?;
    // The same log with its exact derivatives, for the processing loss.
    let exact = if has_derivatives(log) {
        let mut o = opts.clone();
        o.use_logged_derivatives = true;
        let p = aras_signal::process(log, &o, &task).map_err(|e| {
            IdentError::external(format!("processing {} with its derivatives", log.name), e)
        })?;
        let w = stack(model, geometry, &p.samples)?;
        Some((p, w))
    } else {
        None
    };
    let mut processing_loss = Vec::new();
    let mut fitness = Vec::new();
    let mut fitness_kept = Vec::new();
    let mut predicted = Vec::new();
    // Traces: the first two periods.
    let t0 = prep.processed.samples.t.first().copied().unwrap_or(0.0);
    let rows = prep
        .processed
        .samples
        .t
        .iter()
        .take_while(|t| **t - t0 <= 2.0 / f)
        .count();
    let n = prep.n();
    let pick =
        |v: &[f64]| -> Vec<f64> { v[..rows].iter().chain(&v[n..n + rows]).copied().collect() };
    for beta in candidates {
        // The prediction passes the processing's band-limiting, as the
        // angles did (`Processed::band_limit`).
        let mut p = predict_standard(&prep, beta)?;
        for g in p.chunks_mut(n) {
            prep.processed
                .band_limit()
                .apply(g)
                .map_err(|e| IdentError::external("band-limiting the prediction", e))?;
        }
        fitness.push(fitness_per_joint(prep.t(), &p)?);
        if let Some((ep, ew)) = &exact {
            let pe = aras_ident::validate::predict(ew.w.as_ref(), beta)?;
            processing_loss.push(loss_between(ep, &pe, &prep.processed, &p)?);
        }
        fitness_kept.push(fitness_standard(&kept, beta)?);
        predicted.push(pick(&p));
    }
    let ceiling = clean
        .map(|c| noise_ceiling(log, c, &prep, &opts, geometry, &keep))
        .transpose()?;
    Ok(CrossValidation {
        frequency_hz: f,
        fitness,
        fitness_kept,
        ceiling,
        processing_loss,
        traces: Traces {
            t: prep.processed.samples.t[..rows].to_vec(),
            measured: pick(prep.t()),
            predicted,
        },
    })
}

/// Simulates the `truth` robot along (79) at each of `settings`'
/// frequencies for `settings.periods` periods (`sim(duration_s, seed)`
/// gives the simulator's settings, the `i`-th log's seed is
/// `base_seed + 1000 + i`), writes each log with its exact derivatives into
/// `dir` (`xv_<f>hz.csv` + sidecar), reads it back and scores it with
/// [`score_log`] (the noise ceiling from the simulator's noise-free
/// torques). `progress` is told how many logs are done after each.
#[allow(clippy::too_many_arguments)]
pub fn cross_validate(
    truth: &Params,
    sim: &dyn Fn(f64, u64) -> SimConfig,
    settings: &ValidationSettings,
    base_seed: u64,
    process: &ProcessOptions,
    scored: ScoredModel,
    candidates: &[Vec<f64>],
    min_speed: f64,
    dir: &Path,
    progress: &mut dyn FnMut(usize),
) -> Result<Vec<CrossValidation>, PipelineError> {
    let mut out = Vec::new();
    for (i, &f) in settings.frequencies_hz.iter().enumerate() {
        let traj = Sinusoid::paper_79(f).map_err(|e| {
            IdentError::external(format!("the cross-validation trajectory (79) at {f} Hz"), e)
        })?;
        let duration = settings.periods as f64 / f;
        let seed = base_seed.wrapping_add(1000 + i as u64);
        let log = aras_dyn::sim::simulate(truth, &traj, &sim(duration, seed)).map_err(|e| {
            IdentError::external(
                format!("simulating the cross-validation trajectory (79) at {f} Hz"),
                e,
            )
        })?;
        let path = dir.join(format!("xv_{f}hz.csv"));
        aras_dyn::sim::write_log(&path, &log, true)
            .map_err(|e| IdentError::external(format!("writing {}", path.display()), e))?;
        let read = read_log(&path, &ReadOptions::default())
            .map_err(|e| IdentError::external(format!("reading {}", path.display()), e))?;
        out.push(score_log(
            &read,
            Some(&log.tau_clean),
            process,
            scored,
            candidates,
            min_speed,
            f,
        )?);
        progress(i + 1);
    }
    Ok(out)
}

/// The workspace PD check of one parameter set, in degrees for reports.
#[derive(Debug, Clone, Serialize)]
pub struct PdSummary {
    /// Points tested.
    pub points: usize,
    /// Smallest eigenvalue of the motor-space mass matrix (kg·m²).
    pub min_eigenvalue: f64,
    /// Where, `[φ, γ]` (deg).
    pub argmin_deg: [f64; 2],
    /// Largest eigenvalue (kg·m²).
    pub max_eigenvalue: f64,
    /// Where, `[φ, γ]` (deg).
    pub argmax_deg: [f64; 2],
    /// Points with a non-positive eigenvalue.
    pub non_positive: usize,
    /// Points that could not be evaluated.
    pub failures: usize,
    /// True when every point was positive definite.
    pub positive_definite: bool,
}

/// The dynamics of `params`, for the mass-matrix checks.
fn dynamics(params: &Params) -> Result<Dynamics, PipelineError> {
    Dynamics::new(params)
        .map_err(|e| IdentError::external("the parameters' dynamics", e))
        .map_err(PipelineError::from)
}

/// Motor-space mass matrix `J⁻ᵀ M J⁻¹` (80) at pose `x`.
fn mass_motor(dy: &Dynamics, x: &[f64; 2]) -> Result<[[f64; 2]; 2], aras_dyn::DynError> {
    let s = dy.sample(&aras_kin::Motion::new(
        Vector2::new(x[0], x[1]),
        Vector2::zeros(),
        Vector2::zeros(),
    ))?;
    let m = dy.mass_matrix_motor(&s);
    Ok([[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]])
}

/// Mass-matrix (80) eigenvalues over `region`, a box in `[φ, γ]` (rad, e.g.
/// the workspace (77)): its grid plus random points, in parallel.
pub fn pd_check(params: &Params, region: &PdRegion<2>) -> Result<PdSummary, PipelineError> {
    let dy = dynamics(params)?;
    let r = check_positive_definite(|x| mass_motor(&dy, x), region);
    let deg = |a: [f64; 2]| [a[0].to_degrees(), a[1].to_degrees()];
    Ok(PdSummary {
        points: r.points,
        min_eigenvalue: r.min_eigenvalue,
        argmin_deg: deg(r.argmin),
        max_eigenvalue: r.max_eigenvalue,
        argmax_deg: deg(r.argmax),
        non_positive: r.non_positive,
        failures: r.failures,
        positive_definite: r.positive_definite(),
    })
}

/// A heat-map grid: `φ` (deg), `γ` (deg) and `values[i][j]` at `(φ_i, γ_j)`.
pub type EigenGrid = (Vec<f64>, Vec<f64>, Vec<Vec<f64>>);

/// The smallest mass-matrix eigenvalue at the centres of `cells` (`[φ, γ]`)
/// equal cells of the box `lower`..`upper` (rad): `(φ_deg, γ_deg,
/// values[i][j])` for the heat map.
pub fn min_eigen_grid(
    params: &Params,
    lower: [f64; 2],
    upper: [f64; 2],
    cells: [usize; 2],
) -> Result<EigenGrid, PipelineError> {
    let dy = dynamics(params)?;
    let (lo, hi) = (lower, upper);
    let [nx, ny] = cells;
    let axis = |k: usize, n: usize| -> Vec<f64> {
        (0..n)
            .map(|i| lo[k] + (hi[k] - lo[k]) * (i as f64 + 0.5) / n as f64)
            .collect()
    };
    let (xs, ys) = (axis(0, nx), axis(1, ny));
    let mut values = Vec::with_capacity(nx);
    for &p in &xs {
        let mut col = Vec::with_capacity(ny);
        for &g in &ys {
            let m = mass_motor(&dy, &[p, g]).map_err(|e| {
                IdentError::external(
                    format!(
                        "the mass matrix at φ = {:.3}°, γ = {:.3}°",
                        p.to_degrees(),
                        g.to_degrees()
                    ),
                    e,
                )
            })?;
            col.push(aras_ident::symmetric_eigenvalues(&m)[0]);
        }
        values.push(col);
    }
    let deg = |v: Vec<f64>| v.into_iter().map(f64::to_degrees).collect();
    Ok((deg(xs), deg(ys), values))
}

/// The smallest eigenvalue of each link's pseudo-inertia `𝒥_k` (`docs/model.md`,
/// "Physical consistency"; positive ⇔ physically consistent), in kg·m².
pub fn pseudo_inertia_min(params: &Params) -> [f64; 4] {
    std::array::from_fn(|k| {
        let j = params.links[k].pseudo_inertia();
        let a: [[f64; 4]; 4] = std::array::from_fn(|r| std::array::from_fn(|c| j[(r, c)]));
        aras_ident::symmetric_eigenvalues(&a)[0]
    })
}

/// Errors of the base parameters against the truth.
#[derive(Debug, Clone, Serialize)]
pub struct ErrorSummary {
    /// Largest `|error| / |truth|` (%) over the base parameters with
    /// `|truth|` above 1e-6 of the largest.
    pub max_relative_percent: f64,
    /// RMS of `error / σ` (about 1 when the σ are honest and the model is right).
    pub rms_in_sigma: f64,
    /// Each base parameter.
    pub entries: Vec<aras_ident::validate::ParameterError>,
}

/// Base-parameter errors of `estimate` (with `sigma`) against `truth_std`
/// (the truth's standard parameters of the same model).
pub fn parameter_errors(
    base: &BaseParameters,
    estimate: &[f64],
    sigma: &[f64],
    truth_std: &[f64],
) -> Result<ErrorSummary, PipelineError> {
    let truth = base.to_base(truth_std)?;
    let names: Vec<String> = (0..base.n_base()).map(|i| base.expression(i)).collect();
    let entries = aras_ident::validate::parameter_errors(&names, estimate, sigma, &truth)?;
    let scale = truth.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let max_relative_percent = entries
        .iter()
        .filter(|e| e.truth.abs() > 1e-6 * scale)
        .map(|e| 100.0 * (e.error / e.truth).abs())
        .fold(0.0, f64::max);
    let finite: Vec<f64> = entries
        .iter()
        .map(|e| e.in_sigma)
        .filter(|v| v.is_finite())
        .collect();
    let rms_in_sigma =
        (finite.iter().map(|v| v * v).sum::<f64>() / finite.len().max(1) as f64).sqrt();
    Ok(ErrorSummary {
        max_relative_percent,
        rms_in_sigma,
        entries,
    })
}
