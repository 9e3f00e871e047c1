//! The crates picked into another robot project, in CI: a 2-link planar arm
//! that none of them knows, excited by `aras-excite`, processed by
//! `aras-signal`, identified by `aras-ident`, torques from an independent
//! Newton–Euler path.

use std::process::Command;

use aras_ident::LinearModel;
use planar_arm::{Arm, COLUMNS, PlanarArm, Settings, limits, run};

/// Largest relative error, scaled per entry by the truth's magnitude.
fn worst(est: &[f64], truth: &[f64]) -> f64 {
    est.iter()
        .zip(truth)
        .map(|(e, t)| (e - t).abs() / t.abs())
        .fold(0.0, f64::max)
}

/// The hand-derived Lagrangian regressor against the independent recursive
/// Newton–Euler torques, over the excitation's box: equal to rounding
/// (1e-12 N·m on torques of order 10 N·m).
#[test]
fn regressor_times_parameters_equals_newton_euler_torques() {
    let arm = Arm::example();
    let beta = arm.standard();
    let l = limits();
    let mut y = vec![0.0; 2 * COLUMNS];
    for i in 0..500 {
        let u = |k: f64| ((i as f64 * k).sin() + 1.0) / 2.0;
        let q = [
            l.min[0] + u(0.37) * (l.max[0] - l.min[0]),
            l.min[1] + u(0.53) * (l.max[1] - l.min[1]),
        ];
        let qd = [3.0 * (2.0 * u(0.71) - 1.0), 3.0 * (2.0 * u(0.29) - 1.0)];
        let qdd = [12.0 * (2.0 * u(0.13) - 1.0), 12.0 * (2.0 * u(0.91) - 1.0)];
        LinearModel::fill(&PlanarArm, &q, &qd, &qdd, &mut y).unwrap();
        let tau = arm.torques(q, qd, qdd);
        for j in 0..2 {
            let model: f64 = (0..COLUMNS).map(|c| y[2 * c + j] * beta[c]).sum();
            assert!((model - tau[j]).abs() < 1e-12, "sample {i}, joint {j}");
        }
    }
}

/// The dual-number rows aras-excite differentiates are the `f64` rows, and
/// their derivatives match central differences.
#[test]
fn dual_rows_are_the_rows_and_their_derivatives() {
    use aras_excite::{Dual, Regressor};
    let (x, xd, xdd) = ([0.3, -0.7], [1.1, -0.4], [-2.0, 3.0]);
    let seed = |v: &[f64; 2], k: usize| {
        [
            Dual::from_re(v[0]).derivative(k),
            Dual::from_re(v[1]).derivative(k + 1),
        ]
    };
    let mut d = vec![Dual::from_re(0.0); 2 * COLUMNS];
    PlanarArm
        .fill_dual(&seed(&x, 0), &seed(&xd, 2), &seed(&xdd, 4), &mut d)
        .unwrap();
    let mut v = vec![0.0; 2 * COLUMNS];
    LinearModel::fill(&PlanarArm, &x, &xd, &xdd, &mut v).unwrap();
    assert!(d.iter().zip(&v).all(|(a, b)| a.re == *b));
    // ∂/∂q2 by central differences (h = 1e-6: error ~1e-10 on entries of
    // order 10).
    let h = 1e-6;
    let (mut p, mut m) = (v.clone(), v.clone());
    LinearModel::fill(&PlanarArm, &[x[0], x[1] + h], &xd, &xdd, &mut p).unwrap();
    LinearModel::fill(&PlanarArm, &[x[0], x[1] - h], &xd, &xdd, &mut m).unwrap();
    for k in 0..v.len() {
        let fd = (p[k] - m[k]) / (2.0 * h);
        let exact = d[k].eps.0.map_or(0.0, |g| g[1]);
        assert!((fd - exact).abs() < 1e-8, "entry {k}: {exact} vs {fd}");
    }
}

