//! Zero-phase forward–backward filtering (as in the paper, `docs/processing.md`; MATLAB/scipy `filtfilt`),
//! usable on any column: the identification filters every regressor column
//! with the same [`Sos`] as the torques (`docs/processing.md`, "Parallel filtering").
//!
//! Edge handling is scipy's default, reproduced exactly so results match
//! `scipy.signal.sosfiltfilt(sos, x)` and `filtfilt(b, a, x)`:
//! * the signal is extended at both ends by `padlen` samples of its *odd*
//!   reflection (`2·x[0] − x[i]`), with `padlen = 3·ntaps`, `ntaps = 2·sections
//!   + 1` less the trailing zero coefficients of first-order sections
//!   (`3·max(len a, len b)` for a transfer function);
//! * each pass starts from the steady state for a constant input equal to
//!   its first sample (`sosfilt_zi` / `lfilter_zi`), so a constant passes
//!   through unchanged;
//! * signals not longer than `padlen` are rejected, as scipy does.

use rustfft::num_complex::Complex64;

use crate::error::FilterError;
use crate::fourier::Fourier;

/// Signals [`Sos::filtfilt_many_in_place`] advances together: eight `f64`
/// fill one AVX-512 register (two AVX2 ones).
pub const FILTER_LANES: usize = 8;

/// Second-order sections `[b0, b1, b2, 1, a1, a2]` of a digital IIR filter,
/// with their steady-state initial conditions precomputed.
///
/// Each section is `H_s(z) = (b0 + b1 z⁻¹ + b2 z⁻²)/(1 + a1 z⁻¹ + a2 z⁻²)`,
/// the filter is their product. Build with
/// [`Butterworth::lowpass`](crate::Butterworth::lowpass) or [`Sos::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct Sos {
    sections: Vec<[f64; 6]>,
    /// `sosfilt_zi`: per-section state for a unit constant input.
    zi: Vec<[f64; 2]>,
    padlen: usize,
}

/// A filter as one transfer function `b(z)/a(z)` (scipy's `'ba'` form).
///
/// Kept for comparison with `scipy.signal.filtfilt(b, a, x)` and MATLAB; use
/// [`Sos`] for real work (numerically robust at any order).
#[derive(Debug, Clone, PartialEq)]
pub struct TransferFunction {
    b: Vec<f64>,
    a: Vec<f64>,
    zi: Vec<f64>,
}

fn check_finite_input(x: &[f64]) -> Result<(), FilterError> {
    // `v · 0` is 0 for a finite `v` and NaN otherwise: eight independent
    // sums sweep the record in SIMD lanes, and only a non-finite record is
    // searched for its first bad sample.
    let mut acc = [0.0f64; 8];
    let chunks = x.chunks_exact(8);
    let rest = chunks.remainder();
    for c in chunks {
        for (a, v) in acc.iter_mut().zip(c) {
            *a += v * 0.0;
        }
    }
    if acc.iter().chain(rest).all(|v| v.is_finite()) {
        return Ok(());
    }
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(FilterError::NonFinite {
            index,
            value: x[index],
        }),
        None => Ok(()),
    }
}

/// scipy's `odd_ext` of `x` by `edge` samples on each side, into `ext`.
fn odd_extend(x: &[f64], edge: usize, ext: &mut Vec<f64>) {
    let n = x.len();
    ext.clear();
    ext.reserve(n + 2 * edge);
    let (first, last) = (x[0], x[n - 1]);
    ext.extend((1..=edge).rev().map(|i| 2.0 * first - x[i]));
    ext.extend_from_slice(x);
    ext.extend((1..=edge).map(|i| 2.0 * last - x[n - 1 - i]));
}

/// `lfilter_zi` of a normalised (`a[0] = 1`), equal-length pair: the
/// direct-form-II-transposed state for a unit constant input, by the
/// closed-form solution of `zi = A·zi + B` that scipy documents.
fn lfilter_zi(b: &[f64], a: &[f64]) -> Vec<f64> {
    let n = b.len();
    if n < 2 {
        return Vec::new();
    }
    let sum_b: f64 = (1..n).map(|j| b[j] - a[j] * b[0]).sum();
    let sum_a: f64 = a.iter().sum();
    let mut zi = vec![0.0; n - 1];
    zi[0] = sum_b / sum_a;
    let (mut asum, mut csum) = (1.0, 0.0);
    for k in 1..n - 1 {
        asum += a[k];
        csum += b[k] - a[k] * b[0];
        zi[k] = asum * zi[0] - csum;
    }
    zi
}

