//! Identification (`docs/model.md`, `docs/processing.md`): a processed log → stacked regressor →
//! base parameters → OLS (62)–(66) → physically consistent SDP (67)–(73).
//!
//! The mathematics lives in `aras-signal` (processing), `aras-dyn`
//! (regressor) and `aras-ident` (base parameters, least squares, SDP); this
//! module wires them with the configured settings, the way
//! `crates/aras-pipeline/tests/acceptance.rs` does (`docs/validation.md`):
//! **parallel filtering** (`docs/processing.md`: the same zero-phase low-pass on the
//! torques and every regressor column, so a Coulomb jump is smeared
//! identically on both sides of `T = W β`), **reversal exclusion** (rows of
//! a joint near its velocity reversals, where (49)'s `sign(θ̇)` is wrong,
//! widened by the filter's reach) and **σ from the HAC covariance**
//! (`aras_ident::covariance`: correlated residuals, data-driven bandwidth).

use anyhow::{Context, Result, bail};
use aras_dyn::{Model, Params};
use aras_ident::validate::{fitness_per_group, predict};
use aras_ident::{
    BaseParameters, NoiseVariances, OlsEstimate, ReducedLs, SdpSettings, SdpSolution,
};
use aras_kin::{Geometry, Workspace};
use aras_log::Log;
use aras_pipeline::friction_width::{FitRows, WidthRefinement, apply_widths, refine_widths};
use aras_pipeline::prepare::RegressorColumns;
use aras_pipeline::robot::{self, Stacked, consistent_problem, keep_rows, params_from_solution};
use aras_signal::{
    Bandwidth, DerivativeMethod, FilterSpec, OutputRows, PeriodSource, ProcessOptions, Processed,
};
use nalgebra::Vector2;

use crate::config::{BandwidthMode, Config, DerivativeChoice, FilteringMode, Weighting};

/// Processing options from the configuration (`period` overrides the sidecar).
pub fn process_options(
    cfg: &Config,
    period: Option<f64>,
    logged_derivatives: bool,
) -> ProcessOptions {
    let s = &cfg.signal;
    ProcessOptions {
        filter: match s.bandwidth {
            BandwidthMode::Auto => Bandwidth::Auto,
            BandwidthMode::Fixed if s.cutoff_hz > 0.0 => Bandwidth::Fixed(FilterSpec {
                order: s.filter_order,
                cutoff_hz: s.cutoff_hz,
            }),
            BandwidthMode::Fixed => Bandwidth::Off,
        },
        period: period.map_or(PeriodSource::FromSidecar, PeriodSource::Seconds),
        settling_s: s.settling_s,
        max_period_spread: s.max_period_spread,
        derivative: match s.derivative {
            DerivativeChoice::Auto => DerivativeMethod::Auto,
            DerivativeChoice::CentralDifference => DerivativeMethod::CentralDifference,
            DerivativeChoice::Spectral => DerivativeMethod::Spectral,
            DerivativeChoice::SavitzkyGolay => DerivativeMethod::SavitzkyGolay {
                half_window: s.sg_half_window,
                poly_order: s.sg_poly_order,
            },
        },
        use_logged_derivatives: logged_derivatives,
        rows: OutputRows::Averaged,
    }
}

/// What the identification does with a log's logged derivative columns,
/// and why (`None` when the log has none): they are ignored, so that the
/// torques and the regressor, built from θ̇, θ̈ differentiated from the
/// angles, pass through the same zero-phase low-pass. `aras predict` uses
/// them, checked against the angles.
pub fn logged_derivatives_note(log: &Log) -> Option<String> {
    (log.theta_dot.is_some() || log.theta_ddot.is_some()).then(|| {
        "the logged dtheta/ddtheta columns are ignored: the identification differentiates the \
         angles so that the regressor and the torques pass through the same zero-phase \
         low-pass (`aras predict` uses logged derivatives, checked against the angles)"
            .to_string()
    })
}

/// Data ready for least squares (`aras_pipeline::prepare`).
pub use aras_pipeline::prepare::Prepared;

/// Processes a log and stacks the model's regressor on it, filtered as the
/// configured filtering mode says (`aras_pipeline::prepare`), keeping the
/// unfiltered regressor for predictions against the raw torques.
pub fn prepare(
    log: &Log,
    opts: &ProcessOptions,
    mode: FilteringMode,
    model: &Model,
    geometry: &Geometry,
) -> Result<Prepared> {
    let mode = mode.mode();
    let prepared = aras_pipeline::prepare::prepare(
        log,
        opts,
        model,
        geometry,
        mode,
        RegressorColumns::Standard,
        true,
    )
    .with_context(|| format!("regressor of {}", log.name))?;
    let n = prepared.n();
    if n < 2 * model.columns() {
        bail!(
            "{}: only {n} samples after processing, fewer than twice the {} parameters; \
             record a longer log",
            log.name,
            model.columns()
        );
    }
    Ok(prepared)
}

