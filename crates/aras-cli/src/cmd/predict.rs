//! `aras predict`: the torques a parameter file predicts for a log's motion.

use std::fmt::Write as _;

use anyhow::Result;
use serde::Serialize;

use crate::cli::PredictArgs;
use crate::identify::process_options;
use crate::output::{FileKind, NewFile};
use crate::robot::{ParamsUse, read_params};
use aras_pipeline::predict::{Prediction, Route, predict_log};
use aras_pipeline::validate::loss::ProcessingLoss;

/// `--summary` of `predict` (`"format": "aras-predict/1"`).
#[derive(Debug, Serialize)]
struct PredictSummary {
    format: &'static str,
    params: String,
    data: String,
    /// The route of the written PRED.csv.
    route: Route,
    /// Rows of PRED.csv (and of the log).
    rows: [usize; 2],
    /// Fitness (78) per joint of PRED.csv against the log's raw torques on
    /// its rows (%).
    fitness: [f64; 2],
    /// Logged-derivative route minus angles-only route
    /// (`aras_pipeline::validate::loss`); `null` for a log without
    /// derivative columns.
    processing_loss: Option<ProcessingLoss>,
}

/// Runs `predict`: writes `t,tau1,tau2`, the model torque `Y(θ, θ̇, θ̈) β`
/// on every row of the log (θ̇, θ̈ from the log's derivative columns as
/// given, else from the angles with the configured bandwidth, the
/// prediction then band-limited as the angles were), and prints
/// the per-joint fitness (78) of exactly that file against the log's raw
/// torques on the same rows. A log with derivative columns also gets its
/// processing loss (`aras_pipeline::validate::loss`): the same parameters
/// predicted from the angles alone, both scored on the rows both cover.
pub fn run(args: &PredictArgs) -> Result<()> {
    if let Some(urdf) = &args.urdf {
        return super::urdf::predict(args, urdf);
    }
    let loaded = super::load_config(&args.common)?;
    let cfg = loaded.config.clone();
    let sidecar = args.log.sidecar_of(&args.data);
    let inputs = super::input_files(&args.common, &loaded, &[&args.params, &args.data, &sidecar]);
    let out = NewFile::create(&args.out, args.common.force, FileKind::Prediction, &inputs)?;
    let summary_out = match &args.summary {
        Some(p) if p == &args.out => anyhow::bail!(
            "--summary {} is the --out file; give the summary its own name (e.g. PRED.json)",
            p.display()
        ),
        Some(p) => Some(NewFile::create(
            p,
            args.common.force,
            FileKind::PredictionSummary,
            &inputs,
        )?),
        None => None,
    };
    let params = read_params(&args.params, ParamsUse::Estimate)?;
    let log = super::load_log(&args.data, &args.log, &cfg)?;
    // The parameter file's own model: extra effects in it are predicted too.
    let Prediction {
        processed,
        tau,
        route,
        fitness: fit,
        processing_loss: loss,
        loss_unavailable,
    } = predict_log(
        &log,
        &params,
        &process_options(&cfg, args.log.period, false),
    )?;
    let samples = &processed.samples;
    let n = samples.len();
    let loss_unavailable = loss_unavailable.map(|e| format!("{:#}", anyhow::Error::from(e)));
    let mut csv = String::with_capacity(n * 48);
    csv.push_str("t,tau1,tau2\n");
    for i in 0..n {
        let _ = writeln!(csv, "{},{},{}", samples.t[i], tau[i], tau[n + i]);
    }
    out.write(csv.as_bytes())?;
    if let Some(s) = &summary_out {
        let summary = PredictSummary {
            format: "aras-predict/1",
            params: args.params.display().to_string(),
            data: args.data.display().to_string(),
            route,
            rows: [n, log.len()],
            fitness: fit,
            processing_loss: loss,
        };
        s.write((serde_json::to_string_pretty(&summary)? + "\n").as_bytes())?;
    }
    out.commit()?;
    if let Some(s) = summary_out {
        s.commit()?;
    }
    let rows = if n == log.len() {
        format!("all {n} rows")
    } else {
        format!(
            "{n} of {} rows (the derivative's edges have none)",
            log.len()
        )
    };
    println!(
        "{}: {n} rows; θ̇, θ̈: {}; fitness (78) of this file vs the log's raw torques on {rows}: \
         τ1 {:.3} %, τ2 {:.3} %",
        args.out.display(),
        processed.summary.bandwidth.reason,
        fit[0],
        fit[1]
    );
    if let Some(why) = &loss_unavailable {
        eprintln!("note: no processing loss: {why}");
    }
    if let Some(l) = loss {
        println!(
            "processing loss (logged θ̇, θ̈ minus the angles alone, same parameters, the {} rows \
             both cover, vs the raw torques): τ1 {:.3} points ({:.3} % vs {:.3} %), \
             τ2 {:.3} points ({:.3} % vs {:.3} %); {} holds the logged-derivative prediction",
            l.rows,
            l.loss[0],
            l.fitness_logged[0],
            l.fitness_angles[0],
            l.loss[1],
            l.fitness_logged[1],
            l.fitness_angles[1],
            args.out.display()
        );
    }
    Ok(())
}
