//! Where model and measurement disagree: the validation residual per joint,
//! binned against velocity (with bins at rest and split by sign), position,
//! acceleration and time, its whiteness, and the bins whose mean is beyond
//! what noise explains.

use serde::Serialize;

use aras_ident::stats::{integrated_time, ljung_box};

/// What a residual is binned against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    /// Joint rate θ̇ (rad/s).
    Velocity,
    /// Joint angle θ (rad).
    Position,
    /// Joint acceleration θ̈ (rad/s²).
    Acceleration,
    /// Time (s).
    Time,
}

impl Axis {
    fn unit(self) -> &'static str {
        match self {
            Axis::Velocity => "rad/s",
            Axis::Position => "rad",
            Axis::Acceleration => "rad/s²",
            Axis::Time => "s",
        }
    }
    fn symbol(self) -> &'static str {
        match self {
            Axis::Velocity => "θ̇",
            Axis::Position => "θ",
            Axis::Acceleration => "θ̈",
            Axis::Time => "t",
        }
    }
}

/// One bin of a residual profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Bin {
    /// Lower edge.
    pub lo: f64,
    /// Upper edge.
    pub hi: f64,
    /// Samples in the bin.
    pub count: usize,
    /// Mean residual (N·m).
    pub mean: f64,
    /// Standard error of the mean from the noise level and the effective
    /// number of independent samples in the bin (N·m).
    pub std_error: f64,
}

impl Bin {
    /// `mean / std_error`.
    pub fn z(&self) -> f64 {
        if self.std_error > 0.0 {
            self.mean / self.std_error
        } else {
            0.0
        }
    }
}

/// The residual of one joint binned against one axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Profile {
    /// Joint (1 or 2).
    pub joint: usize,
    /// The axis.
    pub axis: Axis,
    /// Bins in increasing order of the axis.
    pub bins: Vec<Bin>,
}

/// Whiteness of a joint's residual (Ljung–Box on the residual decimated to
/// the filter's independent-sample spacing).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Whiteness {
    /// Joint (1 or 2).
    pub joint: usize,
    /// Decimation step (samples).
    pub step: usize,
    /// Lags tested.
    pub lags: usize,
    /// Ljung–Box Q.
    pub q: f64,
    /// p-value under "white noise".
    pub p_value: f64,
    /// Integrated autocorrelation time of the undecimated residual (samples).
    pub autocorrelation_time: f64,
    /// Residual RMS (N·m).
    pub rms: f64,
}

impl Whiteness {
    /// True if whiteness is not rejected at the 1 % level.
    pub fn is_white(&self) -> bool {
        self.p_value >= 0.01
    }
}

/// One statement about a residual, in words with numbers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Finding {
    /// Joint (1 or 2).
    pub joint: usize,
    /// The sentence.
    pub text: String,
    /// True if beyond noise (|z| above the threshold).
    pub systematic: bool,
    /// The z-score behind the statement.
    pub z: f64,
}

/// The residual analysis of one data set.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ResidualAnalysis {
    /// Data set name.
    pub dataset: String,
    /// Profiles per joint and axis.
    pub profiles: Vec<Profile>,
    /// Whiteness per joint.
    pub whiteness: Vec<Whiteness>,
    /// Findings, systematic ones first.
    pub findings: Vec<Finding>,
    /// Per joint, the same residual on the rows the fits leave out near
    /// velocity reversals: not part of [`Self::noise_like`], which judges
    /// the rows the candidates were fitted and scored on, but where a
    /// low-speed friction law the model lacks shows.
    pub left_out: Vec<LeftOut>,
    /// Per joint, where in frequency the residual (every row) has its
    /// power, next to the measured torque's.
    pub spectra: Vec<ResidualSpectrum>,
}

/// One frequency band of a residual spectrum.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpectrumBand {
    /// Lower edge (Hz).
    pub lo_hz: f64,
    /// Upper edge (Hz).
    pub hi_hz: f64,
    /// Fraction of the residual's power in the band.
    pub residual_share: f64,
    /// Fraction of the measured torque's power in the band.
    pub torque_share: f64,
    /// The band's mean residual power density over the median density of
    /// the filter's pass band (≈ 1 for filtered white noise).
    pub density_ratio: f64,
}

