//! # aras-friction: friction of one joint from its log
//!
//! Robot-agnostic friction modelling for any joint — a serial arm, a cable
//! drive, a harmonic-drive joint — from a log of time, position, velocity and
//! friction torque (the measured joint torque minus the rigid-body model).
//!
//! * [`Motion`]: time, position and velocity on the log's own, possibly
//!   irregular, time grid.
//! * [`models`]: [`CoulombViscous`], [`Stribeck`], [`Dahl`] and [`LuGre`],
//!   each with its equations, parameter vector with physical bounds
//!   ([`ParamInfo`]), prediction along a motion ([`FrictionModel`]) and its
//!   separable structure `τ = Φ(θ) β` ([`Separable`]) for fitting.
//!
//! ## Conventions
//! SI units and radians: s, rad, rad/s, N·m. `sgn(0) = 0`. Dynamic models
//! integrate their state over every interval between two samples with an
//! unconditionally stable exact update, so sampling jitter, gaps and stiff
//! bristles are handled alike.
//!
//! ## Dependencies, and why
//! * `nalgebra`: QR least squares on small tall regressors.
//! * `serde`: models and results serialise for reports; `thiserror`: the
//!   error type.
#![warn(missing_docs)]

mod error;
pub mod models;
mod motion;

pub use error::FrictionError;
pub use models::{
    CoulombViscous, Dahl, FrictionModel, LuGre, ParamInfo, Separable, Stribeck, predict_parts, sgn,
    stribeck_decay,
};
pub use motion::Motion;
