//! The noise ceiling: the fitness (78) a *perfect* prediction scores
//! against the same noisy log, so a simulated run's fitness can be read
//! against what is attainable rather than against another experiment.
//!
//! The perfect prediction is the simulated robot's own noise-free torque:
//! the true parameters with every effect of the true model, its smooth
//! friction (`tanh(θ̇/w)`, the simulator's `friction_smoothing`), evaluated
//! at the same processed samples. On every row it is compared with the
//! log's raw torques (repeated on every period of an averaged log), as the
//! fitness (78) is; on the kept rows it is filtered like the model's
//! prediction (parallel filtering filters it; torque-only does not). What
//! keeps it below 100 % is the sensor noise left after processing and the
//! processing itself (derivative estimates, filter edges); an
//! identification can only approach it, or exceed it in-sample by fitting
//! noise.

use anyhow::{Context, Result};
use aras_dyn::{Dynamics, Params, Sign};
use nalgebra::Vector2;

use crate::config::FilteringMode;
use crate::identify::{Prepared, raw_fitness};

/// The noise ceiling of one log, per joint (%).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Ceiling {
    /// On every row, against the log's raw torques (compare with the
    /// fitness on every row).
    pub all: [f64; 2],
    /// On the rows `keep` selects (those away from velocity reversals).
    pub kept: [f64; 2],
}

/// Fitness (78) per joint of the true robot's noise-free torques on
/// `prep` (see the module docs), on every row and on the stacked rows
/// `keep` selects. `friction_smoothing` is the simulator's `tanh` width
/// (rad/s).
#[allow(clippy::needless_range_loop)]
pub fn noise_ceiling(
    prep: &Prepared,
    truth: &Params,
    friction_smoothing: f64,
    mode: FilteringMode,
    keep: &[bool],
) -> Result<Ceiling> {
    let dy = Dynamics::new(truth).context("the true robot's dynamics")?;
    let sign = Sign::Tanh(friction_smoothing);
    let s = &prep.processed.samples;
    let n = s.len();
    let mut tau = vec![0.0; 2 * n];
    for i in 0..n {
        let v = |a: &[Vec<f64>; 2]| Vector2::new(a[0][i], a[1][i]);
        let k = dy
            .sample(&v(&s.x), &v(&s.x_dot), &v(&s.x_ddot))
            .with_context(|| format!("the true robot at processed sample {i}"))?;
        let t = dy.link_torque(&k)
            + dy.friction_torque(&k.theta_dot, sign)
            + dy.elastic_torque(&k.theta)
            + dy.extra_torque(&k, sign);
        tau[i] = t[0];
        tau[n + i] = t[1];
    }
    // Every row: against the log's raw torques, as the fitness (78) is.
    let all = raw_fitness(&prep.processed, &tau)?;
    if let (Some(sos), FilteringMode::Parallel) = (&prep.filter, mode) {
        for j in 0..2 {
            let x = &tau[j * n..(j + 1) * n];
            let y = if prep.periodic() {
                sos.filtfilt_periodic(x)
            } else {
                sos.filtfilt(x)
            }
            .context("filtering the true torques")?;
            tau[j * n..(j + 1) * n].copy_from_slice(&y);
        }
    }
    let mut kept = [0.0; 2];
    for (j, k) in kept.iter_mut().enumerate() {
        let rows = (j * n..(j + 1) * n).filter(|&i| keep.get(i).copied().unwrap_or(false));
        let (m, p): (Vec<f64>, Vec<f64>) = rows.map(|i| (prep.t()[i], tau[i])).unzip();
        *k = aras_ident::validate::fitness(&m, &p)
            .with_context(|| format!("the noise ceiling of joint {} on the kept rows", j + 1))?;
    }
    Ok(Ceiling { all, kept })
}
