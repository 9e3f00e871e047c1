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
