//! The identification recipe on prepared data (`docs/model.md`,
//! `docs/processing.md`): which rows are fitted, OLS (62)–(66) or WLS with
//! σ from the HAC sandwich floored by the filter's white-noise model, the
//! physically consistent SDP (67)–(73), the conversion to standard
//! parameters and the fitness (78) on the log's raw torques and on the
//! fitted rows. The settings are one serialisable struct with its defaults
//! ([`IdentifySettings`]), which the `aras` configuration's
//! `[identification]` section is.

use crate::PipelineError;
use aras_dyn::{Model, Params};
use aras_ident::validate::{fitness_per_group, predict};
use aras_ident::{
    BaseParameters, IdentError, NoiseVariances, OlsEstimate, ReducedLs, SdpSettings, SdpSolution,
};
use aras_signal::{Paired, Processed};
use serde::{Deserialize, Serialize};

use crate::friction_width::{
    FitRows, WidthRefinement, WidthSearch, apply_widths, refine_checked_widths,
};
use crate::prepare::Prepared;
use crate::robot::{FilterMode, Stacked, consistent_problem, keep_rows, params_from_solution};
use crate::streaming::StreamingResult;

/// Quasi-random workspace states of the structural base-parameter analysis
/// (58) by default: enough for a rank decision with a wide margin on the
/// 42 columns of the paper's model.
pub const DEFAULT_BASE_SAMPLES: usize = 400;

/// Row weighting of the least squares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Weighting {
    /// Ordinary least squares (62)–(66).
    Ols,
    /// Per-joint weights `1/σ_j`, σ_j from a first OLS pass's residuals.
    Wls,
}

/// The physically consistent solve (67)–(73).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SdpOptions {
    /// PSD margin ε relative to each link's scale `m L²`.
    pub epsilon: f64,
    /// Link masses may vary by this fraction around the nominal masses.
    pub mass_tolerance: f64,
    /// Box bounds (73) on the link parameters: `[lower, upper]` factors of
    /// the nominal values (paper `[0.8, 1.25]`); absent: no box.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub box_bounds: Option<[f64; 2]>,
    /// Regulariser λ towards the nominal parameters.
    pub regularisation: f64,
    /// Solver tolerance.
    pub tolerance: f64,
    /// Solver iteration limit.
    pub max_iter: u32,
}

impl Default for SdpOptions {
    fn default() -> Self {
        let s = SdpSettings::default();
        Self {
            epsilon: s.psd_margin,
            mass_tolerance: 0.2,
            box_bounds: None,
            regularisation: s.regularisation,
            tolerance: s.tolerance,
            max_iter: s.max_iter,
        }
    }
}

/// Settings of identification. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IdentifySettings {
    /// Filtering mode.
    pub filtering: FilterMode,
    /// Weighting.
    pub weighting: Weighting,
    /// Quasi-random workspace samples for the base-parameter analysis (58)
    /// (default [`DEFAULT_BASE_SAMPLES`]).
    pub base_samples: usize,
    /// Rows where the joint moves slower than this (rad/s) are left out of
    /// the fit, widened by the filter's reach: near a reversal friction is
    /// static (stiction, creep), which (49)'s `sign(θ̇)` does not describe.
    /// 0 keeps every row.
    pub min_speed: f64,
    /// The exclusion around a slow row reaches as far as the zero-phase
    /// filter's impulse response stays above this fraction of its peak.
    pub reversal_reach: f64,
    /// Which rows are fitted: `"away_from_reversals"` (default: the rows
    /// away from velocity reversals by `min_speed`, the sign law (49)) or
    /// `"all"` (every row, the friction's Coulomb transition widths
    /// refined; a joint whose width is not identifiable falls back to the
    /// former).
    pub rows: FitRows,
    /// The width search of `rows = "all"` (`min`, `max` in rad/s, `rounds`).
    pub width: WidthSearch,
    /// The SDP.
    pub sdp: SdpOptions,
}

impl Default for IdentifySettings {
    fn default() -> Self {
        Self {
            filtering: FilterMode::Parallel,
            weighting: Weighting::Ols,
            base_samples: DEFAULT_BASE_SAMPLES,
            min_speed: crate::robot::DEFAULT_MIN_SPEED,
            reversal_reach: crate::robot::DEFAULT_REVERSAL_REACH,
            rows: FitRows::default(),
            width: WidthSearch::default(),
            sdp: SdpOptions::default(),
        }
    }
}

