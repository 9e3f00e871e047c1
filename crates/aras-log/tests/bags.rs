//! ROS 2 bags (MCAP, `sensor_msgs/msg/JointState`) read as logs, on the
//! bags of `fixtures/bags/` written by `scripts/make_test_bags.py` with the
//! `mcap` and `mcap-ros2-support` Python packages; and sidecars that must
//! declare their format.

use std::path::{Path, PathBuf};

use aras_log::{
    BagOptions, Columns, JointNames, LogError, LogReader, ReadOptions, SidecarSource, Stamps,
    is_bag, read_log,
};
use aras_testkit::Scratch;

fn bag(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/bags")
        .join(name)
}

/// The reading of a two-joint robot's tool (ARAS-Diamond's): two joints.
fn with_bag(bag: BagOptions) -> ReadOptions {
    ReadOptions {
        bag,
        joints: Some(2),
        ..ReadOptions::default()
    }
}

fn err(path: &Path, opts: &ReadOptions) -> String {
    match read_log(path, opts) {
        Ok(_) => panic!("{} was accepted", path.display()),
        Err(e) => e.to_string(),
    }
}

/// The CSV written alongside the bags: the values every clean reading must give.
fn clean_csv() -> aras_log::Log {
    read_log(&bag("clean.csv"), &ReadOptions::default()).unwrap()
}

fn assert_close(a: &[f64], b: &[f64], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!((x - y).abs() <= 1e-12, "{what}[{i}]: {x} vs {y}");
    }
}

fn assert_same_as_csv(log: &aras_log::Log, swap: bool) {
    let csv = clean_csv();
    let (a, b) = if swap { (1, 0) } else { (0, 1) };
    assert_close(&log.t, &csv.t, "t");
    assert_close(&log.theta[0], &csv.theta[a], "theta1");
    assert_close(&log.theta[1], &csv.theta[b], "theta2");
    assert_close(&log.tau[0], &csv.tau[a], "tau1");
    assert_close(&log.tau[1], &csv.tau[b], "tau2");
    let (v, cv) = (log.theta_dot.as_ref().unwrap(), csv.theta_dot.unwrap());
    assert_close(&v[0], &cv[a], "dtheta1");
    assert_close(&v[1], &cv[b], "dtheta2");
}

#[test]
fn clean_bag_reads_as_its_csv_with_rates_and_mapping_noted() {
    let log = read_log(&bag("clean.mcap"), &ReadOptions::default()).unwrap();
    assert_same_as_csv(&log, false);
    assert!(log.theta_ddot.is_none());
    assert_eq!(log.summary.rows, 240);
    assert!(
        (log.summary.sample_rate_hz - 100.0).abs() < 1e-6,
        "{:?}",
        log.summary
    );
    let notes = log.notes.join("\n");
    for want in [
        "topic /joint_states, 240 sensor_msgs/msg/JointState messages",
        "header.stamp (1704067200 s)",
        "θ1 = joint `motor_left`, θ2 = joint `motor_right`: the two joints in the order of the first message",
        // Header stamps are exactly 10 ms apart.
        "message rate 100 Hz (median step 10 ms; steps 10–10 ms",
        // The script's recorder receives each message 1.5 ± 0.4 ms late.
        "log time trails header.stamp by 1.1–1.9 ms",
        "other topics ignored: /chatter",
    ] {
        assert!(notes.contains(want), "missing {want:?} in\n{notes}");
    }
    // The rows are labelled with the topic; messages number them.
    assert!(
        log.name.ends_with("clean.mcap#/joint_states"),
        "{}",
        log.name
    );
}

#[test]
fn joints_are_mapped_by_name_and_a_missing_joint_is_named() {
    let swapped = with_bag(BagOptions {
        joints: JointNames::parse("theta1=motor_right,theta2=motor_left").unwrap(),
        ..BagOptions::default()
    });
    let log = read_log(&bag("clean.mcap"), &swapped).unwrap();
    assert_same_as_csv(&log, true);
    assert!(!log.notes.join(" ").contains("order of the first message"));
    let wrong = with_bag(BagOptions {
        joints: JointNames::parse("theta1=motor_left,theta2=elbow").unwrap(),
        ..BagOptions::default()
    });
    let e = err(&bag("clean.mcap"), &wrong);
    assert!(
        e.contains("topic /joint_states, message 1: joint `elbow` (θ2) is not in the message, which names: motor_left, motor_right"),
        "{e}"
    );
}

