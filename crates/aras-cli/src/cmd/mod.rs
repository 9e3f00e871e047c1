//! One module per command; [`fit`] is the shared tail of `pipeline` and
//! `identify` (processing → identification → validation → outputs).

pub mod diagnose;
pub mod excite;
pub mod export_mjcf;
pub mod fit;
pub mod identify;
pub mod identify_streaming;
pub mod pipeline;
pub mod predict;
pub mod simulate;
pub mod validate;

use std::path::Path;

use anyhow::{Result, bail};

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

/// Refuses to overwrite an existing file unless `force`, and a file whose
/// directory does not exist (found before any work is done).
pub fn check_new_file(path: &Path, force: bool) -> Result<()> {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = parent.filter(|d| !d.is_dir()) {
        bail!(
            "cannot write {}: the directory {} does not exist; create it first or choose another --out",
            path.display(),
            dir.display()
        );
    }
    if path.exists() && !force {
        bail!(
            "{} already exists; pass --force to replace it or choose another --out",
            path.display()
        );
    }
    Ok(())
}

/// Prints the log reader's warnings (saturation, …) on stderr, even with
/// `--quiet`: they are about the data, not progress.
pub fn print_warnings(path: &Path, warnings: &[aras_signal::Warning]) {
    for w in warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
}
