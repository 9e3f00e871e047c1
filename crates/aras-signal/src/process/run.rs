//! One run of [`process_in`](super::process_in): what its stages share
//! ([`Run`]) and the stages in the module docs' order, each composed of the
//! steps in [`stages`](super::stages): (0–1) the uniform grid and its
//! period average, (2–3) the bandwidth and the derivatives, then the output
//! rows, the band they passed and the account of the choice.

use aras_log::{Log, Warning};

use super::stages::{self, BandChoice, PeriodChoice, Record};
use super::{
    BandInputs, Bandwidth, BandwidthChoice, FilterSummary, OUTLIER_BLOCK, OutputRows, Pair,
    ProcessOptions, RowMap, Samples, band_of, check_logged_derivatives, describe,
    reject_outlier_blocks, samples_from, shift_motion,
};
use crate::BandLimit;
use crate::bandwidth::{HarmonicSelection, SpectrumCutoff};
use crate::derivative::DerivativeMethod;
use crate::error::ProcessError;
use crate::fourier::Fourier;

/// A checked log and options, and what every stage of the run shares.
pub(super) struct Run<'a> {
    /// The log processed.
    pub log: &'a Log,
    /// The options of the run.
    pub opts: &'a ProcessOptions,
    /// The log's joint count.
    pub joints: usize,
    /// The nominal time step (s).
    pub dt: f64,
    /// The sample rate (Hz).
    pub fs: f64,
    /// The logged rates, when they are used.
    pub logged_vel: Option<&'a Pair>,
    /// The logged accelerations, when the rates are used and they are
    /// logged.
    pub logged_acc: Option<&'a Pair>,
    /// One output sample per row of the log ([`OutputRows::EveryRow`]).
    pub every_row: bool,
    /// Steps the motion is moved later so that it balances the torque held
    /// over each step (`aras_log::TorqueTiming`).
    pub shift: f64,
    /// Notes: the log's, then the run's.
    pub notes: Vec<String>,
    /// Warnings: the log's, then the run's.
    pub warnings: Vec<Warning>,
}

/// Steps 0–1: the record the bandwidth works on, and what became of the
/// grid and the period on the way.
pub(super) struct Periods {
    /// The averaged period block, or the whole uniform grid.
    pub record: Record,
    /// The log's steps were not uniform, so the channels were resampled.
    pub irregular: bool,
    /// Rows of the uniform grid.
    pub grid_rows: usize,
    /// What the resampling did, for the summary.
    pub resampling: Option<String>,
    /// The period used for the average (none when the average was not
    /// made), where it came from, and the detector's account.
    pub used: PeriodChoice,
    /// The grid's angles, kept for the aperiodic remainder of a prediction
    /// on every row.
    pub aperiodic_input: Option<Pair>,
    /// Period blocks left out of the average as outliers.
    pub rejected: usize,
}

/// Steps 2–3: the bandwidth chosen and the motion it yields.
pub(super) struct Smoothed {
    /// The bandwidth chosen (its derivatives taken out into `rates`).
    pub band: BandChoice,
    /// The low-pass applied to θ and τ, if any.
    pub filter: Option<FilterSummary>,
    /// The derivative method used.
    pub method: DerivativeMethod,
    /// θ̇ and θ̈ of the record.
    pub rates: [Pair; 2],
    /// Rows lost at each end of the record by the derivative.
    pub edge: usize,
}

/// The output rows and how they map onto the log's.
pub(super) struct Rows {
    /// The samples, before the model's coordinates are filled.
    pub samples: Samples,
    /// Which output sample stands for each row of the log.
    pub map: RowMap,
    /// Input samples the output does not represent.
    pub dropped: usize,
    /// The spectrum that chose the low-pass of the aperiodic remainder,
    /// when one was added.
    pub aperiodic: Option<SpectrumCutoff>,
}