#[test]
fn reordered_names_and_extra_joints_read_as_the_clean_csv() {
    // Its first message names three joints: no default mapping for a
    // two-joint robot.
    let e = err(&bag("reordered.mcap"), &with_bag(BagOptions::default()));
    assert!(
        e.contains("the first message names 3 joints (motor_left, motor_right, gripper)"),
        "{e}"
    );
    let named = with_bag(BagOptions {
        joints: JointNames::parse("theta1=motor_left,theta2=motor_right").unwrap(),
        ..BagOptions::default()
    });
    let log = read_log(&bag("reordered.mcap"), &named).unwrap();
    assert_same_as_csv(&log, false);
    assert!(
        log.notes.iter().any(|n| n == "joints ignored: gripper"),
        "{:?}",
        log.notes
    );
}

#[test]
fn two_joint_state_topics_need_a_topic() {
    let path = bag("two_topics.mcap");
    let e = err(&path, &with_bag(BagOptions::default()));
    assert!(
        e.contains("the bag has 2 sensor_msgs/msg/JointState topics: choose one with --topic"),
        "{e}"
    );
    assert!(
        e.contains(
            "/arm/joint_states (120 sensor_msgs/msg/JointState messages), \
             /joint_states (240 sensor_msgs/msg/JointState messages)"
        ),
        "{e}"
    );
    let main = with_bag(BagOptions {
        topic: Some("/joint_states".into()),
        ..BagOptions::default()
    });
    assert_same_as_csv(&read_log(&path, &main).unwrap(), false);
    // The arm's topic has three joints: no default mapping.
    let mut arm = BagOptions {
        topic: Some("/arm/joint_states".into()),
        ..BagOptions::default()
    };
    let e = err(&path, &with_bag(arm.clone()));
    assert!(
        e.contains("topic /arm/joint_states: the first message names 3 joints (a1, a2, a3): say which are θ1 and θ2 with --joints"),
        "{e}"
    );
    // A reader not told the joint count takes all three, in message order.
    let all = ReadOptions {
        bag: arm.clone(),
        ..ReadOptions::default()
    };
    let log = read_log(&path, &all).unwrap();
    assert_eq!((log.joints(), log.len()), (3, 120));
    assert!(
        log.notes
            .iter()
            .any(|n| n.contains("θ3 = joint `a3`: the 3 joints in the order")),
        "{:?}",
        log.notes
    );
    arm.joints = JointNames::parse("theta1=a1,theta2=a2").unwrap();
    let log = read_log(&path, &with_bag(arm)).unwrap();
    assert_eq!(log.len(), 120);
    assert!((log.summary.sample_rate_hz - 50.0).abs() < 1e-6);
    assert!(log.notes.iter().any(|n| n == "joints ignored: a3"));
    // An unknown topic lists what there is.
    let e = err(
        &path,
        &with_bag(BagOptions {
            topic: Some("/states".into()),
            ..BagOptions::default()
        }),
    );
    assert!(
        e.contains("the bag has no topic `/states`; the bag's topics: /arm/joint_states (120"),
        "{e}"
    );
}

#[test]
fn dropped_messages_are_a_gap_like_a_csvs() {
    let path = bag("dropped.mcap");
    let e = err(&path, &ReadOptions::default());
    // Messages 60–62 of 240 were dropped: the 61st message read follows a 40 ms step.
    assert!(
        e.contains(
            "dropped.mcap#/joint_states:61: irregular sampling: the worst step, 0.04 s ending at \
             t = 0.63 s, is 4.000× the nominal step 0.01 s"
        ),
        "{e}"
    );
    let lenient = ReadOptions {
        step_tolerance: 3.5,
        ..ReadOptions::default()
    };
    let log = read_log(&path, &lenient).unwrap();
    assert_eq!(log.len(), 236);
    assert!(
        log.notes
            .iter()
            .any(|n| n.contains("steps 10–40 ms, i.e. 25–100 Hz")),
        "{:?}",
        log.notes
    );
}

#[test]
fn missing_effort_is_an_error() {
    let e = err(&bag("no_effort.mcap"), &ReadOptions::default());
    assert!(
        e.contains(
            "topic /joint_states, message 1: it has no effort: aras needs the joint torques (N·m)"
        ),
        "{e}"
    );
}

#[test]
fn unset_stamps_point_to_the_log_time_which_then_reads() {
    let path = bag("no_stamps.mcap");
    let e = err(&path, &ReadOptions::default());
    assert!(
        e.contains("message 2: its time 0 s does not follow the previous message's 0 s: header.stamp is zero")
            && e.contains("--stamps log"),
        "{e}"
    );
    let log = read_log(
        &path,
        &with_bag(BagOptions {
            stamps: Stamps::Log,
            ..BagOptions::default()
        }),
    )
    .unwrap();
    // The script's log time: stamp + 1.5 ms + ((7919 i mod 9) − 4) · 0.1 ms.
    let log_ns = |i: i64| i * 10_000_000 + 1_500_000 + ((i * 7919) % 9 - 4) * 100_000;
    for (i, t) in log.t.iter().enumerate() {
        let want = (log_ns(i as i64) - log_ns(0)) as f64 / 1e9;
        assert!((t - want).abs() <= 1e-12, "{i}: {t} vs {want}");
    }
    assert!(log.notes[0].contains("t = 0 at the first message's log time"));
}

