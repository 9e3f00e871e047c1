//! Parallel filtering and the velocity-reversal exclusion of joint-major
//! data of any joint count (`docs/processing.md`): the zero-phase low-pass
//! applied to every regressor column's joint blocks as to the torques, how
//! far it spreads a local error ([`filter_reach`]), its noise gain
//! ([`noise_gain`]), and the rows kept away from reversals
//! ([`reversal_mask`]).

use aras_ident::IdentError;
use aras_signal::{FILTER_LANES, Sos};
use faer::Mat;
use rayon::prelude::*;

fn external(context: &str, e: impl std::error::Error + Send + Sync + 'static) -> IdentError {
    IdentError::external(context, e)
}

fn invalid(context: &str, reason: impl Into<String>) -> IdentError {
    IdentError::InvalidData {
        context: context.to_owned(),
        reason: reason.into(),
    }
}

/// Applies `sos` forward and backward to each joint's block (rows `0..n`,
/// `n..2n`, …) of every column of the joint-major `w`, in parallel. Filtering acts column by
/// column, so selecting columns first (e.g. the base columns) and filtering
/// only those gives the same values as filtering everything.
pub fn filter_columns(
    w: &mut Mat<f64>,
    n: usize,
    sos: &Sos,
    periodic: bool,
) -> Result<(), IdentError> {
    filter_many_columns(&mut [w], n, sos, periodic)
}

/// [`filter_columns`] on several joint-major matrices of the same `n`
/// samples at once (e.g. the columns of several models on one window): the
/// joint blocks of all of them share the filter's `FILTER_LANES` lanes, so
/// narrow matrices (a model of two columns) do not leave lanes idle.
pub fn filter_many_columns(
    ws: &mut [&mut Mat<f64>],
    n: usize,
    sos: &Sos,
    periodic: bool,
) -> Result<(), IdentError> {
    // The joint count is the first matrix's rows over `n`; every matrix
    // must hold that many whole blocks.
    let joints = match ws.first() {
        Some(w) if n > 0 => (w.nrows() / n).max(1),
        _ => 1,
    };
    if let Some(w) = ws.iter().find(|w| w.nrows() != joints * n) {
        return Err(IdentError::DimensionMismatch {
            what: "joint-major regressor rows",
            expected: joints * n,
            found: w.nrows(),
            hint: "give every joint's block of n rows",
        });
    }
    if n == 0 {
        return Ok(());
    }
    if periodic {
        return ws
            .iter_mut()
            .try_for_each(|w| filter_columns_periodic(w, n, joints, sos));
    }
    // Every column's joint blocks as slices, filtered `FILTER_LANES`
    // at a time (bit-identical to one at a time). A block of zeros stays
    // zeros (a per-joint effect's column in the other joint's rows: most of
    // a diagnosis's candidate columns), so it is left out.
    let mut blocks: Vec<&mut [f64]> = Vec::new();
    for w in ws.iter_mut() {
        for col in w.col_iter_mut() {
            let col = col
                .try_as_col_major_mut()
                .ok_or_else(|| invalid("filtering", "a regressor column is not contiguous"))?
                .as_slice_mut();
            blocks.extend(col.chunks_mut(n).filter(|x| x.iter().any(|v| *v != 0.0)));
        }
    }
    // One job per thread, each reusing one interleaving buffer for its
    // groups (a buffer per group would be allocated and cleared afresh:
    // ≈ 11 MB each for a 10 kHz block).
    let groups = blocks.len().div_ceil(FILTER_LANES);
    let per_job = groups.div_ceil(rayon::current_num_threads()).max(1) * FILTER_LANES;
    blocks.par_chunks_mut(per_job).try_for_each(|job| {
        let mut scratch = Vec::new();
        job.chunks_mut(FILTER_LANES).try_for_each(|group| {
            sos.filtfilt_many_in_place(group, &mut scratch)
                .map_err(|e| external("filtering", e))
        })
    })
}

