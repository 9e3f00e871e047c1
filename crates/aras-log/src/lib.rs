//! The `aras-log/1` log format (`docs/log-format.md`): a CSV of time, joint
//! angles and torques (or encoder counts and motor currents, as in the
//! paper's experiment), optional logged derivatives, and an optional JSON
//! sidecar with sensor constants and the excitation period. Its one reader
//! (whole-file [`read_log`], streaming [`LogReader`]) and its one writer
//! ([`write_log`]).
//!
//! The reader validates everything a log can get wrong: every defect is a
//! [`LogError`] naming file, line, column and value, with the fix. No robot
//! is assumed: a log is two joints' signals.
//!
//! # Dependencies
//!
//! * `serde`, `serde_json`: the sidecar and the serialisable summaries.
//! * `thiserror`: the error enum.
//!
//! The CSV is parsed by a small purpose-built scanner rather than the `csv`
//! crate: the format is plain numeric, and the scanner gives exact line and
//! column positions and reads an hour at 1 kHz in a fraction of a second.

#![warn(missing_docs)]

mod checks;
mod error;
mod header;
mod number;
mod reader;
mod sidecar;
pub mod units;
mod writer;

use std::io::Read;
use std::path::{Path, PathBuf};

pub use checks::{Extreme, NOMINAL_WINDOW, Span, StepDeviation, Warning};
pub use error::LogError;
pub use header::ColumnNames;
pub use reader::{Columns, LogReader, LogReport, LogSummary, MAX_MAGNITUDE};
pub use sidecar::{Excitation, FORMAT, Sensors, Sidecar};
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

/// Options of the log reader. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadOptions {
    /// Sidecar location (default [`SidecarSource::Auto`]).
    pub sidecar: SidecarSource,
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
    /// The lab's own column names (default: the standard names).
    pub columns: ColumnNames,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            sidecar: SidecarSource::Auto,
            sensors: Sensors::default(),
            min_rows: 16,
            step_tolerance: 0.5,
            nominal_step: None,
            saturation_samples: 50,
            check_degrees: true,
            columns: ColumnNames::default(),
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
    /// Joint angles (rad).
    pub theta: [Vec<f64>; 2],
    /// Joint torques (N·m).
    pub tau: [Vec<f64>; 2],
    /// Logged joint rates (rad/s), if present.
    pub theta_dot: Option<[Vec<f64>; 2]>,
    /// Logged joint accelerations (rad/s²), if present.
    pub theta_ddot: Option<[Vec<f64>; 2]>,
    /// The sidecar (default if none).
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
