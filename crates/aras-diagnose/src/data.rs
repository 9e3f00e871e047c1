//! Data sets: processed samples in memory or behind a [`SampleSource`]
//! (e.g. a scratch file), the zero-phase filter they passed and the raw
//! log rows they came from.

use aras_signal::{Butterworth, ProcessSummary, Samples, Sos};

use std::ops::Range;
use std::sync::Arc;

use crate::filtering::noise_gain;
use aras_ident::IdentError;

/// Where a data set's samples are when they are not in memory: e.g. a long
/// log processed block by block into a scratch file, read back window by
/// window, so that its length costs disk space, not memory.
pub trait SampleSource: std::fmt::Debug + Send + Sync {
    /// Samples per joint.
    fn len(&self) -> usize;
    /// True if there are no samples.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Samples `rows` into `out` (its channels replaced).
    fn read(&self, rows: Range<usize>, out: &mut Samples) -> Result<(), IdentError>;
}

/// A processed data set: the samples as `aras_signal::process` produced
/// them, in memory or behind a [`SampleSource`] ([`Dataset::spooled`]), and the
/// zero-phase filter it applied (so every regressor column is filtered the
/// same way, `docs/processing.md`). The diagnosis reads it window by
/// window either way.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// Name used in findings and reports (e.g. the file name).
    pub name: String,
    /// Where the processed samples are.
    storage: Storage,
    /// The low-pass that was applied to θ (`None`: unfiltered); the blocks
    /// apply it to the torques and every regressor column alike.
    pub filter: Option<Sos>,
    /// True if the samples are one period-averaged period (the periodic
    /// filter and circular shifts then apply).
    pub periodic: bool,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// The log's rows, for the fitness (78) against its raw torques on
    /// every row (`None` for a spooled data set).
    log_rows: Option<Arc<LogRows>>,
}

/// The rows of the log a data set was processed from: its raw torques and
/// the sample standing for each row (`aras_signal::Processed::sample_of_row`;
/// for a period-averaged set the block's sample on every period).
#[derive(Debug, Clone)]
pub(crate) struct LogRows {
    /// The log's raw torques per joint, every row.
    pub tau: Vec<Vec<f64>>,
    /// The sample of each row (`None` for rows lost at the derivative's edges).
    pub sample: Vec<Option<usize>>,
}

/// Where a data set's samples are.
#[derive(Debug, Clone)]
enum Storage {
    Memory(Box<Samples>),
    /// Shared: clones of the data set read the same source (a scratch
    /// file is removed with the last of them).
    Spooled(Arc<dyn SampleSource>),
}

impl Dataset {
    /// A data set from `aras_signal::process`'s output: the filter is
    /// re-designed from the processing summary (same order, cut-off and
    /// rate), periodic if the record was period-averaged.
    pub fn from_processed(
        name: impl Into<String>,
        processed: &aras_signal::Processed,
    ) -> Result<Self, IdentError> {
        let s = &processed.summary;
        let filter = processing_filter(s)?;
        Ok(Self {
            name: name.into(),
            storage: Storage::Memory(Box::new(processed.samples.clone())),
            filter,
            periodic: s.periods.is_some(),
            sample_rate_hz: s.sample_rate_hz,
            log_rows: Some(Arc::new(log_rows(processed))),
        })
    }

    /// [`Self::from_processed`] taking ownership of the samples instead of
    /// copying them: the peak memory of loading a long log is one copy of
    /// its processed samples, not two.
    pub fn from_processed_owned(
        name: impl Into<String>,
        processed: aras_signal::Processed,
    ) -> Result<Self, IdentError> {
        let mut p = processed;
        // The rows' samples are looked up while the samples are in place.
        let rows = log_rows(&p);
        let samples = std::mem::take(&mut p.samples);
        let mut d = Self::from_processed(name, &p)?;
        d.storage = Storage::Memory(Box::new(samples));
        d.log_rows = Some(Arc::new(rows));
        Ok(d)
    }

    /// A data set whose processed samples are read from `samples` (e.g. a
    /// scratch file written while a long log was processed block by
    /// block), filtered by `filter` (not period-averaged).
    pub fn spooled(
        name: impl Into<String>,
        samples: impl SampleSource + 'static,
        filter: Option<Sos>,
        sample_rate_hz: f64,
    ) -> Self {
        Self {
            name: name.into(),
            storage: Storage::Spooled(Arc::new(samples)),
            filter,
            periodic: false,
            sample_rate_hz,
            log_rows: None,
        }
    }

