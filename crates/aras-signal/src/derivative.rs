//! Numerical derivatives θ̇, θ̈ of uniformly sampled signals (`docs/processing.md`).
//!
//! Which to use:
//! * [`DerivativeMethod::CentralDifference`]: what the paper does. Second-order
//!   accurate (error `h²/6·x⁽³⁾` and `h²/12·x⁽⁴⁾`), but it amplifies noise at
//!   high frequency (by up to `2/h` and `4/h²`), so use it only on data that
//!   is already low-pass filtered, as [`process`](crate::process) does.
//! * [`DerivativeMethod::SavitzkyGolay`]: local least-squares polynomial fits;
//!   smooths while differentiating, so it tolerates noisier input and
//!   non-periodic records. Costs `half_window` samples at each end of a
//!   non-periodic record and a slight bias on fast content.
//! * [`DerivativeMethod::Spectral`]: multiplication by `iω` in the frequency
//!   domain. Exact (to rounding) for a band-limited *periodic* record, such as
//!   one averaged period of a periodic excitation, and no edge loss. Wrong for
//!   non-periodic records (the jump between the ends spreads ringing), so it
//!   is only offered for periodic data.

use nalgebra::DMatrix;
use rustfft::num_complex::Complex64;
use serde::Serialize;

use crate::error::ProcessError;
use crate::fourier::Fourier;

/// How derivatives are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum DerivativeMethod {
    /// [`Spectral`](Self::Spectral) for a periodic (averaged) record,
    /// [`CentralDifference`](Self::CentralDifference) otherwise.
    #[default]
    Auto,
    /// Central differences `(x[i+1] − x[i−1])/2h`, `(x[i+1] − 2x[i] + x[i−1])/h²`.
    CentralDifference,
    /// Savitzky–Golay: derivative at the centre of a least-squares
    /// polynomial of degree `poly_order` over `2·half_window + 1` samples.
    SavitzkyGolay {
        /// Samples on each side of the centre (≥ 1).
        half_window: usize,
        /// Polynomial degree (2 ≤ degree ≤ 2·half_window).
        poly_order: usize,
    },
    /// Frequency-domain differentiation of a periodic record.
    Spectral,
}

/// First and second derivatives of a signal.
///
/// For a non-periodic record the first and last `edge` samples have no
/// derivative: `first[i]` and `second[i]` belong to sample `i + edge`.
#[derive(Debug, Clone, PartialEq)]
pub struct Derivatives {
    /// First derivative (units/s).
    pub first: Vec<f64>,
    /// Second derivative (units/s²).
    pub second: Vec<f64>,
    /// Samples lost at each end (0 for a periodic record).
    pub edge: usize,
}

/// Savitzky–Golay convolution weights for the derivatives of order 1 and 2
/// at the window centre, per unit step (divide by `h` and `h²`).
fn savgol_weights(half: usize, order: usize) -> Result<(Vec<f64>, Vec<f64>), ProcessError> {
    let w = 2 * half + 1;
    if half == 0 || order < 2 || order >= w {
        return Err(ProcessError::InvalidOption {
            name: "derivative (Savitzky–Golay)",
            value: format!("half_window = {half}, poly_order = {order}"),
            reason: "need half_window ≥ 1 and 2 ≤ poly_order ≤ 2·half_window".into(),
        });
    }
    // Abscissae scaled to [−1, 1] keep the normal equations well conditioned.
    let m = half as f64;
    let a = DMatrix::from_fn(w, order + 1, |i, k| ((i as f64 - m) / m).powi(k as i32));
    let gram = a.transpose() * &a;
    let inv = gram
        .try_inverse()
        .ok_or_else(|| ProcessError::InvalidOption {
            name: "derivative (Savitzky–Golay)",
            value: format!("half_window = {half}, poly_order = {order}"),
            reason: "the fit is singular; use a lower poly_order".into(),
        })?;
    let rows = inv * a.transpose();
    // d/di = (1/m) d/dz; the second derivative of z^2 coefficient c2 is 2·c2.
    let d1 = (0..w).map(|j| rows[(1, j)] / m).collect();
    let d2 = (0..w).map(|j| 2.0 * rows[(2, j)] / (m * m)).collect();
    Ok((d1, d2))
}