impl Sos {
    /// Sections as rows `[b0, b1, b2, a0, a1, a2]`; `a0` must be exactly 1
    /// (as scipy requires), all coefficients finite, at least one section,
    /// and the DC gain of every section finite (`1 + a1 + a2 ≠ 0`), which the
    /// steady-state initial conditions need.
    pub fn new(sections: Vec<[f64; 6]>) -> Result<Self, FilterError> {
        if sections.is_empty() {
            return Err(FilterError::InvalidSection {
                section: 0,
                reason: "the filter has no sections".into(),
            });
        }
        for (i, s) in sections.iter().enumerate() {
            if let Some(j) = s.iter().position(|c| !c.is_finite()) {
                return Err(FilterError::InvalidSection {
                    section: i,
                    reason: format!("coefficient {j} is not finite ({})", s[j]),
                });
            }
            if s[3] != 1.0 {
                return Err(FilterError::InvalidSection {
                    section: i,
                    reason: format!("a0 = {} but must be 1: divide the row by a0", s[3]),
                });
            }
            if s[3] + s[4] + s[5] == 0.0 {
                return Err(FilterError::InvalidSection {
                    section: i,
                    reason: "1 + a1 + a2 = 0: a pole at z = 1 has no steady state".into(),
                });
            }
        }
        let mut zi = Vec::with_capacity(sections.len());
        let mut scale = 1.0;
        for s in &sections {
            let z = lfilter_zi(&s[..3], &s[3..]);
            zi.push([scale * z[0], scale * z[1]]);
            scale *= (s[0] + s[1] + s[2]) / (s[3] + s[4] + s[5]);
        }
        let trailing_b = sections.iter().filter(|s| s[2] == 0.0).count();
        let trailing_a = sections.iter().filter(|s| s[5] == 0.0).count();
        let ntaps = 2 * sections.len() + 1 - trailing_b.min(trailing_a);
        Ok(Self {
            sections,
            zi,
            padlen: 3 * ntaps,
        })
    }

    /// The sections, rows `[b0, b1, b2, 1, a1, a2]` (scipy's layout).
    pub fn sections(&self) -> &[[f64; 6]] {
        &self.sections
    }

    /// Number of samples of odd extension at each end; signals must be
    /// longer than this for [`filtfilt`](Self::filtfilt).
    pub fn padlen(&self) -> usize {
        self.padlen
    }

    /// Steady-state section states for a unit constant input
    /// (`scipy.signal.sosfilt_zi`).
    pub fn steady_state(&self) -> &[[f64; 2]] {
        &self.zi
    }

    /// Complex frequency response `H(e^{iω})` at `freq_hz` for sample rate
    /// `sample_rate_hz`.
    pub fn response(&self, freq_hz: f64, sample_rate_hz: f64) -> Complex64 {
        self.response_at(2.0 * std::f64::consts::PI * freq_hz / sample_rate_hz)
    }

    /// Magnitude `|H|` at `freq_hz`. The zero-phase filter's gain is its square.
    pub fn gain(&self, freq_hz: f64, sample_rate_hz: f64) -> f64 {
        self.response(freq_hz, sample_rate_hz).norm()
    }

    /// `H(e^{iω})` at normalised angular frequency `omega` (rad/sample).
    fn response_at(&self, omega: f64) -> Complex64 {
        let z1 = Complex64::from_polar(1.0, -omega);
        let z2 = z1 * z1;
        self.sections
            .iter()
            .fold(Complex64::new(1.0, 0.0), |acc, s| {
                acc * (s[0] + z1 * s[1] + z2 * s[2]) / (s[3] + z1 * s[4] + z2 * s[5])
            })
    }

