//! The measurement log: CSV `t,theta1,theta2,tau1,tau2` (+ optional exact
//! derivatives) and the JSON sidecar `LOG.json` with the ground truth
//! (format `aras-log/1`, `docs/log-format.md`).

use std::path::Path;

use aras_log::{Columns, Sidecar};
use serde::Serialize;

use super::SimConfig;
use crate::{DynError, Effect, Params, SimError, Trajectory};

/// The noise that was added.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Noise {
    /// Current noise standard deviation (A).
    pub current_std_a: [f64; 2],
    /// Resulting joint torque noise standard deviation (N·m).
    pub torque_std_nm: [f64; 2],
    /// Encoder resolution at the joint (rad).
    pub encoder_resolution_rad: [f64; 2],
    /// Torque samples lag angle samples by this many samples.
    pub torque_delay_samples: usize,
    /// And by this further fraction of a sample (linear interpolation).
    #[serde(skip_serializing_if = "super::is_zero")]
    pub torque_delay_fraction: f64,
}

/// Ground truth of a simulated log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Truth {
    /// The true parameters, as a parameter-file object.
    pub params: Params,
    /// The true model's effects (paper effects + extras present).
    pub effects: Vec<Effect>,
    /// Noise added.
    pub noise: Noise,
    /// Seed of the noise generator.
    pub seed: u64,
    /// The simulator's settings.
    pub simulator: SimConfig,
}

/// The `aras-log/1` sidecar of a simulated log: the sensors, the period of a
/// periodic trajectory, `"torques": "held"`, and the ground truth ([`Truth`]) under `truth`.
pub(crate) fn sidecar(
    truth: &Params,
    traj: &dyn Trajectory,
    cfg: &SimConfig,
) -> Result<Sidecar, DynError> {
    let s = &cfg.sensors;
    let truth = Truth {
        params: truth.clone(),
        effects: truth.model()?.effects().to_vec(),
        noise: Noise {
            current_std_a: s.current_noise_std,
            torque_std_nm: s.torque_noise_std(),
            encoder_resolution_rad: s.resolution(),
            torque_delay_samples: cfg.torque_delay_samples,
            torque_delay_fraction: cfg.torque_delay_fraction,
        },
        seed: cfg.seed,
        simulator: cfg.clone(),
    };
    let mut sidecar = Sidecar {
        format: Some(aras_log::FORMAT.into()),
        truth: Some(serde_json::to_value(&truth).expect("the truth always serialises")),
        // The logged torque is the controller's command, held over the
        // step to the next tick (zero-order hold).
        torques: Some(aras_log::TorqueTiming::Held),
        ..Sidecar::default()
    };
    sidecar.sensors.torque_constants = Some(s.torque_constants.to_vec());
    sidecar.sensors.gear_ratios = Some(s.gear_ratios.to_vec());
    sidecar.sensors.counts_per_rev = Some(s.counts_per_rev.map(f64::from).to_vec());
    sidecar.excitation.period_s = traj.period().filter(|p| p.is_finite() && *p > 0.0);
    Ok(sidecar)
}

/// A simulated log in memory. All columns have the same length.
#[derive(Debug, Clone, PartialEq)]
pub struct SimLog {
    /// Time (s).
    pub t: Vec<f64>,
    /// Measured (quantised) motor angles (rad).
    pub theta: Vec<[f64; 2]>,
    /// Measured motor torques (N·m).
    pub tau: Vec<[f64; 2]>,
    /// The same torques without sensor noise (N·m): what a perfect model
    /// predicts, so the fitness (78) of `tau_clean` against `tau` is the
    /// noise ceiling of the log (not written to the CSV).
    pub tau_clean: Vec<[f64; 2]>,
    /// Exact motor rates (rad/s).
    pub theta_dot: Vec<[f64; 2]>,
    /// Exact motor accelerations (rad/s²).
    pub theta_ddot: Vec<[f64; 2]>,
    /// The sidecar: sensors, period, and the [`Truth`] under `truth`.
    pub sidecar: Sidecar,
}

impl SimLog {
    pub(crate) fn with_capacity(n: usize) -> Self {
        Self {
            t: Vec::with_capacity(n),
            theta: Vec::with_capacity(n),
            tau: Vec::with_capacity(n),
            tau_clean: Vec::with_capacity(n),
            theta_dot: Vec::with_capacity(n),
            theta_ddot: Vec::with_capacity(n),
            sidecar: Sidecar::default(),
        }
    }

    pub(crate) fn push(
        &mut self,
        t: f64,
        th: [f64; 2],
        tau: [f64; 2],
        tau_clean: [f64; 2],
        td: [f64; 2],
        tdd: [f64; 2],
    ) {
        self.t.push(t);
        self.theta.push(th);
        self.tau.push(tau);
        self.tau_clean.push(tau_clean);
        self.theta_dot.push(td);
        self.theta_ddot.push(tdd);
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True if there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// Writes the log to `csv` and its sidecar beside it
/// ([`aras_log::sidecar_path`]) through the format's writer
/// ([`aras_log::write_log`]: atomic, shortest round-trip numbers, so a seed
/// always gives the same bytes). With `derivatives`, the exact
/// `dtheta1,dtheta2,ddtheta1,ddtheta2` columns are appended.
pub fn write_log(csv: &Path, log: &SimLog, derivatives: bool) -> Result<(), SimError> {
    let pair = |v: &[[f64; 2]]| {
        [0, 1]
            .map(|j| v.iter().map(|r| r[j]).collect::<Vec<f64>>())
            .to_vec()
    };
    let (theta_dot, theta_ddot) = if derivatives {
        (pair(&log.theta_dot), pair(&log.theta_ddot))
    } else {
        (vec![Vec::new(); 2], vec![Vec::new(); 2])
    };
    let columns = Columns {
        t: log.t.clone(),
        theta: pair(&log.theta),
        tau: pair(&log.tau),
        theta_dot,
        theta_ddot,
    };
    Ok(aras_log::write_log(csv, &columns, &log.sidecar)?)
}
