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
    logs_on_seeds(model, hidden, (1, 7))
}

/// [`logs`] with the training and validation logs' noise seeds.
fn logs_on_seeds(
    model: &UrdfModel,
    hidden: &[HiddenEffect],
    (train_seed, validation_seed): (u64, u64),
) -> (aras_log::Log, aras_log::Log) {
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
    (
        run(0, 60.0, train_seed, "train"),
        run(40, 20.0, validation_seed, "validation"),
    )
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

/// One case of the study: what is hidden, and the joint and Stribeck
/// velocity the diagnosis should name (`None`: nothing).
struct Case {
    name: &'static str,
    hidden: Vec<HiddenEffect>,
    expect: Option<(usize, f64)>,
}

/// The study over five noise seeds per case (other seeds than the tests
/// above; `docs/urdf.md`, "Diagnose", shows the table it prints): the
/// control names nothing; a Stribeck hump of 0.3 times the Coulomb level
/// (`Fs/Fc` = 1.3) with `v_s` 0.015, 0.03 or 0.07 rad/s (off the scan's
/// grid) on the wrist's joint 4, and with 0.03 rad/s on the shoulder's
/// joint 2 (which carries gravity torques of tens of N·m), is named first
/// and alone on its joint, `v_s` within ±30 %, on every seed. 70 s on two
/// cores, behind `--ignored`; its first seed runs in CI
/// ([`the_study_s_first_seed`]).
#[test]
#[ignore]
fn the_study_names_the_hump_on_every_seed_and_nothing_on_the_control() {
    study(&[0, 1, 2, 3, 4]);
}

/// The study's first seed, every case.
#[test]
fn the_study_s_first_seed() {
    study(&[0]);
}

/// Runs every case of the study on `seeds` (the training and validation
/// logs' noise seeds `100 + k` and `200 + k`), prints each outcome and
/// fails if any misses its case.
fn study(seeds: &[u64]) {
    let model = model();
    let level = 0.3 * DriveTruth::default().coulomb;
    let hump = |joint: usize, v_s: f64| HiddenEffect::Stribeck { joint, level, v_s };
    let mut cases = vec![Case {
        name: "control",
        hidden: vec![],
        expect: None,
    }];
    for (joint, v_s, name) in [
        (3, 0.015, "joint 4, v_s 0.015"),
        (3, 0.03, "joint 4, v_s 0.03"),
        (3, 0.07, "joint 4, v_s 0.07"),
        (1, 0.03, "joint 2, v_s 0.03"),
    ] {
        cases.push(Case {
            name,
            hidden: vec![hump(joint, v_s)],
            expect: Some((joint, v_s)),
        });
    }
    let runs: Vec<(&Case, u64)> = cases
        .iter()
        .flat_map(|c| seeds.iter().map(move |&k| (c, k)))
        .collect();
    // Two at a time: each diagnosis is itself parallel.
    let mut failures = Vec::new();
    for pair in runs.chunks(2) {
        let outcomes: Vec<String> = std::thread::scope(|scope| {
            let handles: Vec<_> = pair
                .iter()
                .map(|&(case, k)| {
                    let model = &model;
                    scope.spawn(move || {
                        let (train, validation) =
                            logs_on_seeds(model, &case.hidden, (100 + k, 200 + k));
                        let d = diagnose(model, &train, &[validation], &settings()).unwrap();
                        judge(case, &d)
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for (&(case, k), o) in pair.iter().zip(&outcomes) {
            eprintln!("study | {} | seed {k} | {o}", case.name);
            if o.starts_with("WRONG") {
                failures.push(format!("{}, seed {k}: {o}", case.name));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A seed's outcome in words, starting with `WRONG` if it misses the case.
fn judge(
    case: &Case,
    d: &aras_diagnose::Diagnosis<aras_urdf::diagnose::UrdfCandidate, Vec<String>>,
) -> String {
    let names: Vec<String> = d.steps.iter().map(|s| s.label.clone()).collect();
    let before = d.fitness[0].fitness[0].as_ref().unwrap();
    let after = d.fitness.last().unwrap().fitness[0].as_ref().unwrap();
    match case.expect {
        None if names.is_empty() => "nothing named".into(),
        None => format!("WRONG: named {names:?}"),
        Some((joint, v_s)) => {
            let Some(step) = d.steps.first() else {
                return "WRONG: nothing named".into();
            };
            let r = step.refinement.as_ref();
            let (v, sd) = r.map_or((f64::NAN, f64::NAN), |r| (r.value, r.std_dev));
            let right = d.steps.len() == 1
                && step.candidate.joints() == Some(vec![joint])
                && (v / v_s - 1.0).abs() <= 0.3;
            format!(
                "{}{} v_s {v:.4} ± {sd:.4} ({:+.0} %), joint {} fitness {:.3} → {:.3} %",
                if right { "" } else { "WRONG: " },
                names.join(" + "),
                100.0 * (v / v_s - 1.0),
                joint + 1,
                before[joint],
                after[joint]
            )
        }
    }
}

/// The named effect added to the model that is used afterwards: the Panda
/// model with a Stribeck column on joint 4 at the diagnosis's refined
/// `v_s` (`ModelSettings::stribeck`, what `identify --urdf --effects
/// stribeck_friction:panda_joint4:V_S` builds), identified on the same
/// training log, recovers the hump's level within 3σ (0.2017 ± 0.0018
/// N·m measured), and on the validation log it predicts within 0.01 point
/// of the simulated robot's own parameters on every joint (0.0000–0.0015
/// measured), where the model without it falls 0.145 points short on
/// joint 4 (and up to 0.02 on the others, whose parameters the missing
/// hump pulls).
#[test]
fn the_named_hump_in_the_model_is_identified_and_closes_the_gap() {
    use aras_urdf::identify::{IdentifySettings, identify};
    use aras_urdf::predict::{PredictSettings, predict};
    let plain = model();
    let hidden = [HiddenEffect::Stribeck {
        joint: 3,
        level: LEVEL,
        v_s: V_S,
    }];
    let (train, validation) = logs(&plain, &hidden);
    let d = diagnose(
        &plain,
        &train,
        std::slice::from_ref(&validation),
        &settings(),
    )
    .unwrap();
    let v_s = d.steps[0].refinement.as_ref().unwrap().value;
    let with = UrdfModel::from_file(
        PANDA,
        ModelSettings {
            stribeck: vec![aras_urdf::StribeckColumn {
                joint: "panda_joint4".into(),
                v_s,
            }],
            ..plain.settings().clone()
        },
    )
    .unwrap();
    assert_eq!(with.parameter_count(), plain.parameter_count() + 1);
    let id_settings = IdentifySettings {
        period: Some(10.0),
        ..IdentifySettings::default()
    };
    let id = identify(&with, &train, &id_settings).unwrap();
    assert_eq!(id.status, aras_ident::SolverStatus::Solved);
    let k = id
        .base_names
        .iter()
        .position(|b| b.ends_with("= panda_joint4.Fs"))
        .expect("the Stribeck level is a base parameter of its own");
    let (fs, sd) = (id.ols[k], id.ols_sigma[k]);
    assert!(
        (fs - LEVEL).abs() <= 3.0 * sd && sd < 0.05 * LEVEL,
        "Fs {fs} ± {sd}"
    );
    let consistent = id.standard[with.parameter_count() - 1];
    assert!(
        (consistent - LEVEL).abs() <= 3.0 * sd,
        "consistent Fs {consistent}"
    );
    // On the validation log: the simulated robot's own parameters (its
    // hump in the added column) set the ceiling.
    let mut truth = DriveTruth::default().parameters(&plain);
    let p = PredictSettings::default();
    let without = identify(&plain, &train, &id_settings).unwrap();
    let f_without = predict(&plain, &without.standard, &validation, &p)
        .unwrap()
        .fitness;
    let f_with = predict(&with, &id.standard, &validation, &p)
        .unwrap()
        .fitness;
    truth.push(LEVEL);
    let wide = UrdfModel::from_file(
        PANDA,
        ModelSettings {
            stribeck: vec![aras_urdf::StribeckColumn {
                joint: "panda_joint4".into(),
                v_s: V_S,
            }],
            ..plain.settings().clone()
        },
    )
    .unwrap();
    let ceiling = predict(&wide, &truth, &validation, &p).unwrap().fitness;
    for j in 0..7 {
        assert!(
            f_with[j] > ceiling[j] - 0.01,
            "joint {}: {} vs ceiling {}",
            j + 1,
            f_with[j],
            ceiling[j]
        );
    }
    assert!(
        f_with[3] - f_without[3] > 0.05,
        "joint 4: {} → {}",
        f_without[3],
        f_with[3]
    );
}
