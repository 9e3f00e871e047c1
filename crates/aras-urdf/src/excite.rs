//! An excitation for a URDF robot designed by `aras-excite` within the
//! URDF's joint and velocity limits, and how much better conditioned it is
//! than random feasible trajectories (`docs/urdf.md`, "Excitation").

use aras_excite::{
    DesignProgress, DesignSettings, ExciteError, FourierTrajectory, assess, base_projection,
    design_with_progress, random_feasible,
};
use nalgebra::Dyn;
use serde::{Deserialize, Serialize};

use crate::UrdfModel;
use crate::identify::IdentifyError;

/// Settings of [`design_excitation`], defaults in
/// [`ExciteSettings::default`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExciteSettings {
    /// Period of the trajectory, s.
    pub period_s: f64,
    /// Harmonics per joint.
    pub harmonics: usize,
    /// Fraction of each joint's half-range and velocity limit kept clear
    /// of the URDF's limits.
    pub margin: f64,
    /// Acceleration limit of every joint, rad/s² (m/s²): URDF gives none.
    pub max_accel: f64,
    /// Optimiser starts (the best is kept).
    pub starts: usize,
    /// Seed of the starts and of the random comparison.
    pub seed: u64,
    /// Random feasible trajectories the design is compared with (0: none).
    pub random_trajectories: usize,
    /// Quasi-random states the base parameters are computed from.
    pub base_states: usize,
}

impl Default for ExciteSettings {
    /// 10 s, 5 harmonics, 10 % margin, 10 rad/s², 4 starts, seed 1,
    /// 100 random trajectories, 600 states.
    fn default() -> Self {
        Self {
            period_s: 10.0,
            harmonics: 5,
            margin: 0.1,
            max_accel: 10.0,
            starts: 4,
            seed: 1,
            random_trajectories: 100,
            base_states: 600,
        }
    }
}

/// What [`design_excitation`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfExcitation {
    /// The designed trajectory, one coordinate per joint in the URDF's order.
    pub trajectory: FourierTrajectory<Dyn>,
    /// Its condition number κ of the column-scaled base regressor.
    pub condition_number: f64,
    /// Median κ of the random feasible trajectories (`None` without them).
    pub random_median: Option<f64>,
    /// Base parameters the design makes identifiable.
    pub n_base: usize,
    /// Worst limit margin of the design relative to each limit (≥ 0:
    /// inside every limit).
    pub worst_relative_margin: f64,
}

/// Designs an excitation for `model` minimising the condition number of its
/// base regressor ((74)–(77) of the paper, in joint space) within the
/// URDF's position and velocity limits shrunk by the margin, and compares
/// it with random feasible trajectories of the same family. `progress` is
/// called after each finished start.
///
/// # Errors
/// [`IdentifyError`] when a joint has no limits, a setting is invalid or
/// the design fails.
pub fn design_excitation(
    model: &UrdfModel,
    settings: &ExciteSettings,
    progress: &(dyn Fn(DesignProgress) + Sync),
) -> Result<UrdfExcitation, IdentifyError> {
    if !(settings.period_s.is_finite() && settings.period_s > 0.0) {
        return Err(crate::UrdfError::Setting {
            name: "period_s".into(),
            problem: format!("{} must be a positive number of seconds", settings.period_s),
        }
        .into());
    }
    let base = model.base_parameters(settings.base_states)?;
    let projection = base_projection(&base);
    let limits = model.excitation_limits(settings.margin, settings.max_accel)?;
    let design_settings = DesignSettings {
        harmonics: settings.harmonics,
        omega_f: std::f64::consts::TAU / settings.period_s,
        starts: settings.starts,
        seed: settings.seed,
        ..DesignSettings::new(limits)
    };
    let d = design_with_progress(model, &projection, &design_settings, progress)?;
    let random_median = if settings.random_trajectories == 0 {
        None
    } else {
        let mut kappa = random_feasible(
            &design_settings,
            settings.random_trajectories,
            settings.seed ^ 0x5eed,
        )?
        .iter()
        .map(|t| {
            assess(model, &projection, t, design_settings.criterion_points)
                .map(|a| a.condition_number)
        })
        .collect::<Result<Vec<f64>, ExciteError>>()?;
        kappa.sort_by(f64::total_cmp);
        Some(kappa[kappa.len() / 2])
    };
    Ok(UrdfExcitation {
        condition_number: d.assessment.condition_number,
        random_median,
        n_base: base.n_base(),
        worst_relative_margin: d.margins.worst_relative,
        trajectory: d.trajectory,
    })
}
