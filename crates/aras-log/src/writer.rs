//! The one writer of the format: CSV and sidecar, each written atomically.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::{Columns, LogError, Sidecar};

/// The sidecar path of a log: the same path with extension `.json`
/// (`run.csv` → `run.json`), where [`read_log`](crate::read_log) looks for it.
pub fn sidecar_path(csv: &Path) -> PathBuf {
    csv.with_extension("json")
}

/// Writes `columns` to `csv` (header `t,theta1,…,thetaN,tau1,…,tauN` for
/// the `N = columns.theta.len()` joints, plus `dtheta1,…,ddthetaN` when the
/// columns hold logged derivatives) and `sidecar` to
/// [`sidecar_path`]`(csv)`.
///
/// Each file is written to a new temporary file beside it and renamed into
/// place, so a reader never sees half a log and no other file is touched. An
/// existing file at `csv` or its sidecar path is replaced: whether that is
/// allowed is the caller's decision (the `aras` tools replace only files they
/// wrote). Numbers use Rust's shortest
/// round-trip formatting: the reader gets back exactly these `f64`s, and the
/// same data always gives the same bytes. Columns of unequal lengths, or a
/// joint count that differs between channels, are an error; nothing is
/// written then.
pub fn write_log(csv: &Path, columns: &Columns, sidecar: &Sidecar) -> Result<(), LogError> {
    let n = columns.len();
    let joints = columns.theta.len();
    let derivatives = columns.theta_dot.iter().any(|c| !c.is_empty());
    let mut groups = vec![("theta", &columns.theta), ("tau", &columns.tau)];
    if derivatives {
        groups.extend([
            ("dtheta", &columns.theta_dot),
            ("ddtheta", &columns.theta_ddot),
        ]);
    }
    let invalid = |value: String, reason: String| LogError::InvalidOption {
        name: "columns",
        value,
        reason,
    };
    if joints == 0 {
        return Err(invalid(
            "theta: no channel".into(),
            "a log needs at least one joint".into(),
        ));
    }
    for (name, group) in &groups {
        if group.len() != joints {
            return Err(invalid(
                format!("{name}: {} channels", group.len()),
                format!("every channel group must have one column per joint ({joints})"),
            ));
        }
        if let Some((j, c)) = group.iter().enumerate().find(|(_, c)| c.len() != n) {
            return Err(invalid(
                format!("{name}{}: {} values", j + 1, c.len()),
                format!("every column must have as many values as `t` ({n})"),
            ));
        }
    }
    write_atomic(csv, |w| {
        write!(w, "t")?;
        for (name, _) in &groups {
            for j in 1..=joints {
                write!(w, ",{name}{j}")?;
            }
        }
        writeln!(w)?;
        for i in 0..n {
            write!(w, "{}", columns.t[i])?;
            for (_, group) in &groups {
                for c in group.iter() {
                    write!(w, ",{}", c[i])?;
                }
            }
            writeln!(w)?;
        }
        Ok(())
    })
    .map_err(|source| LogError::Write {
        path: csv.to_path_buf(),
        source,
    })?;
    let json = serde_json::to_string_pretty(sidecar).map_err(|e| LogError::SidecarWrite {
        path: sidecar_path(csv),
        source: e.into(),
    })?;
    let sidecar_file = sidecar_path(csv);
    write_atomic(&sidecar_file, |w| {
        w.write_all(json.as_bytes())?;
        w.write_all(b"\n")
    })
    .map_err(|source| LogError::Write {
        path: sidecar_file,
        source,
    })
}

