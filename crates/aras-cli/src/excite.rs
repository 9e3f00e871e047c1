//! The excitation design stage ((74)–(77), `docs/excitation.md`): `aras-excite`'s optimiser on the
//! base regressor of the paper's model, configured from `[trajectory]`.

use anyhow::{Context, Result};
use aras_dyn::Params;
use aras_dyn::TaskRegressor;
use aras_excite::{Criterion, Design, DesignProgress, DesignSettings, Limits};
use aras_ident::BaseParameters;
use aras_kin::Workspace;
use indicatif::ProgressBar;
use nalgebra::Vector2;

use crate::config::{Config, CriterionChoice};
use crate::robot::paper_model;

/// The design's settings from the configuration.
pub fn settings(cfg: &Config) -> Result<DesignSettings> {
    let t = &cfg.trajectory;
    let d = |v: [f64; 2]| Vector2::new(v[0].to_radians(), v[1].to_radians());
    let workspace = Workspace::new(d(t.min_deg), d(t.max_deg), d(t.max_rate_deg_s))
        .context("keys `trajectory.min_deg`, `max_deg`, `max_rate_deg_s`")?;
    Ok(DesignSettings {
        harmonics: t.harmonics,
        omega_f: std::f64::consts::TAU / t.period_s,
        limits: Limits::from_workspace(&workspace, d(t.max_accel_deg_s2)),
        criterion: match t.criterion {
            CriterionChoice::Condition => Criterion::Condition,
            CriterionChoice::DOptimal => Criterion::DOptimal,
        },
        constraint_points: t.constraint_points,
        criterion_points: t.criterion_points,
        starts: t.starts,
        seed: t.seed,
        max_outer_iterations: t.max_outer_iterations,
        max_inner_iterations: t.max_inner_iterations,
        ..DesignSettings::default()
    })
}

/// Designs the excitation for the nominal robot's paper model, counting
/// the finished starts on the stage's spinner.
pub fn design(
    cfg: &Config,
    nominal: &Params,
    base: &BaseParameters,
    spinner: &ProgressBar,
) -> Result<Design> {
    let reg = TaskRegressor::new(paper_model(nominal)?, nominal.geometry()?);
    let settings = settings(cfg)?;
    let stage = spinner.message();
    let progress = |p: DesignProgress| {
        spinner.set_message(format!("{stage}: {}/{} starts", p.done, p.total));
    };
    aras_excite::design_with_progress(
        &reg,
        &aras_excite::base_projection(base),
        &settings,
        &progress,
    )
    .context("designing the excitation trajectory")
}
