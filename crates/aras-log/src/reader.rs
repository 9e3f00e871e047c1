//! The streaming CSV reader: rows are parsed, converted to SI and checked in
//! chunks, so arbitrarily long logs can be consumed in bounded memory.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use serde::Serialize;

use super::ReadOptions;
use super::TimeUnit;
use super::checks::{Checks, StepDeviation, Warning};
use super::header::{AngleSource, Field, Layout, Role, TorqueSource, slots};
use super::sidecar::Sidecar;
use crate::error::LogError;
use crate::table::CsvTable;

/// Rows of a log in SI units, structure-of-arrays.
///
/// Filled by [`LogReader::read_rows`], which appends and gives every
/// channel group one column per joint; the columns of `theta_dot` and
/// `theta_ddot` stay empty when the log has no such columns.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Columns {
    /// Time (s).
    pub t: Vec<f64>,
    /// Joint angles θ1 … θn (rad), one column per joint.
    pub theta: Vec<Vec<f64>>,
    /// Joint torques τ1 … τn (N·m).
    pub tau: Vec<Vec<f64>>,
    /// Logged joint rates (rad/s), if the log has `dtheta1 … dthetaN`.
    pub theta_dot: Vec<Vec<f64>>,
    /// Logged joint accelerations (rad/s²), if the log has
    /// `ddtheta1 … ddthetaN`.
    pub theta_ddot: Vec<Vec<f64>>,
}

impl Columns {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True if there are no rows.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Number of joints (angle channels).
    pub fn joints(&self) -> usize {
        self.theta.len()
    }

    /// Gives every channel group `joints` columns (new ones empty, extra
    /// ones dropped), as [`LogReader::read_rows`] does before appending.
    pub fn resize_joints(&mut self, joints: usize) {
        for g in [
            &mut self.theta,
            &mut self.tau,
            &mut self.theta_dot,
            &mut self.theta_ddot,
        ] {
            g.resize_with(joints, Vec::new);
        }
    }

    /// Removes all rows, keeping the allocations.
    pub fn clear(&mut self) {
        self.t.clear();
        for v in self
            .theta
            .iter_mut()
            .chain(self.tau.iter_mut())
            .chain(self.theta_dot.iter_mut())
            .chain(self.theta_ddot.iter_mut())
        {
            v.clear();
        }
    }
}

/// The time base of a log as read.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Timing {
    /// Seconds per unit of the `t` column.
    pub unit_s: f64,
    /// The first time stamp (s) subtracted from every row (a clock epoch,
    /// [`EPOCH_OFFSET_S`](crate::EPOCH_OFFSET_S)), 0 if none.
    pub offset_s: f64,
    /// RMS deviation of the steps from the nominal step (or a whole
    /// multiple of it, across gaps) (s).
    pub jitter_rms_s: f64,
    /// Largest such deviation (s).
    pub jitter_max_s: f64,
}

/// The file line of each data row (comments and blank lines between rows
/// make them differ from `row + header line + 1`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowLines {
    /// `(row, line)` where a row does not follow its predecessor's line.
    breaks: Vec<(usize, u64)>,
}

impl RowLines {
    /// Records that row `row` is on line `line` (rows in order).
    pub fn push(&mut self, row: usize, line: u64) {
        if let Some(&(r, l)) = self.breaks.last()
            && l + (row - r) as u64 == line
        {
            return;
        }
        self.breaks.push((row, line));
    }

    /// The file line of `row`, if known (not for resampled rows).
    pub fn line(&self, row: usize) -> Option<u64> {
        let i = self.breaks.partition_point(|b| b.0 <= row);
        let (r, l) = *self.breaks.get(i.checked_sub(1)?)?;
        Some(l + (row - r) as u64)
    }

    /// The lines of the rows kept by `keep` (in order), renumbered.
    pub fn filtered(&self, keep: impl Iterator<Item = usize>) -> Self {
        let mut out = Self::default();
        for (new, old) in keep.enumerate() {
            if let Some(l) = self.line(old) {
                out.push(new, l);
            }
        }
        out
    }
}

