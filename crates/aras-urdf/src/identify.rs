//! The identification recipe of a URDF robot from its log: processing,
//! base parameters, least squares and the physically consistent estimate,
//! on the toolkit's robot-agnostic crates (`docs/urdf.md`, "Identify").

use aras_ident::{BaseParameters, ConsistentLs, IdentError, LinearModel, LinkLayout, ReducedLs};
use aras_log::Log;
use aras_signal::{Bandwidth, JointCoordinates, PeriodSource, ProcessError, ProcessOptions};
use serde::Serialize;

use crate::{UrdfError, UrdfModel};

/// Why an identification was refused.
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    /// The model or its evaluation.
    #[error(transparent)]
    Urdf(#[from] UrdfError),
    /// The log's processing.
    #[error(transparent)]
    Process(#[from] ProcessError),
    /// The least squares or the SDP.
    #[error(transparent)]
    Ident(#[from] IdentError),
    /// The log's joints are not the model's.
    #[error(
        "{log}: {found} joints logged, the URDF has {expected} ({names}); log every joint in the model's order"
    )]
    Joints {
        /// The log's name.
        log: String,
        /// Joints in the log.
        found: usize,
        /// Joints of the model.
        expected: usize,
        /// The model's joint names, in order.
        names: String,
    },
}

/// Settings of [`identify`], defaults in [`IdentifySettings::default`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IdentifySettings {
    /// The period of the excitation, s, for period averaging and the
    /// harmonic series (`None`: the log's sidecar, else detected).
    pub period: Option<f64>,
    /// Quasi-random states the base parameters are computed from.
    pub base_states: usize,
    /// Mass bounds of the consistent estimate, a fraction of each body's
    /// URDF mass (`0.5`: ±50 %).
    pub mass_tolerance: f64,
}

impl Default for IdentifySettings {
    /// Period from the log, 600 states, ±50 % masses.
    fn default() -> Self {
        Self {
            period: None,
            base_states: 600,
            mass_tolerance: 0.5,
        }
    }
}

/// What [`identify`] found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UrdfIdentification {
    /// Processed samples the fit used.
    pub samples: usize,
    /// How the processing limited the band, in its words.
    pub bandwidth: String,
    /// The base parameters as combinations of the standard ones.
    pub base_names: Vec<String>,
    /// Their least-squares estimates.
    pub ols: Vec<f64>,
    /// The estimates' σ (white residual).
    pub ols_sigma: Vec<f64>,
    /// The standard parameters' names, in order.
    pub parameter_names: Vec<String>,
    /// The physically consistent standard parameters (one positive
    /// definite pseudo-inertia per body, friction and armature ≥ 0).
    pub standard: Vec<f64>,
    /// Their base parameters.
    pub consistent_base: Vec<f64>,
    /// The SDP's status.
    pub status: aras_ident::SolverStatus,
    /// Smallest eigenvalue of each body's pseudo-inertia, in joint order.
    pub min_eigenvalues: Vec<f64>,
    /// Fitness (78) per joint of the consistent parameters on the processed
    /// samples, %.
    pub fitness: Vec<f64>,
}

impl UrdfModel {
    /// Base parameters of this model from its regressor at `states`
    /// quasi-random states: positions inside the URDF's limits (±π where it
    /// gives none), rates within ±2 and accelerations within ±8 per second.
    pub fn base_parameters(&self, states: usize) -> Result<BaseParameters, IdentifyError> {
        let mut u = 0.5f64;
        let mut next = move || {
            u = (u + 0.618_033_988_749_895) % 1.0;
            u
        };
        let range: Vec<(f64, f64)> = self
            .joints()
            .iter()
            .map(|j| match j.limits {
                Some(l) => match (l.lower, l.upper) {
                    (Some(a), Some(b)) if b > a => (a, b),
                    _ => (-std::f64::consts::PI, std::f64::consts::PI),
                },
                None => (-std::f64::consts::PI, std::f64::consts::PI),
            })
            .collect();
        let w = stacked(self, states, |_, q, v, a| {
            for (x, (lo, hi)) in q.iter_mut().zip(&range) {
                *x = lo + (hi - lo) * next();
            }
            v.iter_mut().for_each(|x| *x = 4.0 * next() - 2.0);
            a.iter_mut().for_each(|x| *x = 16.0 * next() - 8.0);
        })?;
        Ok(BaseParameters::from_regressor(
            w.as_ref(),
            &self.names(),
            aras_ident::DEFAULT_RANK_TOLERANCE,
        )?)
    }
}

