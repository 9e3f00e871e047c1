//! Typed errors of the kinematics.

use crate::Singularity;

/// Everything that can go wrong when evaluating the kinematics.
///
/// Every variant names the offending value and the limit it violated, so a
/// caller can print it as-is. Angles in messages are in degrees because that
/// is how people read them; the fields themselves are in radians.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum KinError {
    /// An input was NaN or infinite.
    #[error("{name} is not finite ({value}); every input must be a finite number")]
    NonFinite {
        /// Name of the input (e.g. `"gamma"`, `"phi_dot"`).
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A geometry angle is outside the open interval (0, π).
    #[error(
        "geometry angle {name} = {deg:.6}° is invalid: it must lie strictly between 0° and 180°",
        deg = value.to_degrees()
    )]
    InvalidGeometry {
        /// `"alpha"` or `"beta"`.
        name: &'static str,
        /// The offending value (rad).
        value: f64,
    },
    /// The singularity tolerance is not in (0, 1).
    #[error("singularity tolerance {value} is invalid: it must lie strictly between 0 and 1")]
    InvalidTolerance {
        /// The offending value.
        value: f64,
    },
    /// The polar angle γ cannot be reached by any assembly of the arcs.
    #[error(
        "gamma = {g:.6}° is unreachable: the arcs reach only {lo:.6}° < gamma < {hi:.6}°",
        g = gamma.to_degrees(), lo = min.to_degrees(), hi = max.to_degrees()
    )]
    Unreachable {
        /// Requested polar angle (rad).
        gamma: f64,
        /// Smallest reachable polar angle |α − β| (rad).
        min: f64,
        /// Largest reachable polar angle α + β (rad).
        max: f64,
    },
    /// The joint angles admit no assembly of the distal links.
    #[error(
        "joint angles theta1 = {t1:.6}°, theta2 = {t2:.6}° cannot be assembled: the elbows are \
         {sep:.6}° apart but the distal arcs reach at most {reach:.6}°",
        t1 = theta1.to_degrees(), t2 = theta2.to_degrees(),
        sep = separation.to_degrees(), reach = reach.to_degrees()
    )]
    NoAssembly {
        /// Motor angle θ1 (rad).
        theta1: f64,
        /// Motor angle θ2 (rad).
        theta2: f64,
        /// Arc distance between the elbow axes b and c (rad).
        separation: f64,
        /// Largest elbow separation the distal arcs can close, 2β (rad).
        reach: f64,
    },
    /// The pose is at, or closer than the tolerance to, a singularity.
    #[error("pose is singular: {which} = {value:.3e} is below the tolerance {limit:.3e}")]
    Singular {
        /// Which singularity.
        which: Singularity,
        /// The measured distance (a sine or |K|, dimensionless).
        value: f64,
        /// The tolerance it fell below.
        limit: f64,
    },
    /// The pose or velocity lies outside the configured workspace box (77).
    #[error(
        "{name} = {v:.6}{unit} is outside the workspace [{lo:.6}{unit}, {hi:.6}{unit}] (the paper's (77))",
        v = value.to_degrees(), lo = min.to_degrees(), hi = max.to_degrees()
    )]
    OutsideWorkspace {
        /// `"phi"`, `"gamma"`, `"phi_dot"` or `"gamma_dot"`.
        name: &'static str,
        /// Unit suffix for the message (`"°"` or `"°/s"`).
        unit: &'static str,
        /// The value (rad or rad/s).
        value: f64,
        /// Lower limit (rad or rad/s).
        min: f64,
        /// Upper limit (rad or rad/s).
        max: f64,
    },
}
