//! Diagnosis: where model and measurement disagree, which missing effect
//! explains it, and how much the gap shrinks once it is added.
//!
//! 1. **Residual analysis** ([`residual`]): the current model identified on
//!    TRAIN predicts the validation data; each joint's residual is binned
//!    against velocity (rest band `|θ̇| < 0.05 rad/s`, split by sign),
//!    position, acceleration and time, its whiteness is tested (Ljung–Box)
//!    and bins beyond noise become [`Finding`]s in words with numbers.
//! 2. **Candidates** ([`CANDIDATE_IDS`], [`Candidate`]): `torque_offset`, `coulomb_asymmetry`,
//!    `stribeck_friction` (v_s scanned), `passive_joint_viscous`, `cogging`
//!    (cycles per revolution scanned, order configurable),
//!    `quadratic_damping`, `time_delay` (torque shifted against the angles).
//! 3. **Selection** ([`diagnose`]): each candidate is fitted with the current
//!    model on TRAIN (base-parameter OLS on the augmented, parallel-filtered
//!    regressor) and scored twice: the cross-validated fitness (78) gain per
//!    joint on the validation data, and a nested-model F-test whose
//!    denominator degrees of freedom are the *effective* number of
//!    independent samples (see below); it must also gain ≥ `min_gain` points
//!    on every validation set. The significant candidate with the lowest ΔBIC
//!    is added (aliases listed) and the search repeats; rows near velocity
//!    reversals are excluded exactly as in identification
//!    (`robot::reversal_mask`); each identifier is added at most once,
//!    so the loop ends. Finally the model is re-identified physically
//!    consistently (SDP on the links, friction-like levels `≥ 0`).
//!
//! ## Effective number of samples
//! Filtered and period-averaged samples are strongly correlated: a 10 Hz
//! zero-phase low-pass at 1 kHz leaves about one independent value per
//! 50 samples. Treating 10 000 samples as independent would make every
//! candidate "significant". The F-test therefore uses, per joint,
//! `N_eff = min(2 B T, N / τ_int)`: `2 B T` with `B` the filter's
//! equivalent noise bandwidth ([`Dataset::filter_dof`]), and `N/τ_int` with
//! `τ_int` the integrated autocorrelation time of the augmented model's
//! residual (which also counts slow, systematic misfit as correlated). The
//! significance level is divided by the number of candidate settings tried
//! in a round (Bonferroni for the grid scans).
//!
//! ## σ of the fitted parameters
//! The σ reported with every fitted parameter ([`NamedValue::std_dev`]) is
//! the OLS σ of (64)–(66) divided by `√g`, `g = Σ h²` the filter's noise
//! gain ([`Dataset::noise_gain`]), as in identification
//! (`OlsEstimate::with_filtered_noise`). `g` and `2 B T / N` are the same
//! number (Parseval), so σ and the F-test account for the filter once each
//! and consistently: σ through `g`, the F-test through `N_eff` with the
//! uncorrected residual sum of squares (for one added column `F ≈ z²`,
//! `z = β̂/σ`). Residual bins use `σ_rms / √(g n)` for the same reason.
//!
//! Performance: the regressor blocks of every candidate setting are stacked
//! and filtered once per data set; each fit is one tall-skinny QR.
//! Deterministic: no randomness (the base parameters use a Halton set).

mod candidates;
mod data;
pub mod residual;
mod select;
mod stats;

pub use candidates::{CANDIDATE_IDS, Candidate, CandidateGrid, explanation};
pub use data::Dataset;
pub use residual::{Finding, ResidualAnalysis, Whiteness};
pub use select::{
    CandidateScore, ConsistentFit, DiagnoseOptions, Diagnosis, FitnessRow, NamedValue, Step,
    diagnose,
};
pub use stats::{chi2_sf, f_sf, integrated_time, ljung_box};
