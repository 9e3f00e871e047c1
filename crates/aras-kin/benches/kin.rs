//! Speed of the per-sample kinematics (target: full evaluation < 150 ns).

use aras_kin::{AssemblyMode, Geometry, evaluate, forward, forward_motion, inverse};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector2;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let g = Geometry::aras_diamond();
    let x = Vector2::new(85f64.to_radians(), 60f64.to_radians());
    let th = inverse(&g, &x).unwrap().theta;
    let (xd, xdd) = (Vector2::new(0.3, -0.7), Vector2::new(1.1, 0.4));
    c.bench_function("inverse", |b| b.iter(|| inverse(&g, black_box(&x))));
    c.bench_function("forward", |b| {
        b.iter(|| forward(&g, black_box(&th), AssemblyMode::Plus))
    });
    // What the processing maps every sample of a log with: X, Ẋ, Ẍ from
    // the joint motion, without the link frames.
    let joint = aras_kin::Motion::new(th, Vector2::new(0.9, -0.2), Vector2::new(-1.3, 2.1));
    c.bench_function("forward_motion", |b| {
        b.iter(|| forward_motion(&g, black_box(&joint), AssemblyMode::Plus))
    });
    c.bench_function("evaluate (full per-sample)", |b| {
        b.iter(|| {
            evaluate(
                &g,
                &aras_kin::Motion::new(*black_box(&x), *black_box(&xd), *black_box(&xdd)),
            )
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
