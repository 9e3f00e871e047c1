//! The coordinates a model is written in, computed from the joint motion.
//!
//! Processing works on what the encoders measure, joint angles `θ` and their
//! derivatives. A model may be written in other coordinates (ARAS-Diamond's
//! dynamics use the task pose `X = [φ, γ]`); the caller says how to get them,
//! so this crate knows no robot.

use std::convert::Infallible;

pub use aras_core::Motion;

/// Maps joint motion `[θ, θ̇, θ̈]` to the model's coordinates `[X, Ẋ, Ẍ]`.
///
/// Implemented by [`JointCoordinates`] (the model is written in joint
/// coordinates) and by every closure `Fn(Motion) -> Result<Motion, E>`, e.g.
/// a robot's forward kinematics with their derivatives.
pub trait Coordinates {
    /// Why a sample cannot be mapped (e.g. an unreachable or singular pose).
    type Error: std::error::Error + Send + Sync + 'static;

    /// `[X, Ẋ, Ẍ]` of the joint motion `[θ, θ̇, θ̈]`.
    fn map(&self, joint: Motion) -> Result<Motion, Self::Error>;
}

/// The identity: the model's coordinates are the joint angles.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct JointCoordinates;

impl Coordinates for JointCoordinates {
    type Error = Infallible;

    fn map(&self, joint: Motion) -> Result<Motion, Infallible> {
        Ok(joint)
    }
}

impl<F, E> Coordinates for F
where
    F: Fn(Motion) -> Result<Motion, E>,
    E: std::error::Error + Send + Sync + 'static,
{
    type Error = E;

    fn map(&self, joint: Motion) -> Result<Motion, E> {
        self(joint)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_coordinates_are_the_identity_and_closures_map() {
        let m = Motion::from_arrays([[0.1, -0.2], [1.0, 2.0], [-3.0, 4.0]]);
        assert_eq!(JointCoordinates.map(m).unwrap(), m);
        let doubled = |m: Motion| -> Result<Motion, Infallible> {
            Ok(Motion::new(m.pos * 2.0, m.vel * 2.0, m.acc * 2.0))
        };
        assert_eq!(
            doubled.map(m).unwrap().acc,
            nalgebra::Vector2::new(-6.0, 8.0)
        );
    }
}
