//! Validation's configuration plumbing (`docs/validation.md`): the recipe
//! and its mathematics are `aras_pipeline::validate`; this module hands it
//! the configured settings (`[validation]` is
//! `aras_pipeline::validate::ValidationSettings`; the workspace box is
//! `[trajectory]`'s; the simulator is `[simulation]`'s).

use std::path::Path;

use anyhow::Result;
use aras_dyn::Params;
use aras_ident::validate::PdRegion;
use aras_pipeline::validate::{CrossValidation, ScoredModel};

use crate::config::Config;
use crate::identify::process_options;
use crate::simulate;

/// The workspace box `[trajectory]` `min_deg`..`max_deg`, in radians.
pub fn workspace_box(cfg: &Config) -> ([f64; 2], [f64; 2]) {
    let t = &cfg.trajectory;
    (
        [t.min_deg[0].to_radians(), t.min_deg[1].to_radians()],
        [t.max_deg[0].to_radians(), t.max_deg[1].to_radians()],
    )
}

/// Where the PD check (80) looks: the workspace box with
/// `validation.pd_grid`, `pd_random` and `pd_seed`.
pub fn pd_region(cfg: &Config) -> PdRegion<2> {
    let (lower, upper) = workspace_box(cfg);
    let v = &cfg.validation;
    PdRegion {
        lower,
        upper,
        grid_per_axis: v.pd_grid,
        random: v.pd_random,
        seed: v.pd_seed,
    }
}

/// `aras_pipeline::validate::cross_validate` with the configuration: the
/// truth simulated with `[simulation]`'s robot (`nominal` as the
/// feed-forward model) from seed `simulation.seed`, processed as
/// `[signal]` says, the kept rows by `identification.min_speed`;
/// `progress` ticks once per log.
pub fn cross_validate(
    truth: &Params,
    nominal: &Params,
    scored: ScoredModel,
    candidates: &[Vec<f64>],
    cfg: &Config,
    dir: &Path,
    progress: &indicatif::ProgressBar,
) -> Result<Vec<CrossValidation>> {
    let sim = |duration: f64, seed: u64| simulate::sim_config(cfg, nominal, duration, seed);
    Ok(aras_pipeline::validate::cross_validate(
        truth,
        &sim,
        &cfg.validation,
        cfg.simulation.seed,
        &process_options(cfg, None, false),
        scored,
        candidates,
        cfg.identification.min_speed,
        dir,
        &mut |_| progress.inc(1),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cross-validation's exact-derivative route is the angles-only
    /// processing with `use_logged_derivatives` set, which the library
    /// derives from the options it is given.
    #[test]
    fn exact_route_is_the_same_processing_with_logged_derivatives() {
        let cfg = Config::default();
        let mut angles = process_options(&cfg, None, false);
        assert!(!angles.use_logged_derivatives);
        angles.use_logged_derivatives = true;
        assert_eq!(angles, process_options(&cfg, None, true));
    }
}
