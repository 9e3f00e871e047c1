//! The `aras-log/1` log format (`docs/log-format.md`): a CSV of time, joint
//! angles and torques (or encoder counts and motor currents, as in the
//! paper's experiment), optional logged derivatives, and an optional JSON
//! sidecar with sensor constants and the excitation period. Its one reader
//! (whole-file [`read_log`], streaming [`LogReader`]) and its one writer
//! ([`write_log`]). The reader also takes a ROS 2 bag (an MCAP file, known
//! by [`is_bag`]): the `sensor_msgs/msg/JointState` messages of one topic
//! become the log's rows ([`BagOptions`]: topic, joint names, stamps).
//!
//! A JSON file beside the log is its sidecar only if it declares the format
//! (`"format": "aras-log/1"`, [`find_sidecar`]): a lab's own `run.json`
//! beside `run.csv` is left alone, with a note.
//!
//! The reader validates everything a log can get wrong: every defect is a
//! [`LogError`] naming file, line, column and value, with the fix. No robot
//! is assumed: a log is the signals of its joints, as many as its header
//! names (`theta1 … thetaN`).
//!
//! # Dependencies
//!
//! * `serde`, `serde_json`: the sidecar and the serialisable summaries.
//! * `thiserror`: the error enum.
//! * `mcap` (feature `bags`, on by default): Foxglove's reference reader of
//!   the MCAP container that `ros2 bag record` writes (chunks, zstd and lz4
//!   compression, channels, schemas). The `JointState` messages inside are
//!   CDR-encoded; that fixed layout is decoded here (a few dozen lines),
//!   which names the message and field of any defect.
//!
//! The CSV is parsed by a small purpose-built scanner rather than the `csv`
//! crate: the format is plain numeric, and the scanner gives exact line and
//! column positions and reads an hour at 1 kHz in a fraction of a second.
//! It is public as [`CsvTable`] for other numeric CSV formats (one joint's
//! friction log), so that every CSV of the workspace is read by one set of
//! rules with one set of messages.

#![warn(missing_docs)]

mod bag;
mod checks;
mod error;
mod glitch;
mod header;
mod number;
mod reader;
mod sidecar;
mod table;
pub mod units;
mod writer;

use std::io::Read;
use std::path::{Path, PathBuf};

#[cfg(feature = "bags")]
pub use bag::read_bag_joint;
pub use bag::{BagOptions, JOINT_STATE, JointNames, JointSamples, MCAP_MAGIC, Stamps, is_bag};
pub use checks::{
    Extreme, JITTER_WARN, MIN_PLAUSIBLE_RATE_HZ, NOMINAL_WINDOW, Span, StepDeviation, Warning,
};
pub use error::LogError;
pub use glitch::{
    ANGLE_FLOOR, DEFAULT_GLITCH_THRESHOLD, Glitch, GlitchAction, GlitchKind, GlitchOptions,
    TORQUE_FLOOR, apply_glitches, find_glitches,
};
pub use header::ColumnNames;
pub use reader::{Columns, LogReader, LogReport, LogSummary, RowLines, Timing};
pub use sidecar::{Excitation, FORMAT, FoundSidecar, Sensors, Sidecar, TorqueTiming, find_sidecar};
pub use table::{CsvTable, MAX_MAGNITUDE, RowColumns};
pub use writer::{new_temp_file, sidecar_path, write_atomic, write_log};

/// Where to find the JSON sidecar.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum SidecarSource {
    /// `LOG.json` next to `LOG.csv` if it exists (for [`read_log`]); none
    /// when reading from a stream.
    #[default]
    Auto,
    /// No sidecar.
    None,
    /// This file (an error if it cannot be read).
    Path(PathBuf),
    /// This JSON text, labelled `name` in messages (tests, fuzzing, stdin).
    Text {
        /// Display name.
        name: String,
        /// The JSON.
        json: String,
    },
}

