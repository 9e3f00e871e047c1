//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in identification. Every message says what
/// was wrong, where, and how to fix it.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum IdentError {
    /// Two inputs that must agree in size do not.
    #[error("{what}: expected {expected}, found {found}; {hint}")]
    DimensionMismatch {
        /// Which quantity has the wrong size.
        what: &'static str,
        /// The size required by the other inputs.
        expected: usize,
        /// The size given.
        found: usize,
        /// How to fix it.
        hint: &'static str,
    },
    /// A NaN or infinity in an input matrix or vector.
    #[error(
        "{what} has a non-finite value {value} at row {row}, column {column} (`{name}`); \
         remove or repair the sample before identification"
    )]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Row (sample row) of the bad entry, 0-based.
        row: usize,
        /// Column of the bad entry, 0-based.
        column: usize,
        /// Name of the column (parameter), if known.
        name: String,
        /// The offending value.
        value: f64,
    },
    /// Fewer rows than unknowns: the least-squares problem has no residual
    /// degrees of freedom, so no variance can be estimated.
    #[error(
        "{what}: {rows} rows for {columns} unknowns; at least {needed} rows are needed \
         (record a longer trajectory or more samples)"
    )]
    TooFewRows {
        /// Which problem.
        what: &'static str,
        /// Rows given.
        rows: usize,
        /// Columns (unknowns).
        columns: usize,
        /// Minimum number of rows.
        needed: usize,
    },
    /// The regressor contains no information at all (every column is zero).
    #[error("{what}: every column is zero (rows = {rows}); the data do not move the robot")]
    NoExcitation {
        /// Which problem.
        what: &'static str,
        /// Rows given.
        rows: usize,
    },
    /// The data do not excite some parameters: their columns are (numerically)
    /// linear combinations of the earlier ones, so any estimate would be
    /// arbitrary. Lists them by name.
    #[error(
        "the data do not excite {count} of {total} parameters (rank {rank}, relative tolerance \
         {tolerance:e}): {names}; use a richer excitation trajectory (see docs/excitation.md) or remove these \
         parameters from the model",
        count = lost.len(),
        names = lost_names.join(", ")
    )]
    NotExcited {
        /// Column indices that lose rank, 0-based.
        lost: Vec<usize>,
        /// Their names.
        lost_names: Vec<String>,
        /// Numerical rank of the data's regressor.
        rank: usize,
        /// Number of columns.
        total: usize,
        /// Relative rank tolerance used.
        tolerance: f64,
    },
    /// A parameter name that is not among the standard parameters.
    #[error("unknown parameter `{name}`; known parameters are: {known}")]
    UnknownParameter {
        /// The name asked for.
        name: String,
        /// The known names, comma separated.
        known: String,
    },
    /// An index beyond the parameter vector.
    #[error("{what}: parameter index {index} is out of range (there are {count} parameters)")]
    IndexOutOfRange {
        /// Where the index was given.
        what: String,
        /// The index.
        index: usize,
        /// Number of parameters.
        count: usize,
    },
    /// A malformed link layout for the physically consistent problem.
    #[error("link `{link}`: {reason}")]
    InvalidLayout {
        /// Link name.
        link: String,
        /// What is wrong and how to fix it.
        reason: String,
    },
    /// A malformed selection problem (candidate layout, output group, sums
    /// of different layouts).
    #[error("selection: {reason}")]
    InvalidSelection {
        /// What is wrong and how to fix it.
        reason: String,
    },
    /// Bounds with lower > upper or non-finite values.
    #[error("bounds of `{name}`: lower {lower} > upper {upper} or not finite; give lower ≤ upper")]
    InvalidBounds {
        /// Parameter (or link mass) name.
        name: String,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// A setting outside its valid range.
    #[error("setting `{name}` = {value} is invalid: {reason}")]
    InvalidSetting {
        /// Setting name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What the valid range is.
        reason: &'static str,
    },
    /// The constraints of the physically consistent problem admit no solution.
    #[error(
        "the physically consistent problem is infeasible (solver status {status}): no parameter \
         set satisfies all constraints; widen the mass bounds or box bounds (73), lower the PSD \
         margin, or check that the reference/CAD values are physically consistent"
    )]
    Infeasible {
        /// Solver status as text.
        status: String,
    },
    /// The SDP solver stopped without a usable solution.
    #[error(
        "the SDP solver stopped with status {status} after {iterations} iterations; try a looser \
         tolerance, more iterations, or check the regressor's scaling"
    )]
    SolverFailed {
        /// Solver status as text.
        status: String,
        /// Iterations done.
        iterations: u32,
    },
    /// An error from the robot crates (kinematics, dynamics, signal processing).
    #[error("{context}: {message}")]
    Adapter {
        /// What was being done.
        context: String,
        /// The underlying error's message.
        message: String,
    },
    /// The measured signal is constant, so the fitness (78) is undefined.
    #[error(
        "fitness of group {group}: the measured signal is constant (zero variance over {len} \
         samples), so the NRMSE (78) is undefined"
    )]
    ConstantSignal {
        /// Row group (joint) index.
        group: usize,
        /// Number of samples.
        len: usize,
    },
}

/// Checks that every entry of a column-major view is finite.
pub(crate) fn check_finite_mat(
    what: &'static str,
    m: faer::MatRef<'_, f64>,
    names: &[String],
) -> Result<(), IdentError> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            let v = m[(i, j)];
            if !v.is_finite() {
                return Err(IdentError::NonFinite {
                    what,
                    row: i,
                    column: j,
                    name: names.get(j).cloned().unwrap_or_default(),
                    value: v,
                });
            }
        }
    }
    Ok(())
}

/// Checks that every entry of a vector is finite.
pub(crate) fn check_finite_vec(what: &'static str, v: &[f64]) -> Result<(), IdentError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(IdentError::NonFinite {
            what,
            row: i,
            column: 0,
            name: String::new(),
            value: v[i],
        }),
        None => Ok(()),
    }
}
