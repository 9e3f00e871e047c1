//! Reading a joint log: a CSV file with a header and one row per sample.
//!
//! Required columns: `t` (s), `q` (rad), `tau` (N·m, the joint's friction
//! torque: measured torque minus the rigid-body model; optional in a log
//! that is only predicted, [`read_joint_motion`]). Optional: `dq` (rad/s)
//! — used as given; only when it is absent it is computed from `q` —,
//! `ddq` (rad/s²) and `load` (N·m, the torque the joint carries, e.g. the
//! rigid-body model's: for friction that grows with load). Other columns
//! are ignored; [`ColumnMap`] maps a lab's own names
//! (`t=time,q=q2,dq=dq2,tau=tau_f`). Lines starting with `#` and blank
//! lines are skipped. Time must increase strictly; the steps may be irregular
//! (jitter, gaps). The CSV is read by [`aras_log::CsvTable`], so its rules and
//! messages are the robot log's (comma separators, one field per header
//! column, finite numbers); a column serves one role. Every defect is a
//! [`LogError`] naming the file, line, column and value.
//!
//! Units are checked as the robot log reader checks them
//! ([`aras_log::units`]): a position whose range looks like degrees is
//! refused, and so are logged `dq` / `ddq` columns that are not the
//! derivatives of `q` / `dq` (e.g. degrees per second, a reversed sign).
//! A logged `dq` or `ddq` that holds one value on every row while the
//! column it derives from moves is a logger's placeholder (often all zeros),
//! not a measurement: it is dropped and derived instead, with a note in
//! [`JointMotion::notes`].

use std::{fmt, io::Read, path::Path, str::FromStr};

use aras_log::{CsvTable, RowColumns};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::{FrictionError, Track};

/// Errors reading a joint log. `line` and `column` are 1-based.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum LogError {
    /// A defect of the file as a numeric CSV (unreadable once open, no header, a row
    /// of the wrong length, a value that is not a finite number, time that
    /// does not increase, too few rows) or of its units (degrees, a logged
    /// derivative that is not the derivative of its column), as the robot
    /// log reader reports it: file, line, column, value and the fix.
    #[error(transparent)]
    Csv(#[from] aras_log::LogError),
    /// The file could not be opened.
    #[error("{file}: cannot read the log")]
    Io {
        /// File name.
        file: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A required column is not in the header.
    #[error(
        "{file}:{line}: column `{name}` (for {role}) is missing; the header has: {header}. \
         Map your own names with --columns {role}=NAME"
    )]
    MissingColumn {
        /// File name.
        file: String,
        /// Header line.
        line: u64,
        /// The role (`t`, `q`, `dq`, `tau`, `ddq`).
        role: &'static str,
        /// The column name looked for.
        name: String,
        /// The header's columns.
        header: String,
    },
    /// A malformed `--columns` mapping.
    #[error("--columns {text:?}: {reason}; write e.g. t=time,q=q2,dq=dq2,tau=tau_f")]
    BadMapping {
        /// The mapping text.
        text: String,
        /// What is wrong.
        reason: String,
    },
}

/// Which CSV column holds each quantity. Defaults: `t`, `q`, `dq`, `tau`,
/// `ddq`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ColumnMap {
    /// Time column (s).
    pub t: String,
    /// Position column (rad).
    pub q: String,
    /// Velocity column (rad/s); computed from `q` when absent unless
    /// [`ColumnMap::dq_required`].
    pub dq: String,
    /// Friction torque column (N·m).
    pub tau: String,
    /// Acceleration column (rad/s²), optional.
    pub ddq: String,
    /// Load torque column (N·m), optional: the torque the joint carries
    /// (e.g. the rigid-body model's), for friction that grows with load.
    pub load: String,
    /// True when the user named the velocity column explicitly, so its
    /// absence is an error instead of a reason to differentiate `q`.
    pub dq_required: bool,
}

