//! Raw log → clean, aligned samples θ, θ̇, θ̈, X, Ẋ, Ẍ, τ (`docs/processing.md`).
//!
//! Order of operations, and why:
//! 1. **Period averaging** (if a period is known) on the raw data: averaging
//!    is linear, so doing it first cuts the work by the number of periods
//!    and yields one periodic record, which step 2–3 can treat exactly.
//! 2. **Zero-phase low-pass** of θ and τ (and logged θ̇, θ̈) with the same
//!    Butterworth filter: circular (`|H|²` in the frequency domain) for a
//!    periodic record, scipy-style `filtfilt` otherwise.
//! 3. **Derivatives** of the filtered θ ([`DerivativeMethod`]).
//! 4. **Kinematics**: `X = forward(θ)` (assembly mode `+`, (6)–(7)),
//!    `Ẋ = J⁻¹θ̇`, `Ẍ = J⁻¹(θ̈ − J̇Ẋ)` ((8)–(11)). Going through the
//!    Jacobian rather than differentiating X keeps `θ̇ = J Ẋ` exact sample by
//!    sample, so joint-space terms (friction on θ̇) and task-space terms agree,
//!    and logged θ̇ columns are used as they are.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OVector, U1};
use serde::Serialize;

use crate::bandwidth::{
    CUTOFF_MARGIN, HarmonicSelection, PeriodDetection, PeriodOrigin, SpectrumCutoff,
    uniform_derivatives,
};
use crate::coordinates::{Coordinates, Motion};
use crate::derivative::DerivativeMethod;
use crate::error::ProcessError;
use crate::fourier::Fourier;
use crate::{BandLimit, Butterworth, HarmonicBand, Sos};
use aras_log::{Log, Warning};

mod run;
mod stages;

use run::Run;
use stages::{BandChoice, PeriodChoice};

/// Low-pass filter settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FilterSpec {
    /// Butterworth order (1–32; forward–backward doubles the attenuation).
    pub order: usize,
    /// −3 dB cut-off of one pass (Hz); the zero-phase pair is −6 dB there.
    pub cutoff_hz: f64,
}

impl Default for FilterSpec {
    /// Order 4 at 10 Hz: 20× the highest excitation harmonic (5 × 0.1 Hz,
    /// (74)) and 4× the fastest validation trajectory (2.5 Hz, Table 2),
    /// so the dynamics pass untouched while sensor noise is cut.
    fn default() -> Self {
        Self {
            order: 4,
            cutoff_hz: 10.0,
        }
    }
}

/// Where the excitation period comes from.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub enum PeriodSource {
    /// `excitation.period_s` of the sidecar if present, else the period
    /// [`detect_period`](crate::detect_period) finds in the angles (no averaging if it declines).
    #[default]
    FromSidecar,
    /// This period (s).
    Seconds(f64),
    /// No period averaging and no harmonic fit.
    Off,
}

/// The processing's bandwidth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Bandwidth {
    /// Chosen from the data ([`crate::bandwidth`](crate::detect_period)'s
    /// rules): a harmonic series up to the noise floor for a periodic
    /// record, else a Butterworth whose cut-off follows the angle spectrum.
    Auto,
    /// This zero-phase Butterworth, whatever the data.
    Fixed(FilterSpec),
    /// No filtering.
    Off,
}

impl Default for Bandwidth {
    /// [`Bandwidth::Auto`]: the band the data resolve, so the fast motions
    /// keep their harmonics and the rows near velocity reversals can be
    /// fitted (`docs/processing.md`; the fixed 10 Hz Butterworth,
    /// [`FilterSpec::default`], is the paper's choice).
    fn default() -> Self {
        Self::Auto
    }
}

/// Which samples [`process`] returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputRows {
    /// One averaged block for a periodic record (fast identification),
    /// every row otherwise.
    #[default]
    Averaged,
    /// One sample per row of the log, with the log's raw torques: what a
    /// prediction is compared with (fitness (78) on all rows).
    EveryRow,
}

/// Options of [`process`]. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProcessOptions {
    /// Bandwidth (default: the fixed 10 Hz Butterworth of
    /// [`FilterSpec::default`]).
    pub filter: Bandwidth,
    /// Period for averaging and the harmonic fit (default: from the
    /// sidecar, else detected).
    pub period: PeriodSource,
    /// Seconds dropped at the start before averaging (default 0).
    pub settling_s: f64,
    /// Largest accepted RMS deviation of one period of θ from the average,
    /// relative to the average period's standard deviation (default 0.1).
    /// Torque periods are only reported (noise makes them spread more).
    pub max_period_spread: f64,
    /// Derivative method (default [`DerivativeMethod::Auto`]: the harmonic
    /// series' own derivatives, or central differences after the
    /// Butterworth).
    pub derivative: DerivativeMethod,
    /// Use the log's `dtheta`/`ddtheta` columns when present instead of
    /// differentiating θ (default false: the paper differentiates encoder
    /// angles). They are used exactly as given: no column is filtered.
    pub use_logged_derivatives: bool,
    /// Which samples to return (default [`OutputRows::Averaged`]).
    pub rows: OutputRows,
}

