//! LuGre friction (Canudas de Wit, Olsson, Åström, Lischinsky, "A new model
//! for control of systems with friction", IEEE TAC 40(3), 1995): the
//! simulator's optional low-speed friction law, with an internal state that
//! the plant integrates together with its motion.
//!
//! Each joint's contact is a bristle of deflection `z` (rad):
//!
//! ```text
//! ż = θ̇ − σ0 |θ̇| z / g(θ̇),   g(θ̇) = Fc + (Fs − Fc) exp(−(θ̇ / v_s)²)
//! τ_f = σ0 z + σ1 ż + Fv θ̇
//! ```
//!
//! At constant speed `z` settles at `g(θ̇) sign(θ̇) / σ0`, so the steady
//! friction is the Stribeck curve `g(θ̇) sign(θ̇) + Fv θ̇`; from rest a small
//! displacement deflects the bristle like a spring of stiffness `σ0`
//! (presliding), so a torque below the breakaway level `Fs` holds the joint
//! instead of letting it creep; after a reversal the friction follows the
//! displacement over `≈ Fc / σ0` (rad), with hysteresis. None of this is a
//! function of the current velocity alone, which is why it is simulated as
//! a state and not evaluated as a regressor column. The equations are
//! [`aras_core::LuGreLaw`]'s; this module holds both joints' settings and
//! the plant integrates the state with its motion.

use aras_core::LuGreLaw;
use serde::{Deserialize, Serialize};

use crate::SimError;

/// LuGre parameters of both joints. `Fc` and `Fv` are the truth parameters'
/// Coulomb and viscous levels ((49)); these add the breakaway level, the
/// Stribeck velocity and the bristle dynamics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LuGre {
    /// Breakaway (static) friction `Fs` (N·m), at least the Coulomb level.
    pub static_level: [f64; 2],
    /// Stribeck velocity `v_s` (rad/s, > 0): how fast the friction falls
    /// from `Fs` to `Fc`.
    pub stribeck_velocity: [f64; 2],
    /// Bristle stiffness `σ0` (N·m/rad, > 0); `Fc / σ0` is the presliding
    /// displacement (rad).
    pub stiffness: [f64; 2],
    /// Bristle damping `σ1` (N·m·s/rad, ≥ 0).
    pub damping: [f64; 2],
}

/// Largest `h · σ0 |θ̇| / g` an RK4 step takes: the bristle equation is a
/// relaxation at that rate, and RK4's real stability limit is 2.78.
const MAX_STEP_RATE: f64 = 2.5;

