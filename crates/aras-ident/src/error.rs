//! The crate's error type and the SDP solver's status.

use std::fmt;

use serde::Serialize;
use thiserror::Error;

use crate::linalg::NoConvergence;

/// Everything that can go wrong in identification. Every message says what
/// was wrong, where, and how to fix it.
///
/// A variant with an underlying error returns it from
/// [`source`](std::error::Error::source) and does not repeat it in its own
/// message, so printing the chain (`error: …`, `caused by: …`) shows each
/// cause once.
#[derive(Debug, Error)]
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
        /// What the solver reported.
        status: SolverStatus,
    },
    /// The SDP solver stopped without a usable solution.
    #[error(
        "the SDP solver stopped with status {status} after {iterations} iterations; try a looser \
         tolerance, more iterations, or check the regressor's scaling"
    )]
    SolverFailed {
        /// What the solver reported.
        status: SolverStatus,
        /// Iterations done.
        iterations: u32,
    },
    /// The SDP solver rejected its settings or the problem's data before
    /// iterating.
    #[error(
        "the SDP solver could not be set up ({stage}); check the SDP settings (tolerance, \
         iteration and time limits) for non-finite or non-positive values"
    )]
    SolverSetup {
        /// `"settings"` or `"problem data"`.
        stage: &'static str,
        /// The solver's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// A matrix factorisation did not converge.
    #[error(transparent)]
    NoConvergence(#[from] NoConvergence),
    /// An error from outside identification, kept as the source: the
    /// model's evaluation (a [`LinearModel`](crate::LinearModel)'s error), or
    /// the code that feeds it (reading, filtering, the kinematics).
    #[error("{context}")]
    External {
        /// What was being done, e.g. the sample's index.
        context: String,
        /// The underlying error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// Input data that cannot be used (e.g. a non-finite torque), named with
    /// where they were found.
    #[error("{context}: {reason}")]
    InvalidData {
        /// Where, e.g. the sample's index.
        context: String,
        /// What is wrong and how to fix it.
        reason: String,
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

impl IdentError {
    /// [`IdentError::External`] with `context` (what was being done) and the
    /// underlying error.
    pub fn external(
        context: impl Into<String>,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Self::External {
            context: context.into(),
            source: Box::new(source),
        }
    }
}

/// How the SDP solver (clarabel) ended; the names are the solver's own.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[non_exhaustive]
pub enum SolverStatus {
    /// The solver has not run.
    Unsolved,
    /// Solved to the requested tolerance.
    Solved,
    /// Solved to a reduced accuracy.
    AlmostSolved,
    /// The constraints admit no solution (certificate found).
    PrimalInfeasible,
    /// The objective is unbounded below (certificate found).
    DualInfeasible,
    /// Primal infeasible, to a reduced accuracy.
    AlmostPrimalInfeasible,
    /// Dual infeasible, to a reduced accuracy.
    AlmostDualInfeasible,
    /// The iteration limit was reached.
    MaxIterations,
    /// The time limit was reached.
    MaxTime,
    /// A numerical error stopped the solver.
    NumericalError,
    /// The solver stopped making progress.
    InsufficientProgress,
    /// A user callback stopped the solver.
    CallbackTerminated,
}

impl SolverStatus {
    /// The status's name as the solver spells it (e.g. `"AlmostSolved"`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Unsolved => "Unsolved",
            Self::Solved => "Solved",
            Self::AlmostSolved => "AlmostSolved",
            Self::PrimalInfeasible => "PrimalInfeasible",
            Self::DualInfeasible => "DualInfeasible",
            Self::AlmostPrimalInfeasible => "AlmostPrimalInfeasible",
            Self::AlmostDualInfeasible => "AlmostDualInfeasible",
            Self::MaxIterations => "MaxIterations",
            Self::MaxTime => "MaxTime",
            Self::NumericalError => "NumericalError",
            Self::InsufficientProgress => "InsufficientProgress",
            Self::CallbackTerminated => "CallbackTerminated",
        }
    }

    /// True for a usable solution ([`Solved`](Self::Solved) or
    /// [`AlmostSolved`](Self::AlmostSolved)).
    pub fn is_solved(self) -> bool {
        matches!(self, Self::Solved | Self::AlmostSolved)
    }
}

impl fmt::Display for SolverStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
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
