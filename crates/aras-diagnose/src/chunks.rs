//! The data sets chunk by chunk: their filtered regressor columns,
//! filtered torques and reversal exclusion, with memory per chunk, not per
//! log.
//!
//! Zero-phase filtering is not causal, so a chunk's filtered rows depend on
//! samples around it. Each chunk of `CHUNK` samples is read
//! ([`Dataset::read`], from memory or a scratch file) with a window
//! widened on both sides by the filter's reach down to [`WINDOW_TOL`] of
//! its impulse response peak (or the reversal exclusion's widening, if
//! larger) plus the largest torque shift of the delay candidates; the
//! window's columns and torques are filtered there and only the chunk's
//! own rows are used: they equal the whole-record filter's rows to that
//! tolerance (relative to the column's scale), and the chunk's exclusion
//! equals the whole record's exactly. A window touching an end of the
//! record is padded exactly as the whole-record filter pads it.
//! Period-averaged records (one period, short) are filtered whole with the
//! periodic filter. A window's columns come from the robot model
//! ([`crate::DiagnosisModel`]), unfiltered, and are filtered here.

use aras_signal::Samples;
use rayon::prelude::*;

use crate::data::Dataset;
use crate::filtering::{filter_reach, keep_every_row, reversal_mask};
use aras_ident::IdentError;

/// Samples per chunk, a measured trade-off (`docs/scale.md`): a chunk's
/// window (the chunk plus the filter's reach each side, ≈ 1 700 samples at
/// 10 Hz and 1 kHz) holds ≈ 175 columns of both joints of the ARAS-Diamond, ≈ 18 MB per lane
/// at 3072 samples. Against 4096, the peak memory of a 160 s diagnosis
/// falls from 167–191 to 93–96 MiB and of a 600 s one from 220–239 to
/// 160–168 MiB, for ≈ 8 % more time on the longer log (larger windows
/// leave the allocator more to hold). Narrow passes (a refinement's) are no faster with longer chunks
/// (9 216–16 384 samples: 1 h at 1 kHz, no gain within the machine's
/// noise).
pub(crate) const CHUNK: usize = 3072;

/// Accuracy of a chunk's filtered rows against the whole-record filter
/// (fraction of the impulse-response peak left at the window's edge).
pub(crate) const WINDOW_TOL: f64 = 1e-9;

/// Independent accumulation lanes (fixed, so results never depend on the
/// thread count).
pub(crate) const LANES: usize = 2;

/// How a data set is cut, and which of its rows fits use.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    /// Samples of the record.
    pub n: usize,
    /// Extra samples each side of a chunk.
    pub reach: usize,
    /// Samples per chunk (the whole record when periodic).
    pub chunk: usize,
    /// Joint `j`'s rows with `|θ̇_j|` below this (rad/s) are left out …
    pub min_speed: f64,
    /// … widened by this many samples each side (the filter's reach down
    /// to the data set's tolerance, [`filter_reach`]; 0 unfiltered) …
    pub guard: usize,
    /// … except on the joints marked here, whose every row is used
    /// ([`crate::EngineOptions::all_rows`]; empty: none).
    pub all_rows: Vec<bool>,
}

impl Plan {
    /// The plan of `data` whose rows are kept away from velocity reversals
    /// (`min_speed`, widened to `reach_tol` of the filter's peak) and whose
    /// torques are read up to `max_shift` samples from a row.
    pub(crate) fn new(
        data: &Dataset,
        min_speed: f64,
        reach_tol: f64,
        max_shift: usize,
    ) -> Result<Self, IdentError> {
        let n = data.len();
        let guard = match &data.filter {
            Some(sos) => filter_reach(sos, n, data.periodic, reach_tol)?,
            None => 0,
        };
        let whole = Self {
            n,
            reach: 0,
            chunk: n,
            min_speed,
            guard,
            all_rows: Vec::new(),
        };
        if data.periodic {
            return Ok(whole);
        }
        let filter_reach = match &data.filter {
            Some(sos) => filter_reach(sos, n, false, WINDOW_TOL)?,
            None => 0,
        };
        let reach = filter_reach.max(guard) + max_shift;
        // A record shorter than a few windows is filtered whole.
        if n <= 4 * (CHUNK + 2 * reach) {
            return Ok(whole);
        }
        Ok(Self {
            reach,
            chunk: CHUNK,
            ..whole
        })
    }

    /// The same plan with every row of the joints in `all_rows` used.
    pub(crate) fn with_all_rows(self, all_rows: Vec<bool>) -> Self {
        Self { all_rows, ..self }
    }

    /// Chunks `[a, b)` covering `[lo, hi)`. A last chunk shorter than half
    /// a chunk is joined to the one before, so every window is longer than
    /// the filter's edge padding.
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

/// One chunk's window of a data set: its samples, filtered torques and
/// reversal exclusion, indexed by the record's sample numbers.
#[derive(Debug, Default)]
pub(crate) struct Window {
    /// Record index of the window's first sample.
    pub lo: usize,
    /// Samples `lo..lo + len`.
    pub samples: Samples,
    /// Torques low-passed by the data set's filter (as the columns are),
    /// per joint.
    pub tau: Vec<Vec<f64>>,
    /// Joint-major: true where the row is used by fits and scores.
    keep: Vec<bool>,
    /// The window is a whole period-averaged record: fractional torque
    /// shifts are exact Fourier shifts ([`aras_signal::delayed_periodic`]).
    periodic: bool,
    /// Those shifts, per joint and delay, computed once per window.
    shifted: std::sync::Mutex<Vec<(usize, u64, Vec<f64>)>>,
}

impl Window {
    /// Samples in the window.
    pub(crate) fn len(&self) -> usize {
        self.samples.len()
    }

