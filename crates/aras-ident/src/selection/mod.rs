//! Selection of missing model terms in one pass and bounded memory.
//!
//! A model `y ≈ X_base β` may be missing some of many candidate column
//! blocks (an offset, a friction law at several settings, a periodic
//! disturbance, a time-shifted target…). All candidates share the base
//! columns, so one pass over the data can accumulate everything a forward
//! selection needs: per output group `g` (e.g. joint) the Gram matrix
//!
//! ```text
//! G_g = Σ_rows  z zᵀ,   z = [base columns | every candidate's columns | target]
//! ```
//!
//! and the column sums, for the training data and for each validation set
//! ([`Accumulator`]). From the blocks of `Σ_g G_g` every nested fit follows
//! (Cholesky of the equilibrated sub-Gram, dependent columns left out), and
//! from each group's block its residual sum of squares; with the validation
//! sums, the fitness (78) per set and group. Memory is `groups × width²`
//! numbers per data set whatever the number of rows; a pass costs one
//! matrix product per chunk.
//!
//! ```
//! use aras_ident::selection::{Accumulator, CandidateSpec, Layout, SelectionOptions, select};
//! // y = 1 + 2 x + noise-free offset candidate `x²` absent, `sin` present.
//! let layout = Layout::new(
//!     2,
//!     vec![CandidateSpec::columns("square", 1), CandidateSpec::columns("sine", 1)],
//!     1,
//! )?;
//! let mut sets: Vec<Accumulator> = (0..2).map(|_| Accumulator::new(&layout)).collect();
//! for (s, acc) in sets.iter_mut().enumerate() {
//!     let mut rows = Vec::new();
//!     for i in 0..500 {
//!         let x = (i as f64 * 0.37 + s as f64).sin() * 2.0;
//!         let noise = ((i * 7919 + s * 104729) % 1000) as f64 / 1000.0 - 0.5;
//!         let y = 1.0 + 2.0 * x + 0.8 * (3.0 * x).sin() + 0.01 * noise;
//!         rows.extend([1.0, x, x * x, (3.0 * x).sin(), y]);
//!     }
//!     acc.push_rows(0, &rows)?;
//! }
//! let (train, val) = sets.split_at(1);
//! let sel = select(&train[0], val, &SelectionOptions::default())?;
//! assert_eq!(sel.added(), vec![1]);
//! assert!((sel.final_fit().estimate[2] - 0.8).abs() < 1e-2);
//! # Ok::<(), aras_ident::IdentError>(())
//! ```
//!
//! ## The test
//! A candidate is added when it is significant on the training data — a
//! nested-model F-test with `N_eff = effective_fraction × rows` (correlated
//! rows count less), at `alpha` divided by the candidates tried in the
//! round — **and** gains at least `min_gain` fitness points on **every**
//! validation set. The significant candidate with the lowest ΔBIC is added;
//! candidates of another family explaining the training data equally well
//! are listed as its aliases; at most one member per family (a grid scan)
//! is added. Every round's evaluations are kept ([`Selection::rounds`]).
//!
//! ## Accuracy
//! The Gram is summed with compensation (entries accurate to about `ε`
//! relative); solving from it costs a relative error of order `κ² ε`, `κ`
//! the condition number of the column-scaled model. Every fit reports this
//! check ([`crate::streaming::GramCheck`], [`Accuracy`]); beyond the limit,
//! refit the final model by QR on the rows.
//!
//! ## Nonlinear settings
//! A candidate with a nonlinear setting (a velocity scale, a delay, a
//! period) enters as a family of grid members. Refinement between grid
//! points needs the columns at the new setting: accumulate a second, small
//! layout (base + the selected candidates + the trial) per trial value and
//! call [`fit_model`] — bounded memory, one pass per trial.

mod accumulate;
mod fit;
mod forward;

pub use accumulate::{Accumulator, CandidateSpec, Layout};
pub use fit::{Accuracy, ModelFit};
pub use forward::{
    CandidateEvaluation, EvaluationStatus, Selection, SelectionOptions, SelectionStatus,
    SelectionStep, fit_model, select, select_with,
};
