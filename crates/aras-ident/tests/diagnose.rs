//! The diagnosis on simulated data with hidden effects (ground truth from
//! the simulator), issue 8.
//!
//! TRAIN: the designed excitation `fixtures/trajectories/default-excitation.json`
//! (10 s period, [`TRAIN_PERIODS`] periods, period-averaged). VALIDATION:
//! the paper's trajectory (79) at 0.5 Hz and 1.0 Hz (10 periods each,
//! period-averaged). Default sensors (10 mA current noise, 4096-count
//! encoders). Every log is written as CSV + sidecar and read back, as a
//! user's data would arrive. Simulations run once per scenario.
//!
//! Hidden magnitudes (realistic for this robot: its Coulomb levels are
//! 0.076 / 0.289 N·m, viscous 0.034 / 0.009 N·m·s/rad, and the torques reach
//! ≈ 1 N·m):
//!
//! | effect | hidden |
//! |---|---|
//! | `torque_offset` | [0.02, −0.03] N·m |
//! | `coulomb_asymmetry` | [0.02, 0.04] N·m (Fc ± Fca) |
//! | `stribeck_friction` | v_s = 0.2 rad/s, levels [0.03, 0.06] N·m |
//! | `passive_joint_viscous` | [0.005, 0.005, 0.005] N·m·s/rad |
//! | `cogging` | 12 cycles/rev, harmonics 1–2: 0.01, 0.004 N·m |
//! | `quadratic_damping` | [0.005, 0.005] N·m·s²/rad² |
//! | `time_delay` | 5 samples (5 ms at 1 kHz) |

use std::path::PathBuf;
use std::sync::OnceLock;

use aras_dyn::sim::{SimConfig, simulate, write_log};
use aras_dyn::{Cogging, Model, Params, Sinusoid, Stribeck, Trajectory};
use aras_excite::FourierTrajectory;
use aras_ident::diagnose::{Dataset, DiagnoseOptions, Diagnosis, diagnose};
use aras_signal::{PeriodSource, ProcessOptions, ReadOptions, process, read_log};

/// Periods of the 10 s excitation in TRAIN.
const TRAIN_PERIODS: f64 = 4.0;

fn excitation() -> &'static FourierTrajectory {
    static E: OnceLock<FourierTrajectory> = OnceLock::new();
    E.get_or_init(|| {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/trajectories/default-excitation.json");
        FourierTrajectory::load(&path).unwrap()
    })
}