impl Default for ProcessOptions {
    fn default() -> Self {
        Self {
            filter: Bandwidth::default(),
            period: PeriodSource::FromSidecar,
            settling_s: 0.0,
            max_period_spread: 0.1,
            derivative: DerivativeMethod::Auto,
            use_logged_derivatives: false,
            rows: OutputRows::Averaged,
        }
    }
}

/// Processed samples, structure-of-arrays, SI units (rad, rad/s, rad/s², N·m),
/// one column per joint (coordinate). All columns have the same length.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Samples {
    /// Time (s).
    pub t: Vec<f64>,
    /// Joint angles θ1 … θn.
    pub theta: Vec<Vec<f64>>,
    /// Joint rates θ̇.
    pub theta_dot: Vec<Vec<f64>>,
    /// Joint accelerations θ̈.
    pub theta_ddot: Vec<Vec<f64>>,
    /// The model's coordinates X (ARAS-Diamond: the task pose [φ, γ]).
    pub x: Vec<Vec<f64>>,
    /// Their rates Ẋ.
    pub x_dot: Vec<Vec<f64>>,
    /// Their accelerations Ẍ.
    pub x_ddot: Vec<Vec<f64>>,
    /// Joint torques τ1 … τn: raw or averaged over periods, and low-passed
    /// by the same Butterworth as θ when one is applied (a fit then filters
    /// torques and regressor alike once more, so both sides of `T = W β`
    /// pass the same filters). The log's raw torques stay available for the
    /// fitness on every row ([`Processed::on_log_rows`]).
    pub tau: Vec<Vec<f64>>,
}

impl Samples {
    /// No samples, with one (empty) column per joint in every group, to be
    /// filled by pushing.
    pub fn with_joints(joints: usize) -> Self {
        let group = vec![Vec::new(); joints];
        Self {
            t: Vec::new(),
            theta: group.clone(),
            theta_dot: group.clone(),
            theta_ddot: group.clone(),
            x: group.clone(),
            x_dot: group.clone(),
            x_ddot: group.clone(),
            tau: group,
        }
    }

    /// Number of joints (coordinates).
    pub fn joints(&self) -> usize {
        self.theta.len()
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True if there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Sample `i`'s joint motion `θ, θ̇, θ̈` (dimension `D`: two by
    /// default, [`nalgebra::Dyn`] for any). Panics if `i ≥ len()`, as
    /// indexing does, or if `D` is a fixed dimension other than
    /// [`joints`](Self::joints).
    pub fn joint<D: Dim>(&self, i: usize) -> Motion<f64, D>
    where
        DefaultAllocator: Allocator<D>,
    {
        motion_at(&self.theta, &self.theta_dot, &self.theta_ddot, i)
    }

    /// Sample `i`'s motion in the model's coordinates `X, Ẋ, Ẍ` (as
    /// [`joint`](Self::joint)).
    pub fn task<D: Dim>(&self, i: usize) -> Motion<f64, D>
    where
        DefaultAllocator: Allocator<D>,
    {
        motion_at(&self.x, &self.x_dot, &self.x_ddot, i)
    }
}

/// Entry `i` of per-coordinate columns, as a motion of dimension `D`.
fn motion_at<D: Dim>(p: &[Vec<f64>], v: &[Vec<f64>], a: &[Vec<f64>], i: usize) -> Motion<f64, D>
where
    DefaultAllocator: Allocator<D>,
{
    let d = D::from_usize(p.len());
    let at = |c: &[Vec<f64>]| OVector::<f64, D>::from_fn_generic(d, U1, |r, _| c[r][i]);
    Motion::new(at(p), at(v), at(a))
}

/// The Butterworth filter that was applied to θ (and that a fit must apply
/// to the torques and every regressor column alike).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FilterSummary {
    /// Butterworth order.
    pub order: usize,
    /// Cut-off (Hz).
    pub cutoff_hz: f64,
    /// `"zero-phase forward-backward (scipy sosfiltfilt)"` or the periodic form.
    pub kind: String,
}

/// The period averaging that was done.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodSummary {
    /// Period (s).
    pub period_s: f64,
    /// Periods per averaged block: the smallest `k` with `k·P·fs` a whole
    /// number of samples (1 when a period is; 7 for 0.7 Hz at 1 kHz). The
    /// output is one block, i.e. `k` periods.
    pub periods_per_block: usize,
    /// Samples per block (the output's length before derivative edge loss).
    pub samples_per_block: usize,
    /// Blocks averaged.
    pub blocks_averaged: usize,
    /// Whole periods averaged (`blocks_averaged · periods_per_block`).
    pub periods_averaged: usize,
    /// Samples dropped for settling.
    pub settling_samples: usize,
    /// Samples after the last whole period.
    pub tail_samples: usize,
    /// Relative RMS spread of θ1 … θn, then τ1 … τn (see
    /// [`crate::PeriodAverage`]).
    pub spread_relative: Vec<f64>,
    /// Absolute RMS spread of θ1 … θn (rad), then τ1 … τn (N·m).
    pub spread_rms: Vec<f64>,
}

