//! Adapter to the ARAS-Diamond crates: stacked regressors from `aras-dyn`'s
//! model and `aras-signal`'s samples, parallel filtering (`docs/processing.md`), the
//! SDP layout of the four links, and the way back into `aras-dyn`'s
//! parameter type.

use aras_dyn::{Effect, Model, Params};
use aras_kin::{Geometry, Motion, Workspace};
use aras_signal::{FILTER_LANES, Samples, Sos};
use faer::Mat;
use nalgebra::Vector2;
use rayon::prelude::*;

use aras_ident::{
    BaseParameters, ConsistentLs, DEFAULT_RANK_TOLERANCE, IdentError, RowGroups, SdpSolution,
};

/// A stacked, joint-major regressor with its torques: rows `0..N` are
/// joint 1, `N..2N` joint 2.
#[derive(Debug, Clone)]
pub struct Stacked {
    /// `2N × n` regressor.
    pub w: Mat<f64>,
    /// `2N` torques.
    pub t: Vec<f64>,
    /// Column names (standard parameters of the model).
    pub names: Vec<String>,
    /// Row groups (joint 1, joint 2).
    pub groups: RowGroups,
}

fn dyn_err(context: &str, e: impl std::error::Error + Send + Sync + 'static) -> IdentError {
    IdentError::external(context, e)
}

fn invalid(context: &str, reason: impl Into<String>) -> IdentError {
    IdentError::InvalidData {
        context: context.to_owned(),
        reason: reason.into(),
    }
}

/// Stacks `model`'s regressor over processed `samples` (their `X, Ẋ, Ẍ`
/// through the kinematics; `θ, θ̇` are recomputed from `X`, which is how the
/// samples were derived) and their torques.
pub fn stack(model: &Model, geometry: &Geometry, samples: &Samples) -> Result<Stacked, IdentError> {
    let all: Vec<usize> = (0..model.columns()).collect();
    stack_selected(model, geometry, samples, (&all, model.names()), None)
}

/// Samples stacked at a time by [`stack_selected`]: its scratch (`2 ×
/// 2048 × columns` doubles, 1.4 MB for 42 columns) stays in the allocator's
/// heap, where a whole block's standard regressor would be mapped and
/// cleared afresh for every block of a long log.
const STACK_CHUNK: usize = 2048;

/// [`stack`] keeping only the standard columns `columns` (named `names`),
/// stacked chunk by chunk straight into the selected columns, without the
/// whole standard regressor; into `recycled` when it has the result's shape
/// (every entry is written).
pub(crate) fn stack_selected(
    model: &Model,
    geometry: &Geometry,
    samples: &Samples,
    (columns, names): (&[usize], Vec<String>),
    recycled: Option<Mat<f64>>,
) -> Result<Stacked, IdentError> {
    let n = samples.len();
    for (what, a) in [
        ("x", &samples.x),
        ("x_dot", &samples.x_dot),
        ("x_ddot", &samples.x_ddot),
        ("tau", &samples.tau),
    ] {
        if a[0].len() != n || a[1].len() != n {
            return Err(invalid(
                "samples",
                format!(
                    "`{what}` has {}/{} entries for {n} samples",
                    a[0].len(),
                    a[1].len()
                ),
            ));
        }
    }
    if let Some(&c) = columns.iter().find(|&&c| c >= model.columns()) {
        return Err(invalid(
            "selected regressor columns",
            format!("column {c} of a model with {} columns", model.columns()),
        ));
    }
    let mut w = match recycled {
        Some(m) if m.nrows() == 2 * n && m.ncols() == columns.len() => m,
        _ => Mat::<f64>::zeros(2 * n, columns.len()),
    };
    let mut task: Vec<Motion> = Vec::with_capacity(STACK_CHUNK.min(n));
    let mut scratch = nalgebra::DMatrix::<f64>::zeros(0, model.columns());
    for s in (0..n).step_by(STACK_CHUNK) {
        let e = (s + STACK_CHUNK).min(n);
        let m = e - s;
        task.clear();
        task.extend((s..e).map(|i| samples.task(i)));
        if scratch.nrows() != 2 * m {
            scratch = nalgebra::DMatrix::zeros(2 * m, model.columns());
        }
        model
            .stacked_from_states_into(geometry, &task, &mut scratch)
            .map_err(|e| dyn_err("stacking the regressor", e))?;
        for (k, &c) in columns.iter().enumerate() {
            let src = scratch.column(c);
            for g in 0..2 {
                for i in 0..m {
                    w[(g * n + s + i, k)] = src[g * m + i];
                }
            }
        }
    }
    let t = samples.tau[0]
        .iter()
        .chain(&samples.tau[1])
        .copied()
        .collect();
    Ok(Stacked {
        w,
        t,
        names,
        groups: RowGroups::contiguous(&[n, n])?,
    })
}

