//! Typed errors: parameter files ([`ParamError`]), dynamics ([`DynError`])
//! and the simulator ([`SimError`]).
//!
//! A variant with an underlying error either returns it from
//! [`source`](std::error::Error::source) without repeating it in its own
//! message, or is transparent (shows and returns the underlying error's
//! message and source), so printing the chain shows each cause once.

use std::path::PathBuf;

use aras_kin::KinError;

/// A parameter file or [`Params`](crate::Params) value is not acceptable.
///
/// Keys are given as paths into the JSON object, e.g. `links.3.Ixy` or
/// `gravity[1]`, so a user can find the entry to fix.
#[derive(Debug, thiserror::Error)]
pub enum ParamError {
    /// The text is not valid JSON.
    #[error("invalid JSON at line {line}, column {column}: {message}; fix the syntax there")]
    Syntax {
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// The parser's description.
        message: String,
    },
    /// A required key is absent.
    #[error("missing key `{key}`: add it ({expected})")]
    Missing {
        /// Path of the missing key.
        key: String,
        /// What the key should hold.
        expected: &'static str,
    },
    /// A key that the format does not define.
    #[error("unknown key `{key}`: remove or rename it; allowed here: {allowed}")]
    Unknown {
        /// Path of the unexpected key.
        key: String,
        /// The keys allowed at that level, comma separated.
        allowed: String,
    },
    /// A value of the wrong JSON type.
    #[error("`{key}` must be {expected}, found {found}")]
    WrongType {
        /// Path of the value.
        key: String,
        /// What was expected.
        expected: &'static str,
        /// A short rendering of what was found.
        found: String,
    },
    /// A number that is NaN or infinite.
    #[error("`{key}` = {value} is not finite: every parameter must be a finite number")]
    NonFinite {
        /// Path of the value.
        key: String,
        /// The offending value.
        value: f64,
    },
    /// A finite value outside its admissible range.
    #[error("`{key}` = {value} is invalid: {reason}")]
    Invalid {
        /// Path of the value.
        key: String,
        /// The offending value.
        value: f64,
        /// The rule it broke and how to fix it.
        reason: &'static str,
    },
    /// A link's inertial parameters are not physically consistent,
    /// (67)–(69): acceptable for an OLS estimate, not where a real body is
    /// required (the SDP's reference, a simulated robot, `validate`).
    #[error(
        "link {link} is not physically consistent: {reason}; the links' pseudo-inertias must be \
         positive definite (the paper's (67)–(69)): check the sign and units (kg, kg·m, kg·m²) of \
         `links.{link}`, or use the physically consistent estimate (params.json of `identify`)"
    )]
    NotPhysical {
        /// Link number (1–4).
        link: usize,
        /// What is wrong, with the offending numbers.
        reason: String,
    },
    /// A friction, damping or stiffness coefficient below zero: such a
    /// term feeds energy into the robot, which no real joint does.
    #[error(
        "`{key}` = {value} is negative: friction, damping and stiffness coefficients must be \
         ≥ 0 (a negative one feeds energy into the robot); fix the file, or use the physically \
         consistent estimate (params.json of `identify`, whose fit enforces the sign)"
    )]
    NegativeCoefficient {
        /// Path of the value, e.g. `friction.Fc1`.
        key: String,
        /// The offending value.
        value: f64,
    },
    /// The file could not be read or written.
    #[error("cannot access parameter file {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// An error inside a named file.
    #[error("in parameter file {}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What was wrong in it.
        source: Box<ParamError>,
    },
}