    /// True if the data set knows its log's rows and raw torques (made
    /// [`Self::from_processed`]), so the diagnosis reports its fitness (78)
    /// against the raw torques on every row; false for a spooled set.
    pub fn has_log_rows(&self) -> bool {
        self.log_rows.is_some()
    }

    /// The log's rows, if known.
    pub(crate) fn log_rows(&self) -> Option<&LogRows> {
        self.log_rows.as_deref()
    }

    /// The samples, if they are held in memory (`None` for a spooled data
    /// set: read them with [`Self::read`]).
    pub fn samples(&self) -> Option<&Samples> {
        match &self.storage {
            Storage::Memory(s) => Some(s),
            Storage::Spooled(_) => None,
        }
    }

    /// True if the samples are read from a [`SampleSource`].
    pub fn is_spooled(&self) -> bool {
        matches!(self.storage, Storage::Spooled(_))
    }

    /// Samples `rows` into `out` (its channels replaced), wherever they are.
    pub fn read(&self, rows: Range<usize>, out: &mut Samples) -> Result<(), IdentError> {
        match &self.storage {
            Storage::Spooled(f) => f.read(rows, out),
            Storage::Memory(s) => {
                if rows.start > rows.end || rows.end > s.len() {
                    return Err(IdentError::DimensionMismatch {
                        what: "end of a window of samples",
                        expected: s.len(),
                        found: rows.end,
                        hint: "read windows inside the record",
                    });
                }
                copy_rows(s, rows, out);
                Ok(())
            }
        }
    }

    /// Samples per joint.
    pub fn len(&self) -> usize {
        match &self.storage {
            Storage::Memory(s) => s.len(),
            Storage::Spooled(f) => f.len(),
        }
    }

    /// Joints of the samples (read from one sample when they are not in
    /// memory).
    pub fn joints(&self) -> Result<usize, IdentError> {
        match &self.storage {
            Storage::Memory(s) => Ok(s.joints()),
            Storage::Spooled(f) => {
                let mut one = Samples::default();
                f.read(0..f.len().min(1), &mut one)?;
                Ok(one.joints())
            }
        }
    }

    /// True if there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Upper bound on independent noise samples per joint, `2 B T`: the
    /// zero-phase filter's equivalent noise bandwidth `B = ∫ |H(f)|⁴ df`
    /// (forward–backward squares the power response) times the record
    /// length. Without a filter every sample counts.
    pub fn filter_dof(&self) -> f64 {
        let n = self.len() as f64;
        let Some(sos) = &self.filter else { return n };
        let fs = self.sample_rate_hz;
        let steps = 4000;
        let df = 0.5 * fs / steps as f64;
        let b: f64 = (0..steps)
            .map(|i| {
                let g = sos.gain((i as f64 + 0.5) * df, fs);
                g * g * g * g * df
            })
            .sum();
        (n * 2.0 * b / fs).clamp(1.0, n)
    }

    /// Where the low-pass's pass band ends (Hz): the first frequency where
    /// its one-way gain falls below `1/√2` (the cut-off of a Butterworth
    /// design), found by bisection; a quarter of the sample rate without a
    /// filter.
    pub fn pass_band_end(&self) -> f64 {
        let fs = self.sample_rate_hz;
        let Some(sos) = &self.filter else {
            return 0.25 * fs;
        };
        let (mut lo, mut hi) = (0.0, 0.5 * fs);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if sos.gain(mid, fs) >= std::f64::consts::FRAC_1_SQRT_2 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// Noise power gain of the zero-phase filter, `g = Σ h_k²` of its
    /// impulse response on this record ([`crate::filtering::noise_gain`]; 1
    /// without a filter). White noise of variance `σ²` leaves the filter
    /// with variance `g σ²`, correlated over about `1/g` samples; the OLS σ
    /// of a parameter whose regressor lies in the pass band is divided by
    /// `√g` to be honest ([`aras_ident::OlsEstimate::with_filtered_noise`]).
    /// It is the same quantity as [`Self::filter_dof`]` / len` (Parseval:
    /// `Σ h² = ∫ |H|⁴ df / f_s`), computed in the time domain.
    pub fn noise_gain(&self) -> Result<f64, IdentError> {
        record_noise_gain(self.filter.as_ref(), self.len(), self.periodic)
    }

    pub(crate) fn check(&self) -> Result<(), IdentError> {
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(IdentError::InvalidSetting {
                name: "sample rate of a diagnosis data set",
                value: self.sample_rate_hz,
                reason: "give the log's sample rate in Hz (ProcessSummary::sample_rate_hz)",
            });
        }
        if self.len() < 200 {
            return Err(IdentError::TooFewRows {
                what: "diagnosis data set",
                rows: self.len(),
                columns: 0,
                needed: 200,
            });
        }
        Ok(())
    }
}

