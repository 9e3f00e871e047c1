//! A constant torque offset per actuator, parameters `tau0_1, tau0_2`. No
//! sign constraint: a bias has either sign.

use aras_kin::Scalar;

use super::diagonal;

/// Parameter names in column order.
pub(crate) const NAMES: [&str; 2] = ["tau0_1", "tau0_2"];

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "a constant torque bias per motor: current-sensor or \
    amplifier offset, or a cable or counterweight load that does not depend on the pose; the \
    residual is shifted by the same amount everywhere";

/// Columns of ones on each joint's row.
#[inline(always)]
pub(super) fn fill<T: Scalar>(out: &mut [T]) {
    diagonal(T::one(), T::one(), out);
}
