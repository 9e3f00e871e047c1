//! Period averaging (`docs/processing.md`: 160 s = 16 periods of the excitation are
//! averaged to cut noise). For white noise of standard deviation σ the
//! average of N blocks has σ/√N.
//!
//! A period need not be a whole number of samples: 0.7 Hz at 1 kHz is
//! 1428.57 samples. What is averaged is then a **block** of the smallest
//! number `k` of periods that is a whole number of samples (7 periods of
//! 0.7 Hz = 10 000 samples), so every block starts at the same phase and the
//! averaged block is still one exact period of the (k-periodic) record.

use serde::Serialize;

use crate::error::ProcessError;

/// Largest mismatch (samples) between `k` periods and the whole number of
/// samples of a block. The averaged block is treated as periodic (periodic
/// filter, spectral derivative), so this mismatch is the time step at its
/// wrap-around: 0.05 samples moves a 2.5 Hz sinusoid at 1 kHz by 0.08 % of
/// its amplitude, below the encoder's resolution, while 5 periods of 0.7 Hz
/// (7142.857 samples, 0.14 off) are rejected in favour of 7 (10 000).
pub const MAX_BLOCK_MISMATCH: f64 = 0.05;

/// Largest accumulated drift (samples) of the block starts over the record.
pub const MAX_DRIFT: f64 = 0.5;

/// Most periods in one block that [`average_periods`] tries.
pub const MAX_PERIODS_PER_BLOCK: usize = 1000;

/// The average block of several channels.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodAverage {
    /// Periods in one block: the smallest `k` whose `k·P·fs` is a whole
    /// number of samples (within [`MAX_BLOCK_MISMATCH`]); 1 when the period
    /// itself is.
    pub periods_per_block: usize,
    /// Samples per block (`k·P·fs`, rounded).
    pub samples_per_block: usize,
    /// Whole blocks averaged.
    pub blocks: usize,
    /// Index of the first sample used (after the settling time).
    pub start: usize,
    /// Samples after the last whole block, not used.
    pub tail: usize,
    /// The averaged block, per channel.
    pub channels: Vec<Vec<f64>>,
    /// Per channel: largest RMS difference between one block and the
    /// average (channel units).
    pub spread_rms: Vec<f64>,
    /// Per channel: `spread_rms` relative to the standard deviation of the
    /// averaged block (0 for a constant channel that matches exactly).
    pub spread_relative: Vec<f64>,
    /// Per channel: index of the block with the largest spread.
    pub worst_block: Vec<usize>,
}

impl PeriodAverage {
    /// Whole periods averaged (`blocks · periods_per_block`).
    pub fn periods(&self) -> usize {
        self.blocks * self.periods_per_block
    }
}

