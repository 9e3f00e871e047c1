//! Stribeck friction, parameters `Fs1, Fs2`, columns
//! `sign(θ̇_j) exp(−(θ̇_j/v_s)²)` with the shape velocity `v_s` (rad/s, > 0,
//! a non-linear setting of the effect). Least squares fits the level above
//! Coulomb with its sign left free, so a fit can also say the low-speed
//! friction is lower than Coulomb; the physically consistent fit keeps it
//! ≥ 0, the breakaway hump the effect describes.

use aras_kin::{KinematicSample, Scalar};

use super::diagonal;
use crate::{DynError, Sign};

/// Parameter names in column order.
pub(crate) const NAMES: [&str; 2] = ["Fs1", "Fs2"];

/// Parameters the physically consistent fit keeps non-negative.
pub(super) const NONNEGATIVE: &[&str] = &NAMES;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "friction rises above the Coulomb level at low speed and \
    decays with the Stribeck velocity v_s (boundary lubrication); the residual peaks, with the \
    sign of the velocity, just after each velocity reversal";

/// Errors unless `v_s` is a positive number of rad/s.
pub(super) fn validate(v_s: f64) -> Result<(), DynError> {
    if v_s.is_finite() && v_s > 0.0 {
        Ok(())
    } else {
        Err(DynError::InvalidSetting {
            id: "stribeck_friction",
            setting: "v_s",
            value: v_s,
            reason: "the Stribeck velocity must be a positive number of rad/s",
        })
    }
}

/// Columns `sign(θ̇_j) exp(−(θ̇_j/v_s)²)` on each joint's row.
#[inline(always)]
pub(super) fn fill<T: Scalar>(s: &KinematicSample<T>, v_s: f64, sign: Sign, out: &mut [T]) {
    let f = |v: T| {
        let q = v / T::lift(v_s);
        sign.eval(v) * (-(q * q)).exp()
    };
    diagonal(f(s.joint.vel[0]), f(s.joint.vel[1]), out);
}
