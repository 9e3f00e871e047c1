//! The MJCF export read back: inertials → standard parameters (round trip),
//! body frames and joints → the link frames of `aras_kin`, loop closure,
//! coefficients, and the errors for bodies MuJoCo would reject.
//!
//! The reader below is deliberately small (tags and attributes, no DTD, no
//! entities beyond what the exporter escapes): enough to read what the
//! exporter writes, not an MJCF importer.

use std::collections::HashMap;

use aras_dyn::mjcf::{MjcfError, MjcfOptions, passive_hinge_angles, to_mjcf};
use aras_dyn::{Cogging, Inertia, Params};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector2, Vector3};
use proptest::prelude::*;

/// One element: name, attributes, depth (0 = `<mujoco>`), parent body.
#[derive(Debug, Clone)]
struct Element {
    name: String,
    attrs: HashMap<String, String>,
    body: Option<String>,
}

/// Tags of an MJCF text in document order; panics on malformed text (the
/// test then fails with the reason).
fn parse(xml: &str) -> Vec<Element> {
    let mut out = Vec::new();
    let mut bodies: Vec<String> = Vec::new();
    let mut rest = xml;
    while let Some(start) = rest.find('<') {
        rest = &rest[start..];
        if let Some(r) = rest.strip_prefix("<!--") {
            let end = r.find("-->").expect("unterminated comment");
            assert!(!r[..end].contains("--"), "`--` inside a comment");
            rest = &r[end + 3..];
            continue;
        }
        if let Some(r) = rest.strip_prefix("<?") {
            rest = &r[r.find("?>").expect("unterminated declaration") + 2..];
            continue;
        }
        let end = rest.find('>').expect("unterminated tag");
        let tag = &rest[1..end];
        rest = &rest[end + 1..];
        if let Some(name) = tag.strip_prefix('/') {
            if name.trim() == "body" {
                bodies.pop().expect("unbalanced </body>");
            }
            continue;
        }
        let self_closing = tag.ends_with('/');
        let tag = tag.trim_end_matches('/');
        let (name, mut a) = tag.split_once(char::is_whitespace).unwrap_or((tag, ""));
        let mut attrs = HashMap::new();
        loop {
            a = a.trim_start();
            if a.is_empty() {
                break;
            }
            let eq = a.find('=').expect("attribute without value");
            let key = a[..eq].trim().to_string();
            let v = a[eq + 1..].trim_start();
            assert!(v.starts_with('"'), "unquoted attribute {key}");
            let close = v[1..].find('"').expect("unterminated attribute") + 1;
            attrs.insert(key, v[1..close].to_string());
            a = &v[close + 1..];
        }
        out.push(Element {
            name: name.to_string(),
            attrs: attrs.clone(),
            body: bodies.last().cloned(),
        });
        if name == "body" && !self_closing {
            bodies.push(attrs["name"].clone());
        }
    }
    assert!(bodies.is_empty(), "unclosed bodies {bodies:?}");
    out
}

fn numbers(s: &str) -> Vec<f64> {
    s.split_whitespace()
        .map(|x| x.parse().expect("a number"))
        .collect()
}

fn find<'a>(els: &'a [Element], name: &str, key: &str, value: &str) -> &'a Element {
    els.iter()
        .find(|e| e.name == name && e.attrs.get(key).map(String::as_str) == Some(value))
        .unwrap_or_else(|| panic!("no <{name} {key}=\"{value}\">"))
}

/// The body's inertial, back to the standard parameters by (28).
fn read_link(els: &[Element], k: usize) -> Inertia {
    let body = format!("link{k}");
    let i = els
        .iter()
        .find(|e| e.name == "inertial" && e.body.as_deref() == Some(body.as_str()))
        .expect("inertial");
    let pos = numbers(&i.attrs["pos"]);
    let mass: f64 = i.attrs["mass"].parse().unwrap();
    let f = numbers(&i.attrs["fullinertia"]);
    let ig = Matrix3::new(f[0], f[3], f[4], f[3], f[1], f[5], f[4], f[5], f[2]);
    Inertia::from_com(mass, &ig, &Vector3::new(pos[0], pos[1], pos[2]))
}

