//! The processing's bandwidth, chosen from the data (`docs/processing.md`).
//!
//! A fixed low-pass cuts a fast motion's harmonics (and the torque's
//! friction steps that follow them) or lets a slow motion's noise through.
//! Here the angles themselves say how far their content reaches:
//!
//! * **Periodic record** (period given or [`detect_period`]): a least-squares
//!   Fourier series of θ in the harmonics of the period. On one averaged
//!   block of whole periods with a uniform step the least-squares
//!   coefficients are the DFT bins, so the fit is exact and O(n log n).
//!   **Rule**: the noise floor `σ²` is the median bin power above `fs/4`
//!   divided by `ln 2` (the median of an exponential variable); harmonic `m`
//!   is significant when its power exceeds `σ² ln(H/α)` with `H` candidate
//!   harmonics and `α = 10⁻³` (a noise-only bin passes with probability
//!   `α/H`, so all `H` together with at most `α`); the series keeps
//!   harmonics `1..=M`, `M` the highest significant one. θ̇, θ̈ are the
//!   series' analytic derivatives.
//! * **Otherwise**: a zero-phase Butterworth whose cut-off follows the angle
//!   spectrum. **Rule**: Welch spectrum (Hann, 50 % overlap) of the first
//!   difference of θ (differencing removes offsets and drift and flattens
//!   the motion's dynamic range, so window leakage stays below the floor);
//!   white noise (quantisation) differenced has the spectrum
//!   `c·sin²(πf/fs)`, `c` fitted as the mean ratio above `fs/4` (the mean,
//!   so that the line spectrum of a periodic motion's quantisation error
//!   counts as floor); the
//!   motion reaches up to the highest frequency whose power exceeds
//!   [`SPECTRUM_THRESHOLD`] times that floor; the cut-off is
//!   [`CUTOFF_MARGIN`] times that frequency (where the order-4 zero-phase
//!   filter passes 96 % of the power), within `[2/T, 0.4 fs]`.

use rustfft::FftPlanner;
use rustfft::num_complex::Complex64;
use serde::Serialize;

use crate::fourier::{Fourier, hann};

/// False-alarm probability of the harmonic selection over all candidate
/// harmonics: one spurious harmonic in a thousand records.
pub const HARMONIC_FALSE_ALARM: f64 = 1e-3;

/// A frequency carries motion when its Welch power is this many times the
/// noise floor (10 dB: with 8 or more averaged segments the floor's 99.9 %
/// quantile is below 4).
pub const SPECTRUM_THRESHOLD: f64 = 10.0;

/// Cut-off over the highest frequency of the motion: an order-4 zero-phase
/// Butterworth passes `1/(1 + 1.5⁻⁸)` = 96 % of the power there.
pub const CUTOFF_MARGIN: f64 = 1.5;

/// Smallest normalised autocorrelation at the period for [`detect_period`]
/// to accept it: noise, drift or a non-repeating motion pull it below.
pub const MIN_PERIOD_CORRELATION: f64 = 0.9;

/// Where the period came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PeriodOrigin {
    /// The caller's option (`--period`).
    Given,
    /// The sidecar's `excitation.period_s`.
    Sidecar,
    /// Detected from the angles ([`detect_period`]).
    Detected,
}

/// Outcome of [`detect_period`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodDetection {
    /// The period (s), or `None` when the detector declined.
    pub period_s: Option<f64>,
    /// Normalised autocorrelation of the detrended angles at the best
    /// repeat (1 for an exact repetition).
    pub correlation: f64,
    /// Why the detector declined, if it did.
    pub declined: Option<String>,
}

impl PeriodDetection {
    fn decline(correlation: f64, why: String) -> Self {
        Self {
            period_s: None,
            correlation,
            declined: Some(why),
        }
    }
}

