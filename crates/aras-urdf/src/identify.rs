//! The identification recipe of a URDF robot from its log: processing,
//! base parameters, least squares and the physically consistent estimate,
//! on the toolkit's robot-agnostic crates (`docs/urdf.md`, "Identify").

use aras_ident::{BaseParameters, ConsistentLs, IdentError, LinearModel, LinkLayout, ReducedLs};
use aras_log::Log;
use aras_signal::{
    Bandwidth, JointCoordinates, OutputRows, PeriodSource, ProcessError, ProcessOptions, Samples,
};
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
    /// The excitation design.
    #[error(transparent)]
    Excite(#[from] aras_excite::ExciteError),
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
    /// definite pseudo-inertia per body, friction, armature and Stribeck
    /// levels ≥ 0).
    pub standard: Vec<f64>,
    /// Their base parameters.
    pub consistent_base: Vec<f64>,
    /// The SDP's status.
    pub status: aras_ident::SolverStatus,
    /// Smallest eigenvalue of each body's pseudo-inertia, in joint order.
    pub min_eigenvalues: Vec<f64>,
    /// Fitness (78) per joint of the consistent parameters against the
    /// log's raw torques on every row the processing covers, %.
    pub fitness: Vec<f64>,
}

impl UrdfModel {
    /// Base parameters of this model from its regressor at `states`
    /// quasi-random states: positions inside the URDF's limits (±π where it
    /// gives none), rates within ±2 and accelerations within ±8 per second.
    pub fn base_parameters(&self, states: usize) -> Result<BaseParameters, IdentifyError> {
        let w = self.regressor_on(&quasi_random_samples(self, states))?;
        Ok(BaseParameters::from_regressor(
            w.as_ref(),
            &self.names(),
            aras_ident::DEFAULT_RANK_TOLERANCE,
        )?)
    }
}

/// The `states` quasi-random states of [`UrdfModel::base_parameters`]
/// (a golden-ratio sequence: positions inside the limits, ±π where the URDF
/// gives none, rates within ±2, accelerations within ±8 per second), as
/// samples in joint coordinates with zero torques, so that any column
/// defined on samples (an effect the diagnosis adds) is evaluated on the
/// same states.
pub(crate) fn quasi_random_samples(model: &UrdfModel, states: usize) -> Samples {
    let n = model.dof();
    let mut u = 0.5f64;
    let mut next = move || {
        u = (u + 0.618_033_988_749_895) % 1.0;
        u
    };
    let range: Vec<(f64, f64)> = model
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
    let mut s = Samples::with_joints(n);
    for r in 0..states {
        s.t.push(r as f64);
        for (j, (lo, hi)) in range.iter().enumerate() {
            s.x[j].push(lo + (hi - lo) * next());
        }
        for j in 0..n {
            s.x_dot[j].push(4.0 * next() - 2.0);
        }
        for j in 0..n {
            s.x_ddot[j].push(16.0 * next() - 8.0);
        }
        for j in 0..n {
            s.tau[j].push(0.0);
        }
    }
    s.theta.clone_from(&s.x);
    s.theta_dot.clone_from(&s.x_dot);
    s.theta_ddot.clone_from(&s.x_ddot);
    s
}

/// The physically consistent problem of `model` with `names` (its standard
/// parameters, then any added ones) and `reference` (the URDF's values,
/// then the added ones'): one pseudo-inertia per body on its own mass
/// parameter, masses within `tolerance` of the URDF's, and `nonnegative`
/// (friction, armature and any added level) ≥ 0.
pub(crate) fn consistent_problem(
    model: &UrdfModel,
    names: &[String],
    reference: Vec<f64>,
    tolerance: f64,
    nonnegative: &[String],
) -> Result<ConsistentLs, IdentError> {
    let mut problem = ConsistentLs::new(names, reference.clone())?;
    for l in model.link_columns() {
        let mass = reference[l.mass];
        problem.link(
            LinkLayout::new(l.link.clone(), l.inertia, l.first_moment, mass)
                .with_mass_column(l.mass)
                .with_mass_bounds((1.0 - tolerance) * mass, (1.0 + tolerance) * mass),
        )?;
    }
    problem.nonnegative(nonnegative)?;
    Ok(problem)
}

