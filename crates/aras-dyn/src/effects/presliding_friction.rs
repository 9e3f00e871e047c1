//! Presliding (bristle) friction, parameters `Fb1, Fb2, Db1, Db2`: the
//! bristle level `Fb_j` times the normalised bristle deflection `s_j ∈ [−1,
//! 1]` of LuGre friction with a constant level (Canudas de Wit et al. 1995;
//! [`aras_core::LuGreLaw`] with `Fs = Fc`), and the bristle damping `Db_j`
//! (LuGre's `σ1`, N·m·s/rad) times the bristle rate `ż = θ̇ (1 − s sign θ̇)`
//! (`z = δ s`), which is zero in steady sliding and `θ̇` while the contact
//! presslides. Along each joint's path
//!
//! ```text
//! ds/dθ = (1 − s sign(dθ)) / δ
//! ```
//!
//! with the presliding displacement `δ = Fc / σ0` (rad, > 0), a non-linear
//! setting of the effect. In steady sliding `s = sign(θ̇)`, so `Fb s` is a
//! Coulomb level; after a reversal the friction follows the displacement
//! over a few `δ` instead of the velocity, so a joint that turns slowly
//! holds (presliding, a spring of stiffness `Fb/δ`) and the friction against
//! position is a hysteresis loop. A Stribeck hump on top is the separate
//! `stribeck_friction` effect, static.
//!
//! **A state, not a per-sample column.** `s` depends on the path since the
//! last reversals, so its columns are computed along a stacked sequence of
//! samples ([`crate::Model::stacked`]), never from one sample: the per-sample
//! regressor leaves them zero and [`crate::Model::fill`] refuses a model with
//! this effect. The bristle depends on the path alone, not on the time
//! taken ([`aras_core::LuGreLaw::advance_at_level`]), so the samples' angles
//! advance it exactly, with no time step and whatever the stiffness; a
//! reversal between two samples is seen at the next sample (at 1 kHz the
//! angle travelled there is ≈ θ̈ Δt² / 8, micro-radians, against δ of
//! 1e-4–1e-2 rad). The state starts relaxed at the first sample (`s =
//! sign(θ̇)`, 0 at rest) and forgets its start after a displacement of a
//! few δ (`e^{−5}` after 5δ).

use aras_core::LuGreLaw;

use crate::DynError;

/// Parameter names in column order: the levels, then the dampings.
pub(crate) const NAMES: [&str; 4] = ["Fb1", "Fb2", "Db1", "Db2"];

/// Parameters the physically consistent fit keeps non-negative: the
/// bristle's level and damping dissipate only when positive.
pub(super) const NONNEGATIVE: &[&str] = &NAMES;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "friction with an internal state (LuGre bristles): after a \
    velocity reversal the contact deforms elastically over a presliding displacement δ before it \
    slides, so friction follows the displacement, not the velocity; a slowly turning joint sticks \
    and the residual against position is a hysteresis loop at every reversal";

/// Errors unless `displacement` is a positive number of radians.
pub(super) fn validate(displacement: f64) -> Result<(), DynError> {
    if displacement.is_finite() && displacement > 0.0 {
        Ok(())
    } else {
        Err(DynError::InvalidSetting {
            id: "presliding_friction",
            setting: "displacement",
            value: displacement,
            reason: "the presliding displacement must be a positive number of radians",
        })
    }
}

/// One joint's normalised deflection `s` along its sampled path `theta`,
/// starting relaxed for the direction of `theta_dot[0]`, written to
/// `level`, and the bristle rate `θ̇ (1 − s sign θ̇)` to `rate`.
pub(crate) fn states(
    displacement: f64,
    theta: &[f64],
    theta_dot: &[f64],
    level: &mut [f64],
    rate: &mut [f64],
) {
    // The law normalised by the level: σ0 = 1/δ, level 1, so z = s δ.
    let law = LuGreLaw {
        coulomb: 1.0,
        static_level: 1.0,
        stribeck_velocity: 1.0,
        shape: 2.0,
        stiffness: 1.0 / displacement,
    };
    let Some(&v0) = theta_dot.first() else {
        return;
    };
    let mut z = law.steady_deflection(v0);
    let mut prev = theta[0];
    for (((o, r), &th), &v) in level.iter_mut().zip(rate).zip(theta).zip(theta_dot) {
        z = law.advance_at_level(z, th - prev, 1.0);
        prev = th;
        *o = z / displacement;
        *r = law.rate(v, z);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steady sliding gives ±1; after a reversal the state relaxes along
    /// the displacement as `1 − 2 e^{−x/δ}` (exact at the samples).
    #[test]
    fn relaxes_along_the_displacement_after_a_reversal() {
        let d = 1e-3;
        // Forward far, then back: θ up to 0.1 rad, then down in 1e-4 steps.
        let mut theta: Vec<f64> = (0..=1000).map(|i| i as f64 * 1e-4).collect();
        theta.extend((1..=500).map(|i| 0.1 - i as f64 * 1e-4));
        let v: Vec<f64> = (0..theta.len())
            .map(|i| if i <= 1000 { 1.0 } else { -1.0 })
            .collect();
        let mut s = vec![0.0; theta.len()];
        let mut r = vec![0.0; theta.len()];
        states(d, &theta, &v, &mut s, &mut r);
        // The rate: zero sliding, θ̇ (1 − s sign θ̇) after the reversal.
        assert!(r[1000].abs() < 1e-12);
        assert!((r[1001] + (1.0 + s[1001])).abs() < 1e-12);
        assert!((s[1000] - 1.0).abs() < 1e-12);
        for k in [1, 5, 10, 30] {
            let x = k as f64 * 1e-4;
            let want = -1.0 + 2.0 * (-x / d).exp();
            assert!(
                (s[1000 + k] - want).abs() < 1e-12,
                "{k}: {} vs {want}",
                s[1000 + k]
            );
        }
        assert!(s.iter().all(|x| x.abs() <= 1.0 + 1e-12));
    }

    /// The same path sampled coarsely or finely gives the same state at the
    /// shared samples: the bristle depends on the path, not on the steps.
    #[test]
    fn independent_of_the_sampling_along_a_monotone_stretch() {
        let d = 5e-4;
        let fine: Vec<f64> = (0..=400).map(|i| (i as f64 * 0.01).sin() * 2e-3).collect();
        let coarse: Vec<f64> = fine.iter().step_by(4).copied().collect();
        let vel = |x: &[f64]| -> Vec<f64> {
            (0..x.len())
                .map(|i| x[(i + 1).min(x.len() - 1)] - x[i.saturating_sub(1)])
                .collect()
        };
        let (mut a, mut b) = (vec![0.0; fine.len()], vec![0.0; coarse.len()]);
        let (mut ra, mut rb) = (a.clone(), b.clone());
        states(d, &fine, &vel(&fine), &mut a, &mut ra);
        states(d, &coarse, &vel(&coarse), &mut b, &mut rb);
        // sin(0.01 i) rises until i ≈ 157: monotone there.
        for k in 0..39 {
            assert!(
                (a[4 * k] - b[k]).abs() < 1e-12,
                "{k}: {} vs {}",
                a[4 * k],
                b[k]
            );
        }
    }
}
