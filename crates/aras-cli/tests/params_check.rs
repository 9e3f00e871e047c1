//! One parameter-file check for every command, and `validate` scores the
//! file's whole model (its geometry, gravity and extra effects), not the
//! nominal robot's with the file's inertias.

mod common;

use std::path::{Path, PathBuf};

use common::{aras, fixture, scratch, short_validate_config};

/// The nominal robot's file with `edit` applied, written to `dir/name`.
fn edited(dir: &Path, name: &str, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    let mut v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fixture("robots/aras-diamond.json")).unwrap(),
    )
    .unwrap();
    edit(&mut v);
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    p
}

/// `validate`'s fitness `[τ1, τ2]` at its one frequency.
fn validate(dir: &Path, params: &Path, tag: &str) -> Result<[f64; 2], String> {
    let cfg = short_validate_config(dir);
    let out = dir.join(format!("validate-{tag}"));
    let r = aras(&[
        "validate",
        "--params",
        params.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    if !r.status.success() {
        return Err(String::from_utf8_lossy(&r.stderr).into_owned());
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let f = &s["fitness"][0]["simulated"];
    Ok([f[0].as_f64().unwrap(), f[1].as_f64().unwrap()])
}

#[test]
fn validate_scores_the_files_own_geometry_gravity_and_effects() {
    let dir = scratch("params", "validate");
    let nominal = validate(&dir, &fixture("robots/aras-diamond.json"), "nominal").unwrap();
    let gravity = edited(&dir, "gravity.json", |v| {
        v["gravity"][1] = serde_json::json!(-981.0);
    });
    let alpha = edited(&dir, "alpha.json", |v| {
        v["geometry"]["alpha_deg"] = serde_json::json!(0.785);
    });
    let offset = edited(&dir, "offset.json", |v| {
        v["extra"] = serde_json::json!({"torque_offset": {"tau0_1": 0.5, "tau0_2": -0.5}});
    });
    for (name, p) in [
        ("gravity ×100", gravity),
        ("α = 0.785°", alpha),
        ("offset", offset),
    ] {
        match validate(&dir, &p, name.split(' ').next().unwrap()) {
            Ok(f) => assert!(
                f[0] < nominal[0] - 5.0 || f[1] < nominal[1] - 5.0,
                "{name}: {f:?} against the nominal file's {nominal:?}"
            ),
            // A geometry the configured workspace cannot reach is refused
            // with the reason: also not the nominal robot's fitness.
            Err(msg) => assert!(msg.contains("error"), "{name}: {msg}"),
        }
    }
}

#[test]
fn negative_friction_and_stiffness_are_refused_by_every_command_that_needs_bodies() {
    let dir = scratch("params", "signs");
    for (key, sub) in [("friction", "Fc1"), ("elasticity", "Ke1")] {
        let p = edited(&dir, &format!("{sub}.json"), |v| {
            v[key][sub] = serde_json::json!(-0.3);
        });
        let msg = validate(&dir, &p, sub).expect_err("refused");
        assert!(
            msg.contains(&format!("{key}.{sub}")) && msg.contains("negative"),
            "{msg}"
        );
        let xml = dir.join(format!("{sub}.xml"));
        let r = aras(&[
            "export-mjcf",
            "--params",
            p.to_str().unwrap(),
            "--out",
            xml.to_str().unwrap(),
        ]);
        assert!(!r.status.success());
        let msg = String::from_utf8_lossy(&r.stderr);
        assert!(msg.contains(&format!("{key}.{sub}")), "{msg}");
        assert!(!xml.exists());
    }
}
