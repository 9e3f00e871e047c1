//! `aras export-mjcf`: writes the MJCF of a parameter file atomically,
//! refuses to replace what it did not write (or the parameter file itself),
//! and refuses bodies MuJoCo would reject, naming the link.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh scratch directory, removed when the test passes.
fn scratch(name: &str) -> aras_testkit::Scratch {
    aras_testkit::Scratch::new(&format!("mjcf-{name}"))
}

fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(rel)
}

fn aras(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(r: &Output) -> String {
    String::from_utf8_lossy(&r.stderr).into_owned()
}

#[test]
fn exports_refuses_foreign_files_and_inconsistent_links() {
    let dir = scratch("cli");
    let params = fixture("robots/aras-diamond.json");
    let p = params.to_str().unwrap();
    let out = dir.join("robot.xml");
    let o = out.to_str().unwrap();

    let r = aras(&["export-mjcf", "--params", p, "--out", o]);
    assert!(r.status.success(), "{}", stderr(&r));
    let xml = std::fs::read_to_string(&out).unwrap();
    let want = aras_dyn::mjcf::to_mjcf(
        &aras_dyn::Params::load(&params).unwrap(),
        &Default::default(),
    )
    .unwrap();
    assert_eq!(xml, want);
    // No temporary file left beside it: only its record.
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, [".robot.xml.aras-manifest.json", "robot.xml"]);

    // Exists: refused without --force, replaced with it (aras wrote it).
    let r = aras(&["export-mjcf", "--params", p, "--out", o]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("already exists"), "{}", stderr(&r));
    let r = aras(&["export-mjcf", "--params", p, "--out", o, "--force"]);
    assert!(r.status.success(), "{}", stderr(&r));

    // Someone else's file is never replaced, even with --force.
    let foreign = dir.join("mine.xml");
    std::fs::write(&foreign, "<mujoco model=\"hand-made\"/>\n").unwrap();
    let r = aras(&[
        "export-mjcf",
        "--params",
        p,
        "--out",
        foreign.to_str().unwrap(),
        "--force",
    ]);
    assert!(!r.status.success());
    assert!(
        stderr(&r).contains("no record that aras wrote it"),
        "{}",
        stderr(&r)
    );
    assert_eq!(
        std::fs::read_to_string(&foreign).unwrap(),
        "<mujoco model=\"hand-made\"/>\n"
    );

    // The parameter file itself is never the output.
    let copy = dir.join("p.json");
    std::fs::copy(&params, &copy).unwrap();
    let c = copy.to_str().unwrap();
    let r = aras(&["export-mjcf", "--params", c, "--out", c, "--force"]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("input"), "{}", stderr(&r));

    // A link MuJoCo would reject: the message names it; nothing is written.
    let bad = fixture("bad/params/non_pd_inertia.json");
    let bad_out = dir.join("bad.xml");
    let r = aras(&[
        "export-mjcf",
        "--params",
        bad.to_str().unwrap(),
        "--out",
        bad_out.to_str().unwrap(),
    ]);
    assert!(!r.status.success());
    assert!(
        stderr(&r).contains("link 1 is not physically consistent"),
        "{}",
        stderr(&r)
    );
    assert!(!bad_out.exists());
}
