//! The reader's and writer's errors: what was wrong, where (file, line,
//! column, value) and how to fix it. A variant with an underlying error
//! returns it from [`source`](std::error::Error::source) and does not repeat
//! it in its own message.

use std::path::PathBuf;

/// `x` rounded to 9 significant digits and printed shortest, so differences
/// of logged times print as `0.004`, not `0.0040000000000000036`.
pub(crate) fn sig(x: f64) -> f64 {
    format!("{x:.8e}").parse().unwrap_or(x)
}

/// Errors of reading and validating a log (CSV plus optional JSON sidecar).
///
/// `file` is the display name given to the reader (the path for
/// [`read_log`](crate::read_log)); `line` and `column` are 1-based, the
/// column being the field's position in the row.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read the file")]
    Io {
        /// File name.
        file: String,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A line is not valid UTF-8 text.
    #[error(
        "{file}:{line}: the line is not valid UTF-8 text; save the log as UTF-8 (plain ASCII numbers)"
    )]
    NotUtf8 {
        /// File name.
        file: String,
        /// Line number.
        line: u64,
    },
    /// No header line at all.
    #[error(
        "{file}: no header line: the log is empty or only comments; the first non-comment line \
         must name the columns, e.g. `t,theta1,theta2,tau1,tau2`"
    )]
    NoHeader {
        /// File name.
        file: String,
    },
    /// The header is separated by semicolons.
    #[error(
        "{file}:{line}: the header is separated by ';' but aras logs are comma-separated: \
         replace every ';' by ',' (and decimal commas by points)"
    )]
    Semicolon {
        /// File name.
        file: String,
        /// Line of the header.
        line: u64,
    },
    /// The header is separated by tabs.
    #[error(
        "{file}:{line}: the header is separated by tabs but aras logs are comma-separated: \
         replace every tab by ','"
    )]
    TabSeparated {
        /// File name.
        file: String,
        /// Line of the header.
        line: u64,
    },
    /// A header field is empty.
    #[error(
        "{file}:{line}:{column}: column {column} of the header has no name: name it or remove the empty field"
    )]
    EmptyColumnName {
        /// File name.
        file: String,
        /// Line of the header.
        line: u64,
        /// 1-based column.
        column: usize,
    },
    /// A column name appears twice.
    #[error(
        "{file}:{line}:{column}: column `{name}` appears twice (columns {first} and {column}): remove or rename one"
    )]
    DuplicateColumn {
        /// File name.
        file: String,
        /// Line of the header.
        line: u64,
        /// Column of the second occurrence.
        column: usize,
        /// Column of the first occurrence.
        first: usize,
        /// The duplicated name.
        name: String,
    },
    /// A required column is missing.
    #[error(
        "{file}:{line}: required column `{name}` is missing (the header has: {header}); {hint}"
    )]
    MissingColumn {
        /// File name.
        file: String,
        /// Line of the header.
        line: u64,
        /// The missing column.
        name: String,
        /// The header's column names, comma-separated.
        header: String,
        /// How to fix it.
        hint: String,
    },
    /// Only one of a pair of optional columns is present.
    #[error(
        "{file}:{line}: column `{present}` is present but `{missing}` is not: give both or neither"
    )]
    UnpairedColumn {
        /// File name.
        file: String,
        /// Line of the header.
        line: u64,
        /// The column that is there.
        present: String,
        /// Its missing partner.
        missing: String,
    },
    /// A row has a different number of fields than the header.
    #[error(
        "{file}:{line}: the row has {found} fields but the header has {expected}: every row needs one value per column"
    )]
    FieldCount {
        /// File name.
        file: String,
        /// Line number.
        line: u64,
        /// Number of header columns.
        expected: usize,
        /// Number of fields found.
        found: usize,
    },
    /// A value is not a number.
    #[error("{file}:{line}:{column}: `{name}` value {text:?} is not a number{hint}")]
    NotANumber {
        /// File name.
        file: String,
        /// Line number.
        line: u64,
        /// 1-based column.
        column: usize,
        /// Column name.
        name: String,
        /// The text found.
        text: String,
        /// Extra advice (may be empty).
        hint: String,
    },
    /// A value is NaN or infinite.
    #[error(
        "{file}:{line}:{column}: `{name}` value {text:?} is not finite: logs must hold finite numbers only (drop or repair the row)"
    )]
    NonFinite {
        /// File name.
        file: String,
        /// Line number.
        line: u64,
        /// 1-based column.
        column: usize,
        /// Column name.
        name: String,
        /// The text found.
        text: String,
    },
    /// A value is finite but too large to be a measurement.
    #[error(
        "{file}:{line}:{column}: `{name}` value {text:?} is beyond ±{limit:e}, too large to be a \
         measurement (a corrupt cell?): drop or repair the row"
    )]
    OutOfRange {
        /// File name.
        file: String,
        /// Line number.
        line: u64,
        /// 1-based column.
        column: usize,
        /// Column name.
        name: String,
        /// The text found.
        text: String,
        /// The largest magnitude accepted.
        limit: f64,
    },
    /// Time does not strictly increase.
    #[error(
        "{file}:{line}:{column}: time does not increase: t = {t} s follows t = {previous} s; rows \
         must be sorted by strictly increasing time without repeats"
    )]
    TimeNotIncreasing {
        /// File name.
        file: String,
        /// Line number.
        line: u64,
        /// Column of `t`.
        column: usize,
        /// Previous time.
        previous: f64,
        /// This row's time.
        t: f64,
    },
    /// Fewer data rows than needed.
    #[error("{file}: only {rows} data rows, at least {needed} are needed: record a longer log")]
    TooFewRows {
        /// File name.
        file: String,
        /// Rows found.
        rows: usize,
        /// Rows needed.
        needed: usize,
    },
    /// The sampling step varies beyond the tolerance.
    #[error(
        "{file}:{line}: irregular sampling: the worst step, {s} s ending at t = {t} s, is \
         {ratio:.3}× the nominal step {n} s (tolerance ±{percent}%); samples are missing or the \
         clock jumps: resample the log onto a uniform grid with --resample (config \
         log.resample = true; gaps up to --max-gap s are interpolated, longer ones refused)"
    , percent = tolerance * 100.0, s = sig(*step), n = sig(*nominal))]
    IrregularSampling {
        /// File name.
        file: String,
        /// Line ending the worst step.
        line: u64,
        /// Time ending the worst step.
        t: f64,
        /// The step (s).
        step: f64,
        /// step / nominal.
        ratio: f64,
        /// Nominal step (s).
        nominal: f64,
        /// Relative tolerance.
        tolerance: f64,
    },
    /// The time step is a whole number at an implausibly low rate: `t` is
    /// probably not in seconds.
    #[error(
        "{file}: the time step is {step} (a rate of {rate} Hz if t is in seconds, implausibly \
         slow for robot control): is t in seconds? (a step of {step} looks like {unit}; use \
         --time-unit {flag} (config log.time_unit = \"{flag}\") or convert t to seconds; \
         --time-unit s accepts the times as seconds)",
        step = sig(*step), rate = sig(1.0 / *step)
    )]
    TimeUnit {
        /// File name.
        file: String,
        /// The median step, in the log's own unit.
        step: f64,
        /// The unit it looks like.
        unit: &'static str,
        /// The `--time-unit` value for it.
        flag: &'static str,
    },
    /// Isolated samples far off their neighbours, and the options say to
    /// refuse the log.
    #[error(
        "{file}: {count} isolated glitch(es), samples far off their neighbours (a sensor or \
         logging fault?):{list}\ncheck the sensor; to go on, use --glitches repair (replace \
         each by the interpolation of its neighbours), drop (remove those rows), or warn \
         (keep them) (config log.glitches)"
    )]
    Glitches {
        /// File name.
        file: String,
        /// How many.
        count: usize,
        /// One line per glitch (the first few), each starting with a newline.
        list: String,
    },
    /// Angle columns hold degrees.
    #[error(
        "{file}: angles look like degrees (max |{name}| = {max:.1}): convert to radians (largest value on line {line})"
    )]
    Degrees {
        /// File name.
        file: String,
        /// Column name.
        name: String,
        /// Largest magnitude found.
        max: f64,
        /// Line of that value.
        line: u64,
    },
    /// A logged derivative column is not the derivative of its column.
    #[error(
        "{file}: `{name}` is not the derivative of `{of}`: integrated, it is {ratio:.4}× the \
         change of `{of}` (1 expected); {hint}"
    )]
    InconsistentDerivative {
        /// File name.
        file: String,
        /// The derivative column.
        name: String,
        /// The column it should be the derivative of.
        of: String,
        /// Least-squares ratio of the logged to the column's own derivative.
        ratio: f64,
        /// What the ratio suggests and how to fix it.
        hint: String,
    },
    /// Angle columns hold values that are neither radians nor degrees.
    #[error(
        "{file}: `{name}` reaches {max:.1} (line {line}), which is neither a plausible angle in \
         radians nor in degrees; if these are encoder counts name the columns enc1, enc2 and give \
         sensors.counts_per_rev"
    )]
    ImplausibleAngle {
        /// File name.
        file: String,
        /// Column name.
        name: String,
        /// Largest magnitude found.
        max: f64,
        /// Line of that value.
        line: u64,
    },
    /// The sidecar JSON is malformed or has an unknown key.
    #[error("{file}:{line}:{column}: {message}")]
    Sidecar {
        /// Sidecar file name.
        file: String,
        /// Line (1-based, 0 if unknown).
        line: usize,
        /// Column (1-based, 0 if unknown).
        column: usize,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// A sidecar value is out of range.
    #[error("{file}: {key} = {value} is invalid: {reason}")]
    SidecarValue {
        /// Sidecar file name (or "options" for command-line overrides).
        file: String,
        /// Dotted key, e.g. `sensors.gear_ratios[1]`.
        key: String,
        /// The offending value.
        value: String,
        /// What is allowed.
        reason: String,
    },
    /// A conversion needs a sensor constant nobody gave.
    #[error(
        "{file}: the log has columns {columns} but no {key} is given: add \"{key}\" to the \
         sidecar {sidecar} or set it in ReadOptions::sensors (command line)"
    )]
    MissingSensor {
        /// Log file name.
        file: String,
        /// The columns needing the constant.
        columns: String,
        /// Dotted key, e.g. `sensors.torque_constants`.
        key: String,
        /// Where the sidecar was looked for.
        sidecar: String,
    },
    /// An option value is invalid.
    #[error("invalid read option {name} = {value}: {reason}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Its value.
        value: String,
        /// What is allowed.
        reason: String,
    },
    /// The torque timing given in the options contradicts the sidecar's
    /// statement.
    #[error(
        "{log}: the torques are given as `{given}` (ReadOptions::torques: the command line's \
         --torques or the config's log.torques) but the sidecar {sidecar} states \
         \"torques\": \"{stated}\": drop the override (the sidecar's writer knows how its \
         torques were logged) or correct the sidecar's `torques` key"
    )]
    TorqueTimingConflict {
        /// Log file name.
        log: String,
        /// Sidecar file name.
        sidecar: String,
        /// The sidecar's statement.
        stated: crate::TorqueTiming,
        /// The options' value.
        given: crate::TorqueTiming,
    },
    /// A sidecar file given explicitly does not exist.
    #[error("sidecar {path} cannot be read")]
    SidecarIo {
        /// The path.
        path: PathBuf,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A sidecar given explicitly does not declare the format.
    #[error(
        "{file} does not declare the sidecar format: add \"format\": \"aras-log/1\" to it \
         (docs/log-format.md), or read the log without a sidecar (--sidecar none, \
         SidecarSource::None)"
    )]
    SidecarUndeclared {
        /// Sidecar file name.
        file: String,
    },
    /// The file is not a readable MCAP bag.
    #[error(
        "{file}: not a readable ROS 2 bag (MCAP): {reason}; a bag still being recorded or cut \
         short has no end: re-index it (`mcap recover`) or record it again"
    )]
    Bag {
        /// Bag file name.
        file: String,
        /// What the MCAP reader found.
        reason: String,
    },
    /// The bag's topic to read is missing or ambiguous.
    #[error("{file}: {problem}; the bag's topics: {topics}")]
    BagTopic {
        /// Bag file name.
        file: String,
        /// What is wrong and how to fix it.
        problem: String,
        /// The topics, with message types and counts.
        topics: String,
    },
    /// The bag's joints cannot be mapped to θ1 and θ2.
    #[error("{file}: topic {topic}: {problem}")]
    BagJoints {
        /// Bag file name.
        file: String,
        /// The topic read.
        topic: String,
        /// What is wrong and how to fix it.
        problem: String,
    },
    /// A message of the bag is malformed or lacks what a log needs.
    #[error("{file}: topic {topic}, message {message}: {problem}")]
    BagMessage {
        /// Bag file name.
        file: String,
        /// The topic read.
        topic: String,
        /// 1-based number of the message on its topic.
        message: u64,
        /// What is wrong and how to fix it.
        problem: String,
    },
    /// A log or sidecar file could not be written.
    #[error("{path} cannot be written")]
    Write {
        /// The file.
        path: PathBuf,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The sidecar could not be turned into JSON (e.g. a non-finite number
    /// in `truth`).
    #[error("the sidecar {path} cannot be written as JSON")]
    SidecarWrite {
        /// The sidecar file.
        path: PathBuf,
        /// The serialiser's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}
