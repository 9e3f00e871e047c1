//! # aras-pipeline: identification of the ARAS-Diamond from its logs
//!
//! The robot-specific half of identification, on top of the robot-agnostic
//! `aras-ident`:
//!
//! 1. [`robot`]: with the ARAS-Diamond's regressor as an
//!    [`aras_ident::LinearModel`] ([`TaskRegressor`], `aras-dyn`'s with its
//!    feature `ident`), stacked regressors from `aras-signal`'s
//!    samples, parallel filtering (`docs/processing.md`), the velocity-reversal
//!    mask, the SDP layout of the four links and the way back into
//!    `aras_dyn::Params`.
//! 2. [`prepare`]: one log's way to least squares, written once: process,
//!    stack, the processing's low-pass on torques and columns alike; the
//!    in-memory identification, the streaming blocks and the diagnosis's
//!    data sets all start there.
//! 3. [`refine`] (`aras-diagnose`'s): the one refinement of a continuous
//!    non-linear setting (zoomed passes over a scalar RSS profile, parabola
//!    vertex, σ from the curvature), used by the diagnosis's candidates and
//!    by [`friction_width`], the identification's Coulomb transition widths.
//! 4. [`streaming`]: identification from a CSV log of any length in bounded
//!    memory (chunked reading, filtering with overlap, reversal exclusion,
//!    `aras_ident`'s accumulators).
//! 5. [`diagnose`]: the ARAS-Diamond as a robot of `aras-diagnose`'s
//!    engine (its regressor, its candidate effects, the SDP refit): where
//!    model and measurement disagree, which missing effect explains it, and
//!    how much the gap shrinks once it is added; [`spool`] holds a long log's processed samples in a scratch file that
//!    its passes read window by window ([`streaming::spool_log`]).
//! 6. [`predict`]: the torques a parameter file predicts on a log, scored
//!    against its raw torques, with the processing loss.
//! 7. [`validate`]: validation of identified parameters
//!    (`docs/validation.md`): cross-validation on simulated logs of (79)
//!    with each log's noise ceiling and processing loss, the mass matrix's
//!    positive definiteness (80) over the workspace, the links'
//!    pseudo-inertia eigenvalues and parameter errors against a known truth.
//!
//! ## Errors
//! [`PipelineError`]: `aras-ident`'s errors (estimation, data, its
//! settings, the robot crates' errors with their context) pass through;
//! this crate's settings, a model without the effect an operation needs,
//! and broken invariants are its own variants.
//!
//! ## Dependencies, and why
//! * `aras-kin`, `aras-dyn`, `aras-log`, `aras-signal`, `aras-ident`,
//!   `aras-diagnose`: the robot's kinematics, model and simulator (the
//!   cross-validation logs), the log reader and signal processing, the
//!   estimation and the diagnosis engine this crate wires together.
//! * `thiserror`: the error enum.
//! * `faer`: the stacked regressors handed to `aras-ident`; `nalgebra`: the
//!   robot crates' small vectors; `rayon`: parallel filtering and
//!   candidate fits; `serde`: results serialise for reports.
//!
//! ## Features
//! * `system-openblas` (default): link the distribution's OpenBLAS behind
//!   the SDP's PSD cones (`docs/blas.md`). A program that links another
//!   BLAS depends on this crate with `default-features = false` and
//!   chooses its own (e.g. `openblas-src` with `static`).
#![warn(missing_docs)]
// Dense linear algebra on small fixed matrices reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

pub mod diagnose;
mod error;
pub mod friction_width;
pub mod identify;
pub mod predict;
pub mod prepare;
pub mod robot;
pub mod spool;
pub mod streaming;
pub mod validate;

pub use aras_diagnose::refine;
pub use aras_dyn::{RegressorError, TaskRegressor};
pub use error::PipelineError;
