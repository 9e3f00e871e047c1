//! Identification from logs of any length in bounded memory.
//!
//! * [`identify_log`]: a CSV log → [`StreamingResult`], read in chunks,
//!   with three bounded-memory routes ([`StreamingRoute`]); reversal
//!   exclusion and the filter's noise gain are applied as in memory
//!   ([`StreamingOptions::min_speed`], [`StreamingResult::noise_gain`]).
//!   The least squares themselves are `aras_ident::streaming`'s
//!   accumulators over [`crate::TaskRegressor`].
//! * [`synthetic`]: a fast synthetic run (states or a CSV log of any
//!   length) for the scale tests and benchmarks.
//!
//! Accuracy check against the in-memory path: `tests/streaming.rs`
//! (`identify_log` vs read → process → stack → filter → OLS in memory).
//! Performance and the scale study: `benches/streaming.rs`,
//! `examples/scale_study.rs`, `docs/scale.md`.

mod delayed;
mod log;
pub mod synthetic;

pub use log::{
    StreamingOptions, StreamingResult, StreamingRoute, identify_log, identify_log_with_progress,
    spool_log,
};
