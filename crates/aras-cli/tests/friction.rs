//! `aras friction` on simulated joints with known friction: the diagnosis
//! names the hidden effect with its value, adds nothing on a control, and
//! the final model beats the best classical model on held-out logs at other
//! speeds. Logs come from `aras_friction::sim` (LuGre integrated by RK4 on
//! the exact motion, irregular 1–16 ms sampling, sensor noise).

use std::process::Command;

use std::path::Path;

use aras_friction::{FrictionRun, FrictionSettings, analyse};
use aras_friction::{
    JointLog,
    effects::Effect,
    sim::{JointSimulation, Ripple, SensorNoise, Sine},
};

/// TRAIN at speed 1, validation at 0.6 and 1.5 (held out at other speeds);
/// 40 s each keeps a scenario at about a second of CPU.
fn logs(sim: &JointSimulation) -> (JointLog, Vec<JointLog>) {
    let run = |name: &str, speed: f64, seed: u64| {
        JointSimulation {
            duration: 40.0,
            speed,
            seed,
            ..sim.clone()
        }
        .run(name)
        .log
    };
    (
        run("train", 1.0, 11),
        vec![run("slow", 0.6, 12), run("fast", 1.5, 13)],
    )
}

fn diagnose(sim: &JointSimulation) -> FrictionRun {
    let (train, vals) = logs(sim);
    analyse(&train, &vals, &FrictionSettings::default()).unwrap()
}

/// The first added effect and its fitted value in the refined model.
fn first_effect(run: &FrictionRun, value: &str) -> (Effect, f64) {
    let d = run.diagnosis.as_ref().unwrap();
    let step = d.steps.first().expect("an effect is added");
    let fm = run.final_model.as_ref().unwrap();
    let name = format!("{}.{value}", step.id);
    let p = fm.parameters.iter().find(|p| p.name == name).unwrap();
    (step.effect, p.value)
}

