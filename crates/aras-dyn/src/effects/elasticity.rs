//! Capstan elasticity, (50): `τ_e = K_e θ` per actuator, parameters
//! `Ke1, Ke2`. Physical constraint (70): ≥ 0 (a spring stores energy).

use aras_kin::{KinematicSample, Scalar};

use super::diagonal;

/// Parameter names in column order.
pub(crate) const NAMES: [&str; 2] = ["Ke1", "Ke2"];

/// Parameters that must not be negative, (70).
pub(super) const NONNEGATIVE: &[&str] = &NAMES;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "the capstan cables act as springs: a torque proportional \
    to each motor angle, (50)";

/// Columns `θ1` and `θ2` on their joints' rows.
#[inline(always)]
pub(super) fn fill<T: Scalar>(s: &KinematicSample<T>, out: &mut [T]) {
    diagonal(s.joint.pos[0], s.joint.pos[1], out);
}
