//! `aras friction`: reads the joint logs, runs [`aras_friction::analyse`],
//! writes `friction.json`, `report.html` (with its SVG figures) and
//! `pred_<log>.csv` (columns `t,tau`: the final model's prediction) for TRAIN,
//! every validation log and every `--predict` log. `aras friction-predict`:
//! the final model of a `friction.json` applied to a new log.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use aras_friction::fit::metrics;
use aras_friction::{
    ColumnMap, FinalModel, FrictionRun, JointLog, JointMotion, analyse, read_joint_log,
    read_joint_motion,
};

use crate::cli::{FrictionArgs, FrictionPredictArgs, JointLogArgs};
use crate::output::{FileKind, NewFile};

use crate::friction::conclusion;
use crate::output::OutDir;
use crate::report::Report;
use crate::report::plots::{Series, scatter};
use crate::stages::Stages;

/// Runs `friction`.
pub fn run(args: &FrictionArgs) -> Result<()> {
    let reader = LogReader::new(&args.log)?;
    let mut settings = crate::cmd::load_config(&args.common)?.config.friction;
    if let Some(shape) = args.shape {
        settings.fit.shape = Some(shape);
    }
    settings.validate()?;
    let inputs: Vec<PathBuf> = std::iter::once(args.data.clone())
        .chain(args.validate.iter().cloned())
        .chain(args.predict.iter().cloned())
        .chain(args.common.config.iter().cloned())
        .collect();
    let out = OutDir::create(&args.out, args.common.force, &inputs)?;
    let mut stages = Stages::new(args.common.quiet);
    let read_all = |paths: &[PathBuf]| {
        paths
            .iter()
            .map(|p| reader.read(p))
            .collect::<Result<Vec<_>>>()
    };
    let train = stages.run("read TRAIN", |_| reader.read(&args.data))?;
    let vals = stages.run("read validation logs", |_| read_all(&args.validate))?;
    let predicted = stages.run("read logs to predict", |_| {
        args.predict
            .iter()
            .map(|p| reader.read_motion(p))
            .collect::<Result<Vec<_>>>()
    })?;
    let run = stages.run("fit models + diagnosis", |_| {
        analyse(&train, &vals, &settings)
    })?;
    let logs: Vec<&JointLog> = std::iter::once(&train).chain(&vals).collect();
    // Every log the final model is written for: TRAIN, validation, --predict.
    let written: Vec<&JointMotion> = logs
        .iter()
        .map(|l| &l.motion)
        .chain(predicted.iter().map(ToPredict::motion))
        .collect();
    let names = prediction_names(&written);
    let mut predictions = vec![run.model.predict(&train)?];
    for v in &vals {
        predictions.push(run.model.predict_log(v)?);
    }
    for p in &predicted {
        predictions.push(p.prediction(&run.model)?);
    }
    stages.run("write outputs", |_| -> Result<()> {
        out.write_json("friction.json", &run)?;
        for ((log, name), pred) in written.iter().zip(&names).zip(&predictions) {
            out.write(name, prediction_csv(&log.t, pred))?;
        }
        let report = build(&run, &logs, &predictions[0])?;
        for (file, svg) in report.figures() {
            out.write(file, svg)?;
        }
        out.write("report.html", report.to_html())?;
        Ok(())
    })?;
    let dir = out.commit()?;
    if !args.common.quiet {
        for m in &run.models {
            let v: Vec<String> = m
                .validation
                .iter()
                .map(|x| format!("{:.4}", x.rms))
                .collect();
            let validation = if v.is_empty() {
                "no validation log".to_string()
            } else {
                format!("validation {} N·m", v.join(", "))
            };
            eprintln!(
                "{:<16} RMS train {:.4} N·m, {validation}",
                m.name, m.train.rms
            );
        }
    }
    println!("{}", conclusion(&run));
    let first = logs.len();
    for ((log, name), pred) in predicted
        .iter()
        .zip(&names[first..])
        .zip(&predictions[first..])
    {
        println!(
            "predicted {} → {name}{}",
            log.motion().name,
            log.compared(pred)
        );
    }
    println!("outputs in {}", dir.display());
    Ok(())
}