/// Writes a file atomically: `write` fills a new temporary file beside `path`
/// (`.NAME.PID-N.tmp`, opened with `create_new`, so no existing file is ever
/// truncated), which is synced and renamed onto `path`. On any failure the
/// temporary file is removed and `path` is untouched. An existing file at
/// `path` is replaced: whether that is allowed is the caller's decision.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let (tmp, file) = new_temp_file(path)?;
    let mut w = std::io::BufWriter::new(file);
    let written = write(&mut w)
        .and_then(|()| w.into_inner().map_err(|e| e.into_error()))
        .and_then(|f| f.sync_all())
        .and_then(|()| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// A new file beside `path`, `.NAME.PID-N.tmp` for the first `N` no file
/// has (opened with `create_new`, for reading and writing), so no existing
/// file is ever opened: the temporary file of [`write_atomic`], or a
/// scratch file its caller removes.
pub fn new_temp_file(path: &Path) -> std::io::Result<(PathBuf, std::fs::File)> {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = path.with_file_name(format!(".{name}.{}-{n}.tmp", std::process::id()));
        match std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ReadOptions, read_log};

    fn columns(derivatives: bool) -> Columns {
        let t: Vec<f64> = (0..40).map(|i| i as f64 * 1e-3).collect();
        let f = |k: f64| {
            t.iter()
                .map(|v| (k * v).sin() * 0.3 + 1.0)
                .collect::<Vec<_>>()
        };
        let d = |k: f64| if derivatives { f(k) } else { Vec::new() };
        Columns {
            theta: vec![f(1.0), f(2.0)],
            tau: vec![f(3.0), f(4.0)],
            theta_dot: vec![d(5.0), d(6.0)],
            theta_ddot: vec![d(7.0), d(8.0)],
            t,
        }
    }

    /// What is written is read back bit for bit, sidecar included, and a
    /// ragged column is an error that writes nothing.
    #[test]
    fn written_logs_read_back_exactly() {
        let dir = aras_testkit::Scratch::new("log-writer");
        for derivatives in [false, true] {
            let path = dir.join(format!("run{derivatives}.csv"));
            let c = columns(derivatives);
            let mut sidecar = Sidecar {
                format: Some(crate::FORMAT.into()),
                truth: Some(serde_json::json!({"seed": 7})),
                ..Sidecar::default()
            };
            sidecar.sensors.counts_per_rev = Some(vec![4096.0, 16384.0]);
            sidecar.excitation.period_s = Some(0.02);
            write_log(&path, &c, &sidecar).unwrap();
            let log = read_log(&path, &ReadOptions::default()).unwrap();
            assert_eq!(
                (log.t.clone(), log.theta.clone(), log.tau.clone()),
                (c.t.clone(), c.theta.clone(), c.tau.clone())
            );
            assert_eq!(log.theta_dot.is_some(), derivatives);
            if derivatives {
                assert_eq!(log.theta_dot.unwrap(), c.theta_dot);
                assert_eq!(log.theta_ddot.unwrap(), c.theta_ddot);
            }
            assert_eq!(log.sidecar, sidecar);
            let text = std::fs::read_to_string(sidecar_path(&path)).unwrap();
            assert!(text.contains("4096,") || text.contains("4096\n"), "{text}");
        }
        // Any number of joints: three channels each, read back as three.
        let mut three = columns(true);
        for group in [
            &mut three.theta,
            &mut three.tau,
            &mut three.theta_dot,
            &mut three.theta_ddot,
        ] {
            let extra = group[1].iter().map(|v| 0.5 * v - 0.1).collect();
            group.push(extra);
        }
        let path = dir.join("three.csv");
        write_log(&path, &three, &Sidecar::default()).unwrap();
        let header = std::fs::read_to_string(&path).unwrap();
        assert!(
            header.starts_with(
                "t,theta1,theta2,theta3,tau1,tau2,tau3,dtheta1,dtheta2,dtheta3,\
                 ddtheta1,ddtheta2,ddtheta3\n"
            ),
            "{}",
            &header[..80]
        );
        let log = read_log(&path, &ReadOptions::default()).unwrap();
        assert_eq!(log.joints(), 3);
        assert_eq!((&log.theta, &log.tau), (&three.theta, &three.tau));
        assert_eq!(log.theta_ddot.as_ref(), Some(&three.theta_ddot));
        assert_eq!(log.summary.theta_range.len(), 3);
        // A reader told to expect two joints reads the first two and
        // ignores the third's columns, with a note.
        let opts = ReadOptions {
            joints: Some(2),
            ..ReadOptions::default()
        };
        let two = read_log(&path, &opts).unwrap();
        assert_eq!(two.theta, three.theta[..2].to_vec());
        assert!(
            two.notes.iter().any(|n| n.contains("theta3")),
            "{:?}",
            two.notes
        );
        // A file that merely looks like a temporary file is left alone.
        let bystander = dir.join("runfalse.csv.tmp");
        std::fs::write(&bystander, "mine").unwrap();
        write_log(
            &dir.join("runfalse.csv"),
            &columns(false),
            &Sidecar::default(),
        )
        .unwrap();
        assert_eq!(std::fs::read_to_string(&bystander).unwrap(), "mine");
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp") && n.starts_with('.'))
            .collect();
        assert!(left.is_empty(), "{left:?}");
        // A failing write leaves the target as it was and no temporary file.
        let target = dir.join("keep.txt");
        std::fs::write(&target, "before").unwrap();
        let e = write_atomic(&target, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "disk full");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "before");
        let mut ragged = columns(false);
        ragged.tau[1].pop();
        let path = dir.join("ragged.csv");
        let e = write_log(&path, &ragged, &Sidecar::default()).unwrap_err();
        assert!(e.to_string().contains("tau2: 39 values"), "{e}");
        assert!(!path.exists() && !sidecar_path(&path).exists());
        let temps = std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| {
                let n = e
                    .as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .into_owned();
                n.starts_with('.') && n.ends_with(".tmp")
            })
            .count();
        assert_eq!(temps, 0);
    }
}
