//! Viscous friction in the passive hinges about `b`, `c`, `d`, parameters
//! `Fpb, Fpc, Fpd`. The hinges' relative angular velocities (`Ω3 − Ω1`,
//! `Ω4 − Ω2`, `Ω3 − Ω4`) are mapped to the motors by virtual work: column
//! `J⁻ᵀ (J_ωi − J_ωj)ᵀ (Ω_i − Ω_j)`. Least squares fits the coefficients
//! with their sign free (a negative one flags a misfit rather than being
//! clipped); the physically consistent fit keeps them ≥ 0 (a hinge's
//! viscous friction dissipates).

use aras_kin::{KinematicSample, Scalar};

/// Parameter names in column order.
pub(crate) const NAMES: [&str; 3] = ["Fpb", "Fpc", "Fpd"];

/// Parameters that must not be negative (dissipation).
pub(super) const NONNEGATIVE: &[&str] = &NAMES;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "viscous friction in the passive hinges about b, c and d \
    (bearings of the distal links), proportional to their relative angular rates and mapped to \
    the motors by virtual work; the residual depends on velocity and pose together";

/// `J⁻ᵀ v` for `J = [[1, K], [1, −K]]`: `½ [v0 + v1/K, v0 − v1/K]`.
#[inline(always)]
fn inv_t<T: Scalar>(k: T, v0: T, v1: T) -> (T, T) {
    let half = T::lift(0.5);
    let q = v1 / k;
    (half * (v0 + q), half * (v0 - q))
}

/// Column of a passive hinge between links `i` and `j` (kin indices).
#[inline(always)]
fn hinge<T: Scalar>(s: &KinematicSample<T>, i: usize, j: usize) -> (T, T) {
    let jr = s.link_jacobians[i] - s.link_jacobians[j];
    let w = s.omega[i] - s.omega[j];
    let v = jr.tr_mul(&w);
    inv_t(s.jacobian.k(), v[0], v[1])
}

/// The three hinge columns.
#[inline(always)]
pub(super) fn fill<T: Scalar>(s: &KinematicSample<T>, out: &mut [T]) {
    for (c, (i, j)) in [(2, 0), (3, 1), (2, 3)].into_iter().enumerate() {
        let (a, b) = hinge(s, i, j);
        out[2 * c] = a;
        out[2 * c + 1] = b;
    }
}
