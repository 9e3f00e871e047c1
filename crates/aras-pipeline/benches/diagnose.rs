//! Diagnosis of a long plain log: a 160 s TRAIN log of the designed
//! excitation at 1 kHz, not period-averaged (the chunked, bounded-memory
//! route), and one validation log of (79) at 0.7 Hz, default candidate grid
//! (`docs/scale.md`, "Diagnosis of long plain logs"). Reading and
//! processing the logs are outside the measured loop; the TRAIN data set is
//! held in memory or, as `aras diagnose --streaming` holds it, in a scratch
//! file read window by window.

use std::path::{Path, PathBuf};

use aras_dyn::sim::{SimConfig, simulate, write_log};
use aras_dyn::{Model, Params, Sinusoid, Trajectory};
use aras_excite::FourierTrajectory;
use aras_log::{ReadOptions, read_log};
use aras_pipeline::diagnose::{Dataset, DiagnoseOptions, diagnose};
use aras_pipeline::streaming::{StreamingOptions, spool_log};
use aras_signal::{Bandwidth, FilterSpec, PeriodSource, ProcessOptions, process};
use criterion::{Criterion, criterion_group, criterion_main};

/// The paper's processing (the fixed 10 Hz low-pass), which the library's
/// engine diagnoses away from reversals.
fn popts() -> ProcessOptions {
    ProcessOptions {
        period: PeriodSource::Off,
        filter: Bandwidth::Fixed(FilterSpec::default()),
        ..ProcessOptions::default()
    }
}

/// A simulated plain log (CSV without sidecar) of `traj` over `secs` in
/// `dir`.
fn plain_log(truth: &Params, traj: &dyn Trajectory, secs: f64, dir: &Path, name: &str) -> PathBuf {
    let cfg = SimConfig {
        duration_s: secs,
        ..SimConfig::default()
    };
    let log = simulate(truth, traj, &cfg).unwrap();
    let path = dir.join(format!("{name}.csv"));
    write_log(&path, &log, false).unwrap();
    let _ = std::fs::remove_file(path.with_extension("json"));
    path
}

/// The log at `path` read back and processed in memory, without period
/// averaging.
fn in_memory(path: &Path, truth: &Params, name: &str) -> Dataset {
    let raw = read_log(path, &ReadOptions::default()).unwrap();
    let p = process(
        &raw,
        &popts(),
        &aras_kin::task_motion(&truth.geometry().unwrap()),
    )
    .unwrap();
    Dataset::from_processed_owned(name, p).unwrap()
}

fn bench(c: &mut Criterion) {
    let truth = Params::aras_diamond();
    let excitation = FourierTrajectory::load(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/trajectories/default-excitation.json"),
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("aras-bench-diagnose-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let train_log = plain_log(&truth, &excitation, 160.0, &dir, "train160");
    let val_log = plain_log(
        &truth,
        &Sinusoid::paper_79(0.7).unwrap(),
        10.0 / 0.7,
        &dir,
        "val",
    );
    let train = in_memory(&train_log, &truth, "train160");
    let val = in_memory(&val_log, &truth, "val");
    // The same log processed in overlapping blocks into a scratch file.
    let streamed = spool_log(
        &train_log,
        &StreamingOptions {
            process: popts(),
            ..StreamingOptions::default()
        },
        &dir,
        &mut |_| {},
    )
    .unwrap();
    assert!(
        !train.periodic,
        "the bench is of the chunked, non-periodic route"
    );
    let model = Model::paper(truth.gravity).unwrap();
    let geometry = truth.geometry().unwrap();
    let opts = DiagnoseOptions::default();
    let mut g = c.benchmark_group("diagnose");
    g.sample_size(10);
    g.bench_function("plain_160s_1khz_one_validation", |b| {
        b.iter(|| diagnose(&model, &geometry, &train, std::slice::from_ref(&val), &opts).unwrap())
    });
    g.bench_function("plain_160s_1khz_one_validation_streamed", |b| {
        b.iter(|| {
            diagnose(
                &model,
                &geometry,
                &streamed,
                std::slice::from_ref(&val),
                &opts,
            )
            .unwrap()
        })
    });
    g.finish();
    drop(streamed);
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
