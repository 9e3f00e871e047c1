//! End-to-end streaming identification from a CSV log in bounded memory.

use crate::PipelineError;
use std::ops::Range;
use std::path::Path;

use aras_dyn::Model;
use aras_kin::{AssemblyMode, Geometry, Motion};
use aras_log::{Columns, Log, LogReader, LogReport, LogSummary, ReadOptions, Sidecar};
use aras_signal::{Bandwidth, Butterworth, FilterSpec, PeriodSource, ProcessOptions, Sos};
use nalgebra::Vector2;
use serde::Serialize;

use aras_ident::streaming::{Accumulation, GramCheck, QrAccumulator, RegressorStage, States};
use aras_ident::validate::fitness_from_sums;
use aras_ident::{BaseParameters, IdentError, OlsEstimate, ReducedLs};

use super::delayed::TorqueShift;
use crate::TaskRegressor;
use crate::diagnose::Dataset;
use crate::friction_width::{FitRows, WidthRefinement, WidthSearch};
use crate::identify::IdentifySettings;
use crate::prepare::{RegressorColumns, prepare_block_rows, processing_filter};
use crate::robot::{FilterMode, filter_reach, keep_every_row, reversal_mask};
use crate::spool::SpoolWriter;
use faer::Mat;

/// Options of [`identify_log`]. `Default` gives the documented defaults.
#[derive(Debug, Clone)]
pub struct StreamingOptions {
    /// How the log is read (sidecar, sensor constants, checks).
    pub read: ReadOptions,
    /// Signal processing, as for the in-memory `aras_signal::process`
    /// (filter, period, settling, derivative method, logged derivatives).
    pub process: ProcessOptions,
    /// What the zero-phase filter is applied to after stacking (as
    /// [`crate::robot::filter`]), with the Butterworth the processing
    /// applied to θ; nothing is filtered when it applied none (a harmonic
    /// series, logged derivatives, [`Bandwidth::Off`]).
    pub filter_mode: FilterMode,
    /// Kinematic geometry (default: ARAS-Diamond).
    pub geometry: Geometry,
    /// Samples per block read and processed at a time (default 65 536;
    /// the overlapping-block route makes a block at least five times its
    /// overlap, which at high rates is more). Memory grows with it, not
    /// with the log.
    pub chunk_samples: usize,
    /// Relative size below which a filter's edge transient counts as
    /// decayed (default 1e-12): sets the overlap of filtered blocks.
    pub overlap_tolerance: f64,
    /// Normal equations (default, fast, checked) or incremental QR.
    pub accumulation: Accumulation,
    /// Reversal exclusion: joint `j`'s rows with `|θ̇_j|` below this speed
    /// (rad/s) are left out, widened by the filter's reach, exactly as
    /// [`crate::robot::reversal_mask`] in memory (default
    /// [`IdentifySettings`]' `min_speed`; 0 keeps every row).
    pub min_speed: f64,
    /// Where the filter's impulse response counts as ended for the
    /// widening ([`crate::robot::filter_reach`]; default
    /// [`IdentifySettings`]' `reversal_reach`).
    pub reversal_reach: f64,
    /// A torque delay to remove, in samples (default `None`): each torque
    /// is taken this many samples after its angles while the log streams,
    /// exactly as [`aras_signal::delay_torque`] on the whole log (the rows
    /// without such a torque are left out).
    pub torque_delay: Option<f64>,
    /// Refine the friction's Coulomb widths with this search and fit every
    /// row of a joint whose width is refined ([`crate::friction_width`], as
    /// identification's `rows = "all"` in memory; `None`: the sign law (49)
    /// on the rows `min_speed` keeps; default [`IdentifySettings`]': the
    /// default width search). Done on the period route,
    /// whose averaged period is one record in memory; the other routes fall
    /// back to `min_speed`'s rows with the sign law, said in
    /// [`StreamingResult::widths`].
    pub widths: Option<WidthSearch>,
}

impl Default for StreamingOptions {
    /// The in-memory identification's rows, filtering and width search
    /// ([`IdentifySettings::default`], [`Self::with_identification`]).
    fn default() -> Self {
        Self {
            read: ReadOptions::default(),
            process: ProcessOptions::default(),
            filter_mode: FilterMode::Parallel,
            geometry: Geometry::aras_diamond(),
            chunk_samples: 65_536,
            overlap_tolerance: 1e-12,
            accumulation: Accumulation::Gram,
            min_speed: 0.0,
            reversal_reach: 0.0,
            torque_delay: None,
            widths: None,
        }
        .with_identification(&IdentifySettings::default())
    }
}

impl StreamingOptions {
    /// Errors unless the block size, the overlap tolerance, the reversal
    /// threshold and its reach are in range.
    fn check(&self) -> Result<(), PipelineError> {
        let bad = |name, value, reason| {
            Err(PipelineError::InvalidSetting {
                name,
                value,
                reason,
            })
        };
        if self.chunk_samples < 1024 {
            return bad(
                "chunk_samples",
                self.chunk_samples as f64,
                "read at least 1024 samples per chunk (65 536 is a good size)",
            );
        }
        if !(self.overlap_tolerance > 0.0 && self.overlap_tolerance < 1.0) {
            return bad(
                "overlap_tolerance",
                self.overlap_tolerance,
                "give a relative tolerance in (0, 1), e.g. 1e-12",
            );
        }
        if !(self.min_speed.is_finite() && self.min_speed >= 0.0) {
            return bad(
                "min_speed",
                self.min_speed,
                "give a finite speed ≥ 0 in rad/s (0 keeps every row)",
            );
        }
        if !(self.reversal_reach > 0.0 && self.reversal_reach < 1.0) {
            return bad(
                "reversal_reach",
                self.reversal_reach,
                "give a fraction of the impulse response's peak in (0, 1), e.g. 1e-3",
            );
        }
        Ok(())
    }

    /// These options with the rows, filtering and width search of the
    /// in-memory identification's `settings` (`filtering`, `min_speed`,
    /// `reversal_reach`, and `width` when `rows` is [`FitRows::All`]), so
    /// that both routes fit the same rows the same way.
    pub fn with_identification(self, settings: &IdentifySettings) -> Self {
        Self {
            filter_mode: settings.filtering,
            min_speed: settings.min_speed,
            reversal_reach: settings.reversal_reach,
            widths: (settings.rows == FitRows::All).then_some(settings.width),
            ..self
        }
    }
}

