//! Processed samples in a scratch file: a long log's processing output,
//! written once block by block and read back window by window, so that its
//! length costs disk space (the page cache), not memory.
//!
//! The file is created in a directory the caller chooses (the command line
//! uses its output's staging directory), under a name no other file has
//! (`aras_log::new_temp_file`, `create_new`: an existing file is never
//! opened, let alone overwritten), and removed when the last handle to it
//! is dropped. Records are sample by sample, [`CHANNELS`] little-endian
//! `f64` each, in the order of [`aras_signal::Samples`]' fields.

use crate::PipelineError;
use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use aras_ident::IdentError;
use aras_signal::Samples;

/// Numbers stored per sample: `t`, then `θ, θ̇, θ̈, X, Ẋ, Ẍ, τ` (two each).
pub const CHANNELS: usize = 15;

const RECORD: usize = CHANNELS * 8;

/// The channels of `s` in record order (every channel of
/// [`aras_signal::Samples`]). The samples are of a two-joint robot: the
/// processing refuses any other joint count for two coordinates.
pub(crate) fn channels(s: &Samples) -> [&Vec<f64>; CHANNELS] {
    let all: Vec<&Vec<f64>> = std::iter::once(&s.t)
        .chain(&s.theta)
        .chain(&s.theta_dot)
        .chain(&s.theta_ddot)
        .chain(&s.x)
        .chain(&s.x_dot)
        .chain(&s.x_ddot)
        .chain(&s.tau)
        .collect();
    all.try_into().unwrap_or_else(|a: Vec<_>| {
        panic!(
            "two-joint samples have {CHANNELS} channels, not {}",
            a.len()
        )
    })
}

/// [`channels`], to write.
pub(crate) fn channels_mut(s: &mut Samples) -> [&mut Vec<f64>; CHANNELS] {
    let Samples {
        t,
        theta,
        theta_dot,
        theta_ddot,
        x,
        x_dot,
        x_ddot,
        tau,
    } = s;
    for g in [
        &mut *theta,
        &mut *theta_dot,
        &mut *theta_ddot,
        &mut *x,
        &mut *x_dot,
        &mut *x_ddot,
        &mut *tau,
    ] {
        g.resize_with(2, Vec::new);
    }
    let all: Vec<&mut Vec<f64>> = std::iter::once(t)
        .chain(theta.iter_mut())
        .chain(theta_dot.iter_mut())
        .chain(theta_ddot.iter_mut())
        .chain(x.iter_mut())
        .chain(x_dot.iter_mut())
        .chain(x_ddot.iter_mut())
        .chain(tau.iter_mut())
        .collect();
    all.try_into()
        .unwrap_or_else(|_: Vec<_>| unreachable!("every group holds two channels"))
}

fn io(context: String, e: std::io::Error) -> IdentError {
    IdentError::external(context, e)
}

/// Writes a scratch file of samples; [`Self::finish`] makes it readable.
/// Dropped unfinished (an error on the way), it removes its file.
#[derive(Debug)]
pub struct SpoolWriter {
    file: Option<BufWriter<File>>,
    path: PathBuf,
    len: usize,
    record: Vec<u8>,
}

impl SpoolWriter {
    /// A new, empty scratch file in `dir` (which must exist), named
    /// `.aras-samples.PID-N.tmp` for the first `N` no file has
    /// ([`aras_log::new_temp_file`]).
    pub fn create_in(dir: &Path) -> Result<Self, PipelineError> {
        let (path, file) = aras_log::new_temp_file(&dir.join("aras-samples")).map_err(|e| {
            io(
                format!(
                    "creating a scratch file in {} (choose a writable directory with free \
                     space for about {RECORD} bytes per sample)",
                    dir.display()
                ),
                e,
            )
        })?;
        Ok(Self {
            file: Some(BufWriter::with_capacity(1 << 20, file)),
            path,
            len: 0,
            record: Vec::new(),
        })
    }

    /// Samples written so far.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True if nothing was written.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Appends samples `rows` of `s` (every channel must hold them).
    pub fn append(&mut self, s: &Samples, rows: Range<usize>) -> Result<(), PipelineError> {
        let ch = channels(s);
        if let Some(c) = ch.iter().position(|c| c.len() < rows.end) {
            return Err(IdentError::DimensionMismatch {
                what: "samples of a channel to spool",
                expected: rows.end,
                found: ch[c].len(),
                hint: "give processed samples with every channel filled",
            }
            .into());
        }
        let file = self.file.as_mut().ok_or(PipelineError::Internal(
            "a scratch file appended to after an earlier write error",
        ))?;
        self.record.clear();
        self.record.reserve(rows.len() * RECORD);
        for i in rows.clone() {
            for c in &ch {
                self.record.extend_from_slice(&c[i].to_le_bytes());
            }
        }
        file.write_all(&self.record)
            .map_err(|e| io(format!("writing {}", self.path.display()), e))?;
        self.len += rows.len();
        Ok(())
    }

    /// The written samples, readable by windows.
    pub fn finish(mut self) -> Result<SpooledSamples, PipelineError> {
        let writer = self.file.take().ok_or(PipelineError::Internal(
            "a scratch file finished after an earlier write error",
        ))?;
        let path = std::mem::take(&mut self.path);
        let file = writer
            .into_inner()
            .map_err(|e| io(format!("writing {}", path.display()), e.into_error()));
        let file = match file {
            Ok(f) => f,
            Err(e) => {
                let _ = std::fs::remove_file(&path);
                return Err(e.into());
            }
        };
        Ok(SpooledSamples {
            file: Mutex::new(file),
            path,
            len: self.len,
        })
    }
}

impl Drop for SpoolWriter {
    fn drop(&mut self) {
        if !self.path.as_os_str().is_empty() {
            drop(self.file.take());
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// Samples held in a scratch file ([`SpoolWriter`]); the file is removed
/// when this is dropped.
#[derive(Debug)]
pub struct SpooledSamples {
    file: Mutex<File>,
    path: PathBuf,
    len: usize,
}

impl SpooledSamples {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Where the file is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Samples `rows` into `out` (its channels replaced).
    pub fn read(&self, rows: Range<usize>, out: &mut Samples) -> Result<(), PipelineError> {
        if rows.start > rows.end || rows.end > self.len {
            return Err(IdentError::DimensionMismatch {
                what: "end of a window of spooled samples",
                expected: self.len,
                found: rows.end,
                hint: "read windows inside the record",
            }
            .into());
        }
        let n = rows.len();
        let mut bytes = vec![0u8; n * RECORD];
        {
            let mut f = self.file.lock().unwrap_or_else(|p| p.into_inner());
            f.seek(SeekFrom::Start((rows.start * RECORD) as u64))
                .and_then(|_| f.read_exact(&mut bytes))
                .map_err(|e| io(format!("reading {}", self.path.display()), e))?;
        }
        let mut ch = channels_mut(out);
        for c in ch.iter_mut() {
            c.clear();
            c.reserve(n);
        }
        for rec in bytes.chunks_exact(RECORD) {
            for (c, v) in ch.iter_mut().zip(rec.chunks_exact(8)) {
                let mut b = [0u8; 8];
                b.copy_from_slice(v);
                c.push(f64::from_le_bytes(b));
            }
        }
        Ok(())
    }
}

impl Drop for SpooledSamples {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}
