//! A simulated serial arm: the stand-in for a lab's robot (`docs/urdf.md`,
//! "Simulator").
//!
//! The drive, controller and sensor models are the ARAS-Diamond
//! simulator's (`docs/simulator.md`), per joint of any number of joints:
//! both drive their joints with [`aras_core::drive::PdDrive`] and step
//! their plant with [`aras_core::Rk4`].
//!
//! * **Plant**: `M(q) q̈ = τ − b(q, q̇)` of the truth parameters (rigid
//!   bodies, armature and the model's friction columns, Coulomb as
//!   `tanh(q̇/w)`), from the mass matrix by RNEA
//!   ([`UrdfModel::forward_dynamics`]), integrated by classical RK4 at the
//!   output rate times `substeps`, the torque held between controller ticks
//!   (zero-order hold, as a digital amplifier does).
//! * **Controller** at the output rate: PD in joint space on the quantised
//!   encoder angles, the velocity from a first-order low-pass of their
//!   backward difference, feedforward `τ_ff = RNEA(q_d, q̇_d, q̈_d)` of a
//!   nominal parameter vector, torque limits.
//! * **Sensors**: encoder quantisation (`counts_per_rev × gear_ratio` counts
//!   per joint revolution or per metre), Gaussian current noise times torque
//!   constant times gear ratio on the logged torque.
//! * **Lead-in**: the log starts once the controller has settled on the
//!   trajectory, as a real excitation log does.
//!
//! Seeded: the same settings give the same bytes.

use aras_core::Rk4;
use aras_core::drive::{self, PdDrive};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::{UrdfError, UrdfModel, Workspace};

/// Drives and sensors, one entry per joint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArmSensors {
    /// Encoder counts per motor revolution (after quadrature decoding).
    pub counts_per_rev: Vec<u32>,
    /// Gear ratio: motor revolutions per joint revolution (per metre for a
    /// prismatic joint).
    pub gear_ratios: Vec<f64>,
    /// Motor torque constants, N·m/A.
    pub torque_constants: Vec<f64>,
    /// Standard deviation of the current measurement noise, A.
    pub current_noise_std: Vec<f64>,
}

impl ArmSensors {
    /// `joints` alike: a 16-bit (65 536-count) motor encoder behind a 100:1
    /// gear (9.6e-7 rad per count at the joint), `K_t` = 0.05 N·m/A and
    /// 10 mA current noise (0.05 N·m joint torque noise): a harmonic-drive
    /// arm joint. (Coarser encoders make the PD loop's reaction to the
    /// quantisation a torque the angles do not show: `docs/urdf.md`.)
    pub fn uniform(joints: usize) -> Self {
        Self {
            counts_per_rev: vec![65_536; joints],
            gear_ratios: vec![100.0; joints],
            torque_constants: vec![0.05; joints],
            current_noise_std: vec![0.010; joints],
        }
    }

    /// Joint position resolution `2π/(counts · ratio)`
    /// ([`drive::encoder_resolution`]).
    pub fn resolution(&self) -> Vec<f64> {
        self.counts_per_rev
            .iter()
            .zip(&self.gear_ratios)
            .map(|(&c, &r)| drive::encoder_resolution(c, r))
            .collect()
    }

    /// Joint torque noise `σ_i K_t N`, N·m ([`drive::torque_noise_std`]).
    pub fn torque_noise_std(&self) -> Vec<f64> {
        self.current_noise_std
            .iter()
            .zip(&self.torque_constants)
            .zip(&self.gear_ratios)
            .map(|((&s, &k), &r)| drive::torque_noise_std(s, k, r))
            .collect()
    }
}

/// Drive effects of a simulated robot's joints, the same on every joint,
/// for a truth vector ([`DriveTruth::parameters`]); defaults in
/// [`DriveTruth::default`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DriveTruth {
    /// Viscous friction, N·m·s/rad (N·s/m).
    pub viscous: f64,
    /// Coulomb friction, N·m (N).
    pub coulomb: f64,
    /// Torque offset, N·m (N).
    pub offset: f64,
    /// Rotor inertia reflected to the joint (armature), kg·m² (kg).
    pub armature: f64,
}