/// Errors of the model, regressor and dynamics.
#[derive(Debug, thiserror::Error)]
pub enum DynError {
    /// The kinematics rejected the pose or its rates.
    #[error(transparent)]
    Kin(#[from] KinError),
    /// The parameters are not acceptable.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A buffer or vector has the wrong length for the model.
    #[error(
        "{what} has length {found}, but the model needs {expected}; size it with Model::columns()"
    )]
    Length {
        /// Which argument.
        what: &'static str,
        /// Length required by the model.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// The same effect appears twice in a model.
    #[error("effect `{id}` appears twice in the model; list every effect once")]
    DuplicateEffect {
        /// The repeated effect identifier.
        id: &'static str,
    },
    /// A model with an effect that has an internal state was evaluated one
    /// sample at a time.
    #[error(
        "effect `{id}` has an internal state that depends on the samples before, so one \
         sample's regressor cannot hold it: evaluate the model along the whole sequence \
         (`Model::stacked`), or leave the effect out of this use"
    )]
    StatefulEffect {
        /// The effect identifier.
        id: &'static str,
    },
    /// An effect setting is out of range.
    #[error("effect `{id}`: setting `{setting}` = {value} is invalid: {reason}")]
    InvalidSetting {
        /// The effect identifier.
        id: &'static str,
        /// The setting's name.
        setting: &'static str,
        /// The offending value.
        value: f64,
        /// The rule it broke.
        reason: &'static str,
    },
    /// The parameters hold an effect with other settings than the model's.
    #[error(
        "effect `{id}`: the parameters use {setting} = {params_value} but the model uses \
         {model_value}; use the same setting in both"
    )]
    SettingMismatch {
        /// The effect identifier.
        id: &'static str,
        /// The setting's name.
        setting: &'static str,
        /// Value in the parameters.
        params_value: f64,
        /// Value in the model.
        model_value: f64,
    },
    /// The mass matrix is not positive definite (inconsistent parameters).
    #[error(
        "mass matrix is not positive definite at phi = {phi_deg:.4}°, gamma = {gamma_deg:.4}° \
         (determinant {det:.3e}, M11 {m11:.3e}); the inertial parameters are not physically consistent"
    )]
    NotPositiveDefinite {
        /// φ of the pose (degrees).
        phi_deg: f64,
        /// γ of the pose (degrees).
        gamma_deg: f64,
        /// det M.
        det: f64,
        /// `M[0,0]`.
        m11: f64,
    },
    /// An input was not finite.
    #[error("{name} = {value} is not finite; every input must be a finite number")]
    NonFinite {
        /// Name of the input.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
}

/// Errors of the simulator and the log writer.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A configuration value is out of range.
    #[error("simulator setting `{key}` = {value} is invalid: {reason}")]
    Config {
        /// The setting's name.
        key: &'static str,
        /// The offending value.
        value: f64,
        /// The rule it broke and how to fix it.
        reason: &'static str,
    },
    /// The dynamics failed during the run (e.g. the robot left the reachable
    /// workspace or hit a singularity).
    #[error("simulation failed at t = {t:.6} s")]
    Dynamics {
        /// Simulated time of the failure (s).
        t: f64,
        /// The underlying error.
        source: DynError,
    },
    /// The LuGre bristle relaxes faster than the RK4 step can follow
    /// (`h σ0 |θ̇| / g(θ̇)` above 2.5).
    #[error(
        "LuGre friction is too stiff for the integration step at t = {t:.6} s \
         (h·σ0·|θ̇|/g = {ratio:.2} > 2.5): raise `substeps` or lower `lugre.stiffness`"
    )]
    StiffFriction {
        /// Simulated time (s).
        t: f64,
        /// `h σ0 |θ̇| / g(θ̇)` of the step.
        ratio: f64,
    },
    /// The desired trajectory is not evaluable.
    #[error("the desired trajectory cannot be evaluated at t = {t:.6} s")]
    Trajectory {
        /// Time of the failure (s).
        t: f64,
        /// The underlying error.
        source: DynError,
    },
    /// Writing the log failed (the format's writer says which file and why).
    #[error("cannot write the simulated log")]
    Write {
        /// The writer's error.
        #[from]
        source: aras_log::LogError,
    },
}