#[test]
fn bags_are_known_by_magic_bytes_and_damage_is_an_error() {
    let dir = Scratch::new("bags-magic");
    let renamed = dir.join("recording.bin");
    std::fs::copy(bag("clean.mcap"), &renamed).unwrap();
    assert!(is_bag(&renamed) && !is_bag(&bag("clean.csv")));
    assert_same_as_csv(&read_log(&renamed, &ReadOptions::default()).unwrap(), false);
    // Cut short (a recording that was killed): an error, not a panic.
    let bytes = std::fs::read(bag("clean.mcap")).unwrap();
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = read_log(&cut, &ReadOptions::default()).unwrap_err();
    assert!(matches!(e, LogError::Bag { .. }), "{e}");
    assert!(
        e.to_string().contains("not a readable ROS 2 bag (MCAP)"),
        "{e}"
    );
}

#[test]
fn options_of_the_other_kind_of_log_are_errors() {
    let csv_with_topic = with_bag(BagOptions {
        topic: Some("/joint_states".into()),
        ..BagOptions::default()
    });
    let e = err(&bag("clean.csv"), &csv_with_topic);
    assert!(
        e.contains("is a CSV log: --topic, --joints and --stamps apply to ROS 2 bags"),
        "{e}"
    );
    let bag_with_columns = ReadOptions {
        columns: aras_log::ColumnNames::parse("theta1=q1").unwrap(),
        ..ReadOptions::default()
    };
    let e = err(&bag("clean.mcap"), &bag_with_columns);
    assert!(
        e.contains("is a ROS 2 bag: its joints are mapped by name with --joints"),
        "{e}"
    );
}

#[test]
fn a_bag_streams_in_chunks_like_a_csv() {
    let whole = read_log(&bag("clean.mcap"), &ReadOptions::default()).unwrap();
    let mut reader = LogReader::open(&bag("clean.mcap"), &ReadOptions::default()).unwrap();
    assert!(reader.has_velocity());
    let (mut t, mut chunk, mut calls) = (Vec::new(), Columns::default(), 0);
    while reader.read_rows(&mut chunk, 7).unwrap() > 0 {
        t.extend_from_slice(&chunk.t);
        chunk.clear();
        calls += 1;
    }
    assert_eq!(calls, 240usize.div_ceil(7));
    assert_eq!(t, whole.t);
    assert_eq!(reader.finish().unwrap().summary, whole.summary);
}

/// A log whose `run.json` is `json`, in a scratch directory.
fn log_with_json(dir: &Scratch, json: &str) -> PathBuf {
    let csv = dir.join("run.csv");
    std::fs::copy(bag("clean.csv"), &csv).unwrap();
    std::fs::write(dir.join("run.json"), json).unwrap();
    csv
}

