//! Prediction (`aras predict`): the torques a parameter file predicts for a
//! log's motion, scored against the log's raw torques, with the processing
//! loss where the log carries exact derivative columns
//! ([`crate::validate::loss`]).

use aras_dyn::Params;
use aras_ident::IdentError;
use aras_log::Log;
use aras_signal::{ProcessOptions, Processed};
use serde::Serialize;

use crate::PipelineError;
use crate::identify::paired_fitness;
use crate::validate::loss::{ProcessingLoss, has_derivatives, predict_route, processing_loss};

/// Which θ̇, θ̈ a prediction was made from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Route {
    /// The log's `dtheta*`, `ddtheta*` columns as given.
    LoggedDerivatives,
    /// Differentiated from the angles with the configured bandwidth.
    Angles,
}

/// A log's predicted torques and how well they match it.
#[derive(Debug)]
pub struct Prediction {
    /// The log processed on every row, by [`Self::route`].
    pub processed: Processed,
    /// The model torque `Y(θ, θ̇, θ̈) β` on each processed sample, band-limited
    /// as the angles were; stacked, joint 1 first.
    pub tau: Vec<f64>,
    /// The derivatives it used.
    pub route: Route,
    /// Fitness (78) per joint (%) of `tau` against the log's raw torques on
    /// the log rows that have a sample.
    pub fitness: [f64; 2],
    /// The processing loss (logged-derivative route minus angles-only
    /// route, same parameters); `None` for a log without derivative
    /// columns, or when the angles-only route cannot process the log.
    pub processing_loss: Option<ProcessingLoss>,
    /// Why a log with derivative columns has no processing loss (e.g. a
    /// sidecar period that is no whole number of samples, which only the
    /// angles-only route needs): the prediction stands without it.
    pub loss_unavailable: Option<PipelineError>,
}

/// An error of the parameter file's `what`, with its cause.
fn param_err<E: std::error::Error + Send + Sync + 'static>(
    what: &'static str,
) -> impl Fn(E) -> IdentError {
    move |e| IdentError::external(format!("the parameter file's {what}"), e)
}

/// Predicts `params`' torques (its own model: extra effects in it are
/// predicted too) on every row of `log`: θ̇, θ̈ from the log's derivative
/// columns as given when it has them, else from the angles with `process`'s
/// bandwidth (its `use_logged_derivatives` and `rows` are set here).
///
/// # Errors
/// A parameter file whose model, standard vector or geometry is invalid,
/// and processing or stacking failures of the log.
pub fn predict_log(
    log: &Log,
    params: &Params,
    process: &ProcessOptions,
) -> Result<Prediction, PipelineError> {
    let model = params.model().map_err(param_err("model"))?;
    let beta = params
        .standard_vector(&model)
        .map_err(param_err("standard parameters"))?;
    let beta = beta.as_slice().to_vec();
    let geometry = params.geometry().map_err(param_err("geometry"))?;
    let logged = has_derivatives(log);
    let opts = ProcessOptions {
        use_logged_derivatives: logged,
        ..process.clone()
    };
    let (processed, tau) = predict_route(log, &opts, &model, &geometry, &beta)?;
    // The log's raw torques on the rows that have a sample (the processed
    // samples' torques are band-limited with the motion: not what the
    // prediction is compared with).
    let n = processed.samples.len();
    let pairs = processed
        .paired_with_log_rows(&[&tau[..n], &tau[n..]])
        .map_err(|e| IdentError::external("pairing the prediction with the log's rows", e))?;
    let fitness = paired_fitness(&pairs)?;
    let (processing_loss, loss_unavailable) = match processing_loss(
        log,
        &opts,
        &model,
        &geometry,
        &beta,
        Some((&processed, &tau)),
    ) {
        Ok(l) => (l, None),
        Err(e) => (None, Some(e)),
    };
    Ok(Prediction {
        processed,
        tau,
        route: if logged {
            Route::LoggedDerivatives
        } else {
            Route::Angles
        },
        fitness,
        processing_loss,
        loss_unavailable,
    })
}
