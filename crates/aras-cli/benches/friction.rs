//! `aras friction` analysis time: a 120 s joint log of about 30 000 rows
//! (irregular 1–7 ms steps) with two validation logs of the same size, the
//! five models (LuGre and Maxwell-slip included), the diagnosis and its
//! refinement.
//! Target: ≤ 3 s on 2 cores (docs/friction.md).

use aras_friction::sim::{JointSimulation, Ripple};
use aras_friction::{FrictionSettings, analyse};
use criterion::{Criterion, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let mut sim = JointSimulation {
        duration: 120.0,
        min_step: 1e-3,
        max_step: 7e-3,
        ..JointSimulation::default()
    };
    sim.friction.ripple.push(Ripple {
        cycles: 12.0,
        amplitude: 0.04,
        phase: 0.3,
    });
    let run = |speed: f64, seed: u64, name: &str| {
        JointSimulation {
            speed,
            seed,
            ..sim.clone()
        }
        .run(name)
        .log
    };
    let train = run(1.0, 1, "train");
    let vals = vec![run(0.6, 2, "slow"), run(1.5, 3, "fast")];
    eprintln!(
        "rows: {} / {} / {}",
        train.len(),
        vals[0].len(),
        vals[1].len()
    );
    let settings = FrictionSettings::default();
    let mut g = c.benchmark_group("friction");
    g.sample_size(10);
    g.bench_function("analyse_120s_30k_rows_two_validation", |b| {
        b.iter(|| analyse(&train, &vals, &settings).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
