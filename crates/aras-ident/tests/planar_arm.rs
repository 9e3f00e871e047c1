//! The `planar_arm` example in CI: `aras-ident` identifies a robot it knows
//! nothing about (a 2-link planar arm with Coulomb + viscous friction) from
//! its hand-written regressor, with torques from an independent
//! Newton–Euler path.
#![cfg(feature = "sdp")]
#![allow(clippy::needless_range_loop)]

#[allow(dead_code)]
#[path = "../examples/planar_arm.rs"]
mod planar_arm;

use aras_ident::LinearModel;
use planar_arm::{Arm, COLUMNS, PlanarArm, excitation, run};

/// Largest relative error, scaled per entry by the truth's magnitude.
fn worst(est: &[f64], truth: &[f64]) -> f64 {
    est.iter()
        .zip(truth)
        .map(|(e, t)| (e - t).abs() / t.abs())
        .fold(0.0, f64::max)
}

#[test]
fn regressor_times_parameters_equals_newton_euler_torques() {
    // The hand-derived Lagrangian regressor against the independent
    // recursive Newton–Euler torques: equal to rounding (1e-12 N·m on
    // torques of order 10 N·m).
    let arm = Arm::example();
    let beta = arm.standard();
    let mut y = vec![0.0; 2 * COLUMNS];
    for i in 0..500 {
        let [q, qd, qdd] = excitation(i as f64 * 0.0137);
        PlanarArm.fill(&q, &qd, &qdd, &mut y).unwrap();
        let tau = arm.torques(q, qd, qdd);
        for j in 0..2 {
            let model: f64 = (0..COLUMNS).map(|c| y[2 * c + j] * beta[c]).sum();
            assert!((model - tau[j]).abs() < 1e-12, "sample {i}, joint {j}");
        }
    }
}

#[test]
fn planar_arm_base_parameters_are_recovered_noise_free() {
    let o = run(2000).unwrap();
    // 23 standard parameters, 10 base: Izz, hx, hy of both links with link
    // 2's mass grouped into link 1's Izz and hx, and 4 friction levels.
    assert_eq!(o.truth.len(), 10, "{:#?}", o.base_names);
    // Noise-free: OLS by QR recovers the truth to rounding error (the
    // column-scaled problem's condition number is far below 1e4, so 1e-6
    // leaves a wide margin).
    assert!(
        worst(&o.ols, &o.truth) < 1e-6,
        "OLS {:?} vs {:?}",
        o.ols,
        o.truth
    );
    // The streaming accumulation (Gram path, per-joint groups) of the same
    // samples agrees as tightly.
    assert!(
        worst(&o.streaming, &o.truth) < 1e-6,
        "streaming {:?} vs {:?}",
        o.streaming,
        o.truth
    );
    // The truth is physical and inside every bound, so the SDP reproduces it
    // up to its regulariser (λ = 1e-6 relative, pulling towards a reference
    // 10 % off) and the solver tolerance: 1e-3 relative.
    assert_eq!(o.sdp_status, aras_ident::SolverStatus::Solved);
    assert!(
        worst(&o.sdp, &o.truth) < 1e-3,
        "SDP {:?} vs {:?}",
        o.sdp,
        o.truth
    );
    assert!(
        o.min_eigenvalues.iter().all(|&e| e > 0.0),
        "{:?}",
        o.min_eigenvalues
    );
}
