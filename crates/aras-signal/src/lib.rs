//! Measured robot logs → clean, aligned samples `θ, θ̇, θ̈, X, Ẋ, Ẍ, τ` for
//! identification (`docs/processing.md`). No robot: `X` are whatever
//! coordinates the caller's model is written in ([`Coordinates`]).
//!
//! # Pipeline
//!
//! 1. [`read_log`] / [`read_log_from`] / the streaming [`LogReader`]: the CSV
//!    format of `docs/log-format.md` plus its optional JSON [`Sidecar`];
//!    encoder counts and motor currents are converted to joint angles and
//!    torques; every defect is a [`LogError`] naming file, line and column.
//! 2. [`process`]: period averaging ([`average_periods`]), zero-phase
//!    Butterworth low-pass ([`Butterworth`], [`Sos`]), derivatives
//!    ([`derivatives`], [`DerivativeMethod`]), the model's coordinates from
//!    the caller's [`Coordinates`] ([`JointCoordinates`] when the model is
//!    written in joint angles), with a serialisable [`ProcessSummary`] for
//!    the report.
//! 3. The same [`Sos`] filters any other column (`filtfilt`,
//!    `filtfilt_into`, `filtfilt_in_place`, `filtfilt_periodic`): the
//!    identification must filter every regressor column exactly as the
//!    torques (`docs/processing.md`, "Parallel filtering").
//!
//! # Conventions
//!
//! * SI units throughout: s, rad, rad/s, rad/s², N·m, Hz. Degrees are
//!   rejected ([`LogError::Degrees`]), not converted.
//! * Filtering matches `scipy.signal.sosfiltfilt` / `filtfilt` defaults to
//!   1e-10 (tests against committed reference vectors), so results can be
//!   cross-checked with Python or MATLAB.
//! * Nothing panics on bad input and nothing yields a silent NaN: inputs are
//!   checked for finiteness and every failure is a typed error whose message
//!   says what, where and how to fix it.
//!
//! # Example
//!
//! ```
//! use aras_signal::{
//!     process, read_log_from, Butterworth, JointCoordinates, ProcessOptions, ReadOptions,
//! };
//!
//! let mut csv = String::from("t,theta1,theta2,tau1,tau2\n");
//! for i in 0..2000 {
//!     let t = i as f64 * 1e-3;
//!     let s = (std::f64::consts::TAU * t).sin();
//!     csv += &format!("{t},{},{},{},{}\n", 2.0 + 0.1 * s, 0.6 - 0.1 * s, 0.1 * s, -0.2 * s);
//! }
//! let log = read_log_from(csv.as_bytes(), "demo.csv", &ReadOptions::default())?;
//! let out = process(&log, &ProcessOptions::default(), &JointCoordinates)?;
//! assert_eq!(out.samples.len(), 2000); // one-sided differences at the ends keep every row
//!
//! // The same filter on any other column:
//! let sos = Butterworth::lowpass(4, 10.0, 1000.0)?;
//! let smooth = sos.filtfilt(&log.tau[0])?;
//! # let _ = smooth;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Dependencies
//!
//! * `nalgebra`: small dense least squares for Savitzky–Golay weights.
//! * `rustfft`: O(n log n) transforms of any length for the periodic filter
//!   and spectral derivative (an averaged period of 10 000 samples is not a
//!   power of two; a hand-written mixed-radix FFT would be more code to trust).
//! * `serde`, `serde_json`: the sidecar and the serialisable summaries.
//! * `thiserror`: the error enums.
//!
//! The CSV is parsed by a small purpose-built scanner rather than the `csv`
//! crate: the format is plain numeric, and the scanner gives exact line and
//! column positions and reads an hour at 1 kHz in a fraction of a second
//! (see `benches/signal.rs`).

#![warn(missing_docs)]

mod bandwidth;
mod butterworth;
mod coordinates;
mod derivative;
mod error;
mod fourier;
mod log;
mod periods;
mod process;
mod sos;

pub use bandwidth::{
    CUTOFF_MARGIN, HARMONIC_FALSE_ALARM, HarmonicSelection, MIN_PERIOD_CORRELATION,
    PeriodDetection, PeriodOrigin, SPECTRUM_THRESHOLD, SpectrumCutoff, detect_period,
    spectrum_cutoff,
};
pub use butterworth::{Butterworth, MAX_ORDER};
pub use coordinates::{Coordinates, JointCoordinates, Motion};
pub use derivative::{DerivativeMethod, Derivatives, derivatives, resolve};
pub use error::{FilterError, LogError, ProcessError};
pub use log::{
    ColumnNames, Columns, Excitation, Extreme, FORMAT, Log, LogReader, LogReport, LogSummary,
    NOMINAL_WINDOW, ReadOptions, Sensors, Sidecar, SidecarSource, Span, StepDeviation, Warning,
    read_log, read_log_from,
};
pub use periods::{MAX_BLOCK_MISMATCH, MAX_DRIFT, PeriodAverage, average_periods};
pub use process::{
    Bandwidth, BandwidthChoice, BandwidthMethod, FilterSpec, FilterSummary, OutputRows,
    PeriodSource, PeriodSummary, ProcessOptions, ProcessSummary, Processed, Samples, process,
};
pub use sos::{Sos, TransferFunction};
