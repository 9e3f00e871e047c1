//! The diagnosis of a simulated Panda: friction above the Coulomb level at
//! low speed hidden on joint 4 (off the scan's grid) is named on that
//! joint with its Stribeck velocity and level recovered within their σ,
//! and nothing is named on the control (the same runs without it).

mod common;

use aras_diagnose::Candidate;
use aras_urdf::diagnose::{DiagnoseSettings, diagnose};
use aras_urdf::sim::{
    ArmController, ArmSensors, ArmSimulation, DriveTruth, HiddenEffect, simulate,
};
use aras_urdf::{CoulombWidth, ModelSettings, UrdfModel};
use common::{PANDA, excitation};

/// The simulated robot's hidden Stribeck hump on joint 4 (0-based 3):
/// 0.2 N·m above the 0.5 N·m Coulomb level (`Fs/Fc` = 1.4), `v_s` 0.03 rad/s
/// (between the scan's 0.02 and 0.05).
const LEVEL: f64 = 0.2;
const V_S: f64 = 0.03;

/// The Panda as `identify --urdf` models it (viscous, Coulomb with a
/// 0.02 rad/s width, armature).
fn model() -> UrdfModel {
    UrdfModel::from_file(
        PANDA,
        ModelSettings {
            coulomb_width: CoulombWidth::Uniform(0.02),
            ..ModelSettings::default()
        },
    )
    .unwrap()
}

/// A 60 s training and a 20 s validation log (another trajectory, another
/// noise seed) of the robot with `hidden`.
fn logs(model: &UrdfModel, hidden: &[HiddenEffect]) -> (aras_log::Log, aras_log::Log) {
    let truth = DriveTruth::default().parameters(model);
    let run = |skip: usize, duration_s: f64, seed: u64, name: &str| {
        let (_, trajectory) = excitation(model, skip);
        let mut controller =
            ArmController::for_trajectory(model, &truth, &trajectory, 10.0, 10.0).unwrap();
        controller.feedforward = Some(model.urdf_parameters());
        let sim = ArmSimulation {
            duration_s,
            seed,
            hidden: hidden.to_vec(),
            ..ArmSimulation::new(controller, ArmSensors::uniform(model.dof()))
        };
        let log = simulate(model, &truth, &trajectory, &sim).unwrap();
        let options = aras_log::ReadOptions {
            torques: Some(aras_log::TorqueTiming::Held),
            ..Default::default()
        };
        aras_log::read_log_from(log.to_csv(false).as_bytes(), name, &options).unwrap()
    };
    (run(0, 60.0, 1, "train"), run(40, 20.0, 7, "validation"))
}

fn settings() -> DiagnoseSettings {
    DiagnoseSettings {
        period: Some(10.0),
        ..DiagnoseSettings::default()
    }
}

#[test]
fn hidden_stribeck_friction_on_joint_4_is_named_with_its_values() {
    let model = model();
    let hidden = [HiddenEffect::Stribeck {
        joint: 3,
        level: LEVEL,
        v_s: V_S,
    }];
    let (train, validation) = logs(&model, &hidden);
    let d = diagnose(&model, &train, &[validation], &settings()).unwrap();
    let names: Vec<String> = d.steps.iter().map(|s| s.id.clone()).collect();
    assert_eq!(
        names,
        ["stribeck_friction:panda_joint4"],
        "{}",
        d.conclusion
    );
    let step = &d.steps[0];
    assert_eq!(step.candidate.joints(), Some(vec![3]));
    let r = step.refinement.as_ref().expect("v_s is refined");
    // Measured: v_s 0.0302 ± 0.0003 rad/s, Fs 0.2017 ± 0.0018 N·m.
    assert!(
        (r.value - V_S).abs() <= 3.0 * r.std_dev && (r.value / V_S - 1.0).abs() < 0.3,
        "v_s {} ± {}",
        r.value,
        r.std_dev
    );
    let fs = &r.parameters[0];
    assert_eq!(fs.name, "panda_joint4.Fs");
    assert!(
        (fs.value - LEVEL).abs() <= 3.0 * fs.std_dev && fs.std_dev < 0.1 * LEVEL,
        "Fs {} ± {}",
        fs.value,
        fs.std_dev
    );
    // The physically consistent re-identification of the final model (v_s
    // at its refined value) solves, every body's pseudo-inertia held
    // positive definite, and its Stribeck level, held ≥ 0, is the truth's
    // within the OLS's 3σ (0.2017 N·m measured, as the OLS's).
    let c = d
        .consistent
        .as_ref()
        .expect("a consistent refit is offered");
    assert_eq!(c.status, aras_ident::SolverStatus::Solved);
    let level = c
        .parameters
        .iter()
        .find(|p| p.name == "panda_joint4.Fs")
        .expect("the Stribeck level is a parameter of the refit");
    assert!(
        (level.value - LEVEL).abs() <= 3.0 * fs.std_dev,
        "consistent Fs {} vs {LEVEL} ± {}",
        level.value,
        fs.std_dev
    );
    // The validation fitness of joint 4, on every row against the raw
    // torques, rises; no other joint's falls.
    let before = d.fitness[0].fitness[0].as_ref().unwrap();
    let after = d.fitness[1].fitness[0].as_ref().unwrap();
    assert!(after[3] > before[3], "{before:?} → {after:?}");
    for j in 0..7 {
        assert!(
            after[j] >= before[j] - 1e-3,
            "joint {}: {before:?} → {after:?}",
            j + 1
        );
    }
}

#[test]
fn nothing_is_named_on_the_control() {
    let model = model();
    let (train, validation) = logs(&model, &[]);
    let d = diagnose(&model, &train, &[validation], &settings()).unwrap();
    assert!(d.steps.is_empty(), "{}", d.conclusion);
    // The scan did run: every candidate was scored.
    assert_eq!(
        d.rounds[0].len(),
        aras_urdf::diagnose::candidates(&model, &settings()).len()
    );
}