impl<'a> Run<'a> {
    /// Checks the log against the model's dimension (`expected`, when fixed)
    /// and the options, and settles what the stages share: logged
    /// derivatives (checked against the angles) or none, and the motion's
    /// shift for held torques.
    pub fn new(
        log: &'a Log,
        opts: &'a ProcessOptions,
        expected: Option<usize>,
    ) -> Result<Self, ProcessError> {
        let nj = log.joints();
        if let Some(expected) = expected
            && expected != nj
        {
            return Err(ProcessError::Joints {
                log: log.name.clone(),
                joints: nj,
                expected,
            });
        }
        let dt = log.summary.nominal_step_s;
        let fs = 1.0 / dt;
        let mut notes = log.notes.clone();
        let warnings = log.warnings.clone();
        if !(opts.max_period_spread.is_finite() && opts.max_period_spread > 0.0) {
            return Err(ProcessError::InvalidOption {
                name: "max_period_spread",
                value: opts.max_period_spread.to_string(),
                reason: "give a positive relative RMS such as 0.1".into(),
            });
        }
        let logged_vel = opts
            .use_logged_derivatives
            .then_some(log.theta_dot.as_ref())
            .flatten();
        let logged_acc = logged_vel.and(log.theta_ddot.as_ref());
        if let Some(v) = logged_vel {
            check_logged_derivatives(log, v, logged_acc)?;
        }
        if !opts.use_logged_derivatives && (log.theta_dot.is_some() || log.theta_ddot.is_some()) {
            notes.push(
                "logged derivative columns ignored; θ̇, θ̈ differentiated from θ \
                 (ProcessOptions::use_logged_derivatives)"
                    .into(),
            );
        }
        let every_row = opts.rows == OutputRows::EveryRow;
        // Held torques act over [t_k, t_k+1): the motion estimated from the
        // angles (band-limited, so it averages the steps around t_k)
        // balances τ_k at the hold's midpoint (`aras_log::TorqueTiming`).
        // Logged derivatives are the instantaneous motion at t_k, which the
        // torque held from t_k balances as it is: they are not moved.
        let shift = if logged_vel.is_some() {
            0.0
        } else {
            log.torque_timing().offset_steps()
        };
        Ok(Self {
            log,
            opts,
            joints: nj,
            dt,
            fs,
            logged_vel,
            logged_acc,
            every_row,
            shift,
            notes,
            warnings,
        })
    }

    /// Steps 0–1: a uniform grid, the period (given, from the sidecar, or
    /// detected) and its average. For a prediction on every row, periods
    /// that are outliers (a start-up transient) are left out of the
    /// average, and the angles are kept for what is not periodic, the
    /// aperiodic remainder ([`rows`](Self::rows)).
    pub fn periods(&mut self) -> Result<Periods, ProcessError> {
        let (log, opts, nj) = (self.log, self.opts, self.joints);
        let grid = stages::uniform_grid(log, self.logged_vel, self.logged_acc);
        let (irregular, grid_rows) = (grid.irregular, grid.t.len());
        let choice = stages::choose_period(log, opts, &grid.raw[..nj], self.logged_vel.is_some());
        let mut averaged = stages::average(&grid, &choice, opts, nj, self.dt, &mut self.notes)?;
        let period_used = averaged.as_ref().and(choice.period);
        let aperiodic_input = (self.every_row
            && averaged.is_some()
            && !irregular
            && self.logged_vel.is_none()
            && opts.filter == Bandwidth::Auto)
            .then(|| grid.raw[..nj].to_vec());
        let mut rejected = 0;
        if let (Some(avg), Some(_)) = (&mut averaged, &aperiodic_input) {
            rejected = reject_outlier_blocks(avg, &grid.raw, nj);
        }
        let resampling = grid.resampling.clone();
        let record = stages::record(averaged, grid, choice.period, opts, nj, &mut self.warnings);
        Ok(Periods {
            record,
            irregular,
            grid_rows,
            resampling,
            used: PeriodChoice {
                period: period_used,
                origin: choice.origin.filter(|_| period_used.is_some()),
                detection: choice.detection,
            },
            aperiodic_input,
            rejected,
        })
    }