/// Held-out RMS of the final model against the best classical model:
/// at least 30 % lower on every validation log.
fn assert_beats_classical(run: &FrictionRun) {
    let best = &run.models[run.best];
    let fm = run.final_model.as_ref().unwrap();
    for (b, f) in best.validation.iter().zip(&fm.validation) {
        assert!(
            f.rms <= 0.7 * b.rms,
            "final {} vs best classical {} ({})",
            f.rms,
            b.rms,
            best.name
        );
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn hidden_ripple_is_named_with_its_amplitude() {
    let mut sim = JointSimulation::default();
    sim.friction.ripple.push(Ripple {
        cycles: 12.0,
        amplitude: 0.04,
        phase: 0.3,
    });
    let run = diagnose(&sim);
    let (e, amp) = first_effect(&run, "amplitude");
    let Effect::Ripple { cycles } = e else {
        panic!("{e:?}")
    };
    // Found by the line search, not an integer grid: within 0.5 %.
    assert!(rel(cycles, 12.0) < 5e-3, "cycles {cycles}");
    // 20 %: the acceptance bound; noise 5 mN·m over ~5000 samples puts σ
    // near 1e-4 N·m, so the bound only fails on a wrong model.
    assert!(rel(amp, 0.04) < 0.2, "amplitude {amp}");
    assert_beats_classical(&run);
}

#[test]
fn hidden_drift_is_named_with_its_rate() {
    let mut sim = JointSimulation::default();
    sim.friction.drift = -0.0015; // the Coulomb level falls 0.06 N·m in 40 s
    let run = diagnose(&sim);
    let (e, rate) = first_effect(&run, "rate");
    assert_eq!(e, Effect::CoulombDrift);
    assert!(rel(rate, -0.0015) < 0.2, "rate {rate}");
    assert_beats_classical(&run);
}

#[test]
fn hidden_asymmetry_is_named_with_its_coefficient() {
    let mut sim = JointSimulation::default();
    sim.friction.asymmetry = 0.05;
    let run = diagnose(&sim);
    let (e, c) = first_effect(&run, "coefficient");
    assert_eq!(e, Effect::ViscousAsymmetry);
    assert!(rel(c, 0.05) < 0.2, "coefficient {c}");
    assert_beats_classical(&run);
}

#[test]
fn control_adds_nothing() {
    let run = diagnose(&JointSimulation::default());
    let d = run.diagnosis.as_ref().unwrap();
    assert!(
        d.steps.is_empty(),
        "added {:?}",
        d.steps.iter().map(|s| &s.id).collect::<Vec<_>>()
    );
    assert!(run.final_model.is_none());
    // LuGre, the simulated model, is the best classical one.
    assert_eq!(run.models[run.best].name, "lugre");
}

#[test]
fn fitness_is_the_identification_fitness() {
    // The same definition (78) as aras-ident's validation.
    let y = [0.3, -0.2, 0.25, -0.31, 0.05, 0.11];
    let p = [0.28, -0.19, 0.2, -0.3, 0.0, 0.1];
    let a = aras_friction::fit::fitness(&y, &p).unwrap();
    let b = aras_ident::validate::fitness(&y, &p).unwrap();
    assert!((a - b).abs() < 1e-12);
}

#[test]
fn command_writes_json_report_and_predictions() {
    let dir = aras_testkit::Scratch::new("friction-cli");
    let sim = JointSimulation {
        duration: 20.0,
        ..JointSimulation::default()
    };
    // Own column names, an ignored column, and no velocity for one log (it
    // is then computed from q).
    let mut train = sim.run("train").log;
    let text = train
        .to_csv()
        .replacen("t,q,dq,tau,ddq", "time,q2,dq2,tau_f,ddq", 1);
    std::fs::write(dir.join("train.csv"), text).unwrap();
    train.ddq = None;
    let val = JointSimulation {
        speed: 0.7,
        seed: 5,
        ..sim
    }
    .run("val")
    .log;
    let mut v = String::from("time,q2,tau_f,extra\n");
    for i in 0..val.len() {
        v += &format!("{},{},{},1\n", val.t[i], val.q[i], val.tau[i]);
    }
    std::fs::write(dir.join("val.csv"), v).unwrap();
    let out = dir.join("out");
    let run = |columns: &str| {
        Command::new(env!("CARGO_BIN_EXE_aras"))
            .args(["friction", "--quiet", "--data"])
            .arg(dir.join("train.csv"))
            .arg("--validate")
            .arg(dir.join("val.csv"))
            .args(["--columns", columns, "--out"])
            .arg(&out)
            .output()
            .unwrap()
    };
    // dq=dq2 is named explicitly, so the validation log without it is refused.
    let o = run("t=time,q=q2,dq=dq2,tau=tau_f");
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("val.csv") && err.contains("`dq2`"), "{err}");
    let o = run("t=time,q=q2,tau=tau_f");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("friction.json")).unwrap()).unwrap();
    assert_eq!(json["format"], "aras-friction/1");
    assert_eq!(
        json["models"].as_array().unwrap().len(),
        aras_friction::ModelKind::ALL.len()
    );
    assert_eq!(json["validation"][0]["dq_from_q"], true);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("<svg") && html.contains("Diagnosis"));
    for (name, log) in [("pred_train.csv", &train), ("pred_val.csv", &val)] {
        let text = std::fs::read_to_string(out.join(name)).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("t,tau"));
        let rows: Vec<(f64, f64)> = lines
            .map(|l| {
                let (a, b) = l.split_once(',').unwrap();
                (a.parse().unwrap(), b.parse().unwrap())
            })
            .collect();
        assert_eq!(rows.len(), log.len());
        assert_eq!(rows[3].0, log.t[3]);
        // The prediction tracks the torque (noise 5 mN·m, friction 0.3 N·m).
        let rms = (rows
            .iter()
            .zip(&log.tau)
            .map(|(r, t)| (r.1 - t).powi(2))
            .sum::<f64>()
            / rows.len() as f64)
            .sqrt();
        assert!(rms < 0.02, "{name}: {rms}");
    }
    // Not replaced without --force.
    let o = run("t=time,q=q2,tau=tau_f");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--force"));
}

/// Without a validation log the terminal says so: no empty validation list
/// and no "no further effect" from a diagnosis that did not run.
#[test]
fn command_without_validation_says_there_is_no_diagnosis() {
    let dir = aras_testkit::Scratch::new("friction-noval");
    let sim = JointSimulation {
        duration: 10.0,
        ..JointSimulation::default()
    };
    std::fs::write(dir.join("train.csv"), sim.run("train").log.to_csv()).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["friction", "--data"])
        .arg(dir.join("train.csv"))
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{err}");
    assert!(err.contains("N·m, no validation log"), "{err}");
    assert!(!err.contains("validation []"), "{err}");
    assert!(
        out.contains("No diagnosis: give at least one validation log"),
        "{out}"
    );
    assert!(!out.contains("No further effect"), "{out}");
}

