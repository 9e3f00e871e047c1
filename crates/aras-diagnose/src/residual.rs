//! Where model and measurement disagree: the validation residual per joint,
//! binned against velocity (with bins at rest and split by sign), position,
//! acceleration and time, its whiteness, its spectrum, its trace against
//! time, and the bins whose mean is beyond what noise explains. Everything
//! comes from a summary fed row by row: fixed memory for a set
//! of any length.

use serde::Serialize;

use aras_ident::stats::{integrated_time_of, ljung_box_of};
use aras_ident::validate::FitnessSums;
use aras_signal::{Autocorrelation, PowerSpectrum, SpectrumAccumulator};

use crate::histogram::{Coarse, Histogram};

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
    /// Joint (1-based).
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
    /// Joint (1-based).
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
    /// Joint (1-based).
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
    /// Whiteness per joint; in a diagnosis, of the residual of the model
    /// refitted on this set, which leaves out the training estimate's own
    /// error.
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
    /// Per joint, the residual (every row) against time, decimated.
    pub traces: Vec<Trace>,
    /// Per joint, a bounded sample of rows (for scatter figures; not
    /// written to `diagnosis.json`).
    #[serde(skip)]
    pub samples: Vec<RowSample>,
}

/// One sampled row of a joint: its motion and residual.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SampledRow {
    /// Time (s).
    pub t: f64,
    /// Joint angle θ (rad).
    pub theta: f64,
    /// Joint rate θ̇ (rad/s).
    pub theta_dot: f64,
    /// Joint acceleration θ̈ (rad/s²).
    pub theta_ddot: f64,
    /// Model residual (N·m).
    pub residual: f64,
    /// Whether fits use the row (false: left out near a velocity reversal).
    pub fitted: bool,
}

/// A joint's rows sampled evenly over the record, at most [`SAMPLE_ROWS`]
/// of them: every `stride`-th row, the stride doubling (and every other
/// kept row dropped) when the sample fills, so a record of any length
/// keeps between half and all of [`SAMPLE_ROWS`]. Deterministic.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RowSample {
    /// Joint (1-based).
    pub joint: usize,
    /// One row kept out of `stride`.
    pub stride: usize,
    /// The rows kept, in record order.
    pub rows: Vec<SampledRow>,
}

/// Most rows of a [`RowSample`].
pub const SAMPLE_ROWS: usize = 2000;

/// Builds a [`RowSample`] row by row in bounded memory.
#[derive(Debug, Default)]
struct SampleBuilder {
    seen: usize,
    stride: usize,
    rows: Vec<SampledRow>,
}

impl SampleBuilder {
    fn push(&mut self, row: SampledRow) {
        if self.stride == 0 {
            self.stride = 1;
        }
        if self.seen.is_multiple_of(self.stride) {
            if self.rows.len() == SAMPLE_ROWS {
                let kept: Vec<SampledRow> = self.rows.iter().copied().step_by(2).collect();
                self.rows = kept;
                self.stride *= 2;
            }
            if self.seen.is_multiple_of(self.stride) {
                self.rows.push(row);
            }
        }
        self.seen += 1;
    }

    fn finish(self, joint: usize) -> RowSample {
        RowSample {
            joint,
            stride: self.stride.max(1),
            rows: self.rows,
        }
    }
}

/// A joint's residual against time, decimated to at most [`TRACE_POINTS`]
/// buckets of consecutive rows (every row, fitted or left out): mean,
/// smallest and largest residual per bucket, so a drift, a jump or a
/// burst shows however long the record.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Trace {
    /// Joint (1-based).
    pub joint: usize,
    /// Rows per bucket (the last bucket may hold fewer).
    pub rows_per_point: usize,
    /// Mean time of each bucket (s).
    pub t: Vec<f64>,
    /// Mean residual (N·m).
    pub mean: Vec<f64>,
    /// Smallest residual (N·m).
    pub min: Vec<f64>,
    /// Largest residual (N·m).
    pub max: Vec<f64>,
}

/// Most points of a [`Trace`]: buckets double in size when the record
/// fills this many, so a record of more rows gets between half and all of
/// them.
pub const TRACE_POINTS: usize = 1000;

