//! What the design needs from a dynamic model: `aras-ident`'s
//! [`LinearModel`] (its regressor rows in `f64`), plus the same rows in dual
//! numbers for exact derivatives.

use aras_ident::LinearModel;

/// The forward-mode dual number the design differentiates with: six
/// directions, seeded on six of the `3n` inputs `(X, Ẋ, Ẍ)` of one sample
/// per evaluation (one evaluation for two coordinates).
pub type Dual = num_dual::DualSVec64<6>;

/// A linear-in-parameters model `τ = Y(X, Ẋ, Ẍ) β` of a robot with `n`
/// coordinates and `m` actuators ([`LinearModel::coordinates`],
/// [`LinearModel::outputs`]) in the coordinates `X` the excitation is
/// designed in (joint angles for a serial arm, the task pose `[φ, γ]` for
/// ARAS-Diamond, (42)/(51)) — the identification's own [`LinearModel`], so
/// one model serves both — that can also evaluate its rows in [`Dual`]
/// numbers.
///
/// The design takes values from [`LinearModel::fill`] and the exact
/// derivatives of every entry with respect to `(X, Ẋ, Ẍ)` from
/// [`fill_dual`](Regressor::fill_dual). Write the rows once, generic over
/// `num_dual::DualNum`, and call that from both. Non-smooth entries (e.g.
/// `sign(Ẋ)` of Coulomb friction) should simply have zero derivative.
///
/// A pose the model cannot evaluate (unreachable, singular) is an error; the
/// design checks its box with [`LinearModel::fill`] before it starts.
pub trait Regressor: LinearModel {
    /// [`LinearModel::fill`] in dual numbers: the same rows (column-major
    /// `outputs × columns`, zeroed before each call), with their derivatives along
    /// the directions the inputs are seeded with. Should not allocate.
    fn fill_dual(
        &self,
        q: &[Dual],
        q_dot: &[Dual],
        q_ddot: &[Dual],
        rows: &mut [Dual],
    ) -> Result<(), Self::Error>;
}

impl<R: Regressor> Regressor for &R {
    fn fill_dual(
        &self,
        q: &[Dual],
        q_dot: &[Dual],
        q_ddot: &[Dual],
        rows: &mut [Dual],
    ) -> Result<(), Self::Error> {
        (**self).fill_dual(q, q_dot, q_ddot, rows)
    }
}