    /// One causal pass over `x` in place, starting from the steady state for
    /// a constant input `x0` (`sosfilt(sos, x, zi=zi·x0)`); `reverse` runs
    /// from the last sample to the first: [`Self::pass_lanes`] with one lane.
    fn pass(&self, x: &mut [f64], x0: f64, reverse: bool) {
        let (lanes, _) = x.as_chunks_mut::<1>();
        self.pass_lanes(lanes, [x0], reverse);
    }

    /// Causal filtering in place from rest (`scipy.signal.sosfilt(sos, x)`).
    pub fn filter_in_place(&self, x: &mut [f64]) {
        for s in &self.sections {
            let [b0, b1, b2, _, a1, a2] = *s;
            let (mut z0, mut z1) = (0.0, 0.0);
            for v in x.iter_mut() {
                let xi = *v;
                let y = b0 * xi + z0;
                z0 = b1 * xi - a1 * y + z1;
                z1 = b2 * xi - a2 * y;
                *v = y;
            }
        }
    }

    /// Zero-phase filtering, `scipy.signal.sosfiltfilt(sos, x)` with its
    /// defaults (odd padding of `padlen` samples, steady-state initial
    /// conditions). Allocates the result; see
    /// [`filtfilt_into`](Self::filtfilt_into) to reuse buffers.
    pub fn filtfilt(&self, x: &[f64]) -> Result<Vec<f64>, FilterError> {
        let mut out = vec![0.0; x.len()];
        let mut scratch = Vec::new();
        self.filtfilt_into(x, &mut out, &mut scratch)?;
        Ok(out)
    }

    /// [`filtfilt`](Self::filtfilt) into `out` (same length as `x`), using
    /// `scratch` for the padded signal. `scratch` grows to `len + 2·padlen`
    /// once and is reused, so filtering many columns allocates nothing.
    pub fn filtfilt_into(
        &self,
        x: &[f64],
        out: &mut [f64],
        scratch: &mut Vec<f64>,
    ) -> Result<(), FilterError> {
        if out.len() != x.len() {
            return Err(FilterError::LengthMismatch {
                input: x.len(),
                output: out.len(),
            });
        }
        self.check_len(x.len())?;
        check_finite_input(x)?;
        let edge = self.padlen;
        odd_extend(x, edge, scratch);
        let first = scratch[0];
        self.pass(scratch, first, false);
        let last = scratch[scratch.len() - 1];
        self.pass(scratch, last, true);
        out.copy_from_slice(&scratch[edge..edge + x.len()]);
        Ok(())
    }

    /// [`filtfilt`](Self::filtfilt) overwriting `x`.
    pub fn filtfilt_in_place(
        &self,
        x: &mut [f64],
        scratch: &mut Vec<f64>,
    ) -> Result<(), FilterError> {
        self.filtfilt_in_place_padded(x, self.padlen, scratch)
    }

    /// [`filtfilt_in_place`](Self::filtfilt_in_place) with an explicit pad
    /// length, `scipy.signal.sosfiltfilt(sos, x, padlen=padlen)`.
    ///
    /// scipy's default pad (`3·ntaps`, a few dozen samples) is far shorter
    /// than the transient of a low cut-off filter (its slowest pole decays
    /// over ≈ `fs/(2π·fc·sin(π/2N))` samples), so the first and last few
    /// hundred samples of a non-periodic record carry start-up error. A pad
    /// of several such time constants lets the transient die out inside the
    /// extension; `x` must be longer than `padlen`.
    pub fn filtfilt_in_place_padded(
        &self,
        x: &mut [f64],
        padlen: usize,
        scratch: &mut Vec<f64>,
    ) -> Result<(), FilterError> {
        if x.len() <= padlen {
            return Err(FilterError::TooShort {
                len: x.len(),
                padlen,
            });
        }
        check_finite_input(x)?;
        odd_extend(x, padlen, scratch);
        let first = scratch[0];
        self.pass(scratch, first, false);
        let last = scratch[scratch.len() - 1];
        self.pass(scratch, last, true);
        let n = x.len();
        x.copy_from_slice(&scratch[padlen..padlen + n]);
        Ok(())
    }

