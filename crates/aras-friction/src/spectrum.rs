//! Lines of a residual's spectrum against position: ripple at any spatial
//! frequency.
//!
//! A gear, a motor's cogging or an encoder's eccentricity leave a torque
//! `A sin(k q + φ)` locked to the joint position, `k` cycles per revolution
//! — up to thousands on a gear-tooth scale, where a small stroke holds a few
//! dozen periods and a grid of integer harmonics cannot reach. The residual
//! is searched as a function of `q` instead:
//!
//! 1. **Periodogram.** The samples are summed into position bins of width
//!    `h` (nearest bin: the sum `Σ rᵢ e^{−ikqᵢ}` of every sample, not a bin
//!    mean, so empty bins cost nothing), zero-padded four times and
//!    transformed by an FFT. The band runs from two periods over the stroke
//!    up to `k_max = π / Δq`, `Δq` the median position step between moving
//!    samples (the per-sample step sets what the sampling resolves); `h` puts
//!    `k_max` at half the grid's Nyquist, where the nearest-bin gridding
//!    keeps ≥ 90 % of a line's amplitude.
//! 2. **Detection.** Each bin's power is divided by the median of its
//!    neighbourhood (a residual is rarely white: its level varies with `k`)
//!    and scaled by `ln 2`, so that on a smooth spectrum it is exponential
//!    with mean 1: `P(z > x) = e^{−x}`. A line needs `z > ln(N / α)`, `N` the
//!    independent frequencies searched (one per Fourier cell `2π / stroke`),
//!    `α` [`SpectrumSettings::false_alarm`]: the look-elsewhere effect of a
//!    wide search, counted.
//! 3. **Refinement.** The peak's `k` is refined on the raw rows by variable
//!    projection: golden-section search of the residual sum of squares of
//!    `r ≈ a sin kq + b cos kq + c` around the peak. `σ_k` is the Gauss–Newton
//!    one: `s² / ‖P⊥ J‖²`, `J = (q − q̄)(a cos kq − b sin kq)` with the line's
//!    own columns projected out, `s²` the residual variance inflated by its
//!    integrated autocorrelation time (the rows are not independent).
//! 4. The line is removed from the residual and the search repeats, up to
//!    [`SpectrumSettings::max_lines`].

use rustfft::{FftPlanner, num_complex::Complex};
use serde::{Deserialize, Serialize};

/// Settings of the line search.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpectrumSettings {
    /// At most this many lines are searched (0: no search).
    pub max_lines: usize,
    /// Probability that the search names a line in pure noise, over the
    /// whole band.
    pub false_alarm: f64,
    /// Harmonics of each line offered to the diagnosis as candidates (1: the
    /// line alone; 3: the line, twice and three times its frequency).
    pub harmonics: u32,
}

impl Default for SpectrumSettings {
    fn default() -> Self {
        Self {
            max_lines: 3,
            false_alarm: 1e-3,
            harmonics: 3,
        }
    }
}

/// One line found in the residual.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpectralLine {
    /// Spatial frequency `k`, cycles per revolution.
    pub cycles: f64,
    /// Standard deviation of `k`.
    pub sigma: f64,
    /// Amplitude `√(a² + b²)` of the line in the residual, N·m.
    pub amplitude: f64,
    /// Normalised peak height `z` (exponential with mean 1 on noise).
    pub z: f64,
    /// Probability that noise alone gives a peak this high somewhere in the
    /// band (`N e^{−z}`, at most 1).
    pub false_alarm: f64,
}

/// The search's outcome: the band searched and the lines found, strongest
/// first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PositionSpectrum {
    /// Lowest and highest `k` searched, cycles per revolution (equal when
    /// the log resolves no band).
    pub band: (f64, f64),
    /// The detection threshold on `z`.
    pub threshold: f64,
    /// The lines found.
    pub lines: Vec<SpectralLine>,
}

impl PositionSpectrum {
    /// No band: the log's stroke or sampling resolves no ripple.
    fn empty() -> Self {
        Self {
            band: (0.0, 0.0),
            threshold: f64::INFINITY,
            lines: Vec::new(),
        }
    }

    /// σ of a ripple at `cycles` that is a line found here or one of its
    /// harmonics (`h k` has σ `h σ_k`); `None` otherwise.
    pub fn sigma_of(&self, cycles: f64) -> Option<f64> {
        self.lines.iter().find_map(|l| {
            let h = (cycles / l.cycles).round();
            (h >= 1.0 && (cycles - h * l.cycles).abs() <= 1e-9 * cycles.abs())
                .then_some(h * l.sigma)
        })
    }