impl Default for ColumnMap {
    fn default() -> Self {
        Self {
            t: "t".into(),
            q: "q".into(),
            dq: "dq".into(),
            tau: "tau".into(),
            ddq: "ddq".into(),
            load: "load".into(),
            dq_required: false,
        }
    }
}

impl FromStr for ColumnMap {
    type Err = LogError;
    /// Parses `role=name` pairs separated by commas; roles not given keep
    /// their default names.
    fn from_str(text: &str) -> Result<Self, LogError> {
        let bad = |reason: String| LogError::BadMapping {
            text: text.to_string(),
            reason,
        };
        let mut m = Self::default();
        for pair in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (role, name) = pair
                .split_once('=')
                .ok_or_else(|| bad(format!("`{pair}` is not role=name")))?;
            let (role, name) = (role.trim(), name.trim());
            if name.is_empty() {
                return Err(bad(format!("no column name for `{role}`")));
            }
            match role {
                "t" => m.t = name.into(),
                "q" => m.q = name.into(),
                "dq" => {
                    m.dq = name.into();
                    m.dq_required = true;
                }
                "tau" => m.tau = name.into(),
                "ddq" => m.ddq = name.into(),
                "load" => m.load = name.into(),
                other => {
                    return Err(bad(format!(
                        "unknown role `{other}` (roles: t, q, dq, tau, ddq, load)"
                    )));
                }
            }
        }
        Ok(m)
    }
}

impl fmt::Display for ColumnMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "t={},q={},dq={},tau={},ddq={},load={}",
            self.t, self.q, self.dq, self.tau, self.ddq, self.load
        )
    }
}

/// One joint's motion on the log's own time grid: everything a log holds
/// except the friction torque. A fitted model predicts from it alone
/// ([`crate::FinalModel::predict`]), so a log to be predicted needs no
/// torque column ([`read_joint_motion`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointMotion {
    /// Name for reports and output files (the file stem).
    pub name: String,
    /// Time, s.
    pub t: Vec<f64>,
    /// Position, rad.
    pub q: Vec<f64>,
    /// Velocity, rad/s.
    pub dq: Vec<f64>,
    /// Acceleration, rad/s², when logged.
    pub ddq: Option<Vec<f64>>,
    /// Load torque the joint carries, N·m, when logged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load: Option<Vec<f64>>,
    /// True when `dq` was computed from `q` (no velocity column, or a
    /// placeholder one).
    pub dq_from_q: bool,
    /// What the reader did that the user should know (a placeholder column
    /// dropped), one sentence each.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

impl JointMotion {
    /// The motion (t, q, dq) as a [`Track`].
    pub fn track(&self) -> Result<Track<'_>, FrictionError> {
        Track::new(&self.t, &self.q, &self.dq)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True when the log has no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Acceleration: the logged `ddq`, or the derivative of `dq` on the
    /// log's own grid ([`derivative`]).
    pub fn acceleration(&self) -> Vec<f64> {
        match &self.ddq {
            Some(a) => a.clone(),
            None => derivative(&self.t, &self.dq),
        }
    }
}

/// One joint's log: its motion and the friction torque measured along it,
/// one value per sample. The motion's fields read through the log
/// (`log.q`, `log.len()`): a log is a motion with a torque.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointLog {
    /// The motion.
    #[serde(flatten)]
    pub motion: JointMotion,
    /// Friction torque, N·m, one per sample of the motion.
    pub tau: Vec<f64>,
}

impl std::ops::Deref for JointLog {
    type Target = JointMotion;
    fn deref(&self) -> &JointMotion {
        &self.motion
    }
}

impl std::ops::DerefMut for JointLog {
    fn deref_mut(&mut self) -> &mut JointMotion {
        &mut self.motion
    }
}

