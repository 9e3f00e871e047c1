//! Output directories and files that are never half-written.
//!
//! Every file is written to a temporary sibling and renamed into place, so
//! a reader sees the old file or the new one, never a torn one. A whole run
//! writes into a staging directory next to the target and swaps it in at the
//! end: an interrupted run leaves the previous outputs intact, and an
//! existing directory is only replaced with `--force`.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

/// Writes `bytes` to `path` atomically (temp file in the same directory, fsync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let write = || -> std::io::Result<()> {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    };
    if let Err(e) = write() {
        let _ = fs::remove_file(&tmp);
        return Err(e).with_context(|| format!("cannot write {}", path.display()));
    }
    Ok(())
}

/// A run's output directory, staged until [`OutDir::commit`].
pub struct OutDir {
    target: PathBuf,
    staging: PathBuf,
    committed: bool,
}

impl OutDir {
    /// Prepares to write into `target`. Refuses a non-empty existing
    /// directory unless `force`; nothing is removed before `commit`.
    pub fn create(target: &Path, force: bool) -> Result<Self> {
        if target.exists() {
            if !target.is_dir() {
                bail!(
                    "output path {} exists and is not a directory",
                    target.display()
                );
            }
            let non_empty = fs::read_dir(target)
                .with_context(|| format!("cannot read {}", target.display()))?
                .next()
                .is_some();
            if non_empty && !force {
                bail!(
                    "output directory {} already exists and is not empty; \
                     pass --force to replace it or choose another --out",
                    target.display()
                );
            }
        }
        let parent = target
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        fs::create_dir_all(parent)
            .with_context(|| format!("cannot create {}", parent.display()))?;
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        let staging = parent.join(format!(".{name}.staging-{}", std::process::id()));
        if staging.exists() {
            fs::remove_dir_all(&staging).ok();
        }
        fs::create_dir_all(&staging)
            .with_context(|| format!("cannot create {}", staging.display()))?;
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            committed: false,
        })
    }

    /// Final location of the directory.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Path of `name` inside the staging directory (where files go until commit).
    pub fn path(&self, name: &str) -> PathBuf {
        self.staging.join(name)
    }

    /// Writes a file into the run's directory.
    pub fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> Result<PathBuf> {
        let p = self.path(name);
        if let Some(dir) = p.parent() {
            fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        write_atomic(&p, bytes.as_ref())?;
        Ok(self.target.join(name))
    }

    /// Writes pretty JSON (with a trailing newline).
    pub fn write_json<T: serde::Serialize>(&self, name: &str, value: &T) -> Result<PathBuf> {
        let mut s = serde_json::to_string_pretty(value).context("cannot serialise JSON")?;
        s.push('\n');
        self.write(name, s)
    }

    /// Swaps the staged directory into place (the previous one, if any, is
    /// moved aside first and removed only after the swap succeeded).
    pub fn commit(mut self) -> Result<PathBuf> {
        let backup = self.staging.with_extension("previous");
        let had_old = self.target.exists();
        if had_old {
            fs::rename(&self.target, &backup).with_context(|| {
                format!("cannot move the previous {} aside", self.target.display())
            })?;
        }
        if let Err(e) = fs::rename(&self.staging, &self.target) {
            if had_old {
                let _ = fs::rename(&backup, &self.target);
            }
            return Err(e).with_context(|| {
                format!("cannot move the results into {}", self.target.display())
            });
        }
        if had_old {
            let _ = fs::remove_dir_all(&backup);
        }
        self.committed = true;
        Ok(self.target.clone())
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}
