//! The simulated robot (`aras_dyn::sim`) configured from `[simulation]`:
//! the stand-in for the hardware (`docs/simulator.md`).

use std::path::Path;

use anyhow::{Context, Result};
use aras_dyn::Params;
use aras_dyn::sim::{Controller, Sensors, SimConfig, SimLog};

use crate::config::Config;

/// The simulator's settings for a run of `duration_s` with noise `seed`.
/// With `simulation.feedforward`, the nominal robot's inverse dynamics is
/// fed forward.
pub fn sim_config(cfg: &Config, nominal: &Params, duration_s: f64, seed: u64) -> SimConfig {
    let s = &cfg.simulation;
    SimConfig {
        duration_s,
        lead_in_s: s.lead_in_s,
        output_rate_hz: s.rate_hz,
        substeps: s.substeps,
        controller: Controller {
            kp: s.kp,
            kd: s.kd,
            velocity_cutoff_hz: s.velocity_cutoff_hz,
            feedforward: s.feedforward.then(|| nominal.clone()),
        },
        torque_limit: s.torque_limit,
        friction_smoothing: s.friction_smoothing,
        lugre: s.lugre,
        sensors: Sensors {
            counts_per_rev: s.counts_per_rev,
            gear_ratios: s.gear_ratios,
            torque_constants: s.torque_constants,
            current_noise_std: s.current_noise_std_a,
        },
        torque_delay_samples: s.torque_delay_samples,
        torque_delay_fraction: s.torque_delay_fraction,
        seed,
    }
}

/// The simulated robot's true parameters: `simulation.truth` if given,
/// else the nominal robot.
pub fn truth(cfg: &Config, dir: &Path, nominal: &Params) -> Result<Params> {
    match &cfg.simulation.truth {
        Some(p) => crate::robot::load_params(p, dir).context("key `simulation.truth`"),
        None => Ok(nominal.clone()),
    }
}

/// Simulates `periods` periods of a periodic trajectory (or `duration_s`)
/// and writes `csv` plus its sidecar (with the exact derivatives and the truth).
pub fn run_and_write(
    truth: &Params,
    traj: &dyn aras_dyn::Trajectory,
    sim: &SimConfig,
    csv: &Path,
) -> Result<SimLog> {
    let log = aras_dyn::sim::simulate(truth, traj, sim).context("simulating the robot")?;
    aras_dyn::sim::write_log(csv, &log, true)
        .with_context(|| format!("writing {}", csv.display()))?;
    Ok(log)
}
