//! The data sets' filtered regressor columns, chunk by chunk: memory per
//! chunk, not per log.
//!
//! Zero-phase filtering is not causal, so a chunk's filtered rows depend on
//! samples around it. Each chunk of `CHUNK` samples is computed on a window
//! widened by the filter's reach down to [`WINDOW_TOL`] of its impulse
//! response peak on both sides, filtered there, and only the chunk's own
//! rows are used: they equal the whole-record filter's rows to that
//! tolerance (relative to the column's scale). A window touching an end of
//! the record is padded exactly as the whole-record filter pads it. Period-averaged
//! records (one period, short) are filtered whole with the periodic
//! filter. A window's columns come from [`crate::prepare::columns_on`],
//! the same regressor step a whole log goes through in
//! [`crate::prepare::prepare`].

use aras_kin::{Geometry, KinematicSample};
use rayon::prelude::*;

use super::data::Dataset;
use crate::robot::filter_reach;
use aras_ident::IdentError;

/// Samples per chunk, a measured trade-off (`docs/scale.md`): a chunk's
/// window (the chunk plus the filter's reach each side, ≈ 1 700 samples at
/// 10 Hz and 1 kHz) holds ≈ 175 columns of both joints, ≈ 18 MB per lane
/// at 3072 samples. Against 4096, the peak memory of a 160 s diagnosis
/// falls from 167–191 to 93–96 MiB and of a 600 s one from 220–239 to
/// 160–168 MiB, for ≈ 8 % more time on the longer log (larger windows
/// leave the allocator more to hold).
pub(crate) const CHUNK: usize = 3072;

/// Accuracy of a chunk's filtered rows against the whole-record filter
/// (fraction of the impulse-response peak left at the window's edge).
pub(crate) const WINDOW_TOL: f64 = 1e-9;

/// Independent accumulation lanes (fixed, so results never depend on the
/// thread count).
pub(crate) const LANES: usize = 2;

/// How a data set is cut.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Plan {
    /// Samples of the record.
    pub n: usize,
    /// Extra samples each side of a chunk.
    pub reach: usize,
    /// Samples per chunk (the whole record when periodic).
    pub chunk: usize,
}

impl Plan {
    pub(crate) fn new(data: &Dataset) -> Result<Self, IdentError> {
        let n = data.len();
        if data.periodic || data.filter.is_none() {
            let chunk = if data.periodic { n } else { CHUNK };
            return Ok(Self { n, reach: 0, chunk });
        }
        let sos = data.filter.as_ref().ok_or(IdentError::InvalidSetting {
            name: "filter",
            value: 0.0,
            reason: "internal: a filtered data set without its filter",
        })?;
        let reach = filter_reach(sos, n.min(200_000), false, WINDOW_TOL)?;
        // A record shorter than a few windows is filtered whole.
        if n <= 4 * (CHUNK + 2 * reach) {
            return Ok(Self {
                n,
                reach: 0,
                chunk: n,
            });
        }
        Ok(Self {
            n,
            reach,
            chunk: CHUNK,
        })
    }

    /// Chunks `[a, b)` covering `[lo, hi)`.
    /// A last chunk shorter than half a chunk is joined to the one before,
    /// so every window is longer than the filter's edge padding.
    pub(crate) fn chunks(&self, lo: usize, hi: usize) -> Vec<(usize, usize)> {
        let mut out: Vec<(usize, usize)> = (lo..hi)
            .step_by(self.chunk.max(1))
            .map(|a| (a, (a + self.chunk).min(hi)))
            .collect();
        if out.len() >= 2 {
            let (a, b) = out[out.len() - 1];
            if b - a < self.chunk / 2 {
                out.pop();
                if let Some(last) = out.last_mut() {
                    last.1 = b;
                }
            }
        }
        out
    }

    /// The window `[a', b')` computed for chunk `[a, b)`.
    pub(crate) fn window(&self, a: usize, b: usize) -> (usize, usize) {
        (a.saturating_sub(self.reach), (b + self.reach).min(self.n))
    }
}

/// The kinematics of the window `[lo, hi)` of `data`, evaluated once per
/// window and shared by every model whose columns are built on it.
pub(crate) fn window_kinematics(
    geometry: &Geometry,
    data: &Dataset,
    lo: usize,
    hi: usize,
) -> Result<Vec<KinematicSample>, IdentError> {
    (lo..hi)
        .map(|i| {
            aras_kin::evaluate(geometry, &data.samples.task(i))
                .map_err(|e| IdentError::external(format!("kinematics of sample {i}"), e))
        })
        .collect()
}

/// The whole record's filtered torques per joint (two vectors: the
/// `time_delay` candidates look them up at shifted indices).
pub(crate) fn filtered_torques(data: &Dataset) -> Result<[Vec<f64>; 2], IdentError> {
    let run = |x: &[f64]| -> Result<Vec<f64>, IdentError> {
        match &data.filter {
            None => Ok(x.to_vec()),
            Some(sos) => sos
                .filtfilt_record(x, data.periodic)
                .map_err(|e| IdentError::external("filtering the torques", e)),
        }
    };
    Ok([run(&data.samples.tau[0])?, run(&data.samples.tau[1])?])
}

/// Runs `work(state, a, b)` for every chunk `[a, b)` of `[lo, hi)`, chunk
/// `i` in lane `i % LANES` (lanes in parallel, each in order), and returns
/// the lanes' states in lane order for a deterministic merge.
pub(crate) fn in_lanes<T: Send>(
    plan: &Plan,
    lo: usize,
    hi: usize,
    init: impl Fn() -> T + Sync,
    work: impl Fn(&mut T, usize, usize) -> Result<(), IdentError> + Sync,
) -> Result<Vec<T>, IdentError> {
    let chunks = plan.chunks(lo, hi);
    (0..LANES)
        .into_par_iter()
        .map(|lane| {
            let mut st = init();
            for &(a, b) in chunks.iter().skip(lane).step_by(LANES) {
                work(&mut st, a, b)?;
            }
            Ok(st)
        })
        .collect()
}
