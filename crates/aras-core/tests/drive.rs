//! The simulated drive and the RK4 step: RK4 is exact for polynomial
//! solutions of degree ≤ 4 and matches `exp` to `O(h⁵)` per step; the
//! encoder quantisation is idempotent and within half a count; the
//! velocity estimate converges to a constant rate; the PD torque vanishes
//! on the desired trajectory.

use aras_core::Rk4;
use aras_core::drive::{PdDrive, encoder_resolution, quantise, saturate, torque_noise_std};
use proptest::prelude::*;

/// `ẋ_i = x_{i+1}` (i < 4), `ẋ_4 = 0`: the exact solution is the Taylor
/// polynomial `x_i(t) = Σ_m x_{i+m}(0) tᵐ/m!`, of degree ≤ 4.
fn chain(x: &[f64], d: &mut [f64]) -> Result<(), std::convert::Infallible> {
    d[..4].copy_from_slice(&x[1..]);
    d[4] = 0.0;
    Ok(())
}

fn taylor(x0: &[f64], t: f64) -> Vec<f64> {
    let fact = [1.0, 1.0, 2.0, 6.0, 24.0];
    (0..5)
        .map(|i| {
            (0..5 - i)
                .map(|m| x0[i + m] * t.powi(m as i32) / fact[m])
                .sum()
        })
        .collect()
}

