//! Measured robot logs → clean, aligned samples `θ, θ̇, θ̈, X, Ẋ, Ẍ, τ` for
//! identification (`docs/processing.md`). No robot: `X` are whatever
//! coordinates the caller's model is written in ([`Coordinates`]). No file
//! format: a log arrives as an [`aras_log::Log`] (read by `aras-log`, or
//! built in memory).
//!
//! # Pipeline
//!
//! 1. [`process`]: period averaging ([`average_periods`]), zero-phase
//!    Butterworth low-pass ([`Butterworth`], [`Sos`]), derivatives
//!    ([`derivatives`], [`DerivativeMethod`]), the model's coordinates from
//!    the caller's [`Coordinates`] ([`JointCoordinates`] when the model is
//!    written in joint angles), with a serialisable [`ProcessSummary`] for
//!    the report.
//!    [`resample_log`] first brings a jittered or gappy log onto a uniform
//!    grid on request, reporting every gap and bridging none beyond a
//!    stated length.
//! 2. [`delay_torque`]: torque samples logged later than the angles they
//!    belong to, shifted back (a whole or fractional number of samples).
//! 3. The same [`Sos`] filters any other column (`filtfilt`,
//!    `filtfilt_into`, `filtfilt_in_place`, `filtfilt_periodic`): the
//!    identification must filter every regressor column exactly as the
//!    torques (`docs/processing.md`, "Parallel filtering").
//!
//! # Conventions
//!
//! * SI units throughout: s, rad, rad/s, rad/s², N·m, Hz.
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
//! use aras_log::{read_log_from, ReadOptions};
//! use aras_signal::{process, Butterworth, JointCoordinates, ProcessOptions};
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
//! * `rayon`: the caller's [`Coordinates`] mapped over a long log's samples
//!   on every core (the forward kinematics of 160 000 samples is half of a
//!   plain log's processing); the workspace's other parallel stages use it
//!   too, so a program has one thread pool to configure.
//! * `aras-log`: the [`aras_log::Log`] a processing starts from.
//! * `aras-core`: [`Motion`], the motion sample the caller's [`Coordinates`]
//!   map, shared with the kinematics and the excitation design.
//! * `serde`: the serialisable summaries.
//! * `thiserror`: the error enums.

#![warn(missing_docs)]

mod autocorrelation;
mod band;
mod bandwidth;
mod butterworth;
mod coordinates;
mod delay;
mod derivative;
mod error;
mod fourier;
mod periods;
mod process;
mod resample;
mod sos;
mod spectrum;

pub use autocorrelation::Autocorrelation;
pub use band::{BandLimit, HarmonicBand};
pub use bandwidth::{
    CUTOFF_MARGIN, HARMONIC_FALSE_ALARM, HarmonicSelection, MIN_PERIOD_CORRELATION,
    PeriodDetection, PeriodOrigin, SPECTRUM_THRESHOLD, SpectrumCutoff, detect_period,
    spectrum_cutoff,
};
pub use butterworth::{Butterworth, MAX_ORDER};
pub use coordinates::{Coordinates, JointCoordinates, Motion};
pub use delay::{delay_torque, delayed_at, delayed_periodic};
pub use derivative::{DerivativeMethod, Derivatives, derivatives, resolve};
pub use error::{FilterError, ProcessError};
pub use periods::{
    MAX_BLOCK_MISMATCH, MAX_DRIFT, MAX_STREAMED_BLOCK_SAMPLES, PeriodAverage, PeriodMean,
    PeriodSums, average_periods,
};
pub use process::{
    Bandwidth, BandwidthChoice, BandwidthMethod, FilterSpec, FilterSummary, OutputRows, Paired,
    PeriodSource, PeriodSummary, ProcessOptions, ProcessSummary, Processed, Samples, process,
    process_in,
};
pub use resample::{GAP_RATIO, Gap, MAX_GROWTH, ResampleOptions, Resampling, resample_log};
pub use sos::{FILTER_LANES, Sos, TransferFunction};
pub use spectrum::{
    MAX_SEGMENT, PowerSpectrum, SpectrumAccumulator, SpectrumError, power_spectrum,
};