impl JointLog {
    /// The log as CSV text with header `t,q,dq,tau[,ddq][,load]`, every
    /// number in its shortest exact (round-trip) form.
    pub fn to_csv(&self) -> String {
        use std::fmt::Write;
        let m = &self.motion;
        let mut s = String::with_capacity(m.len() * 90);
        s.push_str("t,q,dq,tau");
        if m.ddq.is_some() {
            s.push_str(",ddq");
        }
        if m.load.is_some() {
            s.push_str(",load");
        }
        s.push('\n');
        for i in 0..m.len() {
            let _ = write!(s, "{},{},{},{}", m.t[i], m.q[i], m.dq[i], self.tau[i]);
            for c in [&m.ddq, &m.load].into_iter().flatten() {
                let _ = write!(s, ",{}", c[i]);
            }
            s.push('\n');
        }
        s
    }
}

/// Minimum number of rows for a log to be usable.
pub const MIN_ROWS: usize = 10;

/// Reads a joint log from a file (see the module docs).
pub fn read_joint_log(path: &Path, columns: &ColumnMap) -> Result<JointLog, LogError> {
    let (file, name, reader) = open(path)?;
    read_joint_log_from(reader, &file, &name, columns)
}

/// Reads a joint log from any reader; `file` names the source in errors and
/// `name` becomes [`JointMotion::name`].
pub fn read_joint_log_from(
    reader: impl Read,
    file: &str,
    name: &str,
    columns: &ColumnMap,
) -> Result<JointLog, LogError> {
    let (motion, tau) = read(reader, file, name, columns, true)?;
    Ok(JointLog {
        motion,
        tau: tau.unwrap_or_default(),
    })
}

/// Reads a log whose torque column may be absent (a log to be predicted):
/// its motion, and its torque when the file has the column. Every other
/// rule is [`read_joint_log`]'s.
pub fn read_joint_motion(
    path: &Path,
    columns: &ColumnMap,
) -> Result<(JointMotion, Option<Vec<f64>>), LogError> {
    let (file, name, reader) = open(path)?;
    read_joint_motion_from(reader, &file, &name, columns)
}

/// [`read_joint_motion`] from any reader (`file` and `name` as in
/// [`read_joint_log_from`]).
pub fn read_joint_motion_from(
    reader: impl Read,
    file: &str,
    name: &str,
    columns: &ColumnMap,
) -> Result<(JointMotion, Option<Vec<f64>>), LogError> {
    read(reader, file, name, columns, false)
}

/// The file's name for errors, its stem for the log's name, and
/// the file (unbuffered: [`CsvTable`] reads it in large blocks itself).
fn open(path: &Path) -> Result<(String, String, std::fs::File), LogError> {
    let file = path.display().to_string();
    let f = std::fs::File::open(path).map_err(|source| LogError::Io {
        file: file.clone(),
        source,
    })?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "log".into());
    Ok((file, name, f))
}

/// The columns of a joint log, by role, as found in a table's header.
struct Roles {
    /// `(role, column)` of every column read, time first.
    read: Vec<(&'static str, usize)>,
}

impl Roles {
    /// Finds the roles' columns, each column for one role: `t` and `q`
    /// always, `tau` when `need_tau`, `dq` when the map names it; the others
    /// when present.
    fn find<R: Read>(
        table: &CsvTable<R>,
        columns: &ColumnMap,
        need_tau: bool,
    ) -> Result<Self, LogError> {
        let missing = |role: &'static str, name: &str| LogError::MissingColumn {
            file: table.file().to_string(),
            line: table.header_line(),
            role,
            name: name.to_string(),
            header: table.names().join(","),
        };
        let mut read = Vec::with_capacity(6);
        for (role, name, required) in [
            ("t", &columns.t, true),
            ("q", &columns.q, true),
            ("tau", &columns.tau, need_tau),
            ("dq", &columns.dq, columns.dq_required),
            ("ddq", &columns.ddq, false),
            ("load", &columns.load, false),
        ] {
            // A column already read for another role (`q=dq` leaves the
            // default `dq` name to `q`) is not an optional role's.
            match table.column(name) {
                Some(c) => match read.iter().find(|(_, used)| *used == c) {
                    None => read.push((role, c)),
                    Some((other, _)) if required => {
                        return Err(LogError::BadMapping {
                            text: columns.to_string(),
                            reason: format!(
                                "column `{name}` is given to both `{other}` and `{role}`"
                            ),
                        });
                    }
                    Some(_) => {}
                },
                None if required => return Err(missing(role, name)),
                None => {}
            }
        }
        Ok(Self { read })
    }

