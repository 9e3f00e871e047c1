//! Direction-dependent Coulomb level, parameters `Fca1, Fca2`, columns
//! `|sign θ̇_j|` (1 while moving, 0 at rest). While the joint moves this is
//! indistinguishable from a torque offset; the two differ only at rest. No
//! sign constraint: either direction may be the stiffer one.

use aras_kin::{KinematicSample, Scalar};

use super::diagonal;
use crate::Sign;

/// Parameter names in column order.
pub(crate) const NAMES: [&str; 2] = ["Fca1", "Fca2"];

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "the Coulomb friction level differs between the two \
    directions of motion (capstan cable pre-tension, seal or bearing asymmetry); while the joint \
    moves it acts like an offset, at rest it vanishes";

/// Columns `|sign θ̇_j|` on each joint's row.
#[inline(always)]
pub(super) fn fill<T: Scalar>(s: &KinematicSample<T>, sign: Sign, out: &mut [T]) {
    let td = s.joint.vel;
    diagonal(sign.eval(td[0]).abs(), sign.eval(td[1]).abs(), out);
}
