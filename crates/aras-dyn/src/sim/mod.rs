//! The simulated robot: the stand-in for hardware (`docs/simulator.md`).
//!
//! * **Plant state** `(X, Ẋ)` in task space (rad, rad/s), integrated by
//!   classical RK4 at `output_rate_hz × substeps` (default 1 kHz × 2 =
//!   2 kHz), motor torque held constant between controller ticks (zero-order
//!   hold, as a digital amplifier does). Motor angles come from the inverse
//!   kinematics, so no forward kinematics is needed. The step is
//!   [`aras_core::Rk4`] on the flat state `[X, Ẋ, z]`.
//! * **Plant torques**: the truth [`Params`] — rigid links (33), viscous +
//!   Coulomb friction with `sign` smoothed by `tanh(θ̇/w)` (no chattering, no
//!   event handling; `w` far below the encoder's velocity resolution),
//!   capstan elasticity (50), and every extra effect present in the
//!   parameters (`Params::extra`), with the same smoothing.
//! * **Controller** at the output rate: PD in motor space on the quantised
//!   encoder angles, the velocity from a low-pass-filtered backward
//!   difference, optional model feedforward, torque limits: the shared
//!   drive model [`aras_core::drive`].
//! * **Sensors**: encoder quantisation (`counts_per_rev × gear_ratio` counts
//!   per joint revolution), Gaussian current noise times torque constant
//!   times gear ratio on the measured torque, an optional sample delay of the
//!   torque against the angles. Seeded; the same seed gives the same bytes.
//!
//! Defaults and why they are realistic: `docs/simulator.md`.

mod log;
mod lugre;

use aras_core::Rk4;
use aras_core::drive::{self, PdDrive};
use aras_kin::Motion;
use aras_kin::{Geometry, evaluate};
use nalgebra::Vector2;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;

use crate::regressor::Sign;
use crate::{DynError, Dynamics, Params, SimError, Trajectory};

pub use log::{Noise, SimLog, Truth, write_log};
pub use lugre::LuGre;

/// Motor-side sensors and drive of each joint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sensors {
    /// Encoder counts per motor revolution (after quadrature decoding).
    pub counts_per_rev: [u32; 2],
    /// Drive (capstan) ratio: motor revolutions per joint revolution.
    pub gear_ratios: [f64; 2],
    /// Motor torque constants (N·m/A).
    pub torque_constants: [f64; 2],
    /// Standard deviation of the current measurement noise (A).
    pub current_noise_std: [f64; 2],
}

impl Default for Sensors {
    /// 4096 counts/rev (1024-line quadrature encoder), capstan ratio 10,
    /// `K_t` = 30.2 mN·m/A (a Maxon RE 35-class motor), 10 mA current noise
    /// (≈ 3 mN·m joint torque noise).
    fn default() -> Self {
        Self {
            counts_per_rev: [4096; 2],
            gear_ratios: [10.0; 2],
            torque_constants: [0.0302; 2],
            current_noise_std: [0.010; 2],
        }
    }
}

impl Sensors {
    /// Joint-angle resolution `2π/(counts · ratio)` (rad,
    /// [`drive::encoder_resolution`]).
    pub fn resolution(&self) -> [f64; 2] {
        std::array::from_fn(|j| {
            drive::encoder_resolution(self.counts_per_rev[j], self.gear_ratios[j])
        })
    }

    /// Joint torque noise `σ_i K_t N` (N·m, [`drive::torque_noise_std`]).
    pub fn torque_noise_std(&self) -> [f64; 2] {
        std::array::from_fn(|j| {
            drive::torque_noise_std(
                self.current_noise_std[j],
                self.torque_constants[j],
                self.gear_ratios[j],
            )
        })
    }
}

/// PD controller in motor space with optional model feedforward.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Controller {
    /// Proportional gains (N·m/rad).
    pub kp: [f64; 2],
    /// Derivative gains (N·m·s/rad).
    pub kd: [f64; 2],
    /// Cut-off of the first-order low-pass on the differentiated encoder
    /// angle (Hz).
    pub velocity_cutoff_hz: f64,
    /// Model for feedforward `τ_ff = Y(X_d, Ẋ_d, Ẍ_d) β` (friction with the
    /// exact sign of the desired velocity); `None` for pure PD (the paper).
    pub feedforward: Option<Params>,
}