    /// [`filtfilt_in_place`](Self::filtfilt_in_place) of many equally long
    /// signals (e.g. the regressor columns a fit filters), [`FILTER_LANES`] at a
    /// time: their samples are interleaved so that one sweep advances every
    /// signal's recurrence together, which the CPU runs in SIMD lanes (a
    /// single recurrence is latency-bound). Each lane does exactly the
    /// arithmetic of the single-signal filter, so the results are
    /// bit-identical to filtering the signals one by one. `scratch` is
    /// reused.
    pub fn filtfilt_many_in_place(
        &self,
        signals: &mut [&mut [f64]],
        scratch: &mut Vec<[f64; FILTER_LANES]>,
    ) -> Result<(), FilterError> {
        let Some(n) = signals.first().map(|s| s.len()) else {
            return Ok(());
        };
        for (index, s) in signals.iter().enumerate() {
            if s.len() != n {
                return Err(FilterError::UnequalSignals {
                    first: n,
                    index,
                    len: s.len(),
                });
            }
            check_finite_input(s)?;
        }
        self.check_len(n)?;
        let edge = self.padlen;
        // Rows per tile of the (de)interleaving copies: 512 rows of eight
        // lanes are 32 KiB, so each signal is read (or written) in order
        // while the tile stays in the L1 cache.
        const TILE: usize = 512;
        for group in signals.chunks_mut(FILTER_LANES) {
            // Odd extension, interleaved; every entry of the used lanes is
            // written, so the buffer is only resized, not cleared. Unused
            // lanes carry zeros.
            scratch.resize(n + 2 * edge, [0.0; FILTER_LANES]);
            if group.len() < FILTER_LANES {
                for row in scratch.iter_mut() {
                    row[group.len()..].fill(0.0);
                }
            }
            let (head, rest) = scratch.split_at_mut(edge);
            let (body, tail) = rest.split_at_mut(n);
            for (l, s) in group.iter().enumerate() {
                for (k, row) in head.iter_mut().enumerate() {
                    row[l] = 2.0 * s[0] - s[edge - k];
                }
                for (k, row) in tail.iter_mut().enumerate() {
                    row[l] = 2.0 * s[n - 1] - s[n - 2 - k];
                }
            }
            for (rows, start) in body.chunks_mut(TILE).zip((0..n).step_by(TILE)) {
                for (l, s) in group.iter().enumerate() {
                    for (row, v) in rows.iter_mut().zip(&s[start..]) {
                        row[l] = *v;
                    }
                }
            }
            let first = scratch[0];
            self.pass_lanes(scratch, first, false);
            let last = scratch[scratch.len() - 1];
            self.pass_lanes(scratch, last, true);
            for (rows, start) in scratch[edge..edge + n]
                .chunks(TILE)
                .zip((0..n).step_by(TILE))
            {
                for (l, s) in group.iter_mut().enumerate() {
                    for (v, row) in s[start..].iter_mut().zip(rows) {
                        *v = row[l];
                    }
                }
            }
        }
        Ok(())
    }

    /// One causal pass over `L` interleaved signals in place, each starting
    /// from the steady state for its constant input `x0[l]`
    /// (`sosfilt(sos, x, zi=zi·x0)`); `reverse` runs from the last sample to
    /// the first. Every lane does the same operations in the same order.
    /// Sections go two per sweep, so the CPU overlaps their recurrences
    /// (each is latency-bound on its own); the arithmetic per section is
    /// unchanged, so results are identical.
    fn pass_lanes<const L: usize>(&self, x: &mut [[f64; L]], x0: [f64; L], reverse: bool) {
        let mul = |c: f64, v: &[f64; L]| -> [f64; L] { std::array::from_fn(|l| c * v[l]) };
        let mut i = 0;
        while i < self.sections.len() {
            if i + 1 < self.sections.len() {
                let (s, t) = (self.sections[i], self.sections[i + 1]);
                let (zs, zt) = (self.zi[i], self.zi[i + 1]);
                let (mut p0, mut p1) = (mul(zs[0], &x0), mul(zs[1], &x0));
                let (mut q0, mut q1) = (mul(zt[0], &x0), mul(zt[1], &x0));
                let mut step = |v: &mut [f64; L]| {
                    for l in 0..L {
                        let xi = v[l];
                        let y = s[0] * xi + p0[l];
                        p0[l] = s[1] * xi - s[4] * y + p1[l];
                        p1[l] = s[2] * xi - s[5] * y;
                        let w = t[0] * y + q0[l];
                        q0[l] = t[1] * y - t[4] * w + q1[l];
                        q1[l] = t[2] * y - t[5] * w;
                        v[l] = w;
                    }
                };
                if reverse {
                    x.iter_mut().rev().for_each(&mut step);
                } else {
                    x.iter_mut().for_each(&mut step);
                }
                i += 2;
            } else {
                let [b0, b1, b2, _, a1, a2] = self.sections[i];
                let zi = self.zi[i];
                let (mut z0, mut z1) = (mul(zi[0], &x0), mul(zi[1], &x0));
                let mut step = |v: &mut [f64; L]| {
                    for l in 0..L {
                        let xi = v[l];
                        let y = b0 * xi + z0[l];
                        z0[l] = b1 * xi - a1 * y + z1[l];
                        z1[l] = b2 * xi - a2 * y;
                        v[l] = y;
                    }
                };
                if reverse {
                    x.iter_mut().rev().for_each(&mut step);
                } else {
                    x.iter_mut().for_each(&mut step);
                }
                i += 1;
            }
        }
    }

