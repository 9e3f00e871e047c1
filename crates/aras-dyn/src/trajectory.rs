//! Desired task-space trajectories that the simulator tracks, and the
//! paper's validation trajectories (47) and (79).

use aras_kin::Motion;
use nalgebra::Vector2;

use crate::DynError;

/// A desired motion `X(t) = [φ, γ]` with its first two derivatives.
pub trait Trajectory: Sync {
    /// `(X, Ẋ, Ẍ)` at time `t` (s), in rad, rad/s, rad/s².
    fn eval(&self, t: f64) -> Motion;

    /// The period (s) if the motion is periodic.
    fn period(&self) -> Option<f64>;
}

/// `X_i(t) = offset_i + amplitude_i · sin(ω t + phase_i)`, one frequency
/// for both coordinates (so the motion is periodic with `2π/ω`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoid {
    /// Amplitudes `[φ, γ]` (rad).
    pub amplitude: Vector2<f64>,
    /// Mean values `[φ, γ]` (rad).
    pub offset: Vector2<f64>,
    /// Phases (rad).
    pub phase: Vector2<f64>,
    /// Angular frequency ω (rad/s, > 0).
    pub omega: f64,
}

impl Sinusoid {
    /// Checks that every field is finite and ω is positive.
    pub fn new(
        amplitude: Vector2<f64>,
        offset: Vector2<f64>,
        phase: Vector2<f64>,
        omega: f64,
    ) -> Result<Self, DynError> {
        let names = [
            "amplitude.phi",
            "amplitude.gamma",
            "offset.phi",
            "offset.gamma",
            "phase.phi",
            "phase.gamma",
            "omega",
        ];
        let vals = [
            amplitude[0],
            amplitude[1],
            offset[0],
            offset[1],
            phase[0],
            phase[1],
            omega,
        ];
        for (name, value) in names.into_iter().zip(vals) {
            if !value.is_finite() {
                return Err(DynError::NonFinite { name, value });
            }
        }
        if omega <= 0.0 {
            return Err(DynError::InvalidSetting {
                id: "sinusoid",
                setting: "omega",
                value: omega,
                reason: "the angular frequency must be positive",
            });
        }
        Ok(Self {
            amplitude,
            offset,
            phase,
            omega,
        })
    }

    /// The paper's model-validation trajectory (47):
    /// `φ = 80° sin(2t) + 90°`, `γ = 40° sin(2t) + 45°` (γ sweeps 5°–85°).
    pub fn paper_47() -> Self {
        let d = f64::to_radians;
        Self {
            amplitude: Vector2::new(d(80.0), d(40.0)),
            offset: Vector2::new(d(90.0), d(45.0)),
            phase: Vector2::zeros(),
            omega: 2.0,
        }
    }

    /// The paper's cross-validation trajectory (79) at `f` Hz:
    /// `φ = 30° cos(ωt) + 85°`, `γ = 20° sin(ωt) + 60°`, `ω = 2πf`.
    pub fn paper_79(f_hz: f64) -> Result<Self, DynError> {
        let d = f64::to_radians;
        Self::new(
            Vector2::new(d(30.0), d(20.0)),
            Vector2::new(d(85.0), d(60.0)),
            Vector2::new(std::f64::consts::FRAC_PI_2, 0.0),
            2.0 * std::f64::consts::PI * f_hz,
        )
    }
}

impl Trajectory for Sinusoid {
    fn eval(&self, t: f64) -> Motion {
        let w = self.omega;
        let mut x = Vector2::zeros();
        let mut v = Vector2::zeros();
        let mut a = Vector2::zeros();
        for i in 0..2 {
            let (s, c) = (w * t + self.phase[i]).sin_cos();
            x[i] = self.offset[i] + self.amplitude[i] * s;
            v[i] = self.amplitude[i] * w * c;
            a[i] = -self.amplitude[i] * w * w * s;
        }
        Motion::new(x, v, a)
    }

    fn period(&self) -> Option<f64> {
        Some(2.0 * std::f64::consts::PI / self.omega)
    }
}
