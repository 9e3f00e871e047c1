//! Parameter files: strict reading, round trips, the default robot from the
//! CAD table (`docs/model.md`, "Default robot"), and the thin-arc helper.

use std::path::PathBuf;

use aras_dyn::{ArcLink, Cogging, Params, PointMass, Stribeck, arc_robot};
use aras_testkit::{assert_source_not_repeated, error_chain as chain, io_source_kind};
use nalgebra::{Matrix3, Vector3};

fn fixture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/robots/aras-diamond.json")
}

/// Regenerates the fixture from the constructor:
/// `cargo test -p aras-dyn --test params -- --ignored write_fixture`.
#[test]
#[ignore]
fn write_fixture() {
    std::fs::create_dir_all(fixture().parent().unwrap()).unwrap();
    Params::aras_diamond().save(fixture()).unwrap();
}

#[test]
fn fixture_equals_constructor() {
    assert_eq!(Params::load(fixture()).unwrap(), Params::aras_diamond());
}

/// Reproduces the CAD table's conversion independently: the COM by explicit
/// rotation matrices, `I_O = I_G + m [ρ]×ᵀ [ρ]×` with the skew matrices
/// written out. Same arithmetic up to ordering, so 1e-15 relative.
#[test]
fn cad_conversion_reproduced() {
    let table: [(f64, [f64; 3], f64, f64); 4] = [
        (
            0.1170118419,
            [6.4413629155e-4, 6.3501139794e-4, 1.7161749378e-5],
            22.9518,
            0.252,
        ),
        (
            0.1121923268,
            [5.3590531389e-4, 5.2840271497e-4, 1.5074544696e-5],
            22.6335,
            0.228,
        ),
        (
            0.1555782254,
            [9.8499010048e-4, 9.3427520943e-4, 6.1016538598e-5],
            22.8026,
            0.276,
        ),
        (
            0.1453301931,
            [7.5779670437e-4, 7.4969800460e-4, 2.3482517406e-5],
            22.5,
            0.204,
        ),
    ];
    let p = Params::load(fixture()).unwrap();
    for (k, (m, ig, q, r)) in table.into_iter().enumerate() {
        let q = q.to_radians();
        let ry = Matrix3::new(q.cos(), 0.0, q.sin(), 0.0, 1.0, 0.0, -q.sin(), 0.0, q.cos());
        let rho = ry * Vector3::new(0.0, 0.0, r);
        let sk = rho.cross_matrix();
        let io = Matrix3::from_diagonal(&Vector3::from(ig)) + sk.transpose() * sk * m;
        let l = &p.links[k];
        assert!(
            (l.inertia() - io).norm() <= 1e-15 * io.norm(),
            "link {}",
            k + 1
        );
        assert!((l.h - rho * m).norm() <= 1e-15 * m * r);
        assert_eq!(l.mass, m);
        // COM lies in the x–z plane, about halfway along the 45° arc.
        assert_eq!(l.h.y, 0.0);
        // Inverse conversion gives back the diagonal COM inertia.
        let back = l.inertia_about_com().unwrap();
        assert!((back - Matrix3::from_diagonal(&Vector3::from(ig))).norm() <= 1e-12 * io.norm());
        // Physically consistent: pseudo-inertia positive definite.
        assert!(
            p.pseudo_inertia(k + 1)
                .unwrap()
                .symmetric_eigenvalues()
                .min()
                > 0.0
        );
    }
    assert_eq!(p.friction.viscous, [0.034321, 0.008779]);
    assert_eq!(p.friction.coulomb, [0.076031, 0.28876]);
    assert_eq!(p.elasticity, [0.001, 0.065757]);
    assert_eq!(p.gravity, Vector3::new(0.0, -9.81, 0.0));
}

fn with_extras() -> Params {
    let mut p = Params::aras_diamond();
    p.extra.torque_offset = Some([0.1, -0.2]);
    p.extra.stribeck_friction = Some(Stribeck {
        v_s: 0.05,
        level: [0.01, 0.02],
    });
    p.extra.cogging = Some(Cogging {
        cycles_per_rev: 7.0,
        sin: [vec![1e-3], vec![2e-3]],
        cos: [vec![3e-3], vec![4e-3]],
    });
    p.extra.passive_joint_viscous = Some([1e-3, 2e-3, 3e-3]);
    p.extra.coulomb_asymmetry = Some([0.01, 0.02]);
    p.extra.quadratic_damping = Some([0.5, 0.25]);
    p
}

