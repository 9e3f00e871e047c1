//! What the design needs from a dynamic model: its regressor rows at one
//! sample, evaluable in any [`Scalar`] so they can be differentiated exactly.

use aras_kin::Scalar;
use nalgebra::Vector2;

/// A linear-in-parameters model `τ = Y(X, Ẋ, Ẍ) β` of a 2-DOF robot in
/// task coordinates, (42)/(51): two rows (one per actuator), `n`
/// columns (standard parameters).
///
/// The design evaluates it in `f64` for values and in forward-mode dual
/// numbers (`num_dual::DualSVec64<6>`, seeded on the six inputs) for the
/// exact derivatives of every entry with respect to `(X, Ẋ, Ẍ)`; that is why
/// [`fill`](Regressor::fill) is generic over [`Scalar`]. Non-smooth entries
/// (e.g. `sign(θ̇)` of Coulomb friction) should simply have zero derivative.
///
/// The design only evaluates poses inside its workspace box, which it checks
/// is reachable and non-singular first.
pub trait Regressor: Sync {
    /// Why an evaluation failed (shown in [`ExciteError::Regressor`](crate::ExciteError)).
    type Error: std::error::Error + Send + Sync + 'static;

    /// Number of columns `n`.
    fn columns(&self) -> usize;

    /// Writes `Y(X, Ẋ, Ẍ)` into `rows`: the 2 × n matrix column-major
    /// (length `2n`; `rows[2j]` is actuator 1's entry of column `j`,
    /// `rows[2j + 1]` actuator 2's, as nalgebra's `Matrix2xX` and aras-dyn's
    /// `Model::fill`). `rows` is zeroed before each call. Should not allocate.
    fn fill<T: Scalar>(
        &self,
        x: &Vector2<T>,
        x_dot: &Vector2<T>,
        x_ddot: &Vector2<T>,
        rows: &mut [T],
    ) -> Result<(), Self::Error>;
}

impl<R: Regressor> Regressor for &R {
    type Error = R::Error;

    fn columns(&self) -> usize {
        (**self).columns()
    }

    fn fill<T: Scalar>(
        &self,
        x: &Vector2<T>,
        x_dot: &Vector2<T>,
        x_ddot: &Vector2<T>,
        rows: &mut [T],
    ) -> Result<(), Self::Error> {
        (**self).fill(x, x_dot, x_ddot, rows)
    }
}