fn assert_round_trip(p: &Params) {
    let xml = to_mjcf(p, &MjcfOptions::default()).expect("exportable");
    let els = parse(&xml);
    for (k, want) in p.links.iter().enumerate() {
        let got = read_link(&els, k + 1);
        let (a, b) = (got.standard(), want.standard());
        let scale_i = a[..6]
            .iter()
            .chain(&b[..6])
            .fold(0f64, |m, x| m.max(x.abs()));
        let scale_h = a[6..]
            .iter()
            .chain(&b[6..])
            .fold(0f64, |m, x| m.max(x.abs()));
        for j in 0..9 {
            let scale = if j < 6 { scale_i } else { scale_h };
            // 1e-12 relative: the numbers are written with shortest
            // round-trip formatting, so only the parallel-axis arithmetic
            // (a few roundings of O(1e-16)) separates the two.
            assert!(
                (a[j] - b[j]).abs() <= 1e-12 * scale,
                "link {} parameter {j}: {} vs {} (scale {scale})",
                k + 1,
                a[j],
                b[j]
            );
        }
        assert_eq!(got.mass, want.mass);
    }
}

/// Rotation of a body's frame relative to its parent from the XML (`quat`).
fn body_quat(els: &[Element], body: &str) -> Matrix3<f64> {
    let b = find(els, "body", "name", body);
    match b.attrs.get("quat") {
        None => Matrix3::identity(),
        Some(q) => {
            let q = numbers(q);
            *UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
                .to_rotation_matrix()
                .matrix()
        }
    }
}

