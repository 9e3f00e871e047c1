//! A fine histogram of one axis (count and residual sum per bin) whose
//! range grows as samples arrive: the residual profiles of a data set of
//! any length in fixed memory. Profile bins (quantile or uniform) are unions
//! of its fine bins, so their counts and means are exact and their edges
//! within one fine bin of the asked-for ones.

/// Fine bins: a profile edge lands within 1/1024 of the axis' extent of
/// where it is asked for (the range grows by doubling, so at least half
/// the bins span the samples).
pub(crate) const FINE: usize = 2048;

/// Count and residual sum per fine bin of width `2^e`, bin `i` covering
/// `[i 2^e, (i + 1) 2^e)`; [`FINE`] consecutive bins from `first`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Histogram {
    e: i32,
    first: i64,
    count: Vec<u64>,
    sum: Vec<f64>,
    n: u64,
    min: f64,
    max: f64,
}

/// One bin of a profile: edges, samples and residual sum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Coarse {
    pub lo: f64,
    pub hi: f64,
    pub count: u64,
    pub sum: f64,
}

/// Bin index of `x` at width `2^e` (scaling by a power of two is exact).
fn index(x: f64, e: i32) -> i64 {
    (x * (-e as f64).exp2()).floor() as i64
}

/// `⌊i / 2^d⌋` for any `d ≥ 0`.
fn halve(i: i64, d: i32) -> i64 {
    if d >= 63 { i >> 63 } else { i >> d }
}

impl Histogram {
    /// Adds axis value `x` with residual `r` (`x` finite).
    pub fn push(&mut self, x: f64, r: f64) {
        if self.n == 0 {
            // A resolution far finer than the value: coarsened as the
            // samples spread.
            self.e = if x == 0.0 {
                -60
            } else {
                x.abs().log2().floor() as i32 - 40
            };
            self.first = index(x, self.e) - (FINE / 2) as i64;
            self.count = vec![0; FINE];
            self.sum = vec![0.0; FINE];
            self.min = x;
            self.max = x;
        }
        // Indices stay far inside i64.
        let big = x.abs() * (-self.e as f64).exp2();
        if big >= (1u64 << 60) as f64 {
            self.coarsen(big.log2().ceil() as i32 - 59);
        }
        self.min = self.min.min(x);
        self.max = self.max.max(x);
        let mut i = index(x, self.e);
        while i < self.first || i >= self.first + FINE as i64 {
            let (lo, hi) = (index(self.min, self.e), index(self.max, self.e));
            let span = (hi - lo + 1) as u64;
            if span > FINE as u64 {
                let d = (span.div_ceil(FINE as u64))
                    .next_power_of_two()
                    .trailing_zeros();
                self.coarsen(d as i32);
            } else {
                // Re-centre the occupied span, leaving room on both sides.
                self.shift_to(lo - ((FINE as u64 - span) / 2) as i64);
            }
            i = index(x, self.e);
        }
        let k = (i - self.first) as usize;
        self.count[k] += 1;
        self.sum[k] += r;
        self.n += 1;
    }

    /// Bins `2^d` times as wide.
    fn coarsen(&mut self, d: i32) {
        let first = halve(self.first, d);
        let (mut count, mut sum) = (vec![0; FINE], vec![0.0; FINE]);
        for k in 0..FINE {
            let j = (halve(self.first + k as i64, d) - first) as usize;
            count[j] += self.count[k];
            sum[j] += self.sum[k];
        }
        self.e += d;
        self.first = first;
        self.count = count;
        self.sum = sum;
    }

    /// Moves the window to start at bin `first` (every occupied bin stays
    /// inside).
    fn shift_to(&mut self, first: i64) {
        let (mut count, mut sum) = (vec![0; FINE], vec![0.0; FINE]);
        for k in 0..FINE {
            if self.count[k] > 0 {
                let j = (self.first + k as i64 - first) as usize;
                count[j] = self.count[k];
                sum[j] = self.sum[k];
            }
        }
        self.first = first;
        self.count = count;
        self.sum = sum;
    }

    /// Fine bin (window index) holding the sample of rank `r` (0-based).
    fn rank_bin(&self, r: u64) -> usize {
        let mut seen = 0;
        for (k, c) in self.count.iter().enumerate() {
            seen += c;
            if seen > r {
                return k;
            }
        }
        FINE - 1
    }

    /// Lower edge of window bin `k`.
    fn edge(&self, k: usize) -> f64 {
        (self.first + k as i64) as f64 * (self.e as f64).exp2()
    }

