//! The autocorrelation of a record that arrives in pieces, over a fixed
//! number of lags, in memory bounded by the lag count: the whiteness and
//! correlation-time statistics of a residual as long as a log.
//!
//! Lagged products are summed block by block with FFTs (a block against
//! itself and the `max_lag` samples after it), so the cost is
//! O(n log max_lag), not the direct sum's O(n · max_lag).

use std::sync::Arc;

use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};

/// Sums `Σ_t x_t x_{t+k}` for `k = 0..=max_lag` over a record pushed in
/// order, and from them the sample autocorrelation
/// `ρ_k = Σ (x_t − x̄)(x_{t+k} − x̄) / Σ (x_t − x̄)²`.
pub struct Autocorrelation {
    max_lag: usize,
    /// Samples per block (the FFT length less `max_lag`).
    block: usize,
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    a: Vec<Complex64>,
    b: Vec<Complex64>,
    scratch: Vec<Complex64>,
    /// Samples (less `shift`) not yet summed as a block's first factor.
    pending: Vec<f64>,
    /// `Σ_t y_t y_{t+k}` of the shifted samples `y = x − shift`.
    products: Vec<f64>,
    /// The first sample: shifting by it keeps the sums' cancellation
    /// small when the mean is far from zero.
    shift: Option<f64>,
    /// The first `max_lag` shifted samples.
    head: Vec<f64>,
    /// The last `max_lag` shifted samples, oldest at `n % max_lag`.
    tail: Vec<f64>,
    sum: f64,
    n: usize,
}

impl Autocorrelation {
    /// An accumulator of the autocorrelation at lags `1..=max_lag`.
    pub fn new(max_lag: usize) -> Self {
        let size = (4 * max_lag).max(256).next_power_of_two();
        let mut planner = FftPlanner::new();
        let forward = planner.plan_fft_forward(size);
        let inverse = planner.plan_fft_inverse(size);
        let scratch = forward
            .get_inplace_scratch_len()
            .max(inverse.get_inplace_scratch_len());
        let zero = Complex64::new(0.0, 0.0);
        Self {
            max_lag,
            block: size - max_lag,
            forward,
            inverse,
            a: vec![zero; size],
            b: vec![zero; size],
            scratch: vec![zero; scratch],
            pending: Vec::with_capacity(size),
            products: vec![0.0; max_lag + 1],
            shift: None,
            head: Vec::with_capacity(max_lag),
            tail: vec![0.0; max_lag],
            sum: 0.0,
            n: 0,
        }
    }

    /// Samples pushed.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Adds the next sample (the caller checks finiteness: a non-finite
    /// sample makes every lag non-finite).
    pub fn push(&mut self, x: f64) {
        let y = x - *self.shift.get_or_insert(x);
        if self.head.len() < self.max_lag {
            self.head.push(y);
        }
        if self.max_lag > 0 {
            self.tail[self.n % self.max_lag] = y;
        }
        self.sum += y;
        self.n += 1;
        self.pending.push(y);
        if self.pending.len() == self.block + self.max_lag {
            self.sum_block(self.block);
        }
    }

    /// Sums the products whose first factor is one of the first `first`
    /// pending samples (the second within `max_lag` after it, all pending),
    /// and drops those samples.
    fn sum_block(&mut self, first: usize) {
        let zero = Complex64::new(0.0, 0.0);
        for (i, (a, b)) in self.a.iter_mut().zip(self.b.iter_mut()).enumerate() {
            let y = self.pending.get(i).copied();
            *a = y.map_or(zero, |v| Complex64::new(v, 0.0));
            *b = if i < first { *a } else { zero };
        }
        self.forward
            .process_with_scratch(&mut self.a, &mut self.scratch);
        self.forward
            .process_with_scratch(&mut self.b, &mut self.scratch);
        for (a, b) in self.a.iter_mut().zip(&self.b) {
            *a *= b.conj();
        }
        self.inverse
            .process_with_scratch(&mut self.a, &mut self.scratch);
        let scale = 1.0 / self.a.len() as f64;
        for (p, c) in self.products.iter_mut().zip(&self.a) {
            *p += c.re * scale;
        }
        self.pending.drain(..first);
    }

    /// `ρ_1..=ρ_max_lag` (0 for a lag at or beyond the record's length, and
    /// for every lag of a constant record).
    pub fn finish(mut self) -> Vec<f64> {
        while !self.pending.is_empty() {
            let first = self.block.min(self.pending.len());
            self.sum_block(first);
        }
        let n = self.n;
        if n < 2 {
            return vec![0.0; self.max_lag];
        }
        let m = self.sum / n as f64;
        let c0 = self.products[0] - n as f64 * m * m;
        if c0 <= 0.0 {
            return vec![0.0; self.max_lag];
        }
        let (mut first_k, mut last_k) = (0.0, 0.0);
        (1..=self.max_lag)
            .map(|k| {
                if k >= n {
                    return 0.0;
                }
                // Σ_{t<n−k} y_t and Σ_{t≥k} y_t from the record's sum less
                // its last or first k samples.
                first_k += self.head[k - 1];
                last_k += self.tail[(n - k) % self.max_lag];
                let ck = self.products[k] - m * (2.0 * self.sum - first_k - last_k)
                    + (n - k) as f64 * m * m;
                ck / c0
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The direct definition.
    fn direct(x: &[f64], max_lag: usize) -> Vec<f64> {
        let n = x.len();
        let m = x.iter().sum::<f64>() / n as f64;
        let c0: f64 = x.iter().map(|v| (v - m) * (v - m)).sum();
        (1..=max_lag)
            .map(|k| {
                if k >= n || c0 == 0.0 {
                    return 0.0;
                }
                x[..n - k]
                    .iter()
                    .zip(&x[k..])
                    .map(|(a, b)| (a - m) * (b - m))
                    .sum::<f64>()
                    / c0
            })
            .collect()
    }

    proptest! {
        /// Block sums equal the direct sums at every lag, for records
        /// shorter than a lag, one block, and many blocks, with an offset
        /// far from zero (|ρ_k| ≤ 1: 1e-11 absolute is rounding of sums
        /// of up to 10⁴ products).
        #[test]
        fn equals_the_direct_sums(
            max_lag in 1usize..300,
            len in 1usize..3000,
            offset in -100.0f64..100.0,
            seed in any::<u64>(),
        ) {
            let mut s = seed | 1;
            let x: Vec<f64> = (0..len)
                .map(|i| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    offset + (i as f64 * 0.05).sin() + (s >> 11) as f64 / (1u64 << 53) as f64
                })
                .collect();
            let mut acc = Autocorrelation::new(max_lag);
            for &v in &x {
                acc.push(v);
            }
            prop_assert_eq!(acc.len(), len);
            let got = acc.finish();
            let want = direct(&x, max_lag);
            prop_assert_eq!(got.len(), max_lag);
            for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                prop_assert!((g - w).abs() < 1e-11, "lag {}: {} vs {}", k + 1, g, w);
            }
        }
    }

    #[test]
    fn constant_and_tiny_records_have_no_correlation() {
        let mut acc = Autocorrelation::new(5);
        for _ in 0..100 {
            acc.push(3.0);
        }
        assert_eq!(acc.finish(), vec![0.0; 5]);
        let mut acc = Autocorrelation::new(5);
        acc.push(1.0);
        assert_eq!(acc.finish(), vec![0.0; 5]);
    }
}