impl StreamingResult {
    /// Fitness (78) per joint of the base parameters `beta_b` on the fitted
    /// rows, `100 (1 − ‖τ − W_b β_b‖ / ‖τ − mean τ‖)`, from the accumulated
    /// factors and [`Self::torque_sums`] (no second pass over the log).
    pub fn fitness(&self, beta_b: &[f64]) -> Result<[f64; 2], PipelineError> {
        let rss = self.accumulator.group_rss(beta_b)?;
        let mut f = [0.0; 2];
        for j in 0..2 {
            let [s1, s2] = self.torque_sums[j];
            f[j] = fitness_from_sums(rss[j], s1, s2, self.rows_fitted[j], j)?;
        }
        Ok(f)
    }
}

/// Which bounded-memory route [`identify_log`] took.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum StreamingRoute {
    /// Logged `dtheta`, `ddtheta` used and no filter: chunks go straight to
    /// the [`RegressorStage`] (the fast path).
    LoggedDerivatives,
    /// A period was given: the period average is accumulated on the fly
    /// (memory: one period), then processed as in memory.
    PeriodAverage,
    /// Non-periodic, filtered or differentiated: overlapping blocks, each
    /// processed as in memory, interior samples kept.
    OverlappingBlocks,
}

/// The result of [`identify_log`].
#[derive(Debug, Clone)]
pub struct StreamingResult {
    /// The accumulated per-joint factors (for WLS: `accumulator.wls(...)`).
    pub accumulator: QrAccumulator,
    /// The unweighted reduced problem (input of OLS and of the SDP).
    pub reduced: ReducedLs,
    /// OLS on it (63)–(66), σ corrected for the filter
    /// ([`OlsEstimate::with_filtered_noise`] with [`Self::noise_gain`]).
    pub ols: OlsEstimate,
    /// Noise power gain `Σ h²` of the zero-phase filter
    /// ([`crate::robot::noise_gain`]; 1 unfiltered): divide variances of a
    /// WLS from [`Self::accumulator`] by it as well.
    pub noise_gain: f64,
    /// The accuracy check of the normal equations (`None` with
    /// [`Accumulation::Qr`]). If it did not pass, rerun with
    /// [`Accumulation::Qr`].
    pub gram_check: Option<GramCheck>,
    /// The route taken.
    pub route: StreamingRoute,
    /// Rows read from the log (with [`StreamingOptions::torque_delay`]: the
    /// rows that have a shifted torque).
    pub samples_read: usize,
    /// Samples that entered the least squares (before reversal exclusion).
    pub samples_used: usize,
    /// Rows fitted per joint (after reversal exclusion).
    pub rows_fitted: [usize; 2],
    /// `[Σ τ, Σ τ²]` per joint over the fitted rows (as they entered the
    /// least squares, i.e. filtered): with [`QrAccumulator::group_rss`]
    /// this gives the fitness (78) on the fitted rows
    /// ([`StreamingResult::fitness`]).
    pub torque_sums: [[f64; 2]; 2],
    /// Blocks processed.
    pub blocks: usize,
    /// Overlap of the blocks (samples each side; 0 unless overlapping).
    pub overlap: usize,
    /// Whole periods averaged (period route).
    pub periods: usize,
    /// The friction's Coulomb widths ([`StreamingOptions::widths`]): the
    /// model accumulated has them, and a refined joint's every row was
    /// fitted; not refined without that option, and failed (rows away from
    /// reversals, the sign law) on a route without a period.
    pub widths: WidthRefinement,
    /// The reader's report (sampling, sources, saturation warnings).
    pub log: LogReport,
}

/// Opens an ARAS-Diamond log: two joints (columns of further joints are
/// ignored with a note, a log with fewer is refused).
fn open_log(path: &Path, read: &ReadOptions) -> Result<LogReader<std::fs::File>, PipelineError> {
    if let Some(n) = read.joints.filter(|&n| n != 2) {
        return Err(PipelineError::InvalidSetting {
            name: "read.joints",
            value: n as f64,
            reason: "ARAS-Diamond has two joints: leave ReadOptions::joints unset or give 2",
        });
    }
    let read = ReadOptions {
        joints: Some(2),
        ..read.clone()
    };
    LogReader::open(path, &read)
        .map_err(|e| sig(&format!("opening the log {}", path.display()), e))
        .map_err(PipelineError::from)
}

fn sig(context: &str, e: impl std::error::Error + Send + Sync + 'static) -> IdentError {
    IdentError::external(context, e)
}

fn invalid(context: &str, reason: &str) -> IdentError {
    IdentError::InvalidData {
        context: context.to_owned(),
        reason: reason.to_owned(),
    }
}

/// Identifies `model`'s base parameters (`base`) from the log at `path`
/// without holding the log in memory: it is read in chunks of
/// `options.chunk_samples` rows, and the least-squares problem is
/// accumulated as an incremental QR ([`QrAccumulator`]).
///
/// The route depends on the log and the options ([`StreamingRoute`]):
/// * **logged derivatives, no filter** (`process.use_logged_derivatives`,
///   the log has `dtheta*` and `ddtheta*`, used as given): per
///   sample `X, Ẋ, Ẍ` by `aras_kin::forward_motion`, then the
///   [`RegressorStage`]; memory: one chunk.
/// * **period averaging** (a period from the options or the sidecar): the
///   sum of each channel over the period is accumulated while reading
///   (memory: one period), then the averaged period is processed exactly as
///   `aras_signal::process` would, stacked and filtered ([`prepare`](crate::prepare::prepare), periodic)
///   and accumulated. The period-to-period spread check of the in-memory
///   path is not made (it needs the average before the periods).
/// * **overlapping blocks** (everything else): blocks of `chunk_samples`
///   plus an overlap each side long enough for the filters' edge
///   transients to decay below `overlap_tolerance` (the slowest pole's time
///   constant `τ = fs/(2π f_c sin(π/2N))` samples (an automatic
///   bandwidth takes its cut-off from the first block's angle spectrum,
///   `aras_signal::spectrum_cutoff`, so every block uses the same filter), `τ ln(1/tol)` per
///   filter, for the signal filter and the regressor filter in series) plus
///   the derivative stencil; each block is processed, stacked and filtered
///   as in memory and only its interior samples are accumulated. Block by
///   block the result then matches the in-memory pipeline to about
///   `overlap_tolerance` (tested).
///
/// Memory is `O(chunk_samples + overlap)` (or one period), independent of
/// the log length. The reader's end-of-log checks run at the end: a log
/// that fails them is an error even though it was consumed.
pub fn identify_log(
    path: &Path,
    model: &Model,
    base: &BaseParameters,
    options: &StreamingOptions,
) -> Result<StreamingResult, PipelineError> {
    identify_log_with_progress(path, model, base, options, &mut |_| {})
}

