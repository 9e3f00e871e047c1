//! The diagnosis on simulated data with hidden effects (ground truth from
//! the simulator). TRAIN: a fixed 5-harmonic Fourier excitation (10 s
//! period, 4 periods); VALIDATION: the paper's trajectory (79) at 0.5 Hz
//! (10 periods). Default sensors: 3 mN·m torque noise, 1.5e-4 rad encoder.

use std::path::PathBuf;

use aras_dyn::sim::{SimConfig, simulate, write_log};
use aras_dyn::{Cogging, Model, Params, Sinusoid, Stribeck, Trajectory};
use aras_excite::FourierTrajectory;
use aras_ident::diagnose::{Dataset, DiagnoseOptions, Diagnosis, diagnose};
use aras_signal::{ProcessOptions, ReadOptions, process, read_log};

/// A fixed 5-harmonic Fourier excitation with a 5 s period whose position
/// amplitudes (sum ±48° in φ, ±19.5° in γ about [85°, 60°]) fill the
/// workspace box (77), so the validation motion (79) is an interpolation.
fn excitation() -> FourierTrajectory {
    let d = f64::to_radians;
    let w = std::f64::consts::TAU / 5.0;
    let amp = [[0.45, 0.2, 0.1, 0.06, 0.04], [0.17, 0.08, 0.04, 0.03, 0.02]];
    let phase = |i: usize, l: usize| {
        if i == 0 {
            1.1 * l as f64
        } else {
            0.7 * l as f64 + 0.5
        }
    };
    let coef = |i: usize, sin: bool| -> Vec<f64> {
        (0..5)
            .map(|k| {
                let c = amp[i][k] * w * (k + 1) as f64;
                let p = phase(i, k + 1);
                if sin { c * p.sin() } else { c * p.cos() }
            })
            .collect()
    };
    FourierTrajectory::new(
        w,
        [d(85.0), d(60.0)],
        [coef(0, false), coef(1, false)],
        [coef(0, true), coef(1, true)],
    )
    .unwrap()
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
    let popts = ProcessOptions {
        use_logged_derivatives: std::env::var("LOGGED").is_ok(),
        filter: if std::env::var("NOFILT").is_ok() {
            None
        } else {
            ProcessOptions::default().filter
        },
        ..ProcessOptions::default()
    };
    let p = process(&raw, &popts, &truth.geometry().unwrap()).unwrap();
    Dataset::from_processed(tag, &p).unwrap()
}

fn run(truth: &Params, delay: usize, tag: &str) -> Diagnosis {
    let train = dataset(truth, &excitation(), 20.0, delay, &format!("{tag}-train"));
    let val = dataset(
        truth,
        &Sinusoid::paper_79(0.5).unwrap(),
        10.0,
        delay,
        &format!("{tag}-val"),
    );
    let cad = Params::aras_diamond();
    let model = Model::paper(cad.gravity).unwrap();
    let opts = DiagnoseOptions {
        reference: Some(cad.clone()),
        ..DiagnoseOptions::default()
    };
    diagnose(&model, &cad.geometry().unwrap(), &train, &[val], &opts).unwrap()
}

fn show(d: &Diagnosis) {
    eprintln!("{}", d.conclusion);
    for r in &d.fitness {
        eprintln!("  step {} {:?}  {}", r.step, r.fitness, r.model);
    }
    for (k, round) in d.rounds.iter().enumerate() {
        eprintln!(" round {k}");
        for c in round.iter().take(6) {
            eprintln!(
                "   {:40} k={} drop={:.3}% neff={:.0} F={:.2} p={:.2e} gain={:?} sig={}",
                c.label,
                c.added_parameters,
                c.rss_drop_percent,
                c.n_eff,
                c.f,
                c.p_value,
                c.gain,
                c.significant
            );
        }
    }
    for a in d.before.iter().chain(&d.after) {
        for w in &a.whiteness {
            eprintln!(
                "  white j{} p={:.3} rms={:.5} tau={:.1}",
                w.joint, w.p_value, w.rms, w.autocorrelation_time
            );
        }
        for f in a.findings.iter().take(4) {
            eprintln!("  {}", f.text);
        }
    }
    eprintln!("  {:.2} s", d.elapsed_s);
}