/// Detects the period of joint angles sampled every `dt` seconds.
///
/// Method: the mean squared difference `MSD(L)` between the angles and
/// themselves `L` samples later (both joints, linear trend removed; from an
/// FFT autocorrelation and prefix sums of squares), as the correlation
/// `r(L) = 1 − MSD(L)/(2 var)`; the period is the shortest lag
/// past the zero-lag lobe whose correlation is within 5 % of the best one,
/// refined by a parabola through the peak and then at the longest multiple
/// of it within half the record (the error divides by that multiple). Declines (with the reason) when the record holds fewer than
/// two repeats, the angles never decorrelate (no motion, or drift only), or
/// the best repeat correlates below [`MIN_PERIOD_CORRELATION`].
pub fn detect_period(theta: &[&[f64]], dt: f64) -> PeriodDetection {
    let n = theta.iter().map(|x| x.len()).min().unwrap_or(0);
    if n < 64 || !(dt.is_finite() && dt > 0.0) {
        return PeriodDetection::decline(0.0, format!("{n} samples are too few to find a period"));
    }
    let m = 2 * n;
    let mut planner = FftPlanner::new();
    let fwd = planner.plan_fft_forward(m);
    let inv = planner.plan_fft_inverse(m);
    let mut acf = vec![0.0; n];
    // Prefix sums of y² per joint, for the mean squared difference.
    let mut sq = vec![vec![0.0; n + 1]; theta.len()];
    for (j, x) in theta.iter().enumerate() {
        let x = &x[..n];
        let (a, b) = linear_fit(x);
        let y = |i: usize| x[i] - a - b * i as f64;
        for i in 0..n {
            sq[j][i + 1] = sq[j][i] + y(i) * y(i);
        }
        let mut buf: Vec<Complex64> = (0..m)
            .map(|i| Complex64::new(if i < n { y(i) } else { 0.0 }, 0.0))
            .collect();
        fwd.process(&mut buf);
        for c in buf.iter_mut() {
            *c = Complex64::new(c.norm_sqr(), 0.0);
        }
        inv.process(&mut buf);
        for (l, r) in acf.iter_mut().enumerate() {
            *r += buf[l].re / m as f64;
        }
    }
    let total: f64 = sq.iter().map(|s| s[n]).sum();
    if total <= 0.0 || !total.is_finite() {
        return PeriodDetection::decline(0.0, "the angles do not move".into());
    }
    // r(L) = 1 − MSD(L)/(2 var): 1 for an exact repeat, 0 for unrelated
    // values; MSD(L) = mean over the overlap of (y(i) − y(i+L))².
    let var = total / n as f64;
    let r: Vec<f64> = (0..n)
        .map(|l| {
            let ss: f64 = sq.iter().map(|s| s[n - l] + (s[n] - s[l])).sum::<f64>();
            1.0 - (ss - 2.0 * acf[l]) / (n - l) as f64 / (2.0 * var)
        })
        .collect();
    let half = n / 2;
    let Some(first_zero) = (1..half).find(|&l| r[l] <= 0.0) else {
        return PeriodDetection::decline(
            r[half.saturating_sub(1)],
            "the angles do not decorrelate within half the record (no repeated motion, \
             or fewer than two periods)"
                .into(),
        );
    };
    let peaks: Vec<usize> = (first_zero + 1..half)
        .filter(|&l| r[l] >= r[l - 1] && r[l] > r[l + 1])
        .collect();
    let best = peaks
        .iter()
        .map(|&l| r[l])
        .fold(f64::NEG_INFINITY, f64::max);
    let Some(&p0) = peaks.iter().find(|&&l| r[l] >= best - 0.05 * best.abs()) else {
        return PeriodDetection::decline(
            0.0,
            "no repeat of the motion within half the record (record at least two periods)".into(),
        );
    };
    if r[p0] < MIN_PERIOD_CORRELATION {
        return PeriodDetection::decline(
            r[p0],
            format!(
                "the best repeat ({:.4} s) correlates only {:.3} < {MIN_PERIOD_CORRELATION}: \
                 the motion is not periodic enough to average (give --period if it is)",
                p0 as f64 * dt,
                r[p0]
            ),
        );
    }
    let coarse = parabola_peak(&r, p0);
    // Refine at the longest multiple within half the record (half the
    // record overlaps, so a start-up transient weighs little).
    let q = (half as f64 / coarse).floor().max(1.0) as usize;
    let guess = (q as f64 * coarse).round() as usize;
    // Neighbouring repeats are a period apart: a quarter-period window
    // holds one peak whatever the coarse error.
    let w = (p0 / 4).max(2).min(guess.saturating_sub(1));
    let lo = guess.saturating_sub(w).max(1);
    let hi = (guess + w).min(n - 2);
    let lq = (lo..=hi)
        .max_by(|&a, &b| r[a].total_cmp(&r[b]))
        .unwrap_or(p0);
    let period = if lq > lo && lq < hi {
        parabola_peak(&r, lq) / q as f64
    } else {
        coarse
    };
    PeriodDetection {
        period_s: Some(period * dt),
        correlation: r[p0],
        declined: None,
    }
}