/// [`identify_log`], calling `progress(rows)` with the number of log rows
/// read so far after each chunk (for a progress bar: an hour at 10 kHz
/// takes minutes).
pub fn identify_log_with_progress(
    path: &Path,
    model: &Model,
    base: &BaseParameters,
    options: &StreamingOptions,
    progress: &mut dyn FnMut(u64),
) -> Result<StreamingResult, PipelineError> {
    options.check()?;
    let name = path.display().to_string();
    let reader = open_log(path, &options.read)?;
    let job = Job {
        model,
        base,
        options,
    };
    let mut stage = RegressorStage::with_accumulation(
        TaskRegressor::new(model.clone(), options.geometry),
        base,
        options.accumulation,
    )?;
    let mut acc = QrAccumulator::new(stage.names(), 2)?;
    let (period, logged) = period_and_derivatives(&reader, options);
    let mut src = Source {
        name: &name,
        reader,
        read: rows_reader(&name, options.torque_delay, progress)?,
    };
    let mut out = Progress::default();
    let mut widths = WidthRefinement::not_refined();
    let route = if period.is_none() && logged {
        stream_logged_derivatives(&mut src, job, &mut stage, &mut out)?;
        acc = stage.accumulator();
        StreamingRoute::LoggedDerivatives
    } else if let Some(p) = period {
        widths = stream_period(&mut src, job, (p, logged), &mut acc, &mut out)?;
        StreamingRoute::PeriodAverage
    } else {
        stream_blocks(&mut src, job, logged, &mut acc, &mut out)?;
        StreamingRoute::OverlappingBlocks
    };
    if options.widths.is_some() && route != StreamingRoute::PeriodAverage {
        widths = WidthRefinement::failed(format!(
            "the log has no period, and the {} route does not refine the widths",
            match route {
                StreamingRoute::LoggedDerivatives => "logged-derivative",
                _ => "overlapping-block",
            }
        ));
    }
    let report = src
        .reader
        .finish()
        .map_err(|e| sig(&format!("checking the log {name}"), e))?;
    let [n1, n2] = [acc.group_rows()[0], acc.group_rows()[1]];
    let b = acc.names().len();
    if n1 < b || n2 < b {
        return Err(IdentError::InvalidData {
            context: format!("streaming identification of {name}"),
            reason: format!(
                "only {n1} (joint 1) and {n2} (joint 2) samples are away from velocity \
                 reversals (min_speed = {} rad/s, widened by the filter's reach at {}); \
                 lower them or excite the joints more",
                options.min_speed, options.reversal_reach
            ),
        }
        .into());
    }
    let reduced = acc.reduced()?;
    let ols = reduced
        .ols()?
        .with_filtered_noise(out.gain.unwrap_or(1.0))?;
    Ok(StreamingResult {
        gram_check: acc.gram_check(),
        accumulator: acc,
        reduced,
        ols,
        noise_gain: out.gain.unwrap_or(1.0),
        rows_fitted: [n1, n2],
        torque_sums: out.tau,
        route,
        samples_read: out.read,
        samples_used: out.used,
        blocks: out.blocks,
        overlap: out.overlap,
        periods: out.periods,
        widths,
        log: report,
    })
}

/// What a streamed identification fits: the model, its base parameters and
/// the options.
#[derive(Clone, Copy)]
struct Job<'a> {
    model: &'a Model,
    base: &'a BaseParameters,
    options: &'a StreamingOptions,
}

/// A log being read: its name, its reader and the row source
/// ([`rows_reader`]).
struct Source<'a, R> {
    name: &'a str,
    reader: LogReader<std::fs::File>,
    read: R,
}

/// The logged-derivative route: each chunk's logged θ̇, θ̈ checked against
/// its angles, mapped to the task space and pushed into `stage` on the rows
/// away from reversals.
fn stream_logged_derivatives<R>(
    src: &mut Source<'_, R>,
    job: Job<'_>,
    stage: &mut RegressorStage<TaskRegressor>,
    out: &mut Progress,
) -> Result<(), PipelineError>
where
    R: FnMut(&mut LogReader<std::fs::File>, &mut Columns, usize) -> Result<usize, PipelineError>,
{
    let mut chunk = Columns::default();
    let mut x = [vec![], vec![]];
    let mut xd = [vec![], vec![]];
    let mut xdd = [vec![], vec![]];
    loop {
        chunk.clear();
        let n = (src.read)(&mut src.reader, &mut chunk, job.options.chunk_samples)?;
        if n == 0 {
            break;
        }
        check_chunk_derivatives(src.name, &chunk)?;
        for v in x.iter_mut().chain(&mut xd).chain(&mut xdd) {
            v.resize(n, 0.0);
        }
        for i in 0..n {
            let th = |a: &[Vec<f64>]| Vector2::new(a[0][i], a[1][i]);
            let joint = Motion::new(
                th(&chunk.theta),
                th(&chunk.theta_dot),
                th(&chunk.theta_ddot),
            );
            let task = aras_kin::forward_motion(&job.options.geometry, &joint, AssemblyMode::Plus)
                .map_err(|e| {
                    sig(
                        &format!(
                            "{}: forward kinematics of sample {}",
                            src.name,
                            out.read + i
                        ),
                        e,
                    )
                })?;
            for c in 0..2 {
                x[c][i] = task.pos[c];
                xd[c][i] = task.vel[c];
                xdd[c][i] = task.acc[c];
            }
        }
        let states = States {
            x: &[&x[0], &x[1]],
            x_dot: &[&xd[0], &xd[1]],
            x_ddot: &[&xdd[0], &xdd[1]],
            tau: &[&chunk.tau[0], &chunk.tau[1]],
        };
        let keep = reversal_mask(&chunk.theta_dot, job.options.min_speed, 0, false)?;
        let (k1, k2) = keep.split_at(n);
        for (j, k) in [k1, k2].into_iter().enumerate() {
            for (&t, _) in chunk.tau[j].iter().zip(k).filter(|(_, k)| **k) {
                out.tau[j][0] += t;
                out.tau[j][1] += t * t;
            }
        }
        stage.push_selected(&states, Some(&[k1, k2]))?;
        out.read += n;
        out.used += n;
        out.blocks += 1;
    }
    Ok(())
}

