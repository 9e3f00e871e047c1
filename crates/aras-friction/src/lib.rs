//! # aras-friction: friction of one joint from its log
//!
//! Robot-agnostic friction modelling for any joint — a serial arm, a cable
//! drive, a harmonic-drive joint — from a log of time, position, velocity and
//! friction torque (the measured joint torque minus the rigid-body model).
//!
//! * [`Track`]: time, position and velocity on the log's own, possibly
//!   irregular, time grid.
//! * [`models`]: [`CoulombViscous`], [`Stribeck`], [`Dahl`], [`LuGre`] and
//!   the generalized Maxwell-slip model [`MaxwellSlip`],
//!   each with its equations, parameter vector with physical bounds
//!   ([`ParamInfo`]), prediction along a motion ([`FrictionModel`]) and its
//!   separable structure `τ = Φ(θ) β` ([`Separable`]) for fitting.
//! * [`log`]: the joint log format (CSV with `t, q, dq, tau`, optional `ddq`),
//!   column mapping ([`ColumnMap`]), derivatives on irregular grids.
//! * [`fit`]: variable-projection fits with physical bounds, several starts
//!   and σ of every parameter; RMS and fitness (78).
//! * [`effects`]: candidate effects beyond a model (ripple, asymmetry,
//!   drift, hysteresis, delay, inertia) as column blocks for a forward
//!   selection, and residual profiles.
//! * [`spectrum`]: lines of the residual's spectrum against position
//!   (ripple at any spatial frequency, refined with σ).
//! * [`sim`]: a single-joint simulator with known friction (LuGre with
//!   internal state, ripple, drift, asymmetry, noise, irregular sampling).
//!
//! ## Conventions
//! SI units and radians: s, rad, rad/s, N·m. `sgn(0) = 0`. Dynamic models
//! integrate their state over every interval between two samples with an
//! unconditionally stable exact update, so sampling jitter, gaps and stiff
//! bristles are handled alike.
//!
//! ## Dependencies, and why
//! * `nalgebra`: QR least squares on small tall regressors.
//! * `rayon`: the finite-difference Jacobian columns of the nonlinear
//!   search are independent model evaluations, run in parallel.
//! * `rustfft`: the periodogram of a residual against position, over up
//!   to a million bins.
//! * `aras-signal`: the autocorrelation of a residual by FFT blocks, for
//!   the selection's independent-sample count.
//! * `serde`: models and results serialise for reports; `thiserror`: the
//!   error type.
#![warn(missing_docs)]
// Small dense linear algebra reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

pub mod analysis;
pub mod effects;
mod error;
pub mod fit;
mod linalg;
pub mod log;
pub mod models;
pub mod sim;
pub mod spectrum;
mod track;

pub use analysis::{
    AnalysisError, AnyModel, FinalModel, FitWarning, FrictionRun, FrictionSettings, ModelKind,
    ModelResult, analyse,
};
pub use error::FrictionError;
pub use log::{
    ColumnMap, JointLog, JointMotion, LogError, read_joint_log, read_joint_log_from,
    read_joint_motion, read_joint_motion_from,
};
pub use models::{
    CoulombViscous, Dahl, FrictionModel, LuGre, MaxwellSlip, ParamInfo, Separable, Stribeck,
    predict_parts, sgn, stribeck_decay,
};
pub use track::Track;