/// Designed, logged, processed, identified: noise-free, the base parameters
/// come back to rounding error.
#[test]
fn planar_arm_base_parameters_are_recovered_noise_free() {
    let o = run(&Settings::default()).unwrap();
    // The design's κ is finite and modest for a 10-parameter arm.
    assert!(
        o.condition_number.is_finite() && o.condition_number < 1e3,
        "κ {}",
        o.condition_number
    );
    // The processing took the harmonic series on the known period and
    // differentiated exactly: q̈ to 1e-8 rad/s² on accelerations of order
    // 10 rad/s².
    assert!(o.bandwidth.contains("Fourier series"), "{}", o.bandwidth);
    assert!(o.max_accel_error < 1e-8, "q̈ error {}", o.max_accel_error);
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

/// The proof that the crates can be picked: this package's normal
/// dependency tree holds neither ARAS-Diamond crate.
#[test]
fn neither_aras_kin_nor_aras_dyn_is_a_dependency() {
    let out = Command::new(env!("CARGO"))
        .args([
            "tree",
            "-p",
            "planar-arm",
            "-e",
            "normal",
            "--prefix",
            "none",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    let tree = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in ["aras-excite", "aras-signal", "aras-ident", "aras-diagnose"] {
        assert!(tree.contains(name), "{name} missing:\n{tree}");
    }
    for name in ["aras-kin", "aras-dyn", "aras-pipeline"] {
        assert!(!tree.contains(name), "{name} in the tree:\n{tree}");
    }
}

/// The n-link regressor (Newton–Euler in linear form) against the
/// independent centre-of-mass recursion, for 1 to 5 links: equal to
/// rounding (1e-11 N·m on torques of order 10 N·m).
#[test]
fn chain_regressor_times_parameters_equals_the_recursion_for_any_number_of_links() {
    use planar_arm::chain::Chain;
    let three = Chain::three_links();
    for n in 1..=5 {
        let pick = |v: &[f64]| (0..n).map(|i| v[i % v.len()]).collect::<Vec<_>>();
        let chain = Chain {
            links: (0..n).map(|i| three.links[i % 3]).collect(),
            length: pick(&three.length),
            coulomb: pick(&three.coulomb),
            viscous: pick(&three.viscous),
            spring: vec![0.0; n],
        };
        let (model, beta) = (chain.model(), chain.standard());
        assert_eq!(model.columns(), beta.len());
        let mut y = vec![0.0; n * model.columns()];
        for s in 0..200 {
            let g = |k: usize, a: f64| {
                (0..n)
                    .map(|j| a * ((s * 7 + j * 3 + k) as f64 * 0.37).sin())
                    .collect::<Vec<_>>()
            };
            let (q, qd, qdd) = (g(0, 1.5), g(1, 3.0), g(2, 12.0));
            LinearModel::fill(&model, &q, &qd, &qdd, &mut y).unwrap();
            let tau = chain.torques(&q, &qd, &qdd);
            for j in 0..n {
                let fit: f64 = (0..beta.len()).map(|c| y[n * c + j] * beta[c]).sum();
                assert!(
                    (fit - tau[j]).abs() < 1e-11,
                    "{n} links, sample {s}, joint {j}: {fit} vs {}",
                    tau[j]
                );
            }
        }
    }
}

/// Three joints, excited by `aras-excite`, identified in memory, streamed
/// and physically consistent: noise-free, the base parameters come back to
/// rounding error.
#[test]
fn three_link_chain_base_parameters_are_recovered_noise_free() {
    use planar_arm::chain::{Chain, identify};
    let samples = 2000;
    let o = identify(&Chain::three_links(), samples).unwrap();
    // The design does better than the typical random feasible trajectory.
    assert!(
        o.condition_number.is_finite() && o.condition_number < o.random_condition_median,
        "κ {} vs random median {}",
        o.condition_number,
        o.random_condition_median
    );
    // Izz, hx, hy of every link (the masses of links 2 and 3 grouped into
    // their predecessors) and 6 friction levels.
    assert_eq!(o.truth.len(), 15, "{:#?}", o.base_names);
    assert!(
        worst(&o.ols, &o.truth) < 1e-6,
        "OLS {:?} vs {:?}",
        o.ols,
        o.truth
    );
    assert_eq!(o.streaming_rows, vec![samples; 3]);
    assert!(
        worst(&o.streaming, &o.truth) < 1e-6,
        "streaming {:?} vs {:?}",
        o.streaming,
        o.truth
    );
    // As for two links: the SDP's regulariser and tolerance, 1e-3 relative.
    assert_eq!(o.sdp_status, aras_ident::SolverStatus::Solved);
    assert!(
        worst(&o.sdp, &o.truth) < 1e-3,
        "SDP {:?} vs {:?}",
        o.sdp,
        o.truth
    );
    assert_eq!(o.min_eigenvalues.len(), 3);
    // The same excitation as a measured log would arrive: three angle and
    // three torque columns, read, period-averaged and band-limited by the
    // processing in joint coordinates of run-time dimension, streamed.
    let period = o.trajectory.period();
    let csv = planar_arm::chain::log_csv(&Chain::three_links(), &o.trajectory, 1000.0, 3, None);
    let l = planar_arm::chain::identify_log(&Chain::three_links(), &csv, period).unwrap();
    assert_eq!(l.joints, 3);
    assert_eq!(l.samples, (period * 1000.0).round() as usize);
    assert!(l.bandwidth.contains("Fourier series"), "{}", l.bandwidth);
    eprintln!(
        "three links from a log: worst relative error {:.1e}; {}",
        worst(&l.streaming, &l.truth),
        l.bandwidth
    );
    assert!(
        worst(&l.streaming, &l.truth) < 1e-6,
        "from the log {:?} vs {:?} ({})",
        l.streaming,
        l.truth,
        l.bandwidth
    );

    // One effect hidden from the model, a spring on joint 2: the selection
    // engine names it (and nothing else) from the excitation, judged on a
    // random feasible motion of the same period, and fits its stiffness.
    let mut sprung = Chain::three_links();
    sprung.spring[1] = 0.35;
    let settings = aras_excite::DesignSettings {
        harmonics: 3,
        omega_f: std::f64::consts::TAU / period,
        ..aras_excite::DesignSettings::new(planar_arm::chain::limits(3))
    };
    let other = aras_excite::random_feasible(&settings, 1, 11)
        .unwrap()
        .remove(0);
    let train = planar_arm::chain::log_csv(&sprung, &o.trajectory, 1000.0, 2, None);
    let validation = planar_arm::chain::log_csv(&sprung, &other, 1000.0, 2, None);
    let d = planar_arm::chain::diagnose_logs(&sprung, &train, &validation, period).unwrap();
    eprintln!("three links, hidden spring on joint 2: {d:?}");
    assert_eq!(d.added, ["spring_2"], "{d:?}");
    assert!((d.values[0] - 0.35).abs() < 1e-6 * 0.35, "{d:?}");
    assert!(d.fitness_after.iter().all(|f| *f > 99.99), "{d:?}");
    assert!(d.fitness_before[1] < d.fitness_after[1] - 1.0, "{d:?}");
    // With sensor noise (encoder-scale angle noise, 5 mN·m on the torques)
    // and 8 periods each: the same effect and nothing else, its stiffness
    // within 1 % (σ of the averaged, band-limited fit ≈ 0.1 %).
    let noise = |seed| planar_arm::chain::Noise {
        angle: 2e-5,
        torque: 5e-3,
        seed,
    };
    let train = planar_arm::chain::log_csv(&sprung, &o.trajectory, 1000.0, 8, Some(noise(1)));
    let validation = planar_arm::chain::log_csv(&sprung, &other, 1000.0, 8, Some(noise(2)));
    let d = planar_arm::chain::diagnose_logs(&sprung, &train, &validation, period).unwrap();
    eprintln!("three links, noisy logs, hidden spring on joint 2: {d:?}");
    assert_eq!(d.added, ["spring_2"], "{d:?}");
    assert!((d.values[0] - 0.35).abs() < 0.01 * 0.35, "{d:?}");
    assert!(
        o.min_eigenvalues.iter().all(|&e| e > 0.0),
        "{:?}",
        o.min_eigenvalues
    );
}