/// The period route: the log averaged over its periods while read, the
/// Coulomb widths refined on the averaged period (`job.options.widths`),
/// and the period accumulated into `acc`. Returns the width refinement.
fn stream_period<R>(
    src: &mut Source<'_, R>,
    job: Job<'_>,
    (p, logged): (f64, bool),
    acc: &mut QrAccumulator,
    out: &mut Progress,
) -> Result<WidthRefinement, PipelineError>
where
    R: FnMut(&mut LogReader<std::fs::File>, &mut Columns, usize) -> Result<usize, PipelineError>,
{
    let averaged = period_average(
        src.name,
        &mut src.reader,
        &mut src.read,
        p,
        job.options,
        logged,
    )?;
    let (log, periods) = (averaged.log, averaged.periods);
    out.periods = periods;
    out.read = averaged.rows;
    out.blocks = averaged.chunks;
    let popts = averaged.process;
    // The averaged period is one record in memory: the widths are
    // refined on it exactly as in memory.
    let refinement = match &job.options.widths {
        Some(search) => {
            let mut prepared = crate::prepare::prepare(
                &log,
                &popts,
                job.model,
                &job.options.geometry,
                job.options.filter_mode,
                RegressorColumns::Standard,
                false,
            )?;
            // Checked against the rows `min_speed` keeps, as in memory.
            let away = prepared.keep_mask(job.options.min_speed, job.options.reversal_reach)?;
            crate::friction_width::refine_checked_widths(
                &mut prepared,
                job.model,
                job.base,
                job.options.filter_mode,
                search,
                &away,
            )?
        }
        None => WidthRefinement::not_refined(),
    };
    let refined = crate::friction_width::with_widths(job.model, refinement.widths())?;
    let job = Job {
        model: &refined,
        ..job
    };
    let rows = BlockRows {
        window: None,
        all_rows: refinement.joints.map(|j| j.all_rows),
    };
    out.used = accumulate_processed(&log, &popts, job, acc, rows, out, &mut None)?;
    Ok(refinement)
}

/// The overlapping-block route: blocks read, filtered with an overlap that
/// covers the filter's transient and the reversal exclusion's reach, and
/// accumulated into `acc` while the next ones are read.
fn stream_blocks<R>(
    src: &mut Source<'_, R>,
    job: Job<'_>,
    logged: bool,
    acc: &mut QrAccumulator,
    out: &mut Progress,
) -> Result<(), PipelineError>
where
    R: FnMut(&mut LogReader<std::fs::File>, &mut Columns, usize) -> Result<usize, PipelineError>,
{
    let mut popts = job.options.process.clone();
    let mut spares: [Option<Mat<f64>>; BLOCKS_IN_FLIGHT] = Default::default();
    let (margin, rows) = overlapping_blocks(
        src.name,
        &mut src.reader,
        &mut src.read,
        &mut popts,
        BlockSizes::new(job.options, logged),
        |p, dt| {
            Ok(overlap(p, dt, job.options.overlap_tolerance)?
                + reach_of(p, dt, job.options.reversal_reach)?)
        },
        |pending, popts| process_blocks(pending, popts, job, acc, out, &mut spares),
    )?;
    out.overlap = margin;
    out.read = rows;
    Ok(())
}

/// The logged derivatives of a chunk checked against its angles, as the
/// in-memory processing checks them
/// ([`aras_log::units::check_derivative_column`]).
fn check_chunk_derivatives(name: &str, chunk: &Columns) -> Result<(), PipelineError> {
    use aras_log::units::check_derivative_column;
    for j in 0..2 {
        let [theta, dtheta, ddtheta] =
            ["theta", "dtheta", "ddtheta"].map(|c| format!("{c}{}", j + 1));
        check_derivative_column(
            name,
            (&dtheta, &chunk.theta_dot[j]),
            (&theta, &chunk.theta[j]),
            &chunk.t,
        )
        .and_then(|()| {
            check_derivative_column(
                name,
                (&ddtheta, &chunk.theta_ddot[j]),
                (&dtheta, &chunk.theta_dot[j]),
                &chunk.t,
            )
        })
        .map_err(|e| sig("the logged derivatives cannot be used", e))?;
    }
    Ok(())
}

/// The period a log is averaged over (the options', else the sidecar's;
/// never detected while streaming) and whether its logged derivatives are
/// used (asked for, and the log has both).
fn period_and_derivatives(
    reader: &LogReader<std::fs::File>,
    options: &StreamingOptions,
) -> (Option<f64>, bool) {
    let period = match options.process.period {
        PeriodSource::FromSidecar => reader.sidecar().excitation.period_s,
        PeriodSource::Seconds(p) => Some(p),
        PeriodSource::Off => None,
    };
    let logged = options.process.use_logged_derivatives
        && reader.has_velocity()
        && reader.has_acceleration();
    (period, logged)
}

/// Appends up to `n` rows of the log to a buffer: `read(reader, into, n)`
/// (fewer only at the end of the log), returns how many.
type ReadRows<'a> = dyn FnMut(&mut LogReader<std::fs::File>, &mut Columns, usize) -> Result<usize, PipelineError>
    + 'a;

/// The rows of a log, `n` at a time: `read(reader, into, n)` appends up to
/// `n` rows to `into` (fewer only at the end of the log), each torque taken
/// `torque_delay` samples after its angles if one is given (the rows
/// without such a torque dropped), and calls `progress` with the rows read
/// so far.
#[allow(clippy::type_complexity)]
fn rows_reader<'a>(
    name: &'a str,
    torque_delay: Option<f64>,
    progress: &'a mut dyn FnMut(u64),
) -> Result<
    impl FnMut(&mut LogReader<std::fs::File>, &mut Columns, usize) -> Result<usize, PipelineError> + 'a,
    PipelineError,
> {
    if let Some(d) = torque_delay.filter(|d| !d.is_finite()) {
        return Err(PipelineError::InvalidSetting {
            name: "torque_delay",
            value: d,
            reason: "give a finite number of samples, e.g. 2.5",
        });
    }
    let mut shift = torque_delay.map(TorqueShift::new);
    let mut raw = Columns::default();
    let mut rows_read = 0u64;
    Ok(
        move |reader: &mut LogReader<std::fs::File>, chunk: &mut Columns, n: usize| {
            let mut got = 0;
            while got < n {
                let into = if shift.is_some() {
                    raw.clear();
                    &mut raw
                } else {
                    &mut *chunk
                };
                let k = reader
                    .read_rows(into, n - got)
                    .map_err(|e| sig(&format!("reading the log {name}"), e))?;
                rows_read += k as u64;
                progress(rows_read);
                if k == 0 {
                    break;
                }
                got += match shift.as_mut() {
                    Some(s) => s.push(&raw, chunk),
                    None => k,
                };
            }
            Ok(got)
        },
    )
}