/// Vertex of the parabola through `r[l−1], r[l], r[l+1]`.
fn parabola_peak(r: &[f64], l: usize) -> f64 {
    let (a, b, c) = (r[l - 1], r[l], r[l + 1]);
    let den = a - 2.0 * b + c;
    if den.abs() < f64::MIN_POSITIVE {
        return l as f64;
    }
    l as f64 + (0.5 * (a - c) / den).clamp(-0.5, 0.5)
}

/// Least-squares line `a + b·i` through `x[i]`.
fn linear_fit(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mi = (n - 1.0) / 2.0;
    let mx = x.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, v) in x.iter().enumerate() {
        let d = i as f64 - mi;
        sxy += d * (v - mx);
        sxx += d * d;
    }
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (mx - b * mi, b)
}

/// The harmonic series kept for one joint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HarmonicSelection {
    /// Harmonics of the period kept (`1..=harmonics`).
    pub harmonics: usize,
    /// Frequency of the highest kept harmonic (Hz).
    pub highest_hz: f64,
    /// Candidate harmonics below the Nyquist frequency.
    pub candidates: usize,
    /// Noise floor: mean power of one noise-only DFT bin, as the RMS angle
    /// per sample it stands for (rad).
    pub noise_rms: f64,
    /// Power ratio over the floor a harmonic needed (`ln(H/α)`).
    pub threshold: f64,
}