/// A position logged in degrees and a joint that never moves are refused
/// through the command, naming the file.
#[test]
fn command_refuses_degrees_and_a_still_joint() {
    let dir = aras_testkit::Scratch::new("friction-units");
    let log = JointSimulation {
        duration: 5.0,
        ..JointSimulation::default()
    }
    .run("train")
    .log;
    let mut deg = String::from("t,q,tau\n");
    let mut still = String::from("t,q,tau\n");
    for i in 0..log.len() {
        deg += &format!("{},{},{}\n", log.t[i], log.q[i].to_degrees(), log.tau[i]);
        still += &format!("{},0.4,{}\n", log.t[i], log.tau[i]);
    }
    std::fs::write(dir.join("deg.csv"), deg).unwrap();
    std::fs::write(dir.join("still.csv"), still).unwrap();
    for (file, want) in [
        ("deg.csv", "deg.csv: angles look like degrees"),
        ("still.csv", "the joint never moves"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_aras"))
            .args(["friction", "-q", "--data"])
            .arg(dir.join(file))
            .arg("--out")
            .arg(dir.join(format!("out-{file}")))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{file} accepted");
        assert!(!err.contains("panicked"), "{err}");
        assert!(err.contains(want), "{file}: {err}");
    }
}

/// `[friction]` of the config file is the library's settings, defaults
/// included: `aras pipeline --print-config` prints them, a run reads them
/// (and `--shape` overrides `fit.shape`), and a value out of range is
/// refused naming the file, the key and its line, writing nothing.
#[test]
fn config_friction_section_is_the_library_settings() {
    let dir = aras_testkit::Scratch::new("friction-config");
    let o = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["pipeline", "--print-config"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.contains("[friction]") && text.contains("[friction.fit]"),
        "{text}"
    );
    let c =
        aras_cli::config::Config::parse(&text, aras_cli::config::Format::Toml, "printed").unwrap();
    assert_eq!(c.friction, FrictionSettings::default());
    let sel = aras_ident::selection::SelectionOptions::default();
    assert_eq!(
        (c.friction.alpha, c.friction.min_gain, c.friction.max_steps),
        (sel.alpha, sel.min_gain, sel.max_steps)
    );

    let sim = JointSimulation {
        duration: 10.0,
        ..JointSimulation::default()
    };
    std::fs::write(dir.join("train.csv"), sim.run("train").log.to_csv()).unwrap();
    let cfg = dir.join("friction.toml");
    std::fs::write(
        &cfg,
        "[friction]\nmax_steps = 2\n[friction.fit]\nstarts = 2\nshape = 1.5\n",
    )
    .unwrap();
    let run = |config: &std::path::Path, extra: &[&str], out: &str| {
        Command::new(env!("CARGO_BIN_EXE_aras"))
            .args(["friction", "-q", "--data"])
            .arg(dir.join("train.csv"))
            .arg("--config")
            .arg(config)
            .args(extra)
            .arg("--out")
            .arg(dir.join(out))
            .output()
            .unwrap()
    };
    let o = run(&cfg, &["--shape", "2"], "out");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("out").join("friction.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["settings"]["max_steps"], 2);
    assert_eq!(json["settings"]["fit"]["starts"], 2);
    assert_eq!(json["settings"]["fit"]["shape"], 2.0);

    let bad =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/bad/config/friction_shape.toml");
    let o = run(&bad, &[], "out-bad");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains(
            "friction_shape.toml:2:1: key `friction.fit.shape`: the Stribeck shape exponent \
             must lie in [0.25, 5]"
        ) && err.contains("found 9"),
        "{err}"
    );
    assert!(!dir.join("out-bad").exists());
}

/// `--predict` logs are applied after every choice and take part in none:
/// the analysis and every other output are byte-identical with or without
/// another `--predict` log, and `aras friction-predict` with the written
/// `friction.json` reproduces each prediction byte for byte (effects
/// included), without replacing a file it did not write.
#[test]
fn predicted_logs_take_no_part_and_the_model_file_reproduces_them() {
    let dir = aras_testkit::Scratch::new("friction-predict");
    let mut sim = JointSimulation {
        duration: 30.0,
        ..JointSimulation::default()
    };
    sim.friction.ripple.push(Ripple {
        cycles: 12.0,
        amplitude: 0.04,
        phase: 0.3,
    });
    let write = |name: &str, speed: f64, seed: u64| {
        let log = JointSimulation {
            speed,
            seed,
            ..sim.clone()
        }
        .run(name)
        .log;
        std::fs::write(dir.join(format!("{name}.csv")), log.to_csv()).unwrap();
    };
    write("train", 1.0, 3);
    write("val", 0.7, 4);
    write("p1", 1.3, 5);
    write("p2", 0.5, 6);
    let friction = |predict: &[&str], out: &str| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_aras"));
        c.args(["friction", "-q", "--data"])
            .arg(dir.join("train.csv"))
            .arg("--validate")
            .arg(dir.join("val.csv"));
        for p in predict {
            c.arg("--predict").arg(dir.join(format!("{p}.csv")));
        }
        let o = c.arg("--out").arg(dir.join(out)).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    let both = friction(&["p1", "p2"], "both");
    let one = friction(&["p1"], "one");
    assert!(both.contains("predicted p2 → pred_p2.csv: RMS"), "{both}");
    let p1_line = |out: &str| {
        out.lines()
            .find(|l| l.starts_with("predicted p1"))
            .map(str::to_owned)
    };
    assert!(p1_line(&one).is_some() && p1_line(&one) == p1_line(&both));
    let read = |out: &str, file: &str| std::fs::read(dir.join(out).join(file)).unwrap();
    for file in [
        "friction.json",
        "pred_train.csv",
        "pred_val.csv",
        "pred_p1.csv",
    ] {
        assert!(read("both", file) == read("one", file), "{file} differs");
    }
    let json: serde_json::Value = serde_json::from_slice(&read("both", "friction.json")).unwrap();
    assert!(
        !json["final_effects"].as_array().unwrap().is_empty(),
        "the hidden ripple is added, so the model file carries an effect: {json}"
    );

    let predict = |data: &str, out: &Path, force: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_aras"));
        c.args(["friction-predict", "--model"])
            .arg(dir.join("both").join("friction.json"))
            .arg("--data")
            .arg(dir.join(data))
            .arg("--out")
            .arg(out);
        if force {
            c.arg("--force");
        }
        c.output().unwrap()
    };
    let out = dir.join("p2-pred.csv");
    let o = predict("p2.csv", &out, false);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read(&out).unwrap() == read("both", "pred_p2.csv"));
    assert!(String::from_utf8_lossy(&o.stdout).contains("fitness (78)"));
    // The motion alone predicts: the same file from p2 without its tau
    // column (the logs share a zero, so no phase is measured from it).
    let p2 = std::fs::read_to_string(dir.join("p2.csv")).unwrap();
    let no_tau: String = p2
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            format!("{},{},{},{}\n", f[0], f[1], f[2], f[4..].join(","))
        })
        .collect();
    assert!(no_tau.starts_with("t,q,dq,ddq\n"), "{}", &no_tau[..40]);
    std::fs::write(dir.join("p2_motion.csv"), no_tau).unwrap();
    let motion_out = dir.join("p2-motion-pred.csv");
    let o = predict("p2_motion.csv", &motion_out, false);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read(&motion_out).unwrap() == read("both", "pred_p2.csv"));
    assert!(String::from_utf8_lossy(&o.stdout).contains("no tau column to compare with"));
    // An existing output needs --force; an input is never replaced.
    let o = predict("p2.csv", &out, false);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--force"));
    assert!(predict("p2.csv", &out, true).status.success());
    let before = std::fs::read(dir.join("p1.csv")).unwrap();
    let o = predict("p2.csv", &dir.join("p1.csv"), true);
    assert!(!o.status.success());
    assert!(std::fs::read(dir.join("p1.csv")).unwrap() == before);
    // A file that is not a friction model is refused with the fix.
    std::fs::write(dir.join("other.json"), "{\"format\": \"aras-params/1\"}").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(["friction-predict", "--model"])
        .arg(dir.join("other.json"))
        .arg("--data")
        .arg(dir.join("p2.csv"))
        .arg("--out")
        .arg(dir.join("x.csv"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("format `aras-params/1` is not `aras-friction/1`"),
        "{err}"
    );
    assert!(!dir.join("x.csv").exists());
}

