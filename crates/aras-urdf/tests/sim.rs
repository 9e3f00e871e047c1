//! The simulated arm: its forward dynamics inverts RNEA, RK4 keeps the
//! energy of a free arm, and OLS and the physically consistent SDP on a
//! simulated Panda log recover the base parameters within their σ and
//! predict another trajectory to its noise ceiling.

mod common;

use aras_excite::FourierTrajectory;
use aras_ident::{ConsistentLs, LinearModel, LinkLayout, ReducedLs};
use aras_urdf::sim::{ArmController, ArmSensors, ArmSimulation, simulate};
use aras_urdf::{JointColumns, UrdfModel, Workspace};
use common::{ALL, excitation, panda, sequence};
use nalgebra::Dyn;

/// The URDF's inertials with friction, offset and armature of their usual
/// sizes.
fn truth(model: &UrdfModel) -> Vec<f64> {
    let mut p = model.urdf_parameters();
    for j in 0..model.dof() {
        let b = 70 + 4 * j;
        p[b..b + 4].copy_from_slice(&[
            0.3 + 0.05 * j as f64,
            0.8 - 0.1 * j as f64,
            0.02 * j as f64 - 0.05,
            0.1 + 0.02 * j as f64,
        ]);
    }
    p
}

/// The Panda's 60 s run: gains on the drive's inertia as its designer
/// knows it (armature included) for 10 Hz, feedforward from the URDF alone
/// (no friction, no armature), `sensors`.
fn panda_run(
    model: &UrdfModel,
    p: &[f64],
    sensors: ArmSensors,
) -> (
    FourierTrajectory<Dyn>,
    ArmSimulation,
    aras_urdf::sim::ArmLog,
) {
    let (offset, trajectory) = excitation(model, 0);
    let mut controller = ArmController::for_model(model, p, &offset, 10.0).unwrap();
    controller.feedforward = Some(model.urdf_parameters());
    let sim = ArmSimulation::new(controller, sensors);
    let log = simulate(model, p, &trajectory, &sim).unwrap();
    (trajectory, sim, log)
}

/// Fitness (78) of `params` on a 20 s run of another trajectory (another
/// noise seed), and the noise ceiling (the true torques against the
/// logged), per joint.
fn cross_validation(
    model: &UrdfModel,
    p: &[f64],
    params: &[f64],
    sim: &ArmSimulation,
) -> Vec<(f64, f64)> {
    let n = model.dof();
    let (_, other) = excitation(model, 40);
    let check = simulate(
        model,
        p,
        &other,
        &ArmSimulation {
            duration_s: 20.0,
            seed: 7,
            ..sim.clone()
        },
    )
    .unwrap();
    let mut predicted = vec![Vec::new(); n];
    for r in 0..check.t.len() {
        let q: Vec<f64> = check.q_exact.iter().map(|c| c[r]).collect();
        let v: Vec<f64> = check.qd.iter().map(|c| c[r]).collect();
        let acc: Vec<f64> = check.qdd.iter().map(|c| c[r]).collect();
        let t = model.inverse_dynamics(params, &q, &v, &acc).unwrap();
        for (c, t) in predicted.iter_mut().zip(t) {
            c.push(t);
        }
    }
    check
        .tau
        .iter()
        .zip(&check.tau_clean)
        .zip(&predicted)
        .map(|((tau, clean), pred)| {
            (
                aras_ident::validate::fitness(tau, pred).unwrap(),
                aras_ident::validate::fitness(tau, clean).unwrap(),
            )
        })
        .collect()
}

#[test]
fn forward_dynamics_inverts_rnea() {
    let model = panda(ALL, [0.4, -0.3, -9.8]);
    let p = truth(&model);
    let mut ws = Workspace::new(&model);
    let mut next = sequence();
    for _ in 0..200 {
        let q: Vec<f64> = (0..7).map(|_| 2.5 * next()).collect();
        let qd: Vec<f64> = (0..7).map(|_| 2.0 * next()).collect();
        let qdd: Vec<f64> = (0..7).map(|_| 8.0 * next()).collect();
        let tau = model.inverse_dynamics(&p, &q, &qd, &qdd).unwrap();
        let a = model.forward_dynamics(&mut ws, &p, &q, &qd, &tau).unwrap();
        for (x, y) in a.iter().zip(&qdd) {
            // The mass matrix's condition (armature 0.1–0.22 kg·m² against
            // wrist inertias of 1e-3) bounds the solve's error.
            assert!((x - y).abs() < 1e-9 * (1.0 + y.abs()), "{a:?} vs {qdd:?}");
        }
    }
}