/// Fits the harmonic series to one block of `kp` periods (uniform step
/// `dt`, `fourier` planned for its length) and replaces `x` by the series,
/// `first`, `second` by its derivatives.
pub(crate) fn harmonic_fit(
    f: &mut Fourier,
    x: &mut [f64],
    first: &mut [f64],
    second: &mut [f64],
    kp: usize,
    dt: f64,
) -> HarmonicSelection {
    let n = x.len();
    let spec = f.spectrum(x);
    let power = |k: usize| spec[k].norm_sqr();
    let nyq = n / 2;
    let candidates = (1..)
        .take_while(|m| m * kp < nyq || (m * kp == nyq && n % 2 == 1))
        .count();
    let upper: Vec<f64> = ((n / 4).max(1) + 1..=nyq).map(power).collect();
    let floor = if upper.len() >= 8 {
        median(upper) / std::f64::consts::LN_2
    } else {
        0.0
    };
    let threshold = ((candidates.max(1)) as f64 / HARMONIC_FALSE_ALARM).ln();
    let harmonics = (1..=candidates)
        .rev()
        .find(|&m| power(m * kp) > threshold * floor)
        .unwrap_or(0);
    let top = harmonics * kp;
    let w0 = std::f64::consts::TAU / (n as f64 * dt);
    let keep = |k: i64| -> bool {
        k == 0
            || ((k.unsigned_abs() as usize).is_multiple_of(kp) && k.unsigned_abs() as usize <= top)
    };
    f.synthesise(&spec, x, |k| {
        if keep(k) {
            Complex64::new(1.0, 0.0)
        } else {
            Complex64::new(0.0, 0.0)
        }
    });
    f.synthesise(&spec, first, |k| {
        if keep(k) && 2 * k.unsigned_abs() as usize != n {
            Complex64::new(0.0, w0 * k as f64)
        } else {
            Complex64::new(0.0, 0.0)
        }
    });
    f.synthesise(&spec, second, |k| {
        if keep(k) {
            Complex64::new(-(w0 * k as f64).powi(2), 0.0)
        } else {
            Complex64::new(0.0, 0.0)
        }
    });
    HarmonicSelection {
        harmonics,
        highest_hz: top as f64 * w0 / std::f64::consts::TAU,
        candidates,
        // |X_k|² of white noise σ² is n σ².
        noise_rms: (floor / n as f64).sqrt(),
        threshold,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// The cut-off the angle spectrum asks for (non-periodic records).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpectrumCutoff {
    /// The chosen cut-off (Hz).
    pub cutoff_hz: f64,
    /// Per joint: highest frequency whose power stands above the floor (Hz).
    pub motion_top_hz: Vec<f64>,
    /// Per joint: the white-noise level the floor stands for, as the RMS
    /// angle per sample (rad).
    pub noise_rms: Vec<f64>,
    /// Welch segment length (samples) and segments averaged.
    pub segments: [usize; 2],
}

/// Chooses a zero-phase low-pass cut-off from the angles' spectrum
/// (uniform step `dt`), by the rule of the module documentation. Records
/// shorter than 256 samples get `0.4 fs` (no spectrum to judge).
pub fn spectrum_cutoff(theta: &[&[f64]], dt: f64) -> SpectrumCutoff {
    let fs = 1.0 / dt;
    let joints = theta.len();
    let n = theta.iter().map(|x| x.len()).min().unwrap_or(0);
    let max_cut = 0.4 * fs;
    if n < 256 {
        return SpectrumCutoff {
            cutoff_hz: max_cut,
            motion_top_hz: vec![max_cut; joints],
            noise_rms: vec![0.0; joints],
            segments: [0, 0],
        };
    }
    // Segments: a power of two, at most n/4 (≥ 7 segments at 50 % overlap)
    // and 8192 samples.
    let mut len = 64usize;
    while len * 2 <= (n - 1) / 4 && len < 8192 {
        len *= 2;
    }
    let hop = len / 2;
    let count = (n - 1 - len) / hop + 1;
    let mut fourier = Fourier::new(len);
    let window = hann(len);
    let wss: f64 = window.iter().map(|w| w * w).sum();
    let mut out = SpectrumCutoff {
        cutoff_hz: 0.0,
        motion_top_hz: vec![0.0; joints],
        noise_rms: vec![0.0; joints],
        segments: [len, count],
    };
    let mut segment = vec![0.0; len];
    for (j, x) in theta.iter().enumerate() {
        let mut psd = vec![0.0; len / 2 + 1];
        for s in 0..count {
            let d = &x[s * hop..s * hop + len + 1];
            let mean = (d[len] - d[0]) / len as f64;
            for (i, b) in segment.iter_mut().enumerate() {
                *b = (d[i + 1] - d[i] - mean) * window[i];
            }
            fourier.add_power(&segment, &mut psd);
        }
        let shape = |k: usize| (std::f64::consts::PI * k as f64 / len as f64).sin().powi(2);
        let ratios: Vec<f64> = (len / 4 + 1..=len / 2).map(|k| psd[k] / shape(k)).collect();
        // The mean, not the median: quantisation of a periodic motion is
        // itself a line spectrum, and its lines belong to the floor.
        let c = ratios.iter().sum::<f64>() / ratios.len().max(1) as f64;
        let top = (1..len / 4)
            .rev()
            .find(|&k| psd[k] > SPECTRUM_THRESHOLD * c * shape(k))
            .unwrap_or(1);
        out.motion_top_hz[j] = top as f64 * fs / len as f64;
        // E|X_k|² of differenced white noise σ²: 4 sin² · σ² · Σw², summed
        // over the segments.
        out.noise_rms[j] = (c / (4.0 * wss * count as f64)).sqrt();
    }
    let lowest = 2.0 / (n as f64 * dt);
    let top = out
        .motion_top_hz
        .iter()
        .fold(f64::NEG_INFINITY, |a, b| a.max(*b));
    out.cutoff_hz = (CUTOFF_MARGIN * top).clamp(lowest.min(max_cut), max_cut);
    out
}

/// Resamples `(t, x)` onto `t0 + k·dt`, `k < n`, by cubic Hermite
/// interpolation with slopes from the three-point formula of the
/// non-uniform grid (exact for quadratics; `t` strictly increasing).
pub(crate) fn resample(t: &[f64], x: &[f64], t0: f64, dt: f64, n: usize) -> Vec<f64> {
    let slopes = nonuniform_slopes(t, x);
    let grid: Vec<f64> = (0..n).map(|k| t0 + k as f64 * dt).collect();
    hermite_at(t, x, &slopes, &grid)
}

/// Three-point first derivative on a non-uniform grid (second-order at the
/// interior, one-sided second-order at the ends).
pub(crate) fn nonuniform_slopes(t: &[f64], x: &[f64]) -> Vec<f64> {
    let n = t.len();
    if n < 3 {
        let s = if n == 2 {
            (x[1] - x[0]) / (t[1] - t[0])
        } else {
            0.0
        };
        return vec![s; n];
    }
    let three = |i0: usize, at: usize| -> f64 {
        // Derivative at t[at] of the parabola through i0, i0+1, i0+2.
        let (a, b, c) = (t[i0], t[i0 + 1], t[i0 + 2]);
        let s = t[at];
        x[i0] * ((s - b) + (s - c)) / ((a - b) * (a - c))
            + x[i0 + 1] * ((s - a) + (s - c)) / ((b - a) * (b - c))
            + x[i0 + 2] * ((s - a) + (s - b)) / ((c - a) * (c - b))
    };
    (0..n)
        .map(|i| match i {
            0 => three(0, 0),
            _ if i == n - 1 => three(n - 3, n - 1),
            _ => three(i - 1, i),
        })
        .collect()
}

/// Cubic Hermite interpolation of `(t, x, slope)` at sorted `at`
/// (clamped to the ends).
pub(crate) fn hermite_at(t: &[f64], x: &[f64], slope: &[f64], at: &[f64]) -> Vec<f64> {
    let n = t.len();
    let mut j = 0;
    at.iter()
        .map(|&s| {
            if n == 1 {
                return x[0];
            }
            while j + 2 < n && t[j + 1] < s {
                j += 1;
            }
            let h = t[j + 1] - t[j];
            let u = ((s - t[j]) / h).clamp(0.0, 1.0);
            let (u2, u3) = (u * u, u * u * u);
            x[j] * (2.0 * u3 - 3.0 * u2 + 1.0)
                + slope[j] * h * (u3 - 2.0 * u2 + u)
                + x[j + 1] * (-2.0 * u3 + 3.0 * u2)
                + slope[j + 1] * h * (u3 - u2)
        })
        .collect()
}

/// First and second derivatives of a uniformly sampled record with no
/// samples lost: central differences inside, second-order one-sided
/// differences at the two ends.
pub(crate) fn uniform_derivatives(x: &[f64], dt: f64) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    let (s1, s2) = (1.0 / dt, 1.0 / (dt * dt));
    let mut d1 = vec![0.0; n];
    let mut d2 = vec![0.0; n];
    if n < 4 {
        return (d1, d2);
    }
    for i in 1..n - 1 {
        d1[i] = 0.5 * (x[i + 1] - x[i - 1]) * s1;
        d2[i] = (x[i + 1] - 2.0 * x[i] + x[i - 1]) * s2;
    }
    d1[0] = (-1.5 * x[0] + 2.0 * x[1] - 0.5 * x[2]) * s1;
    d1[n - 1] = (1.5 * x[n - 1] - 2.0 * x[n - 2] + 0.5 * x[n - 3]) * s1;
    d2[0] = (2.0 * x[0] - 5.0 * x[1] + 4.0 * x[2] - x[3]) * s2;
    d2[n - 1] = (2.0 * x[n - 1] - 5.0 * x[n - 2] + 4.0 * x[n - 3] - x[n - 4]) * s2;
    (d1, d2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    use std::f64::consts::TAU;

    #[test]
    fn detects_the_period_of_a_fractional_sample_motion() {
        // 0.7 Hz at 1 kHz (1428.57 samples), 20 s, quantised to 1.5e-4 rad.
        let dt = 1e-3;
        let q = 1.5e-4;
        let th: Vec<Vec<f64>> = (0..2)
            .map(|j| {
                (0..20_000)
                    .map(|i| {
                        let t = i as f64 * dt;
                        let v = 1.0
                            + 0.3 * (TAU * 0.7 * t + j as f64).sin()
                            + 0.05 * (3.0 * TAU * 0.7 * t).cos();
                        (v / q).round() * q
                    })
                    .collect()
            })
            .collect();
        let d = detect_period(&[&th[0], &th[1]], dt);
        let p = d.period_s.unwrap();
        // 7 periods must land within 0.05 samples of 10 000 for the
        // averaging to accept them: 7 µs over 10 s, 5e-6 of the period.
        assert!((p * 0.7 - 1.0).abs() < 5e-6, "{p}");
        assert!(d.correlation > 0.99);
    }

    #[test]
    fn declines_noise_and_a_ramp() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let noise: Vec<f64> = (0..5000).map(|_| StandardNormal.sample(&mut rng)).collect();
        let d = detect_period(&[&noise, &noise], 1e-3);
        assert!(d.period_s.is_none() && d.declined.is_some(), "{d:?}");
        // A chirp does not repeat.
        let chirp: Vec<f64> = (0..8000)
            .map(|i| {
                let t = i as f64 * 1e-3;
                (TAU * (0.5 + 0.5 * t) * t).sin()
            })
            .collect();
        let d = detect_period(&[&chirp, &chirp], 1e-3);
        assert!(d.period_s.is_none(), "{d:?}");
    }

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn harmonic_fit_keeps_the_motion_and_drops_the_noise() {
        // 5 harmonics of 0.5 Hz in 2 s (one period, 2000 samples) plus
        // white noise: the fit keeps exactly 5 harmonics and its
        // derivatives are within noise of the exact ones.
        let (n, dt) = (2000, 1e-3);
        let w = TAU * 0.5;
        let amps = [0.3, 0.1, 0.03, 0.01, 0.003];
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let sigma = 1e-5;
        let mut x: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                let e: f64 = StandardNormal.sample(&mut rng);
                amps.iter()
                    .enumerate()
                    .map(|(m, a)| a * ((m + 1) as f64 * w * t).sin())
                    .sum::<f64>()
                    + sigma * e
            })
            .collect();
        let mut f = Fourier::new(n);
        let (mut d1, mut d2) = (x.clone(), x.clone());
        let sel = harmonic_fit(&mut f, &mut x, &mut d1, &mut d2, 1, dt);
        assert_eq!(sel.harmonics, 5, "{sel:?}");
        // The floor estimate is the noise (median of 500 bins: ±10 %).
        assert!((sel.noise_rms / sigma - 1.0).abs() < 0.15, "{sel:?}");
        let mut worst: f64 = 0.0;
        for i in 0..n {
            let t = i as f64 * dt;
            let exact: f64 = amps
                .iter()
                .enumerate()
                .map(|(m, a)| a * ((m + 1) as f64 * w) * ((m + 1) as f64 * w * t).cos())
                .sum();
            worst = worst.max((d1[i] - exact).abs());
        }
        // Noise in 5 kept harmonics: σ·√(2·5/n)·ω_max·few ≈ 1e-5·0.07·16.
        assert!(worst < 1e-4, "{worst}");
    }

    #[test]
    fn cutoff_follows_the_motion() {
        // White noise at the level of a 1.5e-4 rad quantisation step (the
        // rule's noise model). The quantisation of an exactly periodic
        // synthetic signal is a line spectrum instead and can fool the rule;
        // periodic records take the harmonic route.
        let dt = 1e-3;
        let sigma = 1.5e-4 / 12f64.sqrt();
        let mut rng = rand::rngs::StdRng::seed_from_u64(17);
        for f0 in [0.5, 2.5] {
            let x: Vec<f64> = (0..20_000)
                .map(|i| {
                    let t = i as f64 * dt;
                    let e: f64 = StandardNormal.sample(&mut rng);
                    0.3 * (TAU * f0 * t).sin() + 0.01 * (3.0 * TAU * f0 * t).sin() + sigma * e
                })
                .collect();
            let c = spectrum_cutoff(&[&x, &x], dt);
            // The third harmonic is 0.01 rad, 50 dB above the floor; the
            // Hann window's leakage keeps it above the floor for ≈ 1.5–2 Hz
            // (Welch resolution 0.24 Hz): the motion ends within 3 f0 + 2 Hz.
            assert!(
                c.cutoff_hz >= 3.0 * f0 && c.cutoff_hz <= CUTOFF_MARGIN * (3.0 * f0 + 2.0),
                "{f0}: {c:?}"
            );
        }
    }

    #[test]
    fn hermite_resampling_is_fourth_order() {
        // Jittered grid of a smooth signal: resampled within h⁴-scale error.
        let mut rng = rand::rngs::StdRng::seed_from_u64(9);
        let mut t = vec![0.0];
        for _ in 0..2000 {
            let e: f64 = StandardNormal.sample(&mut rng);
            t.push(t.last().unwrap() + 1e-3 * (1.0 + 0.2 * e.clamp(-2.0, 2.0)));
        }
        let x: Vec<f64> = t.iter().map(|s| (TAU * 2.0 * s).sin()).collect();
        let r = resample(&t, &x, 0.0, 1e-3, 1900);
        let worst = r
            .iter()
            .enumerate()
            .map(|(k, v)| (v - (TAU * 2.0 * k as f64 * 1e-3).sin()).abs())
            .fold(0.0, f64::max);
        // Slope error O(h²ω³) times h: ≈ (1.4e-3)³ · 12.6³ ≈ 5e-6.
        assert!(worst < 1e-5, "{worst}");
    }
}