/// How θ was smoothed and differentiated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BandwidthMethod {
    /// Least-squares Fourier series in the harmonics of the period.
    HarmonicSeries,
    /// Zero-phase Butterworth low-pass.
    Butterworth,
    /// No smoothing.
    None,
    /// The log's derivative columns, used as given (nothing filtered).
    LoggedDerivatives,
}

/// The bandwidth [`process`] chose and why, for reports and `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandwidthChoice {
    /// What was done.
    pub method: BandwidthMethod,
    /// The period used (s), if any.
    pub period_s: Option<f64>,
    /// Where the period came from.
    pub period_origin: Option<PeriodOrigin>,
    /// The detector's verdict, when it ran.
    pub detection: Option<PeriodDetection>,
    /// Per joint, the harmonic series kept ([`BandwidthMethod::HarmonicSeries`]).
    pub harmonics: Option<Vec<HarmonicSelection>>,
    /// The Butterworth applied ([`BandwidthMethod::Butterworth`]).
    pub filter: Option<FilterSpec>,
    /// The spectrum that chose the automatic cut-off.
    pub spectrum: Option<SpectrumCutoff>,
    /// Prediction on every row of a periodic log: the spectrum that chose
    /// the low-pass of the aperiodic remainder (θ minus the series).
    pub aperiodic: Option<SpectrumCutoff>,
    /// Irregular time steps: how the log was brought to a uniform grid.
    pub resampling: Option<String>,
    /// The choice in one sentence.
    pub reason: String,
}

/// What [`process`] did, for the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProcessSummary {
    /// Rows in the log.
    pub input_samples: usize,
    /// Samples out.
    pub output_samples: usize,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// The Butterworth applied to θ, if any.
    pub filter: Option<FilterSummary>,
    /// Period averaging, if any.
    pub periods: Option<PeriodSummary>,
    /// The bandwidth choice and its reason.
    pub bandwidth: BandwidthChoice,
    /// Input samples not represented in the output: settling, tail, and the
    /// derivative's edge loss (0 with [`OutputRows::EveryRow`] and the
    /// automatic derivatives).
    pub samples_dropped: usize,
    /// Derivative method actually used.
    pub derivative: DerivativeMethod,
    /// `"differentiated θ"` or `"logged dtheta/ddtheta columns"`.
    pub derivative_source: String,
    /// Where angles and torques came from (from the log reader).
    pub angle_source: String,
    /// Where torques came from.
    pub torque_source: String,
    /// The log's torque timing (`aras_log::Log::torque_timing`).
    pub torque_timing: aras_log::TorqueTiming,
    /// How far after each row the motion was evaluated, in sample steps:
    /// ½ for held torques with the motion from the angles, 0 for sampled
    /// torques or logged derivatives.
    pub motion_shift_steps: f64,
}

/// Which output sample stands for each row of the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
enum RowMap {
    /// Row `i` is sample `i − edge`.
    Direct { edge: usize },
    /// Row `i` is sample `(i − start) mod per` (an averaged block).
    Periodic { start: usize, per: usize },
}

/// The result of [`process`].
#[derive(Debug, Clone, PartialEq)]
pub struct Processed {
    /// The samples.
    pub samples: Samples,
    /// What was done.
    pub summary: ProcessSummary,
    /// Notes (the log's and processing's).
    pub notes: Vec<String>,
    /// Warnings (the log's and processing's).
    pub warnings: Vec<Warning>,
    /// The log's raw torques τ1 … τn, every row.
    pub log_tau: Vec<Vec<f64>>,
    map: RowMap,
    band: BandLimit,
}

impl Processed {
    /// The output sample that stands for row `row` of the log (`None` for
    /// rows lost at the derivative's edges).
    pub fn sample_of_row(&self, row: usize) -> Option<usize> {
        let n = self.samples.len();
        match self.map {
            RowMap::Direct { edge } => row.checked_sub(edge).filter(|i| *i < n),
            RowMap::Periodic { start, per } => {
                let i = (row as i64 - start as i64).rem_euclid(per as i64) as usize;
                (i < n).then_some(i)
            }
        }
    }

    /// The band-limiting the angles passed ([`BandLimit`]), as it acts on
    /// any series with one value per sample.
    pub fn band_limit(&self) -> &BandLimit {
        &self.band
    }

    /// A per-sample prediction (`predicted[j]` of length `samples.len()`)
    /// through the processing's own band-limiting
    /// ([`band_limit`](Self::band_limit)), as the angles passed it, so that
    /// its inertial and friction parts see the same bandwidth
    /// (`docs/processing.md`, "Parallel filtering"): the model torque that
    /// is compared with the log's.
    ///
    /// # Errors
    /// [`ProcessError`] when a prediction does not have one series per
    /// joint and one value per sample.
    pub fn band_limited(&self, predicted: &[&[f64]]) -> Result<Vec<Vec<f64>>, ProcessError> {
        self.check_joints(predicted.len())?;
        let mut limited: Vec<Vec<f64>> = predicted.iter().map(|p| p.to_vec()).collect();
        for p in &mut limited {
            self.check_per_sample(p.len())?;
            self.band.apply(p)?;
        }
        Ok(limited)
    }