impl Default for Controller {
    /// `Kp = 30 N·m/rad`, `Kd = 0.3 N·m·s/rad`, 30 Hz velocity filter, no
    /// feedforward: about 9 Hz closed-loop bandwidth on the ≈ 0.01 kg·m²
    /// motor-space inertia, well below the 1 kHz control rate.
    fn default() -> Self {
        Self {
            kp: [30.0; 2],
            kd: [0.3; 2],
            velocity_cutoff_hz: 30.0,
            feedforward: None,
        }
    }
}

/// Everything about a simulation run except the robot and the trajectory.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimConfig {
    /// Recorded time (s); the log has `floor(duration · rate)` samples
    /// (fewer by the torque delay's rows when the lead-in is shorter than
    /// the delay).
    pub duration_s: f64,
    /// Time (s) the robot tracks the trajectory before the log starts:
    /// the integration begins at trajectory time `−lead_in_s` (rounded to
    /// whole samples), on the trajectory with the controller's first
    /// torque, and rows are recorded from trajectory time 0 on, so the
    /// first row is the trajectory's phase 0 whatever the lead-in. The
    /// lead-in lets the PD loop settle from the start-up transient, as a
    /// real experiment is logged after the robot is under way. 0: the log
    /// starts with the start-up.
    pub lead_in_s: f64,
    /// Controller and log rate (Hz).
    pub output_rate_hz: f64,
    /// RK4 steps per output sample (internal rate = output rate × substeps).
    pub substeps: usize,
    /// The controller.
    pub controller: Controller,
    /// Symmetric motor torque limits at the joint (N·m).
    pub torque_limit: [f64; 2],
    /// Width `w` of the `tanh(θ̇/w)` friction smoothing (rad/s).
    pub friction_smoothing: f64,
    /// LuGre friction in place of the smoothed Coulomb term of (49)
    /// (`None`, the default: `Fc tanh(θ̇/w)`). The extra effects keep the
    /// `tanh` smoothing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lugre: Option<LuGre>,
    /// Sensors and drives.
    pub sensors: Sensors,
    /// Torque samples lag the angle samples by this many samples.
    pub torque_delay_samples: usize,
    /// A further fraction of a sample, in `[0, 1)`, by which the torque
    /// lags (default 0): the logged torque is the torque sequence delayed
    /// by `torque_delay_samples + torque_delay_fraction` samples,
    /// interpolated linearly between samples, as a sensor chain whose
    /// timing is not a whole sample (anti-alias filter, ADC or bus
    /// latency) sees the smooth motor current.
    #[serde(skip_serializing_if = "is_zero")]
    pub torque_delay_fraction: f64,
    /// Seed of the noise generator.
    pub seed: u64,
}

impl Default for SimConfig {
    /// 160 s (16 periods of the paper's 10 s excitation) at 1 kHz after a
    /// 2 s lead-in, 2 RK4 substeps, 2.4 N·m limit (8 A × 30.2 mN·m/A × 10),
    /// 0.03 rad/s friction smoothing, default sensors, no delay, seed 1.
    /// The lead-in: the start-up transient of the default PD loop decays
    /// below the steady tracking error within 0.5 s (`docs/simulator.md`),
    /// 2 s leaves a factor of four.
    fn default() -> Self {
        Self {
            duration_s: 160.0,
            lead_in_s: 2.0,
            output_rate_hz: 1000.0,
            substeps: 2,
            controller: Controller::default(),
            torque_limit: [2.4; 2],
            friction_smoothing: 0.03,
            lugre: None,
            sensors: Sensors::default(),
            torque_delay_samples: 0,
            torque_delay_fraction: 0.0,
            seed: 1,
        }
    }
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn positive(key: &'static str, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SimError::Config {
            key,
            value,
            reason: "must be a positive finite number",
        })
    }
}

fn non_negative(key: &'static str, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SimError::Config {
            key,
            value,
            reason: "must be a finite number ≥ 0",
        })
    }
}