/// Time stamps at or beyond this magnitude (s) are taken as a clock epoch:
/// the first one is subtracted from every row ([`Warning::TimeOffset`]).
pub const EPOCH_OFFSET_S: f64 = 1e6;

/// The unit of the `t` column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TimeUnit {
    /// Seconds.
    #[serde(rename = "s")]
    Seconds,
    /// Milliseconds.
    #[serde(rename = "ms")]
    Milliseconds,
    /// Microseconds.
    #[serde(rename = "us")]
    Microseconds,
    /// Nanoseconds.
    #[serde(rename = "ns")]
    Nanoseconds,
}

impl TimeUnit {
    /// Seconds per unit.
    pub fn seconds(self) -> f64 {
        match self {
            Self::Seconds => 1.0,
            Self::Milliseconds => 1e-3,
            Self::Microseconds => 1e-6,
            Self::Nanoseconds => 1e-9,
        }
    }

    /// The short name (`s`, `ms`, `us`, `ns`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Seconds => "s",
            Self::Milliseconds => "ms",
            Self::Microseconds => "us",
            Self::Nanoseconds => "ns",
        }
    }
}

/// Options of the log reader. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadOptions {
    /// Sidecar location (default [`SidecarSource::Auto`]).
    pub sidecar: SidecarSource,
    /// Number of joints the log must have (default `None`: as many as the
    /// header's highest joint number, `theta3` → 3). With `Some(n)`,
    /// columns of joints beyond `n` are ignored (with a note) and a log
    /// with fewer is refused: a robot's tool states its joint count.
    pub joints: Option<usize>,
    /// Sensor constants that override the sidecar's (the command line).
    pub sensors: Sensors,
    /// Fewest data rows accepted (default 16; at least 2).
    pub min_rows: usize,
    /// Largest accepted relative deviation of any time step from the
    /// nominal step, `|step/nominal − 1|` (default 0.5: jitter is accepted,
    /// a dropped sample, a ratio of 2, is not). The nominal step is
    /// [`nominal_step`](Self::nominal_step) if given, else the median of the
    /// first [`NOMINAL_WINDOW`] steps.
    pub step_tolerance: f64,
    /// Known sample step (s), if any.
    pub nominal_step: Option<f64>,
    /// Consecutive samples flat at a torque extreme that count as
    /// saturation (default 50).
    pub saturation_samples: usize,
    /// Reject angle columns that look like degrees (default true).
    pub check_degrees: bool,
    /// The lab's own column names (default: the standard names; CSV logs
    /// only).
    pub columns: ColumnNames,
    /// How a ROS 2 bag is read (topic, joints, stamps; bags only).
    pub bag: BagOptions,
    /// Unit of `t` (default `None`: seconds, and a log whose step is a
    /// whole number at a rate below [`MIN_PLAUSIBLE_RATE_HZ`] is refused
    /// with [`LogError::TimeUnit`]; `Some(TimeUnit::Seconds)` accepts it).
    pub time_unit: Option<TimeUnit>,
    /// How the logged torques relate to the sample times when the sidecar
    /// does not say (default `None`: as the sidecar's `torques` states, else
    /// [`TorqueTiming::Sampled`]). A value that contradicts the sidecar's
    /// statement is refused ([`LogError::TorqueTimingConflict`]).
    pub torques: Option<TorqueTiming>,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            sidecar: SidecarSource::Auto,
            joints: None,
            sensors: Sensors::default(),
            min_rows: 16,
            step_tolerance: 0.5,
            nominal_step: None,
            saturation_samples: 50,
            check_degrees: true,
            columns: ColumnNames::default(),
            bag: BagOptions::default(),
            time_unit: None,
            torques: None,
        }
    }
}

