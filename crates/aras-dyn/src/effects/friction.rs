//! Viscous + Coulomb friction per actuator, (49): `τ_f = Fv θ̇ + Fc sign(θ̇)`,
//! parameters `Fv1, Fc1, Fv2, Fc2`. Physical constraint (70): all ≥ 0
//! (friction dissipates).

use aras_kin::{KinematicSample, Scalar};

use crate::Sign;

/// Parameter names in column order.
pub(crate) const NAMES: [&str; 4] = ["Fv1", "Fc1", "Fv2", "Fc2"];

/// Parameters that must not be negative, (70).
pub(super) const NONNEGATIVE: &[&str] = &NAMES;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "friction in the motors, capstans and active bearings: a \
    part proportional to the motor rate (viscous) and a constant level opposing the motion \
    (Coulomb), (49)";

/// Columns `[θ̇1, sign θ̇1]` on joint 1's row, `[θ̇2, sign θ̇2]` on joint 2's.
#[inline(always)]
pub(super) fn fill<T: Scalar>(s: &KinematicSample<T>, sign: Sign, out: &mut [T]) {
    let (z, td) = (T::zero(), s.joint.vel);
    out.copy_from_slice(&[td[0], z, sign.eval(td[0]), z, z, td[1], z, sign.eval(td[1])]);
}
