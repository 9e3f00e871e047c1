//! What the design needs from a dynamic model: its regressor rows at one
//! sample, in values and in dual numbers for exact derivatives.

use nalgebra::Vector2;

/// The forward-mode dual number the design differentiates with: six
/// directions, seeded on `(X, Ẋ, Ẍ)` of one sample.
pub type Dual = num_dual::DualSVec64<6>;

/// A linear-in-parameters model `τ = Y(X, Ẋ, Ẍ) β` of a 2-DOF robot in the
/// coordinates `X` the excitation is designed in (joint angles for a serial
/// arm, the task pose `[φ, γ]` for ARAS-Diamond, (42)/(51)): two rows (one
/// per actuator), `n` columns.
///
/// The design evaluates it in `f64` for values ([`fill`](Regressor::fill))
/// and in [`Dual`] numbers ([`fill_dual`](Regressor::fill_dual)) for the
/// exact derivatives of every entry with respect to `(X, Ẋ, Ẍ)`. Write the
/// rows once, generic over `num_dual::DualNum<f64>`, and call that from both
/// methods. Non-smooth entries (e.g. `sign(Ẋ)` of Coulomb friction) should
/// simply have zero derivative.
///
/// A pose the model cannot evaluate (unreachable, singular) is an error; the
/// design checks its box with [`fill`](Regressor::fill) before it starts.
pub trait Regressor: Sync {
    /// Why an evaluation failed (shown in [`ExciteError::Regressor`](crate::ExciteError)).
    type Error: std::error::Error + Send + Sync + 'static;

    /// Number of columns `n`.
    fn columns(&self) -> usize;

    /// Writes `Y(X, Ẋ, Ẍ)` into `rows`: the 2 × n matrix column-major
    /// (length `2n`; `rows[2j]` is actuator 1's entry of column `j`,
    /// `rows[2j + 1]` actuator 2's, as nalgebra's `Matrix2xX`). `rows` is
    /// zeroed before each call. Should not allocate.
    fn fill(
        &self,
        x: &Vector2<f64>,
        x_dot: &Vector2<f64>,
        x_ddot: &Vector2<f64>,
        rows: &mut [f64],
    ) -> Result<(), Self::Error>;

    /// [`fill`](Regressor::fill) in dual numbers: the same rows, with their
    /// derivatives along the directions the inputs are seeded with.
    fn fill_dual(
        &self,
        x: &Vector2<Dual>,
        x_dot: &Vector2<Dual>,
        x_ddot: &Vector2<Dual>,
        rows: &mut [Dual],
    ) -> Result<(), Self::Error>;
}

impl<R: Regressor> Regressor for &R {
    type Error = R::Error;

    fn columns(&self) -> usize {
        (**self).columns()
    }

    fn fill(
        &self,
        x: &Vector2<f64>,
        x_dot: &Vector2<f64>,
        x_ddot: &Vector2<f64>,
        rows: &mut [f64],
    ) -> Result<(), Self::Error> {
        (**self).fill(x, x_dot, x_ddot, rows)
    }

    fn fill_dual(
        &self,
        x: &Vector2<Dual>,
        x_dot: &Vector2<Dual>,
        x_ddot: &Vector2<Dual>,
        rows: &mut [Dual],
    ) -> Result<(), Self::Error> {
        (**self).fill_dual(x, x_dot, x_ddot, rows)
    }
}
