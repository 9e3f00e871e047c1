//! A single-joint simulator producing logs with known friction.
//!
//! The joint follows a multisine `q(t) = Σᵢ Aᵢ sin(2π fᵢ s t + φᵢ)` (slow and
//! fast components, many reversals; `s` scales the speed for held-out logs).
//! The friction torque is a LuGre model with optional hidden effects
//! ([`TrueFriction`]): position ripple, a slow drift of the Coulomb level
//! (warming), a Coulomb level that varies along the stroke or grows with
//! the load the joint carries (logged as `load`), Maxwell-slip elements
//! beside LuGre (several presliding lengths), direction asymmetry of
//! the viscous term, a residual inertia
//! and a delay of the torque signal. Samples are taken at irregular times
//! (uniform steps in `[min_step, max_step]`, occasional gaps) with Gaussian
//! sensor noise.
//!
//! The LuGre state is integrated by classical fourth-order Runge–Kutta on the
//! exact velocity with steps small against the bristle time constant — a code
//! path independent of the models' exact update, so fits of simulated logs
//! test the models, not a shared discretisation.

use serde::{Deserialize, Serialize};

use crate::{JointLog, JointMotion, LuGre, sgn};

/// One sine of the motion: amplitude (rad), frequency (Hz), phase (rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sine {
    /// Amplitude, rad.
    pub amplitude: f64,
    /// Frequency, Hz.
    pub frequency: f64,
    /// Phase, rad.
    pub phase: f64,
}

/// A position ripple `A sin(k q + φ)`: `k` periods per radian·2π, i.e. `k`
/// cycles per revolution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ripple {
    /// Cycles per revolution `k` (the ripple is `A sin(k q + φ)`).
    #[serde(alias = "harmonic")]
    pub cycles: f64,
    /// Amplitude `A`, N·m.
    pub amplitude: f64,
    /// Phase `φ`, rad.
    pub phase: f64,
}

/// An elastoplastic (Maxwell-slip) element: a spring that deflects with the
/// position and slips at its level, adding `F · x / x_s`, `x ∈ [−x_s, x_s]`.
/// Several of them are the generalized Maxwell-slip picture of a joint with
/// several presliding lengths (gear stages, bearings, seals).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SlipElement {
    /// Slip level `F`, N·m.
    pub level: f64,
    /// Deflection at slip `x_s`, rad.
    pub length: f64,
}

/// The true friction of the simulated joint: LuGre plus hidden effects.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrueFriction {
    /// The LuGre core.
    pub lugre: LuGre,
    /// Position-dependent ripple terms added to the torque.
    pub ripple: Vec<Ripple>,
    /// Drift of the Coulomb and static levels, N·m/s: `g(v, t) = g(v) + c t`
    /// (negative for warming).
    pub drift: f64,
    /// Direction asymmetry of the viscous term, N·m·s/rad: `+ a |v|`.
    pub asymmetry: f64,
    /// Residual inertia (rigid-body model error), kg·m²: `+ J ddq`.
    pub inertia: f64,
    /// Delay of the logged torque behind the motion, s.
    pub delay: f64,
    /// Position dependence of the Coulomb and static levels, N·m:
    /// `g(v, q) = g(v) + Σ A sin(k q + φ)` (a seal or a preload that varies
    /// along the stroke). Inside the LuGre law, so presliding and sliding
    /// both see it; the torque deviation is odd in the direction.
    #[serde(default)]
    pub coulomb_map: Vec<Ripple>,
    /// Load dependence of the Coulomb and static levels, N·m per N·m:
    /// `g(v, L) = g(v) + μ |L|` (gear and bearing friction grow with the
    /// torque transmitted), `L` the simulation's [`JointSimulation::load`];
    /// `μ ≥ 0` (the integration step is sized for levels that do not fall
    /// below the Coulomb level minus the map's swing).
    #[serde(default)]
    pub load_coefficient: f64,
    /// Maxwell-slip elements in parallel with LuGre (evaluated on the
    /// sample grid from the true positions: exact for an elastoplastic
    /// element, whose state is piecewise linear in `q`).
    #[serde(default)]
    pub slip: Vec<SlipElement>,
}

impl TrueFriction {
    /// LuGre only, no hidden effect.
    pub fn lugre(lugre: LuGre) -> Self {
        Self {
            lugre,
            ripple: Vec::new(),
            drift: 0.0,
            asymmetry: 0.0,
            inertia: 0.0,
            delay: 0.0,
            coulomb_map: Vec::new(),
            load_coefficient: 0.0,
            slip: Vec::new(),
        }
    }
}