/// [`filter_columns`] of one period, circularly.
fn filter_columns_periodic(
    w: &mut Mat<f64>,
    n: usize,
    joints: usize,
    sos: &Sos,
) -> Result<(), IdentError> {
    let src = &*w;
    let filtered: Vec<Result<Vec<f64>, IdentError>> = (0..joints * src.ncols())
        .into_par_iter()
        .map(|k| {
            let (j, g) = (k / joints, k % joints);
            let x: Vec<f64> = (g * n..(g + 1) * n).map(|i| src[(i, j)]).collect();
            run_filter(sos, &x, true)
        })
        .collect();
    for (k, f) in filtered.into_iter().enumerate() {
        let (j, g) = (k / joints, k % joints);
        for (i, v) in f?.into_iter().enumerate() {
            w[(g * n + i, j)] = v;
        }
    }
    Ok(())
}

fn run_filter(sos: &Sos, x: &[f64], periodic: bool) -> Result<Vec<f64>, IdentError> {
    sos.filtfilt_record(x, periodic)
        .map_err(|e| external("filtering", e))
}

/// Marks every row of the joints in `all_rows` (one flag per joint) as
/// kept in the joint-major mask `keep` (one equal block per joint): the
/// joints fitted on every row (a refined Coulomb width) whatever
/// [`reversal_mask`] left out.
pub fn keep_every_row(keep: &mut [bool], all_rows: impl AsRef<[bool]>) {
    let all_rows = all_rows.as_ref();
    let n = keep.len() / all_rows.len().max(1);
    for (g, all) in all_rows.iter().enumerate() {
        if *all {
            keep[g * n..(g + 1) * n].fill(true);
        }
    }
}

/// The default reversal threshold (rad/s) of [`reversal_mask`] for
/// identification and diagnosis alike: a joint's rows with `|θ̇_j|` below it
/// are left out where its Coulomb law is the sign law (49). At 0.2 rad/s a
/// Stribeck hump of `v_s ≲ 0.1` rad/s and a presliding regime lie inside
/// the band, and the robot's designed excitation keeps ≈ 90 % of its rows.
pub const DEFAULT_MIN_SPEED: f64 = 0.2;

/// The default reach of the exclusion on a log the parameters are fitted
/// on: widened by the zero-phase filter's impulse response down to this
/// fraction of its peak ([`filter_reach`]; 253 samples at 10 Hz and
/// 1 kHz), so that the misfit a reversal spreads through the filter is
/// left out too.
pub const DEFAULT_REVERSAL_REACH: f64 = 1e-3;

/// The default reach on validation logs: the filter's main lobe only, so
/// that fast validation motions (at 2.5 Hz the joints reverse every 0.2 s)
/// keep rows.
pub const DEFAULT_VALIDATION_REACH: f64 = 0.5;

/// Rows to keep away from velocity reversals: joint `j`'s row of sample `i`
/// is dropped if `|θ̇_j| < v_min` at any sample within `guard` samples of
/// `i` (circularly when `periodic`). Joint-major mask (one block of `n`
/// rows per joint of `theta_dot`).
///
/// Why: the paper's Coulomb term `Fc sign(θ̇)` (49) is the one part of the
/// model that is wrong on any real drive near a reversal (stiction,
/// pre-sliding, Stribeck; the simulator's `tanh(θ̇/w)`), and the measured
/// `θ̇` is least reliable exactly there, so `sign(θ̇)` may even have the
/// wrong sign. Friction acts per joint, so only that joint's equation is
/// affected. `guard` should cover the zero-phase filter's impulse response
/// ([`filter_reach`]) when the data were filtered, because filtering spreads
/// the mismatch in time.
pub fn reversal_mask(
    theta_dot: &[Vec<f64>],
    v_min: f64,
    guard: usize,
    periodic: bool,
) -> Result<Vec<bool>, IdentError> {
    if !(v_min.is_finite() && v_min >= 0.0) {
        return Err(IdentError::InvalidSetting {
            name: "reversal velocity threshold",
            value: v_min,
            reason: "give a finite speed ≥ 0 in rad/s (0 keeps every row)",
        });
    }
    let joints = theta_dot.len();
    let n = theta_dot.first().map_or(0, Vec::len);
    if let Some((j, v)) = theta_dot.iter().enumerate().find(|(_, v)| v.len() != n) {
        return Err(IdentError::DimensionMismatch {
            what: if j == 1 {
                "θ̇2 samples"
            } else {
                "samples of a joint rate θ̇"
            },
            expected: n,
            found: v.len(),
            hint: "give every joint's rates for the same samples",
        });
    }
    // Each slow sample excludes the window [i − guard, i + guard]; windows
    // are marked in a difference array and resolved by one prefix sum, so
    // the cost is O(n) whatever the guard (the filter's reach grows with the
    // sampling rate: thousands of samples at 10 kHz).
    let mut keep = vec![true; joints * n];
    let mut cover = vec![0i64; n + 1];
    for j in 0..joints {
        cover.iter_mut().for_each(|c| *c = 0);
        let mut mark = |lo: usize, hi: usize| {
            cover[lo] += 1;
            cover[hi + 1] -= 1;
        };
        for (i, v) in theta_dot[j].iter().enumerate() {
            if !v.is_finite() {
                return Err(IdentError::InvalidSetting {
                    name: "joint rate θ̇",
                    value: *v,
                    reason: "every joint rate must be finite",
                });
            }
            if v.abs() >= v_min {
                continue;
            }
            let lo = i as i64 - guard as i64;
            let hi = i as i64 + guard as i64;
            let last = n as i64 - 1;
            if periodic && hi - lo >= last {
                mark(0, n - 1);
            } else if periodic && lo < 0 {
                mark((lo + n as i64) as usize, n - 1);
                mark(0, hi as usize);
            } else if periodic && hi > last {
                mark(lo as usize, n - 1);
                mark(0, (hi - n as i64) as usize);
            } else {
                mark(lo.max(0) as usize, hi.min(last) as usize);
            }
        }
        let mut run = 0;
        for (k, c) in cover[..n].iter().enumerate() {
            run += c;
            keep[j * n + k] = run == 0;
        }
    }
    Ok(keep)
}