proptest! {
    /// RK4 reproduces a degree-4 polynomial solution over a step to
    /// rounding, whatever the step.
    #[test]
    fn rk4_is_exact_for_quartic_solutions(
        x0 in prop::collection::vec(-10.0..10.0f64, 5),
        h in 1e-4..2.0f64,
    ) {
        let mut rk = Rk4::new(5);
        let mut x = x0.clone();
        rk.step(&mut x, h, chain).unwrap();
        let exact = taylor(&x0, h);
        // The terms are at most 10·hᵐ/m! ≤ 10·e^h; a few roundings each.
        let scale = 10.0 * h.exp();
        for (a, b) in x.iter().zip(&exact) {
            prop_assert!((a - b).abs() <= 1e-14 * scale, "{x:?} vs {exact:?}");
        }
    }

    /// The fixed-size integrator takes the same steps, bit for bit, as the
    /// run-time-sized one: the storage changes, not the arithmetic.
    #[test]
    fn fixed_and_sized_integrators_agree_bit_for_bit(
        x0 in prop::collection::vec(-10.0..10.0f64, 5),
        h in 1e-4..2.0f64,
    ) {
        let (mut sized, mut fixed) = (Rk4::new(5), Rk4::<[f64; 5]>::fixed());
        let mut a = x0.clone();
        let mut b: [f64; 5] = x0.as_slice().try_into().unwrap();
        for _ in 0..3 {
            sized.step(&mut a, h, chain).unwrap();
            fixed.step(&mut b, h, chain).unwrap();
        }
        prop_assert_eq!(fixed.dim(), 5);
        prop_assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()), "{a:?} vs {b:?}");
    }

    /// A non-autonomous quadrature: with time as a state, `ẏ = p(t)` for a
    /// cubic `p` integrates exactly (Simpson's rule).
    #[test]
    fn rk4_integrates_cubics_exactly(
        c in prop::collection::vec(-5.0..5.0f64, 4),
        t0 in -2.0..2.0f64,
        h in 1e-3..1.0f64,
    ) {
        let p = |t: f64| c[0] + t * (c[1] + t * (c[2] + t * c[3]));
        let integral = |t: f64| t * (c[0] + t * (c[1] / 2.0 + t * (c[2] / 3.0 + t * c[3] / 4.0)));
        let mut rk = Rk4::new(2);
        let mut x = [t0, 0.0];
        rk.step(&mut x, h, |x: &[f64], d: &mut [f64]| {
            d[0] = 1.0;
            d[1] = p(x[0]);
            Ok::<(), ()>(())
        })
        .unwrap();
        let exact = integral(t0 + h) - integral(t0);
        prop_assert!((x[1] - exact).abs() <= 1e-13 * 5.0 * 3.0f64.powi(4), "{} vs {exact}", x[1]);
        prop_assert!((x[0] - (t0 + h)).abs() <= 1e-15 * 4.0);
    }

    /// `ẋ = λx` over one step: the error against `exp(λh)` is the tail of
    /// its series from `(λh)⁵/5!`, below `|λh|⁵/120 · e^{|λh|}`.
    #[test]
    fn rk4_matches_the_exponential_to_fifth_order(
        x0 in -10.0..10.0f64,
        z in -0.5..0.5f64,
    ) {
        let mut rk = Rk4::new(1);
        let mut x = [x0];
        rk.step(&mut x, z, |x: &[f64], d: &mut [f64]| {
            d[0] = x[0];
            Ok::<(), ()>(())
        })
        .unwrap();
        let exact = x0 * z.exp();
        let bound = x0.abs() * (z.abs().powi(5) / 120.0 * z.abs().exp() + 4e-15);
        prop_assert!((x[0] - exact).abs() <= bound, "{} vs {exact}", x[0]);
    }

    /// Quantised angles are whole counts: quantising again changes
    /// nothing, and the error is at most half a count (to rounding).
    #[test]
    fn quantisation_is_idempotent_within_half_a_count(
        angle in -100.0..100.0f64,
        counts in 1u32..=u32::MAX,
        ratio in 0.1..1000.0f64,
    ) {
        let r = encoder_resolution(counts, ratio);
        let q = quantise(angle, r);
        prop_assert_eq!(quantise(q, r), q);
        prop_assert!((q - angle).abs() <= 0.5 * r * (1.0 + 1e-12) + 4.0 * f64::EPSILON * angle.abs());
    }

    /// Angles advancing at a constant rate `ω`: once the filter's start
    /// has decayed (`(1 − α)^k`), the estimate is `ω` to within two counts
    /// per sample, the difference of quantised angles' error.
    #[test]
    fn the_velocity_estimate_converges_to_a_constant_rate(
        omega in prop::collection::vec(-20.0..20.0f64, 1..4),
        theta0 in -3.0..3.0f64,
        counts in 1000u32..1_000_000,
        cutoff in 5.0..100.0f64,
    ) {
        let dt = 1e-3;
        let n = omega.len();
        let r = encoder_resolution(counts, 10.0);
        let mut drive = PdDrive::new(vec![r; n], vec![0.0; n], cutoff, dt);
        let mut angles = vec![0.0; n];
        for k in 0..3000 {
            for j in 0..n {
                angles[j] = theta0 + omega[j] * (k as f64 * dt);
            }
            drive.sense(&angles);
        }
        for j in 0..n {
            prop_assert_eq!(drive.angles()[j], quantise(angles[j], r));
            let err = (drive.velocity()[j] - omega[j]).abs();
            prop_assert!(err <= 2.0 * r / dt + 1e-9 * (1.0 + omega[j].abs()), "joint {j}: {err}");
        }
    }

    /// On the desired trajectory — angles on whole counts, the estimate
    /// at the desired rate — the PD torque is zero and the caller's
    /// feedforward passes unchanged; a count of error gives `kp · r`.
    #[test]
    fn the_pd_torque_is_zero_on_the_desired_trajectory(
        steps in prop::collection::vec(-50i64..50, 1..4),
        start in -10_000i64..10_000,
        kp in 0.0..1000.0f64,
        kd in 0.0..10.0f64,
        ff in -2.0..2.0f64,
    ) {
        let dt = 1e-3;
        let n = steps.len();
        let r = encoder_resolution(40_960, 1.0);
        let rate: Vec<f64> = steps.iter().map(|&s| s as f64 * r / dt).collect();
        let (kp, kd) = (vec![kp; n], vec![kd; n]);
        let mut drive = PdDrive::new(vec![r; n], rate.clone(), 30.0, dt);
        let mut desired = vec![0.0; n];
        for k in 0..50i64 {
            for j in 0..n {
                desired[j] = (start + steps[j] * k) as f64 * r;
            }
            drive.sense(&desired);
            let mut tau = vec![ff; n];
            drive.add_torque(&kp, &kd, &desired, &rate, &mut tau);
            for j in 0..n {
                // The rate of whole counts per sample, recovered from
                // rounded angles: a few ulps of the counts' magnitude.
                let rounding = kd[j] * 1e-12 * (1.0 + (start.abs() + 50 * 50) as f64 * r / dt);
                prop_assert!((tau[j] - ff).abs() <= rounding, "sample {k}, joint {j}: {}", tau[j] - ff);
            }
            if k == 0 {
                prop_assert!(tau.iter().all(|&t| t == ff));
            }
        }
        let mut off = desired.clone();
        off[0] += r;
        let mut tau = vec![0.0; n];
        drive.add_torque(&kp, &kd, &off, &rate, &mut tau);
        prop_assert!((tau[0] - kp[0] * r).abs() <= 1e-9 * (1.0 + kp[0] * r));
    }

    /// The torque noise is the current noise scaled to the joint, and the
    /// limits clamp symmetrically.
    #[test]
    fn noise_and_limits(
        s in 0.0..0.1f64, kt in 0.001..1.0f64, ratio in 1.0..200.0f64,
        tau in prop::collection::vec(-10.0..10.0f64, 3),
        limit in 0.1..5.0f64,
    ) {
        prop_assert_eq!(torque_noise_std(s, kt, ratio), s * kt * ratio);
        let mut t = tau.clone();
        saturate(&mut t, &[limit; 3]);
        for (a, b) in t.iter().zip(&tau) {
            prop_assert_eq!(*a, b.clamp(-limit, limit));
        }
    }
}

/// A failing derivative stops the step and leaves the state as it was.
#[test]
fn a_failed_step_leaves_the_state() {
    let mut rk = Rk4::new(2);
    let mut x = [1.0, 2.0];
    let mut calls = 0;
    let e = rk.step(&mut x, 0.1, |x: &[f64], d: &mut [f64]| {
        calls += 1;
        if calls == 3 {
            return Err("stage 3");
        }
        d.copy_from_slice(x);
        Ok(())
    });
    assert_eq!(e, Err("stage 3"));
    assert_eq!(x, [1.0, 2.0]);
}

/// The resolution of the ARAS-Diamond's default encoder: 4096 counts per
/// motor revolution behind a capstan of 10.
#[test]
fn resolution_is_two_pi_over_the_counts_at_the_joint() {
    assert_eq!(
        encoder_resolution(4096, 10.0),
        2.0 * std::f64::consts::PI / 40_960.0
    );
}