/// The torque a simulated joint carries, N·m: `gravity · cos(q + phase) +
/// inertia · q̈` (a link's weight and its acceleration, as a rigid-body
/// model would give it). Logged as the `load` column.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LoadTorque {
    /// Gravity amplitude, N·m.
    pub gravity: f64,
    /// Angle of the gravity term's maximum, rad.
    pub phase: f64,
    /// Inertia of the carried link, kg·m².
    pub inertia: f64,
}

impl LoadTorque {
    /// The load at position `q` and acceleration `a`.
    pub fn at(&self, q: f64, a: f64) -> f64 {
        self.gravity * (q + self.phase).cos() + self.inertia * a
    }
}

/// Gaussian sensor noise standard deviations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SensorNoise {
    /// Torque noise, N·m.
    pub tau: f64,
    /// Position noise, rad.
    pub q: f64,
    /// Velocity noise, rad/s.
    pub dq: f64,
}

impl SensorNoise {
    /// No noise.
    pub const NONE: Self = Self {
        tau: 0.0,
        q: 0.0,
        dq: 0.0,
    };
}

/// Settings of one simulated log. [`JointSimulation::default`] is a 60 s log
/// of a collaborative-robot-like joint (friction of a few tenths of a N·m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointSimulation {
    /// Log length, s.
    pub duration: f64,
    /// Smallest sampling step, s.
    pub min_step: f64,
    /// Largest sampling step, s.
    pub max_step: f64,
    /// Probability that a step is a gap of 5–20 × `max_step`.
    pub gap_probability: f64,
    /// The motion's sines.
    pub motion: Vec<Sine>,
    /// Speed scale `s`: frequencies are multiplied by it.
    pub speed: f64,
    /// The true friction.
    pub friction: TrueFriction,
    /// Sensor noise.
    pub noise: SensorNoise,
    /// Random seed (sampling and noise).
    pub seed: u64,
    /// The torque the joint carries, logged as `load` when given.
    #[serde(default)]
    pub load: Option<LoadTorque>,
}

/// A typical joint: `F_c = 0.3`, `F_s = 0.42` N·m, `v_s = 0.04` rad/s,
/// `σ₀ = 300` N·m/rad (presliding 1.4 mrad), `σ₁ = 0.8`, `σ₂ = 0.12`.
pub fn typical_lugre() -> LuGre {
    LuGre {
        offset: 0.01,
        coulomb: 0.3,
        static_friction: 0.42,
        stribeck_velocity: 0.04,
        shape: 2.0,
        sigma0: 300.0,
        sigma1: 0.8,
        sigma2: 0.12,
    }
}

impl Default for JointSimulation {
    fn default() -> Self {
        Self {
            duration: 60.0,
            min_step: 1e-3,
            max_step: 16e-3,
            gap_probability: 1e-3,
            // Slow large strokes with faster small ones on top: velocities
            // from 0 to about 1.5 rad/s and local reversals with
            // small-amplitude presliding.
            motion: vec![
                Sine {
                    amplitude: 0.8,
                    frequency: 0.05,
                    phase: 0.0,
                },
                Sine {
                    amplitude: 0.25,
                    frequency: 0.23,
                    phase: 1.0,
                },
                Sine {
                    amplitude: 0.04,
                    frequency: 0.9,
                    phase: 2.0,
                },
                Sine {
                    amplitude: 0.006,
                    frequency: 1.9,
                    phase: 0.5,
                },
            ],
            speed: 1.0,
            friction: TrueFriction::lugre(typical_lugre()),
            noise: SensorNoise {
                tau: 0.005,
                q: 1e-5,
                dq: 2e-4,
            },
            seed: 1,
            load: None,
        }
    }
}

/// A simulated log and its noise-free torque.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulatedJoint {
    /// The log as a sensor would record it (noise, irregular sampling).
    pub log: JointLog,
    /// The friction torque without noise at the logged times.
    pub clean_tau: Vec<f64>,
}

/// SplitMix64: a tiny, well-mixed generator, enough for sampling jitter and
/// Gaussian noise (no dependency needed).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        // Box–Muller.
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

impl JointSimulation {
    /// Position, velocity and acceleration of the motion at time `t`.
    pub fn kinematics(&self, t: f64) -> (f64, f64, f64) {
        let (mut q, mut v, mut a) = (0.0, 0.0, 0.0);
        for s in &self.motion {
            let w = std::f64::consts::TAU * s.frequency * self.speed;
            let (sn, cs) = (w * t + s.phase).sin_cos();
            q += s.amplitude * sn;
            v += s.amplitude * w * cs;
            a -= s.amplitude * w * w * sn;
        }
        (q, v, a)
    }

    fn sample_times(&self, rng: &mut Rng) -> Vec<f64> {
        let mut t = vec![0.0];
        loop {
            let mut dt = self.min_step + (self.max_step - self.min_step) * rng.uniform();
            if rng.uniform() < self.gap_probability {
                dt = self.max_step * (5.0 + 15.0 * rng.uniform());
            }
            let next = t[t.len() - 1] + dt;
            if next > self.duration {
                break;
            }
            t.push(next);
        }
        t
    }