#[test]
#[ignore]
fn explore() {
    let cad = Params::aras_diamond();
    let d = run(&cad, 0, "control");
    show(&d);
    let mut p = cad.clone();
    p.extra.stribeck_friction = Some(Stribeck {
        v_s: 0.1,
        level: [0.03, 0.08],
    });
    show(&run(&p, 0, "stribeck"));
    let mut p = cad.clone();
    p.extra.cogging = Some(Cogging {
        cycles_per_rev: 12.0,
        sin: [vec![0.02], vec![0.0]],
        cos: [vec![0.0], vec![0.02]],
    });
    show(&run(&p, 0, "cogging"));
    show(&run(&cad, 5, "delay"));
}

#[test]
#[ignore]
fn debug_fit() {
    use aras_ident::robot::{FilterMode, filter, stack};
    use aras_ident::{BaseParameters, ReducedLs};
    let cad = Params::aras_diamond();
    let train = dataset(&cad, &excitation(), 20.0, 0, "dbg-train");
    let _ = 16.0;
    let model = Model::paper(cad.gravity).unwrap();
    let g = cad.geometry().unwrap();
    let mut s = stack(&model, &g, &train.samples).unwrap();
    let truth = cad.standard_vector(&model).unwrap();
    let pred = aras_ident::validate::predict(s.w.as_ref(), truth.as_slice()).unwrap();
    eprintln!(
        "unfiltered truth fitness {:?}",
        aras_ident::validate::fitness_per_group(&s.t, &pred, &s.groups)
    );
    let n = train.len();
    for j in 0..2 {
        let (mut a, mut b, mut ca, mut cb) = (0.0, 0.0, 0, 0);
        for i in 0..n {
            let r = s.t[j * n + i] - pred[j * n + i];
            if train.samples.theta_dot[0][i].abs() > 0.5
                && train.samples.theta_dot[1][i].abs() > 0.5
            {
                a += r * r;
                ca += 1
            } else {
                b += r * r;
                cb += 1
            }
        }
        eprintln!(
            "joint {j}: rms fast {:.4} ({ca}) slow {:.4} ({cb})",
            (a / ca as f64).sqrt(),
            (b / cb as f64).sqrt()
        );
    }
    filter(
        &mut s,
        train.filter.as_ref().unwrap(),
        FilterMode::Parallel,
        train.periodic,
    )
    .unwrap();
    let pred = aras_ident::validate::predict(s.w.as_ref(), truth.as_slice()).unwrap();
    for (vmin, guard) in [(0.1, 0usize), (0.1, 30), (0.1, 60), (0.2, 60)] {
        for j in 0..2 {
            let v = &train.samples.theta_dot[j];
            let (mut a, mut c) = (0.0, 0);
            for i in 0..n {
                let lo = i.saturating_sub(guard);
                let hi = (i + guard + 1).min(n);
                if v[lo..hi].iter().all(|x| x.abs() >= vmin) {
                    let r = s.t[j * n + i] - pred[j * n + i];
                    a += r * r;
                    c += 1;
                }
            }
            eprintln!(
                "vmin {vmin} guard {guard} joint {j}: rms {:.4} kept {c}",
                (a / c as f64).sqrt()
            );
        }
    }
    eprintln!(
        "filtered truth fitness {:?} periodic {} n {}",
        aras_ident::validate::fitness_per_group(&s.t, &pred, &s.groups),
        train.periodic,
        train.len()
    );
    let base = BaseParameters::from_regressor(s.w.as_ref(), &s.names, 1e-8).unwrap();
    let wb = base.base_regressor(s.w.as_ref()).unwrap();
    let ols = ReducedLs::new(wb.as_ref(), &s.t, &base.base_names())
        .unwrap()
        .ols()
        .unwrap();
    eprintln!("nb {} cond {:.3e}", base.n_base(), ols.condition_number);
    let pred = aras_ident::validate::predict(wb.as_ref(), &ols.estimate).unwrap();
    eprintln!(
        "ols fitness {:?}",
        aras_ident::validate::fitness_per_group(&s.t, &pred, &s.groups)
    );
    let th = &train.samples.theta_dot;
    eprintln!(
        "max thd {:?}",
        th.iter()
            .map(|v| v.iter().fold(0.0f64, |a, b| a.max(b.abs())))
            .collect::<Vec<_>>()
    );
}