/// Rows `rows` of every channel of `s` into `out` (its channels replaced,
/// one per joint of `s` in each group).
fn copy_rows(s: &Samples, rows: Range<usize>, out: &mut Samples) {
    let copy = |dst: &mut Vec<f64>, src: &Vec<f64>| {
        dst.clear();
        dst.extend_from_slice(&src[rows.clone()]);
    };
    copy(&mut out.t, &s.t);
    let groups = [
        (&mut out.theta, &s.theta),
        (&mut out.theta_dot, &s.theta_dot),
        (&mut out.theta_ddot, &s.theta_ddot),
        (&mut out.x, &s.x),
        (&mut out.x_dot, &s.x_dot),
        (&mut out.x_ddot, &s.x_ddot),
        (&mut out.tau, &s.tau),
    ];
    for (dst, src) in groups {
        dst.resize_with(src.len(), Vec::new);
        for (d, s) in dst.iter_mut().zip(src) {
            copy(d, s);
        }
    }
}

/// The processing's zero-phase low-pass, designed again from its summary
/// (same order, cut-off and rate); `None` if it applied none.
pub fn processing_filter(summary: &ProcessSummary) -> Result<Option<Sos>, IdentError> {
    summary
        .filter
        .as_ref()
        .map(|f| {
            Butterworth::lowpass(f.order, f.cutoff_hz, summary.sample_rate_hz)
                .map_err(|e| IdentError::external("re-designing the processing low-pass", e))
        })
        .transpose()
}

/// Noise power gain of the zero-phase `filter` applied to a record of `n`
/// samples ([`noise_gain`]; 1 when nothing was filtered).
pub fn record_noise_gain(
    filter: Option<&Sos>,
    n: usize,
    periodic: bool,
) -> Result<f64, IdentError> {
    match filter {
        Some(sos) => noise_gain(sos, n, periodic),
        None => Ok(1.0),
    }
}

/// The log rows of a processed log.
fn log_rows(processed: &aras_signal::Processed) -> LogRows {
    LogRows {
        tau: processed.log_tau.clone(),
        sample: (0..processed.log_tau.first().map_or(0, Vec::len))
            .map(|r| processed.sample_of_row(r))
            .collect(),
    }
}

/// Checks that each joint keeps enough rows after the identification's
/// reversal exclusion (`rows` per joint, as the passes counted them): joint
/// `j`'s rows where `|θ̇_j| < min_speed`, widened by the zero-phase
/// filter's reach ([`crate::filtering::filter_reach`]; no widening without a
/// filter), are left out. Near a velocity reversal the exact `sign` of (49)
/// misfits real (sticking, creeping, smooth) friction far beyond the noise,
/// and the filter spreads that misfit over its impulse response; a
/// candidate must not be rewarded for fitting it.
pub(crate) fn check_rows(rows: &[usize]) -> Result<(), IdentError> {
    for (j, &kept) in rows.iter().enumerate() {
        if kept < MIN_ROWS {
            return Err(IdentError::InvalidSetting {
                name: match j {
                    0 => "rows of joint 1 left after the reversal exclusion",
                    1 => "rows of joint 2 left after the reversal exclusion",
                    2 => "rows of joint 3 left after the reversal exclusion",
                    _ => "rows of a joint past the third left after the reversal exclusion",
                },
                value: kept as f64,
                reason: "the joint is rarely faster than min_speed for a whole filter reach: \
                         record a faster or longer motion, or lower min_speed / raise the \
                         reach tolerance",
            });
        }
    }
    Ok(())
}

/// Fewest rows per joint a diagnosis data set must keep after the exclusion.
const MIN_ROWS: usize = 100;