    /// Runs the simulation.
    pub fn run(&self, name: &str) -> SimulatedJoint {
        let mut rng = Rng(self.seed ^ 0xA5A5_5A5A_1234_5678);
        let times = self.sample_times(&mut rng);
        let f = &self.friction;
        let m = &f.lugre;
        // The law at time t: the Coulomb level drifts, varies along the
        // stroke and grows with the load; the breakaway excess over it does
        // not.
        let load = self.load.filter(|_| f.load_coefficient != 0.0);
        let law = |t: f64| {
            let mut shift = f.drift * t;
            if load.is_some() || !f.coulomb_map.is_empty() {
                let (q, _, a) = self.kinematics(t);
                if let Some(l) = load {
                    shift += f.load_coefficient * l.at(q, a).abs();
                }
                shift += f
                    .coulomb_map
                    .iter()
                    .map(|r| r.amplitude * (r.cycles * q + r.phase).sin())
                    .sum::<f64>();
            }
            aras_core::LuGreLaw {
                coulomb: m.coulomb + shift,
                static_level: m.static_friction + shift,
                stribeck_velocity: m.stribeck_velocity,
                shape: m.shape,
                stiffness: m.sigma0,
            }
        };
        let g = |v: f64, t: f64| law(t).level(v);
        let zdot = |t: f64, z: f64| law(t).rate(self.kinematics(t).1, z);
        // Torque is read at t − delay; integrate the state to those times.
        // Before t = 0 the motion is the same analytic function.
        let t0 = -f.delay.max(0.0);
        let v0 = self.kinematics(t0).1;
        let mut z = sgn(v0) * g(v0, t0) / m.sigma0;
        let mut tz = t0;
        let swing: f64 = f.coulomb_map.iter().map(|r| r.amplitude.abs()).sum();
        let gmin = (m.coulomb.min(m.static_friction) - swing).max(1e-9);
        let mut clean = Vec::with_capacity(times.len());
        // Each slip element starts slipping in the direction of the
        // initial motion, as the LuGre state does.
        let mut slip: Vec<f64> = f.slip.iter().map(|e| sgn(v0) * e.length).collect();
        let mut q_prev = self.kinematics(t0).0;
        for &tk in &times {
            let target = tk - f.delay;
            while tz < target {
                // RK4 step: the bristle rate σ₀|v|/g times the step at most
                // 0.1 (RK4 error per step ≈ 0.1⁵/120) and at most 0.5 ms.
                let v = self.kinematics(tz).1.abs();
                let h = (0.1 * gmin / (m.sigma0 * v.max(1e-12)))
                    .min(5e-4)
                    .min(target - tz);
                let k1 = zdot(tz, z);
                let k2 = zdot(tz + 0.5 * h, z + 0.5 * h * k1);
                let k3 = zdot(tz + 0.5 * h, z + 0.5 * h * k2);
                let k4 = zdot(tz + h, z + h * k3);
                z += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                tz += h;
                if target - tz < 1e-15 {
                    tz = target;
                }
            }
            let (q, v, a) = self.kinematics(target);
            let mut tau = m.offset + m.sigma0 * z + m.sigma1 * zdot(target, z) + m.sigma2 * v;
            for r in &f.ripple {
                tau += r.amplitude * (r.cycles * q + r.phase).sin();
            }
            tau += f.asymmetry * v.abs() + f.inertia * a;
            for (x, e) in slip.iter_mut().zip(&f.slip) {
                *x = (*x + q - q_prev).clamp(-e.length, e.length);
                tau += e.level * *x / e.length;
            }
            q_prev = q;
            clean.push(tau);
        }
        let n = times.len();
        let mut log = JointLog {
            motion: JointMotion {
                name: name.to_string(),
                t: times.clone(),
                q: Vec::with_capacity(n),
                dq: Vec::with_capacity(n),
                ddq: Some(Vec::with_capacity(n)),
                load: self.load.map(|_| Vec::with_capacity(n)),
                dq_from_q: false,
                notes: Vec::new(),
            },
            tau: Vec::with_capacity(n),
        };
        for (k, &tk) in times.iter().enumerate() {
            let (q, v, a) = self.kinematics(tk);
            log.q.push(q + self.noise.q * rng.normal());
            log.dq.push(v + self.noise.dq * rng.normal());
            if let Some(d) = log.ddq.as_mut() {
                d.push(a);
            }
            if let (Some(l), Some(c)) = (self.load, log.load.as_mut()) {
                c.push(l.at(q, a));
            }
            log.tau.push(clean[k] + self.noise.tau * rng.normal());
        }
        SimulatedJoint {
            log,
            clean_tau: clean,
        }
    }
}