impl Default for DriveTruth {
    /// A harmonic-drive arm joint: 0.3 N·m·s/rad, 0.5 N·m Coulomb, no
    /// offset, 0.1 kg·m² armature (a 1e-5 kg·m² rotor behind 100:1).
    fn default() -> Self {
        Self {
            viscous: 0.3,
            coulomb: 0.5,
            offset: 0.0,
            armature: 0.1,
        }
    }
}

impl DriveTruth {
    /// The standard parameters of `model` with the URDF's inertials and
    /// these drive effects on every joint column the model has.
    pub fn parameters(&self, model: &UrdfModel) -> Vec<f64> {
        let mut p = model.urdf_parameters();
        for (x, name) in p.iter_mut().zip(model.parameter_names()) {
            let tag = name.rsplit('.').next().unwrap_or_default();
            let joint = model
                .joints()
                .iter()
                .any(|j| name == format!("{}.{tag}", j.name));
            if joint {
                *x = match tag {
                    "Fv" => self.viscous,
                    "Fc" => self.coulomb,
                    "offset" => self.offset,
                    "Ia" => self.armature,
                    _ => *x,
                };
            }
        }
        p
    }
}

/// PD control in joint space with model feedforward.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArmController {
    /// Proportional gains, N·m/rad (N/m).
    pub kp: Vec<f64>,
    /// Derivative gains, N·m·s/rad (N·s/m).
    pub kd: Vec<f64>,
    /// Cut-off of the first-order low-pass on the differentiated encoder
    /// angle, Hz.
    pub velocity_cutoff_hz: f64,
    /// Standard parameters of the feedforward model (`None`: pure PD).
    pub feedforward: Option<Vec<f64>>,
}

impl ArmController {
    /// Gains for a closed-loop bandwidth of `bandwidth_hz` on each joint's
    /// inertia at `q`, critically damped: `Kp = m_j ω²`, `Kd = 2 m_j ω`
    /// with `m_j = 1/(M⁻¹)_jj`, the inertia joint `j` shows with the other
    /// joints free (not the mass matrix's diagonal `M_jj`, which for two
    /// nearly parallel axes — the Panda's joints 1 and 3 near joint 2 = 0 —
    /// is far above what their differential motion has, and whose gains
    /// then drive that motion unstable through the velocity filter and the
    /// sample delay); a 30 Hz velocity filter (the ARAS-Diamond
    /// simulator's) and feedforward of `params`.
    pub fn for_model(
        model: &UrdfModel,
        params: &[f64],
        q: &[f64],
        bandwidth_hz: f64,
    ) -> Result<Self, UrdfError> {
        let inertia = joint_inertias(model, params, std::slice::from_ref(&q.to_vec()))?;
        Ok(Self::with_inertias(&inertia, params, bandwidth_hz))
    }

    /// [`Self::for_model`] on the smallest inertia each joint shows along
    /// one period of `trajectory` (200 instants), so that the loop stays
    /// at or below `bandwidth_hz` everywhere the robot goes.
    pub fn for_trajectory(
        model: &UrdfModel,
        params: &[f64],
        trajectory: &dyn ArmTrajectory,
        period_s: f64,
        bandwidth_hz: f64,
    ) -> Result<Self, UrdfError> {
        let n = model.dof();
        let (mut v, mut a) = (vec![0.0; n], vec![0.0; n]);
        let states: Vec<Vec<f64>> = (0..200)
            .map(|k| {
                let mut q = vec![0.0; n];
                trajectory.eval_into(period_s * k as f64 / 200.0, &mut q, &mut v, &mut a);
                q
            })
            .collect();
        let inertia = joint_inertias(model, params, &states)?;
        Ok(Self::with_inertias(&inertia, params, bandwidth_hz))
    }

