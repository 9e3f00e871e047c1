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
