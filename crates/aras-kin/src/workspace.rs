//! Workspace box (77) and distance to singularities.

use nalgebra::Vector2;

use crate::pose::{Pose, check_finite};
use crate::{Geometry, KinError, Singularity};

/// Distances of a pose to each singularity (dimensionless, 0 = singular).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SingularityDistance {
    /// `sin A`, proximal links aligned at 0.
    pub sin_a: f64,
    /// `sin γ`, end-effector on the motor axis at 0.
    pub sin_gamma: f64,
    /// `sin B`, elbow stretched at 0.
    pub sin_b: f64,
    /// `|K| = |dA/dγ|`, Jacobian singular at 0.
    pub parallel: f64,
}

impl SingularityDistance {
    fn all(&self) -> [(Singularity, f64); 4] {
        [
            (Singularity::ProximalAligned, self.sin_a),
            (Singularity::PolarAxis, self.sin_gamma),
            (Singularity::ElbowStretched, self.sin_b),
            (Singularity::Parallel, self.parallel),
        ]
    }

    /// The smallest distance and which singularity it belongs to
    /// (a NaN distance, from a degenerate pose, counts as the smallest).
    pub fn min(&self) -> (Singularity, f64) {
        self.all()
            .into_iter()
            .fold((Singularity::ProximalAligned, f64::INFINITY), |m, c| {
                if c.1.is_nan() || c.1 < m.1 { c } else { m }
            })
    }

    /// Errors with the nearest singularity if any distance is below `tol`
    /// or not a number.
    pub fn check(&self, tol: f64) -> Result<(), KinError> {
        let (which, value) = self.min();
        if value.is_nan() || value < tol {
            return Err(KinError::Singular {
                which,
                value,
                limit: tol,
            });
        }
        Ok(())
    }
}

/// Distance of a reachable pose to every singularity; unlike the other
/// functions this does not reject singular poses (it measures them).
pub fn singularity_distance(
    g: &Geometry,
    x: &Vector2<f64>,
) -> Result<SingularityDistance, KinError> {
    Ok(Pose::unchecked(g, x)?.distance())
}

/// Task-space box and rate limits, (77). Radians and rad/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Workspace {
    min: Vector2<f64>,
    max: Vector2<f64>,
    max_rate: Vector2<f64>,
}

impl Workspace {
    /// A box `min ≤ X ≤ max` with rate limits `|Ẋ| ≤ max_rate`.
    /// Bounds must be finite, ordered, and the rates positive.
    pub fn new(
        min: Vector2<f64>,
        max: Vector2<f64>,
        max_rate: Vector2<f64>,
    ) -> Result<Self, KinError> {
        let names = [("phi", "phi_dot"), ("gamma", "gamma_dot")];
        for i in 0..2 {
            check_finite(names[i].0, min[i])?;
            check_finite(names[i].0, max[i])?;
            check_finite(names[i].1, max_rate[i])?;
            if min[i] >= max[i] {
                return Err(KinError::OutsideWorkspace {
                    name: names[i].0,
                    unit: "°",
                    value: min[i],
                    min: f64::NEG_INFINITY,
                    max: max[i],
                });
            }
            if max_rate[i] <= 0.0 {
                return Err(KinError::OutsideWorkspace {
                    name: names[i].1,
                    unit: "°/s",
                    value: max_rate[i],
                    min: 0.0,
                    max: f64::INFINITY,
                });
            }
        }
        Ok(Self { min, max, max_rate })
    }

    /// The paper's identification workspace: φ ∈ [30°, 140°],
    /// γ ∈ [40°, 80°], |φ̇|, |γ̇| ≤ 200°/s.
    pub fn paper() -> Self {
        let d = f64::to_radians;
        Self {
            min: Vector2::new(d(30.0), d(40.0)),
            max: Vector2::new(d(140.0), d(80.0)),
            max_rate: Vector2::new(d(200.0), d(200.0)),
        }
    }

    /// Lower corner `[φ, γ]` (rad).
    pub fn min(&self) -> Vector2<f64> {
        self.min
    }

    /// Upper corner `[φ, γ]` (rad).
    pub fn max(&self) -> Vector2<f64> {
        self.max
    }

    /// Rate limits `[φ̇, γ̇]` (rad/s).
    pub fn max_rate(&self) -> Vector2<f64> {
        self.max_rate
    }

    /// Errors if `x` is outside the box, naming the coordinate and the limit.
    pub fn check_pose(&self, x: &Vector2<f64>) -> Result<(), KinError> {
        for (i, name) in ["phi", "gamma"].into_iter().enumerate() {
            check_finite(name, x[i])?;
            if x[i] < self.min[i] || x[i] > self.max[i] {
                return Err(KinError::OutsideWorkspace {
                    name,
                    unit: "°",
                    value: x[i],
                    min: self.min[i],
                    max: self.max[i],
                });
            }
        }
        Ok(())
    }

    /// Errors if a rate exceeds its limit.
    pub fn check_rate(&self, x_dot: &Vector2<f64>) -> Result<(), KinError> {
        for (i, name) in ["phi_dot", "gamma_dot"].into_iter().enumerate() {
            check_finite(name, x_dot[i])?;
            if x_dot[i].abs() > self.max_rate[i] {
                return Err(KinError::OutsideWorkspace {
                    name,
                    unit: "°/s",
                    value: x_dot[i],
                    min: -self.max_rate[i],
                    max: self.max_rate[i],
                });
            }
        }
        Ok(())
    }
}

impl Default for Workspace {
    fn default() -> Self {
        Self::paper()
    }
}
