//! Identification from logs of any length in bounded memory (
//! "Scale").
//!
//! The least-squares problem `min ‖W_b β_b − T‖` (62)–(66) never needs the
//! stacked regressor, only its QR factor: `[W_b | T] = Q [[R, z], [0, ρ]]`.
//! Stacking two blocks of rows stacks their factors, so the factor can be
//! built block by block (tall-skinny QR): each block of rows is factorised
//! in cache and its `(b+1) × (b+1)` factor merged into a running one
//! ([`QrAccumulator`]). The result is the same [`crate::ReducedLs`] as in
//! memory, so OLS, WLS and the physically consistent SDP work on it
//! unchanged. Memory is `(b+1)²` numbers per joint plus one block.
//!
//! Two accumulations ([`Accumulation`]): **Gram** (default) sums each
//! block's `AᵀA` (one matrix product, compensated sums) and factorises the
//! sum once at the end, about 3× faster than **Qr** (per-block Householder
//! QR, orthogonal transformations only); its accuracy cost, `κ² ε` instead
//! of `κ ε`, is checked on the final factor ([`GramCheck`],
//! [`GRAM_ERROR_LIMIT`]). Reversal exclusion and the filter's noise gain
//! are applied as in memory ([`StreamingOptions::min_speed`],
//! [`StreamingResult::noise_gain`]).
//!
//! * [`QrAccumulator`]: robot-agnostic; push blocks of rows per row group,
//!   merge accumulators, then [`QrAccumulator::reduced`], `ols`, `wls`
//!   (per-group weights, including weights from the first pass's
//!   residuals, in one pass).
//! * [`RegressorStage`]: task-space states → ARAS regressor
//!   (`aras_kin::evaluate`, `aras_dyn::Model::fill`, no allocation per
//!   sample) → base columns → accumulator, in parallel blocks merged in a
//!   fixed order (results do not depend on the thread count).
//! * [`identify_log`]: a CSV log → [`StreamingResult`], read in chunks,
//!   with three bounded-memory routes ([`StreamingRoute`]).
//! * [`synthetic`]: a fast synthetic run (states or a CSV log of any
//!   length) for the scale tests and benchmarks.
//!
//! Accuracy check against the in-memory path: `tests/streaming.rs`
//! (accumulated in chunks vs `ReducedLs::new` on the same rows: estimates
//! agree to 1e-10 relative; `identify_log` vs read → process → stack →
//! filter → OLS in memory). Performance and the scale study:
//! `benches/streaming.rs`, `examples/scale_study.rs`, `docs/scale.md`.

pub(crate) mod accumulator;
pub(crate) mod gram;
mod log;
mod stage;
pub mod synthetic;

pub use accumulator::QrAccumulator;
pub use gram::{Accumulation, GRAM_ERROR_LIMIT, GramCheck};
pub use log::{
    StreamingOptions, StreamingResult, StreamingRoute, identify_log, identify_log_with_progress,
};
pub use stage::{RegressorStage, STAGE_BLOCK_SAMPLES, States};
