//! The robot as the configuration describes it. The adapters between the
//! library crates live in them: `aras_excite::DynRegressor` (the model as
//! the design's regressor), `aras_excite::FourierTrajectory` implements
//! `aras_dyn::Trajectory`, and `aras_ident::robot` stacks, filters and
//! builds the physically consistent problem.

use std::path::Path;

use anyhow::{Context, Result};
use aras_dyn::{Model, Params};
use nalgebra::Vector3;

use crate::config::RobotConfig;

/// The nominal robot: its parameters (the CAD values, the reference of the
/// physically consistent fit) with the configured overrides applied.
pub fn nominal(cfg: &RobotConfig, dir: &Path) -> Result<Params> {
    let mut p = load_params(&cfg.params, dir).context("key `robot.params`")?;
    if let Some(a) = cfg.alpha_deg {
        p.alpha_deg = a;
    }
    if let Some(b) = cfg.beta_deg {
        p.beta_deg = b;
    }
    if let Some(g) = cfg.gravity {
        p.gravity = Vector3::from(g);
    }
    p.validate()
        .context("the robot's parameters with the overrides of [robot]")?;
    p.check_physical().context(
        "the nominal robot (key `robot.params`) is the reference of the physically consistent fit \
         and the simulated robot, so it must be physically consistent",
    )?;
    Ok(p)
}

/// `"default"` → the embedded ARAS-Diamond (spec §9); anything else is a
/// parameter-file path, relative to `dir`.
pub fn load_params(spec: &str, dir: &Path) -> Result<Params> {
    if spec == "default" {
        return Ok(Params::aras_diamond());
    }
    let path = dir.join(spec);
    Params::load(&path).with_context(|| format!("cannot load parameter file {}", path.display()))
}

/// The paper's model (rigid links, friction, elasticity; 42 columns) with
/// the robot's gravity: what is identified.
pub fn paper_model(p: &Params) -> Result<Model> {
    Model::paper(p.gravity).context("building the paper's model")
}