/// Where in frequency one joint's residual has its power.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ResidualSpectrum {
    /// Joint (1 or 2).
    pub joint: usize,
    /// Octave bands from the lowest resolved frequency to the pass band's
    /// end, with the mean (0 Hz) as a band of its own.
    pub bands: Vec<SpectrumBand>,
    /// Frequencies of the plotted densities (Hz, up to twice the cut-off).
    pub frequencies_hz: Vec<f64>,
    /// Residual power density at those frequencies (N²·m²/Hz).
    pub residual_density: Vec<f64>,
    /// Measured torque's power density there (N²·m²/Hz).
    pub torque_density: Vec<f64>,
    /// The band holding most of the residual power, in words, when it holds
    /// at least half of it at ≥ [`SPECTRAL_EXCESS`] times the pass band's
    /// median density.
    pub finding: Option<Finding>,
}

/// Density ratio above which a band's residual power counts as
/// concentrated (filtered white noise is flat in the pass band: its bands'
/// ratios scatter around 1 by the estimate's few-tens-of-% variance).
pub const SPECTRAL_EXCESS: f64 = 10.0;

/// The residual of one joint on the rows that the fits leave out near its
/// velocity reversals (`DiagnoseOptions::min_speed`, widened by the
/// filter's reach), next to the fitted rows' figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeftOut {
    /// Joint (1 or 2).
    pub joint: usize,
    /// Rows left out.
    pub rows: usize,
    /// Rows fitted.
    pub fitted_rows: usize,
    /// Residual RMS on the rows left out (N·m).
    pub rms: f64,
    /// Residual RMS on the fitted rows (N·m).
    pub fitted_rms: f64,
    /// Validation fitness (78) on every row of the set (%).
    pub fitness_all_rows: f64,
    /// Validation fitness (78) on the fitted rows (%).
    pub fitness_fitted_rows: f64,
    /// The residual of the rows left out binned against velocity (rest
    /// band split by sign, quantile bins beyond), standard errors from the
    /// fitted rows' RMS.
    pub profile: Profile,
    /// Bins beyond [`Z_SYSTEMATIC`] standard errors, in words, largest
    /// first.
    pub findings: Vec<Finding>,
}

impl ResidualAnalysis {
    /// True if no bin is systematic and both joints' residuals are white.
    pub fn noise_like(&self) -> bool {
        self.whiteness.iter().all(|w| w.is_white()) && !self.findings.iter().any(|f| f.systematic)
    }

    /// The velocity profile of `joint` (1 or 2).
    pub fn velocity_profile(&self, joint: usize) -> Option<&Profile> {
        self.profiles
            .iter()
            .find(|p| p.joint == joint && p.axis == Axis::Velocity)
    }
}

/// Velocity below which a joint counts as at rest (rad/s): a few encoder
/// quanta per 10 ms.
pub const REST_VELOCITY: f64 = 0.05;
/// |z| above which a bin mean is called systematic. With about 30 bins per
/// joint, 4 keeps the chance of a false call under 0.2 % per analysis.
pub const Z_SYSTEMATIC: f64 = 4.0;

/// Per-joint inputs of the analysis.
pub(crate) struct JointData<'a> {
    pub residual: &'a [f64],
    pub theta: &'a [f64],
    pub theta_dot: &'a [f64],
    pub theta_ddot: &'a [f64],
    pub t: &'a [f64],
}

fn quantile_edges(x: &[f64], bins: usize) -> Vec<f64> {
    let mut v: Vec<f64> = x.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        return vec![];
    }
    let mut e: Vec<f64> = (0..=bins).map(|i| v[((v.len() - 1) * i) / bins]).collect();
    e.dedup();
    e
}

fn bin_by(x: &[f64], r: &[f64], edges: &[f64], sigma: f64, dof_ratio: f64) -> Vec<Bin> {
    let nb = edges.len().saturating_sub(1);
    let mut sum = vec![0.0; nb];
    let mut cnt = vec![0usize; nb];
    for (xi, ri) in x.iter().zip(r) {
        // Upper edge of the last bin is inclusive.
        let k = edges[1..]
            .partition_point(|e| e < xi)
            .min(nb.saturating_sub(1));
        if nb > 0 && *xi >= edges[0] {
            sum[k] += ri;
            cnt[k] += 1;
        }
    }
    (0..nb)
        .filter(|&k| cnt[k] > 0)
        .map(|k| {
            let neff = (cnt[k] as f64 * dof_ratio).max(1.0);
            Bin {
                lo: edges[k],
                hi: edges[k + 1],
                count: cnt[k],
                mean: sum[k] / cnt[k] as f64,
                std_error: sigma / neff.sqrt(),
            }
        })
        .collect()
}

