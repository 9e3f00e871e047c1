//! # aras-ident: base parameters, least squares and physically consistent identification
//!
//! Robot-agnostic identification of a dynamic model that is linear in its
//! parameters, `T = W β` ((58)–(73), (78); `docs/model.md`). The crate works on plain stacked
//! matrices, so any robot project can use it:
//!
//! 1. [`BaseParameters`] (58)–(61): from a stacked regressor on rich data,
//!    the numerical rank, the map `β_b = K β`, the base regressor
//!    `W_b = W E`, readable definitions (`b7 = L1.Izz + L2.Izz + 0.5·L3.Ixx`)
//!    and the unidentifiable parameters.
//! 2. [`ReducedLs`], [`ols`], [`wls`] (62)–(66): least squares by QR (never the
//!    normal equations), σ% per parameter, residual variance, condition
//!    number; weighted LS with per-joint noise variances. Data that do not
//!    excite some base parameters give [`IdentError::NotExcited`] naming them.
//!    [`covariance`]: the uncertainty for correlated residuals (HAC sandwich
//!    with a data-driven bandwidth), which σ, σ% and the tests should use;
//!    [`spectral`]: the same sandwich harmonic by harmonic, for a fit on
//!    whole averaged periods.
//! 3. `ConsistentLs` (67)–(73): the physically consistent estimate as one
//!    convex SDP over the links' pseudo-inertias (default feature `sdp`).
//! 4. [`validate`]: fitness (78), workspace positive definiteness of the mass
//!    matrix (80), parameter errors against a known truth.
//! 5. [`streaming`]: the same least squares from data of any length in
//!    bounded memory (incremental QR or Gram accumulation), for any
//!    [`LinearModel`].
//! 6. [`selection`]: which of many candidate column blocks a model is
//!    missing, from one pass over the data in bounded memory (forward
//!    selection on accumulated Gram blocks, validated on every held-out
//!    set); [`stats`]: the F, χ² and autocorrelation tools it uses.
//!
//! The robot-specific orchestration (the ARAS-Diamond's regressor, reading
//! and processing logs, the diagnosis) lives in `aras-pipeline`.
//!
//! ## Conventions
//! SI units and radians throughout. A stacked regressor has one row per
//! (sample, joint) and one named column per parameter; which rows belong to
//! which joint is a [`RowGroups`]. Inertia parameters are tensor entries about
//! the link's pivot in the link frame (`Ixy = I[0,1] = −Σ m x y`), first
//! moments `h = m ρ`. Matrices enter as faer views (`faer::MatRef`), which any
//! column-major buffer can provide (`MatRef::from_column_major_slice`).
//!
//! ## Dependencies, and why
//! * `faer`: fast blocked QR and SVD of tall regressors (hundreds of
//!   thousands of rows).
//! * `clarabel` (feature `sdp`, default): interior-point conic solver with
//!   PSD cones for the SDP; its PSD cones call LAPACK through `openblas-src`,
//!   the system OpenBLAS with the default feature `system-openblas`; a
//!   binary wanting another flavour turns that off and chooses it, as with
//!   clarabel itself (see `docs/blas.md`). Without default features the
//!   crate needs no system library.
//! * `rayon`: parallel tall-skinny QR, streaming regressor blocks and
//!   workspace scans.
//! * `rustfft`: the spectra of [`spectral`]'s harmonic sandwich (an FFT of
//!   any record length, planned once per length).
//! * `aras-core`: `Inertia`, whose pseudo-inertia the SDP constrains.
//! * `serde`: results serialise for reports; `thiserror`: the error type.
#![warn(missing_docs)]
// Dense linear algebra on small fixed matrices reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

mod base;
pub mod covariance;
mod dense;
mod error;
mod groups;
pub mod linalg;
mod ls;
mod model;
mod rank;
#[cfg(feature = "sdp")]
mod sdp;
pub mod selection;
pub mod simd;
pub mod spectral;
pub mod stats;
pub mod streaming;
pub mod validate;

pub use base::{BaseParameters, COEFFICIENT_CLEAN, DEFAULT_RANK_TOLERANCE, RankMargin};
pub use covariance::{HacCovariance, hac_covariance};
pub use dense::symmetric_eigenvalues;
pub use error::{IdentError, SolverStatus};
pub use groups::RowGroups;
pub use ls::{NoiseVariances, OlsEstimate, ReducedLs, WlsEstimate, ols, wls};
pub use model::LinearModel;
#[cfg(feature = "sdp")]
pub use sdp::{
    ActiveConstraint, ConsistentLs, ConstraintKind, LinkLayout, LinkReport, SdpSettings,
    SdpSolution, pseudo_inertia_min_eigenvalue,
};
pub use spectral::{SpectralCovariance, spectral_covariance};