/// Runs `friction-predict`: the final model of a `friction.json` applied to
/// one log, written as `t,tau`.
pub fn predict(args: &FrictionPredictArgs) -> Result<()> {
    let model = read_model(&args.model)?;
    let reader = LogReader::new(&args.log)?;
    let inputs = [args.model.clone(), args.data.clone()];
    let out = NewFile::create(&args.out, args.force, FileKind::FrictionPrediction, &inputs)?;
    let log = reader.read_motion(&args.data)?;
    let pred = log.prediction(&model)?;
    out.write(prediction_csv(&log.motion().t, &pred).as_bytes())?;
    let path = out.commit()?;
    println!(
        "{}{}; prediction in {}",
        log.motion().name,
        log.compared(&pred),
        path.display()
    );
    Ok(())
}

/// A log to predict: with its torque when the file has one.
enum ToPredict {
    /// A log with its torque.
    Measured(JointLog),
    /// A motion only.
    Motion(JointMotion),
}

impl ToPredict {
    fn motion(&self) -> &JointMotion {
        match self {
            ToPredict::Measured(l) => &l.motion,
            ToPredict::Motion(m) => m,
        }
    }

    /// The final model on this log: with its torque, each line whose phase
    /// each log sets at this log's phase ([`FinalModel::predict_log`]);
    /// without, at TRAIN's (with a note when the model has such lines).
    fn prediction(&self, model: &FinalModel) -> Result<Vec<f64>> {
        Ok(match self {
            ToPredict::Measured(log) => model.predict_log(log)?,
            ToPredict::Motion(m) => {
                if !model.per_log_phase.is_empty() {
                    eprintln!(
                        "note: {}: no torque column, so the ripple lines whose phase each log \
                         sets ({}) keep TRAIN's phase; log the torque to have this log's own",
                        m.name,
                        fmt_cycles(&model.per_log_phase)
                    );
                }
                model.predict(m)?
            }
        })
    }

    /// `: RMS … N·m against its tau, fitness (78) … %`, or a note that the
    /// log has no torque to compare with.
    fn compared(&self, pred: &[f64]) -> String {
        match self {
            ToPredict::Measured(log) => {
                let m = metrics(&log.tau, pred);
                format!(
                    ": RMS {:.4} N·m against its tau{}",
                    m.rms,
                    m.fitness
                        .map_or_else(String::new, |f| format!(", fitness (78) {f:.2} %"))
                )
            }
            ToPredict::Motion(_) => " (no tau column to compare with)".into(),
        }
    }
}

/// `12.00, 5013.27 cycles/rev`.
fn fmt_cycles(k: &[f64]) -> String {
    let k: Vec<String> = k.iter().map(|k| format!("{k:.2}")).collect();
    format!("{} cycles/rev", k.join(", "))
}

/// The final model of an `aras-friction/1` document.
fn read_model(path: &Path) -> Result<FinalModel> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the model {}", path.display()))?;
    let value: serde_json::Value = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not JSON; give the friction.json that `aras friction` wrote",
            path.display()
        )
    })?;
    let format = value.get("format").and_then(|f| f.as_str());
    if format != Some(aras_friction::analysis::FORMAT) {
        bail!(
            "{}: format {} is not `{}`; give the friction.json that `aras friction` wrote",
            path.display(),
            format.map_or_else(|| "missing".into(), |f| format!("`{f}`")),
            aras_friction::analysis::FORMAT
        );
    }
    serde_json::from_value(value).with_context(|| {
        format!(
            "{}: its final model (`final_base`, `final_effects`) cannot be read",
            path.display()
        )
    })
}

