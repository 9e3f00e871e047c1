//! Speed targets: regressor per sample ≤ 300 ns, direct inverse
//! dynamics per sample ≤ 200 ns, stacked regressor for 160 000 samples
//! ≤ 50 ms, simulating 160 s at 1 kHz output ≤ 1 s.

use std::hint::black_box;

use aras_dyn::sim::{SimConfig, simulate};
use aras_dyn::{Dynamics, Params, Sinusoid, Trajectory};
use aras_kin::{Motion, evaluate};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector2;

fn states(n: usize) -> Vec<Motion> {
    let traj = Sinusoid::paper_79(0.5).unwrap();
    (0..n).map(|i| traj.eval(i as f64 * 1e-3)).collect()
}

fn per_sample(c: &mut Criterion) {
    let p = Params::aras_diamond();
    let model = p.model().unwrap();
    let dy = Dynamics::new(&p).unwrap();
    let g = p.geometry().unwrap();
    let s = evaluate(
        &g,
        &Motion::new(
            Vector2::new(1.4, 1.0),
            Vector2::new(0.5, -0.3),
            Vector2::new(4.0, 2.0),
        ),
    )
    .unwrap();
    let mut buf = vec![0.0; 2 * model.columns()];
    c.bench_function("regressor per sample (from KinematicSample)", |b| {
        b.iter(|| model.fill(black_box(&s), &mut buf).unwrap())
    });
    let (x, v, a) = (
        Vector2::new(1.4, 1.0),
        Vector2::new(0.5, -0.3),
        Vector2::new(4.0, 2.0),
    );
    c.bench_function("regressor per sample incl. kinematics", |b| {
        b.iter(|| {
            let s = evaluate(&g, &Motion::new(*black_box(&x), v, a)).unwrap();
            model.fill(&s, &mut buf).unwrap()
        })
    });
    c.bench_function("direct inverse dynamics (33) per sample", |b| {
        b.iter(|| dy.inverse(black_box(&s)))
    });
    c.bench_function("forward dynamics per call incl. kinematics", |b| {
        b.iter(|| {
            dy.forward(black_box(&x), &v, &Vector2::new(0.1, 0.2))
                .unwrap()
        })
    });
}

fn stacked(c: &mut Criterion) {
    let p = Params::aras_diamond();
    let model = p.model().unwrap();
    let g = p.geometry().unwrap();
    let task = states(160_000);
    let samples: Vec<_> = task.iter().map(|t| evaluate(&g, t).unwrap()).collect();
    let mut grp = c.benchmark_group("stacked 160k");
    grp.sample_size(10);
    let mut w = nalgebra::DMatrix::zeros(2 * task.len(), model.columns());
    grp.bench_function("from samples, into buffer", |b| {
        b.iter(|| model.stacked_into(black_box(&samples), &mut w).unwrap())
    });
    grp.bench_function("from states (kinematics included), into buffer", |b| {
        b.iter(|| {
            model
                .stacked_from_states_into(&g, black_box(&task), &mut w)
                .unwrap()
        })
    });
    grp.bench_function("from samples, fresh allocation", |b| {
        b.iter(|| model.stacked(black_box(&samples)).unwrap())
    });
    grp.finish();
}

fn simulation(c: &mut Criterion) {
    let p = Params::aras_diamond();
    let traj = Sinusoid::paper_79(0.5).unwrap();
    let cfg = SimConfig::default();
    assert_eq!(cfg.duration_s, 160.0);
    let mut grp = c.benchmark_group("simulate");
    grp.sample_size(10);
    grp.bench_function("160 s at 1 kHz output (2 kHz RK4)", |b| {
        b.iter(|| simulate(black_box(&p), &traj, &cfg).unwrap())
    });
    grp.finish();
}

criterion_group!(benches, per_sample, stacked, simulation);
criterion_main!(benches);
