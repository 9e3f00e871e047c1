//! Quadratic damping, parameters `Fq1, Fq2`, columns `θ̇_j |θ̇_j|`. Least
//! squares fits the sign free; the physically consistent fit keeps it ≥ 0
//! (`τ θ̇ = Fq |θ̇|³` dissipates only then).

use aras_kin::{KinematicSample, Scalar};

use super::diagonal;

/// Parameter names in column order.
pub(crate) const NAMES: [&str; 2] = ["Fq1", "Fq2"];

/// Parameters that must not be negative (dissipation).
pub(super) const NONNEGATIVE: &[&str] = &NAMES;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "damping growing with the square of the speed (fluid or air \
    drag, windage, velocity-dependent seal friction); the residual grows faster than linearly \
    with |θ̇| and keeps its sign";

/// Columns `θ̇_j |θ̇_j|` on each joint's row.
#[inline(always)]
pub(super) fn fill<T: Scalar>(s: &KinematicSample<T>, out: &mut [T]) {
    let td = s.joint.vel;
    diagonal(td[0] * td[0].abs(), td[1] * td[1].abs(), out);
}