    fn with_inertias(inertia: &[f64], params: &[f64], bandwidth_hz: f64) -> Self {
        let w = std::f64::consts::TAU * bandwidth_hz;
        Self {
            kp: inertia.iter().map(|d| d * w * w).collect(),
            kd: inertia.iter().map(|d| 2.0 * d * w).collect(),
            velocity_cutoff_hz: 30.0,
            feedforward: Some(params.to_vec()),
        }
    }
}

/// Per joint the smallest `1/(M⁻¹)_jj` over `states`.
fn joint_inertias(
    model: &UrdfModel,
    params: &[f64],
    states: &[Vec<f64>],
) -> Result<Vec<f64>, UrdfError> {
    let n = model.dof();
    let mut ws = Workspace::new(model);
    let mut out = vec![f64::INFINITY; n];
    for q in states {
        let (m, _) = model.mass_matrix_and_bias(&mut ws, params, q, &vec![0.0; n])?;
        let m = nalgebra::DMatrix::from_row_slice(n, n, &m);
        let inv = m.cholesky().ok_or_else(|| UrdfError::Setting {
            name: "params".into(),
            problem: "the mass matrix is not positive definite at the trajectory's \
                      configurations: give physically consistent parameters"
                .into(),
        })?;
        let inv = inv.inverse();
        for j in 0..n {
            out[j] = out[j].min(1.0 / inv[(j, j)]);
        }
    }
    Ok(out)
}

/// Everything about a run except the robot and the trajectory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArmSimulation {
    /// Recorded time, s (`floor(duration · rate)` rows).
    pub duration_s: f64,
    /// Time the robot tracks the trajectory before the log starts, s.
    pub lead_in_s: f64,
    /// Controller and log rate, Hz.
    pub output_rate_hz: f64,
    /// RK4 steps per output sample.
    pub substeps: usize,
    /// The controller.
    pub controller: ArmController,
    /// Symmetric torque limits per joint, N·m (N); `None`: unlimited.
    pub torque_limit: Option<Vec<f64>>,
    /// Drives and sensors.
    pub sensors: ArmSensors,
    /// Seed of the noise generator.
    pub seed: u64,
    /// Effects the simulated robot has beyond the model's columns (default
    /// none): what a diagnosis is to find.
    #[serde(default)]
    pub hidden: Vec<HiddenEffect>,
}

/// A torque the simulated robot's joint feels that the model it is
/// simulated from does not contain, evaluated here and only here, so that
/// finding it tests the diagnosis rather than a shared formula.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum HiddenEffect {
    /// Friction above the Coulomb level at low speed on joint `joint`
    /// (0-based): `level · tanh(q̇/w) · exp(−(q̇/v_s)²)` N·m, `w` the
    /// model's Coulomb width of the joint (boundary lubrication, a
    /// breakaway hump).
    Stribeck {
        /// Joint index, 0-based.
        joint: usize,
        /// Static friction minus Coulomb friction, N·m (N), ≥ 0.
        level: f64,
        /// Stribeck velocity, rad/s (m/s), > 0.
        v_s: f64,
    },
    /// A hardening spring `k3 (q − q0)³` on joint `joint` (0-based): a
    /// cable or a capstan's stiffness, outside the candidate effects.
    CubicSpring {
        /// Joint index, 0-based.
        joint: usize,
        /// Stiffness, N·m/rad³ (N/m³).
        k3: f64,
        /// Its neutral position, rad (m).
        q0: f64,
    },
}

impl HiddenEffect {
    /// The joint it acts on.
    fn joint(&self) -> usize {
        match *self {
            HiddenEffect::Stribeck { joint, .. } | HiddenEffect::CubicSpring { joint, .. } => joint,
        }
    }
}

/// The hidden effects and the Coulomb widths their sign uses.
struct Plant<'a> {
    hidden: &'a [HiddenEffect],
    widths: &'a [f64],
}