/// The period average of a log read chunk by chunk ([`period_average`]).
struct PeriodAverage {
    /// One block of averaged periods, as a log.
    log: Log,
    /// Whole periods averaged.
    periods: usize,
    /// Rows read.
    rows: usize,
    /// Chunks read.
    chunks: usize,
    /// The processing options for the averaged log (its period, no
    /// settling: the sums skipped it).
    process: ProcessOptions,
}

/// Sums each channel over the period `period_s` while reading the log
/// with `read(reader, into, n)` (memory: one period), and returns the
/// averaged period as a log to process as in memory.
fn period_average(
    name: &str,
    reader: &mut LogReader<std::fs::File>,
    read: &mut ReadRows<'_>,
    period_s: f64,
    options: &StreamingOptions,
    logged: bool,
) -> Result<PeriodAverage, PipelineError> {
    let mut avg: Option<PeriodSums> = None;
    let mut chunk = Columns::default();
    let mut dt = options.read.nominal_step.unwrap_or(0.0);
    let (mut rows, mut chunks) = (0, 0);
    loop {
        chunk.clear();
        let n = read(reader, &mut chunk, options.chunk_samples)?;
        if n == 0 {
            break;
        }
        let sums = match &mut avg {
            Some(s) => s,
            None => {
                dt = nominal_step(&chunk, dt)?;
                avg.insert(PeriodSums::new(period_s, dt, &options.process, logged)?)
            }
        };
        sums.add(&chunk);
        rows += n;
        chunks += 1;
    }
    let sums = avg.ok_or_else(|| invalid(name, "the log has no data rows"))?;
    let (log, periods) = sums.finish(name, rows, reader.sidecar().clone())?;
    let mut process = options.process.clone();
    process.period = PeriodSource::Seconds(period_s);
    process.settling_s = 0.0;
    Ok(PeriodAverage {
        log,
        periods,
        rows,
        chunks,
        process,
    })
}

/// Processes the log at `path` as [`aras_signal::process`] would, without
/// holding it in memory, into a diagnosis [`Dataset`]:
/// * with a period (from the options or the sidecar), the period average
///   is accumulated while reading (memory: one period) and processed in
///   memory, as [`identify_log`]'s period route does;
/// * otherwise the log is processed in overlapping blocks (as
///   [`identify_log`]'s overlapping-block route does: an automatic
///   bandwidth takes its cut-off from the first block) and the blocks'
///   interior samples are written to a scratch file in `dir`
///   ([`crate::spool`]), which the diagnosis reads window by window; the
///   file is removed with the last clone of the data set.
///
/// Of `options`, the reading, processing, geometry, `chunk_samples`,
/// `overlap_tolerance` and `torque_delay` apply. `progress(rows)` is called
/// with the rows read so far.
pub fn spool_log(
    path: &Path,
    options: &StreamingOptions,
    dir: &Path,
    progress: &mut dyn FnMut(u64),
) -> Result<Dataset, PipelineError> {
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into(),
    );
    let mut reader = open_log(path, &options.read)?;
    let (period, logged) = period_and_derivatives(&reader, options);
    let mut read = rows_reader(&name, options.torque_delay, progress)?;
    let task = aras_kin::task_motion(&options.geometry);
    let process = |log: &Log, popts: &ProcessOptions| {
        aras_signal::process(log, popts, &task).map_err(|e| sig(&format!("processing {name}"), e))
    };
    let dataset = if let Some(p) = period {
        let averaged = period_average(&name, &mut reader, &mut read, p, options, logged)?;
        Dataset::from_processed_owned(name.clone(), process(&averaged.log, &averaged.process)?)?
    } else {
        let mut spool = SpoolWriter::create_in(dir)?;
        let mut popts = options.process.clone();
        let mut filter: Option<(Option<Sos>, f64)> = None;
        overlapping_blocks(
            &name,
            &mut reader,
            &mut read,
            &mut popts,
            BlockSizes::new(options, logged),
            |p, dt| overlap(p, dt, options.overlap_tolerance),
            |pending, popts| {
                use rayon::prelude::*;
                let done = pending
                    .par_iter()
                    .map(|(log, window)| process(log, popts).map(|p| (p, log.len(), *window)))
                    .collect::<Vec<_>>();
                for part in done {
                    let (p, len, window) = part?;
                    if filter.is_none() {
                        let sm = &p.summary;
                        filter = Some((processing_filter(sm)?, sm.sample_rate_hz));
                    }
                    spool.append(&p.samples, kept_range(window, len, p.samples.len()))?;
                }
                Ok(())
            },
        )?;
        let (filter, rate) = filter.ok_or_else(|| invalid(&name, "the log has no data rows"))?;
        Dataset::spooled(name.clone(), spool.finish()?, filter, rate)
    };
    reader
        .finish()
        .map_err(|e| sig(&format!("checking the log {name}"), e))?;
    Ok(dataset)
}

/// What [`overlapping_blocks`] needs to size its blocks.
#[derive(Debug, Clone, Copy)]
struct BlockSizes {
    /// Samples per block at least (`StreamingOptions::chunk_samples`).
    chunk: usize,
    /// The log's sample step if known (> 0), else estimated from the first
    /// block.
    dt: f64,
    /// Logged derivatives are used (no automatic cut-off then).
    logged: bool,
}

impl BlockSizes {
    /// The sizes `options` ask for, on a log whose logged derivatives are
    /// used or not.
    fn new(options: &StreamingOptions, logged: bool) -> Self {
        Self {
            chunk: options.chunk_samples,
            dt: options.read.nominal_step.unwrap_or(0.0),
            logged,
        }
    }
}

/// The processed samples of a block to keep: `window` as [`Block`] gives
/// it, `len` rows read, `n` samples out of the processing, which trims the
/// same number of rows at each end (processed sample `i` is the block's
/// row `(len − n) / 2 + i`).
fn kept_range((start, from, to): (usize, usize, usize), len: usize, n: usize) -> Range<usize> {
    let first = start + (len - n) / 2;
    let i0 = from.saturating_sub(first).min(n);
    i0..to.saturating_sub(first).min(n).max(i0)
}

