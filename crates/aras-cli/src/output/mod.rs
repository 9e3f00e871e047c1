//! Outputs that are never half-written, never replace anything the tool
//! did not write, and never race another run.
//!
//! Every file is written to a temporary sibling and renamed into place, so
//! a reader sees the old file or the new one, never a torn one. A whole run
//! ([`OutDir`]) and a single-file output ([`NewFile`]) are staged in a
//! directory beside the target and moved into place at the end: an
//! interrupted run leaves the previous outputs intact.
//!
//! What the tool wrote is recorded with each file's size and hash
//! ([`Manifest`]): [`MANIFEST`] inside a run directory, `.NAME.aras-manifest.json`
//! beside a single file. `--force` replaces only recorded files that are
//! still byte for byte what was written; a directory without a manifest,
//! with a file the manifest does not list, with a changed file, or holding
//! one of the run's inputs is refused, naming the file. Without `--force`
//! nothing is ever replaced, not even an output another run finished
//! meanwhile. One run at a time writes an output (an advisory lock, see
//! [`OutputLock`]); what interrupted runs left is cleaned up by the next.

mod dir;
mod file;
mod lock;
mod manifest;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

pub use dir::OutDir;
pub use file::{FileKind, NewFile, record_path};
pub use lock::{OutputLock, clean_up_interrupted};
pub use manifest::{Digest, MANIFEST, MANIFEST_FORMAT, Manifest};

/// Writes `bytes` to `path` atomically (`aras_log::write_atomic`: a new temp
/// file in the same directory, fsync, rename; no other file is touched).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    aras_log::write_atomic(path, |w| w.write_all(bytes))
        .with_context(|| format!("cannot write {}", path.display()))
}

/// The absolute, symlink-free form of `p` if it exists.
fn canonical(p: &Path) -> Option<PathBuf> {
    std::fs::canonicalize(p).ok()
}

/// A warning about the outputs, on stderr (also with `--quiet`: it is
/// about the user's files).
fn warn(msg: &str) {
    eprintln!("warning: {msg}");
}
