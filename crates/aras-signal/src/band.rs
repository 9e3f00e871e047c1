//! The band-limiting operator of a processed log, for applying to anything
//! computed from its samples (`docs/processing.md`, "Parallel filtering").
//!
//! Why: the processing band-limits the angles (a low-pass or a truncated
//! harmonic series) before differentiating them, so a torque predicted from
//! the processed motion has passed that operator in its inertial part but
//! not in its sign-like friction part, whose steps at velocity reversals
//! stay sharp while the estimated θ̈ that balances them in the measured
//! torque is smooth. Applying the same operator to the predicted torque
//! (as the identification applies it to τ and every regressor column)
//! makes both parts consistent: what is compared with the raw torque is
//! the band-limited torque of the model, which equals the measured torque
//! wherever the torque itself has no content beyond the band.

use rustfft::num_complex::Complex64;

use crate::error::ProcessError;
use crate::fourier::Fourier;
use crate::sos::Sos;

/// The operator [`process`](crate::process) applied to the angles, as it
/// acts on any per-sample series of the same [`Samples`](crate::Samples).
#[derive(Debug, Clone, PartialEq)]
pub enum BandLimit {
    /// Nothing was band-limited (logged derivatives, filtering off): the
    /// series is left as it is.
    None,
    /// A zero-phase low-pass, forward and backward (`periodic`: exactly
    /// circular, for one averaged block).
    LowPass {
        /// The filter.
        sos: Sos,
        /// Circular filtering of one averaged block.
        periodic: bool,
    },
    /// A truncated harmonic series of the period.
    Harmonics(HarmonicBand),
}

/// The harmonic band of a periodic record.
#[derive(Debug, Clone, PartialEq)]
pub struct HarmonicBand {
    /// Samples per averaged block.
    pub per: usize,
    /// Periods per block: only bins that are multiples of it are harmonics.
    pub periods_per_block: usize,
    /// The highest DFT bin kept (a multiple of `periods_per_block`).
    pub top_bin: usize,
    /// For a series of every log row: the first row of the first averaged
    /// block and the number of whole blocks (`None`: the series is one
    /// averaged block).
    pub rows: Option<(usize, usize)>,
    /// For a series of every log row: the low-pass of its aperiodic
    /// remainder (the series minus its periodic part), as the angles'
    /// remainder was filtered; `None` keeps the remainder as it is.
    pub remainder: Option<Sos>,
}

impl BandLimit {
    /// Applies the operator to `x` in place (`x` has one value per
    /// processed sample).
    ///
    /// # Errors
    /// [`ProcessError`] when `x` is too short for the filter or does not
    /// have the length of the operator's block.
    pub fn apply(&self, x: &mut [f64]) -> Result<(), ProcessError> {
        match self {
            BandLimit::None => Ok(()),
            BandLimit::LowPass { sos, periodic } => {
                let y = sos.filtfilt_record(x, *periodic).map_err(filter_error)?;
                x.copy_from_slice(&y);
                Ok(())
            }
            BandLimit::Harmonics(h) => h.apply(x),
        }
    }

    /// True when [`apply`](Self::apply) changes nothing.
    pub fn is_identity(&self) -> bool {
        matches!(self, BandLimit::None)
    }
}

impl HarmonicBand {
    fn apply(&self, x: &mut [f64]) -> Result<(), ProcessError> {
        let per = self.per;
        match self.rows {
            None => {
                if x.len() != per {
                    return Err(length_error(x.len(), per));
                }
                let mut f = Fourier::new(per);
                self.project(&mut f, x);
                Ok(())
            }
            Some((start, blocks)) => {
                if blocks == 0 || start + blocks * per > x.len() {
                    return Err(length_error(x.len(), start + blocks.max(1) * per));
                }
                // The periodic part: the block average, projected.
                let mut block = vec![0.0; per];
                for b in 0..blocks {
                    let s = &x[start + b * per..start + (b + 1) * per];
                    block.iter_mut().zip(s).for_each(|(a, v)| *a += v);
                }
                block.iter_mut().for_each(|a| *a /= blocks as f64);
                let mut f = Fourier::new(per);
                self.project(&mut f, &mut block);
                let at =
                    |r: usize| block[(r as i64 - start as i64).rem_euclid(per as i64) as usize];
                let mut rest: Vec<f64> = x.iter().enumerate().map(|(r, v)| v - at(r)).collect();
                if let Some(sos) = &self.remainder {
                    rest = sos.filtfilt_record(&rest, false).map_err(filter_error)?;
                }
                for (r, v) in x.iter_mut().enumerate() {
                    *v = at(r) + rest[r];
                }
                Ok(())
            }
        }
    }

    /// The fraction of white noise's power that the projection of one
    /// block keeps: the trace of the projection over `per`, `(1 + 2 ×
    /// harmonics kept) / per` (a harmonic on the Nyquist bin counts once).
    /// It is the `Σ h²` of a low-pass for this operator: what a white-noise
    /// σ and the independent fraction of the rows divide by after the
    /// projection.
    pub fn noise_gain(&self) -> f64 {
        let (kp, per) = (self.periods_per_block.max(1), self.per.max(1));
        let dims: usize = (1..=self.top_bin.min(per / 2))
            .filter(|a| a.is_multiple_of(kp))
            .map(|a| if 2 * a == per { 1 } else { 2 })
            .sum();
        (1 + dims) as f64 / per as f64
    }

