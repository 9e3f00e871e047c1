//! `aras predict`: the torques a parameter file predicts for a log's motion.

use std::fmt::Write as _;

use anyhow::{Context, Result};
use aras_dyn::Params;
use aras_signal::read_log;

use crate::cli::PredictArgs;
use crate::cmd::identify::read_options;
use crate::identify::{fitness_per_joint, prepare, process_options};
use crate::output::{FileKind, check_new_file, write_atomic};
use crate::validate::predict_standard;

/// Runs `predict`: writes `t,tau1,tau2` (the model torque `Y(X, Ẋ, Ẍ) β`
/// at the processed samples) and prints the per-joint fitness (78) against
/// the log's processed torques, filtered like `identify` does.
pub fn run(args: &PredictArgs) -> Result<()> {
    let loaded = super::load_config(&args.common)?;
    let cfg = loaded.config.clone();
    let sidecar = args
        .sidecar
        .clone()
        .unwrap_or_else(|| aras_dyn::sim::sidecar_path(&args.data));
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
    let log = read_log(&args.data, &read_options(args.sidecar.as_deref()))
        .with_context(|| format!("reading {}", args.data.display()))?;
    super::print_warnings(&args.data, &log.warnings);
    let logged = log.theta_dot.is_some() && log.theta_ddot.is_some();
    let mut opts = process_options(&cfg, args.period, logged);
    if args.period.is_none() {
        opts.period = aras_signal::PeriodSource::Off;
    }
    let prep = prepare(&log, &opts, cfg.identification.filtering, &model, &geometry)?;
    let fit = fitness_per_joint(prep.t(), &predict_standard(&prep, &beta)?)?;
    // The model torque itself: the regressor of the processed samples,
    // unfiltered.
    let raw = aras_pipeline::robot::stack(&model, &geometry, &prep.processed.samples)?;
    let tau = aras_ident::validate::predict(raw.w.as_ref(), &beta)?;
    let n = prep.n();
    let mut csv = String::with_capacity(n * 48);
    csv.push_str("t,tau1,tau2\n");
    for i in 0..n {
        let _ = writeln!(
            csv,
            "{},{},{}",
            prep.processed.samples.t[i],
            tau[i],
            tau[n + i]
        );
    }
    write_atomic(&args.out, csv.as_bytes())?;
    println!(
        "{}: {n} rows ({}); fitness (78) vs the log's torques: τ1 {:.2} %, τ2 {:.2} %",
        args.out.display(),
        prep.processed.summary.derivative_source,
        fit[0],
        fit[1]
    );
    Ok(())
}
