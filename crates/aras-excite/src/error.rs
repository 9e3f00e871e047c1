//! Typed errors of the excitation design.

use std::path::PathBuf;

/// Everything that can go wrong when building, reading, sampling or designing
/// an excitation trajectory.
///
/// Messages name the offending setting or key, its value, the limit it broke
/// and how to fix it. A variant with an underlying error returns it from
/// [`source`](std::error::Error::source) and does not repeat it in its own
/// message, so printing the chain shows each cause once. Angles are shown in degrees in messages; fields are SI
/// (rad, rad/s, rad/s²).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExciteError {
    /// A number that must be finite is NaN or infinite.
    #[error("{name} is not finite ({value}); give a finite number")]
    NonFinite {
        /// Setting or key path (e.g. `"a[1][3]"`, `"max_accel[0]"`).
        name: String,
        /// The offending value.
        value: f64,
    },
    /// A setting is outside its admissible range.
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidSetting {
        /// Setting name (e.g. `"harmonics"`, `"omega_f"`).
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What it must satisfy, and how to fix it.
        reason: String,
    },
    /// Per-coordinate coefficient lists of a trajectory disagree in length.
    #[error(
        "coefficient list {name} has {found} entries but the trajectory has {expected} harmonics; \
         give one value per harmonic l = 1..L for each coordinate"
    )]
    CoefficientLength {
        /// Key path of the list (e.g. `"b[1]"`).
        name: String,
        /// Its length.
        found: usize,
        /// The number of harmonics L.
        expected: usize,
    },
    /// The box contains poses the model cannot be evaluated at (unreachable
    /// or numerically singular), so no trajectory inside it can be designed.
    #[error(
        "the box {} is infeasible: at X = {} the regressor fails; shrink the box so it \
         stays inside the reachable, non-singular region",
        box_degrees(lo, hi),
        degrees(at)
    )]
    InfeasibleBox {
        /// Lower corner (rad).
        lo: Vec<f64>,
        /// Upper corner (rad).
        hi: Vec<f64>,
        /// The failing pose (rad).
        at: Vec<f64>,
        /// What the regressor reported.
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// The rate or acceleration limits leave too little room for any useful
    /// motion of a coordinate.
    #[error(
        "{coordinate} can move at most {reach:.4}° peak to peak under the limits (velocity \
         {vel:.4}°/s, acceleration {acc:.4}°/s², box width {width:.4}°, ω_f = {omega:.4} rad/s), \
         less than the required {need:.4}°; raise the velocity/acceleration limits, widen the box, \
         or lower min_excursion",
        reach = reach.to_degrees(), vel = max_rate.to_degrees(), acc = max_accel.to_degrees(),
        width = width.to_degrees(), need = required.to_degrees()
    )]
    TooLittleMotion {
        /// `"phi"` or `"gamma"` for two coordinates, `"x1"` … otherwise.
        coordinate: String,
        /// Largest peak-to-peak excursion the limits allow (rad).
        reach: f64,
        /// The velocity limit (rad/s).
        max_rate: f64,
        /// The acceleration limit (rad/s²).
        max_accel: f64,
        /// Box width (rad).
        width: f64,
        /// The base frequency (rad/s).
        omega: f64,
        /// The required excursion (rad).
        required: f64,
    },
    /// The base projection does not fit the regressor.
    #[error(
        "base projection E is {rows}×{cols} but the regressor has {columns} columns; E must be \
         (columns × base parameters) with at least one base parameter"
    )]
    ProjectionShape {
        /// Rows of E.
        rows: usize,
        /// Columns of E.
        cols: usize,
        /// Columns of the regressor.
        columns: usize,
    },
    /// The kinematics failed while sampling a trajectory.
    #[error("kinematics failed at t = {t:.6} s")]
    Kinematics {
        /// Sample time (s).
        t: f64,
        /// What the kinematics reported.
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// The user's regressor failed at a sample.
    #[error("the regressor failed at {}", pose_degrees(at))]
    Regressor {
        /// Pose of the failing sample (rad).
        at: Vec<f64>,
        /// The regressor's own error.
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// The user's pose constraint failed, or gave a non-finite value or
    /// derivative, at a pose.
    #[error("the pose constraint failed at {}", pose_degrees(at))]
    Constraint {
        /// The pose (rad).
        at: Vec<f64>,
        /// What the constraint reported.
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// No rest pose satisfies the pose constraint with its margin, so no
    /// trajectory can (the repair scales towards such a pose).
    #[error(
        "the pose constraint cannot be met at rest: its best pose {} has max g = {worst:.6e}, \
         above −margin = {neg:.6e}; loosen the constraint or the margin, widen the box, or \
         give constraint.anchor, a pose inside the box where every g_k ≤ −margin",
        pose_degrees(at), neg = -margin
    )]
    ConstraintInfeasible {
        /// The best pose found, or the given anchor (rad).
        at: Vec<f64>,
        /// Its largest constraint value.
        worst: f64,
        /// The required clearance.
        margin: f64,
    },
    /// The stacked base regressor along a trajectory is degenerate
    /// (a zero column or numerically rank-deficient).
    #[error("the base regressor along the trajectory is degenerate: {reason}")]
    Degenerate {
        /// What was found.
        reason: String,
    },
    /// No start of the multi-start gave a usable design.
    #[error(
        "none of the {starts} starts produced a finite criterion (last failure: {last}); the \
         trajectory form cannot excite every base parameter: raise the number of harmonics or \
         the limits, or check the base projection"
    )]
    NoDesign {
        /// Number of starts tried.
        starts: usize,
        /// The last failure message.
        last: String,
    },
    /// A trajectory JSON document is malformed.
    #[error("{origin}: {}{message}", position(*line, *column))]
    Json {
        /// File path, or `"<string>"`.
        origin: String,
        /// Line (1-based, 0 if unknown).
        line: usize,
        /// Column (1-based, 0 if unknown).
        column: usize,
        /// What serde reported.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("cannot read or write {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// Errors on a non-finite value with its name.
pub(crate) fn check_finite(name: impl FnOnce() -> String, value: f64) -> Result<(), ExciteError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ExciteError::NonFinite {
            name: name(),
            value,
        })
    }
}

