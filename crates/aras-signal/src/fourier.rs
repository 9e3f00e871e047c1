//! Small wrapper around `rustfft` for operations on one period of a periodic
//! signal: multiply the spectrum by a real or imaginary factor and transform
//! back (the circular zero-phase filter, the spectral derivative), and the
//! segment power and window of the Welch estimates.

use std::sync::Arc;

use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};

/// The periodic Hann window of `len` samples, `0.5 − 0.5 cos(2π i / len)`:
/// the segments of both Welch estimates (the bandwidth rule's and
/// [`crate::power_spectrum`]'s).
pub(crate) fn hann(len: usize) -> Vec<f64> {
    (0..len)
        .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / len as f64).cos())
        .collect()
}

/// Forward/inverse FFT plans and buffers for one record length.
///
/// Build once per length and reuse: planning and the buffers are the only
/// allocations, applying a multiplier allocates nothing.
pub(crate) struct Fourier {
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    buf: Vec<Complex64>,
    scratch: Vec<Complex64>,
}

impl Fourier {
    /// Plans transforms of length `n` (any `n ≥ 1`; rustfft handles every
    /// size in O(n log n)).
    pub fn new(n: usize) -> Self {
        let mut planner = FftPlanner::new();
        let forward = planner.plan_fft_forward(n);
        let inverse = planner.plan_fft_inverse(n);
        let len = forward
            .get_inplace_scratch_len()
            .max(inverse.get_inplace_scratch_len());
        Self {
            forward,
            inverse,
            buf: vec![Complex64::new(0.0, 0.0); n],
            scratch: vec![Complex64::new(0.0, 0.0); len],
        }
    }

    /// Record length.
    pub fn len(&self) -> usize {
        self.buf.len()
    }

    /// Replaces `x` by `IDFT(m(k) · DFT(x))`, where `m(k)` gets the signed
    /// frequency index `k ∈ (−n/2, n/2]` of each bin. For an even `n` the
    /// Nyquist bin is passed as `+n/2`; the caller decides what an odd
    /// (imaginary) multiplier does there.
    pub fn apply(&mut self, x: &mut [f64], m: impl Fn(i64) -> Complex64) {
        debug_assert_eq!(x.len(), self.len());
        let n = self.len();
        for (b, &v) in self.buf.iter_mut().zip(x.iter()) {
            *b = Complex64::new(v, 0.0);
        }
        self.forward
            .process_with_scratch(&mut self.buf, &mut self.scratch);
        for (k, b) in self.buf.iter_mut().enumerate() {
            let signed = if 2 * k <= n {
                k as i64
            } else {
                k as i64 - n as i64
            };
            *b *= m(signed);
        }
        self.inverse
            .process_with_scratch(&mut self.buf, &mut self.scratch);
        let scale = 1.0 / n as f64;
        for (v, b) in x.iter_mut().zip(self.buf.iter()) {
            *v = b.re * scale;
        }
    }

    /// Adds `|X_k|²` of the DFT of `x` (length [`len`](Self::len)) to
    /// `power[k]` for `k < power.len()` (at most `len / 2 + 1`): one segment
    /// of a Welch or periodogram estimate, without allocating.
    pub fn add_power(&mut self, x: &[f64], power: &mut [f64]) {
        debug_assert_eq!(x.len(), self.len());
        for (b, &v) in self.buf.iter_mut().zip(x.iter()) {
            *b = Complex64::new(v, 0.0);
        }
        self.forward
            .process_with_scratch(&mut self.buf, &mut self.scratch);
        for (p, b) in power.iter_mut().zip(&self.buf) {
            *p += b.norm_sqr();
        }
    }

    /// The DFT of `x` (length [`len`](Self::len)).
    pub fn spectrum(&mut self, x: &[f64]) -> Vec<Complex64> {
        debug_assert_eq!(x.len(), self.len());
        for (b, &v) in self.buf.iter_mut().zip(x.iter()) {
            *b = Complex64::new(v, 0.0);
        }
        self.forward
            .process_with_scratch(&mut self.buf, &mut self.scratch);
        self.buf.clone()
    }

    /// Writes `IDFT(m(k) · spec)` (real part) into `out`, with `m` given
    /// the signed frequency index as in [`apply`](Self::apply).
    pub fn synthesise(
        &mut self,
        spec: &[Complex64],
        out: &mut [f64],
        m: impl Fn(i64) -> Complex64,
    ) {
        let n = self.len();
        for (k, (b, s)) in self.buf.iter_mut().zip(spec).enumerate() {
            let signed = if 2 * k <= n {
                k as i64
            } else {
                k as i64 - n as i64
            };
            *b = *s * m(signed);
        }
        self.inverse
            .process_with_scratch(&mut self.buf, &mut self.scratch);
        let scale = 1.0 / n as f64;
        for (v, b) in out.iter_mut().zip(self.buf.iter()) {
            *v = b.re * scale;
        }
    }
}