/// Reads joint logs as the command line says: CSVs with `--columns`, ROS 2
/// bags with `--topic`, `--joint`, `--stamps`. The reader's notes go to
/// stderr.
struct LogReader<'a> {
    args: &'a JointLogArgs,
    columns: ColumnMap,
}

impl<'a> LogReader<'a> {
    /// Refuses the bag-only options for a CSV.
    fn check_csv(&self, p: &Path) -> Result<()> {
        if self.args.topic.is_some() || self.args.joint.is_some() {
            anyhow::bail!(
                "{}: --topic and --joint apply to ROS 2 bags (.mcap); a CSV's columns are named \
                 with --columns",
                p.display()
            );
        }
        Ok(())
    }

    fn new(args: &'a JointLogArgs) -> Result<Self> {
        let columns = match &args.columns {
            Some(c) => c.parse()?,
            None => ColumnMap::default(),
        };
        Ok(Self { args, columns })
    }

    fn read(&self, p: &Path) -> Result<JointLog> {
        if aras_log::is_bag(p) {
            return read_bag(p, self.args);
        }
        self.check_csv(p)?;
        let log = read_joint_log(p, &self.columns)?;
        for n in &log.notes {
            eprintln!("note: {n}");
        }
        Ok(log)
    }

    /// A log to predict: as [`LogReader::read`], the torque column optional
    /// in a CSV.
    fn read_motion(&self, p: &Path) -> Result<ToPredict> {
        if aras_log::is_bag(p) {
            return Ok(ToPredict::Measured(read_bag(p, self.args)?));
        }
        self.check_csv(p)?;
        let (motion, tau) = read_joint_motion(p, &self.columns)?;
        for n in &motion.notes {
            eprintln!("note: {n}");
        }
        Ok(match tau {
            Some(tau) => ToPredict::Measured(JointLog { motion, tau }),
            None => ToPredict::Motion(motion),
        })
    }
}

/// One joint of a ROS 2 bag as a joint log: `--topic`, `--joint`,
/// `--stamps`; position is `q`, velocity `dq` (computed from `q` when the
/// messages have none), effort `tau`. The rows go through the CSV joint
/// log's checks, labelled `BAG#TOPIC`.
fn read_bag(path: &Path, args: &JointLogArgs) -> Result<JointLog> {
    if args.columns.is_some() {
        anyhow::bail!(
            "{}: a ROS 2 bag's joint is chosen with --joint NAME, not --columns",
            path.display()
        );
    }
    let stamps = match args.stamps {
        crate::cli::StampsArg::Header => aras_log::Stamps::Header,
        crate::cli::StampsArg::Log => aras_log::Stamps::Log,
    };
    let j = aras_log::read_bag_joint(path, args.topic.as_deref(), args.joint.as_deref(), stamps)?;
    for n in &j.notes {
        eprintln!("note: {}: {n}", path.display());
    }
    let mut csv = String::with_capacity(j.t.len() * 64);
    csv.push_str(if j.velocity.is_some() {
        "t,q,dq,tau\n"
    } else {
        "t,q,tau\n"
    });
    for i in 0..j.t.len() {
        let _ = write!(csv, "{},{}", j.t[i], j.position[i]);
        if let Some(v) = &j.velocity {
            let _ = write!(csv, ",{}", v[i]);
        }
        let _ = writeln!(csv, ",{}", j.effort[i]);
    }
    let stem = path
        .file_stem()
        .map_or_else(|| "log".into(), |s| s.to_string_lossy().into_owned());
    Ok(aras_friction::read_joint_log_from(
        csv.as_bytes(),
        &j.label,
        &stem,
        &ColumnMap::default(),
    )?)
}

