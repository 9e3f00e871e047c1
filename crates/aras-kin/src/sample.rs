//! Everything the dynamics needs at one sample, in one allocation-free call.

use nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector2, Vector3};

use crate::links::LINKS;
use crate::pose::{Pose, check_finite};
use crate::{Geometry, Jacobian, KinError, SingularityDistance};

/// Kinematics of the whole mechanism at one sample `(X, Ẋ, Ẍ)`.
///
/// All vectors are in the base frame {0}; angles in rad, rates in rad/s,
/// accelerations in rad/s². Link arrays are indexed 0–3 for links 1–4 (see
/// [`links`](crate::links) for the numbering). Built only by [`evaluate`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct KinematicSample {
    /// Task pose `X = [φ, γ]`.
    pub x: Vector2<f64>,
    /// Task rate `Ẋ`.
    pub x_dot: Vector2<f64>,
    /// Task acceleration `Ẍ`.
    pub x_ddot: Vector2<f64>,
    /// Motor angles `θ`, spec (1)–(2).
    pub theta: Vector2<f64>,
    /// Motor rates `θ̇ = J Ẋ`.
    pub theta_dot: Vector2<f64>,
    /// Motor accelerations `θ̈ = J Ẍ + J̇ Ẋ`.
    pub theta_ddot: Vector2<f64>,
    /// Motor Jacobian `J`, spec (8)–(11).
    pub jacobian: Jacobian,
    /// `J̇` along the sample's motion.
    pub jacobian_dot: Matrix2<f64>,
    /// Link rotations `R_k`.
    pub rotations: [Matrix3<f64>; LINKS],
    /// Link Jacobians `J_ωk`.
    pub link_jacobians: [Matrix3x2<f64>; LINKS],
    /// Their time derivatives `J̇_ωk` along the sample's motion.
    pub link_jacobian_dots: [Matrix3x2<f64>; LINKS],
    /// Link angular velocities `Ω_k = J_ωk Ẋ`, spec (12)–(21).
    pub omega: [Vector3<f64>; LINKS],
    /// Link angular accelerations `Ω̇_k = J_ωk Ẍ + J̇_ωk Ẋ`, spec (22)–(25).
    pub omega_dot: [Vector3<f64>; LINKS],
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
pub fn evaluate(
    g: &Geometry,
    x: &Vector2<f64>,
    x_dot: &Vector2<f64>,
    x_ddot: &Vector2<f64>,
) -> Result<KinematicSample, KinError> {
    check_finite("phi_dot", x_dot[0])?;
    check_finite("gamma_dot", x_dot[1])?;
    check_finite("phi_ddot", x_ddot[0])?;
    check_finite("gamma_ddot", x_ddot[1])?;
    let p = Pose::new(g, x)?;
    let jac = Jacobian::from_k(p.k);
    let kd = p.k_prime * x_dot[1];
    let jacobian_dot = Matrix2::new(0.0, kd, 0.0, -kd);
    let theta_dot = jac.apply(x_dot);
    let theta_ddot = jac.apply(x_ddot) + jacobian_dot * x_dot;
    let link_jacobians = p.link_jacobians();
    let link_jacobian_dots = p.link_jacobian_rates(x_dot);
    let omega = std::array::from_fn(|k| link_jacobians[k] * x_dot);
    let omega_dot =
        std::array::from_fn(|k| link_jacobians[k] * x_ddot + link_jacobian_dots[k] * x_dot);
    Ok(KinematicSample {
        x: *x,
        x_dot: *x_dot,
        x_ddot: *x_ddot,
        theta: Vector2::new(p.theta1, p.theta2),
        theta_dot,
        theta_ddot,
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
