//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in friction modelling. Every message says what
/// was wrong, where, and how to fix it.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum FrictionError {
    /// Two series that must have one value per sample differ in length.
    #[error("{what}: expected {expected} values (one per sample), found {found}")]
    LengthMismatch {
        /// Which series.
        what: &'static str,
        /// Number of samples.
        expected: usize,
        /// Number of values given.
        found: usize,
    },
    /// A stored effect whose coefficient count is not its column count
    /// (an edited or damaged model file).
    #[error(
        "effect `{effect}` has {found} coefficients but {expected} columns; the model file was \
         edited or damaged: write it again with `aras friction`"
    )]
    EffectCoefficients {
        /// The effect's identifier.
        effect: String,
        /// Its number of columns.
        expected: usize,
        /// Coefficients given.
        found: usize,
    },
    /// A model with a load-dependent friction term applied to a log without
    /// a load column.
    #[error(
        "log `{log}` has no `load` column, but the model's friction grows with the load torque: \
         log the torque the joint carries as `load` (or map a column to it, e.g. `load=tau_rb`)"
    )]
    MissingLoad {
        /// The log's name.
        log: String,
    },
    /// A NaN or infinity in an input series.
    #[error("{what} has a non-finite value {value} at sample {index}; remove or repair the sample")]
    NonFinite {
        /// Which series.
        what: &'static str,
        /// 0-based sample index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// Time stamps that do not strictly increase.
    #[error(
        "time does not increase at sample {index}: t = {previous} s, then {value} s; \
         sort the log by time and drop duplicate time stamps"
    )]
    TimeNotIncreasing {
        /// 0-based index of the sample whose time is not after its predecessor.
        index: usize,
        /// Previous time stamp, s.
        previous: f64,
        /// This time stamp, s.
        value: f64,
    },
    /// The joint does not move enough for friction to be identified.
    #[error(
        "the joint never moves: q spans {range:.2e} rad and |dq| reaches {speed:.2e} rad/s (at least \
         {min_travel:e} rad of travel is needed); friction is identified from motion: log a run \
         in which the joint moves, in both directions"
    )]
    NoMotion {
        /// Range of the position, rad.
        range: f64,
        /// Largest |velocity|, rad/s.
        speed: f64,
        /// The travel needed, rad.
        min_travel: f64,
    },
    /// Too few samples for the requested operation.
    #[error("{what}: {found} samples, at least {needed} are needed")]
    TooFewSamples {
        /// Which operation.
        what: &'static str,
        /// Samples given.
        found: usize,
        /// Minimum number of samples.
        needed: usize,
    },
    /// A parameter vector of the wrong length.
    #[error("{model}: {found} parameters given, the model has {expected} ({names})")]
    ParameterCount {
        /// Model name.
        model: &'static str,
        /// Number of parameters of the model.
        expected: usize,
        /// Number given.
        found: usize,
        /// The model's parameter names, in order.
        names: String,
    },
    /// A parameter outside its physical range.
    #[error("{model}: parameter {name} = {value} is outside its physical range [{lower}, {upper}]")]
    ParameterOutOfRange {
        /// Model name.
        model: &'static str,
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// No start of the search gave a usable fit.
    #[error(
        "{model}: no start gave a usable fit (the regressor columns are dependent everywhere); \
         the log may not move the joint or the torque may be constant"
    )]
    NoFit {
        /// Which model.
        model: &'static str,
    },
}
