//! `aras predict`: the torques a parameter file predicts for a log's motion.

use std::fmt::Write as _;

use anyhow::{Context, Result};
use aras_dyn::Params;
use aras_signal::OutputRows;

use crate::cli::PredictArgs;
use crate::identify::{fitness_per_joint, process_options};
use crate::output::{FileKind, check_new_file, write_atomic};

/// Runs `predict`: writes `t,tau1,tau2`, the model torque `Y(θ, θ̇, θ̈) β`
/// on every row of the log (θ̇, θ̈ from the log's derivative columns as
/// given, else from the angles with the data-chosen bandwidth), and prints
/// the per-joint fitness (78) of exactly that file against the log's raw
/// torques on the same rows.
pub fn run(args: &PredictArgs) -> Result<()> {
    let loaded = super::load_config(&args.common)?;
    let cfg = loaded.config.clone();
    let sidecar = args.log.sidecar_of(&args.data);
    check_new_file(
        &args.out,
        args.common.force,
        FileKind::Prediction,
        &super::input_files(&args.common, &loaded, &[&args.params, &args.data, &sidecar]),
    )?;
    let params =
        Params::load(&args.params).with_context(|| format!("reading {}", args.params.display()))?;
    // The parameter file's own model: extra effects in it are predicted too.
    let model = params.model()?;
    let beta = params.standard_vector(&model)?.as_slice().to_vec();
    let geometry = params.geometry()?;
    let log = super::load_log(&args.data, &args.log, &cfg)?;
    let logged = log.theta_dot.is_some() && log.theta_ddot.is_some();
    let mut opts = process_options(&cfg, args.log.period, logged);
    opts.rows = OutputRows::EveryRow;
    let processed = aras_signal::process(&log, &opts, &aras_kin::task_motion(&geometry))
        .with_context(|| format!("processing {}", args.data.display()))?;
    let samples = &processed.samples;
    let w = aras_pipeline::robot::stack(&model, &geometry, samples)?;
    let tau = aras_ident::validate::predict(w.w.as_ref(), &beta)?;
    let n = samples.len();
    let mut measured = samples.tau[0].clone();
    measured.extend_from_slice(&samples.tau[1]);
    let fit = fitness_per_joint(&measured, &tau)?;
    let mut csv = String::with_capacity(n * 48);
    csv.push_str("t,tau1,tau2\n");
    for i in 0..n {
        let _ = writeln!(csv, "{},{},{}", samples.t[i], tau[i], tau[n + i]);
    }
    write_atomic(&args.out, csv.as_bytes())?;
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
    Ok(())
}