    /// The lowest `k` searched: below it a ripple is a smooth function of
    /// the position over the stroke, not a line.
    pub fn lowest(&self) -> f64 {
        self.band.0
    }
}

/// Most bins of the position grid (before padding): 2²⁰ keep the FFT at a
/// few tens of milliseconds.
const MAX_BINS: usize = 1 << 20;
/// Zero-padding factor: peaks at a quarter of a Fourier cell.
const PAD: usize = 4;
/// Bins of the neighbourhood whose median sets a bin's noise level.
const BLOCK: usize = 1024;

/// The position lines of residual `r` at positions `q` (same length, finite;
/// the rows need not be sorted or evenly spaced).
pub fn position_lines(q: &[f64], r: &[f64], settings: &SpectrumSettings) -> PositionSpectrum {
    let n = q.len().min(r.len());
    let Some(grid) = Grid::new(&q[..n]) else {
        return PositionSpectrum::empty();
    };
    let mut resid: Vec<f64> = r[..n].to_vec();
    let cells = ((grid.k_hi - grid.k_lo) / grid.cell()).max(1.0);
    let threshold = (cells / settings.false_alarm).ln();
    let mut lines = Vec::new();
    let mut planner = FftPlanner::new();
    for _ in 0..settings.max_lines {
        let Some((k0, z)) = grid.peak(&q[..n], &resid, &mut planner) else {
            break;
        };
        if z <= threshold {
            break;
        }
        let line = refine(&q[..n], &mut resid, k0, grid.spacing());
        lines.push(SpectralLine {
            z,
            false_alarm: (cells * (-z).exp()).min(1.0),
            ..line
        });
    }
    PositionSpectrum {
        band: (grid.k_lo, grid.k_hi),
        threshold,
        lines,
    }
}

/// The position grid of a log and the band it resolves.
struct Grid {
    q_min: f64,
    stroke: f64,
    /// Bin width, rad.
    h: f64,
    bins: usize,
    /// Padded FFT length.
    len: usize,
    k_lo: f64,
    k_hi: f64,
}

impl Grid {
    fn new(q: &[f64]) -> Option<Self> {
        let (lo, hi) = q
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let stroke = hi - lo;
        if !(stroke.is_finite() && stroke > 0.0) {
            return None;
        }
        let mut steps: Vec<f64> = q
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .filter(|d| *d > 0.0)
            .collect();
        if steps.is_empty() {
            return None;
        }
        let mid = steps.len() / 2;
        let step = *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
        let k_lo = 2.0 * std::f64::consts::TAU / stroke;
        // k_max at half the grid's Nyquist π/h, within MAX_BINS bins.
        let h_min = stroke / (MAX_BINS - 1) as f64;
        let h = (step / 2.0).max(h_min);
        let k_hi = std::f64::consts::PI / (2.0 * h);
        if k_hi <= 2.0 * k_lo {
            return None;
        }
        let bins = (stroke / h).ceil() as usize + 1;
        Some(Self {
            q_min: lo,
            stroke,
            h,
            bins,
            len: (PAD * bins).next_power_of_two(),
            k_lo,
            k_hi,
        })
    }

    /// A Fourier cell, `2π / stroke`: the spacing of independent frequencies.
    fn cell(&self) -> f64 {
        std::f64::consts::TAU / self.stroke
    }

    /// The padded FFT's frequency spacing.
    fn spacing(&self) -> f64 {
        std::f64::consts::TAU / (self.len as f64 * self.h)
    }

    /// The highest normalised peak of the residual's periodogram in the
    /// band: its `k` and `z`.
    fn peak(&self, q: &[f64], r: &[f64], planner: &mut FftPlanner<f64>) -> Option<(f64, f64)> {
        let mut buf = vec![Complex::new(0.0, 0.0); self.len];
        let mean = r.iter().sum::<f64>() / r.len().max(1) as f64;
        for (&x, &y) in q.iter().zip(r) {
            let j = (((x - self.q_min) / self.h).round() as usize).min(self.bins - 1);
            buf[j].re += y - mean;
        }
        planner.plan_fft_forward(self.len).process(&mut buf);
        let dk = self.spacing();
        let lo = (self.k_lo / dk).ceil() as usize;
        let hi = ((self.k_hi / dk).floor() as usize).min(self.len / 2);
        if hi <= lo {
            return None;
        }
        let power: Vec<f64> = buf[lo..=hi].iter().map(|c| c.norm_sqr()).collect();
        let mut best: Option<(usize, f64)> = None;
        let blocks = power.len().div_ceil(BLOCK);
        for b in 0..blocks {
            // Each block's level is its own median; a last short block is
            // measured with the full block before it.
            let end = ((b + 1) * BLOCK).min(power.len());
            let start = b * BLOCK;
            let from = end.saturating_sub(BLOCK).min(start);
            let mut sorted = power[from..end].to_vec();
            let mid = sorted.len() / 2;
            let level = *sorted.select_nth_unstable_by(mid, f64::total_cmp).1;
            if level <= 0.0 {
                continue;
            }
            for (i, &p) in power[start..end].iter().enumerate() {
                let z = std::f64::consts::LN_2 * p / level;
                if best.is_none_or(|(_, bz)| z > bz) {
                    best = Some((start + i, z));
                }
            }
        }
        best.map(|(i, z)| ((lo + i) as f64 * dk, z))
    }
}