/// Builds a [`Trace`] row by row in bounded memory.
#[derive(Debug, Default)]
struct TraceBuilder {
    size: usize,
    /// `(Σt, Σr, min, max, rows)` per complete or open bucket.
    buckets: Vec<(f64, f64, f64, f64, usize)>,
}

impl TraceBuilder {
    fn push(&mut self, t: f64, r: f64) {
        if self.size == 0 {
            self.size = 1;
        }
        match self.buckets.last_mut() {
            Some(b) if b.4 < self.size => {
                b.0 += t;
                b.1 += r;
                b.2 = b.2.min(r);
                b.3 = b.3.max(r);
                b.4 += 1;
            }
            _ => {
                if self.buckets.len() == TRACE_POINTS {
                    let merged = self
                        .buckets
                        .chunks(2)
                        .map(|p| {
                            p.iter().skip(1).fold(p[0], |a, b| {
                                (a.0 + b.0, a.1 + b.1, a.2.min(b.2), a.3.max(b.3), a.4 + b.4)
                            })
                        })
                        .collect();
                    self.buckets = merged;
                    self.size *= 2;
                }
                self.buckets.push((t, r, r, r, 1));
            }
        }
    }

    fn finish(self, joint: usize) -> Trace {
        let n = |b: &(f64, f64, f64, f64, usize)| b.4 as f64;
        Trace {
            joint,
            rows_per_point: self.size,
            t: self.buckets.iter().map(|b| b.0 / n(b)).collect(),
            mean: self.buckets.iter().map(|b| b.1 / n(b)).collect(),
            min: self.buckets.iter().map(|b| b.2).collect(),
            max: self.buckets.iter().map(|b| b.3).collect(),
        }
    }
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
    /// Joint (1-based).
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
    /// Joint (1-based).
    pub joint: usize,
    /// Rows left out.
    pub rows: usize,
    /// Rows fitted.
    pub fitted_rows: usize,
    /// Residual RMS on the rows left out (N·m).
    pub rms: f64,
    /// Residual RMS on the fitted rows (N·m).
    pub fitted_rms: f64,
    /// Validation fitness (78) of the filtered (and period-averaged)
    /// torques on every processed row of the set, left out or fitted (%):
    /// not the raw-torque figure ([`crate::FitnessRow::fitness`]).
    pub fitness_filtered_all_rows: f64,
    /// The same on the fitted rows (%).
    pub fitness_filtered_fitted_rows: f64,
    /// The residual of the rows left out binned against velocity (rest
    /// band split by sign, quantile bins beyond), standard errors from the
    /// fitted rows' RMS.
    pub profile: Profile,
    /// Bins beyond [`Z_SYSTEMATIC`] standard errors, in words, largest
    /// first.
    pub findings: Vec<Finding>,
}

impl ResidualAnalysis {
    /// True if no bin is systematic and every joint's residual is white.
    pub fn noise_like(&self) -> bool {
        self.whiteness.iter().all(|w| w.is_white()) && !self.findings.iter().any(|f| f.systematic)
    }

    /// The velocity profile of `joint` (1-based).
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

/// Lags of the integrated autocorrelation time (Geyer's sum stops at the
/// first non-positive one; a quarter of the record at most).
const MAX_CORRELATION_LAG: usize = 2000;
/// Lags of the Ljung–Box test (a fifth of the decimated record at most).
const MAX_WHITENESS_LAG: usize = 20;

/// A joint's rate profile: quantile bins of `θ̇ ≤ −REST_VELOCITY` and of
/// `θ̇ ≥ REST_VELOCITY` (four each), and the rest band split at zero.
#[derive(Default)]
struct VelocityBins {
    below: Histogram,
    /// `(count, sum)` of `−REST_VELOCITY < θ̇ < 0` and `0 ≤ θ̇ < REST_VELOCITY`.
    rest: [(u64, f64); 2],
    above: Histogram,
}

impl VelocityBins {
    fn push(&mut self, v: f64, r: f64) {
        if v <= -REST_VELOCITY {
            self.below.push(v, r);
        } else if v >= REST_VELOCITY {
            self.above.push(v, r);
        } else {
            let k = usize::from(v >= 0.0);
            self.rest[k].0 += 1;
            self.rest[k].1 += r;
        }
    }