/// Identifies `model` from `log`: the log processed in joint coordinates
/// (`aras-signal`: period averaging and the data-chosen bandwidth when the
/// period is known), the regressor stacked on the processed samples,
/// least squares on the base parameters, and the physically consistent
/// estimate (`aras-ident`'s SDP: one pseudo-inertia per body on its own
/// mass parameter, masses within the tolerance of the URDF's, friction and
/// armature ≥ 0, the URDF's inertials as the reference).
pub fn identify(
    model: &UrdfModel,
    log: &Log,
    settings: &IdentifySettings,
) -> Result<UrdfIdentification, IdentifyError> {
    let n = model.dof();
    if log.joints() != n {
        return Err(IdentifyError::Joints {
            log: log.name.clone(),
            found: log.joints(),
            expected: n,
            names: model.joint_names().join(", "),
        });
    }
    let processed = aras_signal::process_in::<nalgebra::Dyn>(
        log,
        &ProcessOptions {
            filter: Bandwidth::Auto,
            period: settings
                .period
                .map_or(PeriodSource::FromSidecar, PeriodSource::Seconds),
            ..ProcessOptions::default()
        },
        &JointCoordinates,
    )?;
    let s = &processed.samples;
    let base = model.base_parameters(settings.base_states)?;
    let (m, cols) = (s.len(), model.columns());
    let w = stacked(model, m, |r, q, v, a| {
        for j in 0..n {
            q[j] = s.x[j][r];
            v[j] = s.x_dot[j][r];
            a[j] = s.x_ddot[j][r];
        }
    })?;
    let tau = s.tau.concat();
    let wb = base.base_regressor(w.as_ref())?;
    let reduced = ReducedLs::new(wb.as_ref(), &tau, &base.base_names())?;
    let ols = reduced.ols()?;
    let names = model.parameter_names();
    let reference = model.urdf_parameters();
    let mut problem = ConsistentLs::new(&names, reference.clone())?;
    let tol = settings.mass_tolerance;
    for l in model.link_columns() {
        let mass = reference[l.mass];
        problem.link(
            LinkLayout::new(l.link.clone(), l.inertia, l.first_moment, mass)
                .with_mass_column(l.mass)
                .with_mass_bounds((1.0 - tol) * mass, (1.0 + tol) * mass),
        )?;
    }
    let signed: Vec<&str> = names
        .iter()
        .filter(|p| p.ends_with(".Fv") || p.ends_with(".Fc") || p.ends_with(".Ia"))
        .map(String::as_str)
        .collect();
    problem.nonnegative(&signed)?;
    let sdp = problem.solve(&base, &reduced)?;
    let fitness = (0..n)
        .map(|j| {
            let mut pred = vec![0.0; m];
            for (r, p) in pred.iter_mut().enumerate() {
                *p = (0..cols).map(|c| w[(j * m + r, c)] * sdp.standard[c]).sum();
            }
            aras_ident::validate::fitness(&s.tau[j], &pred)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(UrdfIdentification {
        samples: m,
        bandwidth: processed.summary.bandwidth.reason.clone(),
        base_names: base.expressions(),
        ols: ols.estimate,
        ols_sigma: ols.std_dev,
        parameter_names: names,
        consistent_base: sdp.base.clone(),
        status: sdp.status,
        min_eigenvalues: sdp.links.iter().map(|l| l.min_eigenvalue).collect(),
        standard: sdp.standard,
        fitness,
    })
}

/// The regressor of `model` stacked over `rows` states, joint 1's rows
/// first, then joint 2's, …; `state(r, q, q̇, q̈)` writes state `r`.
fn stacked(
    model: &UrdfModel,
    rows: usize,
    mut state: impl FnMut(usize, &mut [f64], &mut [f64], &mut [f64]),
) -> Result<faer::Mat<f64>, IdentifyError> {
    let (n, cols) = (model.dof(), model.columns());
    let mut w = faer::Mat::<f64>::zeros(n * rows, cols);
    let mut y = vec![0.0; n * cols];
    let (mut q, mut v, mut a) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for r in 0..rows {
        state(r, &mut q, &mut v, &mut a);
        model.fill(&q, &v, &a, &mut y)?;
        for j in 0..n {
            for c in 0..cols {
                w[(j * rows + r, c)] = y[n * c + j];
            }
        }
    }
    Ok(w)
}