fn dataset(truth: &Params, traj: &dyn Trajectory, secs: f64, delay: usize, tag: &str) -> Dataset {
    let cfg = SimConfig {
        duration_s: secs,
        torque_delay_samples: delay,
        ..SimConfig::default()
    };
    let log = simulate(truth, traj, &cfg).unwrap();
    let dir = std::env::temp_dir().join(format!("aras-diag-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path: PathBuf = dir.join(format!("{tag}.csv"));
    write_log(&path, &log, true).unwrap();
    let raw = read_log(&path, &ReadOptions::default()).unwrap();
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_file(path.with_extension("json"));
    let popts = ProcessOptions {
        period: PeriodSource::Seconds(traj.period().unwrap()),
        ..ProcessOptions::default()
    };
    let p = process(&raw, &popts, &truth.geometry().unwrap()).unwrap();
    Dataset::from_processed(tag, &p).unwrap()
}

fn run(truth: &Params, delay: usize, tag: &str) -> Diagnosis {
    let period = excitation().period();
    let train = dataset(
        truth,
        excitation(),
        TRAIN_PERIODS * period,
        delay,
        &format!("{tag}-train"),
    );
    let vals: Vec<Dataset> = [0.5, 1.0]
        .iter()
        .map(|&f| {
            dataset(
                truth,
                &Sinusoid::paper_79(f).unwrap(),
                10.0 / f,
                delay,
                &format!("{tag}-val{f}"),
            )
        })
        .collect();
    let cad = Params::aras_diamond();
    let model = Model::paper(cad.gravity).unwrap();
    let opts = DiagnoseOptions {
        reference: Some(cad.clone()),
        ..DiagnoseOptions::default()
    };
    let d = diagnose(&model, &cad.geometry().unwrap(), &train, &vals, &opts).unwrap();
    show(tag, &d);
    d
}

fn show(tag: &str, d: &Diagnosis) {
    eprintln!("== {tag}: {}", d.conclusion);
    for r in &d.fitness {
        eprintln!("  step {} {:?}  {}", r.step, r.fitness, r.model);
    }
    for (k, round) in d.rounds.iter().enumerate() {
        eprintln!(" round {k}");
        for c in round.iter().take(4) {
            eprintln!(
                "   {:40} k={} drop={:.3}% neff={:.0} F={:.2} p={:.2e} gain={:?} sets={:?} sig={}",
                c.label,
                c.added_parameters,
                c.rss_drop_percent,
                c.n_eff,
                c.f,
                c.p_value,
                c.gain,
                c.gain_per_set,
                c.significant
            );
        }
    }
    for s in &d.steps {
        eprintln!(
            "  added {} aliases {:?} {:?}",
            s.label, s.aliases, s.parameters
        );
    }
    for a in d.after.iter() {
        for w in &a.whiteness {
            eprintln!(
                "  after {} white j{} p={:.3} rms={:.5}",
                a.dataset, w.joint, w.p_value, w.rms
            );
        }
        for f in a.findings.iter().filter(|f| f.systematic).take(3) {
            eprintln!("  {}", f.text);
        }
    }
    eprintln!("  {:.2} s", d.elapsed_s);
}

/// Total validation fitness gain of the first step (mean over joints and
/// sets, percentage points).
fn first_gain(d: &Diagnosis) -> f64 {
    let m = |k: usize| {
        let f = &d.fitness[k].fitness;
        f.iter().map(|x| 0.5 * (x[0] + x[1])).sum::<f64>() / f.len() as f64
    };
    m(1) - m(0)
}

fn hidden(id: &str) -> (Params, usize) {
    let mut p = Params::aras_diamond();
    let mut delay = 0;
    let x = &mut p.extra;
    match id {
        "torque_offset" => x.torque_offset = Some([0.02, -0.03]),
        "coulomb_asymmetry" => x.coulomb_asymmetry = Some([0.02, 0.04]),
        "stribeck_friction" => {
            x.stribeck_friction = Some(Stribeck {
                v_s: 0.2,
                level: [0.03, 0.06],
            })
        }
        "passive_joint_viscous" => x.passive_joint_viscous = Some([0.005; 3]),
        "cogging" => {
            x.cogging = Some(Cogging {
                cycles_per_rev: 12.0,
                sin: [vec![0.01, 0.004], vec![0.0, 0.0]],
                cos: [vec![0.0, 0.0], vec![0.01, 0.004]],
            })
        }
        "quadratic_damping" => x.quadratic_damping = Some([0.005, 0.005]),
        "time_delay" => delay = 5,
        _ => panic!("unknown effect {id}"),
    }
    (p, delay)
}

/// The hidden effect is named first (for `coulomb_asymmetry`, which equals
/// `torque_offset` on data that never rest, as the alias of the name
/// given) and the validation fitness improves by at least `gain` points.
fn named_first(id: &str, gain: f64) {
    let (p, delay) = hidden(id);
    let d = run(&p, delay, id);
    let s = d
        .steps
        .first()
        .unwrap_or_else(|| panic!("{id}: nothing found"));
    assert!(
        s.id == id || s.aliases.iter().any(|a| a == id),
        "{id}: first step is {} (aliases {:?})",
        s.label,
        s.aliases
    );
    let g = first_gain(&d);
    assert!(g >= gain, "{id}: gain {g:.3} < {gain}");
}

#[test]
fn finds_torque_offset() {
    named_first("torque_offset", 0.3);
}

#[test]
fn finds_coulomb_asymmetry() {
    named_first("coulomb_asymmetry", 0.5);
}

#[test]
fn finds_stribeck_friction() {
    named_first("stribeck_friction", 0.2);
}

#[test]
fn finds_passive_joint_viscous() {
    named_first("passive_joint_viscous", 10.0);
}

#[test]
fn finds_cogging() {
    named_first("cogging", 10.0);
}

#[test]
fn finds_quadratic_damping() {
    named_first("quadratic_damping", 2.0);
}

#[test]
fn finds_time_delay() {
    named_first("time_delay", 1.0);
}

#[test]
fn control_adds_nothing_and_says_noise_like() {
    let d = run(&Params::aras_diamond(), 0, "control");
    assert!(d.steps.is_empty(), "{}", d.conclusion);
    assert!(d.noise_like, "{}", d.conclusion);
    assert!(d.conclusion.contains("noise-like"), "{}", d.conclusion);
}

#[test]
fn two_hidden_effects_are_both_found_and_nothing_else() {
    let (mut p, _) = hidden("cogging");
    p.extra.quadratic_damping = Some([0.005, 0.005]);
    let d = run(&p, 0, "two");
    let mut ids: Vec<&str> = d.steps.iter().map(|s| s.id.as_str()).collect();
    ids.sort();
    assert_eq!(ids, ["cogging", "quadratic_damping"], "{}", d.conclusion);
    assert!(d.noise_like, "{}", d.conclusion);
}

/// Timing (issue 8): a 160 s TRAIN log (16 periods of the excitation) and
/// two validation logs, all 7 candidates, with one hidden effect so that
/// two rounds run. Ignored: the simulation itself takes a few seconds.
#[test]
#[ignore]
fn timing_160_s() {
    let (p, _) = hidden("quadratic_damping");
    let period = excitation().period();
    let train = dataset(&p, excitation(), 16.0 * period, 0, "timing-train");
    let vals: Vec<Dataset> = [0.5, 1.0]
        .iter()
        .map(|&f| {
            let t = Sinusoid::paper_79(f).unwrap();
            dataset(&p, &t, 10.0 / f, 0, &format!("timing-val{f}"))
        })
        .collect();
    let cad = Params::aras_diamond();
    let model = Model::paper(cad.gravity).unwrap();
    let opts = DiagnoseOptions {
        reference: Some(cad.clone()),
        ..DiagnoseOptions::default()
    };
    let t0 = std::time::Instant::now();
    let d = diagnose(&model, &cad.geometry().unwrap(), &train, &vals, &opts).unwrap();
    let s = t0.elapsed().as_secs_f64();
    eprintln!(
        "160 s log: {s:.2} s, {} rounds, {} candidate settings per round",
        d.rounds.len(),
        d.rounds[0].len()
    );
    assert_eq!(d.steps[0].id, "quadratic_damping");
    assert!(s <= 10.0, "{s:.2} s");
}

/// Robustness (issue 8): magnitude scans for three effects, each at a
/// fraction of the magnitude of the acceptance tests; prints whether the
/// effect is named first. Ignored (≈ 1 min); results in docs/diagnose.md.
#[test]
#[ignore]
fn robustness_magnitudes() {
    for id in ["torque_offset", "quadratic_damping", "stribeck_friction"] {
        for scale in [0.05, 0.1, 0.2, 0.35, 0.5] {
            let (mut p, _) = hidden(id);
            let x = &mut p.extra;
            if let Some(v) = &mut x.torque_offset {
                v.iter_mut().for_each(|a| *a *= scale);
            }
            if let Some(v) = &mut x.quadratic_damping {
                v.iter_mut().for_each(|a| *a *= scale);
            }
            if let Some(s) = &mut x.stribeck_friction {
                s.level.iter_mut().for_each(|a| *a *= scale);
            }
            let d = run(&p, 0, &format!("robust-{id}-{scale}"));
            let first = d.steps.first().map_or("none", |s| s.id.as_str());
            let ok = first == id;
            eprintln!("ROBUST {id} scale {scale}: first = {first} ({ok})");
        }
    }
}