/// A free arm (no gravity, friction or torque) keeps its kinetic energy
/// `½ q̇ᵀ M q̇`: RK4 at 2 kHz for 2 s from a fast start.
#[test]
fn a_free_arm_keeps_its_energy() {
    let model = panda(JointColumns::none(), [0.0; 3]);
    let p = model.urdf_parameters();
    let n = model.dof();
    let still =
        FourierTrajectory::<Dyn>::new(1.0, vec![0.3; n], vec![vec![1.5]; n], vec![vec![0.0]; n])
            .unwrap();
    let controller = ArmController {
        kp: vec![0.0; n],
        kd: vec![0.0; n],
        velocity_cutoff_hz: 100.0,
        feedforward: None,
    };
    let sim = ArmSimulation {
        duration_s: 2.0,
        lead_in_s: 0.0,
        ..ArmSimulation::new(controller, ArmSensors::uniform(n))
    };
    let log = simulate(&model, &p, &still, &sim).unwrap();
    let mut ws = Workspace::new(&model);
    let mut energy = |r: usize| {
        let q: Vec<f64> = log.q_exact.iter().map(|c| c[r]).collect();
        let v: Vec<f64> = log.qd.iter().map(|c| c[r]).collect();
        let (m, _) = model.mass_matrix_and_bias(&mut ws, &p, &q, &v).unwrap();
        let mut e = 0.0;
        for i in 0..n {
            for j in 0..n {
                e += 0.5 * v[i] * m[i * n + j] * v[j];
            }
        }
        e
    };
    let e0 = energy(0);
    let worst = (0..log.t.len())
        .step_by(100)
        .map(|r| (energy(r) / e0 - 1.0).abs())
        .fold(0.0, f64::max);
    // RK4's energy error per step is O((hω)⁵) with h = 0.5 ms and rates of
    // a few rad/s: 3e-13 over 4000 steps measured.
    assert!(e0 > 0.1 && worst < 1e-11, "E0 {e0}, drift {worst}");
}

