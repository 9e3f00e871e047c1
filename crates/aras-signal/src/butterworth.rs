//! Butterworth low-pass design in second-order sections (the paper's
//! zero-phase Butterworth filter, `docs/processing.md`).
//!
//! The design reproduces `scipy.signal.butter(N, fc, fs=fs, output='sos')`
//! step by step, so the coefficients can be checked against scipy directly:
//! analog prototype poles on the unit circle, frequency pre-warping, the
//! bilinear transform, and scipy's `zpk2sos` pairing (`'nearest'`: the pole
//! closest to the unit circle goes last, each pole pair takes the nearest
//! zeros, the overall gain sits in the first section).

use std::f64::consts::PI;

use rustfft::num_complex::Complex64;

use crate::error::FilterError;
use crate::sos::{Sos, TransferFunction};

/// Highest order [`Butterworth::lowpass`] accepts. Beyond this the design
/// still works in sections, but no measured-data use needs it and the
/// transfer-function form is hopelessly ill-conditioned long before.
pub const MAX_ORDER: usize = 32;

/// Butterworth low-pass filter design (maximally flat pass band).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Butterworth;

/// Zeros, poles and gain of a digital filter.
struct Zpk {
    z: Vec<Complex64>,
    p: Vec<Complex64>,
    k: f64,
}

impl Butterworth {
    /// Low-pass of `order` with −3 dB cut-off `cutoff_hz` at sample rate
    /// `sample_rate_hz`, as second-order sections; equals
    /// `scipy.signal.butter(order, cutoff_hz, fs=sample_rate_hz, output='sos')`.
    ///
    /// Errors if the order is not in `1..=MAX_ORDER`, the sample rate is not a
    /// positive finite number, or the cut-off is not strictly between 0 and
    /// the Nyquist frequency.
    pub fn lowpass(order: usize, cutoff_hz: f64, sample_rate_hz: f64) -> Result<Sos, FilterError> {
        let zpk = design(order, cutoff_hz, sample_rate_hz)?;
        Sos::new(zpk2sos(zpk.z, zpk.p, zpk.k))
    }

    /// The same low-pass as one transfer function `b(z)/a(z)`, equal to
    /// `scipy.signal.butter(order, cutoff_hz, fs=sample_rate_hz)` (`'ba'`
    /// output). Prefer [`lowpass`](Self::lowpass): above order ≈ 8 the
    /// polynomial coefficients lose most of their significant digits.
    pub fn lowpass_ba(
        order: usize,
        cutoff_hz: f64,
        sample_rate_hz: f64,
    ) -> Result<TransferFunction, FilterError> {
        let zpk = design(order, cutoff_hz, sample_rate_hz)?;
        let b: Vec<f64> = poly(&zpk.z).iter().map(|c| c.re * zpk.k).collect();
        let a: Vec<f64> = poly(&zpk.p).iter().map(|c| c.re).collect();
        TransferFunction::new(b, a)
    }
}

/// Validates the arguments and returns the digital zeros, poles and gain.
fn design(order: usize, cutoff_hz: f64, sample_rate_hz: f64) -> Result<Zpk, FilterError> {
    if order == 0 || order > MAX_ORDER {
        return Err(FilterError::InvalidOrder {
            order,
            max: MAX_ORDER,
        });
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(FilterError::InvalidSampleRate {
            value: sample_rate_hz,
        });
    }
    let nyquist = 0.5 * sample_rate_hz;
    if !(cutoff_hz.is_finite() && cutoff_hz > 0.0 && cutoff_hz < nyquist) {
        return Err(FilterError::InvalidCutoff {
            cutoff_hz,
            nyquist_hz: nyquist,
            sample_rate_hz,
        });
    }
    // Normalised to Nyquist, then pre-warped for the bilinear transform with
    // scipy's internal fs = 2: warped = 2·fs·tan(π·Wn/fs).
    let wn = 2.0 * cutoff_hz / sample_rate_hz;
    let warped = 4.0 * (PI * wn / 2.0).tan();
    // Analog prototype (buttap): p = −exp(iπm/(2N)), m = −N+1, −N+3, …, N−1;
    // m = 0 (odd N) gives an exactly real pole.
    let n = order as i64;
    let analog: Vec<Complex64> = (0..order as i64)
        .map(|j| {
            let m = -n + 1 + 2 * j;
            let ang = PI * m as f64 / (2.0 * order as f64);
            -Complex64::new(ang.cos(), ang.sin())
        })
        .collect();
    // lp2lp: scale poles by the warped cut-off; gain warped^N (no zeros).
    let scaled: Vec<Complex64> = analog.iter().map(|p| p * warped).collect();
    let k_analog = warped.powi(order as i32);
    // Bilinear transform with fs2 = 2·fs = 4: z = (4 + s)/(4 − s); the N
    // zeros at infinity map to z = −1.
    let fs2 = Complex64::new(4.0, 0.0);
    let p: Vec<Complex64> = scaled.iter().map(|s| (fs2 + s) / (fs2 - s)).collect();
    let z = vec![Complex64::new(-1.0, 0.0); order];
    let denom = scaled
        .iter()
        .fold(Complex64::new(1.0, 0.0), |acc, s| acc * (fs2 - s));
    let k = k_analog * (Complex64::new(1.0, 0.0) / denom).re;
    Ok(Zpk { z, p, k })
}

