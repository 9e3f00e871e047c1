//! The number type the kinematics are evaluated in.

use nalgebra::RealField;

/// A real scalar the kinematics (and anything built on them) can run on.
///
/// `f64` for ordinary evaluation. With the `dual` feature, the forward-mode
/// dual numbers of `num-dual` too, so a caller can get exact derivatives of
/// every kinematic quantity with respect to the inputs (used by the
/// excitation design for exact gradients). Limits and error messages always
/// use the real part, [`Scalar::value`].
pub trait Scalar: RealField + Copy {
    /// The real part (for comparisons against limits and for messages).
    fn value(self) -> f64;

    /// Lifts a constant.
    fn lift(v: f64) -> Self;
}

impl Scalar for f64 {
    #[inline(always)]
    fn value(self) -> f64 {
        self
    }

    #[inline(always)]
    fn lift(v: f64) -> Self {
        v
    }
}

#[cfg(feature = "dual")]
mod dual {
    use super::Scalar;
    use num_dual::{Dual64, DualSVec64};

    impl Scalar for Dual64 {
        fn value(self) -> f64 {
            self.re
        }

        fn lift(v: f64) -> Self {
            Dual64::from(v)
        }
    }

    impl<const N: usize> Scalar for DualSVec64<N>
    where
        Self: nalgebra::RealField + Copy,
    {
        fn value(self) -> f64 {
            self.re
        }

        fn lift(v: f64) -> Self {
            DualSVec64::from(v)
        }
    }
}