    /// Pairs the log's raw torques with a per-sample series, as given, on
    /// every row that has a sample: `(measured, series)` per joint. For an
    /// averaged block the series repeats on every period, settling and tail
    /// included, so the fitness (78) of the pair is the paper's, on all
    /// rows.
    ///
    /// # Errors
    /// [`ProcessError`] when there is not one series per joint with one
    /// value per sample.
    pub fn paired_with_log_rows(&self, series: &[&[f64]]) -> Result<Paired, ProcessError> {
        self.check_joints(series.len())?;
        for p in series {
            self.check_per_sample(p.len())?;
        }
        Ok(self
            .log_tau
            .iter()
            .zip(series)
            .map(|(tau, series)| {
                let rows = tau.len();
                let mut m = Vec::with_capacity(rows);
                let mut p = Vec::with_capacity(rows);
                for (r, &measured) in tau.iter().enumerate() {
                    if let Some(i) = self.sample_of_row(r) {
                        m.push(measured);
                        p.push(series[i]);
                    }
                }
                (m, p)
            })
            .collect())
    }

    /// [`band_limited`](Self::band_limited), then
    /// [`paired_with_log_rows`](Self::paired_with_log_rows): a prediction
    /// and the log's raw torques, ready for the fitness (78) on all rows.
    ///
    /// # Errors
    /// [`ProcessError`] when a prediction does not have one series per
    /// joint and one value per sample.
    pub fn on_log_rows(&self, predicted: &[&[f64]]) -> Result<Paired, ProcessError> {
        let limited = self.band_limited(predicted)?;
        let views: Vec<&[f64]> = limited.iter().map(Vec::as_slice).collect();
        self.paired_with_log_rows(&views)
    }

    fn check_joints(&self, have: usize) -> Result<(), ProcessError> {
        check_count(
            have,
            self.log_tau.len(),
            "pairing a prediction with the log's joints",
            "give one predicted torque series per joint",
        )
    }

    fn check_per_sample(&self, have: usize) -> Result<(), ProcessError> {
        check_count(
            have,
            self.samples.len(),
            "pairing a prediction with the log's rows",
            "give one predicted torque per processed sample",
        )
    }
}

/// `Ok` when `have == need`, else [`ProcessError::TooShort`].
fn check_count(have: usize, need: usize, what: &str, hint: &str) -> Result<(), ProcessError> {
    if have == need {
        Ok(())
    } else {
        Err(ProcessError::TooShort {
            what: what.into(),
            have,
            need,
            hint: hint.into(),
        })
    }
}

/// `(measured, predicted)` per joint on the log's rows
/// ([`Processed::paired_with_log_rows`]).
pub type Paired = Vec<(Vec<f64>, Vec<f64>)>;

/// One series per joint.
type Pair = Vec<Vec<f64>>;

/// The name of channel `c` of the processing's inputs: the `joints` angles,
/// then the torques, then logged derivatives.
fn channel_name(c: usize, joints: usize) -> String {
    match c / joints {
        0 => format!("theta{}", c + 1),
        1 => format!("tau{}", c - joints + 1),
        _ => "a logged derivative".into(),
    }
}

/// Largest relative deviation of a time step from the nominal one that is
/// still treated as uniform (rounding of printed times).
const UNIFORM_TOLERANCE: f64 = 1e-6;

/// Fraction of the record that period averaging may leave unused (settling
/// and tail) without a [`Warning::AveragingUnused`].
const MAX_UNUSED_SILENT: f64 = 0.25;

/// Turns a validated log into samples ready for identification or
/// prediction.
///
/// Steps: (0) irregular time steps are resampled onto the nominal grid by
/// cubic Hermite interpolation (stated in the summary); (1) period
/// averaging when a period is known or detected; (2) the bandwidth
/// ([`Bandwidth`]): harmonic series (θ only), Butterworth (θ and τ alike)
/// or none;
/// (3) derivatives; (4) kinematics. Logged derivative columns, when used,
/// are taken as given and nothing is filtered.
///
/// The model's coordinates are two-dimensional here (ARAS-Diamond's task
/// pose, or a two-joint robot's angles); [`process_in`] takes any number.
pub fn process(
    log: &Log,
    opts: &ProcessOptions,
    coordinates: &impl Coordinates,
) -> Result<Processed, ProcessError> {
    process_in::<nalgebra::U2>(log, opts, coordinates)
}