/// A block read: its rows as a [`Log`], and `(index of its first sample,
/// first sample to keep, end of the samples to keep)`.
type Block = (Log, (usize, usize, usize));

/// The overlapping-block reading shared by streaming identification and
/// [`spool_log`]: blocks of at least `sizes.chunk` rows (and
/// [`BLOCK_PER_MARGIN`] margins) with `margin_of(popts, dt)` rows of
/// overlap each side are read with `read(reader, into, n)` and handed to
/// `flush(blocks, popts)` [`BLOCKS_IN_FLIGHT`] at a time, in order, on a
/// worker thread while the next blocks are read (the caller keeps only each
/// block's samples in its keep range). An automatic
/// bandwidth is fixed from the first block's angle spectrum
/// (`aras_signal::spectrum_cutoff`), so every block uses the same filter;
/// `popts` holds it afterwards. Returns the margin and the rows read.
fn overlapping_blocks(
    name: &str,
    reader: &mut LogReader<std::fs::File>,
    read: &mut ReadRows<'_>,
    popts: &mut ProcessOptions,
    sizes: BlockSizes,
    margin_of: impl Fn(&ProcessOptions, f64) -> Result<usize, PipelineError>,
    mut flush: impl FnMut(&mut Vec<Block>, &ProcessOptions) -> Result<(), PipelineError> + Send,
) -> Result<(usize, usize), PipelineError> {
    // The blocks are processed on a worker while the next ones are read:
    // reading is serial and a quarter of the time at 10 kHz. The rendezvous
    // channel holds nothing, so at most one batch waits while one is
    // processed.
    std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::sync_channel::<(Vec<Block>, ProcessOptions)>(0);
        let worker = scope.spawn(move || -> Result<(), IdentError> {
            for (mut batch, p) in rx {
                flush(&mut batch, &p).map_err(PipelineError::into_ident)?;
            }
            Ok(())
        });
        let read = read_blocks(name, reader, read, popts, sizes, margin_of, |batch, p| {
            // A closed channel means the worker stopped on an error, which
            // the join below returns.
            tx.send((batch, p.clone())).is_ok()
        });
        drop(tx);
        worker
            .join()
            .map_err(|_| invalid(name, "the block worker stopped unexpectedly"))??;
        read
    })
}

/// The reading half of [`overlapping_blocks`]: hands each batch of blocks to
/// `send`, which says whether to go on.
fn read_blocks(
    name: &str,
    reader: &mut LogReader<std::fs::File>,
    read: &mut ReadRows<'_>,
    popts: &mut ProcessOptions,
    sizes: BlockSizes,
    margin_of: impl Fn(&ProcessOptions, f64) -> Result<usize, PipelineError>,
    mut send: impl FnMut(Vec<Block>, &ProcessOptions) -> bool,
) -> Result<(usize, usize), PipelineError> {
    popts.period = PeriodSource::Off;
    let mut rows = 0usize;
    let mut chunk = Columns::default();
    let mut buf = Columns::default();
    let mut buf_start = 0usize; // global index of buf's first sample
    let mut done = 0usize; // samples before this are handed over
    let mut margin = 0usize;
    let mut dt = sizes.dt;
    let mut first = true;
    // Samples per block: `sizes.chunk`, or more where the overlap would
    // otherwise be a large share of each block (high rates).
    let mut block = sizes.chunk;
    let mut eof = false;
    // Blocks read but not yet handed over.
    let mut pending: Vec<Block> = Vec::new();
    while !eof {
        chunk.clear();
        let want = if first { block } else { block + 2 * margin };
        let n = read(reader, &mut chunk, want.saturating_sub(buf.len()))?;
        eof = n == 0 || buf.len() + n < want;
        append(&mut buf, &chunk);
        rows += n;
        if first {
            if buf.is_empty() {
                return Err(invalid(name, "the log has no data rows").into());
            }
            dt = nominal_step(&buf, dt)?;
            if popts.filter == Bandwidth::Auto && !sizes.logged {
                // One cut-off for every block: the first block's spectrum.
                let c = aras_signal::spectrum_cutoff(&[&buf.theta[0], &buf.theta[1]], dt);
                popts.filter = Bandwidth::Fixed(FilterSpec {
                    cutoff_hz: c.cutoff_hz,
                    ..FilterSpec::default()
                });
            }
            margin = margin_of(popts, dt)?;
            block = block.max(BLOCK_PER_MARGIN * margin);
            first = false;
            if !eof {
                // Read the rest of the first block with its margin.
                chunk.clear();
                let want = block + 2 * margin;
                let n = read(reader, &mut chunk, want - buf.len())?;
                eof = buf.len() + n < want;
                append(&mut buf, &chunk);
                rows += n;
            }
        }
        let end = buf_start + buf.len();
        let keep_end = if eof { end } else { end - margin };
        if keep_end <= done && !eof {
            continue;
        }
        pending.push((
            block_log(name, &buf, dt, reader.sidecar().clone()),
            (buf_start, done, keep_end),
        ));
        if (pending.len() == BLOCKS_IN_FLIGHT || eof) && !send(std::mem::take(&mut pending), popts)
        {
            break;
        }
        done = keep_end;
        // Keep `margin` samples before `done` for the next block.
        let drop = (done.saturating_sub(margin)).saturating_sub(buf_start);
        drain_front(&mut buf, drop);
        buf_start += drop;
    }
    Ok((margin, rows))
}

/// Least block length of the overlapping-block route, in margins (filter
/// overlap plus reversal reach, each side), so that the two margins a block
/// re-reads stay under 40 % of it. At 1 kHz the margin is ≈ 2 600 samples
/// and `chunk_samples` rules; at 10 kHz it is ≈ 25 600 and blocks grow to
/// ≈ 128 000 samples: against 65 536, 1 h at 10 kHz takes ≈ 56 s instead
/// of 67 s, for a peak memory of ≈ 280 MiB instead of 190 MiB (eight
/// margins: 48 s and 450 MiB; `docs/scale.md`).
const BLOCK_PER_MARGIN: usize = 5;

/// Blocks of the overlapping-block route processed at once, one per core
/// of a 2-core machine: processing a block is mostly serial (processing,
/// stacking), so two in flight keep both cores busy; each has its own
/// accumulator, merged in order.
const BLOCKS_IN_FLIGHT: usize = 2;

