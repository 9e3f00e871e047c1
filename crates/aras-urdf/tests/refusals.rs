//! What the model cannot express is refused with the file, the element's
//! line and what to do.

use aras_urdf::{CoulombWidth, ModelSettings, UrdfError, UrdfModel};

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/urdf");

/// A two-link arm with `joint` as its second joint's element and `extra`
/// appended inside <robot>.
fn arm(joint: &str, extra: &str) -> String {
    format!(
        r#"<robot name="arm">
  <link name="base"/>
  <link name="upper"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="fore"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/></joint>
{joint}
{extra}
</robot>"#
    )
}

const ELBOW: &str = r#"  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/></joint>"#;

fn refused(text: &str) -> String {
    match UrdfModel::from_urdf_str(text, "arm.urdf", ModelSettings::default()) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn assert_says(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{msg}` does not say `{p}`");
    }
}

#[test]
fn the_arm_itself_is_accepted() {
    let m =
        UrdfModel::from_urdf_str(&arm(ELBOW, ""), "arm.urdf", ModelSettings::default()).unwrap();
    assert_eq!(m.joint_names(), ["shoulder", "elbow"]);
    assert_eq!(m.parameter_count(), 2 * (10 + 3));
}

#[test]
fn floating_and_planar_joints_are_refused() {
    for ty in ["floating", "planar"] {
        let msg = refused(&arm(&ELBOW.replace("revolute", ty), ""));
        assert_says(
            &msg,
            &[
                "arm.urdf:6:",
                "<joint name=\"elbow\">",
                ty,
                "make the joint fixed",
            ],
        );
    }
    let msg = refused(&arm(&ELBOW.replace("revolute", "screw"), ""));
    assert_says(&msg, &["not a URDF joint type", "use revolute, continuous"]);
}

#[test]
fn mimic_joints_are_refused() {
    let msg = refused(&arm(
        &ELBOW.replace("</joint>", "<mimic joint=\"shoulder\"/></joint>"),
        "",
    ));
    assert_says(&msg, &["<mimic>", "\"shoulder\"", "remove <mimic>"]);
    let msg = UrdfModel::from_file(format!("{FIXTURES}/panda.urdf"), ModelSettings::default())
        .unwrap_err()
        .to_string();
    assert_says(
        &msg,
        &[
            "panda.urdf:348:",
            "panda_finger_joint2",
            "panda_finger_joint1",
        ],
    );
}

#[test]
fn loops_and_several_roots_are_refused() {
    let second_parent =
        r#"  <joint name="brace" type="fixed"><parent link="base"/><child link="fore"/></joint>"#;
    let msg = refused(&arm(ELBOW, second_parent));
    assert_says(
        &msg,
        &[
            "<joint name=\"brace\">",
            "already the child of joint \"elbow\"",
            "closes a kinematic loop",
        ],
    );
    let stray = r#"  <link name="stray"/>"#;
    let msg = refused(&arm(ELBOW, stray));
    assert_says(&msg, &["2 root links (base, stray)", "connect every part"]);
    let msg = refused(&arm(ELBOW, "<loop_joint name=\"x\"/>"));
    assert_says(&msg, &["<loop_joint name=\"x\">", "closed chain"]);
}

#[test]
fn impossible_inertials_are_refused() {
    let bad_mass = arm(ELBOW, "").replacen("<mass value=\"1\"/>", "<mass value=\"-1\"/>", 1);
    assert_says(
        &refused(&bad_mass),
        &[
            "arm.urdf:3:",
            "<link name=\"upper\"> <mass>",
            "negative",
            "≥ 0",
        ],
    );
    let not_psd = arm(ELBOW, "").replacen("ixx=\"0.01\"", "ixx=\"-0.01\"", 1);
    assert_says(
        &refused(&not_psd),
        &["not positive semidefinite", "tensor entries"],
    );
    let violates = arm(ELBOW, "").replacen("ixy=\"0\"", "ixy=\"0.02\"", 1);
    assert_says(&refused(&violates), &["not positive semidefinite"]);
    let no_inertia = arm(ELBOW, "").replacen(
        "<inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/>",
        "",
        1,
    );
    assert_says(&refused(&no_inertia), &["has no <inertia>"]);
    let text = arm(ELBOW, "").replacen("iyy=\"0.01\"", "iyy=\"abc\"", 1);
    assert_says(&refused(&text), &["iyy=\"abc\" is not a finite number"]);
    let massless = arm(ELBOW, "").replacen("<mass value=\"1\"/>", "<mass value=\"0\"/>", 1);
    assert_says(&refused(&massless), &["inertia but zero mass"]);
}

#[test]
fn broken_structure_and_settings_are_refused() {
    let msg = refused(&arm(&ELBOW.replace("\"upper\"", "\"uper\""), ""));
    assert_says(&msg, &["parent link \"uper\" is not defined"]);
    let msg = refused(&arm(&ELBOW.replace("0 1 0", "0 0 0"), ""));
    assert_says(&msg, &["<axis>", "axis is zero"]);
    let msg = refused("<robot name=\"r\"><link name=\"a\"/></robot>");
    assert_says(&msg, &["has no revolute, continuous or prismatic joint"]);
    let msg = refused("<robot><link name=\"a\"></robot>");
    assert_says(&msg, &["not well-formed XML", "xacro"]);
    let settings = ModelSettings {
        coulomb_width: CoulombWidth::PerJoint(vec![0.1]),
        ..ModelSettings::default()
    };
    let err = UrdfModel::from_urdf_str(&arm(ELBOW, ""), "arm.urdf", settings).unwrap_err();
    assert!(matches!(err, UrdfError::Setting { .. }), "{err}");
    assert_says(&err.to_string(), &["1 widths for 2 movable joints"]);
    let settings = ModelSettings {
        coulomb_width: CoulombWidth::Uniform(-0.1),
        ..ModelSettings::default()
    };
    assert!(UrdfModel::from_urdf_str(&arm(ELBOW, ""), "arm.urdf", settings).is_err());
    // A Stribeck column names a movable joint, once, with v_s > 0.
    let joints = UrdfModel::from_urdf_str(&arm(ELBOW, ""), "arm.urdf", ModelSettings::default())
        .unwrap()
        .joint_names();
    let stribeck = |cols: &[(&str, f64)]| {
        let settings = ModelSettings {
            stribeck: cols
                .iter()
                .map(|(joint, v_s)| aras_urdf::StribeckColumn {
                    joint: (*joint).to_owned(),
                    v_s: *v_s,
                })
                .collect(),
            ..ModelSettings::default()
        };
        UrdfModel::from_urdf_str(&arm(ELBOW, ""), "arm.urdf", settings)
    };
    let j = joints[1].as_str();
    let msg = stribeck(&[("wrist", 0.03)]).unwrap_err().to_string();
    assert_says(&msg, &["joint `wrist`", "not a movable joint", j]);
    let msg = stribeck(&[(j, 0.0)]).unwrap_err().to_string();
    assert_says(&msg, &["v_s = 0", "> 0"]);
    let msg = stribeck(&[(j, 0.03), (j, 0.05)]).unwrap_err().to_string();
    assert_says(&msg, &["two Stribeck columns"]);
    let m = stribeck(&[(j, 0.03)]).unwrap();
    assert_eq!(m.parameter_names().last().unwrap(), &format!("{j}.Fs"));
    let err =
        UrdfModel::from_file("/nonexistent/robot.urdf", ModelSettings::default()).unwrap_err();
    assert_says(
        &err.to_string(),
        &["/nonexistent/robot.urdf", "check the path"],
    );
}

#[test]
fn bad_states_are_errors_not_nan() {
    let m =
        UrdfModel::from_urdf_str(&arm(ELBOW, ""), "arm.urdf", ModelSettings::default()).unwrap();
    let p = m.urdf_parameters();
    let err = m
        .inverse_dynamics(&p, &[0.0], &[0.0; 2], &[0.0; 2])
        .unwrap_err();
    assert!(
        matches!(err, UrdfError::Dimension { what: "q", .. }),
        "{err}"
    );
    let err = m
        .regressor(&[0.0, f64::NAN], &[0.0; 2], &[0.0; 2])
        .unwrap_err();
    assert_says(&err.to_string(), &["q[1] is NaN", "finite"]);
    let err = m
        .inverse_dynamics(&p[1..], &[0.0; 2], &[0.0; 2], &[0.0; 2])
        .unwrap_err();
    assert!(
        matches!(
            err,
            UrdfError::Dimension {
                what: "parameters",
                ..
            }
        ),
        "{err}"
    );
    let mut short = vec![0.0; 3];
    let err =
        aras_ident::LinearModel::fill(&m, &[0.0; 2], &[0.0; 2], &[0.0; 2], &mut short).unwrap_err();
    assert!(
        matches!(
            err,
            UrdfError::Dimension {
                what: "regressor",
                ..
            }
        ),
        "{err}"
    );
}
