//! Dynamics of the ARAS-Diamond spherical parallel robot in linear-regressor
//! form, an independent Lagrange check, and a simulated robot that writes
//! measurement logs (equation numbers are the source paper's, restated in
//! `docs/model.md`).
//!
//! # Model
//!
//! `τ = Y(X, Ẋ, Ẍ) β` (48)–(53). A [`Model`] is an ordered list of
//! [`Effect`]s; each contributes named columns of `Y` and the matching
//! standard parameters. [`Model::paper`] is the paper's 42-parameter model:
//! per link `Lk.Ixx … Lk.Izz, Lk.hx, Lk.hy, Lk.hz` (inertia tensor about the
//! RCM in the link frame and first moment `m ρ`, (38)–(46)), then
//! `Fv1, Fc1, Fv2, Fc2` (49) and `Ke1, Ke2` (50). The regressor is generic
//! over [`aras_kin::Scalar`] so dual numbers differentiate it exactly.
//!
//! [`Dynamics`] evaluates the same physics directly: (33) in the base frame,
//! the mass matrix (80), Coriolis and gravity terms, energies and forward
//! dynamics. [`lagrange_terms`] derives `M`, `c`, `g` a second, independent
//! way (Lagrange's equations, exact differentiation); the tests make all
//! three agree.
//!
//! # Example
//!
//! ```
//! use aras_dyn::{Dynamics, Params};
//! use aras_kin::Motion;
//! use nalgebra::Vector2;
//!
//! let p = Params::aras_diamond();
//! let model = p.model()?; // rigid links + friction + elasticity: 42 columns
//! let beta = p.standard_vector(&model)?;
//! let dy = Dynamics::new(&p)?;
//! let task = Motion::new(Vector2::new(1.5, 1.0), Vector2::new(0.3, -0.2), Vector2::new(2.0, 1.0));
//! let s = dy.sample(&task)?;
//! let tau = model.regressor(&s) * &beta; // τ = Y β (48)
//! assert!((tau - dy.inverse(&s)).norm() < 1e-12);
//! # Ok::<(), aras_dyn::DynError>(())
//! ```
//!
//! # Conventions
//!
//! * SI units, radians: rad, rad/s, rad/s², N·m, kg, m, kg·m², kg·m.
//! * Frames and link numbering as in `docs/kinematics.md` and `aras_kin::links`: link 1
//!   proximal on θ2 (elbow `b`), link 2 proximal on θ1 (elbow `c`), link 3
//!   distal on `b`, link 4 distal on `c`; arrays are indexed 0–3. Each link's
//!   inertial parameters are in its own frame about the RCM.
//! * `Ixy` etc. are tensor entries (`Ixy = I[0,1] = −Σ m x y`).
//! * Task space is `X = [φ, γ]`, motor space `θ = [θ1, θ2]`, `θ̇ = J Ẋ`.
//!   Torques are motor torques unless a function says "task space"
//!   (`Jᵀ τ`).
//!
//! # Files
//!
//! * Parameter files: [`Params`] (`docs/parameter-format.md`); the default
//!   robot is [`Params::aras_diamond`] = `fixtures/robots/aras-diamond.json`.
//! * Logs: [`sim::write_log`] (CSV + JSON sidecar, `docs/log-format.md`).
//!
//! # Dependencies
//!
//! `aras-core` ([`Inertia`], a link's inertial parameters and
//! pseudo-inertia), `aras-kin` (kinematics, with its `dual` feature), `nalgebra` (fixed-size
//! stack matrices in per-sample code), `num-dual` (exact second derivatives
//! for the Lagrange check), `serde`/`serde_json` (parameter files, log
//! sidecars), `thiserror` (error enums), `rayon` (stacking the regressor
//! over many samples in parallel), `rand`/`rand_distr` (seeded sensor noise
//! in the simulator).

#![warn(missing_docs)]

mod dynamics;
mod effects;
mod error;
mod json;
mod lagrange;
pub mod mjcf;
mod model;
mod params;
mod regressor;
mod robots;
pub mod sim;
#[cfg(feature = "ident")]
mod task_regressor;
mod trajectory;

pub use aras_core::{Inertia, Motion};
pub use dynamics::Dynamics;
pub use effects::{Effect, EffectId, UnknownEffect, coulomb_law, coulomb_law_dw};
pub use error::{DynError, ParamError, SimError};
pub use lagrange::{LagrangeTerms, lagrange_terms};
pub use model::Model;
pub use params::{
    Cogging, DEFAULT_GRAVITY, Extras, Friction, MAX_COGGING_ORDER, Params, Presliding, Stribeck,
};
pub use regressor::Sign;
pub use robots::{ArcLink, PointMass, arc_robot};
#[cfg(feature = "ident")]
pub use task_regressor::{RegressorError, TaskRegressor};
pub use trajectory::{Sinusoid, Trajectory};
