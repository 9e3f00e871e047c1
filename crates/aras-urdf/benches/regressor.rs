//! Per-sample cost of the regressor and of RNEA for the 7-joint Panda
//! (`fixtures/urdf/panda.urdf`, fingers fixed).
use aras_urdf::{ModelSettings, UrdfModel};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/urdf/panda_arm.urdf"
    );
    let model = UrdfModel::from_file(path, ModelSettings::default()).expect("the Panda fixture");
    let n = model.dof();
    let q: Vec<f64> = (0..n).map(|i| 0.3 * i as f64 - 0.8).collect();
    let qd: Vec<f64> = (0..n).map(|i| 0.5 - 0.2 * i as f64).collect();
    let qdd: Vec<f64> = (0..n).map(|i| 1.0 + 0.7 * i as f64).collect();
    let mut y = vec![0.0; n * model.parameter_count()];
    let p = model.urdf_parameters();
    c.bench_function("panda regressor (fill)", |b| {
        b.iter(|| {
            aras_ident::LinearModel::fill(&model, black_box(&q), &qd, &qdd, &mut y).unwrap();
            black_box(&y);
        })
    });
    let mut ws = aras_urdf::Workspace::new(&model);
    let mut tau = vec![0.0; n];
    c.bench_function("panda RNEA", |b| {
        b.iter(|| {
            model
                .inverse_dynamics_with(&mut ws, &p, black_box(&q), &qd, &qdd, &mut tau)
                .unwrap();
            black_box(&tau);
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
