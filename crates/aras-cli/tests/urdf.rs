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

/// Runs `aras` with `args` in `dir`, asserting success; its stdout.
fn aras(dir: &std::path::Path, args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_aras"))
        .current_dir(dir)
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "aras {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Runs `aras` with `args` in `dir`, asserting failure; its stderr.
fn aras_fails(dir: &std::path::Path, args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_aras"))
        .current_dir(dir)
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(!o.status.success(), "aras {args:?} succeeded");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The serial-arm tour of `docs/urdf.md` on the Panda, command by command:
/// an excitation designed in the URDF's limits (κ at least 2.5× below the
/// random median), a simulated robot with Stribeck friction hidden on
/// joint 4, its identification, a prediction and a validation on another
/// motion, and the diagnosis naming the hidden effect.
#[test]
fn the_serial_arm_tour_runs_command_by_command() {
    let dir = aras_testkit::Scratch::new("urdf-tour");
    let d = dir.path();
    let out = aras(d, &["excite", "--urdf", PANDA, "--out", "excitation.json"]);
    let ratio: f64 = out
        .split_once("× higher)")
        .and_then(|(head, _)| head.rsplit_once('('))
        .and_then(|(_, r)| r.trim().parse().ok())
        .unwrap_or_else(|| panic!("no ratio in {out}"));
    assert!(ratio >= 2.5, "{out}");
    // The validation motion: the design at 70 % of its size (inside the
    // same limits), another noise seed.
    let designed = FourierTrajectory::<Dyn>::load(&d.join("excitation.json")).unwrap();
    let n = designed.coordinates();
    let scaled = |c: Vec<&[f64]>| -> Vec<Vec<f64>> {
        c.iter()
            .map(|r| r.iter().map(|x| 0.7 * x).collect())
            .collect()
    };
    let offset: Vec<f64> = designed.offset().iter().copied().collect();
    let other = FourierTrajectory::<Dyn>::new(
        designed.omega_f(),
        offset,
        scaled((0..n).map(|i| designed.a(i)).collect()),
        scaled((0..n).map(|i| designed.b(i)).collect()),
    )
    .unwrap();
    std::fs::write(d.join("other.json"), other.to_json()).unwrap();
    let hidden = "stribeck:4:0.2:0.03";
    let out = aras(
        d,
        &[
            "simulate",
            "--urdf",
            PANDA,
            "--trajectory",
            "excitation.json",
            "--hidden",
            hidden,
            "--out",
            "train.csv",
        ],
    );
    assert!(out.contains("60000 rows, 7 joints"), "{out}");
    aras(
        d,
        &[
            "simulate",
            "--urdf",
            PANDA,
            "--trajectory",
            "other.json",
            "--hidden",
            hidden,
            "--duration",
            "20",
            "--seed",
            "7",
            "--out",
            "val.csv",
        ],
    );
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("val.json")).unwrap()).unwrap();
    assert_eq!(sidecar["torques"], "held");
    assert_eq!(sidecar["truth"]["hidden"][0]["kind"], "stribeck");
    aras(
        d,
        &[
            "identify",
            "--urdf",
            PANDA,
            "--data",
            "train.csv",
            "--out",
            "id",
        ],
    );
    let out = aras(
        d,
        &[
            "predict",
            "--urdf",
            PANDA,
            "--params",
            "id/params.json",
            "--data",
            "val.csv",
            "--out",
            "pred.csv",
        ],
    );
    assert!(out.contains("20000 of 20000 rows"), "{out}");
    let pred = std::fs::read_to_string(d.join("pred.csv")).unwrap();
    assert!(pred.starts_with("t,tau1,tau2,tau3,tau4,tau5,tau6,tau7\n"));
    assert_eq!(pred.lines().count(), 20001);
    aras(
        d,
        &[
            "validate",
            "--urdf",
            PANDA,
            "--params",
            "id/params.json",
            "--data",
            "val.csv",
            "--out",
            "val",
        ],
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("val/validation.json")).unwrap())
            .unwrap();
    // The identified model against the simulated robot's own parameters
    // (the hidden hump is in neither): within 0.1 point per joint.
    for j in 0..n {
        let (f, t) = (
            v[0]["fitness"][j].as_f64().unwrap(),
            v[0]["truth_fitness"][j].as_f64().unwrap(),
        );
        assert!((f - t).abs() < 0.1, "joint {}: {f} vs {t}", j + 1);
    }
    let out = aras(
        d,
        &[
            "diagnose",
            "--urdf",
            PANDA,
            "--data",
            "train.csv",
            "--validate",
            "val.csv",
            "--out",
            "diag",
        ],
    );
    assert!(
        out.contains("added stribeck_friction:panda_joint4"),
        "{out}"
    );
    let diag: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("diag/diagnosis.json")).unwrap())
            .unwrap();
    assert_eq!(diag["steps"].as_array().unwrap().len(), 1, "{out}");
    // The final model re-identified physically consistently, the hump's
    // level in it.
    assert!(
        out.contains("physically consistent refit of the final model (Solved): panda_joint4.Fs = "),
        "{out}"
    );

    // The named effect added to the model: identify with it at the
    // refined v_s, validate on the same log. Joint 4's fitness rises (99.46
    // → 99.50 % measured), no joint's falls, and the model file carries the
    // column to `validate`.
    let v_s = diag["steps"][0]["refinement"]["value"].as_f64().unwrap();
    let effect = format!("stribeck_friction:panda_joint4:{v_s}");
    let out = aras(
        d,
        &[
            "identify",
            "--urdf",
            PANDA,
            "--data",
            "train.csv",
            "--effects",
            &effect,
            "--out",
            "id2",
        ],
    );
    assert!(
        out.contains("physically consistent estimate: Solved"),
        "{out}"
    );
    let params: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("id2/params.json")).unwrap()).unwrap();
    assert_eq!(params["stribeck"][0]["joint"], "panda_joint4");
    assert_eq!(
        params["parameter_names"]
            .as_array()
            .unwrap()
            .last()
            .unwrap(),
        "panda_joint4.Fs"
    );
    aras(
        d,
        &[
            "validate",
            "--urdf",
            PANDA,
            "--params",
            "id2/params.json",
            "--data",
            "val.csv",
            "--out",
            "val2",
        ],
    );
    let v2: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("val2/validation.json")).unwrap())
            .unwrap();
    let fit = |v: &serde_json::Value, j: usize| v[0]["fitness"][j].as_f64().unwrap();
    assert!(
        fit(&v2, 3) > fit(&v, 3) + 0.01,
        "joint 4: {} → {}",
        fit(&v, 3),
        fit(&v2, 3)
    );
    for j in 0..n {
        assert!(
            fit(&v2, j) >= fit(&v, j) - 1e-3,
            "joint {}: {} → {}",
            j + 1,
            fit(&v, j),
            fit(&v2, j)
        );
    }
    // An effect a URDF model cannot take is refused by name.
    let err = aras_fails(
        d,
        &[
            "identify",
            "--urdf",
            PANDA,
            "--data",
            "train.csv",
            "--effects",
            "cogging:12",
            "--out",
            "id3",
        ],
    );
    assert!(err.contains("stribeck_friction:JOINT:V_S"), "{err}");
}