fn rz(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// World rotations of bodies link1..link4 at `qpos = [θ1, q_c, θ2, q_b]`,
/// from the XML's body quats and joint axes.
fn world_rotations(els: &[Element], qpos: &[f64; 4]) -> [Matrix3<f64>; 4] {
    for j in ["theta1", "theta2", "hinge_b", "hinge_c"] {
        assert_eq!(find(els, "joint", "name", j).attrs["axis"], "0 0 1");
    }
    let r2 = body_quat(els, "link2") * rz(qpos[0]);
    let r4 = r2 * body_quat(els, "link4") * rz(qpos[1]);
    let r1 = body_quat(els, "link1") * rz(qpos[2]);
    let r3 = r1 * body_quat(els, "link3") * rz(qpos[3]);
    [r1, r2, r3, r4]
}

#[test]
fn default_robot_round_trips() {
    assert_round_trip(&Params::aras_diamond());
}

#[test]
fn body_frames_are_the_link_frames_and_the_loop_closes() {
    let p = Params::aras_diamond();
    let g = p.geometry().unwrap();
    let xml = to_mjcf(&p, &MjcfOptions::default()).unwrap();
    let els = parse(&xml);
    let connect = find(&els, "connect", "name", "hinge_d");
    assert_eq!(connect.attrs["body1"], "link3");
    assert_eq!(connect.attrs["body2"], "link4");
    let anchor = numbers(&connect.attrs["anchor"]);
    let anchor = Vector3::new(anchor[0], anchor[1], anchor[2]);
    let mut n = 0;
    for phi_deg in (30..=140).step_by(10) {
        for gamma_deg in (40..=80).step_by(5) {
            let x = Vector2::new(
                f64::from(phi_deg).to_radians(),
                f64::from(gamma_deg).to_radians(),
            );
            let ik = aras_kin::inverse(&g, &x).unwrap();
            let [qb, qc] = passive_hinge_angles(&p, &x).unwrap();
            // The passive angles against (4): q_b = π − B, q_c = C − π.
            let pi = std::f64::consts::PI;
            assert!((qb - (pi - ik.passive.b)).abs() < 1e-12);
            assert!((qc - (ik.passive.c - pi)).abs() < 1e-12);
            let r = world_rotations(&els, &[ik.theta[0], qc, ik.theta[1], qb]);
            let want = aras_kin::link_frames(&g, &x).unwrap();
            for k in 0..4 {
                // Products of a few unit rotations: rounding only.
                assert!(
                    (r[k] - want[k]).norm() < 1e-13,
                    "link {} frame at [{phi_deg}°, {gamma_deg}°]",
                    k + 1
                );
            }
            // The anchor, fixed in link 3 and in link 4, is the same point r·d.
            let (p3, p4) = (r[2] * anchor, r[3] * anchor);
            assert!((p3 - p4).norm() < 1e-13);
            let d = Vector3::new(x[1].sin() * x[0].cos(), x[1].sin() * x[0].sin(), x[1].cos());
            assert!((p3 - d * MjcfOptions::default().anchor_radius).norm() < 1e-13);
            n += 1;
        }
    }
    assert_eq!(n, 12 * 9);
    // The home keyframe closes the loop too.
    let key = numbers(&find(&els, "key", "name", "home").attrs["qpos"]);
    let r = world_rotations(&els, &[key[0], key[1], key[2], key[3]]);
    assert!((r[2] * anchor - r[3] * anchor).norm() < 1e-13);
}

#[test]
fn coefficients_actuators_and_gravity() {
    let mut p = Params::aras_diamond();
    p.gravity = Vector3::new(0.1, -9.8, 0.3);
    p.extra.passive_joint_viscous = Some([0.002, 0.003, 0.004]);
    let xml = to_mjcf(&p, &MjcfOptions::default()).unwrap();
    let els = parse(&xml);
    let attr = |joint: &str, a: &str| -> f64 {
        find(&els, "joint", "name", joint).attrs[a].parse().unwrap()
    };
    assert_eq!(attr("theta1", "damping"), p.friction.viscous[0]);
    assert_eq!(attr("theta2", "damping"), p.friction.viscous[1]);
    assert_eq!(attr("theta1", "frictionloss"), p.friction.coulomb[0]);
    assert_eq!(attr("theta2", "frictionloss"), p.friction.coulomb[1]);
    assert_eq!(attr("theta1", "stiffness"), p.elasticity[0]);
    assert_eq!(attr("theta2", "stiffness"), p.elasticity[1]);
    assert_eq!(attr("theta1", "springref"), 0.0);
    assert_eq!(attr("hinge_b", "damping"), 0.002);
    assert_eq!(attr("hinge_c", "damping"), 0.003);
    // Motor 1 drives θ1 (link 2), motor 2 drives θ2 (link 1).
    assert_eq!(
        find(&els, "joint", "name", "theta1").body.as_deref(),
        Some("link2")
    );
    assert_eq!(
        find(&els, "joint", "name", "theta2").body.as_deref(),
        Some("link1")
    );
    for (m, j) in [("motor1", "theta1"), ("motor2", "theta2")] {
        let a = find(&els, "motor", "name", m);
        assert_eq!(a.attrs["joint"], j);
        assert_eq!(a.attrs["gear"], "1");
        assert!(!a.attrs.contains_key("ctrlrange"));
    }
    let opt = els.iter().find(|e| e.name == "option").unwrap();
    assert_eq!(numbers(&opt.attrs["gravity"]), vec![0.1, -9.8, 0.3]);
    // Fpd has no MJCF element: it is named in the comment with its value.
    assert!(xml.contains("passive_joint_viscous: Fpd = 0.004"));
    let comp = els.iter().find(|e| e.name == "compiler").unwrap();
    assert_eq!(comp.attrs["angle"], "radian");
}

#[test]
fn unrepresented_effects_are_listed_with_values() {
    let mut p = Params::aras_diamond();
    p.extra.cogging = Some(Cogging {
        cycles_per_rev: 48.0,
        sin: [vec![0.01], vec![0.0]],
        cos: [vec![0.0], vec![-0.02]],
    });
    p.extra.torque_offset = Some([0.05, -0.01]);
    let xml = to_mjcf(&p, &MjcfOptions::default()).unwrap();
    parse(&xml);
    assert!(xml.contains(
        "cogging: cycles_per_rev = 48, Cs1_1 = 0.01, Cc1_1 = 0, Cs2_1 = 0, Cc2_1 = -0.02"
    ));
    assert!(xml.contains("torque_offset: tau0_1 = 0.05, tau0_2 = -0.01"));
    let plain = to_mjcf(&Params::aras_diamond(), &MjcfOptions::default()).unwrap();
    assert!(plain.contains("Every effect of the parameter file is represented"));
    // The Coulomb transition width: frictionloss keeps the level, the
    // width is named in the notes.
    let mut p = Params::aras_diamond();
    p.friction.width = [0.03, 0.0125];
    let xml = to_mjcf(&p, &MjcfOptions::default()).unwrap();
    parse(&xml);
    assert!(xml.contains("friction: w1 = 0.03, w2 = 0.0125"), "{xml}");
    assert!(xml.contains("frictionloss=\"0.076031\""), "{xml}");
}

#[test]
fn bodies_mujoco_would_reject_are_refused_with_the_link() {
    // Inertia about the COM breaking the triangle inequality: a rod-like
    // tensor diag(1, 1, 3)·1e-4 about the COM.
    let mut p = Params::aras_diamond();
    let l = &p.links[2];
    let rho = l.h / l.mass;
    p.links[2] = Inertia::from_com(
        l.mass,
        &Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 3e-4)),
        &rho,
    );
    let e = to_mjcf(&p, &MjcfOptions::default()).unwrap_err();
    assert!(matches!(e, MjcfError::NotPhysical { link: 3, .. }), "{e}");
    assert!(e.to_string().contains("triangle inequality"), "{e}");
    // A non-positive-definite one.
    let mut p = Params::aras_diamond();
    p.links[0].ixx = -1e-3;
    let e = to_mjcf(&p, &MjcfOptions::default()).unwrap_err();
    assert!(matches!(e, MjcfError::NotPhysical { link: 1, .. }), "{e}");
    // Zero mass.
    let mut p = Params::aras_diamond();
    p.links[3].mass = 0.0;
    let e = to_mjcf(&p, &MjcfOptions::default()).unwrap_err();
    assert!(matches!(e, MjcfError::NotPhysical { link: 4, .. }), "{e}");
    // Negative damping, frictionloss, stiffness.
    for (set, key) in [
        (
            (|p: &mut Params| p.friction.viscous[1] = -0.01) as fn(&mut Params),
            "friction.Fv2",
        ),
        (
            |p: &mut Params| p.friction.coulomb[0] = -0.01,
            "friction.Fc1",
        ),
        (|p: &mut Params| p.elasticity[1] = -0.01, "elasticity.Ke2"),
    ] {
        let mut p = Params::aras_diamond();
        set(&mut p);
        let e = to_mjcf(&p, &MjcfOptions::default()).unwrap_err();
        assert!(e.to_string().contains(key), "{e}");
    }
    // Options.
    let o = MjcfOptions {
        timestep: 0.0,
        ..Default::default()
    };
    assert!(to_mjcf(&Params::aras_diamond(), &o).is_err());
    let o = MjcfOptions {
        constraint_time_constant: 5e-4,
        ..Default::default()
    };
    assert!(to_mjcf(&Params::aras_diamond(), &o).is_err());
}

