#![warn(missing_docs)]
//! Kinematics of the ARAS-Diamond coaxial spherical parallel robot.
//!
//! A 2-DOF spherical five-bar: two coaxial motors on axis `a` drive the
//! proximal links; distal links hinged at the elbows `b`, `c` meet at the
//! end-effector axis `d`. Every link turns about the remote centre of motion
//! (RCM), the origin of every frame here. Equation numbers are the source
//! paper's (see `docs/model.md`); `docs/kinematics.md` restates them.
//!
//! # Conventions
//!
//! * Units: radians, rad/s, rad/s² everywhere (degrees only in messages).
//! * Base frame {0}: `z0 = a`. Task coordinates `X = [φ, γ]`: `γ` is the
//!   polar angle of `d` from `a`, `φ` its azimuth. Motor angles
//!   `θ = [θ1, θ2]` with `θ1 = φ + A`, `θ2 = φ − A`.
//! * Link numbering follows the paper and the robot authors' model: link 1
//!   is the proximal link driven by **θ2** (elbow `b`), link 2 the proximal
//!   link driven by **θ1** (elbow `c`), link 3 the distal link on `b`, link 4
//!   the distal link on `c`. Arrays are indexed 0–3. See [`links`] for the
//!   frames.
//! * Jacobian sign: `θ̇ = J Ẋ` with `J = [[1, K], [1, −K]]`, `K = dA/dγ`. The
//!   paper's (8)–(11) print the opposite sign (see `docs/kinematics.md`); ours is
//!   the derivative of our own IK and is tested against finite differences.
//!
//! # Errors
//!
//! No function returns NaN or panics on bad input: non-finite inputs,
//! unreachable poses, and poses within [`Geometry::singularity_tolerance`] of
//! a singularity are [`KinError`]s that name the value and the limit.
//!
//! # Example
//!
//! ```
//! use aras_kin::{evaluate, forward, inverse, AssemblyMode, Geometry, Motion};
//! use nalgebra::Vector2;
//!
//! let g = Geometry::aras_diamond();
//! let x = Vector2::new(85f64.to_radians(), 60f64.to_radians());
//! let ik = inverse(&g, &x)?;
//! let back = forward(&g, &ik.theta, AssemblyMode::Plus)?;
//! assert!((back - x).norm() < 1e-12);
//!
//! let s = evaluate(&g, &Motion::new(x, Vector2::new(0.3, -0.7), Vector2::zeros()))?;
//! assert!((s.omega[2] - nalgebra::Vector3::new(0.74048, 0.43208, 0.58577)).norm() < 1e-5);
//! # Ok::<(), aras_kin::KinError>(())
//! ```
//!
//! # Dependencies
//!
//! `aras-core` ([`Motion`], the motion sample kinematics map), `nalgebra`
//! (fixed-size stack types, so per-sample evaluation does not allocate) and
//! `thiserror`. The optional feature `dual` adds `num-dual`
//! (forward-mode dual numbers) so every quantity can be differentiated
//! exactly; see [`Scalar`].

mod error;
mod forward;
mod geometry;
mod inverse;
mod jacobian;
pub mod links;
mod pose;
mod sample;
mod scalar;
mod workspace;

pub use aras_core::Motion;
pub use error::KinError;
pub use forward::{AssemblyMode, forward, forward_motion, task_motion};
pub use geometry::{DEFAULT_SINGULARITY_TOLERANCE, Geometry};
pub use inverse::{InverseSolution, PassiveAngles, inverse};
pub use jacobian::{Jacobian, jacobian};
pub use links::{LINKS, link_frames, link_jacobians};
pub use pose::Singularity;
pub use sample::{KinematicSample, evaluate};
pub use scalar::Scalar;
pub use workspace::{SingularityDistance, Workspace, singularity_distance};
