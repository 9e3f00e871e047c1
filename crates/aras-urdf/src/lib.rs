//! Serial and tree robots from their URDF, for identification by the
//! toolkit's robot-agnostic crates (`docs/urdf.md`).
//!
//! [`UrdfModel`] reads a URDF (revolute, continuous and prismatic joints;
//! fixed joints merged into their parent body by the parallel-axis theorem
//! with rotations), takes the base orientation and a gravity vector from
//! [`ModelSettings`], and gives
//!
//! * forward kinematics ([`UrdfModel::body_poses`]),
//! * inverse dynamics by the recursive Newton–Euler algorithm
//!   ([`UrdfModel::inverse_dynamics`]),
//! * the joint-torque regressor `τ = Y(q, q̇, q̈) π` linear in the standard
//!   parameters: per body `m, m·c, I` about the body (joint) frame's origin
//!   in Pinocchio's order ([`LINK_PARAMETERS`]), then per joint the enabled
//!   viscous, Coulomb (`tanh(q̇/w)`), offset and armature columns
//!   ([`JointColumns`]),
//! * the identified URDF: the robot's own file with identified inertials
//!   in place of its own, every other byte kept
//!   ([`UrdfModel::identified_urdf`]), and the robot as MuJoCo MJCF
//!   ([`UrdfModel::to_mjcf`]).
//!
//! The regressor is written once over the number type, so the model is
//! both `aras-ident`'s [`aras_ident::LinearModel`] (base parameters, OLS,
//! the SDP with one pseudo-inertia per body via
//! [`UrdfModel::link_columns`], streaming) and `aras-excite`'s
//! [`aras_excite::Regressor`] (excitation design with exact derivatives).
//! Evaluations reuse a per-thread [`Workspace`] and do not allocate.
//!
//! **Parser.** URDF is read with `roxmltree`, a small, maintained,
//! read-only XML tree with no dependencies of its own beyond `memchr`
//! that keeps every element's position, so a message names the file and
//! line. The URDF-specific crate `urdf-rs` was not taken: it builds on an
//! unmaintained XML reader and fills a missing `<inertial>` or `<mass>`
//! with defaults, so an absent mass cannot be told from a zero one, and
//! its errors carry no position. Only the elements the dynamics needs are
//! read; what the model cannot express (floating and planar joints,
//! `<mimic>`, closed loops, several roots, impossible inertials) is
//! refused with a [`UrdfError`] saying where and what to do.
//!
//! The recipes on a log, one module each, used by the `aras` binary's
//! `--urdf` commands: [`excite`] (an excitation within the URDF's limits),
//! [`identify`], [`predict`] and [`diagnose`] (the toolkit's diagnosis
//! engine with per-joint candidates).
//!
//! [`sim`] simulates such an arm under PD control with the ARAS-Diamond
//! simulator's drive and sensor models, for logs of known parameters
//! (`nalgebra` for the Cholesky solve of the mass matrix; `rand` and
//! `rand_distr` for its seeded sensor noise; `aras-diagnose` for the
//! diagnosis engine).
//!
//! The crate depends on neither `aras-kin` nor `aras-dyn`.

#![allow(clippy::needless_range_loop)] // index loops mirror the equations

pub mod diagnose;
mod dynamics;
mod error;
pub mod excite;
pub mod identify;
mod mjcf;
mod model;
mod parse;
pub mod predict;
pub mod sim;
mod spatial;
mod write;

pub use dynamics::{Pose, Workspace};
pub use error::UrdfError;
pub use model::{
    CoulombWidth, Joint, JointColumns, JointKind, JointLimits, LINK_COLUMNS, LINK_PARAMETERS,
    LinkColumns, ModelSettings, StribeckColumn, UrdfModel,
};
pub use spatial::Scalar;
