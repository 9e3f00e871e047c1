//! `aras identify --urdf`: a simulated Panda log identified from its URDF,
//! the identified URDF and MJCF written beside `params.json`.

use std::process::Command;

use aras_excite::FourierTrajectory;
use aras_urdf::sim::{ArmController, ArmSensors, ArmSimulation, simulate};
use aras_urdf::{ModelSettings, UrdfModel};
use nalgebra::Dyn;

const PANDA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../fixtures/urdf/panda_arm.urdf"
);

#[test]
fn a_panda_log_is_identified_from_its_urdf() {
    let dir = aras_testkit::Scratch::new("identify-urdf");
    let model = UrdfModel::from_file(PANDA, ModelSettings::default()).unwrap();
    // The simulated robot's Coulomb law is smooth (0.02 rad/s, the
    // command's model); a sign law is refused by the simulator.
    let plant = UrdfModel::from_file(
        PANDA,
        ModelSettings {
            coulomb_width: aras_urdf::CoulombWidth::Uniform(0.02),
            ..ModelSettings::default()
        },
    )
    .unwrap();
    assert!(
        simulate(
            &model,
            &model.urdf_parameters(),
            &FourierTrajectory::<Dyn>::new(
                1.0,
                vec![0.0; 7],
                vec![vec![0.0]; 7],
                vec![vec![0.0]; 7]
            )
            .unwrap(),
            &ArmSimulation::new(
                ArmController {
                    kp: vec![0.0; 7],
                    kd: vec![0.0; 7],
                    velocity_cutoff_hz: 30.0,
                    feedforward: None
                },
                ArmSensors::uniform(7)
            )
        )
        .unwrap_err()
        .to_string()
        .contains("coulomb_width")
    );
    let n = model.dof();
    // The truth: the URDF's inertials with viscous, Coulomb and armature
    // (the default joint columns, in that order per joint).
    let mut p = model.urdf_parameters();
    for j in 0..n {
        let c = 10 * n + 3 * j;
        p[c..c + 3].copy_from_slice(&[0.3 + 0.05 * j as f64, 0.6, 0.1 + 0.02 * j as f64]);
    }
    let mut u = 0.5f64;
    let mut next = move || {
        u = (u + 0.618_033_988_749_895) % 1.0;
        0.5 * u - 0.25
    };
    let (mut offset, mut a, mut b) = (Vec::new(), Vec::new(), Vec::new());
    for j in model.joints() {
        let l = j.limits.unwrap();
        offset.push(0.5 * (l.lower.unwrap() + l.upper.unwrap()));
        a.push((0..5).map(|_| next()).collect::<Vec<_>>());
        b.push((0..5).map(|_| next()).collect::<Vec<_>>());
    }
    let trajectory =
        FourierTrajectory::<Dyn>::new(std::f64::consts::TAU / 10.0, offset.clone(), a, b).unwrap();
    let mut controller = ArmController::for_model(&plant, &p, &offset, 10.0).unwrap();
    controller.feedforward = Some(model.urdf_parameters());
    let sim = ArmSimulation {
        duration_s: 30.0,
        ..ArmSimulation::new(controller, ArmSensors::uniform(n))
    };
    let log = simulate(&plant, &p, &trajectory, &sim).unwrap();
    std::fs::write(dir.join("panda.csv"), log.to_csv(false)).unwrap();

    let out = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["identify", "--urdf", PANDA, "--period", "10", "--data"])
        .arg(dir.join("panda.csv"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("7 joints, 10000 processed samples"),
        "{stdout}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("params.json")).unwrap()).unwrap();
    assert_eq!(json["format"], "aras-urdf-params/1");
    assert_eq!(json["status"], "Solved");
    assert_eq!(json["joints"].as_array().unwrap().len(), 7);
    // The identified URDF carries the consistent inertials, read back as
    // written; its masses are within 1 % of the truth's.
    let standard: Vec<f64> = json["standard"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let text = std::fs::read_to_string(out.join("robot_identified.urdf")).unwrap();
    let again = UrdfModel::from_urdf_str(&text, "id.urdf", ModelSettings::default()).unwrap();
    for (k, (x, y)) in again
        .urdf_parameters()
        .iter()
        .zip(&standard)
        .take(10 * n)
        .enumerate()
    {
        assert!((x - y).abs() <= 1e-9 * y.abs().max(1e-3), "{k}: {x} vs {y}");
    }
    assert!(
        std::fs::read_to_string(out.join("robot.xml"))
            .unwrap()
            .starts_with("<mujoco")
    );

    // A log of another robot is refused with the joint counts.
    let mut two = String::from("t,theta1,theta2,tau1,tau2\n");
    for i in 0..2000 {
        let t = i as f64 * 1e-3;
        two += &format!("{t},{},{},0.1,0.2\n", 0.1 * t.sin(), 0.1 * t.cos());
    }
    std::fs::write(dir.join("two.csv"), two).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["identify", "--urdf", PANDA, "--data"])
        .arg(dir.join("two.csv"))
        .arg("--out")
        .arg(dir.join("out2"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("7") && err.contains("joint"), "{err}");
    assert!(!dir.join("out2").exists());
}
