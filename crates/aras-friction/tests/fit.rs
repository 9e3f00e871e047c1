//! Each model recovers its own simulated parameters from noise-free logs.
//! The data come from code paths independent of the model under test: the
//! static models from closures written here, Dahl and LuGre from the
//! simulator's RK4 integration on the exact motion.

use aras_friction::{
    FrictionModel, LuGre, Track,
    fit::{FitSettings, fit_coulomb_viscous, fit_dahl, fit_lugre, fit_stribeck},
    sim::{JointSimulation, SensorNoise, TrueFriction, typical_lugre},
};
use aras_testkit::{assert_source_not_repeated, io_source_kind};

fn quiet(duration: f64, lugre: LuGre) -> JointSimulation {
    JointSimulation {
        duration,
        noise: SensorNoise::NONE,
        gap_probability: 0.0,
        friction: TrueFriction::lugre(lugre),
        ..JointSimulation::default()
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn check(name: &str, got: &[f64], want: &[f64], tol: &[f64]) {
    for i in 0..want.len() {
        let r = if want[i] == 0.0 {
            got[i].abs()
        } else {
            rel(got[i], want[i])
        };
        assert!(
            r <= tol[i],
            "{name} parameter {i}: {} vs {} (rel {r:e})",
            got[i],
            want[i]
        );
    }
}

#[test]
fn coulomb_viscous_and_stribeck_recover_their_parameters() {
    let sim = quiet(30.0, typical_lugre()).run("x");
    let log = &sim.log;
    let m = Track::new(&log.t, &log.q, &log.dq).unwrap();
    let sg = |v: f64| {
        if v > 0.0 {
            1.0
        } else if v < 0.0 {
            -1.0
        } else {
            0.0
        }
    };
    let tau: Vec<f64> = log
        .dq
        .iter()
        .map(|&v| 0.02 + 0.3 * sg(v) + 0.11 * v)
        .collect();
    let f = fit_coulomb_viscous(&m, &tau, &FitSettings::default()).unwrap();
    check("cv", &f.model.parameters(), &[0.02, 0.3, 0.11], &[1e-9; 3]);
    let (fc, fs, vs, d, fv) = (0.3, 0.45, 0.03, 1.4, 0.11);
    let tau: Vec<f64> = log
        .dq
        .iter()
        .map(|&v| -0.01 + (fc + (fs - fc) * (-(v.abs() / vs).powf(d)).exp()) * sg(v) + fv * v)
        .collect();
    let f = fit_stribeck(&m, &tau, &FitSettings::default()).unwrap();
    check(
        "stribeck",
        &f.model.parameters(),
        &[-0.01, fc, fs, vs, d, fv],
        &[1e-6; 6],
    );
}

#[test]
fn dahl_recovers_its_parameters() {
    // Dahl (exponent 1) is LuGre with F_s = F_c and σ₁ = 0.
    let truth = LuGre {
        offset: 0.015,
        coulomb: 0.25,
        static_friction: 0.25,
        stribeck_velocity: 0.04,
        shape: 2.0,
        sigma0: 200.0,
        sigma1: 0.0,
        sigma2: 0.09,
    };
    let sim = quiet(30.0, truth).run("x");
    let log = &sim.log;
    let m = Track::new(&log.t, &log.q, &log.dq).unwrap();
    let f = fit_dahl(&m, &log.tau, &FitSettings::default()).unwrap();
    check(
        "dahl",
        &f.model.parameters(),
        &[0.015, 0.25, 200.0, 0.09],
        &[1e-3; 4],
    );
}

#[test]
fn lugre_recovers_its_parameters() {
    let truth = typical_lugre();
    let sim = quiet(60.0, truth).run("x");
    let log = &sim.log;
    let m = Track::new(&log.t, &log.q, &log.dq).unwrap();
    let settings = FitSettings::default();
    let s = fit_stribeck(&m, &log.tau, &settings).unwrap();
    let f = fit_lugre(&m, &log.tau, &s.model, &settings).unwrap();
    check(
        "lugre",
        &f.model.parameters(),
        &truth.parameters(),
        &[1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 0.05, 0.05, 1e-3],
    );
}

#[test]
fn a_missing_joint_log_keeps_the_io_error_as_source() {
    let path = std::env::temp_dir().join(format!("aras-absent-{}.csv", std::process::id()));
    let e = aras_friction::read_joint_log(&path, &aras_friction::ColumnMap::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("{}: cannot read the log", path.display())
    );
    assert_eq!(io_source_kind(&e), std::io::ErrorKind::NotFound);
    assert_source_not_repeated(&e);
}

#[test]
fn a_joint_that_never_moves_is_refused_not_a_panic() {
    let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
    // Still, up to encoder-level jitter far below the travel needed.
    let q: Vec<f64> = (0..200).map(|i| 0.3 + 1e-9 * (i % 3) as f64).collect();
    let dq = vec![0.0; 200];
    let tau: Vec<f64> = (0..200).map(|i| 0.01 * (i % 5) as f64).collect();
    let m = aras_friction::Track::new(&t, &q, &dq).unwrap();
    let s = aras_friction::fit::FitSettings::default();
    for e in [
        aras_friction::fit::fit_coulomb_viscous(&m, &tau, &s).map(|_| ()),
        aras_friction::fit::fit_stribeck(&m, &tau, &s).map(|_| ()),
        aras_friction::fit::fit_dahl(&m, &tau, &s).map(|_| ()),
    ] {
        let e = e.unwrap_err().to_string();
        assert!(
            e.contains("the joint never moves: q spans 2.00e-9 rad"),
            "{e}"
        );
        assert!(e.contains("log a run in which the joint moves"), "{e}");
    }
}