impl ReadOptions {
    fn validate(&self) -> Result<(), LogError> {
        let bad = |name, value: String, reason: &str| LogError::InvalidOption {
            name,
            value,
            reason: reason.into(),
        };
        if self.joints == Some(0) {
            return Err(bad(
                "joints",
                "0".into(),
                "a log has at least one joint: give the robot's joint count, or none",
            ));
        }
        if self.min_rows < 2 {
            return Err(bad(
                "min_rows",
                self.min_rows.to_string(),
                "at least 2 rows are needed",
            ));
        }
        if !(self.step_tolerance.is_finite() && self.step_tolerance > 0.0) {
            return Err(bad(
                "step_tolerance",
                self.step_tolerance.to_string(),
                "give a positive relative tolerance such as 0.5",
            ));
        }
        if let Some(s) = self.nominal_step
            && !(s.is_finite() && s > 0.0)
        {
            return Err(bad(
                "nominal_step",
                s.to_string(),
                "give a positive step in seconds",
            ));
        }
        if self.saturation_samples < 2 {
            return Err(bad(
                "saturation_samples",
                self.saturation_samples.to_string(),
                "at least 2 samples make a flat run",
            ));
        }
        Ok(())
    }
}

/// A whole log in memory, in SI units, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// Display name (the path for [`read_log`]).
    pub name: String,
    /// Time (s), strictly increasing, nearly uniform.
    pub t: Vec<f64>,
    /// Joint angles (rad), one column per joint.
    pub theta: Vec<Vec<f64>>,
    /// Joint torques (N·m), one column per joint.
    pub tau: Vec<Vec<f64>>,
    /// Logged joint rates (rad/s), if present.
    pub theta_dot: Option<Vec<Vec<f64>>>,
    /// Logged joint accelerations (rad/s²), if present.
    pub theta_ddot: Option<Vec<Vec<f64>>>,
    /// The sidecar (default if none); its `torques` is the log's torque
    /// timing, from the file or, when the file does not state it, from
    /// [`ReadOptions::torques`].
    pub sidecar: Sidecar,
    /// What was read.
    pub summary: LogSummary,
    /// Informational notes (ignored columns, data sources).
    pub notes: Vec<String>,
    /// Warnings (saturation).
    pub warnings: Vec<Warning>,
}

impl Log {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True if there are no samples (never, for a log that was read).
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Number of joints (angle channels).
    pub fn joints(&self) -> usize {
        self.theta.len()
    }

    /// How the logged torques relate to the sample times: the sidecar's
    /// `torques`, else the reader's [`ReadOptions::torques`] (the reader
    /// records it in [`Log::sidecar`]), else [`TorqueTiming::Sampled`]
    /// (a ROS 2 bag's efforts are measurements).
    pub fn torque_timing(&self) -> TorqueTiming {
        self.sidecar.torques.unwrap_or_default()
    }
}

/// Reads and validates a whole log file (sidecar per `opts.sidecar`).
pub fn read_log(path: &Path, opts: &ReadOptions) -> Result<Log, LogError> {
    collect(LogReader::open(path, opts)?)
}

/// Reads and validates a whole log from any byte stream; `name` labels
/// messages.
pub fn read_log_from<R: Read>(src: R, name: &str, opts: &ReadOptions) -> Result<Log, LogError> {
    collect(LogReader::new(src, name, opts)?)
}

fn collect<R: Read>(mut reader: LogReader<R>) -> Result<Log, LogError> {
    let mut cols = Columns::default();
    reader.read_rows(&mut cols, usize::MAX)?;
    cols.resize_joints(reader.joints());
    let sidecar = reader.sidecar().clone();
    let (vel, acc) = (reader.has_velocity(), reader.has_acceleration());
    let report = reader.finish()?;
    let Columns {
        t,
        theta,
        tau,
        theta_dot,
        theta_ddot,
    } = cols;
    Ok(Log {
        name: report.summary.file.clone(),
        t,
        theta,
        tau,
        theta_dot: vel.then_some(theta_dot),
        theta_ddot: acc.then_some(theta_ddot),
        sidecar,
        summary: report.summary,
        notes: report.notes,
        warnings: report.warnings,
    })
}
