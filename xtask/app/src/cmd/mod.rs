//! One module per command; [`fit`] is the shared tail of `pipeline` and
//! `identify` (processing → identification → validation → outputs).

pub mod diagnose;
pub mod excite;
pub mod fit;
pub mod identify;
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

/// Refuses to overwrite an existing file unless `force`.
pub fn check_new_file(path: &Path, force: bool) -> Result<()> {
    if path.exists() && !force {
        bail!(
            "{} already exists; pass --force to replace it or choose another --out",
            path.display()
        );
    }
    Ok(())
}
