//! The coordinates a model is written in, computed from the joint motion.
//!
//! Processing works on what the encoders measure, joint angles `θ` and their
//! derivatives. A model may be written in other coordinates (ARAS-Diamond's
//! dynamics use the task pose `X = [φ, γ]`); the caller says how to get them,
//! so this crate knows no robot.

use std::convert::Infallible;

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, U2};

pub use aras_core::Motion;

/// Maps joint motion `[θ, θ̇, θ̈]` to the model's coordinates `[X, Ẋ, Ẍ]`,
/// both of dimension `D` (two by default; [`nalgebra::Dyn`] for a number of
/// joints known at run time).
///
/// Implemented by [`JointCoordinates`] (the model is written in joint
/// coordinates, any dimension) and by every closure
/// `Fn(Motion<f64, D>) -> Result<Motion<f64, D>, E>`, e.g. a robot's
/// forward kinematics with their derivatives. `Sync`, so that the
/// processing maps a long log's samples on every core.
pub trait Coordinates<D: Dim = U2>: Sync
where
    DefaultAllocator: Allocator<D>,
{
    /// Why a sample cannot be mapped (e.g. an unreachable or singular pose).
    type Error: std::error::Error + Send + Sync + 'static;

    /// `[X, Ẋ, Ẍ]` of the joint motion `[θ, θ̇, θ̈]`.
    fn map(&self, joint: Motion<f64, D>) -> Result<Motion<f64, D>, Self::Error>;

    /// True if [`map`](Self::map) is the identity, so the processing copies
    /// the joint columns instead of mapping sample by sample.
    fn is_identity(&self) -> bool {
        false
    }
}

/// The identity: the model's coordinates are the joint angles.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct JointCoordinates;

impl<D: Dim> Coordinates<D> for JointCoordinates
where
    DefaultAllocator: Allocator<D>,
{
    type Error = Infallible;

    fn map(&self, joint: Motion<f64, D>) -> Result<Motion<f64, D>, Infallible> {
        Ok(joint)
    }

    fn is_identity(&self) -> bool {
        true
    }
}

impl<F, E, D: Dim> Coordinates<D> for F
where
    F: Fn(Motion<f64, D>) -> Result<Motion<f64, D>, E> + Sync,
    E: std::error::Error + Send + Sync + 'static,
    DefaultAllocator: Allocator<D>,
{
    type Error = E;

    fn map(&self, joint: Motion<f64, D>) -> Result<Motion<f64, D>, E> {
        self(joint)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_coordinates_are_the_identity_and_closures_map() {
        let m = Motion::from_arrays([[0.1, -0.2], [1.0, 2.0], [-3.0, 4.0]]);
        assert_eq!(Coordinates::<U2>::map(&JointCoordinates, m).unwrap(), m);
        assert!(Coordinates::<U2>::is_identity(&JointCoordinates));
        let doubled = |m: Motion| -> Result<Motion, Infallible> {
            Ok(Motion::new(m.pos * 2.0, m.vel * 2.0, m.acc * 2.0))
        };
        assert_eq!(
            doubled.map(m).unwrap().acc,
            nalgebra::Vector2::new(-6.0, 8.0)
        );
        assert!(!doubled.is_identity());
    }
}
