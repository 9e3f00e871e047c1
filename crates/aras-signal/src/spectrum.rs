//! One-sided power spectral density of a record: where in frequency a
//! signal (e.g. a model's residual) has its power.
//!
//! One period of a periodic record gets the plain periodogram of the whole
//! record (no window: its bins are exactly the period's harmonics); any
//! other record Welch's average of Hann-windowed segments with half
//! overlap, the segment the largest power of two up to half the record
//! (at least 256 samples, at most [`MAX_SEGMENT`]), trading resolution for
//! a variance that falls with the number of segments. A record that
//! arrives in pieces (a long log read window by window) gets the same
//! estimate from [`SpectrumAccumulator`], in memory bounded by one
//! segment.

use crate::fourier::{Fourier, hann};

/// Why a spectrum could not be estimated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpectrumError {
    /// Fewer samples than the estimate needs.
    #[error("a record of {len} samples is too short for a spectrum: give at least {min}")]
    TooShort {
        /// Samples given.
        len: usize,
        /// Samples needed.
        min: usize,
    },
    /// A sample is NaN or infinite.
    #[error("sample {index} is {value}: the spectrum needs finite samples")]
    NonFinite {
        /// Index of the first such sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The sample rate is not a positive finite number.
    #[error("sample rate {value} Hz is invalid: it must be a positive finite number")]
    InvalidSampleRate {
        /// The offending value (Hz).
        value: f64,
    },
}

/// A one-sided power spectral density.
#[derive(Debug, Clone, PartialEq)]
pub struct PowerSpectrum {
    /// Bin frequencies (Hz), from 0 to Nyquist.
    pub frequencies_hz: Vec<f64>,
    /// Density per bin (signal unit² / Hz); `Σ density · resolution` is the
    /// record's mean square (Parseval).
    pub density: Vec<f64>,
    /// Bin spacing (Hz).
    pub resolution_hz: f64,
}

impl PowerSpectrum {
    /// The power (signal unit²) in `[lo, hi)` Hz.
    pub fn band_power(&self, lo: f64, hi: f64) -> f64 {
        self.frequencies_hz
            .iter()
            .zip(&self.density)
            .filter(|(f, _)| **f >= lo && **f < hi)
            .map(|(_, d)| d * self.resolution_hz)
            .sum()
    }

    /// The total power (the record's mean square, up to the window's
    /// leakage for Welch).
    pub fn total_power(&self) -> f64 {
        self.density.iter().sum::<f64>() * self.resolution_hz
    }
}

/// Longest Welch segment (samples): the resolution a long record gets,
/// and a bound on the estimate's memory whatever the record's length
/// (0.015 Hz at 1 kHz, 0.15 Hz at 10 kHz).
pub const MAX_SEGMENT: usize = 1 << 16;

/// The power spectral density of `x` sampled at `sample_rate_hz`
/// (periodogram of the whole record when `periodic`, else Welch).
pub fn power_spectrum(
    x: &[f64],
    sample_rate_hz: f64,
    periodic: bool,
) -> Result<PowerSpectrum, SpectrumError> {
    let mut acc = SpectrumAccumulator::new(x.len(), sample_rate_hz, periodic)?;
    for &v in x {
        acc.push(v)?;
    }
    acc.finish()
}

/// [`power_spectrum`] of a record that arrives sample by sample, in memory
/// bounded by its segment ([`MAX_SEGMENT`] samples unless `periodic`): the
/// segments are those of the whole record, so the estimate is the same.
pub struct SpectrumAccumulator {
    /// Segment length.
    len: usize,
    /// Samples between segment starts.
    step: usize,
    window: Vec<f64>,
    /// The last `len` samples, oldest at `next % len`.
    ring: Vec<f64>,
    segment: Vec<f64>,
    density: Vec<f64>,
    fourier: Fourier,
    sample_rate_hz: f64,
    /// Samples pushed.
    pushed: usize,
    /// Segments added.
    count: usize,
    min: usize,
}