/// Velocity edges: the rest band `±REST_VELOCITY` split at zero, and four
/// quantile bins of |θ̇| on each side, starting at the rest band's edges
/// (the quantiles' outermost edge would leave a bin of one sample there).
fn velocity_edges(v: &[f64]) -> Vec<f64> {
    let pos: Vec<f64> = v.iter().copied().filter(|x| *x >= REST_VELOCITY).collect();
    let neg: Vec<f64> = v.iter().copied().filter(|x| *x <= -REST_VELOCITY).collect();
    let mut e: Vec<f64> = quantile_edges(&neg, 4);
    if e.len() > 1 {
        e.pop();
    }
    e.extend([-REST_VELOCITY, 0.0, REST_VELOCITY]);
    let p = quantile_edges(&pos, 4);
    e.extend(p.iter().skip(usize::from(p.len() > 1)));
    e.sort_by(|a, b| a.total_cmp(b));
    e.dedup();
    e
}

/// Analyses the residuals of both joints. `sigma` is each joint's noise
/// level per sample (N·m), `dof_ratio` the fraction of samples that are
/// independent (see [`super::Dataset::filter_dof`]).
pub(crate) fn analyse(
    dataset: &str,
    joints: &[JointData<'_>; 2],
    sigma: [f64; 2],
    dof_ratio: f64,
) -> ResidualAnalysis {
    let mut profiles = Vec::new();
    let mut whiteness = Vec::new();
    let mut findings = Vec::new();
    for (j, d) in joints.iter().enumerate() {
        let joint = j + 1;
        for (axis, x) in [
            (Axis::Velocity, d.theta_dot),
            (Axis::Position, d.theta),
            (Axis::Acceleration, d.theta_ddot),
            (Axis::Time, d.t),
        ] {
            if x.is_empty() {
                continue;
            }
            let edges = match axis {
                Axis::Velocity => velocity_edges(x),
                Axis::Time => {
                    let (a, b) = (x[0], x[x.len() - 1]);
                    (0..=8).map(|i| a + (b - a) * i as f64 / 8.0).collect()
                }
                _ => quantile_edges(x, 8),
            };
            let bins = bin_by(x, d.residual, &edges, sigma[j], dof_ratio);
            for b in &bins {
                let z = b.z();
                if z.abs() > Z_SYSTEMATIC {
                    findings.push(Finding {
                        joint,
                        text: format!(
                            "joint {joint}: residual mean {:+.4} N·m for {} in [{:.3}, {:.3}] {} \
                             ({} samples, z = {:.1})",
                            b.mean,
                            axis.symbol(),
                            b.lo,
                            b.hi,
                            axis.unit(),
                            b.count,
                            z
                        ),
                        systematic: true,
                        z,
                    });
                }
            }
            if axis == Axis::Velocity {
                // The jump across the velocity reversal: the slowest bins on
                // either side of zero.
                let below = bins.iter().rfind(|b| b.hi <= 0.0);
                let above = bins.iter().find(|b| b.lo >= 0.0);
                if let (Some(a), Some(b)) = (below, above) {
                    let jump = b.mean - a.mean;
                    let se = (a.std_error * a.std_error + b.std_error * b.std_error).sqrt();
                    let z = if se > 0.0 { jump / se } else { 0.0 };
                    findings.push(Finding {
                        joint,
                        text: format!(
                            "joint {joint}: residual jumps by {jump:+.4} N·m at velocity \
                             reversal (z = {z:.1}){}",
                            if z.abs() > Z_SYSTEMATIC {
                                ""
                            } else {
                                ", within noise"
                            }
                        ),
                        systematic: z.abs() > Z_SYSTEMATIC,
                        z,
                    });
                }
            }
            profiles.push(Profile { joint, axis, bins });
        }
        whiteness.push(white(joint, d.residual, dof_ratio));
    }
    findings.sort_by(|a, b| {
        b.systematic
            .cmp(&a.systematic)
            .then(b.z.abs().total_cmp(&a.z.abs()))
    });
    ResidualAnalysis {
        dataset: dataset.to_owned(),
        profiles,
        whiteness,
        findings,
        left_out: Vec::new(),
        spectra: Vec::new(),
    }
}

/// The spectrum of joint `joint`'s residual `residual` next to its measured
/// torque `measured` (every row of a set sampled at `rate_hz`; `periodic`:
/// one averaged period), the pass band ending at `cutoff_hz`.
pub(crate) fn analyse_spectrum(
    joint: usize,
    residual: &[f64],
    measured: &[f64],
    rate_hz: f64,
    periodic: bool,
    cutoff_hz: f64,
) -> Result<ResidualSpectrum, aras_ident::IdentError> {
    let spectrum = |x: &[f64]| {
        aras_signal::power_spectrum(x, rate_hz, periodic)
            .map_err(|e| aras_ident::IdentError::external("the residual's spectrum", e))
    };
    let r = spectrum(residual)?;
    let t = spectrum(measured)?;
    let df = r.resolution_hz;
    let top = cutoff_hz.min(0.5 * rate_hz);
    let mut pass: Vec<f64> = r
        .frequencies_hz
        .iter()
        .zip(&r.density)
        .filter(|(f, _)| **f > 0.0 && **f <= top)
        .map(|(_, d)| *d)
        .collect();
    pass.sort_by(f64::total_cmp);
    let median = pass.get(pass.len() / 2).copied().unwrap_or(0.0);
    let (r_total, t_total) = (r.total_power().max(1e-300), t.total_power().max(1e-300));
    // The mean, then octaves centred on the lowest resolved frequency's
    // powers of two, up to the pass band's end.
    let mut edges = vec![0.0, 0.5 * df];
    let mut e = df * std::f64::consts::SQRT_2;
    while e < top {
        edges.push(e);
        e *= 2.0;
    }
    edges.push(top.max(edges[edges.len() - 1] + df));
    let bands: Vec<SpectrumBand> = edges
        .windows(2)
        .map(|w| {
            let (lo, hi) = (w[0], w[1]);
            let bins = r
                .frequencies_hz
                .iter()
                .filter(|f| **f >= lo && **f < hi)
                .count()
                .max(1);
            let p = r.band_power(lo, hi);
            SpectrumBand {
                lo_hz: lo,
                hi_hz: hi,
                residual_share: p / r_total,
                torque_share: t.band_power(lo, hi) / t_total,
                density_ratio: if median > 0.0 {
                    p / (bins as f64 * df) / median
                } else {
                    0.0
                },
            }
        })
        .collect();
    let finding = bands
        .iter()
        .filter(|b| b.residual_share >= 0.5 && b.density_ratio >= SPECTRAL_EXCESS)
        .max_by(|a, b| a.residual_share.total_cmp(&b.residual_share))
        .map(|b| {
            let torque_top = bands
                .iter()
                .max_by(|a, c| a.torque_share.total_cmp(&c.torque_share))
                .map_or(0.0, |c| c.lo_hz);
            let what = if b.lo_hz == 0.0 {
                "at 0 Hz: a constant offset".to_owned()
            } else if b.hi_hz <= 2.0 * torque_top.max(df) {
                format!(
                    "where the measured torque has {:.0} % of its power: a misfit that follows \
                     the motion (a missing term in its position, velocity or acceleration)",
                    100.0 * b.torque_share
                )
            } else {
                "above the motion's own frequencies: a fast effect (cogging, a delay, a \
                 resonance)"
                    .to_owned()
            };
            Finding {
                joint,
                text: format!(
                    "joint {joint}: {:.0} % of the residual's power lies in {:.2}–{:.2} Hz \
                     (power density {:.0}× the pass band's median), {what}",
                    100.0 * b.residual_share,
                    b.lo_hz,
                    b.hi_hz,
                    b.density_ratio
                ),
                systematic: true,
                z: b.density_ratio,
            }
        });
    // The plotted part: up to twice the cut-off, at most 400 points.
    let shown = r
        .frequencies_hz
        .iter()
        .take_while(|f| **f <= 2.0 * top)
        .count();
    let step = shown.div_ceil(400).max(1);
    let pick = |v: &[f64]| -> Vec<f64> { v[..shown].iter().step_by(step).copied().collect() };
    Ok(ResidualSpectrum {
        joint,
        bands,
        frequencies_hz: pick(&r.frequencies_hz),
        residual_density: pick(&r.density),
        torque_density: pick(&t.density),
        finding,
    })
}

/// The residual of joint `joint` on the rows left out (`left`), and the
/// fitness on all rows and on the fitted ones from `(measured, residual,
/// fitted)` over every row of the set; `sigma` is the fitted rows' RMS.
pub(crate) fn analyse_left_out(
    joint: usize,
    left: &JointData<'_>,
    all: (&[f64], &[f64], &[bool]),
    sigma: f64,
    dof_ratio: f64,
) -> Result<LeftOut, aras_ident::IdentError> {
    let (measured, residual, fitted) = all;
    let estimate: Vec<f64> = measured.iter().zip(residual).map(|(m, r)| m - r).collect();
    let pick = |want: bool, x: &[f64]| -> Vec<f64> {
        x.iter()
            .zip(fitted)
            .filter(|(_, f)| **f == want)
            .map(|(v, _)| *v)
            .collect()
    };
    let fitness_fitted_rows =
        aras_ident::validate::fitness(&pick(true, measured), &pick(true, &estimate))?;
    let fitness_all_rows = aras_ident::validate::fitness(measured, &estimate)?;
    let rms = rms(left.residual);
    let bins = if left.theta_dot.is_empty() {
        Vec::new()
    } else {
        bin_by(
            left.theta_dot,
            left.residual,
            &velocity_edges(left.theta_dot),
            sigma,
            dof_ratio,
        )
    };
    let mut findings: Vec<Finding> = bins
        .iter()
        .filter(|b| b.z().abs() > Z_SYSTEMATIC)
        .map(|b| Finding {
            joint,
            text: format!(
                "joint {joint}, rows left out near velocity reversals: residual mean {:+.4} N·m \
                 for θ̇ in [{:.3}, {:.3}] rad/s ({} samples, z = {:.1})",
                b.mean,
                b.lo,
                b.hi,
                b.count,
                b.z()
            ),
            systematic: true,
            z: b.z(),
        })
        .collect();
    findings.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
    Ok(LeftOut {
        joint,
        rows: left.residual.len(),
        fitted_rows: fitted.iter().filter(|f| **f).count(),
        rms,
        fitted_rms: sigma,
        fitness_all_rows,
        fitness_fitted_rows,
        profile: Profile {
            joint,
            axis: Axis::Velocity,
            bins,
        },
        findings,
    })
}

/// Root mean square of `x` (0 for no samples).
pub(crate) fn rms(x: &[f64]) -> f64 {
    (x.iter().fold(0.0, |s, v| s + v * v) / x.len().max(1) as f64).sqrt()
}

fn white(joint: usize, r: &[f64], dof_ratio: f64) -> Whiteness {
    let step = ((1.0 / dof_ratio).round() as usize).max(1);
    let dec: Vec<f64> = r.iter().step_by(step).copied().collect();
    let lags = (dec.len() / 5).clamp(1, 20);
    let (q, p_value) = ljung_box(&dec, lags);
    let rms = rms(r);
    Whiteness {
        joint,
        step,
        lags,
        q,
        p_value,
        autocorrelation_time: integrated_time(r, 2000.min(r.len() / 4)),
        rms,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Every velocity lands in exactly one bin that contains it, the
        /// rest band is split at zero, and no bin is a sliver between the
        /// rest band and the first quantile.
        #[test]
        fn velocity_bins_cover_every_sample(v in proptest::collection::vec(-3.0f64..3.0, 1..300)) {
            let e = velocity_edges(&v);
            prop_assert!(e.windows(2).all(|w| w[0] < w[1]));
            for x in [-REST_VELOCITY, 0.0, REST_VELOCITY] {
                prop_assert!(e.contains(&x));
            }
            let r: Vec<f64> = v.iter().map(|_| 1.0).collect();
            let bins = bin_by(&v, &r, &e, 1.0, 1.0);
            prop_assert_eq!(bins.iter().map(|b| b.count).sum::<usize>(), v.len());
            for x in &v {
                prop_assert!(bins.iter().any(|b| b.lo <= *x && *x <= b.hi));
            }
            let outer = |side: f64| v.iter().filter(|x| **x * side >= REST_VELOCITY).count();
            for (side, edge) in [(1.0, REST_VELOCITY), (-1.0, -REST_VELOCITY)] {
                // With at least two distinct speeds beyond the rest band,
                // the bin next to it holds more than one of them.
                let distinct = {
                    let mut s: Vec<f64> =
                        v.iter().copied().filter(|x| *x * side >= REST_VELOCITY).collect();
                    s.sort_by(f64::total_cmp);
                    s.dedup();
                    s.len()
                };
                if outer(side) >= 8 && distinct >= 8 {
                    let next = bins
                        .iter()
                        .find(|b| if side > 0.0 { b.lo == edge } else { b.hi == edge })
                        .expect("a bin next to the rest band");
                    prop_assert!(next.count > 1, "{:?}", next);
                }
            }
        }
    }
}
