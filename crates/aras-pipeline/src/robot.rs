//! Adapter to the ARAS-Diamond crates: stacked regressors from `aras-dyn`'s
//! model and `aras-signal`'s samples, parallel filtering (`docs/processing.md`), the
//! SDP layout of the four links, and the way back into `aras-dyn`'s
//! parameter type.

use crate::PipelineError;
use aras_dyn::{Effect, Model, Params};
use aras_kin::{Geometry, Motion, Workspace};
use aras_signal::{Samples, Sos};
use faer::Mat;
use nalgebra::Vector2;

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
pub fn stack(
    model: &Model,
    geometry: &Geometry,
    samples: &Samples,
) -> Result<Stacked, PipelineError> {
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
) -> Result<Stacked, PipelineError> {
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
            )
            .into());
        }
    }
    if let Some(&c) = columns.iter().find(|&&c| c >= model.columns()) {
        return Err(invalid(
            "selected regressor columns",
            format!("column {c} of a model with {} columns", model.columns()),
        )
        .into());
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
) -> Result<BaseParameters, PipelineError> {
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
        .map_err(PipelineError::from)
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
) -> Result<(), PipelineError> {
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

pub use aras_diagnose::filtering::{
    DEFAULT_MIN_SPEED, DEFAULT_REVERSAL_REACH, DEFAULT_VALIDATION_REACH, filter_columns,
    filter_many_columns, filter_reach, keep_every_row, noise_gain, reversal_mask,
};

fn run_filter(sos: &Sos, x: &[f64], periodic: bool) -> Result<Vec<f64>, PipelineError> {
    sos.filtfilt_record(x, periodic)
        .map_err(|e| dyn_err("filtering", e))
        .map_err(PipelineError::from)
}

/// The rows of `stacked` where `keep` is true (joint-major mask of length
/// `2N`, e.g. from [`reversal_mask`]); the row groups shrink accordingly.
/// Apply after [`filter`], which needs the complete, evenly sampled record.
pub fn keep_rows(stacked: &Stacked, keep: &[bool]) -> Result<Stacked, PipelineError> {
    let m = stacked.w.nrows();
    if keep.len() != m {
        return Err(IdentError::DimensionMismatch {
            what: "row mask",
            expected: m,
            found: keep.len(),
            hint: "give one flag per stacked row (joint-major, 2N)",
        }
        .into());
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
pub fn consistent_problem(
    model: &Model,
    reference: &Params,
) -> Result<ConsistentLs, PipelineError> {
    let names = model.names();
    let beta = reference
        .standard_vector(model)
        .map_err(|e| dyn_err("reference parameters", e))?;
    let mut p = ConsistentLs::new(&names, beta.as_slice().to_vec())?;
    if !model.effects().contains(&Effect::RigidLinks) {
        return Err(invalid(
            "consistent problem",
            "the model has no rigid links, so there is nothing to keep physical",
        )
        .into());
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
) -> Result<Params, PipelineError> {
    let mut p = reference.clone();
    p.set_standard_vector(model, &sol.standard)
        .map_err(|e| dyn_err("writing the SDP result", e))?;
    if sol.masses.len() != p.links.len() {
        return Err(IdentError::DimensionMismatch {
            what: "link masses of the SDP solution",
            expected: p.links.len(),
            found: sol.masses.len(),
            hint: "solve the problem built by `consistent_problem`",
        }
        .into());
    }
    for (l, m) in p.links.iter_mut().zip(&sol.masses) {
        l.mass = *m;
    }
    p.validate().map_err(|e| dyn_err("the SDP result", e))?;
    Ok(p)
}
