//! Performance targets:
//! * filtering 4 channels × 160 000 samples ≤ 10 ms;
//! * full `process` of a 160 s, 1 kHz log ≤ 50 ms;
//! * reading an hour at 1 kHz (3.6 M rows) well under a second;
//! * the streaming statistics of a residual (the diagnosis's bounded
//!   summary): a small fraction of the regressor's ≈ 250 ns per sample.

use std::f64::consts::TAU;
use std::hint::black_box;

use aras_kin::{Geometry, inverse};
use aras_log::{ReadOptions, read_log_from};
use aras_signal::{
    Autocorrelation, Bandwidth, Butterworth, FilterSpec, OutputRows, PeriodSource, ProcessOptions,
    SpectrumAccumulator, process,
};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector2;

/// A log of `seconds` at 1 kHz following a 10 s periodic trajectory, with
/// full-precision (shortest round-trip) numbers as a simulator writes them.
fn log_csv(seconds: usize) -> Vec<u8> {
    let g = Geometry::aras_diamond();
    let mut s = String::from("t,theta1,theta2,tau1,tau2\n");
    let n = seconds * 1000;
    s.reserve(n * 90);
    for i in 0..n {
        let t = i as f64 * 1e-3;
        let w = TAU / 10.0 * t;
        let x = Vector2::new(
            1.4 + 0.3 * w.sin() + 0.1 * (3.0 * w).cos(),
            1.0 + 0.15 * (2.0 * w).sin(),
        );
        let th = inverse(&g, &x).expect("inside the workspace").theta;
        let noise = ((i * 7919) % 1000) as f64 * 1e-6;
        s += &format!(
            "{t},{},{},{},{}\n",
            th[0],
            th[1],
            0.2 * w.cos() + noise,
            -0.1 * w.sin() - noise
        );
    }
    s.into_bytes()
}

fn filtering(c: &mut Criterion) {
    let sos = Butterworth::lowpass(4, 10.0, 1000.0).unwrap();
    let cols: Vec<Vec<f64>> = (0..4)
        .map(|k| {
            (0..160_000)
                .map(|i| ((i * (k + 3)) as f64 * 1e-3).sin())
                .collect()
        })
        .collect();
    let mut work = cols.clone();
    let mut scratch = Vec::new();
    c.bench_function("filtfilt 4 x 160k (order 4)", |b| {
        b.iter(|| {
            for (w, c) in work.iter_mut().zip(&cols) {
                w.copy_from_slice(c);
                sos.filtfilt_in_place(w, &mut scratch).unwrap();
            }
            black_box(&work);
        })
    });
    c.bench_function("filtfilt_periodic 4 x 10k (order 4)", |b| {
        b.iter(|| {
            for c in &cols {
                black_box(sos.filtfilt_periodic(&c[..10_000]).unwrap());
            }
        })
    });
}

fn processing(c: &mut Criterion) {
    let csv = log_csv(160);
    let log = read_log_from(&csv[..], "bench.csv", &ReadOptions::default()).unwrap();
    let g = Geometry::aras_diamond();
    // The fixed 10 Hz low-pass (the paper's processing); the data-chosen
    // bandwidth, the default, is benched below under its own names.
    let fixed = ProcessOptions {
        filter: Bandwidth::Fixed(FilterSpec::default()),
        ..ProcessOptions::default()
    };
    let periodic = ProcessOptions {
        period: PeriodSource::Seconds(10.0),
        ..fixed.clone()
    };
    c.bench_function("process 160 s @ 1 kHz, 16 periods averaged", |b| {
        b.iter(|| black_box(process(&log, &periodic, &aras_kin::task_motion(&g)).unwrap()))
    });
    let plain = ProcessOptions {
        period: PeriodSource::Off,
        ..fixed.clone()
    };
    c.bench_function("process 160 s @ 1 kHz, no averaging", |b| {
        b.iter(|| black_box(process(&log, &plain, &aras_kin::task_motion(&g)).unwrap()))
    });
    // No sidecar: the period is detected from the angles.
    let detected = fixed.clone();
    c.bench_function("process 160 s @ 1 kHz, period detected", |b| {
        b.iter(|| black_box(process(&log, &detected, &aras_kin::task_motion(&g)).unwrap()))
    });
    // The data-chosen bandwidth: the harmonic series of the averaged
    // period, and the spectrum-chosen Butterworth without a period.
    let auto_periodic = ProcessOptions {
        filter: Bandwidth::Auto,
        ..periodic.clone()
    };
    c.bench_function(
        "process 160 s @ 1 kHz, 16 periods averaged, bandwidth auto",
        |b| {
            b.iter(|| black_box(process(&log, &auto_periodic, &aras_kin::task_motion(&g)).unwrap()))
        },
    );
    let auto_plain = ProcessOptions {
        filter: Bandwidth::Auto,
        ..plain.clone()
    };
    c.bench_function("process 160 s @ 1 kHz, no averaging, bandwidth auto", |b| {
        b.iter(|| black_box(process(&log, &auto_plain, &aras_kin::task_motion(&g)).unwrap()))
    });
    // Prediction: θ, θ̇, θ̈ on every row (series + aperiodic remainder).
    let every = ProcessOptions {
        period: PeriodSource::Seconds(10.0),
        rows: OutputRows::EveryRow,
        ..fixed.clone()
    };
    c.bench_function("process 160 s @ 1 kHz, every row (prediction)", |b| {
        b.iter(|| black_box(process(&log, &every, &aras_kin::task_motion(&g)).unwrap()))
    });
}

fn reading(c: &mut Criterion) {
    let csv = log_csv(3600);
    let mut group = c.benchmark_group("read");
    group.sample_size(10);
    group.bench_function("read_log 3.6 M rows (1 h @ 1 kHz)", |b| {
        b.iter(|| black_box(read_log_from(&csv[..], "hour.csv", &ReadOptions::default()).unwrap()))
    });
    group.finish();
}

/// The residual statistics that grow with a record only in time: per
/// sample, the lag sums up to 2000 lags and a Welch spectrum.
fn streaming_statistics(c: &mut Criterion) {
    let x: Vec<f64> = (0..1_000_000)
        .map(|i| (i as f64 * 1e-3).sin() + ((i * 7919) % 1000) as f64 * 1e-6)
        .collect();
    let mut group = c.benchmark_group("streaming statistics");
    group.sample_size(10);
    group.bench_function("autocorrelation 1 M samples, 2000 lags", |b| {
        b.iter(|| {
            let mut acc = Autocorrelation::new(2000);
            for &v in &x {
                acc.push(v);
            }
            black_box(acc.finish())
        })
    });
    group.bench_function("Welch spectrum 1 M samples (2^16-sample segments)", |b| {
        b.iter(|| {
            let mut acc = SpectrumAccumulator::new(x.len(), 1000.0, false).unwrap();
            for &v in &x {
                acc.push(v).unwrap();
            }
            black_box(acc.finish().unwrap())
        })
    });
    group.finish();
}

criterion_group!(
    benches,
    filtering,
    processing,
    reading,
    streaming_statistics
);
criterion_main!(benches);