    fn bins(&self) -> Vec<Coarse> {
        let mut below = self.below.quantile_bins(4);
        if let Some(last) = below.last_mut() {
            last.hi = -REST_VELOCITY;
        }
        let mut above = self.above.quantile_bins(4);
        if let Some(first) = above.first_mut() {
            first.lo = REST_VELOCITY;
        }
        let rest = [(-REST_VELOCITY, 0.0), (0.0, REST_VELOCITY)]
            .into_iter()
            .zip(self.rest)
            .filter(|(_, (count, _))| *count > 0)
            .map(|((lo, hi), (count, sum))| Coarse { lo, hi, count, sum });
        below.into_iter().chain(rest).chain(above).collect()
    }
}

/// What the analysis keeps of one joint's residual: fixed-size
/// histograms, sums and accumulators, whatever the data set's length.
struct JointSummary {
    velocity: VelocityBins,
    position: Histogram,
    acceleration: Histogram,
    time: Histogram,
    left_velocity: VelocityBins,
    /// `Σ r²` of the fitted rows and of the rows left out.
    square: [f64; 2],
    all_rows: FitnessSums,
    fitted_rows: FitnessSums,
    /// The fitted rows' residual, and every `step`-th of them.
    correlation: Autocorrelation,
    decimated: Autocorrelation,
    residual_spectrum: SpectrumAccumulator,
    torque_spectrum: SpectrumAccumulator,
    trace: TraceBuilder,
    sample: SampleBuilder,
}

/// One data set's residual analysis, built row by row in record order
/// (every joint's rows, fitted or left out near a velocity reversal): a
/// data set of any length in fixed memory.
pub(crate) struct ResidualSummary {
    dataset: String,
    joints: Vec<JointSummary>,
    /// Independent fraction of the samples.
    dof_ratio: f64,
    /// Decimation of the Ljung–Box test: the filter's independent-sample
    /// spacing.
    step: usize,
    rate_hz: f64,
    pass_band_end_hz: f64,
}

/// One row of one joint for [`ResidualSummary::push`].
pub(crate) struct Row {
    /// Model residual (N·m).
    pub residual: f64,
    /// The measured torque it was taken from (N·m).
    pub measured: f64,
    /// Whether fits use the row.
    pub fitted: bool,
    /// `θ, θ̇, θ̈` of the joint and `t`.
    pub motion: [f64; 4],
}

impl ResidualSummary {
    /// A summary of data set `dataset` of `joints` joints and `rows` rows
    /// per joint sampled at `rate_hz` (`periodic`: one averaged period), of
    /// which `dof_ratio` are independent, its filter's pass band ending at
    /// `pass_band_end_hz`.
    pub fn new(
        dataset: &str,
        joints: usize,
        rows: usize,
        rate_hz: f64,
        periodic: bool,
        dof_ratio: f64,
        pass_band_end_hz: f64,
    ) -> Result<Self, aras_ident::IdentError> {
        let spectrum = || {
            SpectrumAccumulator::new(rows, rate_hz, periodic)
                .map_err(|e| aras_ident::IdentError::external("the residual's spectrum", e))
        };
        let joint = || -> Result<JointSummary, aras_ident::IdentError> {
            Ok(JointSummary {
                velocity: VelocityBins::default(),
                position: Histogram::default(),
                acceleration: Histogram::default(),
                time: Histogram::default(),
                left_velocity: VelocityBins::default(),
                square: [0.0; 2],
                all_rows: FitnessSums::default(),
                fitted_rows: FitnessSums::default(),
                correlation: Autocorrelation::new(MAX_CORRELATION_LAG),
                decimated: Autocorrelation::new(MAX_WHITENESS_LAG),
                residual_spectrum: spectrum()?,
                torque_spectrum: spectrum()?,
                trace: TraceBuilder::default(),
                sample: SampleBuilder::default(),
            })
        };
        Ok(Self {
            dataset: dataset.to_owned(),
            joints: (0..joints).map(|_| joint()).collect::<Result<_, _>>()?,
            dof_ratio,
            step: ((1.0 / dof_ratio).round() as usize).max(1),
            rate_hz,
            pass_band_end_hz,
        })
    }