/// How an identification's σ (64) and covariance were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SigmaMethod {
    /// The larger of the time-domain HAC sandwich
    /// (`aras_ident::covariance`, which counts the residual's correlation
    /// but runs low on filtered data) and the filter model
    /// ([`Identification::sigma_white`]), per parameter: rows masked away
    /// from reversals, or a record that is not one averaged period.
    LargerOfHacAndWhiteFiltered,
    /// The harmonic sandwich (`aras_ident::spectral`): every row of one
    /// averaged period fitted, the residual's spectrum measured harmonic by
    /// harmonic, so a coloured residual far from the regressor's harmonics
    /// does not widen σ.
    HarmonicSandwich,
    /// White noise before the filter, corrected by its noise gain (the
    /// streaming route, which keeps no residuals): σ = `sigma_white`.
    WhiteFiltered,
}

/// Everything identification produced.
#[derive(Debug, Clone)]
pub struct Identification {
    /// Rows used in the fit per joint (the rest were near reversals).
    pub rows_fitted: [usize; 2],
    /// The identified model's parameter names (standard).
    pub names: Vec<String>,
    /// Base parameters.
    pub base: BaseParameters,
    /// OLS (or WLS) estimate of the base parameters; σ and covariance by
    /// [`Self::sigma_method`].
    pub ols: OlsEstimate,
    /// How `ols`'s σ and covariance were obtained.
    pub sigma_method: SigmaMethod,
    /// σ of the time-domain HAC sandwich alone.
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
pub fn fitness_per_joint(measured: &[f64], predicted: &[f64]) -> Result<[f64; 2], PipelineError> {
    let n = measured.len() / 2;
    Ok([
        aras_ident::validate::fitness(&measured[..n], &predicted[..n])?,
        aras_ident::validate::fitness(&measured[n..], &predicted[n..])?,
    ])
}

/// Fitness (78) per joint of a stacked per-sample prediction against the
/// log's raw torques on every row that has a sample, the prediction
/// band-limited as the angles were.
pub fn raw_fitness(processed: &Processed, predicted: &[f64]) -> Result<[f64; 2], PipelineError> {
    let n = processed.samples.len();
    let pairs = processed
        .on_log_rows(&[&predicted[..n], &predicted[n..]])
        .map_err(|e| IdentError::external("pairing the prediction with the log's rows", e))?;
    paired_fitness(&pairs)
}

/// Fitness (78) per joint of a prediction paired with the log's raw
/// torques (`aras_signal::Processed::paired_with_log_rows`, or
/// `on_log_rows`, which band-limits it first).
pub fn paired_fitness(pairs: &Paired) -> Result<[f64; 2], PipelineError> {
    Ok([
        aras_ident::validate::fitness(&pairs[0].0, &pairs[0].1)?,
        aras_ident::validate::fitness(&pairs[1].0, &pairs[1].1)?,
    ])
}

/// Fitness (78) per joint of the base parameters `beta_b` against the log's
/// raw torques on every row (78): the prediction from the unfiltered
/// regressor, repeated on every period of an averaged log.
pub fn fitness_on_log_rows(
    prepared: &Prepared,
    base: &BaseParameters,
    beta_b: &[f64],
) -> Result<[f64; 2], PipelineError> {
    let st = prepared.unfiltered.as_ref().unwrap_or(&prepared.stacked);
    let w_b = base.base_regressor(st.w.as_ref())?;
    let p = predict(w_b.as_ref(), beta_b)?;
    raw_fitness(&prepared.processed, &p)
}

/// Fitness (78) per joint of `beta_b` on the rows of `st` (its own groups).
pub fn fitness_of(
    st: &Stacked,
    base: &BaseParameters,
    beta_b: &[f64],
) -> Result<[f64; 2], PipelineError> {
    let w_b = base.base_regressor(st.w.as_ref())?;
    let p = predict(w_b.as_ref(), beta_b)?;
    let f = fitness_per_group(&st.t, &p, &st.groups)?;
    Ok([f[0], f[1]])
}

/// Parameters `p` with the standard vector `beta` of `model` (its extra
/// effects cleared: `beta` holds them).
pub fn with_standard(p: &Params, model: &Model, beta: &[f64]) -> Result<Params, PipelineError> {
    let mut q = p.clone();
    q.extra = Default::default();
    q.set_standard_vector(model, beta)
        .map_err(|e| IdentError::external("the identified standard parameters", e))?;
    Ok(q)
}

/// The physically consistent fit (SDP (67)–(73)) of a reduced problem with
/// `nominal` as reference: shared by the in-memory and the streaming
/// identification.
pub fn consistent_fit(
    reduced: &ReducedLs,
    base: &BaseParameters,
    model: &Model,
    nominal: &Params,
    sdp: &SdpOptions,
) -> Result<SdpSolution, PipelineError> {
    let mut problem = consistent_problem(model, nominal)?;
    problem.mass_tolerance(sdp.mass_tolerance)?;
    if let Some([lo, hi]) = sdp.box_bounds {
        let all: Vec<usize> = problem
            .links()
            .iter()
            .flat_map(|l| l.inertia.iter().chain(&l.first_moment).copied())
            .collect();
        problem.box_around_reference(&all, lo, hi)?;
    }
    problem.settings(SdpSettings {
        regularisation: sdp.regularisation,
        psd_margin: sdp.epsilon,
        tolerance: sdp.tolerance,
        max_iter: sdp.max_iter,
        ..SdpSettings::default()
    });
    problem.solve(base, reduced).map_err(PipelineError::from)
}

/// The friction's Coulomb widths for `settings.rows`
/// ([`crate::friction_width`]): with [`FitRows::All`] refined on every row
/// and written into `prepared`'s columns, the model returned with them;
/// with [`FitRows::AwayFromReversals`] the sign law. A refinement that
/// fails, and a joint whose every-row fit costs its rows away from
/// reversals more than `settings.width.max_moving_rows_cost`
/// ([`moving_rows_cost`](crate::friction_width::moving_rows_cost)), fall back to the rows away from reversals
/// (the reason kept in the result); neither stops the identification.
/// Returns the model, the refinement and the rows to fit (joint-major).
pub fn friction_widths(
    prepared: &mut Prepared,
    base: &BaseParameters,
    model: &Model,
    settings: &IdentifySettings,
) -> Result<(Model, WidthRefinement, Vec<bool>), PipelineError> {
    let mode = settings.filtering;
    let away = prepared.keep_mask(settings.min_speed, settings.reversal_reach)?;
    let refinement = match settings.rows {
        FitRows::AwayFromReversals => WidthRefinement::not_refined(),
        FitRows::All => refine_checked_widths(prepared, model, base, mode, &settings.width, &away)?,
    };
    let refined = apply_widths(prepared, model, mode, refinement.widths())?;
    let keep = refinement.keep(&away);
    Ok((refined, refinement, keep))
}

/// The least-squares stage of [`identify`]: OLS (or WLS) on the rows
/// `keep` of prepared data, with its σ by [`SigmaMethod`].
#[derive(Debug, Clone)]
pub struct Estimate {
    /// Rows used in the fit per joint.
    pub rows_fitted: [usize; 2],
    /// The rows fitted (joint-major, filtered as prepared).
    pub fitted: Stacked,
    /// The estimate of the base parameters; σ and covariance by
    /// [`Self::sigma_method`].
    pub ols: OlsEstimate,
    /// The reduced problem on the fitted rows (scaled by `1/σ_joint` for
    /// WLS), which the SDP solves again under its constraints.
    pub reduced: ReducedLs,
    /// How `ols`'s σ and covariance were obtained.
    pub sigma_method: SigmaMethod,
    /// σ of the time-domain HAC sandwich alone.
    pub sigma_hac: Vec<f64>,
    /// σ assuming white noise before the filter.
    pub sigma_white: Vec<f64>,
}

/// OLS (or WLS, `settings.weighting`) of the base parameters on the rows
/// `keep` of prepared data (joint-major; [`friction_widths`]: every row, or
/// a joint's rows away from its velocity reversals by `settings.min_speed`,
/// widened by the filter's reach), with σ by [`SigmaMethod`]: on every row
/// of one averaged period the harmonic sandwich (`aras_ident::spectral`);
/// otherwise the larger of the HAC sandwich (`aras_ident::covariance`) and
/// the white-noise model of the filtered torques, per parameter.
///
/// # Errors
/// A joint with fewer kept rows than base parameters
/// ([`IdentError::InvalidData`], naming the settings to lower), and every
/// failure of the estimation.
pub fn estimate(
    prepared: &Prepared,
    base: &BaseParameters,
    settings: &IdentifySettings,
    keep: &[bool],
) -> Result<Estimate, PipelineError> {
    let bnames = base.base_names();
    // Counted on the mask, before the rows are taken, so a log whose joints
    // never move gets this message rather than one about empty row groups.
    let n = prepared.n();
    let [n1, n2] = [0, 1].map(|j| keep[j * n..(j + 1) * n].iter().filter(|&&k| k).count());
    if n1 < base.n_base() || n2 < base.n_base() {
        let top: Vec<f64> = prepared
            .processed
            .samples
            .theta_dot
            .iter()
            .map(|v| v.iter().fold(0.0f64, |m, x| m.max(x.abs())))
            .collect();
        return Err(IdentError::InvalidData {
            context: "the rows to fit".into(),
            reason: format!(
                "only {n1} (joint 1) and {n2} (joint 2) samples are away from velocity \
                 reversals (identification.min_speed = {} rad/s, widened by the filter's reach \
                 at identification.reversal_reach = {}); the joints reach at most |θ̇| = {:.3} / \
                 {:.3} rad/s; log a motion that excites both joints (e.g. `aras excite`), or \
                 lower those settings",
                settings.min_speed,
                settings.reversal_reach,
                top.first().copied().unwrap_or(0.0),
                top.get(1).copied().unwrap_or(0.0)
            ),
        }
        .into());
    }
    let fit = keep_rows(&prepared.stacked, keep)?;
    let w_fit = base.base_regressor(fit.w.as_ref())?;
    // σ, σ% and the covariance, on the rows as fitted (scaled by 1/σ_joint
    // for WLS): on every row of one averaged period the harmonic sandwich
    // (`aras_ident::spectral`); otherwise the larger of the HAC sandwich
    // (`aras_ident::covariance`) and the filter model, per parameter
    // (`OlsEstimate::with_sigma_floor`). The HAC is kept as `sigma_hac`.
    let periodic = prepared.periodic();
    let gain = prepared.noise_gain()?;
    let whole_periods = periodic && keep.iter().all(|&k| k);
    let spectral = |e: &aras_ident::OlsEstimate, w: faer::MatRef<'_, f64>, t: &[f64]| {
        whole_periods
            .then(|| {
                e.clone()
                    .with_spectral_sandwich(w, t, &fit.groups)
                    .map(|(e, _)| e)
            })
            .transpose()
    };
    let (ols, reduced, sigma_white, harmonic) = match settings.weighting {
        Weighting::Ols => {
            let r = ReducedLs::new(w_fit.as_ref(), &fit.t, &bnames)?;
            let plain = r.ols()?;
            let white = plain.clone().with_filtered_noise(gain)?.std_dev;
            let harmonic = spectral(&plain, w_fit.as_ref(), &fit.t)?;
            let (e, _) = plain.with_hac(w_fit.as_ref(), &fit.t, &fit.groups, periodic)?;
            (e, r, white, harmonic)
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
            let harmonic = spectral(&e.estimate, ww.as_ref(), &tw)?;
            let (est, _) = e
                .estimate
                .with_hac(ww.as_ref(), &tw, &fit.groups, periodic)?;
            (est, e.reduced, white, harmonic)
        }
    };
    let sigma_hac = ols.std_dev.clone();
    let (ols, sigma_method) = match harmonic {
        Some(e) => (e, SigmaMethod::HarmonicSandwich),
        None => (
            ols.with_sigma_floor(&sigma_white)?.0,
            SigmaMethod::LargerOfHacAndWhiteFiltered,
        ),
    };
    Ok(Estimate {
        rows_fitted: [n1, n2],
        fitted: fit,
        ols,
        reduced,
        sigma_method,
        sigma_hac,
        sigma_white,
    })
}

