//! A simulated joint drive: incremental encoder, current sensor and the PD
//! loop a digital servo amplifier closes on them, for any number of joints.
//!
//! The simulators of ARAS-Diamond and of a URDF arm model the drive alike
//! (`docs/simulator.md`): the angle the controller sees is the true angle
//! rounded to whole encoder counts ([`quantise`], [`encoder_resolution`]);
//! its rate is a first-order low-pass of the backward difference of those
//! angles, as drive firmware estimates it ([`PdDrive::sense`]); the command
//! is `τ += K_p (θ_d − θ̂) + K_d (θ̇_d − θ̂̇)` ([`PdDrive::add_torque`]),
//! limited by the amplifier ([`saturate`]); the logged torque carries the
//! current sensor's noise scaled to the joint ([`torque_noise_std`]).

use std::f64::consts::TAU;

/// The joint-angle step of one encoder count, `2π / (counts · ratio)` (rad;
/// m for a prismatic joint whose ratio is motor revolutions per metre).
///
/// `counts_per_rev` are the counts per motor revolution after quadrature
/// decoding and `gear_ratio` the motor revolutions per joint revolution:
/// the gear divides the motor's resolution at the joint.
pub fn encoder_resolution(counts_per_rev: u32, gear_ratio: f64) -> f64 {
    TAU / (counts_per_rev as f64 * gear_ratio)
}

/// The standard deviation of the joint torque noise, `σ_i K_t N` (N·m),
/// of a current measurement with noise `σ_i` (A) on a motor of torque
/// constant `K_t` (N·m/A) behind a gear of ratio `N`: the torque is
/// computed from the measured current, so its noise is the current's
/// scaled to the joint.
pub fn torque_noise_std(current_noise_std: f64, torque_constant: f64, gear_ratio: f64) -> f64 {
    current_noise_std * torque_constant * gear_ratio
}

/// `angle` rounded to the nearest whole count of an encoder of step
/// `resolution` (`round(θ/r) · r`): what the encoder reports.
#[inline]
pub fn quantise(angle: f64, resolution: f64) -> f64 {
    (angle / resolution).round() * resolution
}

/// Each `tau[j]` clamped to `[−limits[j], limits[j]]`: the amplifier's
/// current limit at the joint.
///
/// # Panics
///
/// If the slices' lengths differ.
#[inline]
pub fn saturate(tau: &mut [f64], limits: &[f64]) {
    assert_eq!(tau.len(), limits.len(), "one limit per joint");
    for (t, &l) in tau.iter_mut().zip(limits) {
        *t = t.clamp(-l, l);
    }
}

/// The sensing and PD feedback of a set of joints sampled every `dt`: the
/// quantised angles and the filtered velocity estimate of the last
/// sample, in buffers allocated once, so that a simulation loop allocates
/// nothing per sample.
///
/// The velocity estimate is `v̂ += ((θ̂_k − θ̂_{k−1})/dt − v̂) · α` with
/// `α = 1 − exp(−2π f_c dt)`, the first-order low-pass of cut-off `f_c`
/// discretised exactly for an input held over the sample: the backward
/// difference of quantised angles jumps by `resolution/dt` from one
/// sample to the next, and the filter keeps that out of the derivative
/// term.
#[derive(Debug, Clone, PartialEq)]
pub struct PdDrive {
    resolution: Vec<f64>,
    alpha: f64,
    dt: f64,
    angles: Vec<f64>,
    velocity: Vec<f64>,
    started: bool,
}

impl PdDrive {
    /// A drive of `resolution.len()` joints with encoder steps
    /// `resolution` (see [`encoder_resolution`]), a velocity filter of
    /// cut-off `velocity_cutoff_hz` (Hz) and sample time `dt` (s), whose
    /// velocity estimate starts at `velocity` (the rate the robot starts
    /// with, so that a start on a moving trajectory has no transient of
    /// the estimate). The first [`Self::sense`] only reads the angles:
    /// the backward difference needs two samples.
    ///
    /// # Panics
    ///
    /// If `velocity` and `resolution` differ in length.
    pub fn new(resolution: Vec<f64>, velocity: Vec<f64>, velocity_cutoff_hz: f64, dt: f64) -> Self {
        assert_eq!(resolution.len(), velocity.len(), "one velocity per joint");
        Self {
            alpha: 1.0 - (-TAU * velocity_cutoff_hz * dt).exp(),
            dt,
            angles: vec![0.0; resolution.len()],
            resolution,
            velocity,
            started: false,
        }
    }

    /// Reads the encoders at the true joint `angles`: stores their
    /// quantised values ([`Self::angles`]) and, from the second sample on,
    /// updates the velocity estimate ([`Self::velocity`]) with their
    /// backward difference.
    ///
    /// # Panics
    ///
    /// If `angles` has not one entry per joint.
    #[inline]
    pub fn sense(&mut self, angles: &[f64]) {
        assert_eq!(angles.len(), self.angles.len(), "one angle per joint");
        for (j, &angle) in angles.iter().enumerate() {
            let measured = quantise(angle, self.resolution[j]);
            if self.started {
                let raw = (measured - self.angles[j]) / self.dt;
                self.velocity[j] += (raw - self.velocity[j]) * self.alpha;
            }
            self.angles[j] = measured;
        }
        self.started = true;
    }

    /// The quantised angles of the last sample (zero before the first).
    #[inline]
    pub fn angles(&self) -> &[f64] {
        &self.angles
    }

    /// The filtered velocity estimate of the last sample.
    #[inline]
    pub fn velocity(&self) -> &[f64] {
        &self.velocity
    }

    /// Adds the PD torque `kp_j (θ_d,j − θ̂_j) + kd_j (θ̇_d,j − v̂_j)` of the
    /// last sample to `tau[j]` (which holds the feedforward, or zero): the
    /// feedback on the measured angle and estimated rate that the drive
    /// commands.
    ///
    /// # Panics
    ///
    /// If a slice has not one entry per joint.
    #[inline]
    pub fn add_torque(
        &self,
        kp: &[f64],
        kd: &[f64],
        desired_angles: &[f64],
        desired_velocity: &[f64],
        tau: &mut [f64],
    ) {
        let n = self.angles.len();
        for len in [
            kp.len(),
            kd.len(),
            desired_angles.len(),
            desired_velocity.len(),
            tau.len(),
        ] {
            assert_eq!(len, n, "one entry per joint");
        }
        for j in 0..n {
            tau[j] += kp[j] * (desired_angles[j] - self.angles[j])
                + kd[j] * (desired_velocity[j] - self.velocity[j]);
        }
    }
}
