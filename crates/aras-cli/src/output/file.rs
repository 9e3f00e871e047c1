//! Single-file outputs (`predict`, `excite`, `simulate`, `export-mjcf`,
//! `friction-predict`):
//! staged, placed without replacing anything unless asked, and recorded.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};

use super::lock::{OutputLock, Staging, sibling, sweep_leftovers};
use super::manifest::Manifest;
use super::{canonical, warn};

/// What a single-file output holds. `--force` replaces an existing file
/// only when the record beside it says this tool wrote it, as this kind,
/// and it is unchanged since.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// `aras predict`: a CSV `t,tau1,tau2`.
    Prediction,
    /// `aras predict --summary`: its figures as JSON (`"format": "aras-predict/1"`).
    PredictionSummary,
    /// `aras excite`: a trajectory JSON (`"format": "aras-fourier/1"`).
    Trajectory,
    /// `aras simulate`: a log and its sidecar (LOG.json), written together.
    SimulatedLog,
    /// `aras export-mjcf`: an MJCF file.
    Mjcf,
    /// `aras friction-predict`: a CSV `t,tau`.
    FrictionPrediction,
}

impl FileKind {
    /// The kind's name in the record ([`Manifest::kind`]).
    pub fn id(self) -> &'static str {
        match self {
            Self::Prediction => "prediction",
            Self::PredictionSummary => "prediction-summary",
            Self::Trajectory => "trajectory",
            Self::SimulatedLog => "simulated-log",
            Self::Mjcf => "mjcf",
            Self::FrictionPrediction => "friction-prediction",
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Self::Prediction => "a prediction CSV written by `aras predict`",
            Self::PredictionSummary => "a prediction summary written by `aras predict --summary`",
            Self::Trajectory => "a trajectory written by `aras excite`",
            Self::SimulatedLog => "a log written by `aras simulate` (with its sidecar LOG.json)",
            Self::Mjcf => "an MJCF file written by `aras export-mjcf`",
            Self::FrictionPrediction => "a prediction CSV written by `aras friction-predict`",
        }
    }

    /// The files an output at `target` consists of: itself, and for a
    /// simulated log its sidecar.
    fn files(self, target: &Path) -> Vec<PathBuf> {
        let mut v = vec![target.to_path_buf()];
        if self == Self::SimulatedLog {
            v.push(aras_log::sidecar_path(target));
        }
        v
    }
}

/// The record beside a single-file output `DIR/NAME`: `DIR/.NAME.aras-manifest.json`.
pub fn record_path(target: &Path) -> PathBuf {
    sibling(target, "aras-manifest.json")
}