/// A line on one log: `A sin(k q + φ)` fitted to that log's residual at a
/// given `k`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LinePhase {
    /// Amplitude `A`, N·m.
    pub amplitude: f64,
    /// Phase `φ`, rad in (−π, π].
    pub phase: f64,
    /// σ of `φ` (white-noise σ inflated by the residual's autocorrelation
    /// time).
    pub sigma: f64,
}

/// `x` wrapped to (−π, π]: the difference of two phases.
pub fn wrapped(x: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let w = (x + PI).rem_euclid(TAU) - PI;
    if w == -PI { PI } else { w }
}

/// The line at `k` on one log's residual `r` at positions `q`; `None` when
/// the log holds too few rows or its positions do not separate the columns.
pub fn line_phase(q: &[f64], r: &[f64], k: f64) -> Option<LinePhase> {
    let n = q.len().min(r.len());
    if n < 8 {
        return None;
    }
    let fit = line_fit(&q[..n], &r[..n], k)?;
    let [a, b, c] = fit.coef;
    let amplitude = a.hypot(b);
    let left: Vec<f64> = q[..n]
        .iter()
        .zip(&r[..n])
        .map(|(&x, &y)| {
            let (s, co) = (k * x).sin_cos();
            y - a * s - b * co - c
        })
        .collect();
    let tau = aras_ident::stats::integrated_time(&left, 1000).max(1.0);
    // sin and cos over many periods: each coefficient has σ ≈ s √(2/n),
    // and the phase σ is that over the amplitude.
    let s = (fit.rss / (n - 3) as f64).sqrt();
    let sigma = s * (2.0 * tau / n as f64).sqrt() / amplitude.max(f64::MIN_POSITIVE);
    Some(LinePhase {
        amplitude,
        phase: b.atan2(a),
        sigma,
    })
}

/// The least-squares fit of `r ≈ a sin kq + b cos kq + c` at one `k`.
struct LineFit {
    coef: [f64; 3],
    rss: f64,
}

fn line_fit(q: &[f64], r: &[f64], k: f64) -> Option<LineFit> {
    // Normal equations of three columns that are orthogonal up to the
    // stroke's end effects (many periods): well conditioned, and O(n).
    let mut ne = Normal3::default();
    let mut rr = 0.0;
    for (&x, &y) in q.iter().zip(r) {
        let (s, c) = (k * x).sin_cos();
        ne.push([s, c, 1.0], y);
        rr += y * y;
    }
    let coef = solve3(ne.g, ne.b)?;
    let explained: f64 = (0..3).map(|i| coef[i] * ne.b[i]).sum();
    Some(LineFit {
        coef,
        rss: (rr - explained).max(0.0),
    })
}

/// Normal equations `VᵀV`, `Vᵀy` of three columns, row by row.
#[derive(Default)]
struct Normal3 {
    g: [[f64; 3]; 3],
    b: [f64; 3],
}

impl Normal3 {
    fn push(&mut self, v: [f64; 3], y: f64) {
        for i in 0..3 {
            self.b[i] += v[i] * y;
            for j in 0..3 {
                self.g[i][j] += v[i] * v[j];
            }
        }
    }
}

