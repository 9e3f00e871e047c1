//! The value types every ARAS crate speaks, with no robot in them.
//!
//! * [`Motion`]: position, rate and acceleration of a robot's coordinates at
//!   one instant — a task pose `X = [φ, γ]` with `Ẋ, Ẍ`, or joint angles
//!   `θ, θ̇, θ̈`; two fixed coordinates by default, any fixed number, or a
//!   number known at run time ([`DMotion`]). Trajectories return it,
//!   kinematics map it between joint and task space, processing hands it
//!   to the caller's coordinate map.
//! * [`Inertia`]: a rigid link's inertial parameters about its pivot, and
//!   the pseudo-inertia `𝒥` whose positive (semi)definiteness is physical
//!   consistency (67)–(69). The model builds its dynamics from it and the
//!   physically consistent identification constrains it.
//! * [`LuGreLaw`] and [`stribeck_decay`]: the equations of LuGre friction
//!   (presliding, Stribeck, hysteresis) of one joint, evaluated by the
//!   simulator's plant and by the friction identification.
//! * [`drive`] and [`Rk4`]: the simulated joint drive — encoder
//!   quantisation, current-noise size, the filtered velocity estimate and
//!   PD feedback of [`drive::PdDrive`], torque limits — and the classical
//!   RK4 step on a flat state, for any number of joints: the ARAS-Diamond
//!   simulator and the URDF arm simulator share them.
//!
//! They live here, apart from the kinematics and the model, so that the
//! robot-agnostic crates (processing, identification, excitation design)
//! share them without depending on ARAS-Diamond.
//!
//! # Dependencies
//!
//! * `nalgebra`: the small fixed-size vectors and matrices.

#![warn(missing_docs)]

pub mod drive;
mod inertia;
mod lugre;
mod motion;
mod ode;

pub use inertia::Inertia;
pub use lugre::{LuGreLaw, stribeck_decay};
pub use motion::{DMotion, Motion};
pub use ode::Rk4;