    fn check_len(&self, len: usize) -> Result<(), FilterError> {
        if len <= self.padlen {
            return Err(FilterError::TooShort {
                len,
                padlen: self.padlen,
            });
        }
        Ok(())
    }

    /// Zero-phase filtering of a record: one period of a periodic signal
    /// ([`filtfilt_periodic`](Self::filtfilt_periodic)) when `periodic`,
    /// otherwise a finite record with odd padding
    /// ([`filtfilt`](Self::filtfilt)). The one place where a caller that
    /// handles both kinds of record chooses between them.
    pub fn filtfilt_record(&self, x: &[f64], periodic: bool) -> Result<Vec<f64>, FilterError> {
        if periodic {
            self.filtfilt_periodic(x)
        } else {
            self.filtfilt(x)
        }
    }

    /// Zero-phase filtering of one period of a periodic signal: the
    /// steady-state result of forward–backward filtering the endlessly
    /// repeated record, computed exactly as `DFT⁻¹(|H(ω_k)|² · DFT(x))`. No
    /// edge effects, no padding, any length ≥ 1.
    pub fn filtfilt_periodic(&self, x: &[f64]) -> Result<Vec<f64>, FilterError> {
        let mut out = x.to_vec();
        self.filtfilt_periodic_in_place(&mut out)?;
        Ok(out)
    }

    /// [`filtfilt_periodic`](Self::filtfilt_periodic) in place.
    pub fn filtfilt_periodic_in_place(&self, x: &mut [f64]) -> Result<(), FilterError> {
        if x.is_empty() {
            return Err(FilterError::TooShort { len: 0, padlen: 0 });
        }
        check_finite_input(x)?;
        let mut f = Fourier::new(x.len());
        self.periodic_with(&mut f, x);
        Ok(())
    }

    pub(crate) fn periodic_with(&self, f: &mut Fourier, x: &mut [f64]) {
        let n = f.len() as f64;
        let tau = 2.0 * std::f64::consts::PI;
        f.apply(x, |k| {
            Complex64::new(self.response_at(tau * k as f64 / n).norm_sqr(), 0.0)
        });
    }
}

impl TransferFunction {
    /// `b(z)/a(z)` with coefficients highest power of `z⁻¹` last; `a[0]` must
    /// be non-zero (both are normalised by it, as `lfilter` does), and
    /// `Σ a ≠ 0` (a finite DC gain, needed for the steady state).
    pub fn new(mut b: Vec<f64>, mut a: Vec<f64>) -> Result<Self, FilterError> {
        let bad = |reason: String| FilterError::InvalidSection { section: 0, reason };
        if a.is_empty() || b.is_empty() {
            return Err(bad("b and a must both have at least one coefficient".into()));
        }
        if let Some(v) = a.iter().chain(b.iter()).find(|v| !v.is_finite()) {
            return Err(bad(format!("coefficient {v} is not finite")));
        }
        if a[0] == 0.0 {
            return Err(bad(
                "a[0] = 0: the leading denominator coefficient must be non-zero".into(),
            ));
        }
        let a0 = a[0];
        b.iter_mut().for_each(|v| *v /= a0);
        a.iter_mut().for_each(|v| *v /= a0);
        let n = a.len().max(b.len());
        b.resize(n, 0.0);
        a.resize(n, 0.0);
        if a.iter().sum::<f64>() == 0.0 {
            return Err(bad("Σ a = 0: a pole at z = 1 has no steady state".into()));
        }
        let zi = lfilter_zi(&b, &a);
        Ok(Self { b, a, zi })
    }