impl SimConfig {
    /// Checks every setting; errors name the setting and the rule.
    pub fn validate(&self) -> Result<(), SimError> {
        positive("duration_s", self.duration_s)?;
        positive("output_rate_hz", self.output_rate_hz)?;
        non_negative("lead_in_s", self.lead_in_s)?;
        if self.lead_in_s * self.output_rate_hz > 1e9 {
            return Err(SimError::Config {
                key: "lead_in_s",
                value: self.lead_in_s,
                reason: "must give at most 1e9 samples",
            });
        }
        if self.substeps == 0 || self.substeps > 1000 {
            return Err(SimError::Config {
                key: "substeps",
                value: self.substeps as f64,
                reason: "must be between 1 and 1000",
            });
        }
        if !(self.torque_delay_fraction.is_finite()
            && (0.0..1.0).contains(&self.torque_delay_fraction))
        {
            return Err(SimError::Config {
                key: "torque_delay_fraction",
                value: self.torque_delay_fraction,
                reason: "must lie in [0, 1): whole samples go in torque_delay_samples",
            });
        }
        let n = (self.duration_s * self.output_rate_hz).floor();
        if !(2.0..=1e9).contains(&n) || self.dropped_rows() as f64 >= n {
            return Err(SimError::Config {
                key: "duration_s",
                value: self.duration_s,
                reason: "must give at least 2 samples (and more than the torque delay), at most 1e9",
            });
        }
        let c = &self.controller;
        for j in 0..2 {
            non_negative("controller.kp", c.kp[j])?;
            non_negative("controller.kd", c.kd[j])?;
            positive("torque_limit", self.torque_limit[j])?;
            positive("sensors.gear_ratios", self.sensors.gear_ratios[j])?;
            positive("sensors.torque_constants", self.sensors.torque_constants[j])?;
            non_negative(
                "sensors.current_noise_std",
                self.sensors.current_noise_std[j],
            )?;
            positive(
                "sensors.counts_per_rev",
                self.sensors.counts_per_rev[j] as f64,
            )?;
        }
        positive("controller.velocity_cutoff_hz", c.velocity_cutoff_hz)?;
        positive("friction_smoothing", self.friction_smoothing)?;
        Ok(())
    }
}

impl SimConfig {
    /// Rows dropped at the start of the log for the torque delay: the
    /// whole samples, and one more for a fraction (it interpolates towards
    /// the sample before).
    fn delay_rows(&self) -> usize {
        self.torque_delay_samples + usize::from(self.torque_delay_fraction > 0.0)
    }

    /// Whole samples of the lead-in, `round(lead_in_s · rate)`.
    pub fn lead_in_samples(&self) -> usize {
        (self.lead_in_s * self.output_rate_hz).round() as usize
    }

    /// Rows missing at the start of the log: the delay's rows that the
    /// lead-in does not cover (the lead-in's torques fill the others).
    fn dropped_rows(&self) -> usize {
        self.delay_rows().saturating_sub(self.lead_in_samples())
    }
}

/// The plant: truth dynamics with smooth or LuGre friction.
struct Plant<'a> {
    dy: &'a Dynamics,
    geometry: Geometry,
    sign: Sign,
    lugre: Option<LuGre>,
}

/// The plant's state: task-space position and rate, and the LuGre bristle
/// deflections of the joints (zero and unused without LuGre).
#[derive(Clone, Copy)]
struct State {
    x: Vector2<f64>,
    v: Vector2<f64>,
    z: Vector2<f64>,
}

impl State {
    /// The state as the integrator's flat vector `[X, Ẋ, z]`.
    fn flat(&self) -> [f64; 6] {
        [
            self.x[0], self.x[1], self.v[0], self.v[1], self.z[0], self.z[1],
        ]
    }

    /// The state of a flat vector `[X, Ẋ, z]`.
    fn from_flat(s: &[f64]) -> State {
        State {
            x: Vector2::new(s[0], s[1]),
            v: Vector2::new(s[2], s[3]),
            z: Vector2::new(s[4], s[5]),
        }
    }
}

