//! Forward kinematics, (6)–(7) (`docs/kinematics.md`).

use nalgebra::Vector2;

use crate::pose::{Pose, check_finite};
use crate::{Geometry, KinError, Motion};

/// Assembly mode of the distal links: the sign in (6).
///
/// The two modes are the two positions of `d` on the circle of points at arc
/// β from both elbows. With α = β the `Minus` branch is the degenerate
/// `γ = 0`; ARAS-Diamond works in `Plus`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AssemblyMode {
    /// `+` in (6): the working mode of ARAS-Diamond.
    #[default]
    Plus,
    /// `−` in (6).
    Minus,
}

/// Forward kinematics `θ → X = [φ, γ]`, (6)–(7):
/// `φ = (θ1 + θ2)/2`, `A = (θ1 − θ2)/2`,
/// `γ = 2 atan2(sin α cos A ± √(sin²β − sin²α sin²A), cos α + cos β)`.
///
/// The result is checked as in [`inverse`](crate::inverse): a pose at a
/// singularity (e.g. `γ = 0` on the degenerate branch) is an error.
pub fn forward(
    g: &Geometry,
    theta: &Vector2<f64>,
    mode: AssemblyMode,
) -> Result<Vector2<f64>, KinError> {
    Ok(forward_pose(g, theta, mode)?.0)
}

/// [`forward_motion`] in assembly mode `+` as a function that owns its
/// geometry: the shape a robot-agnostic consumer takes for "the model's
/// coordinates" (a closure of this type is an `aras_signal::Coordinates`).
pub fn task_motion(
    g: &Geometry,
) -> impl Fn(Motion) -> Result<Motion, KinError> + Copy + Send + Sync {
    let g = *g;
    move |joint| forward_motion(&g, &joint, AssemblyMode::Plus)
}

/// Task-space motion from motor-space motion: forward kinematics (6)–(7)
/// with `Ẋ = J⁻¹ θ̇` and `Ẍ = J⁻¹ (θ̈ − J̇ Ẋ)`, `J̇ Ẋ = [K′γ̇², −K′γ̇²]`.
///
/// Returns `(X, Ẋ, Ẍ)`. This is what turns measured encoder angles and
/// their derivatives into the task-space inputs of the dynamics; it skips
/// the link frames [`evaluate`](crate::evaluate) would also build.
pub fn forward_motion(
    g: &Geometry,
    joint: &Motion,
    mode: AssemblyMode,
) -> Result<Motion, KinError> {
    let Motion {
        pos: theta,
        vel: theta_dot,
        acc: theta_ddot,
    } = joint;
    check_finite("theta1_dot", theta_dot[0])?;
    check_finite("theta2_dot", theta_dot[1])?;
    check_finite("theta1_ddot", theta_ddot[0])?;
    check_finite("theta2_ddot", theta_ddot[1])?;
    let (x, pose) = forward_pose(g, theta, mode)?;
    let inv = |v: Vector2<f64>| Vector2::new(0.5 * (v[0] + v[1]), 0.5 * (v[0] - v[1]) / pose.k);
    let x_dot = inv(*theta_dot);
    let jd = pose.k_prime * x_dot[1] * x_dot[1];
    let x_ddot = inv(theta_ddot - Vector2::new(jd, -jd));
    Ok(Motion::new(x, x_dot, x_ddot))
}

fn forward_pose(
    g: &Geometry,
    theta: &Vector2<f64>,
    mode: AssemblyMode,
) -> Result<(Vector2<f64>, Pose), KinError> {
    check_finite("theta1", theta[0])?;
    check_finite("theta2", theta[1])?;
    let phi = 0.5 * (theta[0] + theta[1]);
    let half = 0.5 * (theta[0] - theta[1]);
    let (sin_a, cos_a) = half.sin_cos();
    let disc = g.sb * g.sb - (g.sa * sin_a).powi(2);
    if disc < 0.0 {
        // Elbow separation on the sphere: cos = cos²α + sin²α cos 2A.
        let cos_sep = g.ca * g.ca + g.sa * g.sa * (2.0 * half).cos();
        return Err(KinError::NoAssembly {
            theta1: theta[0],
            theta2: theta[1],
            separation: cos_sep.clamp(-1.0, 1.0).acos(),
            reach: (2.0 * g.beta()).min(std::f64::consts::PI),
        });
    }
    let root = match mode {
        AssemblyMode::Plus => disc.sqrt(),
        AssemblyMode::Minus => -disc.sqrt(),
    };
    let gamma = 2.0 * (g.sa * cos_a + root).atan2(g.ca + g.cb);
    if gamma.sin() < g.singularity_tolerance() {
        // The degenerate branch (e.g. γ = 0 for α = β): d on the motor axis.
        return Err(KinError::Singular {
            which: crate::Singularity::PolarAxis,
            value: gamma.sin(),
            limit: g.singularity_tolerance(),
        });
    }
    let x = Vector2::new(phi, gamma);
    let pose = Pose::new(g, &x)?;
    // With A outside (0, π) the triangle closes on the mirrored side: the
    // angle the IK would give differs from the commanded one.
    if (pose.a - half).abs() > 1e-9 * (1.0 + half.abs()) {
        return Err(KinError::NoAssembly {
            theta1: theta[0],
            theta2: theta[1],
            separation: 2.0 * half.abs(),
            reach: 2.0 * pose.a,
        });
    }
    Ok((x, pose))
}
