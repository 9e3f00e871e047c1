//! The torques a parameter vector predicts for a log's motion, scored
//! against the log's raw torques on every row (`docs/urdf.md`, "Predict").

use aras_log::Log;
use aras_signal::OutputRows;
use serde::Serialize;

use crate::UrdfModel;
use crate::identify::{IdentifyError, log_fitness, process};

/// Settings of [`predict`], defaults in [`PredictSettings::default`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PredictSettings {
    /// The motion's period, s, if it is periodic (`None`: the log's
    /// sidecar, else detected); only the processing uses it, every row is
    /// predicted either way.
    pub period: Option<f64>,
    /// Use the log's `dtheta*`, `ddtheta*` columns, when it has them, as
    /// given instead of differentiating the angles.
    pub logged_derivatives: bool,
}

impl Default for PredictSettings {
    /// Period from the log; logged derivatives used when present.
    fn default() -> Self {
        Self {
            period: None,
            logged_derivatives: true,
        }
    }
}

/// What [`predict`] found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Prediction {
    /// Time of each predicted row, s.
    pub t: Vec<f64>,
    /// The model torque per joint and row, `[joint][row]`, band-limited as
    /// the angles were.
    pub tau: Vec<Vec<f64>>,
    /// Fitness (78) per joint against the log's raw torques on the rows
    /// predicted, %.
    pub fitness: Vec<f64>,
    /// Rows predicted (all but the differentiation's edges).
    pub rows: usize,
    /// Rows of the log.
    pub log_rows: usize,
    /// Where `q̇, q̈` came from and how the band was limited, in words.
    pub derivatives: String,
}

/// The torques the standard parameters `params` of `model` predict on
/// every row of `log`: the log processed as identification processes it
/// (the data-chosen bandwidth; the logged derivatives as given when
/// [`PredictSettings::logged_derivatives`] and present), the regressor on
/// each row times `params`, band-limited like the angles, scored with
/// (78) against the raw torques.
///
/// # Errors
/// [`IdentifyError`] when the log's joints are not the model's, it cannot
/// be processed, or `params` has the wrong length.
pub fn predict(
    model: &UrdfModel,
    params: &[f64],
    log: &Log,
    settings: &PredictSettings,
) -> Result<Prediction, IdentifyError> {
    if params.len() != model.parameter_count() {
        return Err(crate::UrdfError::Dimension {
            what: "standard parameters",
            expected: model.parameter_count(),
            found: params.len(),
        }
        .into());
    }
    let logged = settings.logged_derivatives && log.theta_dot.is_some() && log.theta_ddot.is_some();
    let processed = process(model, log, settings.period, OutputRows::EveryRow, logged)?;
    let w = model.regressor_on(&processed.samples)?;
    let fit = log_fitness(&processed, &w, params)?;
    Ok(Prediction {
        t: processed.samples.t.clone(),
        tau: fit.predicted,
        fitness: fit.fitness,
        rows: fit.rows,
        log_rows: log.len(),
        derivatives: if logged {
            "the log's dtheta, ddtheta columns as given".to_owned()
        } else {
            processed.summary.bandwidth.reason.clone()
        },
    })
}