    /// Profile bins from the window-bin cuts `cuts` (increasing; the
    /// first bin starts at the smallest sample, the last ends at the
    /// largest), empty ones left out.
    fn coarse(&self, cuts: &[usize]) -> Vec<Coarse> {
        let mut cuts: Vec<usize> = cuts.to_vec();
        cuts.insert(0, 0);
        cuts.push(FINE);
        cuts.sort_unstable();
        cuts.dedup();
        cuts.windows(2)
            .filter_map(|w| {
                let count: u64 = self.count[w[0]..w[1]].iter().sum();
                (count > 0).then(|| Coarse {
                    lo: self.edge(w[0]).clamp(self.min, self.max),
                    hi: self.edge(w[1]).clamp(self.min, self.max),
                    count,
                    sum: self.sum[w[0]..w[1]].iter().sum(),
                })
            })
            .collect()
    }

    /// `bins` bins of about equal counts: cut at the fine bins holding the
    /// samples of rank `(n − 1) i / bins`.
    pub fn quantile_bins(&self, bins: usize) -> Vec<Coarse> {
        if self.n == 0 {
            return Vec::new();
        }
        let cuts: Vec<usize> = (1..bins)
            .map(|i| self.rank_bin((self.n - 1) * i as u64 / bins as u64))
            .collect();
        self.coarse(&cuts)
    }

    /// `bins` bins of about equal width between the smallest and largest
    /// sample.
    pub fn uniform_bins(&self, bins: usize) -> Vec<Coarse> {
        if self.n == 0 {
            return Vec::new();
        }
        let cuts: Vec<usize> = (1..bins)
            .map(|i| {
                let x = self.min + (self.max - self.min) * i as f64 / bins as f64;
                (index(x, self.e) - self.first).clamp(0, FINE as i64 - 1) as usize
            })
            .collect();
        self.coarse(&cuts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn check(h: &Histogram, x: &[f64], r: &[f64], bins: &[Coarse]) -> Result<(), TestCaseError> {
        prop_assert_eq!(bins.iter().map(|b| b.count).sum::<u64>(), x.len() as u64);
        prop_assert!(bins.windows(2).all(|w| w[0].hi <= w[1].lo));
        let (lo, hi) = (h.min, h.max);
        prop_assert_eq!(bins[0].lo, lo);
        prop_assert_eq!(bins[bins.len() - 1].hi, hi);
        // Every sample lies in one bin's edges, and the bin sums are the
        // samples' (the bins partition the fine bins).
        let total: f64 = r.iter().sum();
        let binned: f64 = bins.iter().map(|b| b.sum).sum();
        prop_assert!(
            (total - binned).abs() <= 1e-9 * (1.0 + r.iter().map(|v| v.abs()).sum::<f64>())
        );
        for v in x {
            prop_assert!(
                bins.iter().any(|b| b.lo <= *v && *v <= b.hi),
                "{} outside",
                v
            );
        }
        Ok(())
    }

    proptest! {
        /// Quantile bins of samples arriving in any order: counts add up,
        /// every sample is inside its bin's edges, and each bin's count is
        /// within one fine bin's worth of samples of n / bins per edge.
        #[test]
        fn quantile_bins_partition_the_samples(
            x in proptest::collection::vec(-5.0f64..5.0, 1..2000),
            scale in prop_oneof![Just(1e-6), Just(1.0), Just(1e6)],
            offset in -10.0f64..10.0,
        ) {
            let x: Vec<f64> = x.iter().map(|v| offset * scale + v * scale).collect();
            let r: Vec<f64> = x.iter().enumerate().map(|(i, _)| (i % 7) as f64 - 3.0).collect();
            let mut h = Histogram::default();
            for (a, b) in x.iter().zip(&r) {
                h.push(*a, *b);
            }
            prop_assert_eq!(h.n, x.len() as u64);
            let bins = h.quantile_bins(8);
            check(&h, &x, &r, &bins)?;
            let fine_max = *h.count.iter().max().unwrap();
            let n = x.len() as f64;
            for b in &bins {
                prop_assert!(b.count as f64 <= n / 8.0 + 2.0 * fine_max as f64 + 1.0, "{:?}", b);
            }
            let bins = h.uniform_bins(8);
            check(&h, &x, &r, &bins)?;
        }

        /// A monotone drift (a time axis, an angle creeping one way) keeps
        /// the resolution: uniform bins' edges within 2/FINE of the span
        /// of where they are asked for.
        #[test]
        fn drifting_axes_keep_their_resolution(
            n in 10usize..5000,
            down in any::<bool>(),
            step in 1e-4f64..1.0,
        ) {
            let x: Vec<f64> = (0..n)
                .map(|i| if down { -(i as f64) * step } else { i as f64 * step })
                .collect();
            let mut h = Histogram::default();
            for v in &x {
                h.push(*v, 1.0);
            }
            let bins = h.uniform_bins(8);
            check(&h, &x, &vec![1.0; n], &bins)?;
            let span = h.max - h.min;
            for (i, b) in bins.iter().enumerate().skip(1) {
                let want = h.min + span * i as f64 / 8.0;
                prop_assert!((b.lo - want).abs() <= 2.0 * span / FINE as f64 + 1e-12 * span,
                    "edge {} at {} for {}", i, b.lo, want);
            }
        }
    }
}
