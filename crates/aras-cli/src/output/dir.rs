//! A run's output directory: staged beside its target, swapped in at the end.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};

use super::lock::{OutputLock, Staging, sweep_leftovers, unique_sibling};
use super::manifest::{MANIFEST, Manifest, check_replaceable, remove_listed};
use super::{canonical, warn};

/// Refuses when one of `inputs` is `target` or inside it: replacing the
/// directory would delete or overwrite the run's own input.
fn refuse_inputs_inside(target: &Path, inputs: &[PathBuf]) -> Result<()> {
    let Some(t) = canonical(target) else {
        return Ok(());
    };
    for input in inputs {
        if let Some(i) = canonical(input)
            && i.starts_with(&t)
        {
            bail!(
                "the input {} is inside the output directory {}; replacing the directory \
                 would lose it. Choose an --out that does not contain the inputs \
                 (e.g. --out {}-results)",
                input.display(),
                target.display(),
                target.display()
            );
        }
    }
    Ok(())
}

/// Whether `dir` exists and holds anything (an unreadable one counts).
fn is_occupied(dir: &Path) -> bool {
    dir.exists()
        && fs::read_dir(dir)
            .map(|mut d| d.next().is_some())
            .unwrap_or(true)
}

/// The absolute form of `target`: canonical when it exists, else its
/// canonical parent joined with its name (`--out .`, `--out a/..` and
/// `--out ./a` all name one directory, and one lock).
pub(super) fn absolute(target: &Path) -> Result<PathBuf> {
    if let Some(t) = canonical(target) {
        return Ok(t);
    }
    let Some(name) = target.file_name() else {
        bail!(
            "{} cannot be an output; choose another --out",
            target.display()
        );
    };
    let parent = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let parent = canonical(parent).unwrap_or_else(|| parent.to_path_buf());
    Ok(parent.join(name))
}

/// A run's output directory, staged until [`OutDir::commit`].
pub struct OutDir {
    target: PathBuf,
    staging: Staging,
    force: bool,
    // Held until the directory is in place (dropped after the staging).
    _lock: OutputLock,
}

impl OutDir {
    /// Prepares to write into `target`, a run directory of this tool.
    ///
    /// Refused, before any work is done: another run writing `target`; a
    /// `target` that is a file; a `target` that is or contains one of
    /// `inputs`; an existing non-empty directory without `force`; with
    /// `force`, a directory without a manifest or holding anything its
    /// manifest does not list, or a listed file changed since it was
    /// written. What interrupted runs left beside `target` is cleaned up
    /// first (and said on stderr). Nothing is removed before
    /// [`OutDir::commit`].
    pub fn create(target: &Path, force: bool, inputs: &[PathBuf]) -> Result<Self> {
        if target.exists() && !target.is_dir() {
            bail!(
                "output path {} exists and is a file, not a directory written by aras; \
                 choose another --out",
                target.display()
            );
        }
        if target.exists() {
            refuse_inputs_inside(target, inputs)?;
        }
        let parent = match target.parent().filter(|p| !p.as_os_str().is_empty()) {
            Some(p) => p.to_path_buf(),
            None => PathBuf::from("."),
        };
        fs::create_dir_all(&parent)
            .with_context(|| format!("cannot create {}", parent.display()))?;
        let target = absolute(target)?;
        if target.parent().is_none() {
            bail!(
                "{} cannot be an output directory; choose another --out",
                target.display()
            );
        }
        let lock = OutputLock::acquire(&target)?;
        for note in sweep_leftovers(&target) {
            warn(&note);
        }
        if is_occupied(&target) {
            if !force {
                bail!(
                    "output directory {} already exists and is not empty; \
                     pass --force to replace it (only if aras wrote it) or choose another --out",
                    target.display()
                );
            }
            check_replaceable(&target)?;
        }
        let staging = Staging::create(&target)?;
        Ok(Self {
            target,
            staging,
            force,
            _lock: lock,
        })
    }

    /// Final location of the directory.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Path of `name` inside the staging directory (where files go until commit).
    pub fn path(&self, name: &str) -> PathBuf {
        self.staging.dir().join(name)
    }

    /// Writes a file into the run's directory.
    pub fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> Result<PathBuf> {
        let p = self.path(name);
        if let Some(dir) = p.parent() {
            fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        super::write_atomic(&p, bytes.as_ref())?;
        Ok(self.target.join(name))
    }

    /// Writes pretty JSON (with a trailing newline).
    pub fn write_json<T: serde::Serialize>(&self, name: &str, value: &T) -> Result<PathBuf> {
        let mut s = serde_json::to_string_pretty(value).context("cannot serialise JSON")?;
        s.push('\n');
        self.write(name, s)
    }

    /// Writes the manifest and swaps the staged directory into place.
    ///
    /// Without `force` nothing is ever replaced: a directory that appeared
    /// at the target during the run (another program's) stops the swap.
    /// With `force` the previous directory is checked again (files may
    /// have appeared or changed during the run), moved aside, and after the
    /// swap only the files its manifest lists are removed; when that fails
    /// (a read-only old output) the run still succeeds and a warning names
    /// the folder left behind. Whenever the results cannot be moved into
    /// place they are kept in a visible `NAME.unsaved-PID` beside the
    /// target, which the error names.
    pub fn commit(mut self) -> Result<PathBuf> {
        let manifest = Manifest::of_dir(self.staging.dir())?;
        manifest.write_to(&self.staging.dir().join(MANIFEST))?;
        let old = if is_occupied(&self.target) {
            if !self.force {
                let e = anyhow!(
                    "{} appeared while this run was working (written by another program); \
                     nothing was replaced",
                    self.target.display()
                );
                return Err(self.keep(e));
            }
            match check_replaceable(&self.target) {
                Ok(m) => Some(m),
                Err(e) => return Err(self.keep(e)),
            }
        } else {
            None
        };
        self.staging.swapping();
        let backup = match &old {
            Some(_) => {
                let b = unique_sibling(&self.target, "previous");
                if let Err(e) = fs::rename(&self.target, &b) {
                    let e = anyhow::Error::from(e).context(format!(
                        "cannot move the previous {} aside to {}",
                        self.target.display(),
                        b.display()
                    ));
                    return Err(self.keep(e));
                }
                Some(b)
            }
            None => {
                // An empty directory at the target is taken over.
                let _ = fs::remove_dir(&self.target);
                None
            }
        };
        if let Err(e) = fs::rename(self.staging.dir(), &self.target) {
            if let Some(b) = &backup {
                let _ = fs::rename(b, &self.target);
            }
            let e = anyhow::Error::from(e).context(format!(
                "cannot move the results into {} (did another program create it?)",
                self.target.display()
            ));
            return Err(self.keep(e));
        }
        self.staging.done();
        if let (Some(b), Some(m)) = (&backup, &old)
            && let Err(e) = remove_listed(b, m)
        {
            warn(&format!(
                "the new results are in {}; the previous ones were moved to {} and could not \
                 be removed ({e:#}): remove that folder by hand",
                self.target.display(),
                b.display()
            ));
        }
        Ok(self.target.clone())
    }

    /// Keeps the finished results where the user can move them, and says
    /// where in `e`.
    fn keep(&mut self, e: anyhow::Error) -> anyhow::Error {
        let at = self.staging.keep();
        e.context(format!(
            "the results were kept in {}; move them by hand",
            at.display()
        ))
    }
}
