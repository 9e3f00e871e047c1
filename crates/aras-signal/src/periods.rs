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
///
/// The averages are [`PeriodSums`]'s, fed the record row by row, so a log
/// averaged while it is read gives the same numbers.
pub fn average_periods(
    channels: &[&[f64]],
    dt: f64,
    period_s: f64,
    settling_s: f64,
) -> Result<PeriodAverage, ProcessError> {
    let n = channels.first().map_or(0, |c| c.len());
    let mut sums = PeriodSums::new(channels.len(), dt, period_s, settling_s, Some(n))?;
    let used = sums.start
        + sums
            .candidates
            .first()
            .map_or(0, |c| c.blocks_fit(n, sums.start) * c.per);
    let mut row = vec![0.0; channels.len()];
    for i in sums.start..used {
        for (r, ch) in row.iter_mut().zip(channels) {
            *r = ch[i];
        }
        sums.push_at(i, &row);
    }
    sums.seen = n;
    let mean = sums.finish()?;
    let per = mean.samples_per_block;
    let mut out = PeriodAverage {
        periods_per_block: mean.periods_per_block,
        samples_per_block: per,
        blocks: mean.blocks,
        start: mean.start,
        tail: mean.tail,
        channels: Vec::with_capacity(channels.len()),
        spread_rms: Vec::new(),
        spread_relative: Vec::new(),
        worst_block: Vec::new(),
    };
    for (ch, mean) in channels.iter().zip(mean.channels) {
        let data = &ch[out.start..out.start + out.blocks * per];
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

/// The block [`average_periods`] averages: the smallest `k` (periods per
/// block) whose block of `samples` is whole within [`MAX_BLOCK_MISMATCH`]
/// and drifts at most [`MAX_DRIFT`] over the `blocks` that fit in
/// `available` samples, as `(k, samples, blocks)`.
fn choose_block(exact: f64, available: usize) -> Option<(usize, usize, usize)> {
    for k in 1..=MAX_PERIODS_PER_BLOCK {
        let block_exact = k as f64 * exact;
        let block = block_exact.round() as usize;
        if block > available {
            return None;
        }
        let mismatch = (block_exact - block as f64).abs();
        let blocks = available / block;
        if mismatch <= MAX_BLOCK_MISMATCH && mismatch * blocks as f64 <= MAX_DRIFT {
            return Some((k, block, blocks));
        }
    }
    None
}

/// Samples of the candidate blocks [`PeriodSums`] holds at most while the
/// record's length is unknown (per channel, twice: the sums and the block
/// being read): 2²² samples, 70 min at 1 kHz.
pub const MAX_STREAMED_BLOCK_SAMPLES: usize = 1 << 22;

/// The average block of a record, without the spread (which needs the
/// record twice): what [`PeriodSums::finish`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodMean {
    /// Periods per block (see [`PeriodAverage::periods_per_block`]).
    pub periods_per_block: usize,
    /// Samples per block.
    pub samples_per_block: usize,
    /// Whole blocks averaged.
    pub blocks: usize,
    /// Index of the first sample used (after the settling time).
    pub start: usize,
    /// Samples after the last whole block, not used.
    pub tail: usize,
    /// The averaged block, per channel.
    pub channels: Vec<Vec<f64>>,
}

/// Period averaging fed one row (every channel's sample) at a time: the
/// rule of [`average_periods`] for a record too long to hold.
///
/// Until the record ends its length is unknown, and with it the block the
/// rule picks (a block that is whole only to 0.03 samples is used on a
/// short record and refused, for its drift, on a long one). So every block
/// the rule could still pick is summed: the `k` whose mismatch is within
/// [`MAX_BLOCK_MISMATCH`], up to the first that is whole (or the
/// [`MAX_STREAMED_BLOCK_SAMPLES`] budget), each dropped once its drift
/// exceeds [`MAX_DRIFT`]. For a period of a whole number of samples that is
/// one period; for 0.7 Hz at 1 kHz one block of 7 periods.
#[derive(Debug, Clone)]
pub struct PeriodSums {
    channels: usize,
    exact: f64,
    dt: f64,
    period_s: f64,
    settling_s: f64,
    start: usize,
    seen: usize,
    /// The blocks still possible, smallest `k` first.
    candidates: Vec<BlockSums>,
    /// The smallest `k` the budget left out (0: none).
    beyond_budget: usize,
}

/// One candidate block's sums.
#[derive(Debug, Clone)]
struct BlockSums {
    k: usize,
    per: usize,
    mismatch: f64,
    /// `sums[c·per + i]`: channel `c`'s sum at phase `i` over whole blocks.
    sums: Vec<f64>,
    /// The block being read, same layout.
    current: Vec<f64>,
    blocks: usize,
}

impl BlockSums {
    fn new(k: usize, exact: f64, channels: usize) -> Self {
        let block_exact = k as f64 * exact;
        let per = block_exact.round() as usize;
        Self {
            k,
            per,
            mismatch: (block_exact - per as f64).abs(),
            sums: vec![0.0; per * channels],
            current: vec![0.0; per * channels],
            blocks: 0,
        }
    }

    /// Whole blocks in a record of `n` samples starting at `start`.
    fn blocks_fit(&self, n: usize, start: usize) -> usize {
        n.saturating_sub(start) / self.per
    }

    /// True while the rule can still pick this block.
    fn drift_ok(&self) -> bool {
        self.mismatch * self.blocks as f64 <= MAX_DRIFT
    }
}

impl PeriodSums {
    /// Sums for `channels` channels at step `dt` over the period `period_s`
    /// after `settling_s` seconds. `total`, the record's length if known,
    /// fixes the block at once (one candidate, as [`average_periods`]).
    /// Errors as [`average_periods`] for bad settings (and, with `total`,
    /// for a record without a block).
    pub fn new(
        channels: usize,
        dt: f64,
        period_s: f64,
        settling_s: f64,
        total: Option<usize>,
    ) -> Result<Self, ProcessError> {
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
        let exact = period_s / dt;
        if exact.round() < 3.0 {
            return Err(ProcessError::TooShort {
                what: "period averaging".into(),
                have: exact.round() as usize,
                need: 3,
                hint: "a period must span at least 3 samples".into(),
            });
        }
        let mut sums = Self {
            channels,
            exact,
            dt,
            period_s,
            settling_s,
            start: (settling_s / dt).round() as usize,
            seen: 0,
            candidates: Vec::new(),
            beyond_budget: 0,
        };
        if let Some(n) = total {
            let (k, _, _) = sums.choice(n)?;
            sums.candidates.push(BlockSums::new(k, exact, channels));
            return Ok(sums);
        }
        let mut budget = MAX_STREAMED_BLOCK_SAMPLES;
        for k in 1..=MAX_PERIODS_PER_BLOCK {
            let block_exact = k as f64 * exact;
            let per = block_exact.round() as usize;
            let mismatch = (block_exact - per as f64).abs();
            if mismatch > MAX_BLOCK_MISMATCH {
                continue;
            }
            if per > budget {
                sums.beyond_budget = k;
                break;
            }
            budget -= per;
            sums.candidates.push(BlockSums::new(k, exact, channels));
            // A block whole to 1e-9 samples cannot drift half a sample
            // over any record: no larger k is ever picked.
            if mismatch <= 1e-9 {
                break;
            }
        }
        Ok(sums)
    }

    /// Channels per row.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Index of the first row that is summed (after the settling time).
    pub fn start(&self) -> usize {
        self.start
    }

    /// Samples of the largest block still summed: the rows after
    /// [`PeriodSums::start`] whose times the averaged block can need.
    pub fn largest_block(&self) -> usize {
        self.candidates.iter().map(|c| c.per).max().unwrap_or(0)
    }

    /// Adds the next row, one value per channel. Panics if `row` does not
    /// have [`PeriodSums::channels`] values.
    pub fn push(&mut self, row: &[f64]) {
        let i = self.seen;
        self.seen += 1;
        if i >= self.start {
            self.push_at(i, row);
        }
    }

    fn push_at(&mut self, i: usize, row: &[f64]) {
        assert_eq!(
            row.len(),
            self.channels,
            "PeriodSums::push: one value per channel"
        );
        let g = i - self.start;
        let mut completed = false;
        for c in &mut self.candidates {
            let phase = g % c.per;
            for (ch, v) in row.iter().enumerate() {
                c.current[ch * c.per + phase] = *v;
            }
            if phase + 1 == c.per {
                for (s, v) in c.sums.iter_mut().zip(&c.current) {
                    *s += v;
                }
                c.blocks += 1;
                completed = true;
            }
        }
        // A candidate's drift grows only when one of its blocks completes;
        // once it is too far for a record of this length it never comes
        // back.
        if completed {
            self.candidates.retain(|c| c.drift_ok());
        }
    }

    /// The rule of [`average_periods`] for a record of `n` rows.
    fn choice(&self, n: usize) -> Result<(usize, usize, usize), ProcessError> {
        let available = n.saturating_sub(self.start);
        let first = self.exact.round() as usize;
        if available < first {
            return Err(ProcessError::TooShort {
                what: format!(
                    "period averaging (period {} s after {} s settling)",
                    self.period_s, self.settling_s
                ),
                have: n,
                need: self.start + first,
                hint: "record at least one whole period after the settling time".into(),
            });
        }
        choose_block(self.exact, available).ok_or_else(|| {
            let periods = available as f64 / self.exact;
            ProcessError::PeriodNotWhole {
                period_s: self.period_s,
                samples: self.exact,
                step_s: self.dt,
                drift: (self.exact - self.exact.round()).abs() * periods.floor(),
            }
        })
    }

    /// The average of the block [`average_periods`] would pick for the rows
    /// pushed. Errors as [`average_periods`]; [`ProcessError::InvalidOption`]
    /// when that block is longer than the streaming budget.
    pub fn finish(self) -> Result<PeriodMean, ProcessError> {
        let (k, per, blocks) = self.choice(self.seen)?;
        let Some(c) = self.candidates.into_iter().find(|c| c.k == k) else {
            return Err(ProcessError::InvalidOption {
                name: "period",
                value: self.period_s.to_string(),
                reason: format!(
                    "its whole block is {k} periods ({per} samples) at step {} s, more than \
                     the {MAX_STREAMED_BLOCK_SAMPLES} samples averaged while reading (smallest \
                     left out: {} periods); give the period to more digits, resample, or \
                     process the log in memory",
                    self.dt, self.beyond_budget
                ),
            });
        };
        debug_assert_eq!((c.per, c.blocks), (per, blocks));
        let inv = 1.0 / c.blocks as f64;
        let channels = c
            .sums
            .chunks_exact(per)
            .map(|s| s.iter().map(|v| v * inv).collect())
            .collect();
        Ok(PeriodMean {
            periods_per_block: k,
            samples_per_block: per,
            blocks,
            start: self.start,
            tail: self.seen - self.start - blocks * per,
            channels,
        })
    }
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

    /// Streams `x` through [`PeriodSums`] without telling it the length.
    fn streamed(x: &[f64], dt: f64, period: f64) -> Result<PeriodMean, ProcessError> {
        let mut s = PeriodSums::new(1, dt, period, 0.0, None)?;
        for v in x {
            s.push(&[*v]);
        }
        s.finish()
    }

    #[test]
    fn a_block_whole_only_to_a_few_hundredths_is_used_until_it_drifts() {
        // 100.04 samples: one period is whole within 0.04, and drifts more
        // than half a sample after 12 periods; 24 periods (2400.96 samples)
        // are whole within 0.04 too. 1300 samples hold 13 periods and no
        // block of 24; while reading, the one-period sums are dropped.
        let x: Vec<f64> = (0..6000).map(|i| (i as f64 * 0.37).sin()).collect();
        assert!(matches!(
            streamed(&x[..1300], 0.01, 1.0004),
            Err(ProcessError::PeriodNotWhole { .. })
        ));
        for (n, k) in [(1000, 1), (1200, 1), (2600, 24), (6000, 24)] {
            let a = average_periods(&[&x[..n]], 0.01, 1.0004, 0.0).unwrap();
            let s = streamed(&x[..n], 0.01, 1.0004).unwrap();
            assert_eq!(a.periods_per_block, k, "{n} samples");
            assert_eq!(
                (s.periods_per_block, s.blocks, s.tail),
                (a.periods_per_block, a.blocks, a.tail)
            );
            assert_eq!(s.channels, a.channels, "{n} samples: bit for bit");
        }
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

        /// Averaging while reading, without the length, gives the in-memory
        /// average bit for bit, or the same error.
        #[test]
        fn streamed_sums_equal_the_in_memory_average(
            samples in 3.0f64..400.0, n in 0usize..4000, seed in 0u64..1000
        ) {
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let x: Vec<f64> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
            let dt = 1e-3;
            let period = samples * dt;
            match (average_periods(&[&x], dt, period, 0.0), streamed(&x, dt, period)) {
                (Ok(a), Ok(s)) => {
                    proptest::prop_assert_eq!(
                        (s.periods_per_block, s.samples_per_block, s.blocks, s.tail),
                        (a.periods_per_block, a.samples_per_block, a.blocks, a.tail)
                    );
                    proptest::prop_assert_eq!(&s.channels, &a.channels);
                }
                (Err(a), Err(s)) => proptest::prop_assert_eq!(a.to_string(), s.to_string()),
                (a, s) => proptest::prop_assert!(false, "{:?} vs {:?}", a.is_ok(), s.is_ok()),
            }
        }
    }
}