/// A 60 s Panda log (period 10 s, five harmonics per joint inside the
/// joint limits) under PD + feedforward of the URDF's own parameters (the
/// truth has friction, offsets and armature besides): OLS on the exact
/// states and the logged torques (current noise 0.05 N·m) recovers every
/// base parameter, and its σ is the real spread: `Σ z² / n_base` near 1,
/// every `|z| < 4.5` (with 71 Gaussian errors, 3σ would be exceeded by one
/// of them one time in six).
#[test]
fn ols_on_a_simulated_panda_log_recovers_the_base_parameters() {
    let model = panda(ALL, [0.4, -0.3, -9.8]);
    let n = model.dof();
    let p = truth(&model);
    let (trajectory, sim, log) = panda_run(&model, &p, ArmSensors::uniform(n));
    let rows = log.t.len();
    assert_eq!(rows, 60_000);
    // The robot tracks to a fraction of a milliradian.
    let mut per = vec![0.0f64; n];
    let (mut qd, mut vd, mut ad) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for r in (0..rows).step_by(10) {
        trajectory.eval_into(log.t[r], &mut qd, &mut vd, &mut ad);
        for j in 0..n {
            per[j] = per[j].max((log.q_exact[j][r] - qd[j]).abs());
        }
    }
    // 0.4–1.2 mrad measured: the friction the feedforward leaves out over
    // gains of 10 Hz bandwidth.
    let worst = per.iter().fold(0.0f64, |a, &b| a.max(b));
    assert!(worst < 2e-3, "tracking error {per:?} rad");
    // The log in the toolkit's format reads back as seven joints, every
    // number exact.
    let csv = log.to_csv(true);
    let read = aras_log::read_log_from(csv.as_bytes(), "panda.csv", &Default::default()).unwrap();
    assert_eq!(read.joints(), n);
    assert!(read.t == log.t && read.theta == log.q && read.tau == log.tau);
    assert!(read.theta_dot.as_ref() == Some(&log.qd));

    // Base parameters at quasi-random states, then OLS on every fifth row
    // of the log.
    let cols = model.columns();
    let mut y = vec![0.0; n * cols];
    let base = model.base_parameters(600).unwrap();
    let used: Vec<usize> = (0..rows).step_by(5).collect();
    let m = used.len();
    let mut w = faer::Mat::<f64>::zeros(n * m, cols);
    let mut tau = vec![0.0; n * m];
    for (s, &r) in used.iter().enumerate() {
        let q: Vec<f64> = log.q_exact.iter().map(|c| c[r]).collect();
        let v: Vec<f64> = log.qd.iter().map(|c| c[r]).collect();
        let acc: Vec<f64> = log.qdd.iter().map(|c| c[r]).collect();
        model.fill(&q, &v, &acc, &mut y).unwrap();
        for j in 0..n {
            for c in 0..cols {
                w[(j * m + s, c)] = y[n * c + j];
            }
            tau[j * m + s] = log.tau[j][r];
        }
    }
    let wb = base.base_regressor(w.as_ref()).unwrap();
    let reduced = ReducedLs::new(wb.as_ref(), &tau, &base.base_names()).unwrap();
    let fit = reduced.ols().unwrap();
    let want = base.to_base(&p).unwrap();

    // The streaming route (`aras-ident`'s stage: the model's rows into
    // running sums, block by block, in parallel) on the same rows gives
    // the same estimate and σ: 84 000 rows of 71 base columns leave the
    // checked Gram path eleven digits.
    let pick = |c: &[Vec<f64>]| -> Vec<Vec<f64>> {
        c.iter()
            .map(|c| used.iter().map(|&r| c[r]).collect())
            .collect()
    };
    let (sq, sv, sa, st) = (
        pick(&log.q_exact),
        pick(&log.qd),
        pick(&log.qdd),
        pick(&log.tau),
    );
    let (vq, vv, va, vt) = (slices(&sq), slices(&sv), slices(&sa), slices(&st));
    let mut stage = aras_ident::streaming::RegressorStage::new(&model, &base).unwrap();
    stage
        .push(&aras_ident::streaming::States {
            x: &vq,
            x_dot: &vv,
            x_ddot: &va,
            tau: &vt,
        })
        .unwrap();
    assert_eq!(stage.samples(), m);
    let streamed = stage.accumulator().reduced().unwrap().ols().unwrap();
    for k in 0..fit.estimate.len() {
        let (a, b) = (streamed.estimate[k], fit.estimate[k]);
        assert!(
            (a - b).abs() <= 1e-6 * fit.std_dev[k],
            "{}: streamed {a} vs in memory {b} ± {}",
            base.expression(k),
            fit.std_dev[k]
        );
        let (a, b) = (streamed.std_dev[k], fit.std_dev[k]);
        assert!(
            (a / b - 1.0).abs() < 1e-6,
            "{}: σ {a} vs {b}",
            base.expression(k)
        );
    }
    let z: Vec<f64> = fit
        .estimate
        .iter()
        .zip(&fit.std_dev)
        .zip(&want)
        .map(|((e, s), t)| (e - t) / s)
        .collect();
    let chi = z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64;
    let zmax = z.iter().fold(0.0f64, |a, z| a.max(z.abs()));
    assert!(
        zmax < 4.5 && (0.6..1.5).contains(&chi),
        "max |z| {zmax}, mean z² {chi}"
    );

    // Physically consistent: one pseudo-inertia per body on its own mass
    // column (masses within ±50 % of the URDF's), friction and armature
    // ≥ 0, the URDF as the reference. The truth is physical, so the
    // solution keeps the OLS fit: every base parameter within 4.5 σ of the
    // truth still.
    let names = model.parameter_names();
    let mut problem = ConsistentLs::new(&names, model.urdf_parameters()).unwrap();
    for l in model.link_columns() {
        let m = model.urdf_parameters()[l.mass];
        problem
            .link(
                LinkLayout::new(l.link.clone(), l.inertia, l.first_moment, m)
                    .with_mass_column(l.mass)
                    .with_mass_bounds(0.5 * m, 1.5 * m),
            )
            .unwrap();
    }
    let signed: Vec<&str> = names
        .iter()
        .filter(|n| n.ends_with(".Fv") || n.ends_with(".Fc") || n.ends_with(".Ia"))
        .map(String::as_str)
        .collect();
    problem.nonnegative(&signed).unwrap();
    let sdp = problem.solve(&base, &reduced).unwrap();
    assert_eq!(sdp.status, aras_ident::SolverStatus::Solved);
    for l in &sdp.links {
        assert!(l.min_eigenvalue > 0.0, "{}: {}", l.name, l.min_eigenvalue);
    }
    for (((e, s), t), k) in sdp.base.iter().zip(&fit.std_dev).zip(&want).zip(0..) {
        assert!(
            (e - t).abs() < 4.5 * s,
            "{}: {e} vs {t} ± {s}",
            base.expression(k)
        );
    }
    // Its masses are its mass parameters.
    for (l, m) in model.link_columns().iter().zip(&sdp.masses) {
        assert!((sdp.standard[l.mass] - m).abs() <= 1e-9 * m, "{}", l.link);
    }

    // Cross-validation on another trajectory (other coefficients, 20 s):
    // the consistent parameters predict its logged torques within 0.05
    // points of the noise ceiling per joint (0.0008–0.012 measured: 71
    // parameters from 84 000 rows leave a prediction error far under the
    // noise).
    for (j, (fit, ceiling)) in cross_validation(&model, &p, &sdp.standard, &sim)
        .iter()
        .enumerate()
    {
        assert!(
            fit > &(ceiling - 0.05),
            "joint {}: {fit} vs ceiling {ceiling}",
            j + 1
        );
    }
}

