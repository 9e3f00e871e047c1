//! `--force` replaces only what the tool wrote: a run directory carries a
//! manifest of its files, and a directory without one, with anything it
//! does not list, or holding one of the run's inputs, is refused with the
//! offending file's name; single files are replaced only when they are an
//! output of the same kind and not an input.

mod common;

use std::process::Output;

use common::{aras, fixture, own_run, scratch, short_validate_config, snapshot};

use aras_cli::output::{FileKind, MANIFEST, Manifest, NewFile, OutDir, OutputLock, record_path};

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
            kind: None,
            files: vec![listed.clone()],
            digests: Default::default(),
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
    let cfg = short_validate_config(&dir);
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

/// Writes `bytes` as a single-file output of `kind` through the tool's own
/// path (staged, placed, recorded).
fn own_file(path: &std::path::Path, kind: FileKind, bytes: &[u8], force: bool) {
    let f = NewFile::create(path, force, kind, &[]).unwrap();
    f.write(bytes).unwrap();
    f.commit().unwrap();
}

fn file_err(r: anyhow::Result<NewFile>) -> String {
    format!("{:#}", r.err().expect("refused"))
}

/// The reported case: `predict --force` over the user's own measured
/// torques `t,tau1,tau2` (the same header as a prediction) is refused, as
/// there is no record that aras wrote it; the file survives byte for byte.
/// The tool's own prediction is replaced, but not once the user edited it.
#[test]
fn predict_force_never_replaces_the_users_torque_csv() {
    let dir = scratch("force", "user-torques");
    // A short log of the simulated robot, in a folder of its own.
    let logs = dir.join("logs");
    std::fs::create_dir(&logs).unwrap();
    let cfg = logs.join("short.toml");
    std::fs::write(&cfg, "[simulation]\nperiods = 2\n").unwrap();
    let data = logs.join("run.csv");
    let r = aras(&[
        "simulate",
        "--frequency",
        "2",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        data.to_str().unwrap(),
        "-q",
    ]);
    assert!(r.status.success(), "{}", stderr(&r));
    let mine = dir.join("torques.csv");
    std::fs::write(&mine, "t,tau1,tau2\n0,0.125,-0.5\n0.001,0.126,-0.49\n").unwrap();
    let before = std::fs::read(&mine).unwrap();
    let predict = |out: &std::path::Path| {
        aras(&[
            "predict",
            "--params",
            fixture("robots/aras-diamond.json").to_str().unwrap(),
            "--data",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--force",
        ])
    };
    let r = predict(&mine);
    assert!(!r.status.success());
    let msg = stderr(&r);
    assert!(
        msg.contains("torques.csv") && msg.contains("no record that aras wrote it"),
        "{msg}"
    );
    assert_eq!(std::fs::read(&mine).unwrap(), before);
    // The tool's own output: written, recorded, replaced by a re-run.
    let pred = dir.join("pred.csv");
    let r = predict(&pred);
    assert!(r.status.success(), "{}", stderr(&r));
    let record = Manifest::read_file(&record_path(&pred)).unwrap().unwrap();
    assert_eq!(record.kind.as_deref(), Some("prediction"));
    assert_eq!(record.files, ["pred.csv"]);
    let r = predict(&pred);
    assert!(r.status.success(), "{}", stderr(&r));
    // Edited by the user (or replaced by another file): theirs now.
    let mut edited = std::fs::read(&pred).unwrap();
    edited.extend_from_slice(b"9,9,9\n");
    std::fs::write(&pred, &edited).unwrap();
    let r = predict(&pred);
    assert!(!r.status.success());
    assert!(
        stderr(&r).contains("has changed since aras wrote it"),
        "{}",
        stderr(&r)
    );
    assert_eq!(std::fs::read(&pred).unwrap(), edited);
    // The user's file copied over the tool's output: refused too.
    std::fs::copy(&mine, &pred).unwrap();
    assert!(!predict(&pred).status.success());
    assert_eq!(std::fs::read(&pred).unwrap(), before);
    // Nothing is left beside the outputs but them, their records and inputs.
    let mut left: Vec<String> = std::fs::read_dir(&*dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(
        left,
        [
            ".pred.csv.aras-manifest.json",
            "logs",
            "pred.csv",
            "torques.csv"
        ]
    );
}

/// Single files: never an input; with `--force` only a recorded, unchanged
/// output of the same kind is replaced.
#[test]
fn single_file_force_replaces_only_its_own_kind() {
    let dir = scratch("force", "single");
    let pred = dir.join("p.csv");
    own_file(&pred, FileKind::Prediction, b"t,tau1,tau2\n0,0,0\n", false);
    drop(NewFile::create(&pred, true, FileKind::Prediction, &[]).unwrap());
    assert!(file_err(NewFile::create(&pred, false, FileKind::Prediction, &[])).contains("--force"));
    // Recorded as a prediction: not replaced as a trajectory.
    let msg = file_err(NewFile::create(&pred, true, FileKind::Trajectory, &[]));
    assert!(
        msg.contains("p.csv") && msg.contains("is not a trajectory"),
        "{msg}"
    );
    // An unrecorded file of the right shape.
    let notes = dir.join("notes.csv");
    std::fs::write(&notes, "t,tau1,tau2\n1,2,3\n").unwrap();
    let msg = file_err(NewFile::create(&notes, true, FileKind::Prediction, &[]));
    assert!(
        msg.contains("notes.csv") && msg.contains("no record"),
        "{msg}"
    );
    let msg = file_err(NewFile::create(
        &pred,
        true,
        FileKind::Prediction,
        std::slice::from_ref(&pred),
    ));
    assert!(msg.contains("input"), "{msg}");
    // A simulated log: an unrelated LOG.json next to a new log is not
    // overwritten; the log and its sidecar are recorded together.
    let log = dir.join("log.csv");
    std::fs::write(dir.join("log.json"), "{\"note\": 1}").unwrap();
    let msg = file_err(NewFile::create(&log, true, FileKind::SimulatedLog, &[]));
    assert!(msg.contains("log.json"), "{msg}");
    std::fs::remove_file(dir.join("log.json")).unwrap();
    let f = NewFile::create(&log, false, FileKind::SimulatedLog, &[]).unwrap();
    std::fs::write(f.path(), "t\n").unwrap();
    std::fs::write(aras_log::sidecar_path(&f.path()), "{}\n").unwrap();
    f.commit().unwrap();
    assert_eq!(
        Manifest::read_file(&record_path(&log))
            .unwrap()
            .unwrap()
            .files,
        ["log.csv", "log.json"]
    );
    drop(NewFile::create(&log, true, FileKind::SimulatedLog, &[]).unwrap());
    std::fs::write(dir.join("log.json"), "{\"edited\": 1}").unwrap();
    let msg = file_err(NewFile::create(&log, true, FileKind::SimulatedLog, &[]));
    assert!(msg.contains("log.json") && msg.contains("changed"), "{msg}");
    // The trajectory input as the log's sidecar: refused.
    let traj = dir.join("t.json");
    std::fs::copy(fixture("trajectories/default-excitation.json"), &traj).unwrap();
    let msg = file_err(NewFile::create(
        &dir.join("t.csv"),
        true,
        FileKind::SimulatedLog,
        std::slice::from_ref(&traj),
    ));
    assert!(msg.contains("t.json") && msg.contains("input"), "{msg}");
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

/// A file of a run directory edited after the run is the user's: `--force`
/// refuses to replace the directory, naming it.
#[test]
fn force_refuses_a_run_directory_with_an_edited_file() {
    let dir = scratch("force", "edited");
    let out = dir.join("out");
    own_run(&out, &[("params.json", "{}\n"), ("report.html", "<p/>")]);
    std::fs::write(out.join("params.json"), "{\"hand-tuned\": true}\n").unwrap();
    let before = snapshot(&out);
    let msg = err_of(OutDir::create(&out, true, &[]));
    assert!(
        msg.contains("params.json") && msg.contains("changed"),
        "{msg}"
    );
    assert_eq!(snapshot(&out), before);
}

/// Two runs aimed at one output: while one holds it, the other fails at
/// once with the reason (through the binary too), and neither replaces the
/// other's results. A directory that appears at the target while a run
/// without `--force` works stops its swap; its results are kept, visibly.
#[test]
fn concurrent_runs_on_one_output_never_replace_each_other() {
    let dir = scratch("force", "concurrent");
    let out = dir.join("out");
    let first = OutDir::create(&out, false, &[]).unwrap();
    let msg = err_of(OutDir::create(&out, false, &[]));
    assert!(
        msg.contains("another aras run") && msg.contains("pid"),
        "{msg}"
    );
    let msg = err_of(OutDir::create(&out, true, &[]));
    assert!(msg.contains("another aras run"), "{msg}");
    // The binary, while this process holds the output.
    let r = aras(&[
        "identify",
        "--data",
        fixture("logs/good/counts_currents.csv").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("another aras run"), "{}", stderr(&r));
    first.write("params.json", "{\"first\": 1}\n").unwrap();
    first.commit().unwrap();
    // Released: the next run gets it (and is refused only for existing).
    assert!(err_of(OutDir::create(&out, false, &[])).contains("already exists"));
    // A single file: the same lock.
    let pred = dir.join("p.csv");
    let _held = OutputLock::acquire(&std::fs::canonicalize(&*dir).unwrap().join("p.csv")).unwrap();
    assert!(
        file_err(NewFile::create(&pred, false, FileKind::Prediction, &[]))
            .contains("another aras run")
    );
    drop(_held);
    // Another program fills the target while a run without --force works.
    let late = dir.join("late");
    let run = OutDir::create(&late, false, &[]).unwrap();
    run.write("params.json", "{\"mine\": 1}\n").unwrap();
    std::fs::create_dir(&late).unwrap();
    std::fs::write(late.join("theirs.txt"), "theirs").unwrap();
    let msg = format!("{:#}", run.commit().expect_err("refused"));
    assert!(
        msg.contains("appeared") && msg.contains("late.unsaved-"),
        "{msg}"
    );
    assert_eq!(
        std::fs::read_to_string(late.join("theirs.txt")).unwrap(),
        "theirs"
    );
    let kept: Vec<_> = std::fs::read_dir(&*dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("late.unsaved-"))
        .collect();
    assert_eq!(kept.len(), 1);
    let kept = dir.join(&kept[0]);
    assert_eq!(
        std::fs::read_to_string(kept.join("params.json")).unwrap(),
        "{\"mine\": 1}\n"
    );
    // A single file without --force: never replaced, kept visibly.
    let f = NewFile::create(&dir.join("q.csv"), false, FileKind::Prediction, &[]).unwrap();
    f.write(b"t,tau1,tau2\n").unwrap();
    std::fs::write(dir.join("q.csv"), "theirs").unwrap();
    let msg = format!("{:#}", f.commit().expect_err("refused"));
    assert!(
        msg.contains("appeared") && msg.contains("q.csv.unsaved-"),
        "{msg}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("q.csv")).unwrap(),
        "theirs"
    );
}

/// What interrupted runs leave is cleaned up by the next run on the same
/// output, and never blocks it: a stale staging directory (with a scratch
/// file), a moved-aside previous output (removed when the output exists,
/// put back when the swap had not finished), a temporary file. An old
/// output the run cannot remove (read-only) leaves the run successful,
/// with a warning naming the folder.
#[test]
fn leftovers_of_interrupted_runs_are_cleaned_up_and_never_block() {
    let dir = scratch("force", "leftovers");
    let out = dir.join("out");
    own_run(&out, &[("params.json", "{}\n")]);
    // As a crash mid-swap leaves them: an earlier output moved aside under
    // the name every earlier run used, and a staging directory.
    let previous = dir.join(".out.previous");
    own_run(&previous, &[("params.json", "{\"old\": 1}\n")]);
    let staging = dir.join(".out.staging-999999");
    std::fs::create_dir(&staging).unwrap();
    std::fs::write(staging.join(".aras-samples.999999-0.tmp"), vec![0u8; 4096]).unwrap();
    // Not ours by name: another output's staging, a user's folder.
    let other = dir.join(".out.staging-x.staging-1");
    std::fs::create_dir(&other).unwrap();
    std::fs::create_dir(dir.join(".out.previous-mine")).unwrap();
    let o = OutDir::create(&out, true, &[]).unwrap();
    assert!(!previous.exists() && !staging.exists());
    assert!(other.exists() && dir.join(".out.previous-mine").exists());
    o.write("params.json", "{\"new\": 1}\n").unwrap();
    o.commit().unwrap();
    // A swap that stopped after moving the old output aside: restored.
    std::fs::rename(&out, dir.join(".out.previous-123")).unwrap();
    let o = OutDir::create(&out, true, &[]).unwrap();
    assert_eq!(
        std::fs::read_to_string(out.join("params.json")).unwrap(),
        "{\"new\": 1}\n",
        "the earlier output is back in place"
    );
    drop(o);
    // An old output the run cannot remove: read-only for a normal user; as
    // root (who may remove anything) a listed entry that is a directory,
    // which cannot be removed as a file. The new results go in, the run
    // succeeds, and the warning names the folder left behind.
    let root = running_as_root();
    #[cfg(unix)]
    let perm = |mode| {
        use std::os::unix::fs::PermissionsExt;
        std::fs::Permissions::from_mode(mode)
    };
    if root {
        std::fs::create_dir(out.join("sub")).unwrap();
        std::fs::write(out.join("sub/a.svg"), "<svg/>").unwrap();
        let mut m = Manifest::of_dir(&out).unwrap();
        m.files.push("sub".into());
        m.digests
            .insert("sub".into(), aras_cli::output::Digest::of_bytes(b""));
        std::fs::write(out.join(MANIFEST), serde_json::to_string(&m).unwrap()).unwrap();
    } else {
        #[cfg(unix)]
        std::fs::set_permissions(&out, perm(0o555)).unwrap();
    }
    let r = aras(&[
        "validate",
        "--params",
        fixture("robots/aras-diamond.json").to_str().unwrap(),
        "--config",
        short_validate_config(&dir).to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--force",
        "-q",
    ]);
    let msg = stderr(&r);
    assert!(r.status.success(), "{msg}");
    assert!(
        msg.contains("could not be removed") && msg.contains(".out.previous-"),
        "{msg}"
    );
    assert!(out.join("summary.json").exists());
    let backup: Vec<_> = std::fs::read_dir(&*dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy().into_owned();
            n.starts_with(".out.previous-") && n != ".out.previous-mine"
        })
        .collect();
    assert_eq!(backup.len(), 1, "{backup:?}");
    // The next run is not blocked by it, and says it is still there.
    #[cfg(unix)]
    if !root {
        std::fs::set_permissions(&backup[0], perm(0o755)).unwrap();
    }
    let o = OutDir::create(&out, true, &[]).unwrap();
    assert_eq!(backup[0].exists(), root, "removed once it can be");
    drop(o);
}

/// Whether the tests run as root (who may remove files from read-only
/// directories).
fn running_as_root() -> bool {
    std::process::Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

/// Ctrl-C (SIGINT) during a run removes its staging directory and its lock
/// and exits 130; the previous output is untouched.
#[cfg(unix)]
#[test]
fn an_interrupted_run_leaves_nothing_behind() {
    let dir = scratch("force", "sigint");
    let out = dir.join("out");
    own_run(&out, &[("params.json", "{}\n")]);
    let before = snapshot(&out);
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["pipeline", "--out", out.to_str().unwrap(), "--force", "-q"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the run is staging.
    let t0 = std::time::Instant::now();
    let staging = format!(".out.staging-{}", child.id());
    while !dir.join(&staging).exists() {
        assert!(t0.elapsed().as_secs() < 60, "the run never started staging");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(200));
    let killed = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let r = child.wait_with_output().unwrap();
    assert_eq!(r.status.code(), Some(130), "{}", stderr(&r));
    let left: Vec<String> = std::fs::read_dir(&*dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["out"], "left beside the output");
    assert_eq!(snapshot(&out), before);
}