/// Base parameters (58)–(61) of `model` (`aras_pipeline::robot::base_parameters`)
/// on `identification.base_samples` quasi-random states filling the
/// workspace box and rate limits of `[trajectory]`.
pub fn base_parameters(model: &Model, geometry: &Geometry, cfg: &Config) -> Result<BaseParameters> {
    let workspace = workspace(cfg)?;
    robot::base_parameters(model, geometry, &workspace, cfg.identification.base_samples)
        .context("base parameters on workspace samples (is the box in trajectory.min_deg/max_deg reachable?)")
}

/// The box and rate limits of `[trajectory]`, where identification (and
/// the diagnosis) sample the states for the structural base parameters.
pub fn workspace(cfg: &Config) -> Result<Workspace> {
    let t = &cfg.trajectory;
    let d = |v: [f64; 2]| Vector2::new(v[0].to_radians(), v[1].to_radians());
    Workspace::new(d(t.min_deg), d(t.max_deg), d(t.max_rate_deg_s))
        .context("keys `trajectory.min_deg`, `max_deg`, `max_rate_deg_s`")
}

/// Everything identification produced.
pub struct Identification {
    /// Rows used in the fit per joint (the rest were near reversals).
    pub rows_fitted: [usize; 2],
    /// The identified model's parameter names (standard).
    pub names: Vec<String>,
    /// Base parameters.
    pub base: BaseParameters,
    /// OLS (or WLS) estimate of the base parameters; σ and covariance the
    /// HAC sandwich (`OlsEstimate::with_hac`) with every σ raised to at least
    /// `sigma_white` (`OlsEstimate::with_sigma_floor`).
    pub ols: OlsEstimate,
    /// σ of the HAC sandwich alone.
    pub sigma_hac: Vec<f64>,
    /// σ of the OLS (or WLS) estimate assuming white noise before the
    /// filter (`OlsEstimate::with_filtered_noise`), for comparison with the
    /// streaming route.
    pub sigma_white: Vec<f64>,
    /// The SDP solution.
    pub sdp: SdpSolution,
    /// OLS completed to standard parameters closest to the nominal robot.
    pub ols_params: Params,
    /// The physically consistent standard parameters.
    pub sdp_params: Params,
    /// Excitation data: predictions `W_b β_b` (OLS, SDP), stacked, all rows.
    pub predicted_ols: Vec<f64>,
    /// SDP predictions.
    pub predicted_sdp: Vec<f64>,
    /// Fitness (78) per joint, OLS, against the log's raw torques on every
    /// row (the paper's figure).
    pub fitness_ols: [f64; 2],
    /// Fitness (78) per joint, SDP, against the log's raw torques on every row.
    pub fitness_sdp: [f64; 2],
    /// Fitness (78) per joint, OLS, on the fitted rows (away from
    /// reversals, averaged and filtered as fitted).
    pub fitness_ols_kept: [f64; 2],
    /// Fitness (78) per joint, SDP, on the fitted rows.
    pub fitness_sdp_kept: [f64; 2],
}

/// Fitness (78) per joint of stacked torques (joint 1 first, equal halves).
pub fn fitness_per_joint(measured: &[f64], predicted: &[f64]) -> Result<[f64; 2]> {
    let n = measured.len() / 2;
    Ok([
        aras_ident::validate::fitness(&measured[..n], &predicted[..n])?,
        aras_ident::validate::fitness(&measured[n..], &predicted[n..])?,
    ])
}

/// Fitness (78) per joint of the base parameters `beta_b` against the log's
/// raw torques on every row (78): the prediction from the unfiltered
/// regressor, repeated on every period of an averaged log.
pub fn fitness_on_log_rows(
    prepared: &Prepared,
    base: &BaseParameters,
    beta_b: &[f64],
) -> Result<[f64; 2]> {
    let st = prepared.unfiltered.as_ref().unwrap_or(&prepared.stacked);
    let w_b = base.base_regressor(st.w.as_ref())?;
    let p = predict(w_b.as_ref(), beta_b)?;
    raw_fitness(&prepared.processed, &p)
}

/// Fitness (78) per joint of a stacked per-sample prediction against the
/// log's raw torques on every row that has a sample.
pub fn raw_fitness(processed: &Processed, predicted: &[f64]) -> Result<[f64; 2]> {
    let n = processed.samples.len();
    let pairs = processed.on_log_rows(&[&predicted[..n], &predicted[n..]])?;
    Ok([
        aras_ident::validate::fitness(&pairs[0].0, &pairs[0].1)?,
        aras_ident::validate::fitness(&pairs[1].0, &pairs[1].1)?,
    ])
}