/// What the reader learnt about the whole log, available once it is read.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LogSummary {
    /// Display name of the log.
    pub file: String,
    /// Data rows.
    pub rows: usize,
    /// Nominal sample step (s): the median of the first
    /// [`NOMINAL_WINDOW`](crate::NOMINAL_WINDOW) steps, or
    /// [`ReadOptions::nominal_step`] if given.
    pub nominal_step_s: f64,
    /// `1 / nominal_step_s` (Hz).
    pub sample_rate_hz: f64,
    /// Last time minus first time (s).
    pub duration_s: f64,
    /// The step furthest from the nominal one (within tolerance, or reading
    /// would have failed).
    pub worst_step: Option<StepDeviation>,
    /// `"theta columns (rad)"` or `"encoder counts"`.
    pub angle_source: String,
    /// `"tau columns (N·m)"` or `"motor currents"`.
    pub torque_source: String,
    /// `[min, max]` of each joint angle θ1 … θn (rad).
    pub theta_range: Vec<[f64; 2]>,
    /// `[min, max]` of each joint torque τ1 … τn (N·m).
    pub tau_range: Vec<[f64; 2]>,
    /// Where the sidecar came from, if any.
    pub sidecar: Option<String>,
    /// Time unit, epoch offset and jitter.
    pub timing: Timing,
    /// File line of each row.
    #[serde(skip)]
    pub lines: RowLines,
    /// 1-based file columns of the fields θ1 … θn, then τ1 … τn come from
    /// (0 if unknown).
    #[serde(skip)]
    pub channel_columns: Vec<usize>,
}

/// Summary, notes and warnings from [`LogReader::finish`].
#[derive(Debug, Clone, PartialEq)]
pub struct LogReport {
    /// What was read.
    pub summary: LogSummary,
    /// Informational notes (ignored columns, data sources).
    pub notes: Vec<String>,
    /// Warnings (saturation).
    pub warnings: Vec<Warning>,
}

/// Where the rows come from: CSV text, or a ROS 2 bag decoded on opening.
enum Source<R> {
    Csv(CsvTable<R>),
    Bag { rows: Columns, next: usize },
}

/// Streaming reader of one log.
///
/// ```no_run
/// use aras_log::{Columns, LogReader, ReadOptions};
/// # fn main() -> Result<(), aras_log::LogError> {
/// let mut reader = LogReader::open("run.csv".as_ref(), &ReadOptions::default())?;
/// let mut chunk = Columns::default();
/// while reader.read_rows(&mut chunk, 65_536)? > 0 {
///     // ... use chunk.t, chunk.theta, chunk.tau ...
///     chunk.clear();
/// }
/// let report = reader.finish()?; // end-of-log checks: sampling, degrees, saturation
/// # Ok(()) }
/// ```
///
/// Per-row defects (bad numbers, time going backwards) are reported by
/// [`read_rows`](Self::read_rows) at the row; defects that need the whole
/// log (irregular sampling against the nominal step, degrees, too few rows,
/// saturation warnings) by [`finish`](Self::finish).
pub struct LogReader<R> {
    source: Source<R>,
    name: String,
    layout: Layout,
    sidecar: Sidecar,
    sidecar_name: Option<String>,
    checks: Checks,
    opts: ReadOptions,
    done: bool,
    unit_s: f64,
    offset: Option<f64>,
    lines_of_rows: RowLines,
    offset_warning: Option<Warning>,
    /// One parsed row, and its angles and torques in SI (reused).
    row: Row,
}

/// Scratch of one row, allocated once per reader, with where each joint's
/// values are in it (resolved once from the layout, not per row).
#[derive(Debug, Clone, Default)]
struct Row {
    vals: Vec<f64>,
    theta: Vec<f64>,
    tau: Vec<f64>,
    /// Per joint: the slot of its angle field and the factor to radians
    /// ([`AngleSource::field`]).
    angle: Vec<(usize, f64)>,
    /// Per joint: the slot of its torque field and the factor to N·m.
    torque: Vec<(usize, f64)>,
    /// Per joint: the slots of `dthetaJ` and `ddthetaJ`.
    rates: Vec<(usize, usize)>,
}

impl Row {
    fn new(layout: &Layout) -> Self {
        let n = layout.joints;
        let slot = |role: Role, j: usize| Field::Joint(role, j).slot(n);
        let at = |(f, k): (Field, f64)| (f.slot(n), k);
        let angle = (0..n).map(|j| at(layout.angles.field(j))).collect();
        let torque = (0..n).map(|j| at(layout.torques.field(j))).collect();
        Self {
            vals: vec![0.0; slots(n)],
            theta: vec![0.0; n],
            tau: vec![0.0; n],
            angle,
            torque,
            rates: (0..n)
                .map(|j| (slot(Role::Dtheta, j), slot(Role::Ddtheta, j)))
                .collect(),
        }
    }
}