/// Processes the `pending` blocks in parallel, each into its own
/// accumulator (stacking into its lane's spare matrix, which it hands back),
/// and merges them into `acc` and `out` in block order.
fn process_blocks(
    pending: &mut Vec<Block>,
    popts: &ProcessOptions,
    job: Job<'_>,
    acc: &mut QrAccumulator,
    out: &mut Progress,
    spares: &mut [Option<Mat<f64>>; BLOCKS_IN_FLIGHT],
) -> Result<(), PipelineError> {
    use rayon::prelude::*;
    let parts = pending
        .par_iter()
        .zip(spares.par_iter_mut())
        .map(
            |((log, window), spare)| -> Result<(QrAccumulator, Progress, usize), IdentError> {
                let mut a = QrAccumulator::new(acc.names(), acc.n_groups())?;
                let mut p = Progress {
                    gain: out.gain,
                    ..Progress::default()
                };
                let rows = BlockRows {
                    window: Some(*window),
                    all_rows: [false; 2],
                };
                let used = accumulate_processed(log, popts, job, &mut a, rows, &mut p, spare)
                    .map_err(PipelineError::into_ident)?;
                Ok((a, p, used))
            },
        )
        .collect::<Vec<_>>();
    pending.clear();
    for part in parts {
        let (a, p, used) = part?;
        acc.merge(&a)?;
        if out.gain.is_none() {
            out.gain = p.gain;
        }
        for (t, q) in out.tau.iter_mut().zip(p.tau) {
            t[0] += q[0];
            t[1] += q[1];
        }
        out.used += used;
        out.blocks += 1;
    }
    Ok(())
}

#[derive(Default)]
struct Progress {
    read: usize,
    used: usize,
    blocks: usize,
    overlap: usize,
    periods: usize,
    gain: Option<f64>,
    tau: [[f64; 2]; 2],
}

/// The reader's nominal step: `ReadOptions::nominal_step` if given (> 0),
/// else the median of the first 4096 steps, as the reader defines it.
fn nominal_step(c: &Columns, given: f64) -> Result<f64, PipelineError> {
    if given > 0.0 {
        return Ok(given);
    }
    let k = (c.len().saturating_sub(1)).min(aras_log::NOMINAL_WINDOW);
    if k == 0 {
        return Err(invalid(
            "estimating the sample step",
            "the log has fewer than 2 rows; record at least 16 samples",
        )
        .into());
    }
    let mut steps: Vec<f64> = (0..k).map(|i| c.t[i + 1] - c.t[i]).collect();
    steps.sort_by(f64::total_cmp);
    Ok(if k % 2 == 1 {
        steps[k / 2]
    } else {
        0.5 * (steps[k / 2 - 1] + steps[k / 2])
    })
}

/// Samples of overlap each side of a block: the filters' transients (two
/// zero-phase filters in series: the signal's and the regressor's) decay to
/// `tol` and the derivative stencil (at most 64 samples) fits.
fn overlap(p: &ProcessOptions, dt: f64, tol: f64) -> Result<usize, PipelineError> {
    const STENCIL: usize = 64;
    let Bandwidth::Fixed(spec) = p.filter else {
        return Ok(STENCIL);
    };
    let fs = 1.0 / dt;
    let slowest = (std::f64::consts::PI / (2.0 * spec.order as f64)).sin();
    let tau = fs / (std::f64::consts::TAU * spec.cutoff_hz * slowest);
    if !(tau.is_finite() && tau > 0.0) {
        return Err(PipelineError::InvalidSetting {
            name: "filter cut-off",
            value: spec.cutoff_hz,
            reason: "the cut-off must be positive and below the Nyquist frequency",
        });
    }
    Ok(2 * (tau * (1.0 / tol).ln()).ceil() as usize + STENCIL)
}

/// Appends every row of `c` to `buf`.
pub(super) fn append(buf: &mut Columns, c: &Columns) {
    append_rows(buf, c, 0..c.len());
}

/// Appends rows `r` of `c` to `buf` (columns the log lacks stay empty).
pub(super) fn append_rows(buf: &mut Columns, c: &Columns, r: std::ops::Range<usize>) {
    buf.t.extend_from_slice(&c.t[r.clone()]);
    buf.resize_joints(c.joints());
    for k in 0..c.joints() {
        for (b, v) in [
            (&mut buf.theta[k], &c.theta[k]),
            (&mut buf.tau[k], &c.tau[k]),
            (&mut buf.theta_dot[k], &c.theta_dot[k]),
            (&mut buf.theta_ddot[k], &c.theta_ddot[k]),
        ] {
            if !v.is_empty() {
                b.extend_from_slice(&v[r.clone()]);
            }
        }
    }
}

pub(super) fn drain_front(buf: &mut Columns, n: usize) {
    let d = |v: &mut Vec<f64>| {
        let n = n.min(v.len());
        v.drain(..n);
    };
    d(&mut buf.t);
    for k in 0..buf.joints() {
        d(&mut buf.theta[k]);
        d(&mut buf.tau[k]);
        d(&mut buf.theta_dot[k]);
        d(&mut buf.theta_ddot[k]);
    }
}

fn range(v: &[f64]) -> [f64; 2] {
    v.iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], &x| {
            [lo.min(x), hi.max(x)]
        })
}

/// A `Log` over a block of rows, so `aras_signal::process` can run on it.
fn block_log(name: &str, c: &Columns, dt: f64, sidecar: Sidecar) -> Log {
    let pair = |a: &Vec<Vec<f64>>| a.iter().any(|c| !c.is_empty()).then(|| a.clone());
    Log {
        name: name.to_owned(),
        t: c.t.clone(),
        theta: c.theta.clone(),
        tau: c.tau.clone(),
        theta_dot: pair(&c.theta_dot),
        theta_ddot: pair(&c.theta_ddot),
        sidecar,
        summary: LogSummary {
            file: name.to_owned(),
            rows: c.len(),
            nominal_step_s: dt,
            sample_rate_hz: 1.0 / dt,
            duration_s: c.t.last().copied().unwrap_or(0.0) - c.t.first().copied().unwrap_or(0.0),
            worst_step: None,
            angle_source: String::new(),
            torque_source: String::new(),
            theta_range: c.theta.iter().map(|v| range(v)).collect(),
            tau_range: c.tau.iter().map(|v| range(v)).collect(),
            sidecar: None,
            timing: Default::default(),
            lines: Default::default(),
            channel_columns: vec![0; 2 * c.joints()],
        },
        notes: Vec::new(),
        warnings: Vec::new(),
    }
}