/// The model's parameters that are ≥ 0 physically: viscous and Coulomb
/// friction, armature and the Stribeck levels above the Coulomb one.
pub(crate) fn signed_parameters(model: &UrdfModel) -> Vec<String> {
    model
        .parameter_names()
        .into_iter()
        .filter(|p| [".Fv", ".Fc", ".Ia", ".Fs"].iter().any(|s| p.ends_with(s)))
        .collect()
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
    let processed = process(model, log, settings.period, OutputRows::Averaged, false)?;
    let s = &processed.samples;
    let base = model.base_parameters(settings.base_states)?;
    let m = s.len();
    let w = model.regressor_on(s)?;
    let tau = s.tau.concat();
    let wb = base.base_regressor(w.as_ref())?;
    let reduced = ReducedLs::new(wb.as_ref(), &tau, &base.base_names())?;
    let ols = reduced.ols()?;
    let names = model.parameter_names();
    let problem = consistent_problem(
        model,
        &names,
        model.urdf_parameters(),
        settings.mass_tolerance,
        &signed_parameters(model),
    )?;
    let sdp = problem.solve(&base, &reduced)?;
    let fitness = log_fitness(&processed, &w, &sdp.standard)?.fitness;
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

/// `log` processed in joint coordinates as every URDF recipe does: the
/// data-chosen bandwidth, period averaging with `period` (`None`: the
/// sidecar's, else detected), `rows` returned, the log's derivative columns
/// used as given when `logged_derivatives` and present.
pub(crate) fn process(
    model: &UrdfModel,
    log: &Log,
    period: Option<f64>,
    rows: OutputRows,
    logged_derivatives: bool,
) -> Result<aras_signal::Processed, IdentifyError> {
    let n = model.dof();
    if log.joints() != n {
        return Err(IdentifyError::Joints {
            log: log.name.clone(),
            found: log.joints(),
            expected: n,
            names: model.joint_names().join(", "),
        });
    }
    Ok(aras_signal::process_in::<nalgebra::Dyn>(
        log,
        &ProcessOptions {
            filter: Bandwidth::Auto,
            period: period.map_or(PeriodSource::FromSidecar, PeriodSource::Seconds),
            use_logged_derivatives: logged_derivatives,
            rows,
            ..ProcessOptions::default()
        },
        &JointCoordinates,
    )?)
}

/// The model torque `W π` of a processed log through the processing's
/// band-limiting, per joint and sample, and its fitness (78) against the
/// log's raw torques on every row that has a sample.
pub(crate) struct LogFit {
    /// Band-limited prediction, `[joint][sample]`.
    pub predicted: Vec<Vec<f64>>,
    /// Fitness per joint, %.
    pub fitness: Vec<f64>,
    /// Log rows scored.
    pub rows: usize,
}

/// [`LogFit`] of `params` with the stacked regressor `w` of `processed`.
pub(crate) fn log_fitness(
    processed: &aras_signal::Processed,
    w: &faer::Mat<f64>,
    params: &[f64],
) -> Result<LogFit, IdentifyError> {
    let tau = aras_ident::validate::predict(w.as_ref(), params)?;
    let m = processed.samples.len();
    let per_joint: Vec<&[f64]> = tau.chunks(m.max(1)).collect();
    let predicted = processed.band_limited(&per_joint)?;
    let views: Vec<&[f64]> = predicted.iter().map(Vec::as_slice).collect();
    let pairs = processed.paired_with_log_rows(&views)?;
    let fitness = pairs
        .iter()
        .map(|(measured, model)| aras_ident::validate::fitness(measured, model))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(LogFit {
        rows: pairs.first().map_or(0, |p| p.0.len()),
        predicted,
        fitness,
    })
}

impl UrdfModel {
    /// The regressor stacked over processed samples, joint 1's rows first
    /// (`dof · samples × columns`), from their coordinates `x, ẋ, ẍ` (the
    /// joint angles for [`aras_signal::JointCoordinates`]).
    ///
    /// # Errors
    /// [`UrdfError`] when the samples do not have one coordinate per joint.
    pub fn regressor_on(
        &self,
        samples: &aras_signal::Samples,
    ) -> Result<faer::Mat<f64>, UrdfError> {
        let n = self.dof();
        if samples.x.len() != n || samples.x_dot.len() != n || samples.x_ddot.len() != n {
            return Err(UrdfError::Dimension {
                what: "processed samples' coordinates",
                expected: n,
                found: samples.x.len(),
            });
        }
        stacked(self, samples.len(), |r, q, v, a| {
            for j in 0..n {
                q[j] = samples.x[j][r];
                v[j] = samples.x_dot[j][r];
                a[j] = samples.x_ddot[j][r];
            }
        })
    }
}

/// The regressor of `model` stacked over `rows` states, joint 1's rows
/// first, then joint 2's, …; `state(r, q, q̇, q̈)` writes state `r`.
fn stacked(
    model: &UrdfModel,
    rows: usize,
    mut state: impl FnMut(usize, &mut [f64], &mut [f64], &mut [f64]),
) -> Result<faer::Mat<f64>, UrdfError> {
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
