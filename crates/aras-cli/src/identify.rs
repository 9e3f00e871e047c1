//! Identification (`docs/model.md`, `docs/processing.md`): a processed log → stacked regressor →
//! base parameters → OLS (62)–(66) → physically consistent SDP (67)–(73).
//!
//! The mathematics lives in `aras-signal` (processing), `aras-dyn`
//! (regressor), `aras-ident` (base parameters, least squares, SDP) and the
//! recipe in `aras_pipeline::identify` (in memory and streamed); this module
//! hands them the configured settings (`[identification]` is
//! `aras_pipeline::identify::IdentifySettings`). The recipe:
//! **parallel filtering** (`docs/processing.md`: the same zero-phase low-pass on the
//! torques and every regressor column, so a Coulomb jump is smeared
//! identically on both sides of `T = W β`), **reversal exclusion** (rows of
//! a joint near its velocity reversals, where (49)'s `sign(θ̇)` is wrong,
//! widened by the filter's reach) and **σ from a sandwich covariance**
//! (`aras_pipeline::identify::SigmaMethod`: harmonic by harmonic on every
//! row of an averaged period, else the HAC with the filter model's floor).

use anyhow::{Context, Result, bail};
use aras_dyn::{Model, Params};
use aras_ident::BaseParameters;
use aras_kin::{Geometry, Workspace};
use aras_log::Log;
use aras_pipeline::friction_width::WidthRefinement;
use aras_pipeline::prepare::RegressorColumns;
use aras_pipeline::robot;
use aras_signal::{
    Bandwidth, DerivativeMethod, FilterSpec, OutputRows, PeriodSource, ProcessOptions,
};
use nalgebra::Vector2;

use crate::config::{BandwidthMode, Config, DerivativeChoice, FilteringMode};

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

pub use aras_pipeline::identify::{Identification, fitness_per_joint};

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
    Ok(aras_pipeline::identify::friction_widths(
        prepared,
        base,
        model,
        &cfg.identification,
    )?)
}

/// OLS and SDP on prepared data, with `nominal` as the SDP's reference, on
/// the rows `keep` (joint-major; [`friction_widths`]: every row, or a
/// joint's rows away from its velocity reversals by
/// `identification.min_speed`, widened by the filter's reach); σ by
/// `aras_pipeline::identify::SigmaMethod`.
pub fn identify(
    prepared: &Prepared,
    base: &BaseParameters,
    model: &Model,
    nominal: &Params,
    cfg: &Config,
    keep: &[bool],
) -> Result<Identification> {
    Ok(aras_pipeline::identify::identify(
        prepared,
        base,
        model,
        nominal,
        &cfg.identification,
        keep,
    )?)
}
