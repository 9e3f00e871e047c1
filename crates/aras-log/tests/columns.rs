//! A lab's own column names (`ReadOptions::columns`): every role can be
//! mapped, the standard name of a mapped role becomes an ordinary ignored
//! column, and mistakes in the mapping or the log name the user's columns.

use aras_log::{ColumnNames, LogError, ReadOptions, read_log_from};

fn text(header: &str) -> String {
    let mut s = format!("{header}\n");
    for i in 0..40 {
        let t = i as f64 * 1e-3;
        // time, q1, q2, torque_a, torque_b, theta1 (a decoy in degrees)
        s += &format!(
            "{t},{},{},{},{},{}\n",
            2.0 + t,
            1.0 - t,
            0.1 * t,
            -0.2 * t,
            90.0
        );
    }
    s
}

fn opts(spec: &str) -> ReadOptions {
    ReadOptions {
        columns: ColumnNames::parse(spec).unwrap(),
        ..ReadOptions::default()
    }
}

#[test]
fn mapped_columns_are_read_and_the_standard_name_is_ignored() {
    let csv = text("Time,Q1,q2,torque_a,torque_b,theta1");
    let log = read_log_from(
        csv.as_bytes(),
        "lab.csv",
        &opts("t=time, theta1=q1, theta2=q2, tau1=torque_a, tau2=torque_b"),
    )
    .unwrap();
    assert_eq!(log.len(), 40);
    assert_eq!(log.t[3], 3e-3);
    assert_eq!(log.theta[0][3], 2.0 + 3e-3);
    assert_eq!(log.theta[1][3], 1.0 - 3e-3);
    assert_eq!(log.tau[0][3], 0.1 * 3e-3);
    assert_eq!(log.tau[1][3], -0.2 * 3e-3);
    // The decoy `theta1` (degrees) is not read as an angle.
    assert!(
        log.notes.iter().any(|n| n.contains("theta1")),
        "{:?}",
        log.notes
    );
    // Without the mapping the same file is refused: no time column `t`.
    let e = read_log_from(csv.as_bytes(), "lab.csv", &ReadOptions::default()).unwrap_err();
    assert!(matches!(e, LogError::MissingColumn { .. }), "{e}");
}

#[test]
fn a_missing_mapped_column_is_named_as_the_user_wrote_it() {
    let csv = text("time,q1,qq2,torque_a,torque_b,theta1");
    let e = read_log_from(
        csv.as_bytes(),
        "lab.csv",
        &opts("t=time,theta1=q1,theta2=q2,tau1=torque_a,tau2=torque_b"),
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("q2 (theta2)") && msg.contains("lab.csv"),
        "{msg}"
    );
}

#[test]
fn bad_mappings_say_what_is_wrong() {
    for (spec, needle) in [
        ("theta1", "is not ROLE=NAME"),
        ("angle1=q1", "unknown role `angle1`"),
        ("theta1=q1,theta1=q2", "named twice"),
        ("theta1=q,theta2=q", "given to both"),
        ("tau1=", "empty column name"),
    ] {
        let e = ColumnNames::parse(spec).unwrap_err();
        assert!(
            matches!(
                e,
                LogError::InvalidOption {
                    name: "columns",
                    ..
                }
            ),
            "{spec}: {e}"
        );
        assert!(e.to_string().contains(needle), "{spec}: {e}");
    }
    assert!(ColumnNames::parse("").unwrap().is_empty());
}

/// The joint count comes from the header: every column kind for every joint
/// or for none, the first missing one named; a reader told the count takes
/// that many, refuses fewer, and a lab's names map any joint's role.
#[test]
fn joints_come_from_the_header_and_every_joint_needs_every_column() {
    let rows = |header: &str, fields: usize| {
        let mut s = format!("{header}\n");
        for i in 0..40 {
            let t = i as f64 * 1e-3;
            s += &t.to_string();
            for k in 1..fields {
                s += &format!(",{}", 0.1 * k as f64 + t);
            }
            s.push('\n');
        }
        s
    };
    let read = |text: &str, opts: &ReadOptions| read_log_from(text.as_bytes(), "j.csv", opts);
    let four = "t,theta1,theta2,theta3,theta4,tau1,tau2,tau3,tau4";
    let log = read(&rows(four, 9), &ReadOptions::default()).unwrap();
    assert_eq!((log.joints(), log.tau.len()), (4, 4));
    assert_eq!(log.summary.channel_columns, (2..=9).collect::<Vec<_>>());
    // A gap in the joints, a torque missing, a derivative for one joint only.
    for (header, fields, message) in [
        (
            "t,theta1,theta3,tau1,tau2,tau3",
            6,
            "column `theta2` is missing",
        ),
        (
            "t,theta1,theta2,theta3,tau1,tau2",
            6,
            "column `tau3` is missing",
        ),
        (
            "t,theta1,theta2,tau1,tau2,dtheta2",
            6,
            "column `dtheta2` is present but `dtheta1` is not",
        ),
    ] {
        let e = read(&rows(header, fields), &ReadOptions::default()).unwrap_err();
        assert!(e.to_string().contains(message), "{header}: {e}");
    }
    // Told two joints: the others' columns are ignored; told five: refused.
    let two = ReadOptions {
        joints: Some(2),
        ..ReadOptions::default()
    };
    let log = read(&rows(four, 9), &two).unwrap();
    assert_eq!(log.joints(), 2);
    assert!(
        log.notes
            .iter()
            .any(|n| n.contains("theta3") && n.contains("tau4")),
        "{:?}",
        log.notes
    );
    let five = ReadOptions {
        joints: Some(5),
        ..ReadOptions::default()
    };
    let e = read(&rows(four, 9), &five).unwrap_err();
    assert!(e.to_string().contains("theta5"), "{e}");
    // A lab's name for the third joint's torque.
    let mapped = ReadOptions {
        columns: ColumnNames::parse("tau3=elbow_torque").unwrap(),
        ..ReadOptions::default()
    };
    let header = "t,theta1,theta2,theta3,tau1,tau2,elbow_torque";
    let log = read(&rows(header, 7), &mapped).unwrap();
    assert_eq!(log.tau[2][0], 0.1 * 6.0); // the sixth field of the first row
    let e = read(&rows("t,theta1,theta2,theta3,tau1,tau2", 6), &mapped).unwrap_err();
    assert!(e.to_string().contains("elbow_torque (tau3)"), "{e}");
}
