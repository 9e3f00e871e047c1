//! ROS 2 bags through the `aras` binary: every command that takes a log
//! reads `fixtures/bags/*.mcap` (written by `scripts/make_test_bags.py`) as
//! it reads a CSV.

mod common;

use std::path::Path;
use std::process::Output;

use common::aras;

/// A committed fixture's path, as an argument.
fn fixture(rel: &str) -> String {
    common::fixture(rel).display().to_string()
}

fn ok(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    err
}

fn fails(o: &Output, expected: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "accepted: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expected {
        assert!(err.contains(e), "missing {e:?} in:\n{err}");
    }
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `identify --data sim.mcap` (a simulated run as a bag, no velocity in
/// the messages) gives the parameters of the same rows as a CSV, in memory
/// and streamed.
#[test]
fn identify_a_bag_as_its_csv() {
    let dir = common::scratch("bags", "identify");
    let bag = fixture("bags/sim.mcap");
    let log = aras_log::read_log(bag.as_ref(), &aras_log::ReadOptions::default()).unwrap();
    assert_eq!(log.len(), 2000);
    assert!(log.theta_dot.is_none());
    let csv = dir.join("sim.csv");
    let columns = aras_log::Columns {
        t: log.t.clone(),
        theta: log.theta.clone(),
        tau: log.tau.clone(),
        ..Default::default()
    };
    let sidecar = aras_log::Sidecar {
        format: Some(aras_log::FORMAT.into()),
        ..Default::default()
    };
    aras_log::write_log(&csv, &columns, &sidecar).unwrap();
    let run = |data: &str, out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec!["identify", "--quiet", "--data", data, "--out"];
        let o = out.display().to_string();
        args.push(&o);
        args.extend(extra);
        let stderr = ok(&aras(&args));
        (json(&out.join("params.json")), stderr)
    };
    let (from_csv, _) = run(csv.to_str().unwrap(), "csv", &[]);
    let (from_bag, notes) = run(&bag, "bag", &[]);
    assert_eq!(from_bag, from_csv);
    for want in [
        "topic /joint_states, 2000 sensor_msgs/msg/JointState messages",
        "θ1 = joint `joint_a`, θ2 = joint `joint_b`",
        "message rate 100 Hz",
    ] {
        assert!(notes.contains(want), "{want:?} in {notes}");
    }
    // Streamed: the bag is decoded into memory, then processed in chunks as a CSV is.
    let (streamed_csv, _) = run(csv.to_str().unwrap(), "csv-s", &["--streaming", "on"]);
    let (streamed_bag, _) = run(&bag, "bag-s", &["--streaming", "on"]);
    assert_eq!(streamed_bag, streamed_csv);
}

#[test]
fn predict_and_diagnose_take_bags_with_topic_and_joints() {
    let dir = common::scratch("bags", "predict");
    let params = fixture("robots/aras-diamond.json");
    let two = fixture("bags/two_topics.mcap");
    let out = dir.join("p.csv");
    let predict = |extra: &[&str]| {
        let _ = std::fs::remove_file(&out);
        let mut args = vec![
            "predict",
            "--params",
            &params,
            "--data",
            &two,
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        aras(&args)
    };
    fails(
        &predict(&[]),
        &[
            "2 sensor_msgs/msg/JointState topics: choose one with --topic",
            "/arm/joint_states (120 sensor_msgs/msg/JointState messages), /joint_states (240",
        ],
    );
    fails(
        &predict(&["--topic", "/arm/joint_states"]),
        &["the first message names 3 joints (a1, a2, a3)", "--joints"],
    );
    fails(
        &predict(&["--topic", "/arm/joint_states", "--joints", "theta1=a1"]),
        &["option --joints", "give both theta1=JOINT and theta2=JOINT"],
    );
    ok(&predict(&[
        "--topic",
        "/arm/joint_states",
        "--joints",
        "theta1=a1,theta2=a2",
    ]));
    let rows = std::fs::read_to_string(&out).unwrap().lines().count() - 1;
    assert_eq!(rows, 120);
    // The bag options on a CSV, --columns on a bag: errors.
    let csv = fixture("bags/clean.csv");
    std::fs::remove_file(&out).unwrap();
    let o = aras(&[
        "predict",
        "--params",
        &params,
        "--data",
        &csv,
        "--out",
        out.to_str().unwrap(),
        "--topic",
        "/joint_states",
    ]);
    fails(
        &o,
        &["is a CSV log: --topic, --joints and --stamps apply to ROS 2 bags"],
    );
    // diagnose: a bag to train on and one to validate with (the simulated run).
    let sim = fixture("bags/sim.mcap");
    let o = aras(&[
        "diagnose",
        "--quiet",
        "--data",
        &sim,
        "--validate",
        &sim,
        "--out",
        dir.join("diag").to_str().unwrap(),
    ]);
    let err = ok(&o);
    assert!(
        err.contains("sim.mcap: ROS 2 bag: topic /joint_states, 2000"),
        "{err}"
    );
    assert!(dir.join("diag/diagnosis.json").is_file());
}

#[test]
fn friction_takes_one_joint_of_a_bag() {
    let dir = common::scratch("bags", "friction");
    let clean = fixture("bags/clean.mcap");
    let out = dir.join("fr");
    fails(
        &aras(&[
            "friction",
            "--quiet",
            "--data",
            &clean,
            "--out",
            out.to_str().unwrap(),
        ]),
        &[
            "the first message names 2 joints (motor_left, motor_right): say which is the joint with --joint NAME",
        ],
    );
    ok(&aras(&[
        "friction",
        "--quiet",
        "--data",
        &clean,
        "--joint",
        "motor_right",
        "--out",
        out.to_str().unwrap(),
    ]));
    // The prediction is on the bag's rows: t of the clean CSV.
    let pred = std::fs::read_to_string(out.join("pred_clean.csv")).unwrap();
    let t: Vec<f64> = pred
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    let csv = aras_log::read_log(
        fixture("bags/clean.csv").as_ref(),
        &aras_log::ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(t, csv.t);
    let json = json(&out.join("friction.json"));
    // The messages carry velocity: dq is not computed from q.
    assert_eq!(json["train"]["dq_from_q"], false, "{json}");
}
