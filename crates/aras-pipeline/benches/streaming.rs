//! Throughput of the streaming regressor + accumulation stage (
//! target ≥ 5 M samples/s on this machine), and its parts.
#![allow(clippy::needless_range_loop)]

use aras_dyn::Params;
use aras_ident::BaseParameters;
use aras_ident::streaming::{Accumulation, RegressorStage, States};
use aras_kin::Motion;
use aras_pipeline::TaskRegressor;
use aras_pipeline::robot::stack;
use aras_pipeline::streaming::{StreamingOptions, identify_log, synthetic};
use aras_signal::{Bandwidth, FilterSpec, PeriodSource};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nalgebra::Vector2;
use std::hint::black_box;

/// The numerical base of `model` from 2000 synthetic states.
fn base_of(model: &aras_dyn::Model, geo: &aras_kin::Geometry, beta: &[f64]) -> BaseParameters {
    let rich = synthetic::states(model, geo, beta, 2000, 200.0, 0.0).unwrap();
    let samples = aras_signal::Samples {
        t: (0..2000).map(|i| i as f64 / 200.0).collect(),
        x: rich[0].to_vec(),
        x_dot: rich[1].to_vec(),
        x_ddot: rich[2].to_vec(),
        tau: rich[3].to_vec(),
        ..Default::default()
    };
    let st = stack(model, geo, &samples).unwrap();
    BaseParameters::from_regressor(st.w.as_ref(), &st.names, 1e-8).unwrap()
}

fn bench(c: &mut Criterion) {
    let p = Params::aras_diamond();
    let model = p.model().unwrap();
    let geo = p.geometry().unwrap();
    let beta = p.standard_vector(&model).unwrap().as_slice().to_vec();
    let base = base_of(&model, &geo, &beta);

    let n = 262_144;
    let s = synthetic::states(&model, &geo, &beta, n, 1000.0, 0.01).unwrap();
    let states = States {
        x: &[&s[0][0], &s[0][1]],
        x_dot: &[&s[1][0], &s[1][1]],
        x_ddot: &[&s[2][0], &s[2][1]],
        tau: &[&s[3][0], &s[3][1]],
    };
    let mut g = c.benchmark_group("streaming");
    g.throughput(Throughput::Elements(n as u64));
    g.sample_size(10);
    for (name, how) in [
        (
            "regressor_and_accumulation_gram_262144_samples",
            Accumulation::Gram,
        ),
        (
            "regressor_and_accumulation_qr_262144_samples",
            Accumulation::Qr,
        ),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut stage = RegressorStage::with_accumulation(
                    TaskRegressor::new(model.clone(), geo),
                    &base,
                    how,
                )
                .unwrap();
                stage.push(&states).unwrap();
                black_box(stage.accumulator().rows())
            })
        });
    }
    // CPU time per sample: the Gram stage on one thread (the machine is
    // shared, so the 2-thread time depends on the load).
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    g.bench_function(
        "regressor_and_accumulation_gram_1_thread_262144_samples",
        |b| {
            b.iter(|| {
                one.install(|| {
                    let mut stage =
                        RegressorStage::new(TaskRegressor::new(model.clone(), geo), &base).unwrap();
                    stage.push(&states).unwrap();
                    black_box(stage.accumulator().rows())
                })
            })
        },
    );
    // The parts, single-threaded, per sample.
    let mut y = vec![0.0; 2 * model.columns()];
    g.bench_function("evaluate_only_262144_samples", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for i in 0..n {
                let k = aras_kin::evaluate(
                    &geo,
                    &Motion::new(
                        Vector2::new(s[0][0][i], s[0][1][i]),
                        Vector2::new(s[1][0][i], s[1][1][i]),
                        Vector2::new(s[2][0][i], s[2][1][i]),
                    ),
                )
                .unwrap();
                acc += k.joint.pos[0];
            }
            black_box(acc)
        })
    });
    g.bench_function("evaluate_and_fill_262144_samples", |b| {
        b.iter(|| {
            for i in 0..n {
                let k = aras_kin::evaluate(
                    &geo,
                    &Motion::new(
                        Vector2::new(s[0][0][i], s[0][1][i]),
                        Vector2::new(s[1][0][i], s[1][1][i]),
                        Vector2::new(s[2][0][i], s[2][1][i]),
                    ),
                )
                .unwrap();
                model.fill(&k, &mut y).unwrap();
            }
            black_box(y[0])
        })
    });
    g.finish();
}

/// The two routes of a plain log without a period, end to end (CSV
/// parsing included) on a synthetic 2-minute log at 1 kHz written once:
/// logged derivatives (parse, kinematics, regressor, accumulation) and the
/// overlapping filtered blocks (θ differentiated, 10 Hz zero-phase filter on
/// the torques and the base columns, reversal exclusion). `docs/scale.md`
/// quotes their ratio.
fn bench_log_routes(c: &mut Criterion) {
    let p = Params::aras_diamond();
    let model = p.model().unwrap();
    let geo = p.geometry().unwrap();
    let beta = p.standard_vector(&model).unwrap().as_slice().to_vec();
    let n = 120_000;
    let dir = std::env::temp_dir().join(format!("aras-bench-routes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("log.csv");
    synthetic::write_log(&path, &model, &geo, &beta, n, 1000.0, 0.002).unwrap();
    let base = base_of(&model, &geo, &beta);
    let mut g = c.benchmark_group("log_routes");
    g.throughput(Throughput::Elements(n as u64));
    g.sample_size(10);
    for filtered in [false, true] {
        let mut o = StreamingOptions::default();
        o.process.period = PeriodSource::Off;
        if filtered {
            o.process.filter = Bandwidth::Fixed(FilterSpec::default());
        } else {
            o.process.filter = Bandwidth::Off;
            o.process.use_logged_derivatives = true;
        }
        let name = if filtered {
            "overlapping_filtered_blocks_120000_samples"
        } else {
            "logged_derivatives_120000_samples"
        };
        g.bench_function(name, |b| {
            b.iter(|| black_box(identify_log(&path, &model, &base, &o).unwrap().samples_used))
        });
    }
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench, bench_log_routes);
criterion_main!(benches);
