use aras_friction::{Track, fit::*, sim::*};
fn main() {
    let sim = JointSimulation {
        duration: 120.0,
        gap_probability: 0.0,
        ..JointSimulation::default()
    };
    let s = sim.run("x");
    let log = &s.log;
    let m = Track::new(&log.t, &log.q, &log.dq).unwrap();
    let st = FitSettings::default();
    let t0 = std::time::Instant::now();
    let s = fit_stribeck(&m, &log.tau, &st).unwrap();
    println!(
        "stribeck {:?} evals {} it {}",
        t0.elapsed(),
        s.evaluations,
        s.iterations
    );
    let t0 = std::time::Instant::now();
    let d = fit_dahl(&m, &log.tau, &st).unwrap();
    println!(
        "dahl {:?} evals {} it {}",
        t0.elapsed(),
        d.evaluations,
        d.iterations
    );
    let t0 = std::time::Instant::now();
    let l = fit_lugre(&m, &log.tau, &s.model, &st).unwrap();
    println!(
        "lugre {:?} evals {} it {} rows {} {:?}",
        t0.elapsed(),
        l.evaluations,
        l.iterations,
        log.len(),
        l.model
    );
}