    /// Reads `[lo, hi)` of `data` (reusing this window's buffers) and
    /// filters and masks it as `plan` says.
    fn load(
        &mut self,
        data: &Dataset,
        plan: &Plan,
        lo: usize,
        hi: usize,
    ) -> Result<(), IdentError> {
        data.read(lo..hi, &mut self.samples)?;
        self.lo = lo;
        self.periodic = data.periodic;
        match self.shifted.get_mut() {
            Ok(cache) => cache,
            Err(poisoned) => poisoned.into_inner(),
        }
        .clear();
        let joints = self.samples.tau.len();
        self.tau.resize_with(joints, Vec::new);
        for g in 0..joints {
            self.tau[g] = match &data.filter {
                None => self.samples.tau[g].clone(),
                Some(sos) => sos
                    .filtfilt_record(&self.samples.tau[g], data.periodic)
                    .map_err(|e| IdentError::external("filtering the torques", e))?,
            };
        }
        self.keep = reversal_mask(
            &self.samples.theta_dot,
            plan.min_speed,
            plan.guard,
            data.periodic,
        )?;
        if !plan.all_rows.is_empty() {
            keep_every_row(&mut self.keep, &plan.all_rows);
        }
        Ok(())
    }

    /// Whether joint `g`'s row `i` (record index) is used.
    pub(crate) fn kept(&self, g: usize, i: usize) -> bool {
        self.keep[g * self.len() + i - self.lo]
    }

    /// Joint `g`'s used rows (record indices) in `[a, b)`.
    pub(crate) fn rows(&self, g: usize, a: usize, b: usize) -> Vec<usize> {
        (a..b).filter(|&i| self.kept(g, i)).collect()
    }

    /// Joint `g`'s filtered torque `delay` samples after row `i`: a whole
    /// number of samples read as it is; a fraction interpolated
    /// ([`aras_signal::delayed_at`], the window's reach and the passes'
    /// range keep it inside), or on a period-averaged record shifted by its
    /// Fourier series ([`aras_signal::delayed_periodic`]), where the
    /// torques are not low-passed when the processing fitted a harmonic
    /// series and an interpolation would smooth their noise.
    pub(crate) fn shifted(&self, g: usize, i: usize, delay: f64) -> f64 {
        if !self.periodic || delay == delay.floor() {
            return aras_signal::delayed_at(&self.tau[g], i - self.lo, delay);
        }
        let key = delay.to_bits();
        let mut cache = match self.shifted.lock() {
            Ok(c) => c,
            Err(poisoned) => poisoned.into_inner(),
        };
        if let Some((_, _, y)) = cache.iter().find(|(j, d, _)| *j == g && *d == key) {
            return y[i - self.lo];
        }
        let y = aras_signal::delayed_periodic(&self.tau[g], delay);
        let v = y[i - self.lo];
        cache.push((g, key, y));
        v
    }
}

/// Runs `work(state, window, a, b)` for every chunk `[a, b)` of `[lo, hi)`
/// of `data`, chunk `i` in lane `i % LANES` (lanes in parallel, each in
/// order, each reading its windows into one buffer), and returns the
/// lanes' states in lane order for a deterministic merge.
pub(crate) fn in_lanes<T: Send>(
    data: &Dataset,
    plan: &Plan,
    (lo, hi): (usize, usize),
    init: impl Fn() -> T + Sync,
    work: impl Fn(&mut T, &Window, usize, usize) -> Result<(), IdentError> + Sync,
) -> Result<Vec<T>, IdentError> {
    let chunks = plan.chunks(lo, hi);
    (0..LANES)
        .into_par_iter()
        .map(|lane| {
            let mut st = init();
            let mut window = Window::default();
            for &(a, b) in chunks.iter().skip(lane).step_by(LANES) {
                let (wl, wh) = plan.window(a, b);
                window.load(data, plan, wl, wh)?;
                work(&mut st, &window, a, b)?;
            }
            Ok(st)
        })
        .collect()
}

/// Runs `work(window, a, b)` for every chunk `[a, b)` of `[lo, hi)` of
/// `data`, [`LANES`] chunks at a time in parallel, and hands the results to
/// `consume` in record order: for summaries that need the rows in order (a
/// spectrum, lagged products), with at most [`LANES`] chunks' results held.
pub(crate) fn in_order<P: Send>(
    data: &Dataset,
    plan: &Plan,
    (lo, hi): (usize, usize),
    work: impl Fn(&Window, usize, usize) -> Result<P, IdentError> + Sync,
    mut consume: impl FnMut(P) -> Result<(), IdentError>,
) -> Result<(), IdentError> {
    let chunks = plan.chunks(lo, hi);
    let mut windows: Vec<Window> = (0..LANES).map(|_| Window::default()).collect();
    for batch in chunks.chunks(LANES) {
        let pieces: Vec<P> = windows
            .par_iter_mut()
            .zip(batch)
            .map(|(window, &(a, b))| {
                let (wl, wh) = plan.window(a, b);
                window.load(data, plan, wl, wh)?;
                work(window, a, b)
            })
            .collect::<Result<_, _>>()?;
        for p in pieces {
            consume(p)?;
        }
    }
    Ok(())
}