/// The `i`-th point (from 1) of the van der Corput sequence in base `b`.
fn radical_inverse(mut i: u64, b: u64) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= b as f64;
        r += f * (i % b) as f64;
        i /= b;
    }
    r
}

/// Base parameters (58)–(61) of `model` from `samples` rich states: poses
/// filling the `workspace` box, rates within its limits and accelerations
/// within ±20 rad/s², on a six-dimensional Halton sequence (deterministic,
/// no seed, and more even than random points, so no accidental dependency
/// is taken as structural). Default rank tolerance.
///
/// A few hundred samples suffice (the dependencies are structural); the
/// base set is the same for every trajectory of this model and geometry,
/// so an excitation design and an identification can share it.
pub fn base_parameters(
    model: &Model,
    geometry: &Geometry,
    workspace: &Workspace,
    samples: usize,
) -> Result<BaseParameters, IdentError> {
    const PRIMES: [u64; 6] = [2, 3, 5, 7, 11, 13];
    const ACCEL: f64 = 20.0;
    let (lo, hi, rate) = (workspace.min(), workspace.max(), workspace.max_rate());
    let task: Vec<Motion> = (0..samples as u64)
        .map(|i| {
            let u: [f64; 6] = std::array::from_fn(|d| radical_inverse(i + 1, PRIMES[d]));
            Motion::new(
                Vector2::new(
                    lo[0] + u[0] * (hi[0] - lo[0]),
                    lo[1] + u[1] * (hi[1] - lo[1]),
                ),
                Vector2::new(rate[0] * (2.0 * u[2] - 1.0), rate[1] * (2.0 * u[3] - 1.0)),
                Vector2::new(ACCEL * (2.0 * u[4] - 1.0), ACCEL * (2.0 * u[5] - 1.0)),
            )
        })
        .collect();
    let w = model
        .stacked_from_states(geometry, &task)
        .map_err(|e| dyn_err("stacking the regressor for the base analysis", e))?;
    let w = faer::MatRef::from_column_major_slice(w.as_slice(), 2 * samples, model.columns());
    BaseParameters::from_regressor(w, &model.names(), DEFAULT_RANK_TOLERANCE)
}

/// What the zero-phase filter is applied to (`"parallel"`, `"torque_only"`
/// in settings files).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FilterMode {
    /// The torques and every regressor column (`docs/processing.md`): the fit
    /// compares like with like, so Coulomb jumps do not bias it.
    Parallel,
    /// Only the torques, as the paper did (kept for comparison).
    TorqueOnly,
}

/// Applies `sos` forward and backward to each joint's block of the torques
/// and (with [`FilterMode::Parallel`]) of every regressor column, in
/// parallel. `periodic` selects the exact periodic filter for period-averaged
/// data (one period, no edge effects).
pub fn filter(
    stacked: &mut Stacked,
    sos: &Sos,
    mode: FilterMode,
    periodic: bool,
) -> Result<(), IdentError> {
    let n = stacked.groups.counts()[0];
    if mode == FilterMode::Parallel {
        filter_columns(&mut stacked.w, n, sos, periodic)?;
    }
    if periodic {
        for g in 0..2 {
            let f = run_filter(sos, &stacked.t[g * n..(g + 1) * n], periodic)?;
            stacked.t[g * n..(g + 1) * n].copy_from_slice(&f);
        }
    } else {
        // Both joints' torques in two lanes of one sweep (bit-identical to
        // one at a time).
        let (a, b) = stacked.t.split_at_mut(n);
        sos.filtfilt_many_in_place(&mut [a, b], &mut Vec::new())
            .map_err(|e| dyn_err("filtering the torques", e))?;
    }
    Ok(())
}