/// Solves a symmetric 3×3 system by Cholesky; `None` when it is singular.
fn solve3(g: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let s: f64 = g[i][j] - (0..j).map(|m| l[i][m] * l[j][m]).sum::<f64>();
            if i == j {
                if s <= 1e-12 * g[i][i].abs().max(f64::MIN_POSITIVE) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = [0.0; 3];
    for i in 0..3 {
        y[i] = (b[i] - (0..i).map(|m| l[i][m] * y[m]).sum::<f64>()) / l[i][i];
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        x[i] = (y[i] - (i + 1..3).map(|m| l[m][i] * x[m]).sum::<f64>()) / l[i][i];
    }
    Some(x)
}

/// Refines a peak near `k0` (search ±`width`), removes the fitted line from
/// `r` and returns it (its `z` and false alarm left for the caller).
fn refine(q: &[f64], r: &mut [f64], k0: f64, width: f64) -> SpectralLine {
    let rss = |k: f64| line_fit(q, r, k).map_or(f64::INFINITY, |f| f.rss);
    let k = golden(rss, k0 - width, k0 + width);
    let fit = line_fit(q, r, k);
    let [a, b, c] = fit.as_ref().map_or([0.0; 3], |f| f.coef);
    for (y, &x) in r.iter_mut().zip(q) {
        let (s, co) = (k * x).sin_cos();
        *y -= a * s + b * co + c;
    }
    SpectralLine {
        cycles: k,
        sigma: sigma_k(q, r, k, a, b),
        amplitude: a.hypot(b),
        z: 0.0,
        false_alarm: 1.0,
    }
}

/// Golden-section minimum of `f` on `[lo, hi]` to a relative 1e-12 of `k`.
fn golden(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..80 {
        if hi - lo <= 1e-12 * hi.abs().max(1.0) {
            break;
        }
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        }
    }
    0.5 * (lo + hi)
}

/// σ of a line's `k` from the residual `r` left after removing it.
fn sigma_k(q: &[f64], r: &[f64], k: f64, a: f64, b: f64) -> f64 {
    let n = q.len();
    if n < 5 {
        return f64::INFINITY;
    }
    let qm = q.iter().sum::<f64>() / n as f64;
    // ‖P⊥ J‖² = ‖J‖² − Jᵀ V (VᵀV)⁻¹ Vᵀ J, V = [sin, cos, 1].
    let mut ne = Normal3::default();
    let mut jj = 0.0;
    for &x in q {
        let (s, c) = (k * x).sin_cos();
        let j = (x - qm) * (a * c - b * s);
        ne.push([s, c, 1.0], j);
        jj += j * j;
    }
    let Some(w) = solve3(ne.g, ne.b) else {
        return f64::INFINITY;
    };
    let perp = jj - (0..3).map(|i| w[i] * ne.b[i]).sum::<f64>();
    let s2 = r.iter().map(|y| y * y).sum::<f64>() / (n - 4) as f64;
    let tau = aras_ident::stats::integrated_time(r, 1000).max(1.0);
    if perp > 0.0 {
        (s2 * tau / perp).sqrt()
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reproducible pseudo-random sequence in [0, 1).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn normal(u: &mut impl FnMut() -> f64) -> f64 {
        (-2.0 * u().max(1e-300).ln()).sqrt() * (std::f64::consts::TAU * u()).cos()
    }

    /// A slow back-and-forth stroke of `stroke` rad sampled `n` times.
    fn positions(n: usize, stroke: f64, seed: u64) -> Vec<f64> {
        let mut u = uniform(seed);
        let mut t = 0.0;
        (0..n)
            .map(|_| {
                t += 0.001 + 0.015 * u();
                0.5 * stroke * ((0.3 * t).sin() * 0.8 + 0.2 * (1.1 * t + 1.0).sin())
            })
            .collect()
    }

    #[test]
    fn a_hidden_line_is_found_at_its_frequency_with_sigma() {
        let q = positions(20_000, 0.03, 3);
        let mut u = uniform(9);
        let (k, amp) = (5123.4, 0.02);
        let r: Vec<f64> = q
            .iter()
            .map(|&x| amp * (k * x + 0.7).sin() + 0.01 * normal(&mut u))
            .collect();
        let s = position_lines(&q, &r, &SpectrumSettings::default());
        let line = s.lines.first().expect("a line");
        assert!(
            (line.cycles - k).abs() < 5.0 * line.sigma,
            "{} ± {}",
            line.cycles,
            line.sigma
        );
        assert!(line.sigma / k < 1e-3, "σ {}", line.sigma);
        assert!(
            (line.amplitude - amp).abs() < 0.05 * amp,
            "{}",
            line.amplitude
        );
        assert_eq!(s.lines.len(), 1, "{:?}", s.lines);
    }

    #[test]
    fn noise_alone_gives_no_line() {
        let mut found = 0;
        for seed in 0..20 {
            let q = positions(10_000, 0.05, seed);
            let mut u = uniform(100 + seed);
            let r: Vec<f64> = (0..q.len()).map(|_| normal(&mut u)).collect();
            found += position_lines(&q, &r, &SpectrumSettings::default())
                .lines
                .len();
        }
        // α = 1e-3 per search: 20 searches should find none.
        assert_eq!(found, 0);
    }

    #[test]
    fn a_joint_that_does_not_move_has_no_band() {
        let q = vec![0.1; 100];
        let r = vec![0.0; 100];
        let s = position_lines(&q, &r, &SpectrumSettings::default());
        assert!(s.lines.is_empty());
        assert_eq!(s.band, (0.0, 0.0));
    }
}
