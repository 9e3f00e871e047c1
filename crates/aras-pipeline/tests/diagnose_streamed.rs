//! The diagnosis of a long log in bounded memory: TRAIN processed block by
//! block into a scratch file (`streaming::spool_log`) gives the diagnosis
//! of the log processed in memory, and the scratch file is the tool's own.
//!
//! TRAIN: a plain (not period-averaged) 60 s simulated log of the designed
//! excitation with hidden Stribeck friction (v_s = 0.2 rad/s, so that
//! `stribeck_friction` is added and its `v_s` refined) and a torque
//! offset, filtered at a fixed 10 Hz (an automatic cut-off would take the
//! first block's spectrum when streamed, the whole log's in memory).
//! Blocks of at least 4 096 samples: five blocks and twenty diagnosis chunks.

use std::path::{Path, PathBuf};

use aras_dyn::sim::{SimConfig, simulate, write_log};
use aras_dyn::{Params, Sinusoid, Stribeck};
use aras_excite::FourierTrajectory;
use aras_log::{ReadOptions, read_log};
use aras_pipeline::diagnose::{Dataset, DiagnoseOptions, diagnose};
use aras_pipeline::streaming::{StreamingOptions, spool_log};
use aras_signal::{Bandwidth, FilterSpec, PeriodSource, ProcessOptions, Samples, process};

fn popts() -> ProcessOptions {
    ProcessOptions {
        filter: Bandwidth::Fixed(FilterSpec::default()),
        period: PeriodSource::Off,
        ..ProcessOptions::default()
    }
}

fn truth() -> Params {
    let mut p = Params::aras_diamond();
    p.extra.torque_offset = Some([0.02, -0.03]);
    p.extra.stribeck_friction = Some(Stribeck {
        v_s: 0.2,
        level: [0.06, 0.12],
    });
    p
}

/// A simulated log of `secs` written as CSV in `dir`.
fn log(dir: &Path, name: &str, traj: &dyn aras_dyn::Trajectory, secs: f64) -> PathBuf {
    let cfg = SimConfig {
        duration_s: secs,
        seed: 7,
        ..SimConfig::default()
    };
    let sim = simulate(&truth(), traj, &cfg).unwrap();
    let path = dir.join(name);
    write_log(&path, &sim, false).unwrap();
    path
}

fn in_memory(path: &Path) -> Dataset {
    let raw = read_log(path, &ReadOptions::default()).unwrap();
    let geometry = Params::aras_diamond().geometry().unwrap();
    let p = process(&raw, &popts(), &aras_kin::task_motion(&geometry)).unwrap();
    Dataset::from_processed_owned(path.file_name().unwrap().to_string_lossy(), p).unwrap()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * (1e-3 + a.abs().max(b.abs()))
}

