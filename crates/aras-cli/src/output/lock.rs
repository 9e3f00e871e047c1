//! One run at a time per output, and what interrupted runs leave behind.
//!
//! Every output path `DIR/NAME` (a run directory or a single file) is
//! guarded by an advisory lock on `DIR/.NAME.aras-lock`, held from the
//! first check to the swap: a second run aimed at the same output fails at
//! once, naming the first, instead of silently replacing its results. The
//! operating system releases the lock when a process dies, however it dies,
//! so a crash never leaves the output locked.
//!
//! Holding the lock also means that no live run is staging `NAME`: the
//! staging directories (`.NAME.staging-PID`) and moved-aside previous
//! outputs (`.NAME.previous-PID`) found then are an interrupted run's, and
//! [`sweep_leftovers`] cleans them up. Ctrl-C (and `SIGTERM`) removes the
//! run's own staging directory on the way out ([`clean_up_interrupted`]).

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, bail};

use super::manifest::{check_replaceable, remove_listed};

/// The lock of one output path, released (and its file removed) on drop.
#[derive(Debug)]
pub struct OutputLock {
    path: PathBuf,
    file: Option<fs::File>,
}

impl OutputLock {
    /// Takes the lock of the output `target` (an absolute path whose parent
    /// exists). Fails at once, naming the holder, when another run holds it.
    /// On a file system without advisory locks it goes on unlocked (the
    /// results are still never replaced without `--force`).
    pub fn acquire(target: &Path) -> Result<Self> {
        let path = sibling(target, "aras-lock");
        loop {
            let file = fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .with_context(|| format!("cannot create the lock file {}", path.display()))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(fs::TryLockError::WouldBlock) => {
                    let holder = fs::read_to_string(&path).unwrap_or_default();
                    let holder = holder.trim();
                    bail!(
                        "another aras run{} is writing {}: it holds the lock {}. Wait for it \
                         to finish, or choose another --out",
                        if holder.is_empty() {
                            String::new()
                        } else {
                            format!(" ({holder})")
                        },
                        target.display(),
                        path.display()
                    );
                }
                Err(fs::TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
                    return Ok(Self { path, file: None });
                }
                Err(fs::TryLockError::Error(e)) => {
                    return Err(e).with_context(|| format!("cannot lock {}", path.display()));
                }
            }
            // The previous holder removes the file as it lets go: a lock
            // taken on a file no longer at `path` guards nothing; retry.
            if !same_file(&file, &path) {
                continue;
            }
            let _ = file.set_len(0);
            let _ = writeln!(&file, "pid {}", std::process::id());
            register(&path, Leftover::File);
            return Ok(Self {
                path,
                file: Some(file),
            });
        }
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        if self.file.is_some() {
            // Removed while still held, so no one else can be holding it.
            if cfg!(unix) {
                let _ = fs::remove_file(&self.path);
            }
            unregister(&self.path);
        }
    }
}

#[cfg(unix)]
fn same_file(file: &fs::File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_: &fs::File, path: &Path) -> bool {
    path.exists()
}

/// `DIR/.NAME.{what}` for the output `DIR/NAME`.
pub(super) fn sibling(target: &Path, what: &str) -> PathBuf {
    let name = file_name(target);
    target.with_file_name(format!(".{name}.{what}"))
}

