//! Integration with `aras-dyn`: its regressor as a design [`Regressor`],
//! and [`FourierTrajectory`] as a simulator [`Trajectory`].

use aras_dyn::{DynError, Model, Trajectory};
use aras_kin::{Geometry, Scalar, evaluate};
use nalgebra::Vector2;

use crate::{FourierTrajectory, Regressor};

/// An `aras-dyn` [`Model`] (e.g. [`Model::paper`], 42 columns) seen through
/// the kinematics of a [`Geometry`]: `Y(X, Ẋ, Ẍ)` for the design.
///
/// Generic over the scalar like the model itself, so the design gets exact
/// derivatives by dual numbers; `sign(θ̇)` columns have zero derivative.
#[derive(Debug, Clone, PartialEq)]
pub struct DynRegressor {
    model: Model,
    geometry: Geometry,
}

impl DynRegressor {
    /// Wraps a model and the geometry its kinematics use.
    pub fn new(model: Model, geometry: Geometry) -> Self {
        Self { model, geometry }
    }

    /// The paper's model (rigid links, friction, elasticity) for the
    /// ARAS-Diamond with gravity `[0, −9.81, 0]` m/s² (`docs/model.md`, "Default robot").
    pub fn aras_diamond() -> Result<Self, DynError> {
        Ok(Self::new(
            Model::paper(nalgebra::Vector3::new(0.0, -9.81, 0.0))?,
            Geometry::aras_diamond(),
        ))
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

impl Regressor for DynRegressor {
    type Error = DynError;

    fn columns(&self) -> usize {
        self.model.columns()
    }

    fn fill<T: Scalar>(
        &self,
        x: &Vector2<T>,
        x_dot: &Vector2<T>,
        x_ddot: &Vector2<T>,
        rows: &mut [T],
    ) -> Result<(), DynError> {
        let s = evaluate(&self.geometry, x, x_dot, x_ddot)?;
        self.model.fill(&s, rows)
    }
}

impl Trajectory for FourierTrajectory {
    fn eval(&self, t: f64) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
        let s = FourierTrajectory::eval(self, t);
        (s.x, s.x_dot, s.x_ddot)
    }

    fn period(&self) -> Option<f64> {
        Some(FourierTrajectory::period(self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The adapter gives exactly the model's own regressor.
    #[test]
    fn adapter_matches_model() {
        let r = DynRegressor::aras_diamond().unwrap();
        assert_eq!(r.columns(), 42);
        let (x, xd, xdd) = (
            Vector2::new(1.4, 1.0),
            Vector2::new(0.3, -0.7),
            Vector2::new(2.0, 1.0),
        );
        let mut rows = vec![0.0; 84];
        r.fill(&x, &xd, &xdd, &mut rows).unwrap();
        let s = evaluate(r.geometry(), &x, &xd, &xdd).unwrap();
        let y = r.model().regressor(&s);
        assert_eq!(y.as_slice(), &rows[..]);
        let f = FourierTrajectory::at_rest(1.0, 2, x).unwrap();
        assert_eq!(Trajectory::period(&f), Some(std::f64::consts::TAU));
        assert_eq!(Trajectory::eval(&f, 0.3).0, x);
    }
}