#[test]
fn streamed_train_gives_the_in_memory_diagnosis_and_removes_its_scratch_file() {
    let dir = aras_testkit::Scratch::new("diagnose-streamed");
    let traj = FourierTrajectory::load(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/trajectories/default-excitation.json"),
    )
    .unwrap();
    let train_path = log(dir.path(), "train.csv", &traj, 60.0);
    let val_path = log(
        dir.path(),
        "val.csv",
        &Sinusoid::paper_79(0.7).unwrap(),
        10.0 / 0.7,
    );
    let spool_dir = dir.join("scratch");
    std::fs::create_dir(&spool_dir).unwrap();
    let opts = StreamingOptions {
        process: popts(),
        chunk_samples: 4096,
        ..StreamingOptions::default()
    };
    let mut rows_seen = 0;
    let streamed = spool_log(&train_path, &opts, &spool_dir, &mut |r| rows_seen = r).unwrap();
    let memory = in_memory(&train_path);
    assert!(streamed.is_spooled() && !memory.is_spooled());
    assert!(streamed.samples().is_none());
    let rows = read_log(&train_path, &ReadOptions::default())
        .unwrap()
        .len();
    assert_eq!(rows_seen, rows as u64, "progress reaches every row");
    assert_eq!(streamed.len(), memory.len());
    // The same filter: the rates are the reader's nominal step (the first
    // 4 096 steps' median) and the whole log's, equal to rounding.
    assert!(close(streamed.sample_rate_hz, memory.sample_rate_hz, 1e-12));
    let (fs, fm) = (
        streamed.filter.as_ref().unwrap(),
        memory.filter.as_ref().unwrap(),
    );
    for (x, y) in fs.sections().iter().zip(fm.sections()) {
        for (p, q) in x.iter().zip(y) {
            assert!((p - q).abs() <= 1e-12 * q.abs().max(1.0), "{p} vs {q}");
        }
    }
    let files: Vec<_> = std::fs::read_dir(&spool_dir).unwrap().collect();
    assert_eq!(files.len(), 1, "one scratch file while the data set lives");

    // The processed samples agree to the blocks' overlap tolerance (1e-12
    // of each filter's transient) everywhere, block edges included, and to
    // the rounding of the two filters' coefficients (their rates come from
    // the reader's step estimate and from the whole log's). A derivative
    // stencil of step dt amplifies the angles' rounding by 1/dt per order,
    // so a rate or acceleration is compared on the scale max|θ| / dt^d.
    let (mut a, mut b) = (Samples::default(), Samples::default());
    streamed.read(0..streamed.len(), &mut a).unwrap();
    memory.read(0..memory.len(), &mut b).unwrap();
    let max = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let dt = 1.0 / memory.sample_rate_hz;
    for j in 0..2 {
        let th = max(&b.theta[j]);
        for (what, x, y, scale) in [
            ("θ", &a.theta[j], &b.theta[j], th),
            ("θ̇", &a.theta_dot[j], &b.theta_dot[j], th / dt),
            ("θ̈", &a.theta_ddot[j], &b.theta_ddot[j], th / (dt * dt)),
            ("Ẍ", &a.x_ddot[j], &b.x_ddot[j], max(&b.x[j]) / (dt * dt)),
            ("τ", &a.tau[j], &b.tau[j], max(&b.tau[j])),
        ] {
            let e = x
                .iter()
                .zip(y.iter())
                .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()))
                / scale;
            assert!(e < 1e-11, "{what}{}: difference {e:e} of its scale", j + 1);
        }
    }
    assert_eq!(a.t, b.t);

    // The diagnosis: same effects, values and validation figures.
    let val = vec![in_memory(&val_path)];
    let geometry = Params::aras_diamond().geometry().unwrap();
    let model = aras_dyn::Model::paper(Params::aras_diamond().gravity).unwrap();
    let o = DiagnoseOptions::default();
    let ds = diagnose(&model, &geometry, &streamed, &val, &o).unwrap();
    let dm = diagnose(&model, &geometry, &memory, &val, &o).unwrap();
    let ids = |d: &aras_pipeline::diagnose::Diagnosis| -> Vec<String> {
        d.steps.iter().map(|s| s.id.clone()).collect()
    };
    assert_eq!(ids(&ds), ids(&dm));
    assert!(
        ids(&dm).iter().any(|i| i == "stribeck_friction"),
        "the case exercises a refinement: {:?}",
        ids(&dm)
    );
    assert_eq!(ds.rows_fitted, dm.rows_fitted);
    for (x, y) in ds.estimate.iter().zip(&dm.estimate) {
        assert_eq!(x.name, y.name);
        assert!(
            close(x.value, y.value, 1e-6),
            "{}: {} vs {}",
            x.name,
            x.value,
            y.value
        );
        assert!(close(x.std_dev, y.std_dev, 1e-6), "σ of {}", x.name);
    }
    for (x, y) in ds.fitness.iter().zip(&dm.fitness) {
        for (p, q) in x.fitness_filtered.iter().zip(&y.fitness_filtered) {
            assert!((p[0] - q[0]).abs() < 1e-6 && (p[1] - q[1]).abs() < 1e-6);
        }
    }
    for (x, y) in ds.steps.iter().zip(&dm.steps) {
        match (&x.refinement, &y.refinement) {
            (Some(p), Some(q)) => {
                assert!(close(p.value, q.value, 1e-6), "{} vs {}", p.value, q.value);
                for (m, n) in p.parameters.iter().zip(&q.parameters) {
                    assert!(close(m.value, n.value, 1e-6), "{}", m.name);
                }
            }
            (None, None) => {}
            _ => panic!("refined on one route only"),
        }
    }
    let (cs, cm) = (ds.consistent.as_ref(), dm.consistent.as_ref());
    assert_eq!(cs.is_some(), cm.is_some());

    // Clones share the file; the last one removes it.
    let clone = streamed.clone();
    drop(streamed);
    assert_eq!(std::fs::read_dir(&spool_dir).unwrap().count(), 1);
    drop(clone);
    assert_eq!(
        std::fs::read_dir(&spool_dir).unwrap().count(),
        0,
        "the scratch file goes with the data set"
    );
}