    /// Adds joint `g`'s next row (rows in record order).
    pub fn push(&mut self, g: usize, row: &Row) -> Result<(), aras_ident::IdentError> {
        let j = &mut self.joints[g];
        let r = row.residual;
        if !r.is_finite() {
            return Err(aras_ident::IdentError::NonFinite {
                what: "model residual",
                row: j.all_rows.len(),
                column: g,
                name: format!("joint {}", g + 1),
                value: r,
            });
        }
        let spectrum = |e| aras_ident::IdentError::external("the residual's spectrum", e);
        j.residual_spectrum.push(r).map_err(spectrum)?;
        j.torque_spectrum.push(row.measured).map_err(spectrum)?;
        j.all_rows.push(row.measured, row.measured - r);
        let [theta, theta_dot, theta_ddot, t] = row.motion;
        j.trace.push(t, r);
        j.sample.push(SampledRow {
            t,
            theta,
            theta_dot,
            theta_ddot,
            residual: r,
            fitted: row.fitted,
        });
        if row.fitted {
            if j.correlation.len().is_multiple_of(self.step) {
                j.decimated.push(r);
            }
            j.correlation.push(r);
            j.fitted_rows.push(row.measured, row.measured - r);
            j.square[0] += r * r;
            j.velocity.push(theta_dot, r);
            j.position.push(theta, r);
            j.acceleration.push(theta_ddot, r);
            j.time.push(t, r);
        } else {
            j.square[1] += r * r;
            j.left_velocity.push(theta_dot, r);
        }
        Ok(())
    }