fn name_of(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Checks that the existing `file` (one of the output `target`'s files)
/// is recorded as written by this tool, as `kind`, and unchanged.
fn check_own(target: &Path, file: &Path, kind: FileKind) -> Result<()> {
    let record = record_path(target);
    let why = |what: String| {
        anyhow!(
            "{} exists and {what}; --force replaces only files aras wrote. Move it \
             elsewhere or choose another --out",
            file.display()
        )
    };
    let Some(m) = Manifest::read_file(&record)? else {
        return Err(why(format!(
            "there is no record that aras wrote it ({} is missing), so it is treated as yours",
            record.display()
        )));
    };
    if m.kind.as_deref() != Some(kind.id()) {
        return Err(why(format!("is not {}", kind.describe())));
    }
    let dir = target.parent().unwrap_or(Path::new("."));
    m.check_unchanged(dir, &name_of(file))
}

/// A single-file output being written: files go into a staging directory
/// beside the target (`.NAME.staging-PID`), and [`NewFile::commit`] moves
/// them into place and records their digests.
pub struct NewFile {
    target: PathBuf,
    kind: FileKind,
    force: bool,
    staging: Staging,
    _lock: OutputLock,
}

impl NewFile {
    /// Checks the output `path` before any work is done: its directory must
    /// exist; no other run may be writing it; none of its files may be one
    /// of `inputs`; an existing file is replaced only with `force` and only
    /// when this tool wrote it as `kind` and it is unchanged (for a
    /// simulated log this holds for the log and its sidecar LOG.json).
    pub fn create(path: &Path, force: bool, kind: FileKind, inputs: &[PathBuf]) -> Result<Self> {
        let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
        if let Some(dir) = parent.filter(|d| !d.is_dir()) {
            bail!(
                "cannot write {}: the directory {} does not exist; create it first or choose another --out",
                path.display(),
                dir.display()
            );
        }
        let target = super::dir::absolute(path)?;
        for file in kind.files(&target) {
            if file.is_dir() {
                bail!(
                    "{} is a directory; give a file name to --out",
                    file.display()
                );
            }
            if let Some(out) = canonical(&file)
                && let Some(input) = inputs.iter().find(|i| canonical(i).as_ref() == Some(&out))
            {
                bail!(
                    "writing {} would overwrite the input {}; choose another --out",
                    file.display(),
                    input.display()
                );
            }
        }
        let lock = OutputLock::acquire(&target)?;
        for note in sweep_leftovers(&target) {
            warn(&note);
        }
        for file in kind.files(&target) {
            if fs::symlink_metadata(&file).is_err() {
                continue;
            }
            if !force {
                bail!(
                    "{} already exists; pass --force to replace it (only if aras wrote it) or choose another --out",
                    file.display()
                );
            }
            check_own(&target, &file, kind)?;
        }
        let staging = Staging::create(&target)?;
        Ok(Self {
            target,
            kind,
            force,
            staging,
            _lock: lock,
        })
    }

    /// Where to write the output until [`NewFile::commit`] (inside the
    /// staging directory, with the target's file name; a simulated log's
    /// sidecar goes beside it, as [`aras_log::sidecar_path`] says).
    pub fn path(&self) -> PathBuf {
        self.staging.dir().join(name_of(&self.target))
    }

    /// Writes the output's bytes (atomically) into [`NewFile::path`].
    pub fn write(&self, bytes: &[u8]) -> Result<()> {
        super::write_atomic(&self.path(), bytes)
    }

    /// Moves the staged files into place and writes the record of their
    /// digests. Without `force` an existing file is never replaced (a file
    /// that appeared during the run stops the commit); with it, a file is
    /// replaced only if it is still this tool's. When the files cannot be
    /// placed they are kept in a visible `NAME.unsaved-PID` directory, which
    /// the error names.
    pub fn commit(mut self) -> Result<PathBuf> {
        let files = self.kind.files(&self.target);
        let names: Vec<String> = files.iter().map(|f| name_of(f)).collect();
        let manifest = Manifest::of_files(self.staging.dir(), names.clone(), Some(self.kind.id()))
            .context("the output was not written completely")?;
        if self.force {
            for file in &files {
                if fs::symlink_metadata(file).is_ok()
                    && let Err(e) = check_own(&self.target, file, self.kind)
                {
                    return Err(self.keep(e));
                }
            }
        }
        self.staging.swapping();
        for (file, name) in files.iter().zip(&names) {
            if let Err(e) = place(&self.staging.dir().join(name), file, self.force) {
                return Err(self.keep(e));
            }
        }
        let _ = fs::remove_dir(self.staging.dir());
        self.staging.done();
        let record = record_path(&self.target);
        if Manifest::read_file(&record).is_ok() {
            if let Err(e) = manifest.write_to(&record) {
                warn(&format!(
                    "{} was written, but its record {} was not ({e:#}); a later --force \
                     will refuse to replace it",
                    self.target.display(),
                    record.display()
                ));
            }
        } else {
            warn(&format!(
                "{} was written; {} is not a record aras wrote, so it was left as it is and a \
                 later --force will refuse to replace the output",
                self.target.display(),
                record.display()
            ));
        }
        Ok(self.target.clone())
    }

    /// Keeps the staged files where the user can move them, and says
    /// where in `e`.
    fn keep(&mut self, e: anyhow::Error) -> anyhow::Error {
        let at = self.staging.keep();
        e.context(format!(
            "the output was kept in {}; move it by hand",
            at.display()
        ))
    }
}

/// Moves `staged` to `dest`. Without `replace`, atomically refuses an
/// existing `dest` (a hard link fails on an existing name); where the file
/// system has no hard links, checks and renames.
fn place(staged: &Path, dest: &Path, replace: bool) -> Result<()> {
    let exists = || {
        anyhow!(
            "{} appeared while this run was working (written by another program); nothing \
             was replaced",
            dest.display()
        )
    };
    if replace {
        return fs::rename(staged, dest)
            .with_context(|| format!("cannot move the output into {}", dest.display()));
    }
    match fs::hard_link(staged, dest) {
        Ok(()) => {
            let _ = fs::remove_file(staged);
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(exists()),
        Err(_) if fs::symlink_metadata(dest).is_ok() => Err(exists()),
        Err(_) => fs::rename(staged, dest)
            .with_context(|| format!("cannot move the output into {}", dest.display())),
    }
}
