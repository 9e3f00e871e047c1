//! # aras-diagnose: where a robot model and its measurements disagree
//!
//! Which missing effect explains the gap, and how much it shrinks once the
//! effect is added, for a robot of any joint count. The robot enters
//! through one trait, [`DiagnosisModel`]: the starting model's base
//! regressor on a window of processed samples, the [`Candidate`] effects it
//! offers with their columns, and optionally a physically consistent refit
//! ([`ConsistentRefit`]). Everything else is here:
//!
//! 1. **Residual analysis** ([`residual`]): the current model identified on
//!    TRAIN predicts the validation data; each joint's residual is binned
//!    against velocity (rest band `|θ̇| < 0.05 rad/s`, split by sign),
//!    position, acceleration and time, its whiteness is tested (Ljung–Box)
//!    and bins beyond noise become [`Finding`]s in words with numbers.
//! 2. **Selection** ([`diagnose`]) by the robot-agnostic engine
//!    [`aras_ident::selection`]: one chunked pass per data set accumulates, per
//!    joint, the Gram matrix of `[starting model's base regressor | every
//!    candidate setting's filtered columns | τ | τ shifted by every delay]`;
//!    every candidate fit, its F-test and its validation fitness follow from
//!    these blocks. A candidate must be significant on TRAIN (F-test with
//!    the effective number of samples, below) and gain ≥ `min_gain` points
//!    on every validation set; the significant candidate with the lowest
//!    ΔBIC is added (aliases listed) and the search repeats; rows near
//!    velocity reversals are excluded as in identification
//!    ([`filtering::reversal_mask`]); each identifier is added at most
//!    once, so the loop ends. A candidate's continuous setting is then
//!    refined between its grid points ([`refine`]). Finally, where the robot
//!    offers one, the model is re-identified physically consistently from a
//!    chunked incremental QR of the final model.
//!
//! ## Effective number of samples
//! Filtered and period-averaged samples are strongly correlated: a 10 Hz
//! zero-phase low-pass at 1 kHz leaves about one independent value per
//! 50 samples. Treating 10 000 samples as independent would make every
//! candidate "significant". The F-test therefore uses `N_eff = 2 B T` per
//! joint, `B` the filter's equivalent noise bandwidth
//! ([`Dataset::filter_dof`]). Slow systematic misfit is not counted as
//! correlated here (that needs the residual's autocorrelation, i.e. a pass
//! per candidate); the requirement of a gain on every independent
//! validation set is the guard against fitting it. The significance level
//! is divided by the number of candidate settings tried in a round
//! (Bonferroni for the grid scans).
//!
//! ## σ of the fitted parameters
//! The σ reported with every fitted parameter ([`NamedValue::std_dev`]) is
//! that of the HAC sandwich covariance ([`aras_ident::covariance`],
//! `OlsEstimate::with_hac`), as in identification: it counts the filtered,
//! correlated residual (and any slow misfit) with a bandwidth taken from
//! the residual's own autocorrelation time. The F-test uses the
//! uncorrected residual sums of squares with `N_eff` degrees of freedom
//! (the filter's `2 B T / N = Σ h²`, Parseval, or `N / τ_int`); residual
//! bins use `σ_rms / √(g n)`.
//!
//! ## Memory and time
//! Every pass reads its data sets window by window ([`Dataset::read`]):
//! each chunk of 3072 samples with the zero-phase filter's reach to 1e-9
//! of its peak on both sides, where the window's candidate columns and
//! torques are filtered and its reversal exclusion is computed, so a
//! chunk's rows equal the whole record's to that accuracy. A data set's
//! samples are in memory or behind a [`SampleSource`] (e.g. a scratch file
//! written while a long log is processed in overlapping blocks): then
//! nothing proportional to the training log is held. The sums are
//! `joints × width²` numbers per data set (each joint's rows carry only the
//! columns that are not zero on them). The residual analysis summarises
//! each validation set row by row in record order into fixed-size
//! histograms, lag sums, Welch spectra, a decimated trace and an evenly
//! strided sample of at most [`SAMPLE_ROWS`] rows for the figures.
//! Passes over the training log: one for the selection, two per refined
//! setting, one for the physically consistent fit. Deterministic: fixed
//! accumulation lanes, no randomness.
//!
//! ## Dependencies, and why
//! * `aras-signal`: processed samples, the zero-phase filter and the
//!   residual's spectra; `aras-ident`: the selection engine, least squares,
//!   statistics; `faer`: the regressor blocks; `rayon`: parallel windows
//!   and filtering; `serde`: the report serialises.
#![warn(missing_docs)]
// Dense linear algebra on small matrices reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

mod chunks;
mod data;
mod engine;
pub mod filtering;
mod histogram;
pub mod refine;
pub mod residual;

pub use aras_ident::stats::{chi2_sf, f_sf, integrated_time, ljung_box};
pub use data::{Dataset, SampleSource, processing_filter, record_noise_gain};
pub use engine::{
    Candidate, CandidateScore, ConsistentFit, ConsistentRefit, ConsistentSolution, Diagnosis,
    DiagnosisModel, EngineOptions, FitnessRow, LogPrediction, NamedValue, NoRefit, Refinement,
    RefinementStatus, SearchScale, Step, diagnose,
};
pub use residual::{
    Finding, LeftOut, ResidualAnalysis, ResidualSpectrum, RowSample, SAMPLE_ROWS, SampledRow,
    SpectrumBand, TRACE_POINTS, Trace, Whiteness,
};