impl LogReader<File> {
    /// Opens a log file: a CSV, or a ROS 2 bag ([`is_bag`](crate::is_bag):
    /// extension `.mcap` or the MCAP magic bytes), whose topic is decoded
    /// into memory here and then served in chunks like a CSV's rows. With
    /// [`SidecarSource::Auto`](crate::SidecarSource::Auto) the sidecar is
    /// the file of the same name with extension `.json`, if it exists and
    /// declares the format ([`find_sidecar`](crate::find_sidecar)).
    pub fn open(path: &Path, opts: &ReadOptions) -> Result<Self, LogError> {
        let name = path.display().to_string();
        let found = crate::find_sidecar(Some(path), &opts.sidecar)?;
        if crate::is_bag(path) {
            return Self::open_bag(path, name, opts, found);
        }
        if !opts.bag.is_default() {
            return Err(LogError::InvalidOption {
                name: "bag",
                value: format!("{:?}", opts.bag),
                reason: format!(
                    "{name} is a CSV log: --topic, --joints and --stamps apply to ROS 2 bags \
                     (.mcap) only; name a CSV's columns with --columns"
                ),
            });
        }
        let file = File::open(path).map_err(|source| LogError::Io {
            file: name.clone(),
            source,
        })?;
        Self::with_sidecar(file, name, opts, found)
    }

    #[cfg(feature = "bags")]
    fn open_bag(
        path: &Path,
        name: String,
        opts: &ReadOptions,
        found: crate::FoundSidecar,
    ) -> Result<Self, LogError> {
        if opts.columns != Default::default() {
            return Err(LogError::InvalidOption {
                name: "columns",
                value: format!("{:?}", opts.columns),
                reason: format!(
                    "{name} is a ROS 2 bag: its joints are mapped by name with --joints \
                     theta1=JOINT,theta2=JOINT,…, not with --columns"
                ),
            });
        }
        let bytes = std::fs::read(path).map_err(|source| LogError::Io {
            file: name.clone(),
            source,
        })?;
        let bag = crate::bag::read(&bytes, &name, &opts.bag, opts.joints)?;
        drop(bytes);
        let joints = bag.cols.joints();
        let mut roles = vec![Role::Theta, Role::Tau];
        if bag.has_velocity {
            roles.push(Role::Dtheta);
        }
        let mut header = String::from("t");
        for role in roles {
            for j in 0..joints {
                header.push(',');
                header.push_str(&Field::Joint(role, j).name());
            }
        }
        let opts = &crate::ReadOptions {
            joints: Some(joints),
            ..opts.clone()
        };
        // Messages are numbered on their topic: the "line" of a row.
        let label = format!("{name}#{}", bag.topic);
        let r = LogReader::with_sidecar(header.as_bytes(), label, opts, found)?;
        let mut layout = r.layout;
        layout.notes.splice(0..0, bag.notes);
        Ok(LogReader {
            source: Source::Bag {
                rows: bag.cols,
                next: 0,
            },
            name: r.name,
            layout,
            sidecar: r.sidecar,
            sidecar_name: r.sidecar_name,
            checks: r.checks,
            opts: r.opts,
            done: false,
            // Bag times are already seconds from the first message.
            unit_s: 1.0,
            offset: None,
            lines_of_rows: r.lines_of_rows,
            offset_warning: None,
            row: r.row,
        })
    }

    #[cfg(not(feature = "bags"))]
    fn open_bag(
        _path: &Path,
        name: String,
        _opts: &ReadOptions,
        _found: crate::FoundSidecar,
    ) -> Result<Self, LogError> {
        Err(LogError::Bag {
            file: name,
            reason: "this build of aras-log reads no bags (feature `bags` is off)".into(),
        })
    }
}

impl<R: Read> LogReader<R> {
    /// Reader over any byte source; `name` labels messages.
    /// [`SidecarSource::Auto`](crate::SidecarSource::Auto) means no sidecar here (there is no path to
    /// look next to).
    pub fn new(src: R, name: &str, opts: &ReadOptions) -> Result<Self, LogError> {
        let found = crate::find_sidecar(None, &opts.sidecar)?;
        Self::with_sidecar(src, name.to_string(), opts, found)
    }

