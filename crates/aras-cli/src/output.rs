//! Output directories and files that are never half-written, and never
//! replace anything the tool did not write.
//!
//! Every file is written to a temporary sibling and renamed into place, so
//! a reader sees the old file or the new one, never a torn one. A whole run
//! writes into a staging directory next to the target and swaps it in at the
//! end: an interrupted run leaves the previous outputs intact.
//!
//! A finished run directory carries a manifest, [`MANIFEST`], listing every
//! file the run wrote. An existing directory is replaced only with
//! `--force`, and only when everything in it is listed in its manifest:
//! a directory without one, with a file the manifest does not list, or
//! holding one of the run's inputs is refused, naming the file. Single-file
//! outputs are replaced with `--force` only when they are one of this
//! tool's outputs of the same kind ([`FileKind`]) and not an input.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Component, Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

/// Name of the manifest in every run directory the tool writes.
pub const MANIFEST: &str = ".aras-manifest.json";

/// Format tag of [`Manifest`].
pub const MANIFEST_FORMAT: &str = "aras-manifest/1";

/// Writes `bytes` to `path` atomically (`aras_log::write_atomic`: a new temp
/// file in the same directory, fsync, rename; no other file is touched).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    aras_log::write_atomic(path, |w| w.write_all(bytes))
        .with_context(|| format!("cannot write {}", path.display()))
}

/// The list of files a run wrote, stored as [`MANIFEST`] in its directory.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Always [`MANIFEST_FORMAT`].
    pub format: String,
    /// The tool and its version that wrote the directory, e.g. `aras 0.1.0`.
    pub tool: String,
    /// Paths of the files written, relative to the directory, with `/`
    /// separators (the manifest itself is not listed).
    pub files: Vec<String>,
}

impl Manifest {
    /// The manifest of the files under `dir` (recursively), as written now.
    pub fn of_dir(dir: &Path) -> Result<Self> {
        let mut files = Vec::new();
        let mut dirs = Vec::new();
        walk(dir, dir, &mut files, &mut dirs)?;
        files.retain(|f| f != MANIFEST);
        files.sort();
        Ok(Self {
            format: MANIFEST_FORMAT.into(),
            tool: format!("aras {}", env!("CARGO_PKG_VERSION")),
            files,
        })
    }

    /// Reads `dir`'s manifest: `None` when there is none. A listed path that
    /// is absolute or leaves the directory (`..`) is an error: such a
    /// manifest was not written by this tool and is never followed.
    pub fn read(dir: &Path) -> Result<Option<Self>> {
        let path = dir.join(MANIFEST);
        let text = match fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
        };
        let m: Self = serde_json::from_str(&text).with_context(|| {
            format!(
                "{} is not a manifest written by aras; move the directory's files \
                 elsewhere or choose another --out",
                path.display()
            )
        })?;
        if m.format != MANIFEST_FORMAT {
            bail!(
                "{}: unknown manifest format `{}` (expected `{MANIFEST_FORMAT}`); \
                 choose another --out",
                path.display(),
                m.format
            );
        }
        for f in &m.files {
            if !is_plain_relative(f) {
                bail!(
                    "{}: the listed path `{f}` is not inside the directory (absolute or with `..`); \
                     the manifest is not followed and nothing is replaced; choose another --out",
                    path.display()
                );
            }
        }
        Ok(Some(m))
    }
}

/// A relative path made only of normal components (no root, no `.`/`..`).
fn is_plain_relative(p: &str) -> bool {
    !p.is_empty()
        && !p.contains('\\')
        && Path::new(p)
            .components()
            .all(|c| matches!(c, Component::Normal(_)))
}

/// Files (as `/`-separated relative paths) and directories under `dir`.
/// Symbolic links count as files and are not followed.
fn walk(root: &Path, dir: &Path, files: &mut Vec<String>, dirs: &mut Vec<PathBuf>) -> Result<()> {
    for e in fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))? {
        let e = e.with_context(|| format!("cannot read {}", dir.display()))?;
        let p = e.path();
        let ty = e
            .file_type()
            .with_context(|| format!("cannot read {}", p.display()))?;
        if ty.is_dir() {
            dirs.push(p.clone());
            walk(root, &p, files, dirs)?;
        } else {
            let rel = p.strip_prefix(root).unwrap_or(&p);
            let parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            files.push(parts.join("/"));
        }
    }
    Ok(())
}

/// The absolute, symlink-free form of `p` if it exists.
fn canonical(p: &Path) -> Option<PathBuf> {
    fs::canonicalize(p).ok()
}

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