    /// Keeps the mean and the harmonics up to `top_bin` of one block.
    fn project(&self, f: &mut Fourier, x: &mut [f64]) {
        let (kp, top) = (self.periods_per_block.max(1), self.top_bin);
        f.apply(x, |k| {
            let a = k.unsigned_abs() as usize;
            if a == 0 || (a.is_multiple_of(kp) && a <= top) {
                Complex64::new(1.0, 0.0)
            } else {
                Complex64::new(0.0, 0.0)
            }
        });
    }
}

fn filter_error(source: crate::FilterError) -> ProcessError {
    ProcessError::Filter {
        context: "band-limiting a series like the processed angles".into(),
        source,
    }
}

fn length_error(have: usize, need: usize) -> ProcessError {
    ProcessError::TooShort {
        what: "band-limiting a series like the processed angles".into(),
        have,
        need,
        hint: "give one value per processed sample (Processed::samples)".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Butterworth;
    use std::f64::consts::TAU;

    fn wave(n: usize, per: usize, harmonics: &[(usize, f64)]) -> Vec<f64> {
        (0..n)
            .map(|i| {
                harmonics
                    .iter()
                    .map(|&(m, a)| a * (TAU * (m * i) as f64 / per as f64).sin())
                    .sum::<f64>()
                    + 0.25
            })
            .collect()
    }

    /// The noise gain is the projection's `Σ h²`: applied to each unit
    /// impulse of the block, the squared outputs sum to the trace.
    #[test]
    fn harmonic_noise_gain_is_the_projections_trace() {
        for (per, kp, top) in [(96, 1, 7), (96, 3, 30), (64, 2, 32), (101, 1, 50)] {
            let band = HarmonicBand {
                per,
                periods_per_block: kp,
                top_bin: top,
                rows: None,
                remainder: None,
            };
            let mut sum = 0.0;
            for i in 0..per {
                let mut e = vec![0.0; per];
                e[i] = 1.0;
                band.apply(&mut e).unwrap();
                sum += e.iter().map(|v| v * v).sum::<f64>();
            }
            let g = band.noise_gain();
            assert!(
                (sum / per as f64 - g).abs() < 1e-12,
                "{per} {kp} {top}: {sum} vs {g}"
            );
        }
    }

    #[test]
    fn harmonic_projection_keeps_the_band_and_drops_the_rest() {
        let per = 400;
        let mut x = wave(per, per, &[(1, 1.0), (5, 0.1), (30, 0.05)]);
        let band = HarmonicBand {
            per,
            periods_per_block: 1,
            top_bin: 10,
            rows: None,
            remainder: None,
        };
        BandLimit::Harmonics(band).apply(&mut x).unwrap();
        let want = wave(per, per, &[(1, 1.0), (5, 0.1)]);
        let worst = x
            .iter()
            .zip(&want)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-12, "{worst}");
    }

    #[test]
    fn every_row_projection_repeats_the_periodic_part_and_keeps_a_slow_remainder() {
        // 5 blocks after 37 rows of lead-in, with a slow start-up transient
        // (aperiodic: it decays within the lead-in and the first block); a
        // 30th harmonic is outside the band.
        let (per, start, blocks) = (200, 37, 5);
        let n = start + blocks * per + 23;
        let transient = |i: usize| 0.05 * (-(i as f64) / 40.0).exp();
        let mut x: Vec<f64> = wave(n, per, &[(2, 1.0), (30, 0.02)])
            .iter()
            .enumerate()
            .map(|(i, v)| v + transient(i))
            .collect();
        let band = HarmonicBand {
            per,
            periods_per_block: 1,
            top_bin: 4,
            rows: Some((start, blocks)),
            remainder: Some(Butterworth::lowpass(4, 20.0, 1000.0).unwrap()),
        };
        BandLimit::Harmonics(band).apply(&mut x).unwrap();
        let want: Vec<f64> = wave(n, per, &[(2, 1.0)])
            .iter()
            .enumerate()
            .map(|(i, v)| v + transient(i))
            .collect();
        // The band is kept, the 30th harmonic (amplitude 0.02) is gone and
        // the transient survives: the error left is the transient's share in
        // the block average (at most its value at the first block's start
        // over the 5 blocks, 4.0e-3, plus the truncated series' overshoot
        // on that edge, bounded here by half as much again), decaying with
        // the transient.
        // Away from the record's last 50 rows, where the remainder's
        // zero-phase filter meets the record's end (its odd padding does
        // not cancel the 30th harmonic's last half cycle).
        let leak = transient(start) / blocks as f64;
        let inner = 0..n - 50;
        let worst = inner
            .clone()
            .map(|i| (x[i] - want[i]).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1.5 * leak, "{worst} vs {leak}");
        let late = (start + 2 * per..n - 50)
            .map(|i| (x[i] - want[i]).abs())
            .fold(0.0, f64::max);
        assert!(late < 5e-4, "{late}");
    }

    #[test]
    fn low_pass_is_the_zero_phase_filter() {
        let sos = Butterworth::lowpass(4, 10.0, 1000.0).unwrap();
        let x = wave(2000, 400, &[(1, 1.0), (40, 0.3)]);
        let mut y = x.clone();
        BandLimit::LowPass {
            sos: sos.clone(),
            periodic: false,
        }
        .apply(&mut y)
        .unwrap();
        assert_eq!(y, sos.filtfilt_record(&x, false).unwrap());
        let mut z = x.clone();
        BandLimit::None.apply(&mut z).unwrap();
        assert_eq!(z, x);
    }

    #[test]
    fn a_block_of_the_wrong_length_is_an_error() {
        let band = BandLimit::Harmonics(HarmonicBand {
            per: 100,
            periods_per_block: 1,
            top_bin: 3,
            rows: None,
            remainder: None,
        });
        assert!(band.apply(&mut [0.0; 99]).is_err());
    }
}
