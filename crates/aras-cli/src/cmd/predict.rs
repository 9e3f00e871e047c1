//! `aras predict`: the torques a parameter file predicts for a log's motion.

use std::fmt::Write as _;

use anyhow::{Context, Result};
use aras_signal::OutputRows;

use crate::cli::PredictArgs;
use crate::identify::process_options;
use crate::output::{FileKind, NewFile};
use crate::robot::{ParamsUse, read_params};

/// Runs `predict`: writes `t,tau1,tau2`, the model torque `Y(θ, θ̇, θ̈) β`
/// on every row of the log (θ̇, θ̈ from the log's derivative columns as
/// given, else from the angles with the data-chosen bandwidth), and prints
/// the per-joint fitness (78) of exactly that file against the log's raw
/// torques on the same rows.
pub fn run(args: &PredictArgs) -> Result<()> {
    let loaded = super::load_config(&args.common)?;
    let cfg = loaded.config.clone();
    let sidecar = args.log.sidecar_of(&args.data);
    let out = NewFile::create(
        &args.out,
        args.common.force,
        FileKind::Prediction,
        &super::input_files(&args.common, &loaded, &[&args.params, &args.data, &sidecar]),
    )?;
    let params = read_params(&args.params, ParamsUse::Estimate)?;
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
    // The log's raw torques on the rows written (the processed samples'
    // torques are band-limited with the motion: not what the file is
    // compared with).
    let [(m1, p1), (m2, p2)] = processed.on_log_rows([&tau[..n], &tau[n..]])?;
    let fit = [
        aras_ident::validate::fitness(&m1, &p1)?,
        aras_ident::validate::fitness(&m2, &p2)?,
    ];
    let mut csv = String::with_capacity(n * 48);
    csv.push_str("t,tau1,tau2\n");
    for i in 0..n {
        let _ = writeln!(csv, "{},{},{}", samples.t[i], tau[i], tau[n + i]);
    }
    out.write(csv.as_bytes())?;
    out.commit()?;
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