impl Plant<'_> {
    /// The hidden effects' joint torques at `(q, q̇)` subtracted from `tau`
    /// into `out`: what the plant's dynamics is driven by.
    fn torque(&self, q: &[f64], v: &[f64], tau: &[f64], out: &mut [f64]) {
        let widths = self.widths;
        out.copy_from_slice(tau);
        for h in self.hidden {
            match *h {
                HiddenEffect::Stribeck { joint, level, v_s } => {
                    let x = v[joint];
                    out[joint] -= level * (x / widths[joint]).tanh() * (-(x / v_s).powi(2)).exp();
                }
                HiddenEffect::CubicSpring { joint, k3, q0 } => {
                    out[joint] -= k3 * (q[joint] - q0).powi(3);
                }
            }
        }
    }
}

impl ArmSimulation {
    /// 60 s at 1 kHz after a 2 s lead-in, 2 RK4 substeps, no torque limit,
    /// seed 1, with `controller` and `sensors`.
    pub fn new(controller: ArmController, sensors: ArmSensors) -> Self {
        Self {
            duration_s: 60.0,
            lead_in_s: 2.0,
            output_rate_hz: 1000.0,
            substeps: 2,
            controller,
            torque_limit: None,
            sensors,
            seed: 1,
            hidden: Vec::new(),
        }
    }