/// Checks that every entry of the existing run directory `target` is listed
/// in its manifest, so replacing it loses nothing the tool did not write.
fn check_replaceable(target: &Path) -> Result<Manifest> {
    let Some(manifest) = Manifest::read(target)? else {
        bail!(
            "output directory {} exists, is not empty and has no {MANIFEST}, so it was not \
             written by aras; --force replaces only directories aras wrote. Move its files \
             elsewhere or choose another --out",
            target.display()
        );
    };
    let mut files = Vec::new();
    let mut dirs = Vec::new();
    walk(target, target, &mut files, &mut dirs)?;
    let listed: BTreeSet<&str> = manifest.files.iter().map(String::as_str).collect();
    for f in &files {
        if f != MANIFEST && !listed.contains(f.as_str()) {
            bail!(
                "output directory {} holds {}, which aras did not write (it is not in {MANIFEST}); \
                 --force replaces only what aras wrote. Move that file elsewhere or choose another --out",
                target.display(),
                target.join(f).display()
            );
        }
    }
    // A directory is ours when it holds (at some depth) a listed file.
    for d in &dirs {
        let rel = d.strip_prefix(target).unwrap_or(d);
        let prefix: Vec<String> = rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        let prefix = prefix.join("/") + "/";
        if !files.iter().any(|f| f.starts_with(&prefix)) {
            bail!(
                "output directory {} holds the empty directory {}, which aras did not write; \
                 remove it or choose another --out",
                target.display(),
                d.display()
            );
        }
    }
    Ok(manifest)
}

/// Removes the files of `manifest` from `dir`, then the directories left
/// empty; anything else stays (and is reported in the error).
fn remove_listed(dir: &Path, manifest: &Manifest) -> Result<()> {
    for f in &manifest.files {
        let p = dir.join(f);
        match fs::remove_file(&p) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(e).with_context(|| format!("cannot remove {}", p.display())),
        }
    }
    let _ = fs::remove_file(dir.join(MANIFEST));
    let mut files = Vec::new();
    let mut dirs = Vec::new();
    walk(dir, dir, &mut files, &mut dirs)?;
    // Deepest first; `remove_dir` only removes empty directories.
    dirs.sort_by_key(|d| std::cmp::Reverse(d.components().count()));
    for d in dirs {
        let _ = fs::remove_dir(d);
    }
    fs::remove_dir(dir).with_context(|| {
        format!(
            "{} still holds files aras did not write; they were kept",
            dir.display()
        )
    })
}

/// A run's output directory, staged until [`OutDir::commit`].
pub struct OutDir {
    target: PathBuf,
    staging: PathBuf,
    committed: bool,
}