#[test]
fn only_a_json_that_declares_the_format_is_a_sidecar() {
    let dir = Scratch::new("bags-sidecar");
    // A lab's own run.json beside the log: not read, with a note.
    for (json, why) in [
        (r#"{"operator": "anna", "excitation": "chirp"}"#, ""),
        ("[1, 2, 3]", " (it is not a JSON object)"),
        ("operator: anna\n", " (it is not valid JSON)"),
        (r#"{"format": "lab-run/3", "period_s": "ten"}"#, ""),
    ] {
        let csv = log_with_json(&dir, json);
        let log = read_log(&csv, &ReadOptions::default()).unwrap();
        assert_eq!(log.sidecar, aras_log::Sidecar::default(), "{json}");
        assert_eq!(log.summary.sidecar, None);
        let note = format!(
            "{} does not declare the aras-log/1 format{why}; not read as a sidecar",
            dir.join("run.json").display()
        );
        assert!(
            log.notes.iter().any(|n| n.starts_with(&note)),
            "{note:?} in {:?}",
            log.notes
        );
        // Given explicitly, it is an error with the fix (when it parses as a sidecar at all).
        let explicit = ReadOptions {
            sidecar: SidecarSource::Path(dir.join("run.json")),
            ..ReadOptions::default()
        };
        assert!(read_log(&csv, &explicit).is_err(), "{json}");
    }
    // A declared sidecar is read, and checked.
    let csv = log_with_json(
        &dir,
        r#"{"format": "aras-log/1", "excitation": {"period_s": 2.0}}"#,
    );
    let log = read_log(&csv, &ReadOptions::default()).unwrap();
    assert_eq!(log.sidecar.excitation.period_s, Some(2.0));
    let csv = log_with_json(
        &dir,
        r#"{"format": "aras-log/1", "excitation": {"period": 2.0}}"#,
    );
    assert!(err(&csv, &ReadOptions::default()).contains("unknown field `period`"));
    // A damaged sidecar that names the format is reported, not ignored.
    let csv = log_with_json(
        &dir,
        r#"{"format": "aras-log/1", "excitation": {"period_s": 2.0,}}"#,
    );
    assert!(err(&csv, &ReadOptions::default()).contains("run.json:1:"));
    // `SidecarSource::None` reads none, whatever lies beside the log.
    let none = ReadOptions {
        sidecar: SidecarSource::None,
        ..ReadOptions::default()
    };
    let log = read_log(&csv, &none).unwrap();
    assert_eq!(log.summary.sidecar, None);
    assert!(
        log.notes.iter().all(|n| !n.contains("sidecar")),
        "{:?}",
        log.notes
    );
    // An explicit sidecar without the declaration: the fix is in the message.
    std::fs::write(
        dir.join("plain.json"),
        r#"{"excitation": {"period_s": 2.0}}"#,
    )
    .unwrap();
    let explicit = ReadOptions {
        sidecar: SidecarSource::Path(dir.join("plain.json")),
        ..ReadOptions::default()
    };
    let e = err(&csv, &explicit);
    assert!(
        e.contains(
            "plain.json does not declare the sidecar format: add \"format\": \"aras-log/1\""
        ) && e.contains("--sidecar none"),
        "{e}"
    );
}

#[test]
fn a_bag_takes_the_declared_sidecar_beside_it() {
    let dir = Scratch::new("bags-bag-sidecar");
    let path = dir.join("run.mcap");
    std::fs::copy(bag("clean.mcap"), &path).unwrap();
    std::fs::write(
        dir.join("run.json"),
        r#"{"format": "aras-log/1", "excitation": {"period_s": 1.5}}"#,
    )
    .unwrap();
    let log = read_log(&path, &ReadOptions::default()).unwrap();
    assert_eq!(log.sidecar.excitation.period_s, Some(1.5));
    assert_eq!(
        log.summary.sidecar,
        Some(dir.join("run.json").display().to_string())
    );
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

    /// A damaged bag (bytes changed, or cut) reads or fails with an error:
    /// never a panic.
    #[test]
    fn damaged_bags_never_panic(
        flips in proptest::collection::vec((0.0f64..1.0, proptest::prelude::any::<u8>()), 1..6),
        keep in 0.05f64..1.0,
    ) {
        let dir = Scratch::new("bags-fuzz");
        let mut bytes = std::fs::read(bag("clean.mcap")).unwrap();
        for (at, b) in flips {
            let i = ((bytes.len() - 1) as f64 * at) as usize;
            bytes[i] = b;
        }
        bytes.truncate(((bytes.len() as f64) * keep) as usize);
        let path = dir.join("fuzz.mcap");
        std::fs::write(&path, &bytes).unwrap();
        if let Ok(log) = read_log(&path, &ReadOptions::default()) {
            proptest::prop_assert!(log.t.iter().chain(&log.tau[0]).all(|x| x.is_finite()));
        }
    }
}

/// A chunk whose uncompressed-size field is damaged (1.7e18 bytes) is an
/// error naming the chunk, not an allocation that aborts the process.
#[test]
fn a_damaged_chunk_size_is_an_error_not_an_abort() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/bags/clean.mcap");
    let mut bytes = std::fs::read(&path).unwrap();
    // Walk the records (opcode, u64 length, body) to the first chunk.
    let mut at = 8;
    let chunk = loop {
        let op = bytes[at];
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if op == 0x06 {
            break at;
        }
        at += 9 + len;
    };
    // Body: start time, end time, then the uncompressed size.
    let size = chunk + 9 + 16;
    bytes[size..size + 8].copy_from_slice(&1_704_067_201_986_331_401u64.to_le_bytes());
    let dir = std::env::temp_dir().join(format!("aras-bag-chunk-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("damaged.mcap");
    std::fs::write(&bad, &bytes).unwrap();
    let e = aras_log::read_log(&bad, &aras_log::ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("declares"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A bag's JointState efforts are measurements: sampled, unless the
/// options say otherwise.
#[test]
fn bag_torques_are_sampled_unless_overridden() {
    use aras_log::TorqueTiming;
    let log = read_log(&bag("clean.mcap"), &ReadOptions::default()).unwrap();
    assert_eq!(log.torque_timing(), TorqueTiming::Sampled);
    let opts = ReadOptions {
        torques: Some(TorqueTiming::Held),
        ..ReadOptions::default()
    };
    let log = read_log(&bag("clean.mcap"), &opts).unwrap();
    assert_eq!(log.torque_timing(), TorqueTiming::Held);
}