    /// Checks every setting against the model's joint count.
    fn validate(&self, joints: usize) -> Result<(), UrdfError> {
        let bad = |name: &str, problem: String| UrdfError::Setting {
            name: name.into(),
            problem,
        };
        for (name, v) in [
            ("duration_s", self.duration_s),
            ("output_rate_hz", self.output_rate_hz),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(name, format!("{v} must be a positive number")));
            }
        }
        if !(self.lead_in_s.is_finite() && self.lead_in_s >= 0.0) {
            return Err(bad(
                "lead_in_s",
                format!("{} must be a number ≥ 0", self.lead_in_s),
            ));
        }
        if self.substeps == 0 {
            return Err(bad("substeps", "0 must be at least 1".into()));
        }
        let c = &self.controller;
        let s = &self.sensors;
        let lengths = [
            ("controller.kp", c.kp.len()),
            ("controller.kd", c.kd.len()),
            ("sensors.counts_per_rev", s.counts_per_rev.len()),
            ("sensors.gear_ratios", s.gear_ratios.len()),
            ("sensors.torque_constants", s.torque_constants.len()),
            ("sensors.current_noise_std", s.current_noise_std.len()),
        ];
        for (name, len) in lengths.into_iter().chain(
            self.torque_limit
                .as_ref()
                .map(|l| ("torque_limit", l.len())),
        ) {
            if len != joints {
                return Err(bad(
                    name,
                    format!("{len} entries for a robot of {joints} joints: give one per joint"),
                ));
            }
        }
        if s.counts_per_rev.contains(&0)
            || s.gear_ratios.iter().any(|r| !(r.is_finite() && *r > 0.0))
        {
            return Err(bad(
                "sensors",
                "counts per revolution and gear ratios must be positive".into(),
            ));
        }
        for h in &self.hidden {
            let ok = h.joint() < joints
                && match *h {
                    HiddenEffect::Stribeck { level, v_s, .. } => {
                        level.is_finite() && level >= 0.0 && v_s.is_finite() && v_s > 0.0
                    }
                    HiddenEffect::CubicSpring { k3, q0, .. } => k3.is_finite() && q0.is_finite(),
                };
            if !ok {
                return Err(bad(
                    "hidden",
                    format!(
                        "{h:?} is not a valid effect of a robot of {joints} joints: joints are \
                         0-based, a Stribeck level is ≥ 0 and its v_s > 0, numbers are finite"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A simulated log: one row per controller tick, every joint.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmLog {
    /// The URDF's joint names, in joint order.
    pub joint_names: Vec<String>,
    /// Time of each row, s (the trajectory's time).
    pub t: Vec<f64>,
    /// Quantised encoder positions, `q[joint][row]`.
    pub q: Vec<Vec<f64>>,
    /// Exact positions.
    pub q_exact: Vec<Vec<f64>>,
    /// Logged torques: the held command plus current noise.
    pub tau: Vec<Vec<f64>>,
    /// The held command without noise.
    pub tau_clean: Vec<Vec<f64>>,
    /// Exact velocity at each row.
    pub qd: Vec<Vec<f64>>,
    /// Exact acceleration at each row (under the held command).
    pub qdd: Vec<Vec<f64>>,
}

impl ArmLog {
    /// The log's channels for `aras_log::write_log` (the format's one
    /// writer): angles and torques, and the exact `q̇`, `q̈` when
    /// `derivatives`.
    pub fn columns(&self, derivatives: bool) -> aras_log::Columns {
        aras_log::Columns {
            t: self.t.clone(),
            theta: self.q.clone(),
            tau: self.tau.clone(),
            theta_dot: if derivatives {
                self.qd.clone()
            } else {
                Vec::new()
            },
            theta_ddot: if derivatives {
                self.qdd.clone()
            } else {
                Vec::new()
            },
        }
    }

    /// The log in the toolkit's CSV format (`docs/log-format.md`):
    /// `t, theta1 … thetaN, tau1 … tauN`, with the exact `dthetaJ`,
    /// `ddthetaJ` when `derivatives`; the joint names in a comment line.
    pub fn to_csv(&self, derivatives: bool) -> String {
        use std::fmt::Write;
        let n = self.q.len();
        let mut s = format!("# joints: {}\nt", self.joint_names.join(","));
        let mut kinds = vec!["theta", "tau"];
        if derivatives {
            kinds.extend(["dtheta", "ddtheta"]);
        }
        for k in &kinds {
            for j in 1..=n {
                let _ = write!(s, ",{k}{j}");
            }
        }
        s.push('\n');
        for r in 0..self.t.len() {
            let _ = write!(s, "{}", self.t[r]);
            let mut blocks = vec![&self.q, &self.tau];
            if derivatives {
                blocks.extend([&self.qd, &self.qdd]);
            }
            for b in blocks {
                for c in b {
                    let _ = write!(s, ",{}", c[r]);
                }
            }
            s.push('\n');
        }
        s
    }
}

/// A desired motion: `(q_d, q̇_d, q̈_d)` written into the slices at time `t`.
pub trait ArmTrajectory {
    /// The desired state at `t`, s.
    fn eval_into(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]);
}

impl ArmTrajectory for aras_excite::FourierTrajectory<nalgebra::Dyn> {
    fn eval_into(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) {
        aras_excite::FourierTrajectory::eval_into(self, t, q, qd, qdd);
    }
}

/// Simulates `model` with standard parameters `truth` tracking
/// `trajectory` (see the module docs). A model whose Coulomb column is the
/// sign of the rate (width 0) is refused: RK4 cannot integrate through its
/// jump at a reversal. The robot starts on the trajectory
/// `lead_in_s` before its time 0; row `k` holds `t_k = k / rate`, the
/// quantised (and exact) positions at `t_k`, the torque commanded at `t_k` (held until
/// `t_{k+1}`) with and without noise, and the exact `q̇`, `q̈` at `t_k`.
pub fn simulate(
    model: &UrdfModel,
    truth: &[f64],
    trajectory: &dyn ArmTrajectory,
    sim: &ArmSimulation,
) -> Result<ArmLog, UrdfError> {
    let n = model.dof();
    sim.validate(n)?;
    let widths = match &model.settings().coulomb_width {
        crate::CoulombWidth::Uniform(w) => vec![*w; n],
        crate::CoulombWidth::PerJoint(w) => w.clone(),
    };
    if (model.joint_columns().coulomb || !sim.hidden.is_empty())
        && widths.iter().any(|w| w.is_nan() || *w <= 0.0)
    {
        return Err(UrdfError::Setting {
            name: "coulomb_width".into(),
            problem: "the simulated robot's Coulomb law is the sign of the rate (width 0), \
                      which the integration cannot follow through a reversal (the joint \
                      chatters and the tracking breaks down); simulate a model with a \
                      smooth law, e.g. CoulombWidth::Uniform(0.02) rad/s"
                .into(),
        });
    }

    if truth.len() != model.parameter_count() {
        return Err(UrdfError::Dimension {
            what: "truth parameters",
            expected: model.parameter_count(),
            found: truth.len(),
        });
    }
    let mut ws = Workspace::new(model);
    let rows = (sim.duration_s * sim.output_rate_hz).floor() as usize;
    let lead = (sim.lead_in_s * sim.output_rate_hz).round() as i64;
    let dt = 1.0 / sim.output_rate_hz;
    let h = dt / sim.substeps as f64;
    let noise = sim.sensors.torque_noise_std();
    let c = &sim.controller;
    let mut rng = StdRng::seed_from_u64(sim.seed);
    let (mut qd_des, mut vd_des, mut ad_des) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let t0 = -lead as f64 * dt;
    trajectory.eval_into(t0, &mut qd_des, &mut vd_des, &mut ad_des);
    // The state `[q, q̇]`, starting on the trajectory.
    let mut x = [qd_des.as_slice(), vd_des.as_slice()].concat();
    let mut drive = PdDrive::new(
        sim.sensors.resolution(),
        vd_des.clone(),
        c.velocity_cutoff_hz,
        dt,
    );
    let mut rk4 = Rk4::new(2 * n);
    let mut log = ArmLog {
        joint_names: model.joint_names(),
        t: Vec::with_capacity(rows),
        q: vec![Vec::with_capacity(rows); n],
        q_exact: vec![Vec::with_capacity(rows); n],
        tau: vec![Vec::with_capacity(rows); n],
        tau_clean: vec![Vec::with_capacity(rows); n],
        qd: vec![Vec::with_capacity(rows); n],
        qdd: vec![Vec::with_capacity(rows); n],
    };
    let (mut tau, mut driving) = (vec![0.0; n], vec![0.0; n]);
    let plant_of = Plant {
        hidden: &sim.hidden,
        widths: &widths,
    };
    for k in -lead..rows as i64 {
        let t = k as f64 * dt;
        let (q, v) = x.split_at(n);
        drive.sense(q);
        trajectory.eval_into(t, &mut qd_des, &mut vd_des, &mut ad_des);
        match &c.feedforward {
            Some(p) => {
                model.inverse_dynamics_with(&mut ws, p, &qd_des, &vd_des, &ad_des, &mut tau)?
            }
            None => tau.fill(0.0),
        }
        drive.add_torque(&c.kp, &c.kd, &qd_des, &vd_des, &mut tau);
        if let Some(l) = &sim.torque_limit {
            drive::saturate(&mut tau, l);
        }
        if k >= 0 {
            let q_meas = drive.angles();
            plant_of.torque(q, v, &tau, &mut driving);
            let a = model.forward_dynamics(&mut ws, truth, q, v, &driving)?;
            log.t.push(t);
            for j in 0..n {
                let z: f64 = StandardNormal.sample(&mut rng);
                log.q[j].push(q_meas[j]);
                log.q_exact[j].push(q[j]);
                log.tau[j].push(tau[j] + noise[j] * z);
                log.tau_clean[j].push(tau[j]);
                log.qd[j].push(v[j]);
                log.qdd[j].push(a[j]);
            }
        }
        for _ in 0..sim.substeps {
            rk4.step(&mut x, h, |s, d| {
                let (q, v) = s.split_at(n);
                plant_of.torque(q, v, &tau, &mut driving);
                let a = model.forward_dynamics(&mut ws, truth, q, v, &driving)?;
                d[..n].copy_from_slice(v);
                d[n..].copy_from_slice(&a);
                Ok::<(), UrdfError>(())
            })?;
        }
    }
    Ok(log)
}
