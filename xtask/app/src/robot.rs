//! The robot as the configuration describes it, and the two small adapters
//! that connect the library crates: `aras-dyn`'s [`Model`] as the design's
//! [`aras_excite::Regressor`], and a [`FourierTrajectory`] as the
//! simulator's [`Trajectory`].

use std::path::Path;

use anyhow::{Context, Result};
use aras_dyn::{Model, Params, Trajectory};
use aras_excite::FourierTrajectory;
use aras_kin::{Geometry, Scalar, evaluate};
use nalgebra::{Vector2, Vector3};

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

/// `aras-dyn`'s regressor through `aras-kin`'s kinematics, for the design.
pub struct ModelRegressor {
    /// The model.
    pub model: Model,
    /// Its geometry.
    pub geometry: Geometry,
}

impl aras_excite::Regressor for ModelRegressor {
    type Error = aras_dyn::DynError;

    fn columns(&self) -> usize {
        self.model.columns()
    }

    fn fill<T: Scalar>(
        &self,
        x: &Vector2<T>,
        x_dot: &Vector2<T>,
        x_ddot: &Vector2<T>,
        rows: &mut [T],
    ) -> Result<(), Self::Error> {
        let s = evaluate(&self.geometry, x, x_dot, x_ddot)?;
        self.model.fill(&s, rows)
    }
}

/// A Fourier excitation as a desired trajectory of the simulator.
pub struct FourierPath<'a>(pub &'a FourierTrajectory);

impl Trajectory for FourierPath<'_> {
    fn eval(&self, t: f64) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
        let s = self.0.eval(t);
        (s.x, s.x_dot, s.x_ddot)
    }

    fn period(&self) -> Option<f64> {
        Some(self.0.period())
    }
}