    /// The slot of `role` in a parsed row, if the log has its column.
    fn slot(&self, role: &str) -> Option<usize> {
        self.read.iter().position(|(r, _)| *r == role)
    }
}

/// The reader behind both entry points: the torque column is required when
/// `need_tau`, and read when present otherwise.
fn read(
    reader: impl Read,
    file: &str,
    name: &str,
    columns: &ColumnMap,
    need_tau: bool,
) -> Result<(JointMotion, Option<Vec<f64>>), LogError> {
    let mut table = CsvTable::new(reader, file)?;
    let roles = Roles::find(&table, columns, need_tau)?;
    let picks: Vec<(usize, String)> = roles
        .read
        .iter()
        .map(|&(_, c)| (c, table.names()[c].clone()))
        .collect();
    let pick = RowColumns::new(table.names().len(), &picks)?;
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); picks.len()];
    let mut data_lines: Vec<u64> = Vec::new();
    let mut row = vec![0.0; picks.len()];
    while let Some(line) = table.next_row(&pick, &mut row)? {
        if let Some(&previous) = cols[0].last()
            && row[0] <= previous
        {
            return Err(aras_log::LogError::TimeNotIncreasing {
                file: file.to_string(),
                line,
                column: picks[0].0 + 1,
                previous,
                t: row[0],
            }
            .into());
        }
        data_lines.push(line);
        for (c, v) in cols.iter_mut().zip(&row) {
            c.push(*v);
        }
    }
    if cols[0].len() < MIN_ROWS {
        return Err(aras_log::LogError::TooFewRows {
            file: file.to_string(),
            rows: cols[0].len(),
            needed: MIN_ROWS,
        }
        .into());
    }
    let mut take = |role: &str| roles.slot(role).map(|k| std::mem::take(&mut cols[k]));
    let (t, q) = (take("t").unwrap_or_default(), take("q").unwrap_or_default());
    let (tau, mut dq_logged, mut ddq, load) = (take("tau"), take("dq"), take("ddq"), take("load"));
    let mut notes = Vec::new();
    if let Some(v) = &dq_logged
        && is_placeholder(&t, &q, v)
    {
        notes.push(placeholder_note(file, &columns.dq, v[0], &columns.q));
        dq_logged = None;
    }
    let dq_from_q = dq_logged.is_none();
    let dq = dq_logged.unwrap_or_else(|| derivative(&t, &q));
    if let Some(a) = &ddq
        && is_placeholder(&t, &dq, a)
    {
        notes.push(placeholder_note(file, &columns.ddq, a[0], &columns.dq));
        ddq = None;
    }
    check_units(
        file,
        columns,
        (&t, &q, &data_lines),
        (&dq, !dq_from_q),
        ddq.as_deref(),
    )?;
    let motion = JointMotion {
        name: name.to_string(),
        t,
        q,
        dq,
        ddq,
        load,
        dq_from_q,
        notes,
    };
    Ok((motion, tau))
}

/// A logged derivative `dx` that holds one value on every row while `x`
/// moves against it: a placeholder (a logger's zeros), not a derivative.
/// A constant `dx` that *is* the derivative (a constant-speed log) passes
/// the unit check and is kept.
fn is_placeholder(t: &[f64], x: &[f64], dx: &[f64]) -> bool {
    let constant = dx.iter().all(|&v| v == dx[0]);
    constant
        && aras_log::units::derivative_ratio(t, x, dx)
            .is_some_and(|r| (r - 1.0).abs() > aras_log::units::RATIO_TOLERANCE)
}

