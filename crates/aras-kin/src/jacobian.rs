//! Motor Jacobian `θ̇ = J Ẋ`, (8)–(11), with the sign explained in `docs/kinematics.md`.

use nalgebra::{Matrix2, Vector2};

use crate::pose::Pose;
use crate::{Geometry, KinError, Scalar};

/// The motor Jacobian `J = [[1, K], [1, −K]]` with `K = dA/dγ`.
///
/// Sign: differentiating `θ1 = φ + A(γ)`, `θ2 = φ − A(γ)` gives `+K` in the
/// first row. The paper prints `R = −K` there (`docs/kinematics.md`, "Jacobian"); we follow the
/// derivative of our own IK, which the tests check by finite differences.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jacobian<T: Scalar = f64> {
    k: T,
}

impl<T: Scalar> Jacobian<T> {
    pub(crate) fn from_k(k: T) -> Self {
        Self { k }
    }

    /// `K = dA/dγ` (dimensionless).
    pub fn k(&self) -> T {
        self.k
    }

    /// `J` as a matrix (rows θ̇1, θ̇2; columns φ̇, γ̇).
    pub fn matrix(&self) -> Matrix2<T> {
        Matrix2::new(T::one(), self.k, T::one(), -self.k)
    }

    /// `J⁻¹ = ½ [[1, 1], [1/K, −1/K]]`, so `Ẋ = J⁻¹ θ̇`.
    /// Always finite: poses with `|K|` below the tolerance never yield a Jacobian.
    pub fn inverse(&self) -> Matrix2<T> {
        let half = T::lift(0.5);
        let ik = half / self.k;
        Matrix2::new(half, half, ik, -ik)
    }

    /// 2-norm condition number `σmax/σmin = max(1, |K|)/min(1, |K|)`
    /// (the singular values of J are √2 and √2|K|).
    pub fn condition_number(&self) -> f64 {
        let k = self.k.value().abs();
        k.max(1.0) / k.min(1.0)
    }

    /// Motor velocities `θ̇ = J Ẋ` (rad/s).
    pub fn apply(&self, x_dot: &Vector2<T>) -> Vector2<T> {
        self.matrix() * x_dot
    }
}

/// The motor Jacobian at a pose; errors on unreachable or singular poses.
pub fn jacobian(g: &Geometry, x: &Vector2<f64>) -> Result<Jacobian, KinError> {
    Ok(Jacobian::from_k(Pose::new(g, x)?.k))
}
