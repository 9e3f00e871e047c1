//! End-to-end cost of the URDF recipes on the 7-joint Panda: identifying a
//! 60 s, 1 kHz simulated log (processing, base parameters, least squares
//! and the physically consistent SDP), and designing its excitation.
use aras_excite::FourierTrajectory;
use aras_urdf::excite::{ExciteSettings, design_excitation};
use aras_urdf::identify::{IdentifySettings, identify};
use aras_urdf::sim::{ArmController, ArmSensors, ArmSimulation, DriveTruth, simulate};
use aras_urdf::{CoulombWidth, ModelSettings, UrdfModel};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Dyn;
use std::hint::black_box;

fn panda() -> UrdfModel {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/urdf/panda_arm.urdf"
    );
    let settings = ModelSettings {
        coulomb_width: CoulombWidth::Uniform(0.02),
        ..ModelSettings::default()
    };
    UrdfModel::from_file(path, settings).expect("the Panda fixture")
}

/// A 60 s log of a 10 s, five-harmonic motion about the middle of the
/// joint ranges.
fn log(model: &UrdfModel) -> aras_log::Log {
    let (mut offset, mut a, mut b) = (Vec::new(), Vec::new(), Vec::new());
    let mut u = 0.5f64;
    let mut next = move || {
        u = (u + 0.618_033_988_749_895) % 1.0;
        0.5 * u - 0.25
    };
    for j in model.joints() {
        let l = j.limits.expect("Panda limits");
        offset.push(0.5 * (l.lower.unwrap_or(0.0) + l.upper.unwrap_or(0.0)));
        a.push((0..5).map(|_| next()).collect::<Vec<_>>());
        b.push((0..5).map(|_| next()).collect::<Vec<_>>());
    }
    let trajectory = FourierTrajectory::<Dyn>::new(std::f64::consts::TAU / 10.0, offset, a, b)
        .expect("trajectory");
    let truth = DriveTruth::default().parameters(model);
    let mut controller =
        ArmController::for_trajectory(model, &truth, &trajectory, 10.0, 10.0).expect("gains");
    controller.feedforward = Some(model.urdf_parameters());
    let sim = ArmSimulation::new(controller, ArmSensors::uniform(model.dof()));
    let arm = simulate(model, &truth, &trajectory, &sim).expect("simulation");
    let options = aras_log::ReadOptions {
        torques: Some(aras_log::TorqueTiming::Held),
        ..Default::default()
    };
    aras_log::read_log_from(arm.to_csv(false).as_bytes(), "panda.csv", &options).expect("log")
}

fn bench(c: &mut Criterion) {
    let model = panda();
    let log = log(&model);
    let settings = IdentifySettings {
        period: Some(10.0),
        ..IdentifySettings::default()
    };
    let mut g = c.benchmark_group("panda");
    g.sample_size(10);
    g.bench_function("identify a 60 s log", |b| {
        b.iter(|| black_box(identify(&model, black_box(&log), &settings).expect("identified")))
    });
    g.bench_function("excitation design (4 starts, 100 random)", |b| {
        b.iter(|| {
            black_box(
                design_excitation(&model, &ExciteSettings::default(), &|_| {}).expect("design"),
            )
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