/// The scratch file never takes an existing file's name: files named as
/// the tool names its scratch files stay as they were, and a failed
/// spooling (a log with a bad row) leaves nothing behind.
#[test]
fn scratch_files_never_replace_a_file_and_go_on_error() {
    use aras_pipeline::spool::SpoolWriter;
    let dir = aras_testkit::Scratch::new("spool-names");
    let pid = std::process::id();
    for k in 0..64 {
        std::fs::write(
            dir.join(format!(".aras-samples.{pid}-{k}.tmp")),
            format!("user {k}"),
        )
        .unwrap();
    }
    let mut w = SpoolWriter::create_in(dir.path()).unwrap();
    // Ten samples, every channel its own values.
    let ch = |k: usize| -> Vec<f64> { (0..10).map(|i| (100 * k + i) as f64 + 0.25).collect() };
    let s = Samples {
        t: ch(0),
        theta: vec![ch(1), ch(2)],
        theta_dot: vec![ch(3), ch(4)],
        theta_ddot: vec![ch(5), ch(6)],
        x: vec![ch(7), ch(8)],
        x_dot: vec![ch(9), ch(10)],
        x_ddot: vec![ch(11), ch(12)],
        tau: vec![ch(13), ch(14)],
    };
    w.append(&s, 2..7).unwrap();
    let spooled = w.finish().unwrap();
    assert_eq!(spooled.len(), 5);
    let mut back = Samples::default();
    spooled.read(1..4, &mut back).unwrap();
    // Rows 1..4 of the spool are samples 3..6, every channel in place.
    let mut want = Samples::with_joints(2);
    let pick = |v: &Vec<f64>| v[3..6].to_vec();
    want.t = pick(&s.t);
    for j in 0..2 {
        want.theta[j] = pick(&s.theta[j]);
        want.theta_dot[j] = pick(&s.theta_dot[j]);
        want.theta_ddot[j] = pick(&s.theta_ddot[j]);
        want.x[j] = pick(&s.x[j]);
        want.x_dot[j] = pick(&s.x_dot[j]);
        want.x_ddot[j] = pick(&s.x_ddot[j]);
        want.tau[j] = pick(&s.tau[j]);
    }
    assert_eq!(back, want);
    assert!(spooled.read(3..6, &mut back).is_err(), "past the end");
    drop(spooled);
    for k in 0..64 {
        let text =
            std::fs::read_to_string(dir.join(format!(".aras-samples.{pid}-{k}.tmp"))).unwrap();
        assert_eq!(text, format!("user {k}"));
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 64);

    // A log with a non-numeric torque in row 5000: the error names it and
    // no scratch file stays.
    let bad = dir.join("bad.csv");
    let mut text = String::from("t,theta1,theta2,tau1,tau2\n");
    for i in 0..9000 {
        let t = i as f64 * 1e-3;
        let tau = if i == 5000 {
            "x".to_owned()
        } else {
            format!("{}", 0.1 * t.sin())
        };
        text += &format!("{t},{},{},{tau},0.0\n", 0.3 * t.sin(), 0.8 + 0.2 * t.cos());
    }
    std::fs::write(&bad, text).unwrap();
    let opts = StreamingOptions {
        process: popts(),
        chunk_samples: 4096,
        ..StreamingOptions::default()
    };
    let e = spool_log(&bad, &opts, dir.path(), &mut |_| {}).unwrap_err();
    let msg = aras_testkit::error_chain(&e);
    assert!(
        msg.contains("bad.csv:5002:4") && msg.contains("\"x\" is not a number"),
        "{msg}"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 65);
}
