//! One sample of motion of two coordinates.

use nalgebra::{Scalar, Vector2};

/// Position, rate and acceleration of two coordinates at one instant.
///
/// The coordinates are the caller's: a task pose `X = [φ, γ]` (rad) with
/// `Ẋ` (rad/s) and `Ẍ` (rad/s²), or joint angles `θ, θ̇, θ̈`. Generic over
/// the number type so that forward-mode dual numbers carry derivatives
/// through it; `f64` by default.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion<T: Scalar = f64> {
    /// Position (rad).
    pub pos: Vector2<T>,
    /// Rate (rad/s).
    pub vel: Vector2<T>,
    /// Acceleration (rad/s²).
    pub acc: Vector2<T>,
}

impl<T: Scalar> Motion<T> {
    /// A motion from its position, rate and acceleration.
    pub const fn new(pos: Vector2<T>, vel: Vector2<T>, acc: Vector2<T>) -> Self {
        Self { pos, vel, acc }
    }
}

impl Motion<f64> {
    /// A motion from plain arrays `[q, q̇, q̈]`, each `[q1, q2]`.
    pub fn from_arrays([pos, vel, acc]: [[f64; 2]; 3]) -> Self {
        Self::new(pos.into(), vel.into(), acc.into())
    }

    /// The motion as plain arrays `[q, q̇, q̈]`, each `[q1, q2]`.
    pub fn to_arrays(&self) -> [[f64; 2]; 3] {
        [self.pos.into(), self.vel.into(), self.acc.into()]
    }

    /// True if every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.to_arrays().iter().flatten().all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_round_trip_and_finiteness_is_checked_on_every_entry() {
        let a = [[0.1, -0.2], [1.0, 2.0], [-3.0, 4.0]];
        let m = Motion::from_arrays(a);
        assert_eq!(m.to_arrays(), a);
        assert_eq!(m.vel, Vector2::new(1.0, 2.0));
        assert!(m.is_finite());
        for k in 0..6 {
            let mut b = a;
            b[k / 2][k % 2] = f64::NAN;
            assert!(!Motion::from_arrays(b).is_finite(), "entry {k}");
        }
    }
}
