//! Inverse kinematics, (1)–(5) (`docs/kinematics.md`).

use nalgebra::Vector2;

use crate::pose::Pose;
use crate::{Geometry, KinError};

/// Passive joint angles `θ_p = [A, B, C, D]` (rad), (1), (4), (5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassiveAngles {
    /// Angle at `a` between the arcs a–b (or a–c) and a–d; `A = (θ1 − θ2)/2`.
    pub a: f64,
    /// Elbow angle at `b` between the arcs b–a and b–d.
    pub b: f64,
    /// Elbow angle at `c`; equal to `B` by symmetry.
    pub c: f64,
    /// Angle at `d` between the arcs d–a and d–b (or d–c).
    pub d: f64,
}

/// Result of the inverse kinematics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InverseSolution {
    /// Motor angles `θ = [θ1, θ2]` (rad).
    pub theta: Vector2<f64>,
    /// Passive angles (rad).
    pub passive: PassiveAngles,
}

/// Inverse kinematics `X = [φ, γ] → θ = [θ1, θ2]` and the passive angles,
/// (1)–(5): `θ1 = φ + A`, `θ2 = φ − A`.
///
/// Errors if γ is unreachable, the pose is within the geometry's tolerance of
/// a singularity, or an input is not finite.
pub fn inverse(g: &Geometry, x: &Vector2<f64>) -> Result<InverseSolution, KinError> {
    let p = Pose::new(g, x)?;
    // Angle at d, (5): cos D = (cos α − cos γ cos β)/(sin γ sin β).
    let cos_d = ((g.ca - p.cos_gamma * g.cb) / (p.sin_gamma * g.sb)).clamp(-1.0, 1.0);
    let b = p.sin_b.atan2(p.cos_b);
    Ok(InverseSolution {
        theta: Vector2::new(p.theta1, p.theta2),
        passive: PassiveAngles {
            a: p.a,
            b,
            c: b,
            d: cos_d.acos(),
        },
    })
}