fn check_step(dt: f64) -> Result<(), ProcessError> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(ProcessError::InvalidOption {
            name: "sample step",
            value: dt.to_string(),
            reason: "the step must be a positive number of seconds".into(),
        })
    }
}

/// First and second derivatives of `x` sampled every `dt` seconds.
///
/// `periodic` treats `x` as one period (wrapping around at the ends, no
/// samples lost). [`DerivativeMethod::Auto`] picks spectral for periodic
/// data and central differences otherwise; spectral on non-periodic data is
/// an error.
pub fn derivatives(
    x: &[f64],
    dt: f64,
    method: DerivativeMethod,
    periodic: bool,
) -> Result<Derivatives, ProcessError> {
    check_step(dt)?;
    let n = x.len();
    match resolve(method, periodic) {
        DerivativeMethod::Spectral => {
            if !periodic {
                return Err(ProcessError::InvalidOption {
                    name: "derivative",
                    value: "spectral".into(),
                    reason: "frequency-domain differentiation needs a periodic record: set a \
                             period (excitation.period_s) or use central differences or \
                             Savitzky–Golay"
                        .into(),
                });
            }
            if n < 3 {
                return Err(ProcessError::TooShort {
                    what: "spectral derivative".into(),
                    have: n,
                    need: 3,
                    hint: "record more samples per period".into(),
                });
            }
            let mut f = Fourier::new(n);
            let mut first = x.to_vec();
            let mut second = x.to_vec();
            spectral_with(&mut f, &mut first, &mut second, dt);
            Ok(Derivatives {
                first,
                second,
                edge: 0,
            })
        }
        DerivativeMethod::CentralDifference => convolve(
            x,
            &[-0.5, 0.0, 0.5],
            &[1.0, -2.0, 1.0],
            dt,
            periodic,
            "central differences",
        ),
        DerivativeMethod::SavitzkyGolay {
            half_window,
            poly_order,
        } => {
            let (d1, d2) = savgol_weights(half_window, poly_order)?;
            convolve(x, &d1, &d2, dt, periodic, "Savitzky–Golay derivative")
        }
        DerivativeMethod::Auto => unreachable!("resolved above"),
    }
}

/// The concrete method [`DerivativeMethod::Auto`] stands for.
pub fn resolve(method: DerivativeMethod, periodic: bool) -> DerivativeMethod {
    match method {
        DerivativeMethod::Auto if periodic => DerivativeMethod::Spectral,
        DerivativeMethod::Auto => DerivativeMethod::CentralDifference,
        m => m,
    }
}

/// Spectral first and second derivatives in place (inputs: two copies of x).
pub(crate) fn spectral_with(f: &mut Fourier, first: &mut [f64], second: &mut [f64], dt: f64) {
    let n = f.len() as i64;
    let w0 = 2.0 * std::f64::consts::PI / (n as f64 * dt);
    // The Nyquist bin of an even length is its own mirror: the odd (first)
    // derivative of a real signal has no component there.
    f.apply(first, |k| {
        if 2 * k == n {
            Complex64::new(0.0, 0.0)
        } else {
            Complex64::new(0.0, w0 * k as f64)
        }
    });
    f.apply(second, |k| Complex64::new(-(w0 * k as f64).powi(2), 0.0));
}