    /// Steps 2–3: the bandwidth (a harmonic series, a low-pass of θ and τ,
    /// logged rates or none), then the derivatives of the record's angles
    /// unless the bandwidth already gave them.
    pub fn smooth(&self, record: &mut Record) -> Result<Smoothed, ProcessError> {
        let (log, opts, nj) = (self.log, self.opts, self.joints);
        let periodic = record.periods.is_some();
        let n = record.t.len();
        let mut fourier = periodic.then(|| Fourier::new(n));
        let logged = self.logged_vel.is_some();
        let mut band = stages::choose_band(
            record,
            fourier.as_mut(),
            opts,
            logged.then_some(self.logged_acc.is_some()),
            nj,
            self.dt,
        );
        let filter = match band.filter {
            Some(spec) => Some(stages::low_pass(
                spec,
                &mut record.data,
                fourier.as_mut(),
                log,
                nj,
            )?),
            None => None,
        };
        let (method, theta_dot, theta_ddot, edge) = stages::differentiate(
            band.derivatives.take(),
            &record.data[..nj],
            fourier.as_mut(),
            opts.derivative,
            self.dt,
        )?;
        Ok(Smoothed {
            band,
            filter,
            method,
            rates: [theta_dot, theta_ddot],
            edge,
        })
    }

    /// The output rows from the record's angles and their `rates` (`edge`
    /// rows lost at each end): every row of the log evaluated from a
    /// periodic or resampled record ([`at_log_times`](Self::at_log_times),
    /// [`resampled`](Self::resampled)), else the record's own rows
    /// ([`record_rows`](Self::record_rows)).
    pub fn rows(
        &self,
        periods: &Periods,
        rates: [Pair; 2],
        edge: usize,
        harmonics: Option<&[HarmonicSelection]>,
    ) -> Result<Rows, ProcessError> {
        let (record, irregular) = (&periods.record, periods.irregular);
        let periodic = record.periods.is_some();
        let keep = edge..record.t.len() - edge;
        let theta: Pair = record.data[..self.joints]
            .iter()
            .map(|c| c[keep.clone()].to_vec())
            .collect();
        let [theta_dot, theta_ddot] = rates;
        let motion = [theta, theta_dot, theta_ddot];
        if self.every_row && (irregular || periodic) {
            self.at_log_times(periods, motion, edge, harmonics)
        } else if irregular && !periodic {
            Ok(self.resampled(&record.t[keep], motion))
        } else {
            Ok(self.record_rows(record, motion, edge))
        }
    }

    /// Every row of the log from a periodic or resampled record: exact
    /// indices on a uniform grid, cubic Hermite (with the derivatives as
    /// slopes) between grid points; with the aperiodic remainder added when
    /// the angles were kept for it (at most the band of the series'
    /// `harmonics`), and the log's raw torques.
    fn at_log_times(
        &self,
        periods: &Periods,
        motion: [Pair; 3],
        edge: usize,
        harmonics: Option<&[HarmonicSelection]>,
    ) -> Result<Rows, ProcessError> {
        let (log, shift, dt) = (self.log, self.shift, self.dt);
        let (record, irregular) = (&periods.record, periods.irregular);
        let periodic = record.periods.is_some();
        let [theta, theta_dot, theta_ddot] = &motion;
        let mut motion = stages::at_log_times(
            &log.t,
            record.t[edge],
            [theta, theta_dot, theta_ddot],
            dt,
            shift,
            irregular,
            periodic,
        );
        let mut aperiodic = None;
        if let Some(th) = &periods.aperiodic_input {
            aperiodic = Some(stages::add_aperiodic_remainder(
                th,
                &mut motion,
                harmonics,
                log,
            )?);
        }
        let [mut x, mut v, mut a] = motion;
        if !irregular && shift != 0.0 {
            shift_motion(&mut x, &mut v, &mut a, shift, dt, false);
        }
        Ok(Rows {
            samples: samples_from(log.t.clone(), x, v, a, log.tau.clone()),
            map: RowMap::Direct { edge: 0 },
            dropped: 0,
            aperiodic,
        })
    }