    /// The analysis of the rows pushed.
    pub fn finish(self) -> Result<ResidualAnalysis, aras_ident::IdentError> {
        let mut a = ResidualAnalysis {
            dataset: self.dataset,
            profiles: Vec::new(),
            whiteness: Vec::new(),
            findings: Vec::new(),
            left_out: Vec::new(),
            spectra: Vec::new(),
            traces: Vec::new(),
            samples: Vec::new(),
        };
        let dof_ratio = self.dof_ratio;
        for (g, j) in self.joints.into_iter().enumerate() {
            let joint = g + 1;
            let fitted = j.correlation.len();
            let left = j.all_rows.len() - fitted;
            let sigma = (j.square[0] / fitted.max(1) as f64).sqrt();
            let bins = |c: Vec<Coarse>| -> Vec<Bin> {
                c.into_iter()
                    .map(|c| {
                        let neff = (c.count as f64 * dof_ratio).max(1.0);
                        Bin {
                            lo: c.lo,
                            hi: c.hi,
                            count: c.count as usize,
                            mean: c.sum / c.count as f64,
                            std_error: sigma / neff.sqrt(),
                        }
                    })
                    .collect()
            };
            for (axis, c) in [
                (Axis::Velocity, j.velocity.bins()),
                (Axis::Position, j.position.quantile_bins(8)),
                (Axis::Acceleration, j.acceleration.quantile_bins(8)),
                (Axis::Time, j.time.uniform_bins(8)),
            ] {
                if fitted == 0 {
                    continue;
                }
                let profile = Profile {
                    joint,
                    axis,
                    bins: bins(c),
                };
                a.findings.extend(profile_findings(&profile));
                a.profiles.push(profile);
            }
            let rms = |sq: f64, n: usize| (sq / n.max(1) as f64).sqrt();
            let dec_n = j.decimated.len();
            let lags = (dec_n / 5).clamp(1, MAX_WHITENESS_LAG);
            let dec_rho = j.decimated.finish();
            let (q, p_value) = ljung_box_of(&dec_rho[..lags], dec_n);
            let max_lag = MAX_CORRELATION_LAG.min(fitted / 4);
            let rho = j.correlation.finish();
            a.whiteness.push(Whiteness {
                joint,
                step: self.step,
                lags,
                q,
                p_value,
                autocorrelation_time: integrated_time_of(
                    rho[..max_lag.saturating_sub(1)].iter().copied(),
                ),
                rms: sigma,
            });
            let profile = Profile {
                joint,
                axis: Axis::Velocity,
                bins: bins(j.left_velocity.bins()),
            };
            let mut findings = bin_findings(
                &profile,
                &format!("joint {joint}, rows left out near velocity reversals"),
            );
            findings.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
            a.left_out.push(LeftOut {
                joint,
                rows: left,
                fitted_rows: fitted,
                rms: rms(j.square[1], left),
                fitted_rms: sigma,
                fitness_filtered_all_rows: j.all_rows.fitness(g)?,
                fitness_filtered_fitted_rows: j.fitted_rows.fitness(g)?,
                profile,
                findings,
            });
            let spectrum =
                |acc: SpectrumAccumulator| -> Result<PowerSpectrum, aras_ident::IdentError> {
                    acc.finish()
                        .map_err(|e| aras_ident::IdentError::external("the residual's spectrum", e))
                };
            a.traces.push(j.trace.finish(joint));
            a.samples.push(j.sample.finish(joint));
            a.spectra.push(spectrum_analysis(
                joint,
                &spectrum(j.residual_spectrum)?,
                &spectrum(j.torque_spectrum)?,
                self.rate_hz,
                self.pass_band_end_hz,
            ));
        }
        a.findings.sort_by(|a, b| {
            b.systematic
                .cmp(&a.systematic)
                .then(b.z.abs().total_cmp(&a.z.abs()))
        });
        Ok(a)
    }
}

/// The bins of `p` beyond [`Z_SYSTEMATIC`] standard errors, in words
/// about `subject` (e.g. "joint 2").
fn bin_findings(p: &Profile, subject: &str) -> Vec<Finding> {
    p.bins
        .iter()
        .filter(|b| b.z().abs() > Z_SYSTEMATIC)
        .map(|b| Finding {
            joint: p.joint,
            text: format!(
                "{subject}: residual mean {:+.4} N·m for {} in [{:.3}, {:.3}] {} ({} samples, \
                 z = {:.1})",
                b.mean,
                p.axis.symbol(),
                b.lo,
                b.hi,
                p.axis.unit(),
                b.count,
                b.z()
            ),
            systematic: true,
            z: b.z(),
        })
        .collect()
}

/// [`bin_findings`] of `p`, and for a velocity profile the jump across the
/// reversal, in words.
fn profile_findings(p: &Profile) -> Vec<Finding> {
    let (joint, axis) = (p.joint, p.axis);
    let mut findings = bin_findings(p, &format!("joint {joint}"));
    if axis == Axis::Velocity {
        // The jump across the velocity reversal: the slowest bins on
        // either side of zero.
        let below = p.bins.iter().rfind(|b| b.hi <= 0.0);
        let above = p.bins.iter().find(|b| b.lo >= 0.0);
        if let (Some(a), Some(b)) = (below, above) {
            let jump = b.mean - a.mean;
            let se = (a.std_error * a.std_error + b.std_error * b.std_error).sqrt();
            let z = if se > 0.0 { jump / se } else { 0.0 };
            findings.push(Finding {
                joint,
                text: format!(
                    "joint {joint}: residual jumps by {jump:+.4} N·m at velocity reversal \
                     (z = {z:.1}){}",
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
    findings
}

/// Where joint `joint`'s residual spectrum `r` has its power, next to the
/// measured torque's `t` (sampled at `rate_hz`, the pass band ending at
/// `cutoff_hz`).
fn spectrum_analysis(
    joint: usize,
    r: &PowerSpectrum,
    t: &PowerSpectrum,
    rate_hz: f64,
    cutoff_hz: f64,
) -> ResidualSpectrum {
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
    ResidualSpectrum {
        joint,
        bands,
        frequencies_hz: pick(&r.frequencies_hz),
        residual_density: pick(&r.density),
        torque_density: pick(&t.density),
        finding,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sampled(n: usize) -> RowSample {
        let mut b = SampleBuilder::default();
        for i in 0..n {
            b.push(SampledRow {
                t: i as f64,
                ..SampledRow::default()
            });
        }
        b.finish(1)
    }

    /// The row sample keeps every row of a short record, and of a long one
    /// between half and all of `SAMPLE_ROWS`, evenly strided from the first.
    #[test]
    fn row_sample_is_bounded_and_even() {
        let short = sampled(500);
        assert_eq!((short.rows.len(), short.stride), (500, 1));
        for n in [SAMPLE_ROWS, SAMPLE_ROWS + 1, 10_007, 123_456] {
            let s = sampled(n);
            assert!(
                s.rows.len() >= SAMPLE_ROWS / 2 && s.rows.len() <= SAMPLE_ROWS,
                "{n}: {} rows",
                s.rows.len()
            );
            for (k, r) in s.rows.iter().enumerate() {
                assert_eq!(r.t, (k * s.stride) as f64, "{n}: row {k}");
            }
            assert_eq!(
                s.rows.len(),
                n.div_ceil(s.stride),
                "{n}: every stride-th row"
            );
        }
    }

    proptest! {
        /// Every velocity lands in one bin whose edges hold it, the rest
        /// band is split at zero with exact counts and sums, and the bins
        /// beyond it start and end at its edges.
        #[test]
        fn velocity_bins_cover_every_sample(v in proptest::collection::vec(-3.0f64..3.0, 1..300)) {
            let mut bins = VelocityBins::default();
            for (i, x) in v.iter().enumerate() {
                bins.push(*x, i as f64);
            }
            let b = bins.bins();
            prop_assert!(b.windows(2).all(|w| w[0].hi <= w[1].lo));
            prop_assert_eq!(b.iter().map(|b| b.count).sum::<u64>(), v.len() as u64);
            for x in &v {
                prop_assert!(b.iter().any(|b| b.lo <= *x && *x <= b.hi), "{} outside", x);
            }
            for (lo, hi) in [(-REST_VELOCITY, 0.0), (0.0, REST_VELOCITY)] {
                let inside: Vec<usize> =
                    (0..v.len()).filter(|&i| v[i] > -REST_VELOCITY && v[i] < REST_VELOCITY
                        && (v[i] >= 0.0) == (lo == 0.0)).collect();
                let bin = b.iter().find(|c| c.lo == lo && c.hi == hi);
                prop_assert_eq!(bin.map_or(0, |c| c.count), inside.len() as u64);
                let sum: f64 = inside.iter().map(|&i| i as f64).sum();
                prop_assert_eq!(bin.map_or(0.0, |c| c.sum), sum);
            }
            if v.iter().any(|x| *x >= REST_VELOCITY) {
                prop_assert!(b.iter().any(|c| c.lo == REST_VELOCITY));
            }
            if v.iter().any(|x| *x <= -REST_VELOCITY) {
                prop_assert!(b.iter().any(|c| c.hi == -REST_VELOCITY));
            }
        }
    }

    /// The summary, fed row by row, gives what the whole arrays give:
    /// RMS, fitness (78) on all and on the fitted rows, Ljung–Box on the
    /// decimated fitted residual, the integrated autocorrelation time, the
    /// spectra, and bin means equal to the means of the samples inside
    /// each bin's edges. A correlated residual with a velocity-dependent
    /// bias, an offset torque and a slow drift, as a misfit leaves.
    #[test]
    fn summary_equals_the_whole_record_statistics() {
        let (n, rate) = (20_000, 1000.0);
        let mut s = 0x9E37_79B9_7F4A_7C15_u64;
        let mut noise = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut rows: [Vec<Row>; 2] = Default::default();
        let mut ar = [0.0; 2];
        for i in 0..n {
            let t = i as f64 / rate;
            for g in 0..2 {
                let w = 1.0 + g as f64;
                let v = 1.5 * (w * t).cos();
                ar[g] = 0.8 * ar[g] + 0.01 * noise();
                let residual = ar[g] + 0.02 * v.signum() * (-v.abs() / 0.1).exp() + 1e-4 * t;
                rows[g].push(Row {
                    residual,
                    measured: 3.0 + (w * t).sin() + residual,
                    fitted: v.abs() > 0.1,
                    motion: [1.5 * (w * t).sin() / w, v, -1.5 * w * (w * t).sin(), t],
                });
            }
        }
        let dof_ratio = 0.1;
        let mut sum = ResidualSummary::new("set", 2, n, rate, false, dof_ratio, 20.0).unwrap();
        for i in 0..n {
            for g in 0..2 {
                sum.push(g, &rows[g][i]).unwrap();
            }
        }
        let a = sum.finish().unwrap();
        let close = |x: f64, y: f64, tol: f64| (x - y).abs() <= tol * y.abs().max(1e-300);
        for g in 0..2 {
            let pick = |f: bool, x: fn(&Row) -> f64| -> Vec<f64> {
                rows[g].iter().filter(|r| r.fitted == f).map(x).collect()
            };
            let kept = pick(true, |r| r.residual);
            let left = pick(false, |r| r.residual);
            let rms = |x: &[f64]| (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
            let w = &a.whiteness[g];
            assert!(close(w.rms, rms(&kept), 1e-12));
            let dec: Vec<f64> = kept.iter().step_by(10).copied().collect();
            let (q, p) = aras_ident::stats::ljung_box(&dec, 20);
            assert_eq!((w.step, w.lags), (10, 20));
            assert!(
                close(w.q, q, 1e-9) && close(w.p_value, p, 1e-9),
                "{w:?} vs {q} {p}"
            );
            let tau = aras_ident::stats::integrated_time(&kept, 2000.min(kept.len() / 4));
            assert!(
                close(w.autocorrelation_time, tau, 1e-9),
                "{} vs {tau}",
                w.autocorrelation_time
            );
            let l = &a.left_out[g];
            assert_eq!((l.rows, l.fitted_rows), (left.len(), kept.len()));
            assert!(close(l.rms, rms(&left), 1e-12));
            let meas: Vec<f64> = rows[g].iter().map(|r| r.measured).collect();
            let est: Vec<f64> = rows[g].iter().map(|r| r.measured - r.residual).collect();
            let fit_all = aras_ident::validate::fitness(&meas, &est).unwrap();
            assert!((l.fitness_filtered_all_rows - fit_all).abs() < 1e-9);
            let fit_kept = aras_ident::validate::fitness(
                &pick(true, |r| r.measured),
                &pick(true, |r| r.measured - r.residual),
            )
            .unwrap();
            assert!((l.fitness_filtered_fitted_rows - fit_kept).abs() < 1e-9);
            let resid: Vec<f64> = rows[g].iter().map(|r| r.residual).collect();
            let ps = aras_signal::power_spectrum(&resid, rate, false).unwrap();
            let sp = &a.spectra[g];
            for (f, d) in sp.frequencies_hz.iter().zip(&sp.residual_density) {
                let k = (f / ps.resolution_hz).round() as usize;
                assert!(close(*d, ps.density[k], 1e-12));
            }
            // The trace: buckets of consecutive rows, their means and
            // extremes those of the rows they hold.
            let tr = &a.traces[g];
            assert!(
                tr.t.len() <= TRACE_POINTS && tr.t.len() > TRACE_POINTS / 2,
                "{}",
                tr.t.len()
            );
            for (k, chunk) in resid.chunks(tr.rows_per_point).enumerate() {
                let mean = chunk.iter().sum::<f64>() / chunk.len() as f64;
                assert!((tr.mean[k] - mean).abs() < 1e-12);
                assert_eq!(
                    tr.min[k],
                    chunk.iter().copied().fold(f64::INFINITY, f64::min)
                );
                assert_eq!(
                    tr.max[k],
                    chunk.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                );
                let t0 = (k * tr.rows_per_point) as f64 / rate;
                let t1 = ((k * tr.rows_per_point + chunk.len() - 1) as f64) / rate;
                assert!((tr.t[k] - 0.5 * (t0 + t1)).abs() < 1e-9);
            }
            // Profiles: each bin's mean is that of the fitted samples it
            // holds (the samples strictly inside its edges, and at most a
            // few on an edge).
            for p in a.profiles.iter().filter(|p| p.joint == g + 1) {
                let axis = match p.axis {
                    Axis::Position => 0,
                    Axis::Velocity => 1,
                    Axis::Acceleration => 2,
                    Axis::Time => 3,
                };
                assert_eq!(p.bins.iter().map(|b| b.count).sum::<usize>(), kept.len());
                for b in &p.bins {
                    let inside: Vec<f64> = rows[g]
                        .iter()
                        .filter(|r| r.fitted && r.motion[axis] > b.lo && r.motion[axis] < b.hi)
                        .map(|r| r.residual)
                        .collect();
                    assert!(
                        b.count >= inside.len() && b.count <= inside.len() + 2,
                        "{b:?}"
                    );
                    if b.count == inside.len() {
                        let mean = inside.iter().sum::<f64>() / inside.len() as f64;
                        assert!((b.mean - mean).abs() < 1e-12, "{b:?} vs {mean}");
                    }
                }
            }
        }
    }
}
