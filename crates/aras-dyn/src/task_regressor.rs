//! The ARAS-Diamond's regressor as an [`aras_ident::LinearModel`] (feature
//! `ident`): the one adapter identification and excitation design share.

use aras_ident::LinearModel;
use aras_kin::{Geometry, KinError, Motion, Scalar};
use nalgebra::Vector2;
use thiserror::Error;

use crate::{DynError, Model};

/// An `aras-dyn` [`Model`] seen through the kinematics of a [`Geometry`]:
/// task coordinates `q = X = [φ, γ]` (rad) and their rates in, the 2 × n
/// regressor (45)–(53) out (one row per actuator). This is what
/// `aras-ident`'s robot-agnostic machinery (the streaming
/// [`RegressorStage`](aras_ident::streaming::RegressorStage)) sees of the
/// robot.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskRegressor {
    model: Model,
    geometry: Geometry,
}

impl TaskRegressor {
    /// Wraps a model and the geometry its kinematics use.
    pub fn new(model: Model, geometry: Geometry) -> Self {
        Self { model, geometry }
    }

    /// The paper's model (rigid links, friction, elasticity) for the
    /// ARAS-Diamond with gravity `[0, −9.81, 0]` m/s² (`docs/model.md`,
    /// "Default robot").
    pub fn aras_diamond() -> Result<Self, DynError> {
        Ok(Self::new(
            Model::paper(nalgebra::Vector3::new(0.0, -9.81, 0.0))?,
            Geometry::aras_diamond(),
        ))
    }

    /// The regressor rows at `(X, Ẋ, Ẍ)` in any [`Scalar`] (dual numbers
    /// give their exact derivatives; `sign(θ̇)` columns have zero
    /// derivative): what [`LinearModel::fill`] computes in `f64`.
    pub fn fill_rows<T: Scalar>(
        &self,
        task: &Motion<T>,
        rows: &mut [T],
    ) -> Result<(), RegressorError> {
        let s = aras_kin::evaluate(&self.geometry, task).map_err(RegressorError::Kinematics)?;
        self.model.fill(&s, rows).map_err(RegressorError::Model)
    }

    /// The wrapped model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The geometry.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }
}

/// Why the regressor of a sample could not be evaluated.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum RegressorError {
    /// The kinematics (1)–(25) failed: outside the workspace or singular.
    #[error("the kinematics (1)–(25) failed")]
    Kinematics(#[source] KinError),
    /// The model rejected the sample or the buffer.
    #[error("the dynamic model rejected the sample")]
    Model(#[source] DynError),
}

impl LinearModel for TaskRegressor {
    type Error = RegressorError;

    fn coordinates(&self) -> usize {
        2
    }

    fn outputs(&self) -> usize {
        2
    }

    fn names(&self) -> Vec<String> {
        self.model.names()
    }

    fn columns(&self) -> usize {
        self.model.columns()
    }

    #[inline]
    fn fill(
        &self,
        q: &[f64],
        q_dot: &[f64],
        q_ddot: &[f64],
        rows: &mut [f64],
    ) -> Result<(), RegressorError> {
        let v = |a: &[f64]| Vector2::new(a[0], a[1]);
        self.fill_rows(&Motion::new(v(q), v(q_dot), v(q_ddot)), rows)
    }
}