/// Fitness (78) per joint of `beta_b` on the rows of `st` (its own groups).
pub fn fitness_of(st: &Stacked, base: &BaseParameters, beta_b: &[f64]) -> Result<[f64; 2]> {
    let w_b = base.base_regressor(st.w.as_ref())?;
    let p = predict(w_b.as_ref(), beta_b)?;
    let f = fitness_per_group(&st.t, &p, &st.groups)?;
    Ok([f[0], f[1]])
}

/// Parameters `p` with the standard vector `beta` of `model`.
pub fn with_standard(p: &Params, model: &Model, beta: &[f64]) -> Result<Params> {
    let mut q = p.clone();
    q.extra = Default::default();
    q.set_standard_vector(model, beta)?;
    Ok(q)
}

/// The physically consistent fit (SDP (67)–(73)) of a reduced problem with
/// `nominal` as reference and the `[identification.sdp]` settings: shared by
/// the in-memory and the streaming identification.
pub fn consistent_fit(
    reduced: &ReducedLs,
    base: &BaseParameters,
    model: &Model,
    nominal: &Params,
    cfg: &Config,
) -> Result<SdpSolution> {
    let ic = &cfg.identification;
    let sc = &ic.sdp;
    let mut problem = consistent_problem(model, nominal)
        .context("the physically consistent problem around the nominal robot")?;
    problem.mass_tolerance(sc.mass_tolerance)?;
    if let Some([lo, hi]) = sc.box_bounds {
        let all: Vec<usize> = problem
            .links()
            .iter()
            .flat_map(|l| l.inertia.iter().chain(&l.first_moment).copied())
            .collect();
        problem.box_around_reference(&all, lo, hi)?;
    }
    problem.settings(SdpSettings {
        regularisation: sc.regularisation,
        psd_margin: sc.epsilon,
        tolerance: sc.tolerance,
        max_iter: sc.max_iter,
        ..SdpSettings::default()
    });
    problem
        .solve(base, reduced)
        .context("physically consistent fit (SDP)")
}

/// The friction's Coulomb widths for `identification.rows`
/// (`aras_pipeline::friction_width`): with `"all"` refined on every row
/// and written into `prepared`'s columns, the model returned with them;
/// with `"away_from_reversals"` the sign law. A refinement that fails
/// falls back (both joints on the rows away from reversals, the reason
/// kept in the result), it does not stop the identification.
pub fn friction_widths(
    prepared: &mut Prepared,
    base: &BaseParameters,
    model: &Model,
    cfg: &Config,
) -> Result<(Model, WidthRefinement, Vec<bool>)> {
    let ic = &cfg.identification;
    let mode = ic.filtering.mode();
    let away = prepared.keep_mask(ic.min_speed, ic.reversal_reach)?;
    let refinement = match ic.rows {
        FitRows::AwayFromReversals => WidthRefinement::not_refined(),
        FitRows::All => match refine_widths(prepared, model, base, mode, &ic.width) {
            Ok(r) => r,
            Err(e) => WidthRefinement::failed(e.to_string()),
        },
    };
    let refined = apply_widths(prepared, model, mode, refinement.widths())?;
    let keep = refinement.keep(&away);
    Ok((refined, refinement, keep))
}

/// [`friction_widths`] on one log processed and stacked as `identify`
/// processes it (`period` as `--period`): what the refinement found. For
/// commands that start from identify's model on a log they read themselves
/// (`diagnose`).
pub fn widths_on_log(
    log: &Log,
    period: Option<f64>,
    model: &Model,
    geometry: &Geometry,
    cfg: &Config,
) -> Result<WidthRefinement> {
    if cfg.identification.rows == FitRows::AwayFromReversals {
        return Ok(WidthRefinement::not_refined());
    }
    let opts = process_options(cfg, period, false);
    let mut prepared = prepare(log, &opts, cfg.identification.filtering, model, geometry)?;
    let base = base_parameters(model, geometry, cfg)?;
    Ok(friction_widths(&mut prepared, &base, model, cfg)?.1)
}