/// A joint on a short stroke (`stroke` rad peak to peak, about), fast
/// enough to cross the Stribeck region both ways, logged every 1–6 ms with
/// a high-resolution encoder (0.2 µrad noise: a gear-tooth ripple of
/// 8000 cycles/rev moves 1.6e-3 rad of phase per µrad). Returns the log and
/// its noise floor, the RMS of the logged torque against the true friction.
fn short_stroke(seed: u64, speed: f64, stroke: f64, ripple: Option<Ripple>) -> (JointLog, f64) {
    let sine = |share: f64, frequency: f64, phase: f64| Sine {
        amplitude: share * stroke,
        frequency,
        phase,
    };
    let mut sim = JointSimulation {
        duration: 30.0,
        speed,
        seed,
        min_step: 1e-3,
        max_step: 6e-3,
        motion: vec![
            sine(0.3, 0.5, 0.0),
            sine(0.12, 1.7, 1.0),
            sine(0.03, 5.0, 2.0),
        ],
        noise: SensorNoise {
            tau: 0.005,
            q: 2e-7,
            dq: 2e-4,
        },
        ..JointSimulation::default()
    };
    sim.friction.ripple.extend(ripple);
    let s = sim.run("short");
    let floor = aras_friction::fit::metrics(&s.log.tau, &s.clean_tau).rms;
    (s.log, floor)
}

