//! Cogging per joint: harmonics `h = 1..order` of `sin/cos(h n_c θ_j)` with
//! `n_c` cycles per joint revolution (non-linear settings of the effect),
//! parameters `Cs{j}_{h}, Cc{j}_{h}`. No sign constraint: amplitudes and
//! phases are free.

use aras_kin::{KinematicSample, Scalar};

use crate::DynError;
use crate::params::MAX_COGGING_ORDER;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "torque periodic in the motor angle (permanent-magnet \
    detent torque, gear or capstan-groove ripple), with a fixed number of cycles per joint \
    revolution; the residual oscillates with the joint angle";

/// `4 · order` columns.
pub(super) fn columns(order: usize) -> usize {
    4 * order
}

/// `Cs1_1, Cc1_1, …, Cs2_order, Cc2_order`: joint 1 then joint 2; per
/// harmonic `h` the sine `Cs{j}_{h}`, then the cosine `Cc{j}_{h}`.
pub(crate) fn names(order: usize) -> Vec<String> {
    let mut v = Vec::with_capacity(4 * order);
    for j in 1..=2 {
        for h in 1..=order {
            v.push(format!("Cs{j}_{h}"));
            v.push(format!("Cc{j}_{h}"));
        }
    }
    v
}

/// Errors unless `cycles_per_rev` is positive and `order` in 1–16.
pub(super) fn validate(cycles_per_rev: f64, order: usize) -> Result<(), DynError> {
    if !(cycles_per_rev.is_finite() && cycles_per_rev > 0.0) {
        return Err(DynError::InvalidSetting {
            id: "cogging",
            setting: "cycles_per_rev",
            value: cycles_per_rev,
            reason: "the number of cogging cycles per revolution must be positive",
        });
    }
    if order == 0 || order > MAX_COGGING_ORDER {
        return Err(DynError::InvalidSetting {
            id: "cogging",
            setting: "order",
            value: order as f64,
            reason: "the cogging order must be between 1 and 16",
        });
    }
    Ok(())
}

/// `sin(h n_c θ_j)`, `cos(h n_c θ_j)` on joint `j`'s row, joint by joint.
#[inline(always)]
pub(super) fn fill<T: Scalar>(
    s: &KinematicSample<T>,
    cycles_per_rev: f64,
    order: usize,
    out: &mut [T],
) {
    let (z, th) = (T::zero(), s.joint.pos);
    let mut c = 0;
    for j in 0..2 {
        // Harmonic h + 1 from h by the angle-addition formulas: one sin_cos
        // per joint instead of one per harmonic (rounding grows by about
        // one ulp per harmonic, ≤ 16).
        let (s1, c1) = (th[j] * T::lift(cycles_per_rev)).sin_cos();
        let (mut sn, mut cs) = (s1, c1);
        for _ in 1..=order {
            out[2 * c + j] = sn;
            out[2 * c + 1 - j] = z;
            out[2 * c + 2 + j] = cs;
            out[2 * c + 3 - j] = z;
            c += 2;
            (sn, cs) = (sn * c1 + cs * s1, cs * c1 - sn * s1);
        }
    }
}