/// OLS and SDP on prepared data, with `nominal` as the SDP's reference, on
/// the rows `keep` (joint-major; [`friction_widths`]: every row, or a
/// joint's rows away from its velocity reversals by
/// `identification.min_speed`, widened by the filter's reach); σ is the
/// HAC sandwich's (`aras_ident::covariance`).
pub fn identify(
    prepared: &Prepared,
    base: &BaseParameters,
    model: &Model,
    nominal: &Params,
    cfg: &Config,
    keep: &[bool],
) -> Result<Identification> {
    let ic = &cfg.identification;
    let names = model.names();
    let bnames = base.base_names();
    // Counted on the mask, before the rows are taken, so a log whose joints
    // never move gets this message rather than one about empty row groups.
    let n = prepared.n();
    let [n1, n2] = [0, 1].map(|j| keep[j * n..(j + 1) * n].iter().filter(|&&k| k).count());
    if n1 < base.n_base() || n2 < base.n_base() {
        let top = prepared
            .processed
            .samples
            .theta_dot
            .iter()
            .map(|v| v.iter().fold(0.0f64, |m, x| m.max(x.abs())))
            .collect::<Vec<_>>();
        bail!(
            "only {n1} (joint 1) and {n2} (joint 2) samples are away from velocity reversals \
             (identification.min_speed = {} rad/s, widened by the filter's reach at \
             identification.reversal_reach = {}); the joints reach at most |θ̇| = {:.3} / \
             {:.3} rad/s; log a motion that excites both joints (e.g. `aras excite`), or lower \
             those settings",
            ic.min_speed,
            ic.reversal_reach,
            top[0],
            top[1]
        );
    }
    let fit = keep_rows(&prepared.stacked, keep)?;
    let w_fit = base.base_regressor(fit.w.as_ref())?;
    // σ, σ% and the covariance: the HAC sandwich (`aras_ident::covariance`)
    // on the rows as fitted (scaled by 1/σ_joint for WLS).
    let periodic = prepared.periodic();
    let gain = prepared.noise_gain()?;
    let (ols, reduced, sigma_white) = match ic.weighting {
        Weighting::Ols => {
            let r = ReducedLs::new(w_fit.as_ref(), &fit.t, &bnames)?;
            let plain = r.ols()?;
            let white = plain.clone().with_filtered_noise(gain)?.std_dev;
            let (e, _) = plain.with_hac(w_fit.as_ref(), &fit.t, &fit.groups, periodic)?;
            (e, r, white)
        }
        Weighting::Wls => {
            let e = aras_ident::wls(
                w_fit.as_ref(),
                &fit.t,
                &bnames,
                &fit.groups,
                NoiseVariances::FromResiduals,
            )?;
            let scale: Vec<f64> = fit
                .groups
                .labels()
                .iter()
                .map(|&g| 1.0 / e.variances[g].sqrt())
                .collect();
            let ww = faer::Mat::from_fn(w_fit.nrows(), w_fit.ncols(), |i, j| {
                w_fit[(i, j)] * scale[i]
            });
            let tw: Vec<f64> = fit.t.iter().zip(&scale).map(|(t, s)| t * s).collect();
            let white = e.estimate.clone().with_filtered_noise(gain)?.std_dev;
            let (est, _) = e
                .estimate
                .with_hac(ww.as_ref(), &tw, &fit.groups, periodic)?;
            (est, e.reduced, white)
        }
    };
    // σ: the larger of the HAC and the filter model, per parameter
    // (`OlsEstimate::with_sigma_floor`).
    let sigma_hac = ols.std_dev.clone();
    let (ols, _) = ols.with_sigma_floor(&sigma_white)?;
    let sdp = consistent_fit(&reduced, base, model, nominal, cfg)?;
    let reference: Vec<f64> = nominal
        .standard_vector(model)
        .context("the nominal robot's standard parameters")?
        .as_slice()
        .to_vec();
    let ols_std = base.to_standard_near(&ols.estimate, &reference)?;
    let ols_params = with_standard(nominal, model, &ols_std)?;
    let mut sdp_params = nominal.clone();
    sdp_params.extra = Default::default();
    let sdp_params = params_from_solution(&sdp_params, model, &sdp)?;
    let w_b = base.base_regressor(prepared.w_ref())?;
    let predicted_ols = predict(w_b.as_ref(), &ols.estimate)?;
    let predicted_sdp = predict(w_b.as_ref(), &sdp.base)?;
    let fitness_ols = fitness_on_log_rows(prepared, base, &ols.estimate)?;
    let fitness_sdp = fitness_on_log_rows(prepared, base, &sdp.base)?;
    let fitness_ols_kept = fitness_of(&fit, base, &ols.estimate)?;
    let fitness_sdp_kept = fitness_of(&fit, base, &sdp.base)?;
    Ok(Identification {
        rows_fitted: [n1, n2],
        names,
        base: base.clone(),
        ols,
        sigma_white,
        sigma_hac,
        sdp,
        ols_params,
        sdp_params,
        predicted_ols,
        predicted_sdp,
        fitness_ols,
        fitness_sdp,
        fitness_ols_kept,
        fitness_sdp_kept,
    })
}