    /// Every row of the log again, with its raw torque, from a resampled
    /// aperiodic record (times `t`).
    fn resampled(&self, t: &[f64], motion: [Pair; 3]) -> Rows {
        let log = self.log;
        let [theta, theta_dot, theta_ddot] = &motion;
        let [x, v, a] = stages::resampled_at_log_times(
            t,
            [theta, theta_dot, theta_ddot],
            &log.t,
            self.shift,
            self.dt,
        );
        Rows {
            samples: samples_from(log.t.clone(), x, v, a, log.tau.clone()),
            map: RowMap::Direct { edge: 0 },
            dropped: 0,
            aperiodic: None,
        }
    }

    /// The record's own rows without the `edge` rows the derivative lost at
    /// each end, with its (averaged, filtered) torques, the motion moved to
    /// the hold's midpoint for held torques.
    fn record_rows(&self, record: &Record, motion: [Pair; 3], edge: usize) -> Rows {
        let nj = self.joints;
        let keep = edge..record.t.len() - edge;
        let tau = record.data[nj..2 * nj]
            .iter()
            .map(|c| c[keep.clone()].to_vec())
            .collect();
        let [mut theta, mut theta_dot, mut theta_ddot] = motion;
        if self.shift != 0.0 {
            shift_motion(
                &mut theta,
                &mut theta_dot,
                &mut theta_ddot,
                self.shift,
                self.dt,
                record.periods.is_some(),
            );
        }
        Rows {
            samples: samples_from(
                record.t[keep.clone()].to_vec(),
                theta,
                theta_dot,
                theta_ddot,
                tau,
            ),
            map: match record.map {
                RowMap::Direct { .. } => RowMap::Direct { edge },
                p => p,
            },
            dropped: record.dropped + 2 * edge,
            aperiodic: None,
        }
    }

    /// The operator the angles passed, for whatever is computed from them
    /// ([`band_of`]).
    pub fn band(
        &self,
        periods: &Periods,
        band: &BandChoice,
        rows: &Rows,
    ) -> Result<BandLimit, ProcessError> {
        band_of(BandInputs {
            logged: self.logged_vel.is_some(),
            harmonics: band.harmonics.as_deref(),
            spec_used: band.filter,
            remainder_hz: rows.aperiodic.as_ref().map(|c| c.cutoff_hz),
            periods: periods.record.periods.as_ref(),
            every_row: self.every_row,
            irregular: periods.irregular,
            rows: periods.grid_rows,
            block: periods.record.t.len(),
            fs: self.fs,
        })
        .map_err(|source| ProcessError::Filter {
            context: format!("designing the band-limiting of {}", self.log.name),
            source,
        })
    }

    /// The bandwidth chosen and why ([`describe`]), with what the run did
    /// besides: outlier blocks left out, the aperiodic remainder's
    /// low-pass, the motion moved for held torques.
    pub fn bandwidth(
        &self,
        periods: &Periods,
        band: &BandChoice,
        aperiodic: Option<SpectrumCutoff>,
    ) -> BandwidthChoice {
        let mut bandwidth = describe(
            self.logged_vel.is_some(),
            band,
            &periods.used,
            periods.resampling.clone(),
            self.opts.filter,
        );
        let rejected = periods.rejected;
        if rejected > 0 {
            bandwidth.reason += &format!(
                "; {rejected} period block(s) left out of the average as outliers (θ deviating \
                 more than {OUTLIER_BLOCK}× the median block)"
            );
        }
        if let Some(c) = aperiodic {
            bandwidth.reason += &format!(
                "; the aperiodic remainder (θ − series, e.g. a start-up transient) low-passed \
                 at {:.1} Hz (where its spectrum meets the noise, at most the highest harmonic)",
                c.cutoff_hz
            );
            bandwidth.aperiodic = Some(c);
        }
        if self.shift != 0.0 {
            bandwidth.reason += "; torques held over each step (zero-order hold): the motion is \
                                 evaluated at the hold's midpoint, half a step after each sample";
        }
        bandwidth
    }
}