fn placeholder_note(file: &str, name: &str, value: f64, of: &str) -> String {
    format!(
        "{file}: column `{name}` is {value} on every row while `{of}` moves: taken as a \
         placeholder and derived from `{of}` instead"
    )
}

/// The position in radians (not degrees, [`aras_log::units::check_angle_column`])
/// and the logged derivatives consistent with it
/// ([`aras_log::units::check_derivative_column`]: `dq` against `q` when it
/// was `logged`, `ddq` against `dq`, logged or derived). `lines[i]` is the
/// file line of sample `i`.
fn check_units(
    file: &str,
    columns: &ColumnMap,
    (t, q, lines): (&[f64], &[f64], &[u64]),
    (dq, logged): (&[f64], bool),
    ddq: Option<&[f64]>,
) -> Result<(), LogError> {
    use aras_log::units::{check_angle_column, check_derivative_column};
    let (mut lo, mut hi, mut top, mut at) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, 0);
    for (i, &v) in q.iter().enumerate() {
        lo = lo.min(v);
        hi = hi.max(v);
        if v.abs() > top {
            top = v.abs();
            at = i;
        }
    }
    let line = lines.get(at).copied().unwrap_or(0);
    check_angle_column(file, &columns.q, [lo, hi, top], line)?;
    if logged {
        check_derivative_column(file, (&columns.dq, dq), (&columns.q, q), t)?;
    }
    if let Some(ddq) = ddq {
        check_derivative_column(file, (&columns.ddq, ddq), (&columns.dq, dq), t)?;
    }
    Ok(())
}