/// [`process`] for a model whose coordinates have dimension `D`: a fixed
/// one (`U2`, `U7`) checked against the log's joints, or
/// [`nalgebra::Dyn`], the log's joint count. Every step runs per joint; the
/// bandwidth and the period are shared by all joints.
///
/// ```
/// use aras_log::{read_log_from, ReadOptions};
/// use aras_signal::{process_in, JointCoordinates, ProcessOptions};
///
/// let mut csv = String::from("t,theta1,theta2,theta3,tau1,tau2,tau3\n");
/// for i in 0..2000 {
///     let t = i as f64 * 1e-3;
///     let s = (std::f64::consts::TAU * t).sin();
///     csv += &format!("{t},{},{},{},{},{},{}\n", 0.1 * s, 0.2 * s, -0.1 * s, s, 0.5 * s, 0.2);
/// }
/// let log = read_log_from(csv.as_bytes(), "arm.csv", &ReadOptions::default())?;
/// let out = process_in::<nalgebra::Dyn>(&log, &ProcessOptions::default(), &JointCoordinates)?;
/// assert_eq!((out.samples.joints(), out.samples.len()), (3, 2000));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn process_in<D: Dim>(
    log: &Log,
    opts: &ProcessOptions,
    coordinates: &impl Coordinates<D>,
) -> Result<Processed, ProcessError>
where
    DefaultAllocator: Allocator<D>,
{
    let mut run = Run::new(log, opts, D::try_to_usize())?;
    // Logged derivatives, every row: the log as it is.
    if let (Some(v), Some(a), true) = (run.logged_vel, run.logged_acc, run.every_row) {
        return as_logged(log, v, a, coordinates, run.notes, run.warnings);
    }
    // 0–1. A uniform grid, the period and its average.
    let mut periods = run.periods()?;
    // 2–3. Bandwidth and derivatives.
    let smoothed = run.smooth(&mut periods.record)?;
    let harmonics = smoothed.band.harmonics.as_deref();
    // The output rows, the band they passed and the account of the choice.
    let rows = run.rows(&periods, smoothed.rates, smoothed.edge, harmonics)?;
    let band = run.band(&periods, &smoothed.band, &rows)?;
    let bandwidth = run.bandwidth(&periods, &smoothed.band, rows.aperiodic);
    // 4. Kinematics.
    let mut s = rows.samples;
    model_coordinates(&mut s, coordinates)?;

    Ok(Processed {
        summary: ProcessSummary {
            input_samples: log.len(),
            output_samples: s.len(),
            sample_rate_hz: run.fs,
            filter: smoothed.filter,
            periods: periods.record.periods,
            bandwidth,
            samples_dropped: rows.dropped,
            derivative: smoothed.method,
            derivative_source: if run.logged_vel.is_some() {
                "logged dtheta/ddtheta columns"
            } else {
                "differentiated θ"
            }
            .into(),
            angle_source: log.summary.angle_source.clone(),
            torque_source: log.summary.torque_source.clone(),
            torque_timing: log.torque_timing(),
            motion_shift_steps: run.shift,
        },
        samples: s,
        notes: run.notes,
        warnings: run.warnings,
        log_tau: log.tau.clone(),
        map: rows.map,
        band,
    })
}

/// A log with logged rates and accelerations, on every row: its samples as
/// they are, nothing filtered or averaged.
fn as_logged<D: Dim>(
    log: &Log,
    vel: &Pair,
    acc: &Pair,
    coordinates: &impl Coordinates<D>,
    notes: Vec<String>,
    warnings: Vec<Warning>,
) -> Result<Processed, ProcessError>
where
    DefaultAllocator: Allocator<D>,
{
    let mut s = samples_from(
        log.t.clone(),
        log.theta.clone(),
        vel.clone(),
        acc.clone(),
        log.tau.clone(),
    );
    model_coordinates(&mut s, coordinates)?;
    Ok(Processed {
        summary: ProcessSummary {
            input_samples: log.len(),
            output_samples: s.len(),
            sample_rate_hz: 1.0 / log.summary.nominal_step_s,
            filter: None,
            periods: None,
            bandwidth: BandwidthChoice {
                method: BandwidthMethod::LoggedDerivatives,
                period_s: None,
                period_origin: None,
                detection: None,
                harmonics: None,
                filter: None,
                spectrum: None,
                aperiodic: None,
                resampling: None,
                reason: "the log's dtheta/ddtheta columns are used exactly as given, with the \
                         logged angles and torques: nothing is filtered or averaged"
                    .into(),
            },
            samples_dropped: 0,
            derivative: DerivativeMethod::Auto,
            derivative_source: "logged dtheta/ddtheta columns".into(),
            angle_source: log.summary.angle_source.clone(),
            torque_source: log.summary.torque_source.clone(),
            torque_timing: log.torque_timing(),
            motion_shift_steps: 0.0,
        },
        samples: s,
        notes,
        warnings,
        log_tau: log.tau.clone(),
        map: RowMap::Direct { edge: 0 },
        band: BandLimit::None,
    })
}

/// What [`band_of`] needs to know about a processing run.
struct BandInputs<'a> {
    logged: bool,
    harmonics: Option<&'a [crate::HarmonicSelection]>,
    spec_used: Option<FilterSpec>,
    remainder_hz: Option<f64>,
    periods: Option<&'a PeriodSummary>,
    every_row: bool,
    irregular: bool,
    rows: usize,
    block: usize,
    fs: f64,
}

