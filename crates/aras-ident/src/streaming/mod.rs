//! Least squares from data of any length in bounded memory.
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
//! [`GRAM_ERROR_LIMIT`]).
//!
//! * [`QrAccumulator`]: push blocks of rows per row group, merge
//!   accumulators, then [`QrAccumulator::reduced`], `ols`, `wls`
//!   (per-group weights, including weights from the first pass's
//!   residuals, in one pass).
//! * [`RegressorStage`]: states → a [`crate::LinearModel`]'s regressor (no
//!   allocation per sample) → base columns → accumulator, in parallel
//!   blocks merged in a fixed order (results do not depend on the thread
//!   count).
//!
//! Reading logs in chunks, filtering blocks with overlap and excluding
//! velocity reversals is the robot pipeline's part (`aras-pipeline`).
//! Accuracy against the in-memory path: accumulated in chunks vs
//! `ReducedLs::new` on the same rows agree to 1e-10 relative
//! (`aras-pipeline/tests/streaming.rs`).

pub(crate) mod accumulator;
pub(crate) mod gram;
mod stage;

pub use accumulator::QrAccumulator;
pub use gram::{Accumulation, GRAM_ERROR_LIMIT, GramCheck};
pub use stage::{RegressorStage, STAGE_BLOCK_SAMPLES, States};
