//! The noise ceiling: the fitness (78) a *perfect* prediction scores
//! against the same noisy log, so a simulated run's fitness can be read
//! against what is attainable rather than against another experiment.
//!
//! The perfect prediction is the torque the simulated motors really
//! produced, before the sensor noise was added
//! (`aras_dyn::sim::SimLog::tau_clean`): it needs no model, no parameters
//! and no processing, so nothing of the method under test enters it. It is
//! known only for a log simulated in the same run.
//!
//! * **Every row**: the noise-free torque against the log's raw torques, on
//!   the rows the fitness (78) of a prediction uses.
//! * **Kept rows**: the noise-free torque is put through exactly the
//!   processing of the measured one (period averaging, and the zero-phase
//!   filter or harmonic projection that both filtering modes apply to the
//!   torques) and compared with the processed measured torque on the rows
//!   away from velocity reversals, as the in-sample fitness is. What keeps
//!   both below 100 % is the sensor noise alone.

use crate::PipelineError;
use aras_ident::IdentError;
use aras_kin::Geometry;
use aras_log::Log;
use aras_signal::ProcessOptions;
use serde::Serialize;

use crate::prepare::Prepared;

/// The noise ceiling of one log, per joint (%).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Ceiling {
    /// On every row, against the log's raw torques (compare with the
    /// fitness on every row).
    pub all: [f64; 2],
    /// On the rows `keep` selects (those away from velocity reversals),
    /// processed like the identification data.
    pub kept: [f64; 2],
}

/// Fitness (78) per joint of the noise-free torques `clean` (one per row of
/// `log`) against `log` (see the module docs). `prep` is `log` processed
/// with `opts` and stacked, `keep` its kept stacked rows.
pub fn noise_ceiling(
    log: &Log,
    clean: &[[f64; 2]],
    prep: &Prepared,
    opts: &ProcessOptions,
    geometry: &Geometry,
    keep: &[bool],
) -> Result<Ceiling, PipelineError> {
    if clean.len() != log.len() {
        return Err(IdentError::InvalidData {
            context: format!("the noise ceiling of {}", log.name),
            reason: format!(
                "the noise-free torques have {} rows but {} has {}",
                clean.len(),
                log.name,
                log.len()
            ),
        }
        .into());
    }
    let processed = &prep.processed;
    let mut all = [0.0; 2];
    for (j, a) in all.iter_mut().enumerate() {
        let (m, p): (Vec<f64>, Vec<f64>) = (0..log.len())
            .filter(|&r| processed.sample_of_row(r).is_some())
            .map(|r| (log.tau[j][r], clean[r][j]))
            .unzip();
        *a = aras_ident::validate::fitness(&m, &p).map_err(|e| {
            IdentError::external(
                format!("the noise ceiling of joint {} on every row", j + 1),
                e,
            )
        })?;
    }

    // The noise-free torques through the same processing: the angles are
    // the same, so the same periods, rows and derivatives are chosen.
    let mut quiet = log.clone();
    for j in 0..2 {
        quiet.tau[j] = clean.iter().map(|c| c[j]).collect();
    }
    let twin =
        aras_signal::process(&quiet, opts, &aras_kin::task_motion(geometry)).map_err(|e| {
            IdentError::external("processing the noise-free torques for the noise ceiling", e)
        })?;
    let n = prep.n();
    if twin.samples.len() != n {
        return Err(IdentError::InvalidData {
            context: format!("the noise ceiling of {}", log.name),
            reason: format!(
                "the noise-free twin of {} was processed into {} samples, the log into {n}",
                log.name,
                twin.samples.len()
            ),
        }
        .into());
    }
    let mut kept = [0.0; 2];
    for (j, k) in kept.iter_mut().enumerate() {
        let mut tau = twin.samples.tau[j].clone();
        prep.limit_torque(&mut tau).map_err(|e| {
            IdentError::external(
                "band-limiting the noise-free torques as the measured ones",
                e,
            )
        })?;
        let (m, p): (Vec<f64>, Vec<f64>) = (0..n)
            .filter(|&i| keep.get(j * n + i).copied().unwrap_or(false))
            .map(|i| (prep.t()[j * n + i], tau[i]))
            .unzip();
        *k = aras_ident::validate::fitness(&m, &p).map_err(|e| {
            IdentError::external(
                format!("the noise ceiling of joint {} on the kept rows", j + 1),
                e,
            )
        })?;
    }
    Ok(Ceiling { all, kept })
}