/// The band-limiting the angles passed, as an operator on per-sample
/// series. One band for every channel: the harmonic series keeps, for the
/// torque of either joint, the harmonics that the angles of every moving
/// joint resolve (the smallest count among joints that move), since each
/// joint's torque is built from both joints' motion and a harmonic beyond a
/// joint's count is noise in its θ̈. Samples at irregular log times are left
/// as they are (a uniform filter does not apply to them).
fn band_of(b: BandInputs<'_>) -> Result<BandLimit, crate::FilterError> {
    if b.logged {
        return Ok(BandLimit::None);
    }
    let samples_irregular = b.irregular && (b.every_row || b.periods.is_none());
    if let (Some(h), Some(p)) = (b.harmonics, b.periods) {
        let moving: Vec<usize> = h.iter().map(|s| s.harmonics).filter(|m| *m > 0).collect();
        let count = moving.iter().copied().min().unwrap_or(0);
        let kp = p.periods_per_block.max(1);
        if samples_irregular {
            return Ok(BandLimit::None);
        }
        let rows = b.every_row.then(|| {
            let whole = (b.rows - p.settling_samples - p.tail_samples) / p.samples_per_block.max(1);
            (p.settling_samples, whole)
        });
        let remainder = match (b.every_row, b.remainder_hz) {
            (true, Some(hz)) => Some(Butterworth::lowpass(FilterSpec::default().order, hz, b.fs)?),
            _ => None,
        };
        return Ok(BandLimit::Harmonics(HarmonicBand {
            per: b.block,
            periods_per_block: kp,
            top_bin: count * kp,
            rows,
            remainder,
        }));
    }
    match b.spec_used {
        Some(spec) if !samples_irregular => Ok(BandLimit::LowPass {
            sos: Butterworth::lowpass(spec.order, spec.cutoff_hz, b.fs)?,
            periodic: b.periods.is_some() && !b.every_row,
        }),
        _ => Ok(BandLimit::None),
    }
}

/// Moves the motion `u` steps later (`0 ≤ u < 1`) by cubic Hermite
/// interpolation between neighbouring samples, each quantity with its own
/// derivative as slope (the jerk from central differences of θ̈); the last
/// sample of a non-periodic record by its Taylor step.
fn shift_motion(x: &mut Pair, v: &mut Pair, a: &mut Pair, u: f64, dt: f64, periodic: bool) {
    let (u2, u3) = (u * u, u * u * u);
    let (h00, h10, h01, h11) = (
        2.0 * u3 - 3.0 * u2 + 1.0,
        u3 - 2.0 * u2 + u,
        -2.0 * u3 + 3.0 * u2,
        u3 - u2,
    );
    for j in 0..x.len() {
        let m = x[j].len();
        if m < 2 {
            continue;
        }
        let jerk = periodic_slopes(&a[j], dt, periodic);
        let step = |y: &[f64], dy: &[f64], i: usize| -> f64 {
            if i + 1 < m || periodic {
                let i1 = (i + 1) % m;
                y[i] * h00 + dy[i] * dt * h10 + y[i1] * h01 + dy[i1] * dt * h11
            } else {
                y[i] + dy[i] * u * dt
            }
        };
        let nx: Vec<f64> = (0..m)
            .map(|i| {
                let last = i + 1 == m && !periodic;
                if last {
                    x[j][i] + v[j][i] * u * dt + 0.5 * a[j][i] * (u * dt).powi(2)
                } else {
                    step(&x[j], &v[j], i)
                }
            })
            .collect();
        let nv: Vec<f64> = (0..m).map(|i| step(&v[j], &a[j], i)).collect();
        let na: Vec<f64> = (0..m).map(|i| step(&a[j], &jerk, i)).collect();
        (x[j], v[j], a[j]) = (nx, nv, na);
    }
}

fn samples_from(t: Vec<f64>, theta: Pair, theta_dot: Pair, theta_ddot: Pair, tau: Pair) -> Samples {
    let zeros = vec![vec![0.0; t.len()]; theta.len()];
    Samples {
        t,
        theta,
        theta_dot,
        theta_ddot,
        x: zeros.clone(),
        x_dot: zeros.clone(),
        x_ddot: zeros,
        tau,
    }
}

/// `a / b / c`: one figure per joint, as the reports write them.
fn per_joint(values: impl IntoIterator<Item = String>) -> String {
    values.into_iter().collect::<Vec<_>>().join(" / ")
}

/// Slopes of a uniformly sampled series (central differences; wrapping
/// for a periodic record, one-sided at the ends otherwise).
fn periodic_slopes(y: &[f64], dt: f64, periodic: bool) -> Vec<f64> {
    let n = y.len();
    if n < 4 {
        return vec![0.0; n];
    }
    if !periodic {
        return uniform_derivatives(y, dt).0;
    }
    (0..n)
        .map(|i| (y[(i + 1) % n] - y[(i + n - 1) % n]) / (2.0 * dt))
        .collect()
}

