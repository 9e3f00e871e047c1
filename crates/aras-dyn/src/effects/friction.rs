//! Viscous + Coulomb friction per actuator, `τ_f = Fv θ̇ + Fc tanh(θ̇ / w)`
//! with a transition width `w ≥ 0` per joint (rad/s, a non-linear setting of
//! the effect); `w = 0` is exactly the paper's `Fv θ̇ + Fc sign(θ̇)` (49).
//! Parameters `Fv1, Fc1, Fv2, Fc2`. Physical constraint (70): all ≥ 0
//! (friction dissipates).

use aras_kin::{KinematicSample, Scalar};

use crate::{DynError, Sign};

/// Parameter names in column order.
pub(crate) const NAMES: [&str; 4] = ["Fv1", "Fc1", "Fv2", "Fc2"];

/// Parameters that must not be negative, (70).
pub(super) const NONNEGATIVE: &[&str] = &NAMES;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "friction in the motors, capstans and active bearings: a \
    part proportional to the motor rate (viscous) and a constant level opposing the motion \
    (Coulomb), (49), reached over a transition width w of the rate";

/// Errors unless both widths are finite and ≥ 0 rad/s.
pub(super) fn validate(w: [f64; 2]) -> Result<(), DynError> {
    for (j, v) in w.iter().enumerate() {
        if !(v.is_finite() && *v >= 0.0) {
            return Err(DynError::InvalidSetting {
                id: "friction",
                setting: ["w[0] (joint 1)", "w[1] (joint 2)"][j],
                value: *v,
                reason: "the Coulomb transition width must be a finite number ≥ 0 of rad/s \
                         (0 is the sign law (49))",
            });
        }
    }
    Ok(())
}

/// The Coulomb law of one joint: `tanh(v / w)` for `w > 0`, else the caller's
/// `sign` evaluation (the exact sign of (49), or the simulator's smoothing).
#[inline(always)]
pub(super) fn coulomb<T: Scalar>(v: T, w: f64, sign: Sign) -> T {
    if w > 0.0 {
        (v / T::lift(w)).tanh()
    } else {
        sign.eval(v)
    }
}

/// Columns `[θ̇1, c(θ̇1)]` on joint 1's row, `[θ̇2, c(θ̇2)]` on joint 2's, with
/// `c` the Coulomb law of [`coulomb`].
#[inline(always)]
pub(super) fn fill<T: Scalar>(s: &KinematicSample<T>, w: [f64; 2], sign: Sign, out: &mut [T]) {
    let (z, td) = (T::zero(), s.joint.vel);
    let c1 = coulomb(td[0], w[0], sign);
    let c2 = coulomb(td[1], w[1], sign);
    out.copy_from_slice(&[td[0], z, c1, z, z, td[1], z, c2]);
}

/// The Coulomb law of one joint in `f64`: `tanh(v / w)` for a width
/// `w > 0` (rad/s), the exact `sign(v)` (0 at rest) for `w = 0`, (49).
pub fn coulomb_law(v: f64, w: f64) -> f64 {
    coulomb(v, w, Sign::Exact)
}

/// `∂/∂w` of [`coulomb_law`]: `−(v / w²) sech²(v / w)` for `w > 0`; 0 at
/// `w = 0` (the sign law does not change with the width). The derivative of
/// a friction column `Fc_j`'s entry on joint `j`'s row; every other entry of
/// the regressor is independent of `w`.
pub fn coulomb_law_dw(v: f64, w: f64) -> f64 {
    if w > 0.0 {
        let x = v / w;
        let sech = 1.0 / x.cosh();
        -(x / w) * sech * sech
    } else {
        0.0
    }
}
