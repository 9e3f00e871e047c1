//! Validation (`docs/validation.md`): cross-validation on the trajectories (79),
//! positive definiteness of the mass matrix (80) over the workspace, the
//! links' pseudo-inertia eigenvalues, and parameter errors against a known
//! truth.

use std::path::Path;

use anyhow::{Context, Result};
use aras_dyn::{Dynamics, Model, Params, Sinusoid};
use aras_ident::BaseParameters;
use aras_ident::validate::{PdRegion, check_positive_definite};
use aras_log::{ReadOptions, read_log};
use aras_pipeline::robot::{Stacked, keep_rows, reversal_mask, stack};
use aras_signal::OutputRows;
use nalgebra::Vector2;
use serde::Serialize;

use crate::config::Config;
use crate::identify::{Prepared, fitness_per_joint, process_options};
use crate::simulate;

/// Fitness of each candidate on one cross-validation trajectory.
#[derive(Debug, Clone, Serialize)]
pub struct CrossValidation {
    /// Frequency of (79) (Hz).
    pub frequency_hz: f64,
    /// Fitness (78) per joint for each candidate, in the order given,
    /// against the log's raw torques on every row.
    pub fitness: Vec<[f64; 2]>,
    /// The same on the rows away from velocity reversals
    /// (`identification.min_speed`, `validation.reversal_reach`).
    pub fitness_kept: Vec<[f64; 2]>,
    /// Noise ceiling (78) per joint: the true robot's noise-free torques
    /// against the same log (`crate::ceiling`).
    pub ceiling: crate::ceiling::Ceiling,
    /// Processing loss of each candidate (`crate::loss`): its fitness with
    /// the simulator's exact θ̇, θ̈ minus its fitness from the angles
    /// alone (the `fitness` above), on the rows both cover.
    pub processing_loss: Vec<crate::loss::ProcessingLoss>,
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
pub fn predict_standard(prep: &Prepared, beta: &[f64]) -> Result<Vec<f64>> {
    Ok(aras_ident::validate::predict(prep.w_ref(), beta)?)
}

/// Fitness (78) per joint of a standard parameter vector on the rows of `st`.
fn fitness_standard(st: &Stacked, beta: &[f64]) -> Result<[f64; 2]> {
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

/// Simulates the truth robot along (79) at each configured frequency with
/// the same sensors and noise as the excitation run, writes each log into
/// `dir` (`xv_<f>hz.csv` + sidecar), reads it back and processes it exactly
/// like the identification data, and scores each candidate parameter vector
/// (standard parameters of `scored.model`).
pub fn cross_validate(
    truth: &Params,
    nominal: &Params,
    scored: ScoredModel,
    candidates: &[Vec<f64>],
    cfg: &Config,
    dir: &Path,
    progress: &indicatif::ProgressBar,
) -> Result<Vec<CrossValidation>> {
    let ScoredModel { geometry, model } = scored;
    let mut out = Vec::new();
    for (i, &f) in cfg.validation.frequencies_hz.iter().enumerate() {
        let traj = Sinusoid::paper_79(f)?;
        let duration = cfg.validation.periods as f64 / f;
        let seed = cfg.simulation.seed.wrapping_add(1000 + i as u64);
        let sim = simulate::sim_config(cfg, nominal, duration, seed);
        let log = aras_dyn::sim::simulate(truth, &traj, &sim).with_context(|| {
            format!("simulating the cross-validation trajectory (79) at {f} Hz")
        })?;
        let path = dir.join(format!("xv_{f}hz.csv"));
        aras_dyn::sim::write_log(&path, &log, true)?;
        let read = read_log(&path, &ReadOptions::default())?;
        // θ, θ̇, θ̈ on every row with the data-chosen bandwidth (a harmonic
        // series in the sidecar's period), the prediction from the
        // unfiltered regressor, compared with the raw torques (78).
        let mut opts = process_options(cfg, None, false);
        opts.rows = OutputRows::EveryRow;
        let processed = aras_signal::process(&read, &opts, &aras_kin::task_motion(geometry))
            .with_context(|| format!("processing {}", path.display()))?;
        let stacked = stack(model, geometry, &processed.samples)?;
        let prep = Prepared {
            processed,
            stacked,
            filter: None,
            unfiltered: None,
        };
        let keep = reversal_mask(
            &prep.processed.samples.theta_dot,
            cfg.identification.min_speed,
            0,
            false,
        )?;
        let kept = keep_rows(&prep.stacked, &keep)?;
        // The same log with the simulator's exact derivatives, for the
        // processing loss.
        let exact_opts = process_options(cfg, None, true);
        let exact = if crate::loss::has_derivatives(&read) {
            let mut o = exact_opts.clone();
            o.rows = OutputRows::EveryRow;
            let p = aras_signal::process(&read, &o, &aras_kin::task_motion(geometry))
                .with_context(|| format!("processing {} with its derivatives", path.display()))?;
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
                prep.processed.band_limit().apply(g)?;
            }
            fitness.push(fitness_per_joint(prep.t(), &p)?);
            if let Some((ep, ew)) = &exact {
                let pe = aras_ident::validate::predict(ew.w.as_ref(), beta)?;
                processing_loss.push(crate::loss::loss_between(ep, &pe, &prep.processed, &p)?);
            }
            fitness_kept.push(fitness_standard(&kept, beta)?);
            predicted.push(pick(&p));
        }
        let ceiling =
            crate::ceiling::noise_ceiling(&read, &log.tau_clean, &prep, &opts, geometry, &keep)?;
        out.push(CrossValidation {
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
        });
        progress.inc(1);
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

fn workspace_box(cfg: &Config) -> ([f64; 2], [f64; 2]) {
    let t = &cfg.trajectory;
    (
        [t.min_deg[0].to_radians(), t.min_deg[1].to_radians()],
        [t.max_deg[0].to_radians(), t.max_deg[1].to_radians()],
    )
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

/// Mass-matrix (80) eigenvalues over the workspace box (77): grid plus
/// random points, in parallel.
pub fn pd_check(params: &Params, cfg: &Config) -> Result<PdSummary> {
    let dy = Dynamics::new(params)?;
    let (lo, hi) = workspace_box(cfg);
    let v = &cfg.validation;
    let region = PdRegion {
        lower: lo,
        upper: hi,
        grid_per_axis: v.pd_grid,
        random: v.pd_random,
        seed: v.pd_seed,
    };
    let r = check_positive_definite(|x| mass_motor(&dy, x), &region);
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

/// The smallest mass-matrix eigenvalue on a `[φ, γ]` grid over the
/// workspace: `(φ_deg, γ_deg, values[i][j])` for the heat map.
pub fn min_eigen_grid(params: &Params, cfg: &Config) -> Result<EigenGrid> {
    let dy = Dynamics::new(params)?;
    let (lo, hi) = workspace_box(cfg);
    let [nx, ny] = cfg.validation.heatmap;
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
            let m = mass_motor(&dy, &[p, g])?;
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
) -> Result<ErrorSummary> {
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