impl LuGre {
    /// Checks the settings against the Coulomb levels `fc` they extend.
    pub(crate) fn validate(&self, fc: [f64; 2]) -> Result<(), SimError> {
        let bad = |key, value, reason| Err(SimError::Config { key, value, reason });
        for (j, fc) in fc.into_iter().enumerate() {
            let fs = self.static_level[j];
            if !(fs.is_finite() && fs >= fc && fs > 0.0) {
                return bad(
                    "lugre.static_level",
                    fs,
                    "must be finite, positive and at least the joint's Coulomb level Fc",
                );
            }
            for (key, v) in [
                ("lugre.stribeck_velocity", self.stribeck_velocity[j]),
                ("lugre.stiffness", self.stiffness[j]),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return bad(key, v, "must be a positive finite number");
                }
            }
            let d = self.damping[j];
            if !(d.is_finite() && d >= 0.0) {
                return bad("lugre.damping", d, "must be a finite number ≥ 0");
            }
        }
        Ok(())
    }

    /// Joint `j`'s law with Coulomb level `fc` (N·m): the workspace's one
    /// LuGre law ([`aras_core::LuGreLaw`]), Gaussian Stribeck shape.
    fn law(&self, j: usize, fc: f64) -> LuGreLaw {
        LuGreLaw {
            coulomb: fc,
            static_level: self.static_level[j],
            stribeck_velocity: self.stribeck_velocity[j],
            shape: 2.0,
            stiffness: self.stiffness[j],
        }
    }

    /// `g(θ̇)` of joint `j` with Coulomb level `fc` (N·m).
    #[cfg(test)]
    fn level(&self, j: usize, fc: f64, v: f64) -> f64 {
        self.law(j, fc).level(v)
    }

    /// The bristle deflection at steady sliding with rate `v`.
    pub(crate) fn steady_state(&self, j: usize, fc: f64, v: f64) -> f64 {
        self.law(j, fc).steady_deflection(v)
    }

    /// `ż` of joint `j` at rate `v` and deflection `z`.
    pub(crate) fn rate(&self, j: usize, fc: f64, v: f64, z: f64) -> f64 {
        self.law(j, fc).rate(v, z)
    }

    /// Friction torque of joint `j` (N·m) with Coulomb level `fc` and
    /// viscous coefficient `fv`.
    pub(crate) fn torque(&self, j: usize, fc: f64, fv: f64, v: f64, z: f64) -> f64 {
        self.stiffness[j] * z + self.damping[j] * self.rate(j, fc, v, z) + fv * v
    }

    /// Errors if a step of `h` seconds at rate `v` is beyond RK4's stable
    /// range for the bristle relaxation.
    pub(crate) fn check_step(&self, fc: [f64; 2], v: [f64; 2], h: f64) -> Result<(), f64> {
        for j in 0..2 {
            let ratio = h * self.law(j, fc[j]).relaxation_rate(v[j]);
            if ratio > MAX_STEP_RATE {
                return Err(ratio);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law() -> LuGre {
        LuGre {
            static_level: [0.4, 0.4],
            stribeck_velocity: [0.05, 0.05],
            stiffness: [300.0, 300.0],
            damping: [0.5, 0.5],
        }
    }

    /// Integrates one joint's bristle at a prescribed rate with small
    /// explicit Euler steps (independent of the simulator's RK4).
    fn integrate(l: &LuGre, fc: f64, v: impl Fn(f64) -> f64, t_end: f64, z0: f64) -> f64 {
        let h = 1e-6;
        let mut z = z0;
        let steps = (t_end / h) as usize;
        for k in 0..steps {
            z += h * l.rate(0, fc, v(k as f64 * h), z);
        }
        z
    }

    /// At constant speed the friction settles on the Stribeck curve
    /// `g(v) sign(v) + Fv v`.
    #[test]
    fn steady_sliding_follows_the_stribeck_curve() {
        let l = law();
        let (fc, fv) = (0.3, 0.01);
        for v in [-0.5, -0.05, 0.01, 0.05, 0.2, 1.0] {
            // A displacement of 40 relaxation lengths g/σ0 (at most 0.4/300).
            let t_end = 40.0 * 0.4 / (300.0 * f64::abs(v));
            let z = integrate(&l, fc, |_| v, t_end, 0.0);
            let got = l.torque(0, fc, fv, v, z);
            let want = l.level(0, fc, v) * f64::signum(v) + fv * v;
            assert!((got - want).abs() < 1e-6, "v {v}: {got} vs {want}");
            assert!((z - l.steady_state(0, fc, v)).abs() < 1e-9);
        }
    }

    /// From rest, a displacement `d` deflects the bristle as
    /// `σ0 z = g (1 − exp(−σ0 d / g))` (the solution of `dz/dθ = 1 − σ0 z / g`
    /// at constant `g`): a spring of stiffness σ0 for `d ≪ g/σ0`. 1e-4 rad
    /// gives 0.0289 N·m (0.03 for the linear spring), far below the
    /// breakaway level (presliding).
    #[test]
    fn small_displacement_from_rest_is_a_spring() {
        let l = law();
        let v = 1e-3;
        let z = integrate(&l, 0.3, |_| v, 0.1, 0.0);
        let f = l.stiffness[0] * z;
        let g = l.level(0, 0.3, v);
        let want = g * (1.0 - (-l.stiffness[0] * 1e-4 / g).exp());
        assert!((f - want).abs() < 1e-6, "{f} vs {want}");
        assert!((f - 0.03).abs() < 0.03 * 0.05, "{f}");
    }

    /// The deflection never leaves `|z| ≤ Fs / σ0` when it starts inside.
    #[test]
    fn deflection_stays_bounded() {
        let l = law();
        let bound = l.static_level[0] / l.stiffness[0];
        let z = integrate(&l, 0.3, |t| 3.0 * (40.0 * t).sin(), 0.3, 0.0);
        assert!(z.abs() <= bound * (1.0 + 1e-9), "{z} vs {bound}");
    }

    #[test]
    fn settings_below_the_coulomb_level_are_refused() {
        let mut l = law();
        l.static_level[1] = 0.1;
        let e = l.validate([0.3, 0.3]).unwrap_err().to_string();
        assert!(e.contains("lugre.static_level"), "{e}");
        let mut l = law();
        l.stiffness[0] = f64::NAN;
        assert!(
            l.validate([0.3, 0.3])
                .unwrap_err()
                .to_string()
                .contains("stiffness")
        );
    }
}