impl SpectrumAccumulator {
    /// An estimate for a record of `record_len` samples at
    /// `sample_rate_hz` (the segment length depends on the length, so it
    /// is given first): the periodogram of the whole record when
    /// `periodic`, else Welch with Hann segments of the largest power of
    /// two up to half the record (at least 256, at most [`MAX_SEGMENT`])
    /// and half overlap.
    pub fn new(
        record_len: usize,
        sample_rate_hz: f64,
        periodic: bool,
    ) -> Result<Self, SpectrumError> {
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return Err(SpectrumError::InvalidSampleRate {
                value: sample_rate_hz,
            });
        }
        let min = if periodic { 4 } else { 512 };
        if record_len < min {
            return Err(SpectrumError::TooShort {
                len: record_len,
                min,
            });
        }
        let (len, window): (usize, Vec<f64>) = if periodic {
            (record_len, vec![1.0; record_len])
        } else {
            let mut l = 256;
            while 2 * l <= record_len / 2 && l < MAX_SEGMENT {
                l *= 2;
            }
            (l, hann(l))
        };
        Ok(Self {
            len,
            step: if periodic { len } else { len / 2 },
            window,
            ring: vec![0.0; len],
            segment: vec![0.0; len],
            density: vec![0.0; len / 2 + 1],
            fourier: Fourier::new(len),
            sample_rate_hz,
            pushed: 0,
            count: 0,
            min,
        })
    }

    /// Adds the next sample (a non-finite one is refused with its index).
    pub fn push(&mut self, x: f64) -> Result<(), SpectrumError> {
        if !x.is_finite() {
            return Err(SpectrumError::NonFinite {
                index: self.pushed,
                value: x,
            });
        }
        self.ring[self.pushed % self.len] = x;
        self.pushed += 1;
        if self.pushed >= self.len && (self.pushed - self.len).is_multiple_of(self.step) {
            let oldest = self.pushed % self.len;
            let (newer, older) = self.ring.split_at(oldest);
            for ((s, v), w) in self
                .segment
                .iter_mut()
                .zip(older.iter().chain(newer))
                .zip(&self.window)
            {
                *s = v * w;
            }
            self.fourier.add_power(&self.segment, &mut self.density);
            self.count += 1;
        }
        Ok(())
    }

    /// The estimate from the segments completed so far.
    pub fn finish(self) -> Result<PowerSpectrum, SpectrumError> {
        if self.count == 0 {
            return Err(SpectrumError::TooShort {
                len: self.pushed,
                min: self.len.max(self.min),
            });
        }
        let w2: f64 = self.window.iter().map(|w| w * w).sum();
        let (len, rate, count) = (self.len, self.sample_rate_hz, self.count as f64);
        let mut density = self.density;
        for (k, d) in density.iter_mut().enumerate() {
            // One-sided: the bins between 0 and Nyquist count twice.
            let twice = if k == 0 || 2 * k == len { 1.0 } else { 2.0 };
            *d *= twice / (w2 * rate * count);
        }
        let resolution_hz = rate / len as f64;
        Ok(PowerSpectrum {
            frequencies_hz: (0..density.len())
                .map(|k| k as f64 * resolution_hz)
                .collect(),
            density,
            resolution_hz,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parseval for the periodogram: the power adds up to the mean square;
    /// a sinusoid on a harmonic puts all of it in its bin.
    #[test]
    fn periodogram_is_exact_on_harmonics() {
        let (n, fs) = (1000, 1000.0);
        let x: Vec<f64> = (0..n)
            .map(|i| 0.3 + 2.0 * (2.0 * std::f64::consts::PI * 5.0 * i as f64 / fs).sin())
            .collect();
        let s = power_spectrum(&x, fs, true).unwrap();
        let ms = x.iter().map(|v| v * v).sum::<f64>() / n as f64;
        assert!((s.total_power() - ms).abs() < 1e-12 * ms);
        assert!(
            (s.band_power(4.5, 5.5) - 2.0).abs() < 1e-12,
            "{}",
            s.band_power(4.5, 5.5)
        );
        assert!((s.band_power(0.0, 0.5) - 0.09).abs() < 1e-12);
    }

    /// Welch on white noise: flat at `σ² / (fs/2)` per Hz, within the
    /// estimate's scatter (≈ 60 segments: a few % per bin averaged over
    /// bands of 100 bins).
    #[test]
    fn welch_of_white_noise_is_flat() {
        let fs = 1000.0;
        // A deterministic, decorrelated sequence (xorshift), variance 1/3
        // of a uniform on [−1, 1].
        let mut s = 0x9E37_79B9_7F4A_7C15_u64;
        let x: Vec<f64> = (0..65_536)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            })
            .collect();
        let p = power_spectrum(&x, fs, false).unwrap();
        let want = (1.0 / 3.0) / (fs / 2.0);
        for lo in [50.0, 200.0, 400.0] {
            let band = p.band_power(lo, lo + 50.0) / 50.0;
            assert!((band / want - 1.0).abs() < 0.1, "{lo} Hz: {band} vs {want}");
        }
    }

    /// The accumulator's segments are the whole record's: against a
    /// direct loop over the Hann segments of a record four times the
    /// segment cap (seven half-overlapping segments).
    #[test]
    fn long_records_take_capped_segments_like_a_direct_loop() {
        let fs = 1000.0;
        let n = 4 * MAX_SEGMENT + 12_345;
        let mut s = 0x2545_F491_4F6C_DD1D_u64;
        let x: Vec<f64> = (0..n)
            .map(|i| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let u = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                u + (std::f64::consts::TAU * 3.0 * i as f64 / fs).sin()
            })
            .collect();
        let p = power_spectrum(&x, fs, false).unwrap();
        let len = MAX_SEGMENT;
        assert_eq!(p.density.len(), len / 2 + 1);
        let w = hann(len);
        let w2: f64 = w.iter().map(|v| v * v).sum();
        let mut f = Fourier::new(len);
        let mut want = vec![0.0; len / 2 + 1];
        let mut count = 0;
        let mut start = 0;
        while start + len <= n {
            let seg: Vec<f64> = x[start..start + len]
                .iter()
                .zip(&w)
                .map(|(a, b)| a * b)
                .collect();
            f.add_power(&seg, &mut want);
            count += 1;
            start += len / 2;
        }
        assert_eq!(count, 7);
        for (k, (got, d)) in p.density.iter().zip(&want).enumerate() {
            let twice = if k == 0 || 2 * k == len { 1.0 } else { 2.0 };
            let d = d * twice / (w2 * fs * count as f64);
            assert!(
                (got - d).abs() <= 1e-12 * d.abs().max(1e-9),
                "bin {k}: {got} vs {d}"
            );
        }
    }

    #[test]
    fn bad_input_is_named() {
        assert!(matches!(
            power_spectrum(&[1.0; 100], 1000.0, false),
            Err(SpectrumError::TooShort { .. })
        ));
        assert!(matches!(
            power_spectrum(&[1.0, f64::NAN, 1.0, 1.0], 1000.0, true),
            Err(SpectrumError::NonFinite { index: 1, .. })
        ));
        assert!(matches!(
            power_spectrum(&[1.0; 8], 0.0, true),
            Err(SpectrumError::InvalidSampleRate { .. })
        ));
    }
}