/// The recipe from the log alone (`aras_urdf::identify`): the 60 s Panda
/// log written in the toolkit's format and read back, processed from its
/// quantised angles (one averaged period, the data-chosen bandwidth), OLS
/// and the consistent estimate, which predicts another trajectory's
/// torques within 0.1 points of the noise ceiling per joint (0.0014–0.0084
/// measured).
#[test]
fn the_recipe_identifies_the_panda_from_its_log() {
    let model = panda(ALL, [0.4, -0.3, -9.8]);
    let n = model.dof();
    let p = truth(&model);
    let (_, sim, log) = panda_run(&model, &p, ArmSensors::uniform(n));
    let (gaps, status) = recipe_gaps(&model, &p, &sim, &log);
    assert_eq!(status, aras_ident::SolverStatus::Solved);
    for (j, gap) in gaps.iter().enumerate() {
        assert!(
            *gap < 0.1,
            "joint {}: {gap} points below the ceiling",
            j + 1
        );
    }
}

/// Each channel as a slice.
fn slices(c: &[Vec<f64>]) -> Vec<&[f64]> {
    c.iter().map(Vec::as_slice).collect()
}

/// The recipe's least squares from the log alone against the truth: every
/// base parameter from the processed, quantised angles (one averaged
/// period, the data-chosen bandwidth) within 3σ of the truth's on the
/// default noise seed (max |z| 2.92 measured; 3.15, 2.48 and 2.85 on the
/// other three seeds, as 62 Gaussian errors do: one in six such runs has
/// one beyond 3), and the σ the real spread over four seeds: mean z² of the
/// 248 errors within its ±3σ band (`1 ± 3 √(2/248)`, 0.98 measured). The log is read as what the
/// simulator writes, torques held over each step: read as sampled, the
/// half-sample shift between torques and angles biases joint 2's viscous
/// friction by 12σ (mean z² 9.3 on the default seed).
#[test]
fn the_recipe_s_base_parameters_are_the_truth_s_within_3_sigma() {
    let model = panda(ALL, [0.4, -0.3, -9.8]);
    let p = truth(&model);
    let settings = aras_urdf::identify::IdentifySettings {
        period: Some(10.0),
        ..Default::default()
    };
    let base = model.base_parameters(settings.base_states).unwrap();
    let want = base.to_base(&p).unwrap();
    let z_of = |seed: u64| -> Vec<f64> {
        let (offset, trajectory) = excitation(&model, 0);
        let mut controller = ArmController::for_model(&model, &p, &offset, 10.0).unwrap();
        controller.feedforward = Some(model.urdf_parameters());
        let sim = ArmSimulation {
            seed,
            ..ArmSimulation::new(controller, ArmSensors::uniform(model.dof()))
        };
        let log = simulate(&model, &p, &trajectory, &sim).unwrap();
        let read = aras_log::read_log_from(
            log.to_csv(false).as_bytes(),
            "panda.csv",
            &aras_log::ReadOptions {
                torques: Some(aras_log::TorqueTiming::Held),
                ..Default::default()
            },
        )
        .unwrap();
        let id = aras_urdf::identify::identify(&model, &read, &settings).unwrap();
        assert_eq!(id.base_names, base.expressions());
        id.ols
            .iter()
            .zip(&id.ols_sigma)
            .zip(&want)
            .map(|((e, s), t)| (e - t) / s)
            .collect()
    };
    let runs: Vec<Vec<f64>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (1..=4u64)
            .map(|seed| scope.spawn(move || z_of(seed)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let z = &runs[0];
    let zmax = z.iter().fold(0.0f64, |a, z| a.max(z.abs()));
    let worst = z.iter().position(|x| x.abs() == zmax).unwrap();
    assert!(
        zmax < 3.0,
        "seed 1: max |z| {zmax} ({})",
        base.expression(worst)
    );
    let all: Vec<f64> = runs.concat();
    let chi = all.iter().map(|z| z * z).sum::<f64>() / all.len() as f64;
    let band = 3.0 * (2.0 / all.len() as f64).sqrt();
    assert!(
        (chi - 1.0).abs() < band,
        "mean z² {chi} over {} errors, outside 1 ± {band}",
        all.len()
    );
}

/// The limit of the angles: with 4096-count encoders (1.5e-5 rad at the
/// joint, 16 times coarser) the controller's reaction to the quantisation
/// puts torque into the log that the angles do not show. The recipe's
/// estimate falls 0.08–0.31 points below the ceiling per joint, every joint
/// more than five times the default encoders' largest gap (0.0084; measured
/// ≥ 9 times), and the consistent fit ends on the boundary of physical
/// consistency (the solver at reduced accuracy). Behind `--ignored`: it
/// documents a limit, not a guarantee.
#[test]
#[ignore]
fn coarse_encoders_cost_the_recipe_fitness() {
    let model = panda(ALL, [0.4, -0.3, -9.8]);
    let n = model.dof();
    let p = truth(&model);
    let (_, sim, log) = panda_run(&model, &p, ArmSensors::uniform(n));
    let (fine, _) = recipe_gaps(&model, &p, &sim, &log);
    let worst_fine = fine.iter().fold(0.0f64, |a, g| a.max(*g));
    let mut sensors = ArmSensors::uniform(n);
    sensors.counts_per_rev = vec![4096; n];
    let (_, sim, log) = panda_run(&model, &p, sensors);
    let (coarse, _) = recipe_gaps(&model, &p, &sim, &log);
    assert!(
        coarse.iter().all(|g| *g > 5.0 * worst_fine),
        "coarse {coarse:?} vs fine {fine:?}"
    );
}

/// The recipe on `log`, then the points by which its consistent estimate
/// falls below the ceiling on another trajectory, per joint, and the SDP's
/// status.
fn recipe_gaps(
    model: &UrdfModel,
    p: &[f64],
    sim: &ArmSimulation,
    log: &aras_urdf::sim::ArmLog,
) -> (Vec<f64>, aras_ident::SolverStatus) {
    let csv = log.to_csv(false);
    let read = aras_log::read_log_from(csv.as_bytes(), "panda.csv", &Default::default()).unwrap();
    let settings = aras_urdf::identify::IdentifySettings {
        period: Some(10.0),
        ..Default::default()
    };
    let id = aras_urdf::identify::identify(model, &read, &settings).unwrap();
    assert_eq!(id.samples, 10_000);
    assert!(
        id.min_eigenvalues.iter().all(|&e| e > 0.0),
        "{:?}",
        id.min_eigenvalues
    );
    let gaps = cross_validation(model, p, &id.standard, sim)
        .iter()
        .map(|(fit, ceiling)| ceiling - fit)
        .collect();
    (gaps, id.status)
}