/// Applies `sos` forward and backward to each joint's block (rows `0..n`,
/// `n..2n`) of every column of `w`, in parallel. Filtering acts column by
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
    if let Some(w) = ws.iter().find(|w| w.nrows() != 2 * n) {
        return Err(IdentError::DimensionMismatch {
            what: "joint-major regressor rows",
            expected: 2 * n,
            found: w.nrows(),
            hint: "give both joints' blocks of n rows",
        });
    }
    if periodic {
        return ws
            .iter_mut()
            .try_for_each(|w| filter_columns_periodic(w, n, sos));
    }
    // Every column's two joint blocks as slices, filtered `FILTER_LANES`
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
            let (a, b) = col.split_at_mut(n);
            blocks.extend([a, b].into_iter().filter(|x| x.iter().any(|v| *v != 0.0)));
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
                .map_err(|e| dyn_err("filtering", e))
        })
    })
}

/// [`filter_columns`] of one period, circularly.
fn filter_columns_periodic(w: &mut Mat<f64>, n: usize, sos: &Sos) -> Result<(), IdentError> {
    let src = &*w;
    let filtered: Vec<Result<Vec<f64>, IdentError>> = (0..2 * src.ncols())
        .into_par_iter()
        .map(|k| {
            let (j, g) = (k / 2, k % 2);
            let x: Vec<f64> = (g * n..(g + 1) * n).map(|i| src[(i, j)]).collect();
            run_filter(sos, &x, true)
        })
        .collect();
    for (k, f) in filtered.into_iter().enumerate() {
        let (j, g) = (k / 2, k % 2);
        for (i, v) in f?.into_iter().enumerate() {
            w[(g * n + i, j)] = v;
        }
    }
    Ok(())
}

fn run_filter(sos: &Sos, x: &[f64], periodic: bool) -> Result<Vec<f64>, IdentError> {
    sos.filtfilt_record(x, periodic)
        .map_err(|e| dyn_err("filtering", e))
}

/// Marks every row of the joints in `all_rows` as kept in the joint-major
/// mask `keep` (two equal halves): the joints fitted on every row (a
/// refined Coulomb width) whatever [`reversal_mask`] left out.
pub(crate) fn keep_every_row(keep: &mut [bool], all_rows: [bool; 2]) {
    let n = keep.len() / 2;
    for (g, all) in all_rows.iter().enumerate() {
        if *all {
            keep[g * n..(g + 1) * n].fill(true);
        }
    }
}

/// Rows to keep away from velocity reversals: joint `j`'s row of sample `i`
/// is dropped if `|θ̇_j| < v_min` at any sample within `guard` samples of
/// `i` (circularly when `periodic`). Joint-major mask for a [`Stacked`].
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
    let n = theta_dot[0].len();
    if theta_dot[1].len() != n {
        return Err(IdentError::DimensionMismatch {
            what: "θ̇2 samples",
            expected: n,
            found: theta_dot[1].len(),
            hint: "give both joints' rates for the same samples",
        });
    }
    // Each slow sample excludes the window [i − guard, i + guard]; windows
    // are marked in a difference array and resolved by one prefix sum, so
    // the cost is O(n) whatever the guard (the filter's reach grows with the
    // sampling rate: thousands of samples at 10 kHz).
    let mut keep = vec![true; 2 * n];
    let mut cover = vec![0i64; n + 1];
    for j in 0..2 {
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
        .map_err(|e| dyn_err("impulse response of the filter", e))?;
    Ok((h, centre))
}

