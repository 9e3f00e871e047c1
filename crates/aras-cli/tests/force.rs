//! `--force` replaces only what the tool wrote: a run directory carries a
//! manifest of its files, and a directory without one, with anything it
//! does not list, or holding one of the run's inputs, is refused with the
//! offending file's name; single files are replaced only when they are an
//! output of the same kind and not an input.

mod common;

use std::process::Output;

use common::{aras, fixture, own_run, scratch, snapshot};

use aras_cli::output::{FileKind, MANIFEST, Manifest, OutDir, check_new_file};

fn stderr(r: &Output) -> String {
    String::from_utf8_lossy(&r.stderr).into_owned()
}

fn err_of(r: anyhow::Result<OutDir>) -> String {
    format!("{:#}", r.err().expect("refused"))
}

/// The reported case: the raw log and an unrelated note in the output
/// directory; `identify --force` is refused before anything is read or
/// written, naming the log, and both files survive byte for byte.
#[test]
fn identify_force_refuses_an_out_dir_holding_its_input_log() {
    let lab = scratch("force", "lab");
    let log = lab.join("run.csv");
    std::fs::copy(fixture("logs/good/counts_currents.csv"), &log).unwrap();
    std::fs::write(lab.join("notes.txt"), "calibration notes\n").unwrap();
    let before = snapshot(&lab);
    let r = aras(&[
        "identify",
        "--data",
        log.to_str().unwrap(),
        "--out",
        lab.to_str().unwrap(),
        "--force",
        "-q",
    ]);
    assert!(!r.status.success());
    let msg = stderr(&r);
    assert!(
        msg.contains("run.csv") && msg.contains("inside the output directory"),
        "{msg}"
    );
    assert_eq!(
        snapshot(&lab),
        before,
        "a file in the lab directory changed"
    );
}

/// Even a file the tool wrote (a pipeline's `log.csv`, listed in the
/// manifest) is refused as an input inside the output.
#[test]
fn an_input_listed_in_the_manifest_is_still_refused() {
    let dir = scratch("force", "listed-input");
    let out = dir.join("out");
    own_run(&out, &[("log.csv", "t\n"), ("params.json", "{}\n")]);
    let before = snapshot(&out);
    let msg = err_of(OutDir::create(&out, true, &[out.join("log.csv")]));
    assert!(msg.contains("log.csv") && msg.contains("--out"), "{msg}");
    // The output directory being the input's directory itself.
    let msg = err_of(OutDir::create(&out, true, std::slice::from_ref(&out)));
    assert!(msg.contains("inside the output directory"), "{msg}");
    assert_eq!(snapshot(&out), before);
}

/// A file the manifest does not list is named, and nothing is removed.
#[test]
fn force_refuses_a_directory_with_an_unlisted_file() {
    let dir = scratch("force", "unlisted");
    let out = dir.join("out");
    own_run(
        &out,
        &[("params.json", "{}\n"), ("figures/a.svg", "<svg/>")],
    );
    std::fs::write(out.join("figures/notes.txt"), "mine").unwrap();
    let before = snapshot(&out);
    let msg = err_of(OutDir::create(&out, true, &[]));
    assert!(
        msg.contains("notes.txt") && msg.contains("did not write"),
        "{msg}"
    );
    assert_eq!(snapshot(&out), before);
    // An unlisted empty directory is refused too.
    std::fs::remove_file(out.join("figures/notes.txt")).unwrap();
    std::fs::create_dir(out.join("mine")).unwrap();
    let msg = err_of(OutDir::create(&out, true, &[]));
    assert!(msg.contains("mine"), "{msg}");
}

/// A directory without a manifest (not written by aras) is refused with
/// `--force`, and without `--force` any non-empty directory is.
#[test]
fn force_refuses_a_directory_without_a_manifest() {
    let dir = scratch("force", "no-manifest");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("params.json"), "{}\n").unwrap();
    let before = snapshot(&out);
    let msg = err_of(OutDir::create(&out, true, &[]));
    assert!(
        msg.contains(MANIFEST) && msg.contains("choose another --out"),
        "{msg}"
    );
    let msg = err_of(OutDir::create(&out, false, &[]));
    assert!(msg.contains("--force"), "{msg}");
    assert_eq!(snapshot(&out), before);
}

/// A manifest that lists a path outside the directory (`..`, absolute) is
/// not followed: the run is refused and the outside file stays.
#[test]
fn a_manifest_pointing_outside_the_directory_is_not_followed() {
    let dir = scratch("force", "escape");
    let out = dir.join("out");
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    for listed in [
        "../victim.txt".to_string(),
        victim.display().to_string(),
        "a/../../victim.txt".to_string(),
    ] {
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(&out).unwrap();
        let m = Manifest {
            format: "aras-manifest/1".into(),
            tool: "aras 0.1.0".into(),
            files: vec![listed.clone()],
        };
        std::fs::write(out.join(MANIFEST), serde_json::to_string(&m).unwrap()).unwrap();
        let msg = err_of(OutDir::create(&out, true, &[]));
        assert!(msg.contains("not inside the directory"), "{listed}: {msg}");
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    }
    // A manifest that is not one of ours (another format) is refused too.
    std::fs::write(out.join(MANIFEST), "{\"files\": []}").unwrap();
    assert!(err_of(OutDir::create(&out, true, &[])).contains("not a manifest written by aras"));
}

