//! Everything the dynamics needs at one sample, in one allocation-free call.

use nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector2, Vector3};

use crate::links::LINKS;
use crate::pose::{Pose, check_finite};
use crate::{Geometry, Jacobian, KinError, Motion, Scalar, SingularityDistance};

/// Kinematics of the whole mechanism at one task motion sample `(X, Ẋ, Ẍ)`.
///
/// All vectors are in the base frame {0}; angles in rad, rates in rad/s,
/// accelerations in rad/s². Link arrays are indexed 0–3 for links 1–4 (see
/// [`links`](crate::links) for the numbering). Built only by [`evaluate`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct KinematicSample<T: Scalar = f64> {
    /// Task motion `X = [φ, γ]`, `Ẋ`, `Ẍ`: what the sample was evaluated at.
    pub task: Motion<T>,
    /// Motor motion: angles `θ` (1)–(2), rates `θ̇ = J Ẋ` and accelerations
    /// `θ̈ = J Ẍ + J̇ Ẋ`.
    pub joint: Motion<T>,
    /// Motor Jacobian `J`, (8)–(11).
    pub jacobian: Jacobian<T>,
    /// `J̇` along the sample's motion.
    pub jacobian_dot: Matrix2<T>,
    /// Link rotations `R_k`.
    pub rotations: [Matrix3<T>; LINKS],
    /// Link Jacobians `J_ωk`.
    pub link_jacobians: [Matrix3x2<T>; LINKS],
    /// Their time derivatives `J̇_ωk` along the sample's motion.
    pub link_jacobian_dots: [Matrix3x2<T>; LINKS],
    /// Link angular velocities `Ω_k = J_ωk Ẋ`, (12)–(21).
    pub omega: [Vector3<T>; LINKS],
    /// Link angular accelerations `Ω̇_k = J_ωk Ẍ + J̇_ωk Ẋ`, (22)–(25).
    pub omega_dot: [Vector3<T>; LINKS],
    /// Distance to each singularity.
    pub singularity: SingularityDistance,
}

/// Evaluates the full kinematics at one sample, analytically (no finite
/// differences) and without heap allocation.
///
/// Errors if an input is not finite, γ is unreachable, or the pose is within
/// the geometry's tolerance of a singularity. The workspace box (77) is *not*
/// enforced here (validation trajectories such as (47) leave it); use
/// [`Workspace`](crate::Workspace) for that.
///
/// Generic over the [`Scalar`]: `f64` for ordinary use, or forward-mode dual
/// numbers (feature `dual`) to get exact derivatives of everything with
/// respect to the inputs.
#[inline]
pub fn evaluate<T: Scalar>(g: &Geometry, task: &Motion<T>) -> Result<KinematicSample<T>, KinError> {
    let Motion {
        pos: x,
        vel: x_dot,
        acc: x_ddot,
    } = task;
    check_finite("phi_dot", x_dot[0])?;
    check_finite("gamma_dot", x_dot[1])?;
    check_finite("phi_ddot", x_ddot[0])?;
    check_finite("gamma_ddot", x_ddot[1])?;
    let p = Pose::new(g, x)?;
    let jac = Jacobian::from_k(p.k);
    let kd = p.k_prime * x_dot[1];
    let jacobian_dot = Matrix2::new(T::zero(), kd, T::zero(), -kd);
    let theta_dot = jac.apply(x_dot);
    let theta_ddot = jac.apply(x_ddot) + jacobian_dot * x_dot;
    let link_jacobians = p.link_jacobians();
    let link_jacobian_dots = p.link_jacobian_rates(x_dot);
    let omega = std::array::from_fn(|k| link_jacobians[k] * x_dot);
    let omega_dot =
        std::array::from_fn(|k| link_jacobians[k] * x_ddot + link_jacobian_dots[k] * x_dot);
    Ok(KinematicSample {
        task: *task,
        joint: Motion::new(Vector2::new(p.theta1, p.theta2), theta_dot, theta_ddot),
        jacobian: jac,
        jacobian_dot,
        rotations: p.frames(g),
        link_jacobians,
        link_jacobian_dots,
        omega,
        omega_dot,
        singularity: p.distance(),
    })
}