/// Half-length (samples) of the zero-phase filter's impulse response down to
/// `tol` of its peak, on a record of `n` samples (circular when
/// `periodic`): how far filtering spreads a local model error.
pub fn filter_reach(sos: &Sos, n: usize, periodic: bool, tol: f64) -> Result<usize, IdentError> {
    let (impulse, centre) = settled_impulse(sos, n, periodic)?;
    let n = impulse.len();
    let peak = impulse.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let reach = impulse
        .iter()
        .enumerate()
        .filter(|(_, v)| v.abs() > tol * peak)
        .map(|(i, _)| {
            let d = i.abs_diff(centre);
            if periodic { d.min(n - d) } else { d }
        })
        .max()
        .unwrap_or(0);
    Ok(reach)
}

/// Noise power gain `Σ h_k²` of the zero-phase filter (`h` its impulse
/// response): white noise of variance `σ²` leaves the filter with variance
/// `g σ²`, strongly correlated over about `1/g` samples.
pub fn noise_gain(sos: &Sos, n: usize, periodic: bool) -> Result<f64, IdentError> {
    Ok(settled_impulse(sos, n, periodic)?
        .0
        .iter()
        .map(|v| v * v)
        .sum())
}

/// The filter's impulse response at the centre of a record of `n` samples
/// (circular when `periodic`), with the index of its centre. Away from the
/// ends of a long record the response does not depend on its length: a
/// record of 4096 samples (doubled until the response has died out to 1e-9
/// of its peak at its ends) gives the same values as the whole record at a
/// fraction of the cost and memory. A period is circular: its length is
/// part of the answer.
fn settled_impulse(sos: &Sos, n: usize, periodic: bool) -> Result<(Vec<f64>, usize), IdentError> {
    let mut m = if periodic { n } else { n.min(4096) };
    loop {
        let (h, c) = impulse_response(sos, m, periodic)?;
        let peak = h.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        let ends = h
            .first()
            .map_or(0.0, |v| v.abs())
            .max(h.last().map_or(0.0, |v| v.abs()));
        if m == n || ends <= 1e-9 * peak {
            return Ok((h, c));
        }
        m = (2 * m).min(n);
    }
}

fn impulse_response(sos: &Sos, n: usize, periodic: bool) -> Result<(Vec<f64>, usize), IdentError> {
    let centre = n / 2;
    let mut x = vec![0.0; n];
    if n == 0 {
        return Ok((x, 0));
    }
    x[centre] = 1.0;
    let h = sos
        .filtfilt_record(&x, periodic)
        .map_err(|e| external("impulse response of the filter", e))?;
    Ok((h, centre))
}