/// Polynomial coefficients (highest power first) with the given roots.
fn poly(roots: &[Complex64]) -> Vec<Complex64> {
    let mut c = vec![Complex64::new(1.0, 0.0)];
    for r in roots {
        c.push(Complex64::new(0.0, 0.0));
        for i in (1..c.len()).rev() {
            let prev = c[i - 1];
            c[i] -= r * prev;
        }
    }
    c
}

fn is_real(c: &Complex64) -> bool {
    c.im == 0.0
}

/// scipy's `_cplxreal`: one member (positive imaginary part) of each
/// conjugate pair, then the real values, each group sorted as scipy does.
fn cplxreal(values: &[Complex64]) -> Vec<Complex64> {
    let tol = 100.0 * f64::EPSILON;
    let mut v = values.to_vec();
    v.sort_by(|a, b| {
        a.re.total_cmp(&b.re)
            .then(a.im.abs().total_cmp(&b.im.abs()))
    });
    let (real, cplx): (Vec<Complex64>, Vec<Complex64>) =
        v.into_iter().partition(|c| c.im.abs() <= tol * c.norm());
    let mut pos: Vec<Complex64> = cplx.iter().copied().filter(|c| c.im > 0.0).collect();
    let mut neg: Vec<Complex64> = cplx.iter().copied().filter(|c| c.im < 0.0).collect();
    // Within runs of (nearly) equal real part, sort by imaginary part.
    let by_run = |v: &mut Vec<Complex64>| {
        let mut start = 0;
        while start < v.len() {
            let mut end = start + 1;
            while end < v.len() && (v[end].re - v[end - 1].re) <= tol * v[end - 1].norm() {
                end += 1;
            }
            v[start..end].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
            start = end;
        }
    };
    by_run(&mut pos);
    by_run(&mut neg);
    let mut out: Vec<Complex64> = pos
        .iter()
        .zip(neg.iter())
        .map(|(p, n)| (p + n.conj()) / 2.0)
        .collect();
    out.extend(real.iter().map(|c| Complex64::new(c.re, 0.0)));
    out
}