/// Centred convolution with weights `d1`, `d2` (odd length), scaled by
/// `1/dt` and `1/dt²`.
fn convolve(
    x: &[f64],
    d1: &[f64],
    d2: &[f64],
    dt: f64,
    periodic: bool,
    what: &str,
) -> Result<Derivatives, ProcessError> {
    let n = x.len();
    let half = d1.len() / 2;
    let need = 2 * half + 1;
    if n < need {
        return Err(ProcessError::TooShort {
            what: what.into(),
            have: n,
            need,
            hint: "use a shorter window or a longer record".into(),
        });
    }
    let (s1, s2) = (1.0 / dt, 1.0 / (dt * dt));
    let dot = |i: usize, w: &[f64]| -> f64 {
        if periodic {
            w.iter()
                .enumerate()
                .map(|(j, c)| c * x[(i + n + j - half) % n])
                .sum()
        } else {
            w.iter()
                .zip(&x[i - half..=i + half])
                .map(|(c, v)| c * v)
                .sum()
        }
    };
    let range = if periodic { 0..n } else { half..n - half };
    let first = range.clone().map(|i| dot(i, d1) * s1).collect();
    let second = range.map(|i| dot(i, d2) * s2).collect();
    Ok(Derivatives {
        first,
        second,
        edge: if periodic { 0 } else { half },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// One period of a band-limited signal and its exact derivatives.
    fn signal(n: usize, dt: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let w = TAU / (n as f64 * dt);
        let mut x = Vec::new();
        let mut d = Vec::new();
        let mut dd = Vec::new();
        for i in 0..n {
            let t = i as f64 * dt;
            x.push(0.3 + (w * t).sin() + 0.2 * (3.0 * w * t).cos());
            d.push(w * (w * t).cos() - 0.6 * w * (3.0 * w * t).sin());
            dd.push(-w * w * (w * t).sin() - 1.8 * w * w * (3.0 * w * t).cos());
        }
        (x, d, dd)
    }

    fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn spectral_is_exact_for_band_limited_periodic_signals() {
        for n in [64, 101, 1000] {
            let dt = 0.01;
            let (x, d, dd) = signal(n, dt);
            let r = derivatives(&x, dt, DerivativeMethod::Spectral, true).unwrap();
            // Rounding of an O(n log n) transform times ω (≈ 20/s here) and ω².
            assert!(max_abs_diff(&r.first, &d) < 1e-10, "n {n}");
            assert!(max_abs_diff(&r.second, &dd) < 1e-8, "n {n}");
        }
    }

    #[test]
    fn central_differences_have_second_order_error() {
        let (n, dt) = (1000, 0.001);
        let (x, d, dd) = signal(n, dt);
        let r = derivatives(&x, dt, DerivativeMethod::CentralDifference, true).unwrap();
        // Error bound h²/6·max|x'''| and h²/12·max|x''''| with ω = 2π/s:
        // max|x'''| ≤ ω³(1 + 5.4), max|x''''| ≤ ω⁴(1 + 16.2).
        let w = TAU;
        assert!(max_abs_diff(&r.first, &d) <= dt * dt / 6.0 * w.powi(3) * 6.4);
        assert!(max_abs_diff(&r.second, &dd) <= dt * dt / 12.0 * w.powi(4) * 17.2 + 1e-6);
        // Non-periodic: one sample lost at each end, aligned.
        let r = derivatives(&x, dt, DerivativeMethod::CentralDifference, false).unwrap();
        assert_eq!((r.edge, r.first.len()), (1, n - 2));
        assert!((r.first[0] - d[1]).abs() < 1e-4);
    }

    #[test]
    fn savitzky_golay_is_exact_on_polynomials() {
        // A cubic is reproduced exactly by a degree-3 fit: derivatives exact.
        let dt = 0.02;
        let x: Vec<f64> = (0..50)
            .map(|i| {
                let t = i as f64 * dt;
                1.0 - 2.0 * t + 0.5 * t * t + 0.25 * t * t * t
            })
            .collect();
        let m = DerivativeMethod::SavitzkyGolay {
            half_window: 4,
            poly_order: 3,
        };
        let r = derivatives(&x, dt, m, false).unwrap();
        assert_eq!(r.edge, 4);
        for (k, (d1, d2)) in r.first.iter().zip(&r.second).enumerate() {
            let t = (k + 4) as f64 * dt;
            assert!((d1 - (-2.0 + t + 0.75 * t * t)).abs() < 1e-9);
            assert!((d2 - (1.0 + 1.5 * t)).abs() < 1e-7);
        }
    }

    #[test]
    fn bad_requests_are_errors() {
        let x = vec![0.0; 10];
        assert!(derivatives(&x, 0.01, DerivativeMethod::Spectral, false).is_err());
        assert!(derivatives(&x, -1.0, DerivativeMethod::CentralDifference, false).is_err());
        let m = DerivativeMethod::SavitzkyGolay {
            half_window: 2,
            poly_order: 5,
        };
        assert!(derivatives(&x, 0.01, m, false).is_err());
        let m = DerivativeMethod::SavitzkyGolay {
            half_window: 8,
            poly_order: 2,
        };
        assert!(matches!(
            derivatives(&x, 0.01, m, false),
            Err(ProcessError::TooShort { .. })
        ));
    }
}
