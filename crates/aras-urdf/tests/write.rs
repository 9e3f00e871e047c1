//! The identified URDF: identified inertials in, every other byte kept,
//! and read back as the parameters written.

use aras_urdf::{ModelSettings, UrdfModel};

const PANDA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../fixtures/urdf/panda_arm.urdf"
);

/// `text` without its `<inertial>` elements and XML comments.
fn without_inertials(text: &str) -> String {
    let doc = roxmltree::Document::parse(text).unwrap();
    let mut cut: Vec<std::ops::Range<usize>> = doc
        .descendants()
        .filter(|n| n.is_comment() || (n.is_element() && n.tag_name().name() == "inertial"))
        .map(|n| n.range())
        .collect();
    cut.sort_by_key(|r| r.start);
    let mut out = String::new();
    let mut at = 0;
    for r in cut {
        if r.start >= at {
            out.push_str(&text[at..r.start]);
            at = r.end;
        }
    }
    out.push_str(&text[at..]);
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[test]
fn identified_inertials_replace_the_originals_and_nothing_else() {
    let source = std::fs::read_to_string(PANDA).unwrap();
    let model =
        UrdfModel::from_urdf_str(&source, "panda_arm.urdf", ModelSettings::default()).unwrap();
    assert!(
        model.joints().iter().any(|j| !j.merged.is_empty()),
        "fixture has merged links"
    );
    // Another physical robot: each body 20 % heavier and its centre of mass
    // moved (m c scaled by 1.1, I_O by 1.3 keeps I_c positive here).
    let mut p = model.urdf_parameters();
    let bodies = 10 * model.dof();
    for body in p[..bodies].chunks_mut(10) {
        body[0] *= 1.2;
        for x in &mut body[1..4] {
            *x *= 1.1;
        }
        for x in &mut body[4..] {
            *x *= 1.3;
        }
    }
    let text = model
        .identified_urdf(&source, "panda_arm.urdf", &p)
        .unwrap();
    let again =
        UrdfModel::from_urdf_str(&text, "identified.urdf", ModelSettings::default()).unwrap();
    for (k, (a, b)) in again.urdf_parameters().iter().zip(&p).enumerate() {
        assert!(
            (a - b).abs() <= 1e-12 * b.abs().max(1e-3),
            "{k}: {a} vs {b}"
        );
    }
    for (a, b) in again.joints().iter().zip(model.joints()) {
        assert!(a.name == b.name && a.axis == b.axis && a.limits == b.limits);
        assert!(a.origin_translation == b.origin_translation);
    }
    assert_eq!(without_inertials(&text), without_inertials(&source));
    // The merged links' inertials now live in their body's.
    assert!(text.contains("inertial identified as part of link `panda_link7`"));
}

#[test]
fn links_without_inertial_get_one_and_unphysical_bodies_are_refused() {
    let source = r#"<robot name="two">
  <link name="base"/>
  <link name="a"/>
  <link name="b">
    <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
  <joint name="j2" type="revolute">
    <parent link="a"/><child link="b"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
</robot>
"#;
    let model = UrdfModel::from_urdf_str(source, "two.urdf", ModelSettings::default()).unwrap();
    // Body a: 1 kg at (0.1, 0, 0), central inertia diag(0.01, 0.02, 0.03);
    // body b: 2 kg at the origin, diag(0.1, 0.1, 0.1).
    let a = [
        1.0,
        0.1,
        0.0,
        0.0,
        0.01,
        0.0,
        0.02 + 0.01,
        0.0,
        0.0,
        0.03 + 0.01,
    ];
    let b = [2.0, 0.0, 0.0, 0.0, 0.1, 0.0, 0.1, 0.0, 0.0, 0.1];
    let mut p: Vec<f64> = a.iter().chain(&b).copied().collect();
    // The joint columns (friction, armature) have no place in a URDF.
    p.resize(model.parameter_count(), 0.0);
    let text = model.identified_urdf(source, "two.urdf", &p).unwrap();
    let again = UrdfModel::from_urdf_str(&text, "two-id.urdf", ModelSettings::default()).unwrap();
    for (x, y) in again.urdf_parameters().iter().zip(&p) {
        assert!((x - y).abs() < 1e-15, "{x} vs {y}");
    }
    assert!(text.contains("<link name=\"base\"/>"), "{text}");
    assert!(text.contains("<visual>"), "{text}");
    // A negative mass, and an inertia that no body has (I_xx > I_yy + I_zz
    // about the centre of mass is not a physical body, yet it is
    // positive definite; a negative principal moment is refused).
    let mut bad = p.clone();
    bad[10] = -2.0;
    let e = model
        .identified_urdf(source, "two.urdf", &bad)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("link `b`") && e.contains("not a physical body"),
        "{e}"
    );
    let mut bad = p.clone();
    bad[4] = -0.05;
    let e = model
        .identified_urdf(source, "two.urdf", &bad)
        .unwrap_err()
        .to_string();
    assert!(e.contains("link `a`"), "{e}");
    // Another robot's text is refused.
    let other = source.replace("\"j2\"", "\"elbow\"");
    let e = model
        .identified_urdf(&other, "other.urdf", &p)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not the robot this model was built from"), "{e}");
}

/// The MJCF of a two-link arm: bodies nested as the tree, joint columns as
/// MuJoCo's armature and damping, Coulomb and offset named in a comment,
/// negative armature refused. (MuJoCo's own inverse dynamics of the
/// Panda's and the UR5's MJCF is checked by `cargo xtask check-urdf`.)
#[test]
fn the_mjcf_nests_the_bodies_and_carries_armature_and_damping() {
    let source = r#"<robot name="two">
  <link name="base"/>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
  <link name="b"><inertial><origin xyz="0.1 0 0"/><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
  <joint name="j2" type="prismatic">
    <parent link="a"/><child link="b"/><origin xyz="0.3 0 0" rpy="0 0.5 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.2" effort="10" velocity="1"/>
  </joint>
</robot>
"#;
    let model = UrdfModel::from_urdf_str(source, "two.urdf", ModelSettings::default()).unwrap();
    let mut p = model.urdf_parameters();
    let names = model.parameter_names();
    let set = |p: &mut Vec<f64>, name: &str, v: f64| {
        let i = names.iter().position(|n| n == name).unwrap();
        p[i] = v;
    };
    set(&mut p, "j1.Ia", 0.2);
    set(&mut p, "j2.Fv", 1.5);
    set(&mut p, "j2.Fc", 0.7);
    let xml = model.to_mjcf(&p).unwrap();
    let a = xml.find("<body name=\"a\"").unwrap();
    let b = xml.find("<body name=\"b\"").unwrap();
    let a_end = xml.rfind("</body>").unwrap();
    assert!(a < b && b < a_end, "{xml}");
    assert!(
        xml.contains("type=\"hinge\" axis=\"0 0 1\" range=\"-1 1\" armature=\"0.2\" damping=\"0\""),
        "{xml}"
    );
    assert!(xml.contains("type=\"slide\""), "{xml}");
    assert!(xml.contains("damping=\"1.5\""), "{xml}");
    assert!(xml.contains("Stribeck hump): j2: Coulomb 0.7 -->"), "{xml}");
    assert!(xml.contains("mass=\"2\""), "{xml}");
    set(&mut p, "j1.Ia", -0.1);
    let e = model.to_mjcf(&p).unwrap_err().to_string();
    assert!(
        e.contains("armature -0.1 is negative") && e.contains("link `a`"),
        "{e}"
    );
}