fn file_name(target: &Path) -> String {
    target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// A new sibling `DIR/.NAME.{what}-PID` (or `-PID-K`) that does not exist.
pub(super) fn unique_sibling(target: &Path, what: &str) -> PathBuf {
    let pid = std::process::id();
    let first = sibling(target, &format!("{what}-{pid}"));
    (1..)
        .map(|k| {
            if k == 1 {
                first.clone()
            } else {
                sibling(target, &format!("{what}-{pid}-{k}"))
            }
        })
        .find(|p| fs::symlink_metadata(p).is_err())
        .unwrap_or(first)
}

/// A visible `DIR/NAME.unsaved-PID` (or `-K`) that does not exist: where
/// finished results go when they cannot be moved into place, out of reach
/// of [`sweep_leftovers`].
fn unsaved_path(target: &Path) -> PathBuf {
    let name = file_name(target);
    let pid = std::process::id();
    (1..)
        .map(|k| {
            let suffix = if k == 1 {
                String::new()
            } else {
                format!("-{k}")
            };
            target.with_file_name(format!("{name}.unsaved-{pid}{suffix}"))
        })
        .find(|p| fs::symlink_metadata(p).is_err())
        .expect("an unused name")
}

/// Whether `rest` is `PID` or `PID-K` (the suffixes this tool appends).
fn is_pid_suffix(rest: &str) -> bool {
    let mut parts = rest.splitn(2, '-');
    let all_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    parts.next().is_some_and(all_digits) && parts.next().is_none_or(all_digits)
}

/// Cleans up what interrupted runs left beside the output `target`; call
/// with its [`OutputLock`] held. Returns one line per action for the user.
///
/// * `.NAME.staging-PID`: an unfinished run's staging; removed.
/// * `.NAME.previous-PID` (and `.NAME.previous`): a replaced output moved
///   aside. Put back when `target` is gone (the run stopped mid-swap), else
///   its listed files are removed, as the swap would have. When it holds
///   anything aras did not write, or cannot be removed, it stays and the
///   line says so: it never blocks the run.
/// * `.NAME.PID-K.tmp`: a temporary file of an atomic write; removed.
pub(super) fn sweep_leftovers(target: &Path) -> Vec<String> {
    let mut notes = Vec::new();
    let (Some(dir), name) = (target.parent(), file_name(target)) else {
        return notes;
    };
    let Ok(entries) = fs::read_dir(dir) else {
        return notes;
    };
    let staging = format!(".{name}.staging-");
    let previous = format!(".{name}.previous");
    let temp = format!(".{name}.");
    let mut found: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    found.sort();
    for p in found {
        let entry = file_name(&p);
        let Ok(meta) = fs::symlink_metadata(&p) else {
            continue;
        };
        if let Some(rest) = entry.strip_prefix(&staging)
            && is_pid_suffix(rest)
            && meta.is_dir()
        {
            match fs::remove_dir_all(&p) {
                Ok(()) => notes.push(format!(
                    "removed {}, the staging directory of an interrupted run",
                    p.display()
                )),
                Err(e) => notes.push(format!(
                    "could not remove {}, the staging directory of an interrupted run ({e}); \
                     remove it by hand",
                    p.display()
                )),
            }
        } else if let Some(rest) = entry.strip_prefix(&previous)
            && (rest.is_empty() || rest.strip_prefix('-').is_some_and(is_pid_suffix))
            && meta.is_dir()
        {
            notes.push(previous_output(&p, target));
        } else if let Some(rest) = entry.strip_prefix(&temp)
            && let Some(stem) = rest.strip_suffix(".tmp")
            && is_pid_suffix(stem)
            && meta.is_file()
            && fs::remove_file(&p).is_ok()
        {
            notes.push(format!(
                "removed {}, the temporary file of an interrupted write",
                p.display()
            ));
        }
    }
    notes
}

/// What to do with an output an interrupted run had moved aside.
fn previous_output(p: &Path, target: &Path) -> String {
    let manifest = match check_replaceable(p) {
        Ok(m) => m,
        Err(e) => {
            return format!(
                "kept {}, an earlier output moved aside by an interrupted run: {e:#}",
                p.display()
            );
        }
    };
    if fs::symlink_metadata(target).is_err() {
        return match fs::rename(p, target) {
            Ok(()) => format!(
                "restored {} from {}, where an interrupted run had moved it",
                target.display(),
                p.display()
            ),
            Err(e) => format!(
                "kept {}, an earlier output of {} moved aside by an interrupted run; it \
                 could not be put back ({e}): move it by hand",
                p.display(),
                target.display()
            ),
        };
    }
    match remove_listed(p, &manifest) {
        Ok(()) => format!(
            "removed {}, an earlier output an interrupted run had already replaced",
            p.display()
        ),
        Err(e) => format!(
            "kept {}, an earlier output moved aside by an interrupted run, which could not \
             be removed ({e:#}); remove it by hand",
            p.display()
        ),
    }
}

/// The staging directory of an output, `.NAME.staging-PID` beside it:
/// where a run writes until its outputs are moved into place. Dropped
/// before [`Staging::done`], it is removed with everything in it; until
/// [`Staging::swapping`] an interrupt removes it too.
pub(super) struct Staging {
    dir: PathBuf,
    target: PathBuf,
    done: bool,
}

impl Staging {
    /// Creates the staging directory of the output `target`.
    pub(super) fn create(target: &Path) -> Result<Self> {
        let dir = unique_sibling(target, "staging");
        fs::create_dir(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
        register(&dir, Leftover::Dir);
        Ok(Self {
            dir,
            target: target.to_path_buf(),
            done: false,
        })
    }

    /// The directory.
    pub(super) fn dir(&self) -> &Path {
        &self.dir
    }

    /// The outputs are being moved into place: from here an interrupt
    /// leaves the directory to the next run's sweep, as removing it
    /// mid-swap could lose both the old and the new outputs.
    pub(super) fn swapping(&self) {
        unregister(&self.dir);
    }

    /// The directory was moved into place or emptied: nothing to remove.
    pub(super) fn done(&mut self) {
        unregister(&self.dir);
        self.done = true;
    }

    /// Moves the finished outputs to a visible name no later run sweeps
    /// (`NAME.unsaved-PID`) and returns where they are (the staging
    /// directory itself if that move fails).
    pub(super) fn keep(&mut self) -> PathBuf {
        self.done();
        let kept = unsaved_path(&self.target);
        match fs::rename(&self.dir, &kept) {
            Ok(()) => kept,
            Err(_) => self.dir.clone(),
        }
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.done {
            let _ = fs::remove_dir_all(&self.dir);
            unregister(&self.dir);
        }
    }
}

/// What the interrupt handler removes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Leftover {
    /// A staging directory (removed with everything in it).
    Dir,
    /// A lock file.
    File,
}

static LIVE: Mutex<Vec<(PathBuf, Leftover)>> = Mutex::new(Vec::new());

/// Marks `path` as this run's, to remove if the run is interrupted.
fn register(path: &Path, what: Leftover) {
    if let Ok(mut v) = LIVE.lock() {
        v.push((path.to_path_buf(), what));
    }
}

/// `path` no longer needs removing on interrupt (done, or handed over).
fn unregister(path: &Path) {
    if let Ok(mut v) = LIVE.lock() {
        v.retain(|(p, _)| p != path);
    }
}

/// Removes this run's staging directories and lock files: for the binary's
/// Ctrl-C / `SIGTERM` handler, before it exits. An output already swapped
/// into place is not touched; one being swapped is left to the next run's
/// `sweep_leftovers`.
pub fn clean_up_interrupted() {
    let live = match LIVE.lock() {
        Ok(mut v) => std::mem::take(&mut *v),
        Err(_) => return,
    };
    for (p, what) in live {
        let _ = match what {
            Leftover::Dir => fs::remove_dir_all(&p),
            Leftover::File => fs::remove_file(&p),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pid_suffixes() {
        assert!(is_pid_suffix("123"));
        assert!(is_pid_suffix("123-4"));
        assert!(!is_pid_suffix(""));
        assert!(!is_pid_suffix("x"));
        assert!(!is_pid_suffix("12-"));
        assert!(!is_pid_suffix("12-3-4"));
        assert!(!is_pid_suffix("x.staging-123"));
    }
}