/// The error's message followed by each of its causes, `": "`-separated:
/// the one-line form kept in a start's report.
pub(crate) fn with_causes(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text.push_str(": ");
        text.push_str(&c.to_string());
        cause = c.source();
    }
    text
}

/// `line L, column C: `, or nothing when the position is unknown (0).
fn position(line: usize, column: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!("line {line}, column {column}: ")
    }
}

/// `[a°, b°, …]` to 3 decimals.
fn degrees(v: &[f64]) -> String {
    let parts: Vec<String> = v
        .iter()
        .map(|x| format!("{:.3}°", x.to_degrees()))
        .collect();
    format!("[{}]", parts.join(", "))
}

/// `X1 ∈ [lo°, hi°], X2 ∈ …` of a box.
fn box_degrees(lo: &[f64], hi: &[f64]) -> String {
    let parts: Vec<String> = lo
        .iter()
        .zip(hi)
        .enumerate()
        .map(|(i, (l, h))| {
            format!(
                "X{} ∈ [{:.3}°, {:.3}°]",
                i + 1,
                l.to_degrees(),
                h.to_degrees()
            )
        })
        .collect();
    parts.join(", ")
}

/// `φ = a°, γ = b°` for ARAS-Diamond's two task coordinates, `X = [a°, …]`
/// otherwise, to 4 decimals.
fn pose_degrees(at: &[f64]) -> String {
    match at {
        [phi, gamma] => format!(
            "φ = {:.4}°, γ = {:.4}°",
            phi.to_degrees(),
            gamma.to_degrees()
        ),
        _ => {
            let parts: Vec<String> = at
                .iter()
                .map(|x| format!("{:.4}°", x.to_degrees()))
                .collect();
            format!("X = [{}]", parts.join(", "))
        }
    }
}