/// Identification on prepared data: [`estimate`] on the rows `keep`, the
/// physically consistent SDP with `nominal` as its reference
/// ([`consistent_fit`]), both completed to standard parameters, and their
/// fitness (78) against the raw torques and on the fitted rows.
///
/// # Errors
/// Those of [`estimate`], and every failure of the SDP.
pub fn identify(
    prepared: &Prepared,
    base: &BaseParameters,
    model: &Model,
    nominal: &Params,
    settings: &IdentifySettings,
    keep: &[bool],
) -> Result<Identification, PipelineError> {
    let Estimate {
        rows_fitted,
        fitted,
        ols,
        reduced,
        sigma_method,
        sigma_hac,
        sigma_white,
    } = estimate(prepared, base, settings, keep)?;
    let sdp = consistent_fit(&reduced, base, model, nominal, &settings.sdp)?;
    let (ols_params, sdp_params) = standard_params(nominal, model, base, &ols.estimate, &sdp)?;
    let w_b = base.base_regressor(prepared.w_ref())?;
    let predicted_ols = predict(w_b.as_ref(), &ols.estimate)?;
    let predicted_sdp = predict(w_b.as_ref(), &sdp.base)?;
    let fitness_ols = fitness_on_log_rows(prepared, base, &ols.estimate)?;
    let fitness_sdp = fitness_on_log_rows(prepared, base, &sdp.base)?;
    let fitness_ols_kept = fitness_of(&fitted, base, &ols.estimate)?;
    let fitness_sdp_kept = fitness_of(&fitted, base, &sdp.base)?;
    Ok(Identification {
        rows_fitted,
        names: model.names(),
        base: base.clone(),
        ols,
        sigma_method,
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

/// The estimates of a streamed identification
/// ([`crate::streaming::StreamingResult`]).
#[derive(Debug, Clone)]
pub struct StreamedIdentification {
    /// OLS (or WLS) estimate of the base parameters; σ the white-noise model
    /// of the filtered torques (see [`identify_streamed`]).
    pub ols: OlsEstimate,
    /// The SDP solution.
    pub sdp: SdpSolution,
    /// OLS completed to standard parameters closest to the nominal robot.
    pub ols_params: Params,
    /// The physically consistent standard parameters.
    pub sdp_params: Params,
    /// Fitness (78) per joint of the OLS estimate on the fitted rows.
    pub fitness_ols: [f64; 2],
    /// Fitness (78) per joint of the SDP estimate on the fitted rows.
    pub fitness_sdp: [f64; 2],
}

/// [`identify`] on a streamed accumulation: the same weighting, SDP and
/// standard parameters, with one difference, stated here and in the
/// output's `sigma_method`: σ is the white-noise model of the filtered
/// torques (`OlsEstimate::with_filtered_noise`), since a stream keeps no
/// residual series for the HAC sandwich; it is the in-memory route's
/// [`Identification::sigma_white`], the floor of its σ. The fitness is on
/// the fitted rows (a stream keeps no samples to predict every row).
pub fn identify_streamed(
    result: &StreamingResult,
    base: &BaseParameters,
    model: &Model,
    nominal: &Params,
    settings: &IdentifySettings,
) -> Result<StreamedIdentification, PipelineError> {
    let (ols, reduced) = match settings.weighting {
        Weighting::Ols => (result.ols.clone(), result.reduced.clone()),
        Weighting::Wls => {
            let e = result.accumulator.wls(NoiseVariances::FromResiduals)?;
            (
                e.estimate.with_filtered_noise(result.noise_gain)?,
                e.reduced,
            )
        }
    };
    let sdp = consistent_fit(&reduced, base, model, nominal, &settings.sdp)?;
    let (ols_params, sdp_params) = standard_params(nominal, model, base, &ols.estimate, &sdp)?;
    Ok(StreamedIdentification {
        fitness_ols: result.fitness(&ols.estimate)?,
        fitness_sdp: result.fitness(&sdp.base)?,
        ols,
        sdp,
        ols_params,
        sdp_params,
    })
}

/// Both routes' standard parameters: the OLS base estimate completed to
/// the standard vector closest to the nominal robot's, and the SDP
/// solution's (each with the nominal robot's other settings).
fn standard_params(
    nominal: &Params,
    model: &Model,
    base: &BaseParameters,
    ols: &[f64],
    sdp: &SdpSolution,
) -> Result<(Params, Params), PipelineError> {
    let reference: Vec<f64> = nominal
        .standard_vector(model)
        .map_err(|e| IdentError::external("the nominal robot's standard parameters", e))?
        .as_slice()
        .to_vec();
    let ols_std = base.to_standard_near(ols, &reference)?;
    let ols_params = with_standard(nominal, model, &ols_std)?;
    let mut sdp_params = nominal.clone();
    sdp_params.extra = Default::default();
    let sdp_params = params_from_solution(&sdp_params, model, sdp)?;
    Ok((ols_params, sdp_params))
}
