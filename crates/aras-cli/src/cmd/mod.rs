//! One module per command; [`fit`] is the shared tail of `pipeline` and
//! `identify` (processing → identification → validation → outputs).

pub mod diagnose;
pub mod excite;
pub mod export_mjcf;
pub mod fit;
pub mod friction;
pub mod identify;
pub mod identify_streaming;
pub mod pipeline;
pub mod predict;
pub mod simulate;
pub mod urdf;
pub mod validate;

use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::cli::Common;
use crate::config::{Config, Loaded};

/// The configuration of `--config`, or the defaults.
pub fn load_config(common: &Common) -> Result<Loaded> {
    match &common.config {
        Some(p) => Ok(Config::load(p)?),
        None => Ok(Loaded {
            config: Config::default(),
            dir: ".".into(),
        }),
    }
}

/// The files a run reads that could sit in its output: the config file,
/// the parameter files it names (`robot.params`, `simulation.truth`) and
/// `extra` (logs, sidecars, parameter files of the command line). Outputs
/// that hold one of them are refused ([`crate::output`]).
pub fn input_files(common: &Common, loaded: &Loaded, extra: &[&Path]) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = extra.iter().map(|p| p.to_path_buf()).collect();
    v.extend(common.config.clone());
    let cfg = &loaded.config;
    if cfg.robot.params != "default" {
        v.push(loaded.dir.join(&cfg.robot.params));
    }
    if let Some(t) = &cfg.simulation.truth {
        v.push(loaded.dir.join(t));
    }
    v
}

/// Prints the log reader's notes on stderr (what was read and how: a bag's
/// topic, joints and message rate, a JSON beside the log not read as its
/// sidecar, ignored columns), even with `--quiet`, like the warnings.
pub fn print_notes(path: &Path, notes: &[String]) {
    for n in notes {
        eprintln!("note: {}: {n}", path.display());
    }
}

/// Prints the log reader's warnings (saturation, …) on stderr, even with
/// `--quiet`: they are about the data, not progress.
pub fn print_warnings(path: &Path, warnings: &[aras_log::Warning]) {
    for w in warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
}

/// Reads a log the way every command does: the reader with `args`' options
/// and the config's `[log]` section, then the glitch check and, if asked,
/// resampling onto a uniform grid. Warnings are printed here.
pub fn load_log(path: &Path, args: &crate::cli::LogArgs, cfg: &Config) -> Result<aras_log::Log> {
    load_log_of(path, args, cfg, 2)
}

/// [`load_log`] of a robot with `joints` joints (a URDF robot's).
pub fn load_log_of(
    path: &Path,
    args: &crate::cli::LogArgs,
    cfg: &Config,
    joints: usize,
) -> Result<aras_log::Log> {
    use anyhow::Context;
    let settings = args.settings(&cfg.log);
    let options = aras_log::ReadOptions {
        joints: Some(joints),
        ..args.read_options(&cfg.log)?
    };
    let log = aras_log::read_log(path, &options)
        .with_context(|| format!("reading {}", path.display()))?;
    let (mut log, _) = aras_log::apply_glitches(log, &settings.glitch_options())
        .with_context(|| format!("reading {}", path.display()))?;
    if settings.resample {
        let opts = aras_signal::ResampleOptions {
            max_gap_s: settings.max_gap_s,
        };
        log = aras_signal::resample_log(&log, &opts)
            .with_context(|| format!("resampling {}", path.display()))?
            .0;
    }
    print_notes(path, &log.notes);
    print_warnings(path, &log.warnings);
    Ok(log)
}

/// The reader's options for a streamed log. The streaming reader keeps no
/// whole log, so it can neither look for glitches nor resample: asking for
/// either (`--resample`, `--glitches refuse|drop|repair`) is refused rather
/// than ignored, and with the default (`warn`) a note says the log is not
/// checked.
pub fn streaming_read_options(
    args: &crate::cli::LogArgs,
    cfg: &Config,
) -> Result<aras_log::ReadOptions> {
    let s = args.settings(&cfg.log);
    if s.resample {
        anyhow::bail!(
            "--resample (log.resample) needs the whole log in memory: use --streaming off"
        );
    }
    if s.glitches == aras_log::GlitchAction::Warn {
        eprintln!(
            "note: streamed logs are not checked for isolated glitches; run with \
             --streaming off to check them",
        );
    }
    if matches!(
        s.glitches,
        aras_log::GlitchAction::Drop
            | aras_log::GlitchAction::Repair
            | aras_log::GlitchAction::Refuse
    ) {
        anyhow::bail!(
            "--glitches {} (log.glitches) needs the whole log in memory: use --streaming off \
             (streamed logs are not checked for glitches)",
            s.glitches.name()
        );
    }
    args.read_options(&cfg.log)
}