/// The bandwidth chosen and why, for reports and `summary.json`: the
/// `band` chosen for a run with `logged` derivatives or not, the `period`
/// used (none when no average was made), how an irregular log was brought
/// to a uniform grid, and the bandwidth `asked` for.
fn describe(
    logged: bool,
    band: &BandChoice,
    period: &PeriodChoice,
    resampling: Option<String>,
    asked: Bandwidth,
) -> BandwidthChoice {
    let (harmonics, spec, spectrum) = (band.harmonics.clone(), band.filter, band.spectrum.clone());
    let (period_s, period_origin, detection) =
        (period.period, period.origin, period.detection.clone());
    let declined = detection
        .as_ref()
        .and_then(|d| d.declined.clone())
        .map(|r| format!(" (no period: {r})"))
        .unwrap_or_default();
    let spectrum_used = spectrum.as_ref();
    let (method, reason) = if logged {
        (
            BandwidthMethod::LoggedDerivatives,
            "the log's derivative columns are used as given; nothing is filtered".to_string(),
        )
    } else if let Some(h) = &harmonics {
        (
            BandwidthMethod::HarmonicSeries,
            format!(
                "periodic record ({} period {:.6} s): Fourier series with {} harmonics \
                 (up to {} Hz), the highest whose power exceeds {:.1}× the noise floor \
                 (≈ {} rad RMS per sample); θ̇, θ̈ are the series' derivatives",
                match period_origin {
                    Some(PeriodOrigin::Detected) => "detected",
                    Some(PeriodOrigin::Sidecar) => "sidecar",
                    _ => "given",
                },
                period_s.unwrap_or(0.0),
                per_joint(h.iter().map(|s| s.harmonics.to_string())),
                per_joint(h.iter().map(|s| format!("{:.1}", s.highest_hz))),
                h.first().map_or(0.0, |s| s.threshold),
                per_joint(h.iter().map(|s| format!("{:.2e}", s.noise_rms))),
            ),
        )
    } else if let Some(s) = spec {
        let why = match (asked, spectrum_used) {
            (Bandwidth::Fixed(_), _) => {
                "a fixed cut-off from the settings, not chosen from the data".to_string()
            }
            (_, Some(c)) => format!(
                "the angles' motion reaches {} Hz above the noise floor \
                 (≈ {} rad RMS per sample); cut-off {CUTOFF_MARGIN}× that{declined}",
                per_joint(c.motion_top_hz.iter().map(|f| format!("{f:.2}"))),
                per_joint(c.noise_rms.iter().map(|r| format!("{r:.2e}"))),
            ),
            _ => String::new(),
        };
        (
            BandwidthMethod::Butterworth,
            format!(
                "zero-phase Butterworth order {} at {:.3} Hz: {why}",
                s.order, s.cutoff_hz
            ),
        )
    } else {
        (
            BandwidthMethod::None,
            "no filter (switched off)".to_string(),
        )
    };
    BandwidthChoice {
        method,
        period_s,
        period_origin,
        detection,
        harmonics,
        filter: spec,
        spectrum,
        aperiodic: None,
        resampling,
        reason,
    }
}

/// A period block whose θ deviates from the average by more than this
/// many times the median block's deviation is an outlier.
const OUTLIER_BLOCK: f64 = 3.0;

/// Re-averages `avg` without the blocks whose θ deviates by more than
/// [`OUTLIER_BLOCK`] times the median block (the median block always
/// stays, so at least half remain). Returns the number left out.
fn reject_outlier_blocks(avg: &mut crate::PeriodAverage, raw: &[Vec<f64>], angles: usize) -> usize {
    let (per, blocks, start) = (avg.samples_per_block, avg.blocks, avg.start);
    let dev: Vec<f64> = (0..blocks)
        .map(|b| {
            (0..angles)
                .map(|c| {
                    let x = &raw[c][start + b * per..start + (b + 1) * per];
                    x.iter()
                        .zip(&avg.channels[c])
                        .map(|(v, m)| (v - m).powi(2))
                        .sum::<f64>()
                })
                .sum::<f64>()
        })
        .collect();
    let mut sorted = dev.clone();
    sorted.sort_by(f64::total_cmp);
    let med = sorted[blocks / 2];
    let keep: Vec<usize> = (0..blocks)
        .filter(|&b| dev[b] <= OUTLIER_BLOCK * OUTLIER_BLOCK * med)
        .collect();
    if keep.len() == blocks {
        return 0;
    }
    let inv = 1.0 / keep.len() as f64;
    for (c, ch) in avg.channels.iter_mut().enumerate() {
        for (i, m) in ch.iter_mut().enumerate() {
            *m = keep
                .iter()
                .map(|&b| raw[c][start + b * per + i])
                .sum::<f64>()
                * inv;
        }
    }
    blocks - keep.len()
}