/// Which rows of a processed record [`accumulate_processed`] pushes.
#[derive(Debug, Clone, Copy)]
struct BlockRows {
    /// The samples with global indices in `done..keep_end`, as
    /// `(first index of the record, done, keep_end)`; every sample if `None`.
    window: Option<(usize, usize, usize)>,
    /// Per joint, every row (a joint fitted on every row) instead of those
    /// the reversal exclusion keeps.
    all_rows: [bool; 2],
}

/// Processes `log` as in memory (process → stack → filter → reversal
/// exclusion → base columns) and pushes the kept rows of the samples
/// `rows` chooses. Returns the samples in the window; sets `gain` (the
/// filter's noise gain) on the first call. Stacks into `spare` when it has
/// the block's shape and leaves the block's matrix there for the next
/// block.
fn accumulate_processed(
    log: &Log,
    popts: &ProcessOptions,
    job: Job<'_>,
    acc: &mut QrAccumulator,
    rows: BlockRows,
    out: &mut Progress,
    spare: &mut Option<Mat<f64>>,
) -> Result<usize, PipelineError> {
    let options = job.options;
    let mut block = prepare_block_rows(
        log,
        popts,
        job.model,
        &options.geometry,
        options.filter_mode,
        RegressorColumns::Base(job.base),
        (options.min_speed, options.reversal_reach),
        spare.take(),
    )?;
    let n = block.n;
    if out.gain.is_none() {
        out.gain = block.noise_gain;
    }
    keep_every_row(&mut block.keep, rows.all_rows);
    let Range { start: i0, end: i1 } = rows.window.map_or(0..n, |w| kept_range(w, log.len(), n));
    if i1 == i0 {
        *spare = Some(block.stacked.w);
        return Ok(0);
    }
    let keep = &block.keep;
    let st = &block.stacked;
    let wb = &st.w;
    for g in 0..2 {
        // Runs of kept rows, pushed as views of the block's matrix (no copy).
        let mut i = g * n + i0;
        let end = g * n + i1;
        while i < end {
            if !keep[i] {
                i += 1;
                continue;
            }
            let start = i;
            while i < end && keep[i] {
                i += 1;
            }
            let w = wb.as_ref().subrows(start, i - start);
            let t = &st.t[start..i];
            for v in t {
                out.tau[g][0] += v;
                out.tau[g][1] += v * v;
            }
            match options.accumulation {
                Accumulation::Qr => acc.push_rows(g, w, t)?,
                Accumulation::Gram => acc.push_rows_gram(g, w, t)?,
            }
        }
    }
    *spare = Some(block.stacked.w);
    Ok(i1 - i0)
}

/// Samples the reversal exclusion widens by ([`filter_reach`] of the
/// filter at `dt`; 0 unfiltered): added to the overlap of blocks so that
/// every kept sample's mask sees all the rates it depends on.
fn reach_of(p: &ProcessOptions, dt: f64, tol: f64) -> Result<usize, PipelineError> {
    let Bandwidth::Fixed(spec) = p.filter else {
        return Ok(0);
    };
    let sos = Butterworth::lowpass(spec.order, spec.cutoff_hz, 1.0 / dt)
        .map_err(|e| sig("designing the regressor filter", e))?;
    // A record long enough for the impulse response to end inside it.
    let n = 2 * overlap(p, dt, 1e-12)? + 1;
    filter_reach(&sos, n, false, tol).map_err(PipelineError::from)
}

/// The period averaging of a log being read: [`aras_signal::PeriodSums`]
/// over θ, τ (and the logged derivatives), plus the times of the first
/// block for the averaged log.
struct PeriodSums {
    sums: aras_signal::PeriodSums,
    logged: bool,
    seen: usize,
    t0: Vec<f64>,
    dt: f64,
    period_s: f64,
}

impl PeriodSums {
    fn new(
        period_s: f64,
        dt: f64,
        p: &ProcessOptions,
        logged: bool,
    ) -> Result<Self, PipelineError> {
        let channels = if logged { 8 } else { 4 };
        let sums = aras_signal::PeriodSums::new(channels, dt, period_s, p.settling_s, None)
            .map_err(|source| IdentError::External {
                context: "period averaging while reading".into(),
                source: Box::new(source),
            })?;
        Ok(Self {
            t0: Vec::with_capacity(sums.largest_block()),
            sums,
            logged,
            seen: 0,
            dt,
            period_s,
        })
    }

    fn add(&mut self, c: &Columns) {
        let mut row = [0.0; 8];
        let width = self.sums.channels();
        for i in 0..c.len() {
            if self.seen + i >= self.sums.start() && self.t0.len() < self.sums.largest_block() {
                self.t0.push(c.t[i]);
            }
            row[..4].copy_from_slice(&[c.theta[0][i], c.theta[1][i], c.tau[0][i], c.tau[1][i]]);
            if self.logged {
                row[4..].copy_from_slice(&[
                    c.theta_dot[0][i],
                    c.theta_dot[1][i],
                    c.theta_ddot[0][i],
                    c.theta_ddot[1][i],
                ]);
            }
            self.sums.push(&row[..width]);
        }
        self.seen += c.len();
    }

    /// The averaged block as a log of one block (an incomplete last block
    /// is dropped, as in memory), and the periods averaged.
    fn finish(
        self,
        name: &str,
        rows: usize,
        sidecar: Sidecar,
    ) -> Result<(Log, usize), PipelineError> {
        let mean = self.sums.finish().map_err(|source| IdentError::External {
            context: format!(
                "period averaging of {name} ({rows} rows, period {} s)",
                self.period_s
            ),
            source: Box::new(source),
        })?;
        let periods = mean.blocks * mean.periods_per_block;
        let mut ch = mean.channels.into_iter();
        let mut next = || ch.next().unwrap_or_default();
        let (th0, th1, tau0, tau1) = (next(), next(), next(), next());
        let (theta_dot, theta_ddot) = if self.logged {
            let (a, b, c, d) = (next(), next(), next(), next());
            (vec![a, b], vec![c, d])
        } else {
            (vec![Vec::new(); 2], vec![Vec::new(); 2])
        };
        let mut t = self.t0;
        t.truncate(mean.samples_per_block);
        let cols = Columns {
            t,
            theta: vec![th0, th1],
            tau: vec![tau0, tau1],
            theta_dot,
            theta_ddot,
        };
        Ok((block_log(name, &cols, self.dt, sidecar), periods))
    }
}
