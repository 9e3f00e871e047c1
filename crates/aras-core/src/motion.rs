//! One sample of motion of any number of coordinates.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, Dyn, OVector, Scalar, U1, U2};

/// Position, rate and acceleration of `D` coordinates at one instant.
///
/// The coordinates are the caller's: a task pose `X = [φ, γ]` (rad) with
/// `Ẋ` (rad/s) and `Ẍ` (rad/s²), or joint angles `θ, θ̇, θ̈` (rad, or m
/// for a prismatic joint). The dimension is a type, as in nalgebra: two
/// coordinates by default (ARAS-Diamond; fixed-size, no allocation), any
/// fixed `Const<N>`, or [`Dyn`] for a robot whose joints are known only at
/// run time ([`DMotion`]). Generic over the number type so that
/// forward-mode dual numbers carry derivatives through it; `f64` by
/// default.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion<T: Scalar = f64, D: Dim = U2>
where
    DefaultAllocator: Allocator<D>,
{
    /// Position (rad).
    pub pos: OVector<T, D>,
    /// Rate (rad/s).
    pub vel: OVector<T, D>,
    /// Acceleration (rad/s²).
    pub acc: OVector<T, D>,
}

/// A motion whose number of coordinates is known at run time.
pub type DMotion<T = f64> = Motion<T, Dyn>;

impl<T: Scalar + Copy> Copy for Motion<T, U2> {}

impl<T: Scalar + Default> Default for Motion<T, U2> {
    fn default() -> Self {
        let z = || OVector::<T, U2>::from_element(T::default());
        Self::new(z(), z(), z())
    }
}

impl<T: Scalar, D: Dim> Motion<T, D>
where
    DefaultAllocator: Allocator<D>,
{
    /// A motion from its position, rate and acceleration.
    pub const fn new(pos: OVector<T, D>, vel: OVector<T, D>, acc: OVector<T, D>) -> Self {
        Self { pos, vel, acc }
    }

    /// Number of coordinates.
    pub fn dim(&self) -> usize {
        self.pos.len()
    }
}

impl<D: Dim> Motion<f64, D>
where
    DefaultAllocator: Allocator<D>,
{
    /// The motionless state of `dim` coordinates at zero (`dim` is checked
    /// against a fixed `D`: a mismatch panics, as nalgebra's constructors).
    pub fn zeros_generic(dim: D) -> Self {
        let z = || OVector::<f64, D>::zeros_generic(dim, U1);
        Self::new(z(), z(), z())
    }

    /// True if every entry is finite.
    pub fn is_finite(&self) -> bool {
        [&self.pos, &self.vel, &self.acc]
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()))
    }
}

impl DMotion<f64> {
    /// The motionless state of `dim` coordinates at zero.
    pub fn zeros(dim: usize) -> Self {
        Self::zeros_generic(Dyn(dim))
    }

    /// A motion from slices `q, q̇, q̈` of equal length.
    ///
    /// # Panics
    /// If the lengths differ.
    pub fn from_slices(pos: &[f64], vel: &[f64], acc: &[f64]) -> Self {
        assert!(
            pos.len() == vel.len() && vel.len() == acc.len(),
            "Motion::from_slices: q, q̇, q̈ of lengths {}, {}, {}",
            pos.len(),
            vel.len(),
            acc.len()
        );
        let v = |s: &[f64]| OVector::<f64, Dyn>::from_column_slice(s);
        Self::new(v(pos), v(vel), v(acc))
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

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

    #[test]
    fn a_run_time_dimension_holds_any_number_of_coordinates() {
        let m = DMotion::from_slices(&[0.1, 0.2, 0.3], &[1.0, 2.0, 3.0], &[0.0; 3]);
        assert_eq!(m.dim(), 3);
        assert_eq!(m.vel.as_slice(), &[1.0, 2.0, 3.0]);
        assert!(m.is_finite());
        let mut z = DMotion::zeros(7);
        assert_eq!((z.dim(), z.pos.sum()), (7, 0.0));
        z.acc[6] = f64::INFINITY;
        assert!(!z.is_finite());
        // The default stays two fixed coordinates, Copy.
        let two = Motion::<f64>::default();
        let copy = two;
        assert_eq!((two.dim(), copy), (2, two));
    }
}