/// Derivative of samples `y(t)` on an irregular grid: at interior points the
/// slope of the parabola through the sample and its two neighbours
/// (second-order accurate for any step ratio), at the ends the one-sided
/// three-point parabola. With fewer than three samples, the secant.
pub fn derivative(t: &[f64], y: &[f64]) -> Vec<f64> {
    let n = t.len().min(y.len());
    if n < 2 {
        return vec![0.0; n];
    }
    if n == 2 {
        let s = (y[1] - y[0]) / (t[1] - t[0]);
        return vec![s, s];
    }
    // Slope at t[i] of the parabola through (a, b, c) = (i0, i0+1, i0+2).
    let parabola = |i0: usize, at: f64| {
        let (t0, t1, t2) = (t[i0], t[i0 + 1], t[i0 + 2]);
        let (y0, y1, y2) = (y[i0], y[i0 + 1], y[i0 + 2]);
        // Derivatives of the Lagrange basis polynomials at `at`.
        let l0 = ((at - t1) + (at - t2)) / ((t0 - t1) * (t0 - t2));
        let l1 = ((at - t0) + (at - t2)) / ((t1 - t0) * (t1 - t2));
        let l2 = ((at - t0) + (at - t1)) / ((t2 - t0) * (t2 - t1));
        y0 * l0 + y1 * l1 + y2 * l2
    };
    let mut d = Vec::with_capacity(n);
    d.push(parabola(0, t[0]));
    for i in 1..n - 1 {
        d.push(parabola(i - 1, t[i]));
    }
    d.push(parabola(n - 3, t[n - 1]));
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, map: &ColumnMap) -> Result<JointLog, LogError> {
        read_joint_log_from(text.as_bytes(), "x.csv", "x", map)
    }

    fn rows(header: &str, n: usize) -> String {
        let mut s = format!("# comment\n{header}\n");
        for i in 0..n {
            let t = i as f64 * 0.01 + if i % 2 == 1 { 0.003 } else { 0.0 };
            s += &format!("{t},{},{},{},7\n", t.sin(), t.cos(), 0.1 * t);
        }
        s
    }

    #[test]
    fn reads_mapped_columns_and_ignores_others() {
        let map: ColumnMap = "t=time,q=q2,dq=dq2,tau=tau_f".parse().unwrap();
        let log = read(&rows("time,q2,dq2,tau_f,other", 20), &map).unwrap();
        assert_eq!(log.len(), 20);
        assert!(!log.dq_from_q);
        assert!((log.dq[3] - log.t[3].cos()).abs() < 1e-12);
        assert!(log.ddq.is_none() && log.load.is_none());
        // The fifth column as the load torque, by its default name or
        // mapped; written back by `to_csv`.
        let log = read(&rows("t,q,dq,tau,load", 20), &ColumnMap::default()).unwrap();
        assert_eq!(log.load.as_deref(), Some(&[7.0; 20][..]));
        let again = read(&log.to_csv(), &ColumnMap::default()).unwrap();
        assert_eq!(again.load, log.load);
        let map: ColumnMap = "load=tau_rb".parse().unwrap();
        let log = read(&rows("t,q,dq,tau,tau_rb", 20), &map).unwrap();
        assert_eq!(log.load.as_ref().map(Vec::len), Some(20));
    }

    /// `t, q, dq, tau` of a sine, `q` and `dq` scaled by `kq`, `kv`.
    fn sine(kq: f64, kv: f64) -> String {
        let mut s = String::from("t,q,dq,tau\n");
        for i in 0..400 {
            let t = i as f64 * 0.005;
            let (q, dq) = (0.8 * (2.0 * t).sin(), 1.6 * (2.0 * t).cos());
            s += &format!("{t},{},{},{}\n", kq * q, kv * dq, 0.1 * dq.signum());
        }
        s
    }

    #[test]
    fn units_are_checked_like_the_robot_logs() {
        let deg = 180.0 / std::f64::consts::PI;
        assert!(read(&sine(1.0, 1.0), &ColumnMap::default()).is_ok());
        // Degrees: the position spans 92°, beyond 3π "radians".
        let e = read(&sine(deg, deg), &ColumnMap::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("x.csv: angles look like degrees (max |q| = 45.8)"),
            "{e}"
        );
        assert!(e.contains("convert to radians"), "{e}");
        // A rate in degrees per second beside radians: the column, the ratio, the fix.
        let e = read(&sine(1.0, deg), &ColumnMap::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("`dq` is not the derivative of `q`"), "{e}");
        assert!(e.contains("57.2"), "{e}");
        assert!(e.contains("degrees per second"), "{e}");
        let e = read(&sine(1.0, -1.0), &ColumnMap::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("sign is reversed"), "{e}");
    }

    #[test]
    fn placeholder_derivative_columns_are_derived_with_a_note() {
        // A logger's zeros in `ddq`, then in both `dq` and `ddq`.
        let with_ddq = |zero_dq: bool| {
            let mut s = String::from("t,q,dq,tau,ddq\n");
            for i in 0..400 {
                let t = i as f64 * 0.005;
                let dq = if zero_dq { 0.0 } else { 1.6 * (2.0 * t).cos() };
                s += &format!("{t},{},{dq},0.1,0\n", 0.8 * (2.0 * t).sin());
            }
            s
        };
        let log = read(&with_ddq(false), &ColumnMap::default()).unwrap();
        assert!(log.ddq.is_none() && !log.dq_from_q);
        assert_eq!(log.notes.len(), 1, "{:?}", log.notes);
        assert!(log.notes[0].contains("`ddq` is 0 on every row while `dq` moves"));
        // The acceleration is now the derivative of dq: −3.2 sin(2t).
        let a = log.acceleration();
        assert!((a[100] + 3.2 * (2.0 * log.t[100]).sin()).abs() < 1e-3);
        let log = read(&with_ddq(true), &ColumnMap::default()).unwrap();
        assert!(log.dq_from_q && log.ddq.is_none());
        assert_eq!(log.notes.len(), 2, "{:?}", log.notes);
        assert!((log.dq[100] - 1.6 * (2.0 * log.t[100]).cos()).abs() < 1e-3);
        // A constant speed is a true constant derivative: kept, no note.
        let mut s = String::from("t,q,dq,tau,ddq\n");
        for i in 0..400 {
            let t = i as f64 * 0.005;
            s += &format!("{t},{},0.3,0.1,0\n", 0.3 * t);
        }
        let log = read(&s, &ColumnMap::default()).unwrap();
        assert!(log.notes.is_empty() && log.ddq.is_some() && !log.dq_from_q);
    }

    #[test]
    fn missing_velocity_is_derived_unless_mapped() {
        let log = read(&rows("t,q,vel,tau,x", 50), &ColumnMap::default()).unwrap();
        assert!(log.dq_from_q);
        // Second-order formula on a jittered 10 ms grid: error ≈ h²/6 |q'''| ≈ 2e-5.
        for i in 0..log.len() {
            assert!((log.dq[i] - log.t[i].cos()).abs() < 1e-4, "{i}");
        }
        let map: ColumnMap = "dq=speed".parse().unwrap();
        let e = read(&rows("t,q,vel,tau,x", 50), &map).unwrap_err();
        assert!(e.to_string().contains("`speed`"), "{e}");
    }

    #[test]
    fn errors_name_file_line_column_value() {
        let s = "# c\nt,q,dq,tau\n0,0,0,0\n0.1,abc,0,0\n";
        let e = read(s, &ColumnMap::default()).unwrap_err().to_string();
        assert!(e.starts_with("x.csv:4:2:") && e.contains("\"abc\""), "{e}");
        let s = "t,q,dq,tau\n0,0,0,0\n0.1,0,0,inf\n";
        let e = read(s, &ColumnMap::default()).unwrap_err().to_string();
        assert!(e.starts_with("x.csv:3:4:") && e.contains("inf"), "{e}");
        let s = "t,q,dq,tau\n0,0,0,0\n0,0,0,0\n";
        let e = read(s, &ColumnMap::default()).unwrap_err().to_string();
        assert!(e.starts_with("x.csv:3:1:"), "{e}");
        let e = read("a,b\n1,2\n", &ColumnMap::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("column `t`") && e.contains("a,b"), "{e}");
        assert!("t=time,z=3".parse::<ColumnMap>().is_err());
        // The CSV's own rules are the robot log's: one field per column,
        // commas between them.
        let e = read("t,q,dq,tau\n0,0,0,0,5\n", &ColumnMap::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("x.csv:2: the row has 5 fields but the header has 4"),
            "{e}"
        );
        let e = read("t;q;dq;tau\n", &ColumnMap::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("separated by ';'"), "{e}");
    }

    #[test]
    fn a_column_serves_one_role() {
        // `q=dq` reads the position from the column named `dq`; the
        // velocity, whose default name that is, is derived.
        let map: ColumnMap = "q=dq".parse().unwrap();
        let log = read(&rows("t,dq,x,tau,y", 20), &map).unwrap();
        assert!(log.dq_from_q);
        assert!((log.q[3] - log.t[3].sin()).abs() < 1e-15);
        // A required role on a column another role reads is a mapping error.
        let map: ColumnMap = "t=q".parse().unwrap();
        let e = read(&rows("a,q,dq,tau,b", 20), &map)
            .unwrap_err()
            .to_string();
        assert!(e.contains("column `q` is given to both `t` and `q`"), "{e}");
    }

    #[test]
    fn derivative_is_exact_for_parabolas_on_irregular_grids() {
        let t = [0.0, 0.001, 0.017, 0.02, 0.5, 0.51];
        let y: Vec<f64> = t.iter().map(|t| 3.0 + 2.0 * t - 5.0 * t * t).collect();
        let d = derivative(&t, &y);
        for (ti, di) in t.iter().zip(&d) {
            assert!((di - (2.0 - 10.0 * ti)).abs() < 1e-9, "{ti}: {di}");
        }
    }
}