/// Averages whole blocks of periods of `channels` (all of equal length,
/// uniform step `dt`), after dropping `settling_s` seconds.
///
/// A block is the smallest number `k` of periods that spans a whole number
/// of samples up to [`MAX_BLOCK_MISMATCH`], with the block starts drifting
/// by at most [`MAX_DRIFT`] samples over the record; at least one whole
/// block must remain. Errors: [`ProcessError::InvalidOption`] for a bad
/// period, step or settling time, [`ProcessError::TooShort`] when not even
/// one block (or a block of 3 samples) fits, [`ProcessError::PeriodNotWhole`]
/// when no `k` fits the record.
pub fn average_periods(
    channels: &[&[f64]],
    dt: f64,
    period_s: f64,
    settling_s: f64,
) -> Result<PeriodAverage, ProcessError> {
    let bad = |name, value: f64, reason: &str| ProcessError::InvalidOption {
        name,
        value: value.to_string(),
        reason: reason.into(),
    };
    if !(period_s.is_finite() && period_s > 0.0) {
        return Err(bad(
            "period",
            period_s,
            "the period must be a positive number of seconds",
        ));
    }
    if !(settling_s.is_finite() && settling_s >= 0.0) {
        return Err(bad(
            "settling_s",
            settling_s,
            "the settling time must be ≥ 0 s",
        ));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(bad(
            "sample step",
            dt,
            "the step must be a positive number of seconds",
        ));
    }
    let n = channels.first().map_or(0, |c| c.len());
    let exact = period_s / dt;
    if exact.round() < 3.0 {
        return Err(ProcessError::TooShort {
            what: "period averaging".into(),
            have: exact.round() as usize,
            need: 3,
            hint: "a period must span at least 3 samples".into(),
        });
    }
    let start = (settling_s / dt).round() as usize;
    let available = n.saturating_sub(start);
    let first = exact.round() as usize;
    if available < first {
        return Err(ProcessError::TooShort {
            what: format!("period averaging (period {period_s} s after {settling_s} s settling)"),
            have: n,
            need: start + first,
            hint: "record at least one whole period after the settling time".into(),
        });
    }
    // The smallest k whose block is whole (k = 1 for a whole period).
    let mut found = None;
    for k in 1..=MAX_PERIODS_PER_BLOCK {
        let block_exact = k as f64 * exact;
        let block = block_exact.round() as usize;
        if block > available {
            break;
        }
        let mismatch = (block_exact - block as f64).abs();
        let blocks = available / block;
        if mismatch <= MAX_BLOCK_MISMATCH && mismatch * blocks as f64 <= MAX_DRIFT {
            found = Some((k, block, blocks));
            break;
        }
    }
    let Some((k, per, blocks)) = found else {
        let periods = available as f64 / exact;
        return Err(ProcessError::PeriodNotWhole {
            period_s,
            samples: exact,
            step_s: dt,
            drift: (exact - exact.round()).abs() * periods.floor(),
        });
    };
    let mut out = PeriodAverage {
        periods_per_block: k,
        samples_per_block: per,
        blocks,
        start,
        tail: n - start - blocks * per,
        channels: Vec::with_capacity(channels.len()),
        spread_rms: Vec::new(),
        spread_relative: Vec::new(),
        worst_block: Vec::new(),
    };
    let inv = 1.0 / blocks as f64;
    for ch in channels {
        let data = &ch[start..start + blocks * per];
        let mut mean = vec![0.0; per];
        for p in data.chunks_exact(per) {
            for (m, v) in mean.iter_mut().zip(p) {
                *m += v;
            }
        }
        mean.iter_mut().for_each(|m| *m *= inv);
        let (mut worst, mut worst_k) = (0.0f64, 0);
        for (b, p) in data.chunks_exact(per).enumerate() {
            let ss: f64 = p.iter().zip(&mean).map(|(v, m)| (v - m).powi(2)).sum();
            let rms = (ss / per as f64).sqrt();
            if rms > worst {
                (worst, worst_k) = (rms, b);
            }
        }
        let mu = mean.iter().sum::<f64>() / per as f64;
        let sd = (mean.iter().map(|m| (m - mu).powi(2)).sum::<f64>() / per as f64).sqrt();
        let rel = if worst == 0.0 {
            0.0
        } else if sd > 0.0 {
            worst / sd
        } else {
            f64::INFINITY
        };
        out.channels.push(mean);
        out.spread_rms.push(worst);
        out.spread_relative.push(rel);
        out.worst_block.push(worst_k);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    #[test]
    fn averaging_reduces_white_noise_by_sqrt_n() {
        let (per, periods, sigma) = (4000, 16, 0.1);
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let clean: Vec<f64> = (0..per)
            .map(|i| (std::f64::consts::TAU * i as f64 / per as f64).sin())
            .collect();
        let noisy: Vec<f64> = (0..per * periods)
            .map(|i| {
                let e: f64 = StandardNormal.sample(&mut rng);
                clean[i % per] + sigma * e
            })
            .collect();
        let avg = average_periods(&[&noisy], 0.001, per as f64 * 0.001, 0.0).unwrap();
        assert_eq!(
            (avg.blocks, avg.periods_per_block, avg.tail),
            (periods, 1, 0)
        );
        let resid: f64 = avg.channels[0]
            .iter()
            .zip(&clean)
            .map(|(a, c)| (a - c).powi(2))
            .sum::<f64>()
            / per as f64;
        let expected = sigma / (periods as f64).sqrt();
        // The RMS of 4000 Gaussian samples estimates σ/√N with a relative
        // standard error of 1/√(2·4000) ≈ 1.1 %; 6 % is more than 5 standard
        // errors, yet a reduction by √(N/2) or √(2N) would be caught.
        assert!(
            (resid.sqrt() / expected - 1.0).abs() < 0.06,
            "{} vs {expected}",
            resid.sqrt()
        );
        // Each period's deviation from the average is the noise itself.
        assert!((avg.spread_rms[0] / sigma - 1.0).abs() < 0.1);
    }

    #[test]
    fn settling_tail_and_drift() {
        let x: Vec<f64> = (0..1050).map(|i| (i % 100) as f64).collect();
        let a = average_periods(&[&x], 0.01, 1.0, 0.2).unwrap();
        assert_eq!((a.start, a.blocks, a.tail), (20, 10, 30));
        // Starting at sample 20, every period is 20..99, 0..19: identical.
        assert_eq!(a.spread_rms[0], 0.0);
        assert_eq!(a.channels[0][0], 20.0);
        // 100.3 samples a period: 10 periods (1003 samples) are the first
        // whole block; 900 samples hold none, 1050 hold one.
        let b = average_periods(&[&x], 0.01, 1.003, 0.0).unwrap();
        assert_eq!(
            (b.periods_per_block, b.samples_per_block, b.blocks),
            (10, 1003, 1)
        );
        assert!(matches!(
            average_periods(&[&x[..900]], 0.01, 1.003, 0.0),
            Err(ProcessError::PeriodNotWhole { .. })
        ));
        assert!(matches!(
            average_periods(&[&x], 0.01, 20.0, 0.0),
            Err(ProcessError::TooShort { .. })
        ));
    }

    #[test]
    fn a_period_of_fractional_samples_is_averaged_in_whole_blocks() {
        // 0.7 Hz at 1 kHz: 1428.57 samples a period; 7 periods = 10 000.
        let f = 0.7;
        let dt = 0.001;
        let n = (16.0 / f / dt) as usize; // 22 857: 16 periods
        let x: Vec<f64> = (0..n)
            .map(|i| (std::f64::consts::TAU * f * i as f64 * dt).sin())
            .collect();
        let a = average_periods(&[&x], dt, 1.0 / f, 0.0).unwrap();
        assert_eq!(
            (a.periods_per_block, a.samples_per_block, a.blocks, a.tail),
            (7, 10_000, 2, 2_857)
        );
        assert_eq!(a.periods(), 14);
        // The blocks start at the same phase: their average is the signal
        // itself, to rounding (sin of arguments up to 2π·16).
        assert!(a.spread_rms[0] < 1e-12, "{}", a.spread_rms[0]);
        for (i, v) in a.channels[0].iter().enumerate() {
            let exact = (std::f64::consts::TAU * f * i as f64 * dt).sin();
            assert!((v - exact).abs() < 1e-12);
        }
        // Too short for one block of 7 periods (and 5 periods, 0.14 samples
        // off, are not accepted instead).
        assert!(matches!(
            average_periods(&[&x[..9_000]], dt, 1.0 / f, 0.0),
            Err(ProcessError::PeriodNotWhole { .. })
        ));
    }

    proptest::proptest! {
        /// For a period of `p/q` samples (`q` ≤ 12, in lowest terms), the
        /// block is exactly `q` periods (= `p` samples): no smaller `k`
        /// makes `k·p/q` whole within 0.05 (the nearest miss is `1/q` ≥ 0.083).
        #[test]
        fn block_is_the_smallest_whole_multiple(q in 1usize..=12, p0 in 30usize..400) {
            let gcd = |mut a: usize, mut b: usize| { while b != 0 { (a, b) = (b, a % b); } a };
            let p = (p0..).find(|p| gcd(*p, q) == 1).unwrap();
            let dt = 1e-3;
            let period = p as f64 / q as f64 * dt;
            let n = 3 * p + 17;
            let x: Vec<f64> = (0..n).map(|i| (i % p) as f64).collect();
            let a = average_periods(&[&x], dt, period, 0.0).unwrap();
            proptest::prop_assert_eq!(
                (a.periods_per_block, a.samples_per_block, a.blocks, a.tail),
                (q, p, 3, 17)
            );
            proptest::prop_assert_eq!(a.spread_rms[0], 0.0);
        }
    }
}