    /// Numerator (normalised so `a[0] = 1`, padded to the common length).
    pub fn b(&self) -> &[f64] {
        &self.b
    }

    /// Denominator (normalised so `a[0] = 1`, padded to the common length).
    pub fn a(&self) -> &[f64] {
        &self.a
    }

    /// `3·max(len a, len b)`, scipy's default `padlen` for `filtfilt`.
    pub fn padlen(&self) -> usize {
        3 * self.b.len()
    }

    fn pass(&self, x: &mut [f64], x0: f64, reverse: bool, z: &mut [f64]) {
        let (b, a) = (&self.b, &self.a);
        let m = z.len();
        for (zj, zi) in z.iter_mut().zip(&self.zi) {
            *zj = zi * x0;
        }
        let mut step = |v: &mut f64| {
            let xi = *v;
            let y = b[0] * xi + if m > 0 { z[0] } else { 0.0 };
            for j in 0..m {
                let next = if j + 1 < m { z[j + 1] } else { 0.0 };
                z[j] = b[j + 1] * xi - a[j + 1] * y + next;
            }
            *v = y;
        };
        if reverse {
            x.iter_mut().rev().for_each(&mut step);
        } else {
            x.iter_mut().for_each(&mut step);
        }
    }

    /// Zero-phase filtering, `scipy.signal.filtfilt(b, a, x)` with its
    /// defaults (odd padding of `3·max(len a, len b)` samples, steady-state
    /// initial conditions from `lfilter_zi`).
    pub fn filtfilt(&self, x: &[f64]) -> Result<Vec<f64>, FilterError> {
        let edge = self.padlen();
        if x.len() <= edge {
            return Err(FilterError::TooShort {
                len: x.len(),
                padlen: edge,
            });
        }
        check_finite_input(x)?;
        let mut ext = Vec::new();
        odd_extend(x, edge, &mut ext);
        let mut z = vec![0.0; self.zi.len()];
        let first = ext[0];
        self.pass(&mut ext, first, false, &mut z);
        let last = ext[ext.len() - 1];
        self.pass(&mut ext, last, true, &mut z);
        Ok(ext[edge..edge + x.len()].to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The lane sweep finds the first non-finite sample wherever it is
        /// (in the eight-sample chunks or the remainder) and passes every
        /// finite record, extreme magnitudes included.
        #[test]
        fn the_finiteness_sweep_finds_the_first_bad_sample(
            x in proptest::collection::vec(prop_oneof![
                -1e308f64..1e308,
                Just(f64::MAX),
                Just(f64::MIN_POSITIVE),
                Just(-0.0),
            ], 0..100),
            bad in proptest::option::of((any::<prop::sample::Index>(), prop_oneof![
                Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)
            ])),
        ) {
            let mut x = x;
            match bad {
                Some((at, v)) if !x.is_empty() => {
                    let i = at.index(x.len());
                    x[i] = v;
                    let e = check_finite_input(&x).unwrap_err();
                    let found = matches!(e, FilterError::NonFinite { index, .. } if index == i);
                    prop_assert!(found, "{:?} for a bad sample at {}", e, i);
                }
                _ => prop_assert!(check_finite_input(&x).is_ok()),
            }
        }
    }

    #[test]
    fn rejects_bad_sections_with_reasons() {
        let e = Sos::new(vec![[1.0, 0.0, 0.0, 2.0, 0.0, 0.0]]).unwrap_err();
        assert!(e.to_string().contains("a0 = 2 but must be 1"), "{e}");
        let e = Sos::new(vec![[1.0, f64::NAN, 0.0, 1.0, 0.0, 0.0]]).unwrap_err();
        assert!(e.to_string().contains("coefficient 1 is not finite"), "{e}");
        let e = Sos::new(vec![[1.0, 0.0, 0.0, 1.0, -1.0, 0.0]]).unwrap_err();
        assert!(e.to_string().contains("pole at z = 1"), "{e}");
        assert!(Sos::new(vec![]).is_err());
    }