impl Plant<'_> {
    /// `(Ẋ, Ẍ, ż)` at `state` under the motor torque `tau`.
    #[allow(clippy::type_complexity)]
    fn deriv(
        &self,
        state: &State,
        tau: &Vector2<f64>,
    ) -> Result<(Vector2<f64>, Vector2<f64>, Vector2<f64>), DynError> {
        let s = evaluate(
            &self.geometry,
            &Motion::new(state.x, state.v, Vector2::zeros()),
        )?;
        let (friction, z_rate) = match &self.lugre {
            None => (
                self.dy.friction_torque(&s.joint.vel, self.sign),
                Vector2::zeros(),
            ),
            Some(l) => {
                let f = &self.dy.params().friction;
                let w = &s.joint.vel;
                (
                    Vector2::from_fn(|j, _| {
                        l.torque(j, f.coulomb[j], f.viscous[j], w[j], state.z[j])
                    }),
                    Vector2::from_fn(|j, _| l.rate(j, f.coulomb[j], w[j], state.z[j])),
                )
            }
        };
        let other =
            friction + self.dy.elastic_torque(&s.joint.pos) + self.dy.extra_torque(&s, self.sign);
        let a = self.dy.forward_links(&s, &(tau - other))?;
        Ok((state.v, a, z_rate))
    }

    /// One classical RK4 step of length `h` under the held `tau`.
    fn rk4(
        &self,
        rk4: &mut Rk4<[f64; 6]>,
        state: &mut State,
        tau: &Vector2<f64>,
        h: f64,
    ) -> Result<(), DynError> {
        let mut flat = state.flat();
        rk4.step(&mut flat, h, |s, d| -> Result<(), DynError> {
            let (xd, vd, zd) = self.deriv(&State::from_flat(s), tau)?;
            d.copy_from_slice(&[xd[0], xd[1], vd[0], vd[1], zd[0], zd[1]]);
            Ok(())
        })?;
        *state = State::from_flat(&flat);
        Ok(())
    }
}