    fn with_sidecar(
        src: R,
        name: String,
        opts: &ReadOptions,
        found: crate::FoundSidecar,
    ) -> Result<Self, LogError> {
        opts.validate()?;
        opts.sensors.validate("ReadOptions::sensors")?;
        let crate::FoundSidecar {
            mut sidecar,
            name: sidecar_name,
            note: sidecar_note,
        } = found;
        let mut timing_note = None;
        match (sidecar.torques, opts.torques) {
            (Some(stated), Some(given)) if stated != given => {
                return Err(LogError::TorqueTimingConflict {
                    log: name,
                    sidecar: sidecar_name.unwrap_or_default(),
                    stated,
                    given,
                });
            }
            (None, Some(given)) => {
                sidecar.torques = Some(given);
                timing_note = Some(format!("torques taken as {given} (from the options)"));
            }
            _ => {}
        }
        let sensors = sidecar.sensors.overridden_by(&opts.sensors);
        let table = CsvTable::new(src, &name)?;
        let where_sidecar = sidecar_name
            .clone()
            .unwrap_or_else(|| "(none found: LOG.json next to LOG.csv)".into());
        let layout = Layout::parse(
            table.names(),
            &name,
            table.header_line(),
            &sensors,
            &where_sidecar,
            &opts.columns,
            opts.joints,
        )?;
        let mut notes = layout.notes.clone();
        notes.extend(sidecar_note);
        if opts.sensors != Default::default() {
            notes.push("sensor constants from ReadOptions override the sidecar".into());
        }
        notes.extend(timing_note);
        let checks = Checks::new(opts.nominal_step, opts.saturation_samples, layout.joints);
        let row = Row::new(&layout);
        let mut layout = layout;
        layout.notes = notes;
        Ok(Self {
            source: Source::Csv(table),
            name,
            layout,
            sidecar,
            sidecar_name,
            checks,
            opts: opts.clone(),
            done: false,
            unit_s: opts.time_unit.map_or(1.0, TimeUnit::seconds),
            offset: None,
            lines_of_rows: RowLines::default(),
            offset_warning: None,
            row,
        })
    }

    /// The log's display name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The sidecar (default if none); its `torques` is the log's torque
    /// timing, from the file or, when the file does not state it, from
    /// [`ReadOptions::torques`].
    pub fn sidecar(&self) -> &Sidecar {
        &self.sidecar
    }

    /// How the logged torques relate to the sample times (as
    /// [`Log::torque_timing`](crate::Log::torque_timing)).
    pub fn torque_timing(&self) -> crate::TorqueTiming {
        self.sidecar.torques.unwrap_or_default()
    }

    /// Column names of the header, trimmed and lower-cased, in file order.
    pub fn columns(&self) -> &[String] {
        &self.layout.names
    }

    /// Number of joints of the log.
    pub fn joints(&self) -> usize {
        self.layout.joints
    }

    /// True if the log has `dtheta1 … dthetaN`.
    pub fn has_velocity(&self) -> bool {
        self.layout.has_velocity
    }

    /// True if the log has `ddtheta1 … ddthetaN`.
    pub fn has_acceleration(&self) -> bool {
        self.layout.has_acceleration
    }

    /// Notes so far (ignored columns, data sources).
    pub fn notes(&self) -> &[String] {
        &self.layout.notes
    }

    /// Appends up to `max_rows` rows to `out`; returns how many (0 at the
    /// end of the log). Stops at the first defective row with its error.
    pub fn read_rows(&mut self, out: &mut Columns, max_rows: usize) -> Result<usize, LogError> {
        let Source::Csv(table) = &mut self.source else {
            return self.read_bag_rows(out, max_rows);
        };
        let mut count = 0;
        let n = self.layout.joints;
        out.resize_joints(n);
        let row = &mut self.row;
        while count < max_rows && !self.done {
            let Some(line) = table.next_row(&self.layout.row_columns, &mut row.vals)? else {
                self.done = true;
                break;
            };
            let vals = &row.vals;
            let raw_t = vals[0];
            // A clock epoch: subtract the first stamp in the file's own unit
            // (exact for stamps within a factor of 2 of it, Sterbenz).
            let offset = *self.offset.get_or_insert_with(|| {
                if (raw_t * self.unit_s).abs() >= crate::EPOCH_OFFSET_S {
                    raw_t
                } else {
                    0.0
                }
            });
            let t = if offset == 0.0 {
                raw_t * self.unit_s
            } else {
                if self.offset_warning.is_none() {
                    let ulp = f64::from_bits(raw_t.abs().to_bits() + 1) - raw_t.abs();
                    self.offset_warning = Some(Warning::TimeOffset {
                        offset_s: raw_t * self.unit_s,
                        resolution_s: ulp * self.unit_s,
                    });
                }
                (raw_t - offset) * self.unit_s
            };
            for (theta, &(s, k)) in row.theta.iter_mut().zip(&row.angle) {
                *theta = vals[s] * k;
            }
            for (tau, &(s, k)) in row.tau.iter_mut().zip(&row.torque) {
                *tau = vals[s] * k;
            }
            self.checks.row(
                &self.name,
                line,
                self.layout.column(Field::T),
                t,
                &row.theta,
                &row.tau,
            )?;
            self.lines_of_rows.push(self.checks.rows - 1, line);
            out.t.push(t);
            for j in 0..n {
                out.theta[j].push(row.theta[j]);
                out.tau[j].push(row.tau[j]);
                let (v, a) = row.rates[j];
                if self.layout.has_velocity {
                    out.theta_dot[j].push(vals[v]);
                }
                if self.layout.has_acceleration {
                    out.theta_ddot[j].push(vals[a]);
                }
            }
            count += 1;
        }
        Ok(count)
    }