/// A physically consistent link: four point masses at random positions
/// (their inertia about the COM is positive definite and obeys the
/// triangle inequality strictly unless they are coplanar with the COM).
fn point_mass_link() -> impl Strategy<Value = Inertia> {
    prop::collection::vec((0.01f64..0.5, -0.3f64..0.3, -0.3f64..0.3, -0.3f64..0.3), 4).prop_map(
        |pts| {
            let mut l = Inertia::default();
            let mut i = Matrix3::zeros();
            for (m, x, y, z) in pts {
                let r = Vector3::new(x, y, z);
                l.mass += m;
                l.h += r * m;
                i += (Matrix3::identity() * r.norm_squared() - r * r.transpose()) * m;
            }
            l.set_inertia(&i);
            l
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any physically consistent parameter set comes back from the XML to
    /// 1e-12 relative.
    #[test]
    fn random_consistent_links_round_trip(links in prop::collection::vec(point_mass_link(), 4)) {
        let mut p = Params::aras_diamond();
        for (k, l) in links.into_iter().enumerate() {
            p.links[k] = l;
        }
        // Nearly coplanar draws are legitimately rejected (as MuJoCo would).
        prop_assume!(p.links.iter().all(|l| {
            let e = l.pseudo_inertia().symmetric_eigenvalues();
            e.min() > 1e-9 * e.max()
        }));
        assert_round_trip(&p);
    }
}

#[test]
fn an_unusable_home_pose_keeps_the_kinematic_reason_as_source() {
    let opts = MjcfOptions {
        home: [0.5, 0.0], // γ = 0: outside the reachable polar angles
        ..MjcfOptions::default()
    };
    let e = to_mjcf(&Params::aras_diamond(), &opts).unwrap_err();
    assert_eq!(
        e.to_string(),
        "MJCF option `home` = [0.5, 0] rad is not a usable pose"
    );
    let kin = std::error::Error::source(&e)
        .and_then(|s| s.downcast_ref::<aras_kin::KinError>())
        .expect("the kinematic reason is the source");
    assert!(!e.to_string().contains(&kin.to_string()));
}