    #[test]
    fn short_and_non_finite_inputs_are_errors() {
        let sos = crate::Butterworth::lowpass(4, 10.0, 1000.0).unwrap();
        assert_eq!(sos.padlen(), 15);
        let e = sos.filtfilt(&[0.0; 15]).unwrap_err();
        assert_eq!(
            e,
            FilterError::TooShort {
                len: 15,
                padlen: 15
            }
        );
        assert!(sos.filtfilt(&[0.0; 16]).is_ok());
        let mut x = vec![0.0; 40];
        x[7] = f64::INFINITY;
        assert!(matches!(
            sos.filtfilt(&x),
            Err(FilterError::NonFinite { index: 7, .. })
        ));
        let mut out = vec![0.0; 39];
        assert!(matches!(
            sos.filtfilt_into(&[0.0; 40], &mut out, &mut Vec::new()),
            Err(FilterError::LengthMismatch { .. })
        ));
    }

    /// Bad input to the many-signal filter is an error naming what is
    /// wrong, and leaves every signal untouched.
    #[test]
    fn many_signals_reject_unequal_lengths_non_finite_values_and_short_records() {
        let sos = crate::Butterworth::lowpass(2, 5.0, 100.0).unwrap();
        let (mut a, mut b) = (vec![1.0; 40], vec![2.0; 39]);
        let e = sos
            .filtfilt_many_in_place(&mut [&mut a, &mut b], &mut Vec::new())
            .unwrap_err();
        assert!(
            matches!(
                e,
                FilterError::UnequalSignals {
                    first: 40,
                    index: 1,
                    len: 39
                }
            ),
            "{e}"
        );
        let mut c = vec![1.0; 40];
        c[5] = f64::NAN;
        let mut d = vec![1.0; 40];
        let e = sos
            .filtfilt_many_in_place(&mut [&mut d, &mut c], &mut Vec::new())
            .unwrap_err();
        assert!(matches!(e, FilterError::NonFinite { index: 5, .. }), "{e}");
        assert!(
            d.iter().all(|v| *v == 1.0),
            "a good signal was changed before the error"
        );
        let mut short = vec![1.0; sos.padlen()];
        assert!(matches!(
            sos.filtfilt_many_in_place(&mut [&mut short], &mut Vec::new()),
            Err(FilterError::TooShort { .. })
        ));
        assert!(sos.filtfilt_many_in_place(&mut [], &mut Vec::new()).is_ok());
    }

    #[test]
    fn in_place_and_into_agree_with_allocating_form() {
        let sos = crate::Butterworth::lowpass(3, 5.0, 100.0).unwrap();
        let x: Vec<f64> = (0..300)
            .map(|i| (i as f64 * 0.37).sin() + 0.01 * i as f64)
            .collect();
        let y = sos.filtfilt(&x).unwrap();
        let mut z = x.clone();
        let mut scratch = Vec::new();
        sos.filtfilt_in_place(&mut z, &mut scratch).unwrap();
        assert_eq!(y, z);
    }

    #[test]
    fn periodic_filter_passes_low_harmonics_and_matches_long_filtfilt() {
        // A record of 3 harmonics; the periodic filter must equal ordinary
        // filtfilt on a long repetition, far from its edges.
        let sos = crate::Butterworth::lowpass(4, 8.0, 200.0).unwrap();
        let n = 200;
        let x: Vec<f64> = (0..n)
            .map(|i| {
                let w = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                (w).sin() + 0.5 * (7.0 * w).cos() + 0.2 * (20.0 * w).sin()
            })
            .collect();
        let yp = sos.filtfilt_periodic(&x).unwrap();
        let long: Vec<f64> = (0..21 * n).map(|i| x[i % n]).collect();
        let yl = sos.filtfilt(&long).unwrap();
        // Transients of this filter decay by e⁻¹ in ~10 samples: after 10
        // periods they are below 1e-12.
        for i in 0..n {
            assert!((yp[i] - yl[10 * n + i]).abs() < 1e-10, "{i}");
        }
    }
}