/// Simulates the robot `truth` tracking `traj` and returns the log.
///
/// With `L` lead-in samples ([`SimConfig::lead_in_samples`]) the robot
/// starts on the trajectory at `t_0 = −L / rate` (`X = X_d(t_0)`,
/// `Ẋ = Ẋ_d(t_0)`), and the controller runs from there. Row `k ≥ 0` holds
/// `t_k = k / rate` (trajectory time `t_k`), the quantised angles at `t_k`,
/// the measured torque of sample `k − delay`, and the exact `θ̇`, `θ̈` at
/// `t_k` (`θ̈` just after the controller's update). Rows whose delayed
/// torque would fall before `t_0` are dropped (only when the lead-in is
/// shorter than the delay).
pub fn simulate(
    truth: &Params,
    traj: &dyn Trajectory,
    cfg: &SimConfig,
) -> Result<SimLog, SimError> {
    cfg.validate()?;
    if let Some(b) = &truth.extra.presliding_friction {
        return Err(SimError::Config {
            key: "truth extra.presliding_friction",
            value: b.displacement,
            reason: "the simulator's bristle friction is its `lugre` setting (a LuGre state \
                     integrated with the motion); remove presliding_friction from the truth \
                     parameters and set lugre instead",
        });
    }
    let at0 = |source| SimError::Dynamics { t: 0.0, source };
    let dy = Dynamics::new(truth).map_err(at0)?;
    let ff = match &cfg.controller.feedforward {
        Some(p) => Some(Dynamics::new(p).map_err(at0)?),
        None => None,
    };
    let fc = truth.friction.coulomb;
    if let Some(l) = &cfg.lugre {
        l.validate(fc)?;
    }
    let plant = Plant {
        dy: &dy,
        geometry: *dy.geometry(),
        sign: Sign::Tanh(cfg.friction_smoothing),
        lugre: cfg.lugre,
    };
    let g = plant.geometry;
    let n = (cfg.duration_s * cfg.output_rate_hz).floor() as usize;
    let dt = 1.0 / cfg.output_rate_hz;
    let h = dt / cfg.substeps as f64;
    let noise = cfg.sensors.torque_noise_std();
    let c = &cfg.controller;
    let mut rng = StdRng::seed_from_u64(cfg.seed);

    let desired = |t: f64| -> Result<aras_kin::KinematicSample, SimError> {
        evaluate(&g, &traj.eval(t)).map_err(|e| SimError::Trajectory {
            t,
            source: e.into(),
        })
    };
    let lead = cfg.lead_in_samples() as i64;
    let d0 = desired(-lead as f64 * dt)?;
    let mut state = State {
        x: d0.task.pos,
        v: d0.task.vel,
        z: match &cfg.lugre {
            Some(l) => Vector2::from_fn(|j, _| l.steady_state(j, fc[j], d0.joint.vel[j])),
            None => Vector2::zeros(),
        },
    };
    let mut drive = PdDrive::new(
        cfg.sensors.resolution().to_vec(),
        d0.joint.vel.as_slice().to_vec(),
        c.velocity_cutoff_hz,
        dt,
    );
    let mut rk4 = Rk4::fixed();

    let mut log = SimLog::with_capacity(n);
    // (measured, noise-free) torque of every step from the first, for the
    // delayed rows.
    let mut tau_hist: Vec<([f64; 2], [f64; 2])> = Vec::with_capacity(n + lead as usize);
    for k in -lead..n as i64 {
        let t = k as f64 * dt;
        // Steps since the start.
        let i = (k + lead) as usize;
        let at = |source| SimError::Dynamics { t, source };
        let s = evaluate(&g, &Motion::new(state.x, state.v, Vector2::zeros()))
            .map_err(|e| at(e.into()))?;
        drive.sense(s.joint.pos.as_slice());
        let theta_meas = drive.angles();
        let d = if i == 0 { d0 } else { desired(t)? };
        let mut tau = Vector2::zeros();
        if let Some(f) = &ff {
            tau += f.inverse(&d);
        }
        drive.add_torque(
            &c.kp,
            &c.kd,
            d.joint.pos.as_slice(),
            d.joint.vel.as_slice(),
            tau.as_mut_slice(),
        );
        drive::saturate(tau.as_mut_slice(), &cfg.torque_limit);
        let (_, xdd, _) = plant.deriv(&state, &tau).map_err(at)?;
        let theta_ddot = s.jacobian.matrix() * xdd + s.jacobian_dot * state.v;
        let mut measured = [0.0; 2];
        for j in 0..2 {
            let z: f64 = StandardNormal.sample(&mut rng);
            measured[j] = tau[j] + noise[j] * z;
        }
        tau_hist.push((measured, [tau[0], tau[1]]));
        if k >= 0 && i >= cfg.delay_rows() {
            let d = cfg.torque_delay_samples;
            let (mut measured, mut clean) = tau_hist[i - d];
            let phi = cfg.torque_delay_fraction;
            if phi > 0.0 {
                // Linear interpolation towards the sample before; the
                // noise is that sample's own draw.
                let (_, before) = tau_hist[i - d - 1];
                for j in 0..2 {
                    let noise = measured[j] - clean[j];
                    clean[j] = (1.0 - phi) * clean[j] + phi * before[j];
                    measured[j] = clean[j] + noise;
                }
            }
            log.push(
                t,
                [theta_meas[0], theta_meas[1]],
                measured,
                clean,
                [s.joint.vel[0], s.joint.vel[1]],
                [theta_ddot[0], theta_ddot[1]],
            );
        }
        for _ in 0..cfg.substeps {
            if let Some(l) = &cfg.lugre {
                let w = evaluate(&g, &Motion::new(state.x, state.v, Vector2::zeros()))
                    .map_err(|e| at(e.into()))?
                    .joint
                    .vel;
                l.check_step(fc, [w[0], w[1]], h)
                    .map_err(|ratio| SimError::StiffFriction { t, ratio })?;
            }
            plant.rk4(&mut rk4, &mut state, &tau, h).map_err(at)?;
        }
    }
    log.sidecar =
        log::sidecar(truth, traj, cfg).map_err(|e| SimError::Dynamics { t: 0.0, source: e })?;
    Ok(log)
}
