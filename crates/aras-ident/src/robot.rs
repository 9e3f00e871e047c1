//! Adapter to the ARAS-Diamond crates: stacked regressors from `aras-dyn`'s
//! model and `aras-signal`'s samples, parallel filtering (spec §6 NOTE), the
//! SDP layout of the four links, and the way back into `aras-dyn`'s
//! parameter type. Everything else in this crate is robot-agnostic.

use aras_dyn::{Effect, Model, Params};
use aras_kin::Geometry;
use aras_signal::{Samples, Sos};
use faer::Mat;
use nalgebra::Vector2;
use rayon::prelude::*;

use crate::error::IdentError;
use crate::groups::RowGroups;
use crate::sdp::{ConsistentLs, SdpSolution};

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

fn dyn_err(context: &str, e: impl std::fmt::Display) -> IdentError {
    IdentError::Adapter {
        context: context.to_owned(),
        message: e.to_string(),
    }
}

/// Stacks `model`'s regressor over processed `samples` (their `X, Ẋ, Ẍ`
/// through the kinematics; `θ, θ̇` are recomputed from `X`, which is how the
/// samples were derived) and their torques.
pub fn stack(model: &Model, geometry: &Geometry, samples: &Samples) -> Result<Stacked, IdentError> {
    let n = samples.len();
    let v = |a: &[Vec<f64>; 2]| -> Vec<Vector2<f64>> {
        (0..n).map(|i| Vector2::new(a[0][i], a[1][i])).collect()
    };
    for (what, a) in [
        ("x", &samples.x),
        ("x_dot", &samples.x_dot),
        ("x_ddot", &samples.x_ddot),
        ("tau", &samples.tau),
    ] {
        if a[0].len() != n || a[1].len() != n {
            return Err(dyn_err(
                "samples",
                format!(
                    "`{what}` has {}/{} entries for {n} samples",
                    a[0].len(),
                    a[1].len()
                ),
            ));
        }
    }
    let w = model
        .stacked_from_states(
            geometry,
            &v(&samples.x),
            &v(&samples.x_dot),
            &v(&samples.x_ddot),
        )
        .map_err(|e| dyn_err("stacking the regressor", e))?;
    let w = faer::MatRef::from_column_major_slice(w.as_slice(), 2 * n, model.columns()).to_owned();
    let t = samples.tau[0]
        .iter()
        .chain(&samples.tau[1])
        .copied()
        .collect();
    Ok(Stacked {
        w,
        t,
        names: model.names(),
        groups: RowGroups::contiguous(&[n, n])?,
    })
}

/// What the zero-phase filter is applied to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilterMode {
    /// The torques and every regressor column (spec §6 NOTE): the fit
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
    let run = |x: &[f64]| -> Result<Vec<f64>, IdentError> {
        if periodic {
            sos.filtfilt_periodic(x)
        } else {
            sos.filtfilt(x)
        }
        .map_err(|e| dyn_err("filtering", e))
    };
    let cols = if mode == FilterMode::Parallel {
        stacked.w.ncols()
    } else {
        0
    };
    let w = &stacked.w;
    let filtered: Vec<Result<Vec<f64>, IdentError>> = (0..2 * cols)
        .into_par_iter()
        .map(|k| {
            let (j, g) = (k / 2, k % 2);
            let x: Vec<f64> = (g * n..(g + 1) * n).map(|i| w[(i, j)]).collect();
            run(&x)
        })
        .collect();
    for (k, f) in filtered.into_iter().enumerate() {
        let (j, g) = (k / 2, k % 2);
        for (i, v) in f?.into_iter().enumerate() {
            stacked.w[(g * n + i, j)] = v;
        }
    }
    for g in 0..2 {
        let f = run(&stacked.t[g * n..(g + 1) * n])?;
        stacked.t[g * n..(g + 1) * n].copy_from_slice(&f);
    }
    Ok(())
}

/// The physically consistent problem for `model` (which must contain the
/// rigid links) with `reference` (e.g. the CAD parameters) as regulariser
/// target and mass reference (bounds ±20 %), and `Fv, Fc ≥ 0`, `Ke ≥ 0` (70)
/// for the effects the model has.
pub fn consistent_problem(model: &Model, reference: &Params) -> Result<ConsistentLs, IdentError> {
    let names = model.names();
    let beta = reference
        .standard_vector(model)
        .map_err(|e| dyn_err("reference parameters", e))?;
    let mut p = ConsistentLs::new(&names, beta.as_slice().to_vec())?;
    if !model.effects().contains(&Effect::RigidLinks) {
        return Err(dyn_err(
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
    let signed: Vec<&String> = names
        .iter()
        .filter(|n| ["Fv1", "Fc1", "Fv2", "Fc2", "Ke1", "Ke2"].contains(&n.as_str()))
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