/// Index of the value closest to the unit circle (first on ties).
fn idx_worst(p: &[Complex64], among: impl Fn(&Complex64) -> bool) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, c) in p.iter().enumerate() {
        if !among(c) {
            continue;
        }
        let d = (1.0 - c.norm()).abs();
        if best.is_none_or(|(_, bd)| d < bd) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

#[derive(Clone, Copy)]
enum Which {
    Any,
    Real,
    Complex,
}

/// Index of the entry of `from` nearest to `to` of the requested kind.
fn nearest(from: &[Complex64], to: Complex64, which: Which) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, c) in from.iter().enumerate() {
        let ok = match which {
            Which::Any => true,
            Which::Real => is_real(c),
            Which::Complex => !is_real(c),
        };
        if !ok {
            continue;
        }
        let d = (c - to).norm();
        if best.is_none_or(|(_, bd)| d < bd) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// One section from up to two zeros and two poles (scipy `_single_zpksos`):
/// coefficients right-aligned in `[b0 b1 b2 | a0 a1 a2]`.
fn single(z: &[Complex64], p: &[Complex64]) -> [f64; 6] {
    let mut s = [0.0; 6];
    let b = poly(z);
    let a = poly(p);
    for (i, c) in b.iter().enumerate() {
        s[3 - b.len() + i] = c.re;
    }
    for (i, c) in a.iter().enumerate() {
        s[6 - a.len() + i] = c.re;
    }
    s
}

/// scipy's `zpk2sos` with `pairing='nearest'` for a digital filter.
fn zpk2sos(mut z: Vec<Complex64>, mut p: Vec<Complex64>, k: f64) -> Vec<[f64; 6]> {
    if z.is_empty() && p.is_empty() {
        return vec![[k, 0.0, 0.0, 1.0, 0.0, 0.0]];
    }
    let zero = Complex64::new(0.0, 0.0);
    while p.len() < z.len() {
        p.push(zero);
    }
    while z.len() < p.len() {
        z.push(zero);
    }
    let n_sections = p.len().div_ceil(2);
    if p.len() % 2 == 1 {
        p.push(zero);
        z.push(zero);
    }
    let mut z = cplxreal(&z);
    let mut p = cplxreal(&p);
    let mut sos = vec![[0.0; 6]; n_sections];
    for si in (0..n_sections).rev() {
        let Some(i1) = idx_worst(&p, |_| true) else {
            break;
        };
        let p1 = p.remove(i1);
        let reals_p = p.iter().filter(|c| is_real(c)).count();
        let reals_z = z.iter().filter(|c| is_real(c)).count();
        if is_real(&p1) && reals_p == 0 {
            // Last remaining real pole: pair with the nearest real zero.
            let zz = match nearest(&z, p1, Which::Real) {
                Some(i) => z.remove(i),
                None => zero,
            };
            sos[si] = single(&[zz, zero], &[p1, zero]);
        } else if p.len() + 1 == z.len() && !is_real(&p1) && reals_p == 1 && reals_z == 1 {
            // One real pole and one real zero left: this pair must take a
            // complex zero.
            let i = nearest(&z, p1, Which::Complex).expect("complex zero present");
            let z1 = z.remove(i);
            sos[si] = single(&[z1, z1.conj()], &[p1, p1.conj()]);
        } else {
            let p2 = if is_real(&p1) {
                let i = idx_worst(&p, is_real).expect("a real pole remains");
                p.remove(i)
            } else {
                p1.conj()
            };
            sos[si] = match nearest(&z, p1, Which::Any) {
                None => single(&[], &[p1, p2]),
                Some(i) => {
                    let z1 = z.remove(i);
                    if !is_real(&z1) {
                        single(&[z1, z1.conj()], &[p1, p2])
                    } else if let Some(j) = nearest(&z, p1, Which::Real) {
                        let z2 = z.remove(j);
                        single(&[z1, z2], &[p1, p2])
                    } else {
                        single(&[z1], &[p1, p2])
                    }
                }
            };
        }
    }
    for c in &mut sos[0][..3] {
        *c *= k;
    }
    sos
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_dc_gain_and_half_power_at_cutoff() {
        for order in 1..=10 {
            let sos = Butterworth::lowpass(order, 7.0, 200.0).unwrap();
            // Exact-arithmetic identities of the design; 1e-12 leaves room for
            // the rounding of a few dozen products.
            assert!((sos.gain(0.0, 200.0) - 1.0).abs() < 1e-12, "order {order}");
            assert!((sos.gain(7.0, 200.0) - 0.5f64.sqrt()).abs() < 1e-12);
        }
    }

    #[test]
    fn rejects_bad_arguments() {
        assert!(matches!(
            Butterworth::lowpass(0, 1.0, 10.0),
            Err(FilterError::InvalidOrder { .. })
        ));
        assert!(matches!(
            Butterworth::lowpass(2, 5.0, 10.0),
            Err(FilterError::InvalidCutoff { .. })
        ));
        assert!(matches!(
            Butterworth::lowpass(2, 1.0, f64::NAN),
            Err(FilterError::InvalidSampleRate { .. })
        ));
        let msg = Butterworth::lowpass(2, 600.0, 1000.0)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("Nyquist frequency 500 Hz"), "{msg}");
    }
}