/// Pad length for a non-periodic record: ten time constants of the
/// filter's slowest pole, `fs/(2π·fc·sin(π/2N))` samples each, so start-up
/// transients decay to e⁻¹⁰ inside the odd extension; never less than
/// scipy's default, and capped below the record length.
fn padlen(sos: &Sos, spec: FilterSpec, fs: f64, n: usize) -> usize {
    let slowest = (std::f64::consts::PI / (2.0 * spec.order as f64)).sin();
    let tau = fs / (std::f64::consts::TAU * spec.cutoff_hz * slowest);
    ((10.0 * tau).ceil() as usize)
        .max(sos.padlen())
        .min(n.saturating_sub(1))
}

/// Filters every channel of `data` (in `channel_name`'s order for a log of
/// `joints` joints, which names a failing channel) in place.
fn filter_all(
    sos: &Sos,
    spec: FilterSpec,
    fs: f64,
    data: &mut [Vec<f64>],
    fourier: Option<&mut Fourier>,
    name: &str,
    joints: usize,
) -> Result<(), ProcessError> {
    match fourier {
        Some(f) => {
            for ch in data.iter_mut() {
                sos.periodic_with(f, ch);
            }
        }
        None => {
            let mut scratch = Vec::new();
            let pad = padlen(sos, spec, fs, data[0].len());
            for (c, ch) in data.iter_mut().enumerate() {
                sos.filtfilt_in_place_padded(ch, pad, &mut scratch)
                    .map_err(|source| ProcessError::Filter {
                        context: format!("filtering {} of {name}", channel_name(c, joints)),
                        source,
                    })?;
            }
        }
    }
    Ok(())
}

/// Samples per parallel task of the coordinate map: a few hundred
/// microseconds of kinematics each, so the tasks' overhead is negligible and
/// a 160 s log is shared among the cores.
const MAP_CHUNK: usize = 4096;

/// Fills the model's coordinates X, Ẋ, Ẍ from θ, θ̇, θ̈ at every sample
/// (copies for the identity), in parallel chunks; the error reported is the
/// first sample's that fails, as a sequential map would report it.
fn model_coordinates<D: Dim>(s: &mut Samples, c: &impl Coordinates<D>) -> Result<(), ProcessError>
where
    DefaultAllocator: Allocator<D>,
{
    use rayon::prelude::*;
    if c.is_identity() {
        s.x.clone_from(&s.theta);
        s.x_dot.clone_from(&s.theta_dot);
        s.x_ddot.clone_from(&s.theta_ddot);
        return Ok(());
    }
    let (n, dims) = (s.len(), s.x.len());
    if n == 0 || dims == 0 {
        return Ok(());
    }
    let (theta, theta_dot, theta_ddot, t) = (&s.theta, &s.theta_dot, &s.theta_ddot, &s.t);
    // Each task's pieces of the output columns: X1…, Ẋ1…, Ẍ1….
    let mut tasks: Vec<Vec<&mut [f64]>> = (0..n.div_ceil(MAP_CHUNK))
        .map(|_| Vec::with_capacity(3 * dims))
        .collect();
    for col in s.x.iter_mut().chain(&mut s.x_dot).chain(&mut s.x_ddot) {
        for (task, piece) in tasks.iter_mut().zip(col.chunks_mut(MAP_CHUNK)) {
            task.push(piece);
        }
    }
    let done: Vec<Result<(), ProcessError>> = tasks
        .into_par_iter()
        .enumerate()
        .map(|(k, mut cols)| {
            for r in 0..cols[0].len() {
                let i = k * MAP_CHUNK + r;
                let task = c
                    .map(motion_at(theta, theta_dot, theta_ddot, i))
                    .map_err(|e| ProcessError::Coordinates {
                        index: i,
                        t: t[i],
                        source: Box::new(e),
                    })?;
                for j in 0..dims {
                    cols[j][r] = task.pos[j];
                    cols[dims + j][r] = task.vel[j];
                    cols[2 * dims + j][r] = task.acc[j];
                }
            }
            Ok(())
        })
        .collect();
    done.into_iter().collect()
}

/// Refuses logged derivative columns that are not the derivatives of the
/// logged angles (θ̇ against θ, θ̈ against the logged θ̇): a rate in degrees
/// per second, a reversed sign or another column would otherwise be used as
/// given.
fn check_logged_derivatives(
    log: &Log,
    vel: &[Vec<f64>],
    acc: Option<&Vec<Vec<f64>>>,
) -> Result<(), ProcessError> {
    let wrap = |source| ProcessError::LoggedDerivatives { source };
    for j in 0..log.joints() {
        let [theta, dtheta, ddtheta] =
            ["theta", "dtheta", "ddtheta"].map(|c| format!("{c}{}", j + 1));
        aras_log::units::check_derivative_column(
            &log.name,
            (&dtheta, &vel[j]),
            (&theta, &log.theta[j]),
            &log.t,
        )
        .map_err(wrap)?;
        if let Some(a) = acc {
            aras_log::units::check_derivative_column(
                &log.name,
                (&ddtheta, &a[j]),
                (&dtheta, &vel[j]),
                &log.t,
            )
            .map_err(wrap)?;
        }
    }
    Ok(())
}
