//! The measurement log: CSV `t,theta1,theta2,tau1,tau2` (+ optional exact
//! derivatives) and the JSON sidecar `LOG.json` with the ground truth
//! (format `aras-log/1`, `docs/log-format.md`).

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::SimConfig;
use crate::{DynError, Effect, Params, SimError, Trajectory};

/// Sensor description needed to interpret the log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensorInfo {
    /// Motor torque constants (N·m/A).
    pub torque_constants: [f64; 2],
    /// Drive ratios.
    pub gear_ratios: [f64; 2],
    /// Encoder counts per motor revolution.
    pub counts_per_rev: [u32; 2],
}

/// The excitation's period, present when the trajectory is periodic.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Excitation {
    /// Period (s).
    pub period_s: f64,
}

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

/// The JSON sidecar of a log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sidecar {
    /// Always `"aras-log/1"`.
    pub format: &'static str,
    /// Sensors.
    pub sensors: SensorInfo,
    /// Present only for periodic trajectories.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub excitation: Option<Excitation>,
    /// Ground truth (simulated logs only).
    pub truth: Truth,
}

impl Sidecar {
    pub(crate) fn new(
        truth: &Params,
        traj: &dyn Trajectory,
        cfg: &SimConfig,
    ) -> Result<Self, DynError> {
        let s = &cfg.sensors;
        Ok(Self {
            format: "aras-log/1",
            sensors: SensorInfo {
                torque_constants: s.torque_constants,
                gear_ratios: s.gear_ratios,
                counts_per_rev: s.counts_per_rev,
            },
            excitation: traj
                .period()
                .filter(|p| p.is_finite() && *p > 0.0)
                .map(|period_s| Excitation { period_s }),
            truth: Truth {
                params: truth.clone(),
                effects: truth.model()?.effects().to_vec(),
                noise: Noise {
                    current_std_a: s.current_noise_std,
                    torque_std_nm: s.torque_noise_std(),
                    encoder_resolution_rad: s.resolution(),
                    torque_delay_samples: cfg.torque_delay_samples,
                },
                seed: cfg.seed,
                simulator: cfg.clone(),
            },
        })
    }
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
    /// The sidecar's content.
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
            sidecar: Sidecar {
                format: "aras-log/1",
                sensors: SensorInfo {
                    torque_constants: [0.0; 2],
                    gear_ratios: [0.0; 2],
                    counts_per_rev: [0; 2],
                },
                excitation: None,
                truth: Truth {
                    params: Params::zero(45.0, 45.0),
                    effects: Vec::new(),
                    noise: Noise {
                        current_std_a: [0.0; 2],
                        torque_std_nm: [0.0; 2],
                        encoder_resolution_rad: [0.0; 2],
                        torque_delay_samples: 0,
                    },
                    seed: 0,
                    simulator: SimConfig::default(),
                },
            },
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

/// The sidecar path of a log: the same path with extension `.json`
/// (`run.csv` → `run.json`).
pub fn sidecar_path(csv: &Path) -> PathBuf {
    csv.with_extension("json")
}

fn atomic_write(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), SimError> {
    let io = |source| SimError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let file = std::fs::File::create(&tmp).map_err(io)?;
    let mut w = std::io::BufWriter::new(file);
    write(&mut w).map_err(io)?;
    w.into_inner()
        .map_err(|e| io(e.into_error()))?
        .sync_all()
        .map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// Writes the log to `csv` and its sidecar to [`sidecar_path`]`(csv)`,
/// each atomically (temporary file, then rename). Numbers use Rust's
/// shortest round-trip formatting, so a seed always gives the same bytes.
/// With `derivatives`, the exact `dtheta1,dtheta2,ddtheta1,ddtheta2`
/// columns are appended.
pub fn write_log(csv: &Path, log: &SimLog, derivatives: bool) -> Result<(), SimError> {
    atomic_write(csv, |w| {
        write!(w, "t,theta1,theta2,tau1,tau2")?;
        if derivatives {
            write!(w, ",dtheta1,dtheta2,ddtheta1,ddtheta2")?;
        }
        writeln!(w)?;
        for i in 0..log.len() {
            let (th, tau) = (log.theta[i], log.tau[i]);
            write!(w, "{},{},{},{},{}", log.t[i], th[0], th[1], tau[0], tau[1])?;
            if derivatives {
                let (d, dd) = (log.theta_dot[i], log.theta_ddot[i]);
                write!(w, ",{},{},{},{}", d[0], d[1], dd[0], dd[1])?;
            }
            writeln!(w)?;
        }
        Ok(())
    })?;
    let json = serde_json::to_string_pretty(&log.sidecar).expect("the sidecar always serialises");
    atomic_write(&sidecar_path(csv), |w| {
        w.write_all(json.as_bytes())?;
        w.write_all(b"\n")
    })
}
