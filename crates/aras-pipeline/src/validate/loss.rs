//! The processing loss (`docs/processing.md`, "Fitness figures"): how much
//! of a prediction's fitness (78) the processing of the angles costs.
//!
//! A log with exact derivative columns (`dtheta*`, `ddtheta*`, as the
//! simulator writes them) is predicted twice with the same parameters: from
//! the logged θ̇, θ̈ as given, and from the angles alone (the normal
//! processing, `use_logged_derivatives = false`). Both predictions are
//! scored against the log's raw torques on the same rows, the rows both
//! cover; the loss per joint is the first fitness minus the second, in
//! percentage points. Positive: differentiating the angles costs that much.

use crate::PipelineError;
use aras_dyn::Model;
use aras_ident::IdentError;
use aras_kin::Geometry;
use aras_log::Log;
use aras_signal::{OutputRows, ProcessOptions, Processed};
use serde::Serialize;

/// The processing loss of one prediction, per joint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProcessingLoss {
    /// Fitness (78) per joint (%) with the logged θ̇, θ̈, against the
    /// log's raw torques on the rows both routes cover.
    pub fitness_logged: [f64; 2],
    /// Fitness (78) per joint (%) from the angles alone, on the same rows.
    pub fitness_angles: [f64; 2],
    /// `fitness_logged − fitness_angles` per joint (percentage points).
    pub loss: [f64; 2],
    /// Rows of the log both routes cover (the scored rows).
    pub rows: usize,
}

/// A log processed on every row with `opts` and the model torque
/// `Y(θ, θ̇, θ̈) β` on its samples through the processing's band-limiting
/// (`Processed::band_limited`), stacked (joint 1 first): the prediction that
/// is compared with the log's raw torques.
pub fn predict_route(
    log: &Log,
    opts: &ProcessOptions,
    model: &Model,
    geometry: &Geometry,
    beta: &[f64],
) -> Result<(Processed, Vec<f64>), PipelineError> {
    let mut opts = opts.clone();
    opts.rows = OutputRows::EveryRow;
    let processed = aras_signal::process(log, &opts, &aras_kin::task_motion(geometry))
        .map_err(|e| IdentError::external(format!("processing {}", log.name), e))?;
    let w = crate::robot::stack(model, geometry, &processed.samples)?;
    let tau = aras_ident::validate::predict(w.w.as_ref(), beta)?;
    let n = processed.samples.len();
    let limited = processed
        .band_limited(&[&tau[..n], &tau[n..]])
        .map_err(|e| IdentError::external("band-limiting the prediction", e))?;
    Ok((processed, limited.concat()))
}

/// The processing loss of the prediction `pl` on `logged` (the
/// logged-derivative route) against `pa` on `angles` (the angles-only
/// route), both stacked per-sample predictions of the same log: fitness
/// (78) against the log's raw torques on the rows both routes have a
/// sample for.
pub fn loss_between(
    logged: &Processed,
    pl: &[f64],
    angles: &Processed,
    pa: &[f64],
) -> Result<ProcessingLoss, PipelineError> {
    let rows = logged.log_tau[0].len();
    if angles.log_tau[0].len() != rows {
        return Err(IdentError::InvalidData {
            context: "the processing loss".into(),
            reason: format!(
                "the two routes come from different logs ({rows} and {} rows)",
                angles.log_tau[0].len()
            ),
        }
        .into());
    }
    let (nl, na) = (logged.samples.len(), angles.samples.len());
    if pl.len() != 2 * nl || pa.len() != 2 * na {
        return Err(IdentError::InvalidData {
            context: "the processing loss".into(),
            reason: format!(
                "predictions of {} and {} values for {nl} and {na} samples",
                pl.len(),
                pa.len()
            ),
        }
        .into());
    }
    let both: Vec<(usize, usize, usize)> = (0..rows)
        .filter_map(|r| Some((r, logged.sample_of_row(r)?, angles.sample_of_row(r)?)))
        .collect();
    let mut fitness_logged = [0.0; 2];
    let mut fitness_angles = [0.0; 2];
    for j in 0..2 {
        let m: Vec<f64> = both.iter().map(|&(r, _, _)| logged.log_tau[j][r]).collect();
        let l: Vec<f64> = both.iter().map(|&(_, i, _)| pl[j * nl + i]).collect();
        let a: Vec<f64> = both.iter().map(|&(_, _, i)| pa[j * na + i]).collect();
        fitness_logged[j] = aras_ident::validate::fitness(&m, &l).map_err(|e| {
            IdentError::external(
                format!("fitness of joint {} with the logged derivatives", j + 1),
                e,
            )
        })?;
        fitness_angles[j] = aras_ident::validate::fitness(&m, &a).map_err(|e| {
            IdentError::external(
                format!("fitness of joint {} from the angles alone", j + 1),
                e,
            )
        })?;
    }
    Ok(ProcessingLoss {
        fitness_logged,
        fitness_angles,
        loss: [0, 1].map(|j| fitness_logged[j] - fitness_angles[j]),
        rows: both.len(),
    })
}

/// True if `log` has both exact derivative columns (θ̇ and θ̈).
pub fn has_derivatives(log: &Log) -> bool {
    log.theta_dot.is_some() && log.theta_ddot.is_some()
}

/// The processing loss of `beta` on `log` (`None` without derivative
/// columns): `logged` is the log already processed and predicted on the
/// logged-derivative route, if at hand; `opts` the configured processing
/// (its `use_logged_derivatives` and `rows` are set here).
pub fn processing_loss(
    log: &Log,
    opts: &ProcessOptions,
    model: &Model,
    geometry: &Geometry,
    beta: &[f64],
    logged: Option<(&Processed, &[f64])>,
) -> Result<Option<ProcessingLoss>, PipelineError> {
    if !has_derivatives(log) {
        return Ok(None);
    }
    let mut o = opts.clone();
    o.use_logged_derivatives = false;
    let (angles, pa) = predict_route(log, &o, model, geometry, beta)
        .map_err(|e| IdentError::external("the angles-only route of the processing loss", e))?;
    let own;
    let (pl_proc, pl) = match logged {
        Some(l) => l,
        None => {
            o.use_logged_derivatives = true;
            own = predict_route(log, &o, model, geometry, beta).map_err(|e| {
                IdentError::external("the logged-derivative route of the processing loss", e)
            })?;
            (&own.0, &own.1[..])
        }
    };
    loss_between(pl_proc, pl, &angles, &pa).map(Some)
}