/// A gear-tooth ripple (3000–8000 cycles/rev, not an integer) on a stroke
/// of 0.03–0.05 rad is found by the line search: named first, spatial
/// frequency within 0.5 % (and within 4σ), amplitude within 10 %, held-out
/// RMS within 10 % of the noise floor on two logs it did not train on
/// (other noise and sampling, at 0.8 and 1.0 of TRAIN's speed).
#[test]
fn gear_tooth_ripple_on_a_short_stroke_is_found_at_its_frequency() {
    for (seed, cycles, amplitude, stroke) in [
        (21, 3217.3, 0.12, 0.03),
        (31, 5012.7, 0.2, 0.04),
        (41, 7633.9, 0.08, 0.05),
    ] {
        let ripple = Ripple {
            cycles,
            amplitude,
            phase: 0.4,
        };
        let (train, _) = short_stroke(seed, 1.0, stroke, Some(ripple));
        let (a, fa) = short_stroke(seed + 1, 0.8, stroke, Some(ripple));
        let (b, fb) = short_stroke(seed + 2, 1.0, stroke, Some(ripple));
        let run = analyse(&train, &[a, b], &FrictionSettings::default()).unwrap();
        let d = run.diagnosis.as_ref().unwrap();
        let line = d.spectrum.lines.first().expect("a line");
        let (e, amp) = first_effect(&run, "amplitude");
        let Effect::Ripple { cycles: k } = e else {
            panic!("{cycles}: first effect {e:?}")
        };
        assert!(rel(k, cycles) < 5e-3, "{cycles}: found {k}");
        assert!(
            (k - cycles).abs() < 4.0 * line.sigma,
            "{cycles}: found {k} ± {}",
            line.sigma
        );
        assert!(rel(amp, amplitude) < 0.1, "{cycles}: amplitude {amp}");
        let fm = run.final_model.as_ref().unwrap();
        for (m, floor) in fm.validation.iter().zip([fa, fb]) {
            assert!(
                m.rms <= 1.1 * floor,
                "{cycles}: RMS {} floor {floor}",
                m.rms
            );
        }
    }
}

/// The short-stroke control (no ripple), five strokes and seeds: no line,
/// nothing added.
#[test]
fn short_stroke_control_has_no_line_and_adds_nothing() {
    for (k, stroke) in [0.02, 0.027, 0.034, 0.041, 0.05].into_iter().enumerate() {
        let seed = 100 + 10 * k as u64;
        let (train, _) = short_stroke(seed, 1.0, stroke, None);
        let (a, _) = short_stroke(seed + 1, 0.8, stroke, None);
        let (b, _) = short_stroke(seed + 2, 1.0, stroke, None);
        let run = analyse(&train, &[a, b], &FrictionSettings::default()).unwrap();
        let d = run.diagnosis.as_ref().unwrap();
        assert!(
            d.spectrum.lines.is_empty(),
            "{stroke}: {:?}",
            d.spectrum.lines
        );
        assert!(
            d.steps.is_empty(),
            "{stroke}: added {:?}",
            d.steps.iter().map(|s| &s.id).collect::<Vec<_>>()
        );
    }
}