/// Re-running over the tool's own output replaces it: the new manifest
/// lists exactly the new files, the old run's files are gone.
#[test]
fn force_replaces_the_tools_own_previous_output() {
    let dir = scratch("force", "rerun");
    let out = dir.join("out");
    own_run(&out, &[("old.json", "{}\n"), ("figures/a.svg", "<svg/>")]);
    own_run(&out, &[("new.json", "{}\n"), ("validation/b.csv", "t\n")]);
    let m = Manifest::read(&out).unwrap().unwrap();
    assert_eq!(m.files, ["new.json", "validation/b.csv"]);
    assert!(m.tool.starts_with("aras "));
    let names: Vec<String> = snapshot(&out).into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, [MANIFEST, "new.json", "validation/b.csv"]);
    // No backup or staging directory is left next to it.
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, ["out"]);
}

/// The real binary, twice over the same directory: the second run with
/// `--force` succeeds and writes its manifest; without it, it is refused.
#[test]
fn validate_twice_with_force_replaces_its_own_output() {
    let dir = scratch("force", "validate");
    let cfg = dir.join("short.toml");
    std::fs::write(
        &cfg,
        "[validation]\nfrequencies_hz = [1.0]\nperiods = 2\npd_grid = 5\npd_random = 10\n",
    )
    .unwrap();
    let out = dir.join("out");
    let params = fixture("robots/aras-diamond.json");
    let run = |force: bool| {
        let mut a = vec![
            "validate",
            "--params",
            params.to_str().unwrap(),
            "--config",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ];
        if force {
            a.push("--force");
        }
        aras(&a)
    };
    let r = run(false);
    assert!(r.status.success(), "{}", stderr(&r));
    let m = Manifest::read(&out).unwrap().expect("a manifest");
    assert!(m.files.iter().any(|f| f == "summary.json"), "{:?}", m.files);
    assert!(!run(false).status.success());
    let r = run(true);
    assert!(r.status.success(), "{}", stderr(&r));
    // The config file inside the output is an input: refused.
    let inner = out.join("cfg.toml");
    std::fs::copy(&cfg, &inner).unwrap();
    let r = aras(&[
        "validate",
        "--params",
        params.to_str().unwrap(),
        "--config",
        inner.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--force",
    ]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("cfg.toml"), "{}", stderr(&r));
}

/// Files that appear in the old directory while the run works are not
/// lost: the commit is refused, the old directory stays as it is and the
/// results are kept in the staging directory the message names.
#[test]
fn a_file_added_during_the_run_blocks_the_swap() {
    let dir = scratch("force", "during");
    let out = dir.join("out");
    own_run(&out, &[("params.json", "{}\n")]);
    let o = OutDir::create(&out, true, &[]).unwrap();
    o.write("params.json", "{\"new\": 1}\n").unwrap();
    std::fs::write(out.join("late.txt"), "written meanwhile").unwrap();
    let before = snapshot(&out);
    let msg = format!("{:#}", o.commit().expect_err("refused"));
    assert!(msg.contains("late.txt") && msg.contains("kept in"), "{msg}");
    assert_eq!(snapshot(&out), before);
}

/// Single files: never an input, and with `--force` only an output of the
/// same kind is replaced.
#[test]
fn single_file_force_replaces_only_its_own_kind() {
    let dir = scratch("force", "single");
    let pred = dir.join("p.csv");
    std::fs::write(&pred, "t,tau1,tau2\n0,0,0\n").unwrap();
    check_new_file(&pred, true, FileKind::Prediction, &[]).unwrap();
    assert!(check_new_file(&pred, false, FileKind::Prediction, &[]).is_err());
    let notes = dir.join("notes.csv");
    std::fs::write(&notes, "a,b\n1,2\n").unwrap();
    let msg = format!(
        "{:#}",
        check_new_file(&notes, true, FileKind::Prediction, &[]).unwrap_err()
    );
    assert!(
        msg.contains("notes.csv") && msg.contains("not a prediction"),
        "{msg}"
    );
    let msg = format!(
        "{:#}",
        check_new_file(
            &pred,
            true,
            FileKind::Prediction,
            std::slice::from_ref(&pred)
        )
        .unwrap_err()
    );
    assert!(msg.contains("input"), "{msg}");
    // A simulated log: the sidecar carries the simulator's marker, and an
    // unrelated LOG.json next to a new log is not overwritten.
    let log = dir.join("log.csv");
    std::fs::write(dir.join("log.json"), "{\"note\": 1}").unwrap();
    let msg = format!(
        "{:#}",
        check_new_file(&log, true, FileKind::SimulatedLog, &[]).unwrap_err()
    );
    assert!(msg.contains("log.json"), "{msg}");
    std::fs::write(&log, "t\n").unwrap();
    std::fs::write(
        dir.join("log.json"),
        "{\"format\": \"aras-log/1\", \"truth\": {}}",
    )
    .unwrap();
    check_new_file(&log, true, FileKind::SimulatedLog, &[]).unwrap();
    // The trajectory input as the log's sidecar: refused.
    let traj = dir.join("t.json");
    std::fs::copy(fixture("trajectories/default-excitation.json"), &traj).unwrap();
    let msg = format!(
        "{:#}",
        check_new_file(
            &dir.join("t.csv"),
            true,
            FileKind::SimulatedLog,
            std::slice::from_ref(&traj)
        )
        .unwrap_err()
    );
    assert!(msg.contains("t.json") && msg.contains("input"), "{msg}");
    check_new_file(&traj, true, FileKind::Trajectory, &[]).unwrap();
    // The CLI: `predict --out` onto its own log.
    let data = dir.join("run.csv");
    std::fs::copy(fixture("logs/good/counts_currents.csv"), &data).unwrap();
    let before = std::fs::read(&data).unwrap();
    let r = aras(&[
        "predict",
        "--params",
        fixture("robots/aras-diamond.json").to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--out",
        data.to_str().unwrap(),
        "--force",
    ]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("input"), "{}", stderr(&r));
    assert_eq!(std::fs::read(&data).unwrap(), before);
}
