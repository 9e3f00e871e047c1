//! The LuGre friction law of one joint (Canudas de Wit, Olsson, Åström,
//! Lischinsky, "A new model for control of systems with friction", IEEE TAC
//! 40(3), 1995), the one home of its equations: the simulator's plant
//! (`aras-dyn`), the friction identification and its simulator
//! (`aras-friction`) evaluate it here and integrate its state in their own
//! way (with the plant's RK4 step, or exactly along a sampled motion).
//!
//! The contact is a bristle of deflection `z` (rad):
//!
//! ```text
//! ż = v − σ0 |v| z / g(v),   g(v) = Fc + (Fs − Fc) exp(−|v / v_s|^δ)
//! ```
//!
//! At constant speed `z` settles at `g(v) sign(v) / σ0`, so the steady
//! friction `σ0 z` is the Stribeck curve `g(v) sign(v)`; from rest a small
//! displacement deflects the bristle like a spring of stiffness `σ0`
//! (presliding). The torque adds the bristle damping and the viscous term,
//! `σ0 z + σ1 ż + Fv v`, whose coefficients the caller holds.

/// The Stribeck decay `exp(−|v / v_s|^δ)`, with the common exponents
/// (`δ = 2`, the classical Gaussian shape, and `δ = 1`) computed without
/// `powf`.
pub fn stribeck_decay(v: f64, stribeck_velocity: f64, shape: f64) -> f64 {
    let x = (v / stribeck_velocity).abs();
    let e = if shape == 2.0 {
        x * x
    } else if shape == 1.0 {
        x
    } else {
        x.powf(shape)
    };
    (-e).exp()
}

/// The LuGre law's settings of one joint, in any consistent unit of torque
/// (N·m, or normalised by `Fc`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuGreLaw {
    /// Coulomb level `Fc` (> 0).
    pub coulomb: f64,
    /// Breakaway (static) level `Fs` (> 0).
    pub static_level: f64,
    /// Stribeck velocity `v_s` (rad/s, > 0).
    pub stribeck_velocity: f64,
    /// Shape exponent `δ` of the Stribeck decay (2 in the original model).
    pub shape: f64,
    /// Bristle stiffness `σ0` (torque per rad, > 0); `Fc / σ0` is the
    /// presliding displacement.
    pub stiffness: f64,
}

impl LuGreLaw {
    /// The sliding level `g(v) = Fc + (Fs − Fc) exp(−|v / v_s|^δ)`.
    pub fn level(&self, v: f64) -> f64 {
        self.coulomb
            + (self.static_level - self.coulomb)
                * stribeck_decay(v, self.stribeck_velocity, self.shape)
    }

    /// The relaxation rate `σ0 |v| / g(v)` (1/s) at which `z` approaches its
    /// steady state: what bounds an explicit integrator's step.
    pub fn relaxation_rate(&self, v: f64) -> f64 {
        self.stiffness * v.abs() / self.level(v)
    }

    /// The bristle rate `ż = v − σ0 |v| z / g(v)` at rate `v` and deflection
    /// `z`.
    pub fn rate(&self, v: f64, z: f64) -> f64 {
        v - self.relaxation_rate(v) * z
    }

    /// The deflection after a monotone displacement `dx` from `z` at a
    /// constant sliding level `g`: the exact solution of `dz/dx = 1 − σ0 z
    /// sign(dx) / g`, `z_ss + (z − z_ss) exp(−σ0 |dx| / g)` with `z_ss =
    /// sign(dx) g / σ0`. Where the level does not change along the step (no
    /// Stribeck hump, `Fs = Fc`, or away from it) the bristle depends on the
    /// path alone, not on the time taken, so a sampled path advances
    /// exactly, whatever its stiffness; `dx = 0` leaves `z` unchanged.
    pub fn advance_at_level(&self, z: f64, dx: f64, level: f64) -> f64 {
        if dx == 0.0 {
            return z;
        }
        let z_ss = dx.signum() * level / self.stiffness;
        z_ss + (z - z_ss) * (-self.stiffness * dx.abs() / level).exp()
    }

    /// The deflection of steady sliding at rate `v`, `g(v) sign(v) / σ0`
    /// (0 at rest).
    pub fn steady_deflection(&self, v: f64) -> f64 {
        if v == 0.0 {
            0.0
        } else {
            self.level(v) * v.signum() / self.stiffness
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn law() -> LuGreLaw {
        LuGreLaw {
            coulomb: 0.3,
            static_level: 0.4,
            stribeck_velocity: 0.05,
            shape: 2.0,
            stiffness: 300.0,
        }
    }

    /// The level runs from `Fs` at rest to `Fc` fast, and the fast paths of
    /// the decay equal `powf`.
    #[test]
    fn level_runs_from_breakaway_to_coulomb() {
        let l = law();
        assert_eq!(l.level(0.0), 0.4);
        assert!((l.level(10.0) - 0.3).abs() < 1e-15);
        assert!((l.level(0.05) - (0.3 + 0.1 * (-1.0f64).exp())).abs() < 1e-15);
        for (v, shape) in [(0.07, 2.0), (-0.02, 1.0)] {
            let want = (-(f64::abs(v) / 0.05).powf(shape)).exp();
            assert!((stribeck_decay(v, 0.05, shape) - want).abs() < 1e-15);
        }
    }

    /// Stepping the path in pieces equals one step (the solution is exact),
    /// and small steps follow the rate equation integrated finely.
    #[test]
    fn advance_at_level_is_the_exact_path_solution() {
        let l = LuGreLaw {
            static_level: 0.3,
            ..law()
        };
        let g = l.level(1.0);
        let z0 = -0.5 * g / l.stiffness;
        let one = l.advance_at_level(z0, 2e-3, g);
        let mut z = z0;
        for _ in 0..8 {
            z = l.advance_at_level(z, 2.5e-4, g);
        }
        assert!(
            (z - one).abs() < 1e-15 * g / l.stiffness * 10.0,
            "{z} vs {one}"
        );
        // Euler along x with tiny steps: first order, its relative error
        // about h σ0 / (2 g) ≈ 4e-6 here.
        let mut e = z0;
        let h = 1e-8;
        for _ in 0..200_000 {
            e += h * (1.0 - l.stiffness * e / g);
        }
        assert!((e - one).abs() < 1e-5 * g / l.stiffness, "{e} vs {one}");
        assert_eq!(l.advance_at_level(z0, 0.0, g), z0);
        // Backwards, towards −g/σ0.
        let back = l.advance_at_level(one, -1.0, g);
        assert!((back + g / l.stiffness).abs() < 1e-12);
    }

    proptest! {
        /// The steady deflection is where the rate vanishes, and the law is
        /// odd: `ż(−v, −z) = −ż(v, z)`.
        #[test]
        fn steady_state_is_the_rest_point_and_the_law_is_odd(
            v in -2.0f64..2.0, z in -2e-3f64..2e-3
        ) {
            let l = law();
            prop_assert!(l.rate(v, l.steady_deflection(v)).abs() < 1e-12);
            prop_assert!((l.rate(-v, -z) + l.rate(v, z)).abs() < 1e-15);
        }
    }
}
