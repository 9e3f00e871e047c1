//! Forward kinematics, (6)–(7) (`docs/kinematics.md`).

use nalgebra::Vector2;

use crate::pose::{Pose, Triangle, check_finite, check_pose};
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
    let (x, t) = forward_triangle(g, theta, mode)?;
    let inv = |v: Vector2<f64>| Vector2::new(0.5 * (v[0] + v[1]), 0.5 * (v[0] - v[1]) / t.k);
    let x_dot = inv(*theta_dot);
    let jd = t.k_prime * x_dot[1] * x_dot[1];
    let x_ddot = inv(theta_ddot - Vector2::new(jd, -jd));
    Ok(Motion::new(x, x_dot, x_ddot))
}

/// `φ`, `A` and `γ` of (6)–(7) with `sin γ`, and the checks that need no
/// more: finite angles, an assembly that closes, `d` off the motor axis.
fn polar_angle(
    g: &Geometry,
    theta: &Vector2<f64>,
    mode: AssemblyMode,
) -> Result<(f64, f64, f64, f64), KinError> {
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
    let sin_gamma = gamma.sin();
    if sin_gamma < g.singularity_tolerance() {
        // The degenerate branch (e.g. γ = 0 for α = β): d on the motor axis.
        return Err(KinError::Singular {
            which: crate::Singularity::PolarAxis,
            value: sin_gamma,
            limit: g.singularity_tolerance(),
        });
    }
    Ok((phi, half, gamma, sin_gamma))
}

/// With `A` outside (0, π) the triangle closes on the mirrored side: the
/// angle `a` the IK gives (from the cosine rule) differs from the
/// commanded `half`.
fn check_assembly(theta: &Vector2<f64>, half: f64, a: f64) -> Result<(), KinError> {
    if (a - half).abs() > 1e-9 * (1.0 + half.abs()) {
        return Err(KinError::NoAssembly {
            theta1: theta[0],
            theta2: theta[1],
            separation: 2.0 * half.abs(),
            reach: 2.0 * a,
        });
    }
    Ok(())
}

fn forward_pose(
    g: &Geometry,
    theta: &Vector2<f64>,
    mode: AssemblyMode,
) -> Result<(Vector2<f64>, Pose), KinError> {
    let (phi, half, gamma, _) = polar_angle(g, theta, mode)?;
    let x = Vector2::new(phi, gamma);
    let pose = Pose::new(g, &x)?;
    check_assembly(theta, half, pose.a)?;
    Ok((x, pose))
}

/// [`forward_pose`] without the link frames: `X` and the triangle at its
/// `γ`, the same checks in the same order and the same numbers, bit for
/// bit (the motion needs only `K` and `K′`; the cosine rule's `A` is
/// computed only where it can differ from the commanded one).
fn forward_triangle(
    g: &Geometry,
    theta: &Vector2<f64>,
    mode: AssemblyMode,
) -> Result<(Vector2<f64>, Triangle), KinError> {
    let (phi, half, gamma, sg) = polar_angle(g, theta, mode)?;
    check_pose(g, phi, gamma)?;
    let t = Triangle::at(g, sg, gamma.cos());
    t.distance(sg).check(g.singularity_tolerance())?;
    // Inside [0, π] the cosine rule's A is `half` to rounding, far inside
    // the check's 1e-9.
    let a = if (0.0..=std::f64::consts::PI).contains(&half) {
        half
    } else {
        t.sin_a.atan2(t.cos_a)
    };
    check_assembly(theta, half, a)?;
    Ok((Vector2::new(phi, gamma), t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The lean route gives the frames' route's `X`, `K` and `K′` bit
        /// for bit, and the same error where there is one: across the
        /// workspace, its edges and beyond (θ over two turns each way).
        #[test]
        fn the_lean_route_is_the_pose_route(
            t1 in -4.0 * std::f64::consts::PI..4.0 * std::f64::consts::PI,
            t2 in -4.0 * std::f64::consts::PI..4.0 * std::f64::consts::PI,
            minus in any::<bool>(),
        ) {
            let g = Geometry::aras_diamond();
            let mode = if minus { AssemblyMode::Minus } else { AssemblyMode::Plus };
            let theta = Vector2::new(t1, t2);
            match (forward_pose(&g, &theta, mode), forward_triangle(&g, &theta, mode)) {
                (Ok((x, pose)), Ok((y, t))) => {
                    prop_assert_eq!(x, y);
                    prop_assert_eq!(pose.k.to_bits(), t.k.to_bits());
                    prop_assert_eq!(pose.k_prime.to_bits(), t.k_prime.to_bits());
                }
                (Err(a), Err(b)) => prop_assert_eq!(a, b),
                (a, b) => prop_assert!(false, "{:?} vs {:?}", a.map(|r| r.0), b.map(|r| r.0)),
            }
        }
    }

    /// Near the workspace the two routes agree too (θ in the working
    /// mode's range, where most samples of a log lie).
    #[test]
    fn the_lean_route_is_the_pose_route_in_the_workspace() {
        let g = Geometry::aras_diamond();
        let mut n_ok = 0;
        for i in 0..200 {
            for k in 0..200 {
                let theta = Vector2::new(-1.0 + 0.0137 * i as f64, -2.5 + 0.0131 * k as f64);
                let (a, b) = (
                    forward_pose(&g, &theta, AssemblyMode::Plus),
                    forward_triangle(&g, &theta, AssemblyMode::Plus),
                );
                match (a, b) {
                    (Ok((x, pose)), Ok((y, t))) => {
                        n_ok += 1;
                        assert_eq!(x, y);
                        assert_eq!(pose.k.to_bits(), t.k.to_bits());
                        assert_eq!(pose.k_prime.to_bits(), t.k_prime.to_bits());
                    }
                    (Err(a), Err(b)) => assert_eq!(a, b),
                    (a, b) => panic!("{theta:?}: {:?} vs {:?}", a.map(|r| r.0), b.map(|r| r.0)),
                }
            }
        }
        assert!(n_ok > 10_000, "{n_ok} poses in the grid");
    }
}
