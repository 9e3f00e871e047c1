//! `aras identify`: identification from any log in the documented format.

use anyhow::{Context, Result};
use aras_dyn::{Model, Params};
use aras_kin::Geometry;

use crate::cli::{IdentifyArgs, StreamingMode};
use crate::cmd::fit::{self, FitInput};
use crate::config::Config;
use crate::identify::base_parameters;
use crate::output::OutDir;
use crate::robot::{nominal, paper_model, parse_extras};
use crate::stages::Stages;
use aras_pipeline::diagnose::Additions;

/// The truth stored by the simulator in a sidecar (`truth.params`), if any.
pub fn sidecar_truth(sidecar: &aras_log::Sidecar) -> Option<aras_dyn::Params> {
    aras_dyn::Params::from_value(sidecar.truth.as_ref()?.get("params")?).ok()
}

/// What the intro of an identification report says about the log's
/// origin: a simulated log's truth gives parameter errors; a measured
/// log has neither truth nor noise ceiling.
pub fn truth_clause(truth: bool) -> &'static str {
    if truth {
        "; the sidecar holds the simulation's truth, so parameter errors are reported"
    } else {
        "; a measured log (its sidecar holds no simulation truth): the fitness is against the \
         measured torques, with no noise ceiling and no parameter errors"
    }
}

/// Log size above which `--streaming auto` streams: 256 MB, about 2 M rows
/// of a 9-column log (≈ 130 bytes per row), whose in-memory stacked
/// regressor alone would take ≈ 1.3 GB.
pub const STREAMING_BYTES: u64 = 256 << 20;

/// Whether `identify` streams the log (`--streaming`).
pub fn streams(args: &IdentifyArgs) -> Result<bool> {
    streams_log(args.streaming, &args.data, STREAMING_BYTES)
}

/// Whether a command streams `log` in `mode`: `auto` does for files larger
/// than `auto_bytes`.
pub fn streams_log(mode: StreamingMode, log: &std::path::Path, auto_bytes: u64) -> Result<bool> {
    Ok(match mode {
        StreamingMode::On => true,
        StreamingMode::Off => false,
        StreamingMode::Auto => {
            std::fs::metadata(log)
                .with_context(|| format!("reading {}", log.display()))?
                .len()
                > auto_bytes
        }
    })
}

/// What both `identify` paths start from.
struct Setup {
    cfg: Config,
    out: OutDir,
    stages: Stages,
    nominal: Params,
    model: Model,
    geometry: Geometry,
}

/// Config, output directory, nominal robot and the model with the
/// requested extra effects.
fn setup(args: &IdentifyArgs, extras: &Additions) -> Result<Setup> {
    let loaded = super::load_config(&args.common)?;
    let cfg = loaded.config.clone();
    let sidecar = args.log.sidecar_of(&args.data);
    let out = OutDir::create(
        &args.out,
        args.common.force,
        &super::input_files(&args.common, &loaded, &[&args.data, &sidecar]),
    )?;
    let stages = Stages::new(args.common.quiet);
    let nominal = nominal(&cfg.robot, &loaded.dir)?;
    // The paper's model with the extra effects appended (their columns last).
    let model = extras.model(&paper_model(&nominal)?)?;
    let geometry = nominal.geometry()?;
    Ok(Setup {
        cfg,
        out,
        stages,
        nominal,
        model,
        geometry,
    })
}

/// Runs `identify`.
pub fn run(args: &IdentifyArgs) -> Result<()> {
    if let Some(urdf) = &args.urdf {
        return super::urdf::identify(args, urdf);
    }
    let extras = parse_extras(&args.effects)?;
    if streams(args)? {
        return run_streaming(args, &extras);
    }
    let Setup {
        cfg,
        out,
        mut stages,
        nominal,
        model,
        geometry,
    } = setup(args, &extras)?;
    let mut log = stages.run("read log", |_| super::load_log(&args.data, &args.log, &cfg))?;
    if let Some(d) = extras.torque_delay {
        log = aras_signal::delay_torque(&log, d)
            .with_context(|| format!("removing the time delay from {}", args.data.display()))?;
    }
    // The sidecar the reader took (`--sidecar`, else LOG.json beside the log).
    let truth = sidecar_truth(&log.sidecar);
    let base = stages.run("base parameters (58)", |_| {
        base_parameters(&model, &geometry, &cfg)
    })?;
    let intro = format!(
        "Identification of `{}` ({} rows, {:.1} s at {:.1} Hz){}{}.",
        args.data.display(),
        log.summary.rows,
        log.summary.duration_s,
        log.summary.sample_rate_hz,
        crate::robot::delay_clause(&extras),
        truth_clause(truth.is_some())
    );
    let summary = fit::run(
        FitInput {
            cfg: &cfg,
            nominal: &nominal,
            truth: truth.as_ref(),
            clean_torque: None,
            cross_validate: false,
            log: &log,
            period: args.log.period,
            design: None,
            base: &base,
            model: &model,
            command: "identify",
            seed: None,
            noise: None,
            reproducible: args.reproducible,
            intro,
        },
        &out,
        &mut stages,
    )?;
    let dir = out.commit()?;
    println!("{}", fit::terminal_table(&summary));
    println!("outputs in {}", dir.display());
    Ok(())
}

/// `identify` in bounded memory (`--streaming on`, or `auto` on a large log).
fn run_streaming(args: &IdentifyArgs, extras: &Additions) -> Result<()> {
    use super::identify_streaming::{fit_and_write, options, stream};
    let Setup {
        cfg,
        out,
        mut stages,
        nominal,
        model,
        geometry,
    } = setup(args, extras)?;
    // The streaming reader keeps no sidecar for us: find it for its truth,
    // as the reader does (a declared LOG.json, `--sidecar`, or none).
    let truth = aras_log::find_sidecar(Some(&args.data), &args.log.read_options(&cfg.log)?.sidecar)
        .ok()
        .and_then(|f| sidecar_truth(&f.sidecar));
    let base = stages.run("base parameters (58)", |_| {
        base_parameters(&model, &geometry, &cfg)
    })?;
    let opts = aras_pipeline::streaming::StreamingOptions {
        torque_delay: extras.torque_delay,
        ..options(args, &cfg, &nominal)?
    };
    let r = stages.run("stream log → least squares", |bar| {
        stream(&args.data, &model, &base, &opts, bar)
    })?;
    super::print_notes(&args.data, &r.log.notes);
    super::print_warnings(&args.data, &r.log.warnings);
    for f in &r.widths.fallback {
        eprintln!("note: {f}");
    }
    // The model with the widths refined on the averaged period, if any.
    let model = aras_pipeline::friction_width::with_widths(&model, r.widths.widths())?;
    let intro = format!(
        "Identification of `{}` ({} rows, streamed){}{}. {}",
        args.data.display(),
        r.samples_read,
        crate::robot::delay_clause(extras),
        truth_clause(truth.is_some()),
        r.widths.sentence()
    );
    let summary = fit_and_write(
        &r,
        &cfg,
        &nominal,
        truth.as_ref(),
        &base,
        &model,
        args.reproducible,
        &intro,
        &out,
        &mut stages,
    )?;
    let dir = out.commit()?;
    println!("{}", fit::terminal_table(&summary));
    println!("outputs in {}", dir.display());
    Ok(())
}