#[test]
fn json_round_trip_is_exact() {
    for p in [Params::aras_diamond(), with_extras()] {
        let text = p.to_json_string();
        assert_eq!(Params::from_json_str(&text).unwrap(), p);
        // Through serde too.
        let q: Params = serde_json::from_str(&text).unwrap();
        assert_eq!(q, p);
    }
    let text = with_extras().to_json_string();
    assert!(text.contains("\"Cs1_1\"") && text.contains("\"cycles_per_rev\""));
}

fn err_of(edit: impl Fn(&mut serde_json::Value)) -> String {
    let mut v = serde_json::to_value(with_extras()).unwrap();
    edit(&mut v);
    Params::from_json_str(&v.to_string())
        .unwrap_err()
        .to_string()
}

#[test]
fn bad_files_name_the_key() {
    let e = err_of(|v| {
        v["links"]["3"].as_object_mut().unwrap().remove("Ixy");
    });
    assert!(e.contains("missing key `links.3.Ixy`"), "{e}");
    let e = err_of(|v| v["links"]["2"]["Ixq"] = 1.0.into());
    assert!(
        e.contains("unknown key `links.2.Ixq`") && e.contains("Ixx"),
        "{e}"
    );
    let e = err_of(|v| v["friction"]["Fv1"] = "fast".into());
    assert!(
        e.contains("`friction.Fv1` must be a number") && e.contains("\"fast\""),
        "{e}"
    );
    let e = err_of(|v| v["gravity"] = serde_json::json!([0.0, -9.81]));
    assert!(e.contains("`gravity`") && e.contains("2 entries"), "{e}");
    let e = err_of(|v| v["geometry"]["alpha_deg"] = 190.0.into());
    assert!(e.contains("geometry.alpha_deg") && e.contains("190"), "{e}");
    let e = err_of(|v| {
        v.as_object_mut().unwrap().remove("elasticity");
    });
    assert!(e.contains("missing key `elasticity`"), "{e}");
    let e = err_of(|v| v["extra"]["stribeck_friction"]["v_s"] = (-1.0).into());
    assert!(e.contains("extra.stribeck_friction.v_s"), "{e}");
    let e = err_of(|v| v["extra"]["cogging"]["order"] = 2.into());
    assert!(e.contains("missing key `extra.cogging.Cs1_2`"), "{e}");
    let e = err_of(|v| v["extra"]["cogging"]["order"] = 1.5.into());
    assert!(e.contains("extra.cogging.order"), "{e}");
    let e = err_of(|v| v["extra"]["backlash"] = serde_json::json!({}));
    assert!(e.contains("unknown key `extra.backlash`"), "{e}");
    let e = err_of(|v| v["links"] = serde_json::json!([1, 2]));
    assert!(e.contains("`links` must be a JSON object"), "{e}");
    // Out-of-range numbers are JSON errors with a position.
    let text = with_extras()
        .to_json_string()
        .replace("\"Ke1\": 0.001", "\"Ke1\": 1e999");
    let e = Params::from_json_str(&text).unwrap_err().to_string();
    assert!(e.contains("line") && e.contains("column"), "{e}");
    let e = Params::from_json_str("{\"geometry\": {")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 1"), "{e}");
    // Gravity is optional and defaults to [0, −9.81, 0].
    let mut v = serde_json::to_value(Params::aras_diamond()).unwrap();
    v.as_object_mut().unwrap().remove("gravity");
    assert_eq!(
        Params::from_json_str(&v.to_string()).unwrap(),
        Params::aras_diamond()
    );
}

#[test]
fn non_finite_values_are_rejected_everywhere() {
    let mut p = Params::aras_diamond();
    p.links[2].ixy = f64::NAN;
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains("links.3.Ixy") && e.contains("not finite"), "{e}");
    let mut p = Params::aras_diamond();
    p.gravity.z = f64::INFINITY;
    assert!(p.validate().unwrap_err().to_string().contains("gravity[2]"));
    assert!(aras_dyn::Dynamics::new(&p).is_err());
    let mut p = with_extras();
    p.extra.cogging.as_mut().unwrap().cos[1][0] = f64::NAN;
    assert!(
        p.validate()
            .unwrap_err()
            .to_string()
            .contains("extra.cogging.Cc2_1")
    );
}