/// The rows of `stacked` where `keep` is true (joint-major mask of length
/// `2N`, e.g. from [`reversal_mask`]); the row groups shrink accordingly.
/// Apply after [`filter`], which needs the complete, evenly sampled record.
pub fn keep_rows(stacked: &Stacked, keep: &[bool]) -> Result<Stacked, IdentError> {
    let m = stacked.w.nrows();
    if keep.len() != m {
        return Err(IdentError::DimensionMismatch {
            what: "row mask",
            expected: m,
            found: keep.len(),
            hint: "give one flag per stacked row (joint-major, 2N)",
        });
    }
    let rows: Vec<usize> = (0..m).filter(|&i| keep[i]).collect();
    let n = stacked.groups.counts()[0];
    let n1 = rows.iter().filter(|&&i| i < n).count();
    Ok(Stacked {
        w: Mat::from_fn(rows.len(), stacked.w.ncols(), |i, j| {
            stacked.w[(rows[i], j)]
        }),
        t: rows.iter().map(|&i| stacked.t[i]).collect(),
        names: stacked.names.clone(),
        groups: RowGroups::contiguous(&[n1, rows.len() - n1])?.with_samples(
            rows.iter().map(|&i| stacked.groups.samples()[i]).collect(),
            stacked.groups.sample_count(),
        )?,
    })
}

/// The physically consistent problem for `model` (which must contain the
/// rigid links) with `reference` (e.g. the CAD parameters) as regulariser
/// target and mass reference (bounds ±20 %), and the sign constraints (70)
/// of the effects the model has ([`Effect::nonnegative`]: `Fv, Fc ≥ 0`,
/// `Ke ≥ 0`).
pub fn consistent_problem(model: &Model, reference: &Params) -> Result<ConsistentLs, IdentError> {
    let names = model.names();
    let beta = reference
        .standard_vector(model)
        .map_err(|e| dyn_err("reference parameters", e))?;
    let mut p = ConsistentLs::new(&names, beta.as_slice().to_vec())?;
    if !model.effects().contains(&Effect::RigidLinks) {
        return Err(invalid(
            "consistent problem",
            "the model has no rigid links, so there is nothing to keep physical",
        ));
    }
    for (k, link) in reference.links.iter().enumerate() {
        let l = format!("L{}", k + 1);
        let f = |s: &str| format!("{l}.{s}");
        let (ix, iy, iz, iyy, iyz, izz) =
            (f("Ixx"), f("Ixy"), f("Ixz"), f("Iyy"), f("Iyz"), f("Izz"));
        let (hx, hy, hz) = (f("hx"), f("hy"), f("hz"));
        p.link_by_names(
            &l,
            [&ix, &iy, &iz, &iyy, &iyz, &izz],
            [&hx, &hy, &hz],
            link.mass,
        )?;
    }
    let signed: Vec<&str> = model
        .effects()
        .iter()
        .flat_map(|e| e.nonnegative().iter().copied())
        .collect();
    p.nonnegative(&signed)?;
    Ok(p)
}

/// `reference` with the SDP's standard parameters and masses written in
/// (the round trip into `aras-dyn`'s parameter type).
pub fn params_from_solution(
    reference: &Params,
    model: &Model,
    sol: &SdpSolution,
) -> Result<Params, IdentError> {
    let mut p = reference.clone();
    p.set_standard_vector(model, &sol.standard)
        .map_err(|e| dyn_err("writing the SDP result", e))?;
    if sol.masses.len() != p.links.len() {
        return Err(IdentError::DimensionMismatch {
            what: "link masses of the SDP solution",
            expected: p.links.len(),
            found: sol.masses.len(),
            hint: "solve the problem built by `consistent_problem`",
        });
    }
    for (l, m) in p.links.iter_mut().zip(&sol.masses) {
        l.mass = *m;
    }
    p.validate().map_err(|e| dyn_err("the SDP result", e))?;
    Ok(p)
}