impl OutDir {
    /// Prepares to write into `target`, a run directory of this tool.
    ///
    /// Refused, before any work is done: a `target` that is a file; a
    /// `target` that is or contains one of `inputs`; an existing non-empty
    /// directory without `force`; with `force`, a directory without a
    /// manifest or holding anything its manifest does not list. Nothing is
    /// removed before [`OutDir::commit`].
    pub fn create(target: &Path, force: bool, inputs: &[PathBuf]) -> Result<Self> {
        if target.exists() {
            if !target.is_dir() {
                bail!(
                    "output path {} exists and is a file, not a directory written by aras; \
                     choose another --out",
                    target.display()
                );
            }
            refuse_inputs_inside(target, inputs)?;
            let non_empty = fs::read_dir(target)
                .with_context(|| format!("cannot read {}", target.display()))?
                .next()
                .is_some();
            if non_empty {
                if !force {
                    bail!(
                        "output directory {} already exists and is not empty; \
                         pass --force to replace it (only if aras wrote it) or choose another --out",
                        target.display()
                    );
                }
                check_replaceable(target)?;
            }
        }
        // Work on the absolute path: `--out .` or `--out dir/..` still have
        // a parent to stage in.
        let target = match canonical(target) {
            Some(t) => t,
            None => target.to_path_buf(),
        };
        let parent = target
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let Some(name) = target.file_name().map(|n| n.to_string_lossy().into_owned()) else {
            bail!(
                "{} cannot be an output directory; choose another --out",
                target.display()
            );
        };
        fs::create_dir_all(parent)
            .with_context(|| format!("cannot create {}", parent.display()))?;
        let staging = parent.join(format!(".{name}.staging-{}", std::process::id()));
        if staging.exists() {
            fs::remove_dir_all(&staging).ok();
        }
        fs::create_dir_all(&staging)
            .with_context(|| format!("cannot create {}", staging.display()))?;
        Ok(Self {
            target,
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

    /// Writes the manifest and swaps the staged directory into place.
    ///
    /// The previous directory, if any, is checked again (files may have
    /// appeared during the run), moved aside, and after the swap only the
    /// files its manifest lists are removed. If it now holds anything else,
    /// nothing is replaced and the results stay in the staging directory,
    /// whose path the error gives.
    pub fn commit(mut self) -> Result<PathBuf> {
        let manifest = Manifest::of_dir(&self.staging)?;
        let mut text = serde_json::to_string_pretty(&manifest).context("cannot serialise JSON")?;
        text.push('\n');
        write_atomic(&self.staging.join(MANIFEST), text.as_bytes())?;
        let backup = self.staging.with_extension("previous");
        let old = if self.target.exists()
            && fs::read_dir(&self.target)
                .map(|mut d| d.next().is_some())
                .unwrap_or(true)
        {
            match check_replaceable(&self.target) {
                Ok(m) => Some(m),
                Err(e) => {
                    // Keep the results: the user can move them by hand.
                    self.committed = true;
                    return Err(e.context(format!(
                        "the results were kept in {}",
                        self.staging.display()
                    )));
                }
            }
        } else {
            None
        };
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
        self.committed = true;
        if had_old {
            match &old {
                Some(m) => remove_listed(&backup, m)?,
                // An empty directory.
                None => {
                    let _ = fs::remove_dir(&backup);
                }
            }
        }
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

/// What a single-file output holds: `--force` replaces an existing file only
/// when it is of the same kind, i.e. one this tool writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// `aras predict`: a CSV whose header is `t,tau1,tau2`.
    Prediction,
    /// `aras excite`: a trajectory JSON (`"format": "aras-fourier/1"`).
    Trajectory,
    /// `aras simulate`: a log whose sidecar (LOG.json) holds the simulator's
    /// ground truth (`truth`), which only the simulator writes.
    SimulatedLog,
    /// `aras export-mjcf`: an MJCF file carrying the exporter's mark
    /// ([`aras_dyn::mjcf::GENERATOR_MARK`]) in its opening comment.
    Mjcf,
}

impl FileKind {
    /// Whether the existing file at `path` is an output of this kind.
    fn matches(self, path: &Path) -> bool {
        match self {
            Self::Prediction => fs::read(path)
                .map(|b| b.starts_with(b"t,tau1,tau2\n"))
                .unwrap_or(false),
            Self::Trajectory => json_of(path).is_some_and(|v| {
                v.get("format").and_then(|f| f.as_str()) == Some("aras-fourier/1")
            }),
            Self::SimulatedLog => aras_log::Sidecar::read(&aras_log::sidecar_path(path))
                .is_ok_and(|s| s.format.as_deref() == Some(aras_log::FORMAT) && s.truth.is_some()),
            Self::Mjcf => fs::read(path)
                .map(|b| {
                    let head = String::from_utf8_lossy(&b[..b.len().min(512)]).into_owned();
                    head.contains(aras_dyn::mjcf::GENERATOR_MARK)
                })
                .unwrap_or(false),
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Self::Prediction => "a prediction CSV written by `aras predict` (header t,tau1,tau2)",
            Self::Trajectory => "a trajectory written by `aras excite` (format aras-fourier/1)",
            Self::SimulatedLog => {
                "a log written by `aras simulate` (its sidecar LOG.json holds the simulator's truth)"
            }
            Self::Mjcf => "an MJCF file written by `aras export-mjcf`",
        }
    }
}

fn json_of(path: &Path) -> Option<serde_json::Value> {
    serde_json::from_str(&fs::read_to_string(path).ok()?).ok()
}

/// Checks a single-file output before any work is done: its directory must
/// exist; it must not be one of `inputs`; an existing file is replaced only
/// with `force` and only when it is an output of `kind`. For a simulated
/// log this holds for the log and for its sidecar (LOG.json).
pub fn check_new_file(path: &Path, force: bool, kind: FileKind, inputs: &[PathBuf]) -> Result<()> {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = parent.filter(|d| !d.is_dir()) {
        bail!(
            "cannot write {}: the directory {} does not exist; create it first or choose another --out",
            path.display(),
            dir.display()
        );
    }
    let mut written = vec![path.to_path_buf()];
    if kind == FileKind::SimulatedLog {
        written.push(aras_log::sidecar_path(path));
    }
    for file in &written {
        if !file.exists() {
            continue;
        }
        if file.is_dir() {
            bail!(
                "{} is a directory; give a file name to --out",
                file.display()
            );
        }
        let out = canonical(file);
        for input in inputs {
            if out.is_some() && canonical(input) == out {
                bail!(
                    "writing {} would overwrite the input {}; choose another --out",
                    file.display(),
                    input.display()
                );
            }
        }
        if !force {
            bail!(
                "{} already exists; pass --force to replace it (only if aras wrote it) or choose another --out",
                file.display()
            );
        }
        if !kind.matches(path) {
            bail!(
                "{} exists and is not {}; --force replaces only what aras wrote. \
                 Move it elsewhere or choose another --out",
                file.display(),
                kind.describe()
            );
        }
    }
    Ok(())
}