#[test]
fn load_and_save_report_the_file() {
    let dir = aras_testkit::Scratch::new("dyn-params");
    let path = dir.join("robot.json");
    with_extras().save(&path).unwrap();
    assert_eq!(Params::load(&path).unwrap(), with_extras());
    std::fs::write(&path, "{\"geometry\": 3}").unwrap();
    let e = chain(&Params::load(&path).unwrap_err());
    assert!(
        e.contains("robot.json") && e.contains("`geometry` must be a JSON object"),
        "{e}"
    );
    let e = Params::load(dir.join("absent.json"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("absent.json"), "{e}");
}

/// The thin-arc helper against a brute-force sum over 200 000 point masses
/// along the arc (midpoint rule: error ~ (L/n)² ≈ 1e-11 relative).
#[test]
fn arc_helper_matches_discretised_arc() {
    let link = ArcLink {
        arc_mass: 0.12,
        arc_radius: 0.25,
        points: vec![PointMass {
            mass: 0.05,
            angle: 0.7,
            radius: 0.25,
        }],
    };
    let p = arc_robot(
        45.0,
        50.0,
        &[link.clone(), link.clone(), link.clone(), link],
    )
    .unwrap();
    for (k, span) in [(0, 45f64), (2, 50.0)] {
        let span = span.to_radians();
        let n = 200_000;
        let (mut i, mut h) = (Matrix3::zeros(), Vector3::zeros());
        let dm = 0.12 / n as f64;
        let mut add = |m: f64, ang: f64, r: f64| {
            let pos = Vector3::new(r * ang.sin(), 0.0, r * ang.cos());
            i += (Matrix3::identity() * pos.norm_squared() - pos * pos.transpose()) * m;
            h += pos * m;
        };
        for q in 0..n {
            add(dm, (q as f64 + 0.5) / n as f64 * span, 0.25);
        }
        add(0.05, 0.7, 0.25);
        let l = &p.links[k];
        assert!(
            (l.inertia() - i).norm() <= 1e-9 * i.norm(),
            "link {}: {} vs {}",
            k + 1,
            l.inertia(),
            i
        );
        assert!((l.h - h).norm() <= 1e-9 * h.norm());
        assert!((l.mass - 0.17).abs() < 1e-15);
        // Planar body: pseudo-inertia semidefinite (y extent zero).
        assert!(l.pseudo_inertia().symmetric_eigenvalues().min() > -1e-15);
    }
    let bad = ArcLink {
        arc_mass: -1.0,
        ..Default::default()
    };
    let e = arc_robot(
        45.0,
        45.0,
        &[
            ArcLink::default(),
            bad,
            ArcLink::default(),
            ArcLink::default(),
        ],
    )
    .unwrap_err();
    assert!(e.to_string().contains("arc_robot.links.2.arc_mass"), "{e}");
}

#[test]
fn pseudo_inertia_rejects_link_numbers_outside_1_to_4() {
    let p = Params::aras_diamond();
    for k in [0, 5, usize::MAX] {
        let e = p.pseudo_inertia(k).unwrap_err().to_string();
        assert!(e.contains("1 to 4"), "{e}");
    }
    assert!(p.pseudo_inertia(4).is_ok());
}

#[test]
fn file_errors_name_the_file_and_keep_the_cause_as_source() {
    let dir = aras_testkit::Scratch::new("dyn-chain");
    let path = dir.join("robot.json");
    std::fs::write(&path, "{\"geometry\": 3}").unwrap();
    let e = Params::load(&path).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("in parameter file {}", path.display())
    );
    let inner = std::error::Error::source(&e).expect("the defect is the source");
    assert!(
        inner
            .to_string()
            .contains("`geometry` must be a JSON object"),
        "{inner}"
    );
    assert_source_not_repeated(&e);

    let absent = dir.join("absent.json");
    let e = Params::load(&absent).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("cannot access parameter file {}", absent.display())
    );
    assert_eq!(io_source_kind(&e), std::io::ErrorKind::NotFound);
    assert_source_not_repeated(&e);
}