/// `pred_<stem>.csv` for each log; a stem used twice gets `_2`, `_3`, ….
fn prediction_names(logs: &[&JointMotion]) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    logs.iter()
        .map(|l| {
            let mut name = format!("pred_{}.csv", l.name);
            let mut k = 2;
            while seen.contains(&name) {
                name = format!("pred_{}_{k}.csv", l.name);
                k += 1;
            }
            seen.push(name.clone());
            name
        })
        .collect()
}

fn prediction_csv(t: &[f64], tau: &[f64]) -> String {
    let mut s = String::with_capacity(t.len() * 40);
    s.push_str("t,tau\n");
    for (t, y) in t.iter().zip(tau) {
        let _ = writeln!(s, "{t},{y}");
    }
    s
}

fn fmt(x: f64) -> String {
    if x == 0.0 || (1e-3..1e4).contains(&x.abs()) {
        format!("{x:.5}")
    } else {
        format!("{x:.4e}")
    }
}

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "—".into(), fmt)
}

/// The report: models table, τ–v scatter, hysteresis at a reversal,
/// residuals against q and t, the diagnosis steps. `final_train` is the
/// final model's prediction on TRAIN (`logs[0]`).
fn build(run: &FrictionRun, logs: &[&JointLog], final_train: &[f64]) -> Result<Report> {
    let train = logs[0];
    let mut r = Report::new(format!("Friction of joint log `{}`", train.name));
    r.paragraph(format!(
        "TRAIN `{}`: {} samples over {:.1} s, steps {:.1}–{:.1} ms{}. Validation: {}.",
        run.train.name,
        run.train.rows,
        run.train.duration,
        run.train.steps[0] * 1e3,
        run.train.steps[1] * 1e3,
        if run.train.dq_from_q {
            " (velocity computed from q)"
        } else {
            ""
        },
        if run.validation.is_empty() {
            "none".to_string()
        } else {
            run.validation
                .iter()
                .map(|v| format!("`{}` ({} samples)", v.name, v.rows))
                .collect::<Vec<_>>()
                .join(", ")
        }
    ));
    r.heading(2, "Conclusion").paragraph(conclusion(run));
    r.heading(2, "Models");
    let mut header = vec![
        "model".to_string(),
        "RMS train N·m".into(),
        "fit train %".into(),
    ];
    for v in &run.validation {
        header.push(format!("RMS {} N·m", v.name));
        header.push(format!("fit {} %", v.name));
    }
    let rows = run
        .models
        .iter()
        .chain(run.final_model.iter())
        .map(|m| {
            let mut row = vec![m.name.clone(), fmt(m.train.rms), fmt_opt(m.train.fitness)];
            for v in &m.validation {
                row.push(fmt(v.rms));
                row.push(fmt_opt(v.fitness));
            }
            row
        })
        .collect();
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    r.table(&h, rows);
    for m in run.models.iter().chain(run.final_model.iter()) {
        r.heading(3, format!("`{}`", m.name));
        r.table(
            &["parameter", "value", "σ", "unit", "note"],
            m.parameters
                .iter()
                .map(|p| {
                    vec![
                        p.name.clone(),
                        fmt(p.value),
                        fmt_opt(p.sigma),
                        p.unit.clone(),
                        if p.fixed {
                            "fixed".into()
                        } else if p.at_bound {
                            "at bound".into()
                        } else {
                            String::new()
                        },
                    ]
                })
                .collect(),
        );
        for w in &m.warnings {
            r.paragraph(format!("**{w}.**"));
        }
    }

    // τ–v scatter with each model's steady-state curve.
    let vmax = train.dq.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let vgrid: Vec<f64> = (0..=400)
        .map(|i| -vmax + 2.0 * vmax * i as f64 / 400.0)
        .collect();
    let curves: Vec<(String, Vec<f64>)> = run
        .fitted
        .iter()
        .map(|m| {
            (
                m.name().to_string(),
                vgrid.iter().map(|&v| m.steady_state(v)).collect(),
            )
        })
        .collect();
    let svg = scatter(
        "friction torque against velocity (TRAIN) and each model's steady state",
        "dq (rad/s)",
        "tau (N·m)",
        &[Series {
            name: "measured".into(),
            x: &train.dq,
            y: &train.tau,
        }],
        &curves
            .iter()
            .map(|(n, y)| Series {
                name: n.clone(),
                x: &vgrid,
                y,
            })
            .collect::<Vec<_>>(),
        6000,
    )?;
    r.figure(
        "tau_v.svg",
        "Measured friction torque against velocity with the steady-state curve of every model.",
        svg,
    );

    // Hysteresis loop at the slowest reversal of TRAIN.
    if let Some((a, b)) = reversal_window(train) {
        let dx: Vec<f64> = train.q[a..b].iter().map(|q| q - train.q[a]).collect();
        let preds: Vec<(String, Vec<f64>)> = run
            .fitted
            .iter()
            .map(|m| Ok((m.name().to_string(), m.predict(train)?[a..b].to_vec())))
            .collect::<Result<_>>()?;
        let svg = scatter(
            "hysteresis at a reversal (TRAIN)",
            "q − q(start) (rad)",
            "tau (N·m)",
            &[Series {
                name: "measured".into(),
                x: &dx,
                y: &train.tau[a..b],
            }],
            &preds
                .iter()
                .map(|(n, y)| Series {
                    name: n.clone(),
                    x: &dx,
                    y,
                })
                .collect::<Vec<_>>(),
            4000,
        )?;
        r.figure(
            "hysteresis.svg",
            format!(
                "Torque against position around the slowest reversal, t = {:.2}–{:.2} s.",
                train.t[a],
                train.t[b - 1]
            ),
            svg,
        );
    }

    // Residuals against q and t: best classical and final model.
    let best = &run.fitted[run.best];
    let rb: Vec<f64> = train
        .tau
        .iter()
        .zip(best.predict(train)?)
        .map(|(a, b)| a - b)
        .collect();
    let rf: Vec<f64> = train
        .tau
        .iter()
        .zip(final_train)
        .map(|(a, b)| a - b)
        .collect();
    for (axis, x, unit, file) in [
        ("position", &train.q, "q (rad)", "residual_q.svg"),
        ("time", &train.t, "t (s)", "residual_t.svg"),
    ] {
        let svg = scatter(
            &format!("TRAIN residual against {axis}"),
            unit,
            "tau − model (N·m)",
            &[
                Series {
                    name: format!("{} (best classical)", best.name()),
                    x,
                    y: &rb,
                },
                Series {
                    name: "final model".into(),
                    x,
                    y: &rf,
                },
            ],
            &[],
            5000,
        )?;
        r.figure(file, format!("TRAIN residual against {axis}."), svg);
    }
    r.heading(2, "Residual of the best classical model (TRAIN)");
    r.table(
        &["axis", "share of residual variance explained by bin means"],
        run.residual
            .iter()
            .map(|p| {
                vec![
                    format!("{:?}", p.axis).to_lowercase(),
                    format!("{:.3}", p.explained),
                ]
            })
            .collect(),
    );
    crate::friction::report_diagnosis(run, &mut r);
    Ok(r)
}

/// The window (sample range) around the TRAIN reversal with the smallest
/// acceleration, ±1.5 s, where presliding hysteresis shows best.
fn reversal_window(log: &JointLog) -> Option<(usize, usize)> {
    let acc = log.acceleration();
    let n = log.len();
    let k = (1..n)
        .filter(|&i| log.dq[i - 1] * log.dq[i] < 0.0)
        .min_by(|&a, &b| acc[a].abs().total_cmp(&acc[b].abs()))?;
    let t0 = log.t[k] - 1.5;
    let t1 = log.t[k] + 1.5;
    let a = log.t.partition_point(|&t| t < t0);
    let b = log.t.partition_point(|&t| t <= t1);
    (b > a + 2).then_some((a, b))
}
