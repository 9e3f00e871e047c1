//! Benchmarks: trajectory evaluation per sample, one criterion assessment,
//! and the whole default design (target ≤ 30 s) on the paper's 42-column
//! model; the base projection comes from the test-only QR helper.

#[path = "../src/test_support.rs"]
mod test_support;

use std::hint::black_box;

use aras_dyn::TaskRegressor;
use aras_excite::{DesignSettings, assess, design, random_feasible};
use criterion::{Criterion, criterion_group, criterion_main};

fn benches(c: &mut Criterion) {
    let reg = TaskRegressor::aras_diamond().unwrap();
    let e = test_support::base_projection(&reg, 400, 7);
    let settings = DesignSettings {
        ..DesignSettings::default()
    };
    let traj = random_feasible(&settings, 1, 5).unwrap().remove(0);

    c.bench_function("fourier eval (L=5), per sample", |b| {
        let mut t = 0.0;
        b.iter(|| {
            t += 0.001;
            black_box(traj.eval(black_box(t)))
        })
    });
    c.bench_function(
        "assess paper model (42 columns, 23 base), 100 samples",
        |b| b.iter(|| assess(&reg, &e, black_box(&traj), 100).unwrap()),
    );
    let mut g = c.benchmark_group("design");
    g.sample_size(10);
    g.bench_function("default design, paper model", |b| {
        b.iter(|| design(&reg, &e, black_box(&settings)).unwrap())
    });
    g.finish();
}

criterion_group!(group, benches);
criterion_main!(group);
