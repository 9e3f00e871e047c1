//! Optimal excitation trajectories for identifying the dynamics of any
//! robot whose model is linear in its parameters, equations (74)–(77)
//! (`docs/excitation.md`). ARAS-Diamond is one such robot (feature
//! `aras-diamond`); another brings its own [`Regressor`].
//!
//! * [`FourierTrajectory`]: finite Fourier series (74)–(76) per coordinate,
//!   exact `X`, `Ẋ`, `Ẍ`, JSON I/O (`docs/excitation.md`), sampling.
//! * [`design`]: minimises the condition number of the column-scaled stacked
//!   *base* regressor ([`Criterion::Condition`]) or a D-optimality criterion
//!   ([`Criterion::DOptimal`]) over the coefficients, subject to the box and
//!   rate limits (77), an acceleration limit and zero velocity at the period
//!   boundary, from several random feasible starts; [`design_constrained`]
//!   adds a user [`PoseConstraint`] `g(X) ≤ 0` (task-space limits of an arm
//!   designed in joint space, [`pose`]).
//! * [`Regressor`]: the one thing the design needs from a dynamic model:
//!   `aras-ident`'s `LinearModel` (its `m × p` regressor rows at `(X, Ẋ, Ẍ)`
//!   for `m` actuators and `p` parameters,
//!   the same model the identification uses) that also gives its rows in
//!   [`Dual`] numbers for their exact derivatives.
//!
//! # Conventions
//!
//! SI units and radians everywhere (rad, rad/s, rad/s², s); degrees appear
//! only in messages. `X` are the coordinates the model is written in (joint
//! angles of a serial arm; `[φ, γ]` for ARAS-Diamond, coordinate 0 is φ).
//! The base projection `E` (`n × b`, `W_b = W E`) comes from the
//! base-parameter analysis (`aras-ident`), so the design criterion is on the
//! identifiable combinations only.
//!
//! # Guarantees
//!
//! * Constraints hold in **continuous time**, not only on the grid: the grid
//!   bounds are tightened by a margin from Bernstein's inequality (see
//!   [`constraints`]).
//! * Gradients are exact: `X, Ẋ, Ẍ` are linear in the coefficients, the
//!   regressor is differentiated by forward-mode dual numbers, and the
//!   criteria by their SVD (see [`criterion`]); tests check them against
//!   finite differences.
//! * Deterministic for a seed (no time limits by default); bad settings are
//!   [`ExciteError`]s naming the setting, never panics or NaN.
//!
//! # Dependencies, and why
//!
//! * `optimization_engine` (OpEn): a maintained, pure-Rust constrained
//!   optimiser: augmented Lagrangian (ALM) for the linear path constraints,
//!   PANOC (L-BFGS forward–backward) inside, with user gradients.
//! * `num-dual`: exact derivatives of the regressor with respect to
//!   `(X, Ẋ, Ẍ)` ([`Dual`]).
//! * `aras-ident` (no default features, so no system library): the
//!   `LinearModel` trait [`Regressor`] extends, faer's SVD behind its AVX
//!   upper-state clear.
//! * `aras-core`: [`Motion`], the motion sample trajectories return.
//! * `faer`: the thin SVD of the stacked base regressor.
//! * `nalgebra`: the small fixed-size vectors of the API, and the
//!   projection matrix `E` at the API edge.
//! * `rand`: seeded random feasible starts (`Xoshiro256PlusPlus`, portable).
//! * `rayon`: the starts run in parallel (progress through a callback,
//!   [`design_with_progress`]).
//! * `serde`/`serde_json`: the trajectory file format; `thiserror`: errors.
//! * With the feature `aras-diamond` only, `aras-kin` and `aras-dyn`: the
//!   robot's regressor (`aras_dyn::TaskRegressor`) as a [`Regressor`], the
//!   simulator's `Trajectory` trait for [`FourierTrajectory`], and
//!   motor-space samples (`MotorRow`).

#![warn(missing_docs)]

#[cfg(feature = "aras-diamond")]
mod aras_diamond;
pub mod constraints;
pub mod criterion;
mod design;
mod error;
mod fourier;
mod param;
pub mod pose;
mod regressor;

pub use aras_core::Motion;
#[cfg(feature = "aras-diamond")]
pub use aras_diamond::MotorRow;
pub use constraints::{DEFAULT_MAX_ACCEL_DEG, Limits, Margins};
pub use criterion::{Assessment, Criterion, base_projection};
pub use design::{
    Design, DesignProgress, DesignSettings, StartReport, assess, design, design_constrained,
    design_with_progress, random_feasible, random_feasible_constrained,
};
pub use error::ExciteError;
pub use fourier::{DEFAULT_HARMONICS, DEFAULT_OMEGA_F, FORMAT, FourierTrajectory, TaskRow};
pub use pose::{ConstraintCheck, ConstraintSettings, DualConstraint, PoseConstraint};
pub use regressor::{Dual, Regressor};

// Lets the shared test helpers name this crate the same way in unit tests,
// integration tests and benches.
#[cfg(test)]
extern crate self as aras_excite;
#[cfg(test)]
pub(crate) mod test_support;