    /// [`read_rows`](Self::read_rows) of a bag's decoded rows: a row's
    /// "line" is its message's number on the topic.
    fn read_bag_rows(&mut self, out: &mut Columns, max_rows: usize) -> Result<usize, LogError> {
        let Source::Bag { rows, next } = &mut self.source else {
            return Ok(0);
        };
        let start = *next;
        let end = rows.len().min(start.saturating_add(max_rows));
        let n = self.layout.joints;
        out.resize_joints(n);
        let row = &mut self.row;
        for i in start..end {
            for j in 0..n {
                row.theta[j] = rows.theta[j][i];
                row.tau[j] = rows.tau[j][i];
            }
            self.checks
                .row(&self.name, i as u64 + 1, 1, rows.t[i], &row.theta, &row.tau)?;
            out.t.push(rows.t[i]);
            for j in 0..n {
                out.theta[j].push(row.theta[j]);
                out.tau[j].push(row.tau[j]);
                if self.layout.has_velocity {
                    out.theta_dot[j].push(rows.theta_dot[j][i]);
                }
            }
            *next = i + 1;
        }
        if *next == rows.len() {
            self.done = true;
        }
        Ok(end - start)
    }

    /// Runs the end-of-log checks (reading any rows not yet read, without
    /// keeping them) and returns the summary, notes and warnings.
    pub fn finish(mut self) -> Result<LogReport, LogError> {
        let mut sink = Columns::default();
        while self.read_rows(&mut sink, 65_536)? > 0 {
            sink.clear();
        }
        let check_degrees = self.opts.check_degrees && self.layout.angles == AngleSource::Theta;
        let rows = self.checks.rows;
        let res = self.checks.finish(
            &self.name,
            self.opts.min_rows,
            self.opts.step_tolerance,
            check_degrees,
            self.opts.time_unit.is_some(),
            self.opts.nominal_step.is_some(),
        )?;
        let channel_columns = self.layout.channel_columns();
        let mut warnings = res.warnings;
        if let Some(w) = self.offset_warning.take() {
            warnings.insert(0, w);
        }
        let summary = LogSummary {
            file: self.name.clone(),
            rows,
            nominal_step_s: res.nominal_step,
            sample_rate_hz: 1.0 / res.nominal_step,
            duration_s: res.duration,
            worst_step: res.worst_step,
            angle_source: match self.layout.angles {
                AngleSource::Theta => "theta columns (rad)".into(),
                AngleSource::Encoder { .. } => "encoder counts".into(),
            },
            torque_source: match self.layout.torques {
                TorqueSource::Tau => "tau columns (N·m)".into(),
                TorqueSource::Current { .. } => "motor currents".into(),
            },
            theta_range: res.theta_range,
            tau_range: res.tau_range,
            sidecar: self.sidecar_name.clone(),
            timing: Timing {
                unit_s: self.unit_s,
                offset_s: self.offset.unwrap_or(0.0) * self.unit_s,
                jitter_rms_s: res.jitter_rms,
                jitter_max_s: res.jitter_max,
            },
            lines: self.lines_of_rows,
            channel_columns,
        };
        Ok(LogReport {
            summary,
            notes: self.layout.notes,
            warnings,
        })
    }
}
