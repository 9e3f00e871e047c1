//! Position-level quantities shared by every kinematic function.
//!
//! Everything about the mechanism at a pose `X = [φ, γ]` follows from the
//! spherical triangle (a, b or c, d). The angle `A` at `a` and the elbow angle
//! `B` depend on `γ` only, so their γ-derivatives are scalars; rotation about
//! `a` by `φ` carries every vector along. This is why the link Jacobians and
//! their time derivatives have closed forms (see `links`).

use nalgebra::{Vector2, Vector3};

use crate::{Geometry, KinError, Scalar, SingularityDistance};

/// All position-level scalars and unit vectors at one pose.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pose<T: Scalar = f64> {
    pub sin_gamma: T,
    pub cos_gamma: T,
    /// Angle A at `a` (rad), (1).
    pub a: T,
    pub sin_a: T,
    pub sin_b: T,
    pub cos_b: T,
    /// K = dA/dγ, (8)–(11), with the sign of `docs/kinematics.md`.
    pub k: T,
    /// dK/dγ.
    pub k_prime: T,
    /// μ: elbow rate of the distal link on `b` per unit γ̇ (Ω3 = θ̇2 a + μ γ̇ b).
    pub mu: T,
    /// dμ/dγ.
    pub mu_prime: T,
    pub theta1: T,
    pub theta2: T,
    /// (sin θ1, cos θ1) and (sin θ2, cos θ2), reused by the proximal frames.
    pub sc1: (T, T),
    pub sc2: (T, T),
    pub b: Vector3<T>,
    pub c: Vector3<T>,
    pub d: Vector3<T>,
}

pub(crate) fn check_finite<T: Scalar>(name: &'static str, value: T) -> Result<(), KinError> {
    let value = value.value();
    if value.is_finite() {
        Ok(())
    } else {
        Err(KinError::NonFinite { name, value })
    }
}

/// A pose's own checks before any evaluation: finite angles and a polar
/// angle the arcs can reach.
pub(crate) fn check_pose<T: Scalar>(g: &Geometry, phi: T, gamma: T) -> Result<(), KinError> {
    check_finite("phi", phi)?;
    check_finite("gamma", gamma)?;
    let (lo, hi) = g.reachable_gamma();
    if gamma.value() < lo || gamma.value() > hi {
        return Err(KinError::Unreachable {
            gamma: gamma.value(),
            min: lo,
            max: hi,
        });
    }
    Ok(())
}

impl<T: Scalar> Pose<T> {
    /// Evaluates the pose and rejects unreachable or singular ones.
    pub fn new(g: &Geometry, x: &Vector2<T>) -> Result<Self, KinError> {
        let pose = Self::unchecked(g, x)?;
        pose.distance().check(g.singularity_tolerance())?;
        Ok(pose)
    }

    pub fn distance(&self) -> SingularityDistance {
        SingularityDistance {
            sin_a: self.sin_a.value(),
            sin_gamma: self.sin_gamma.value(),
            sin_b: self.sin_b.value(),
            parallel: self.k.value().abs(),
        }
    }

    /// Evaluates the pose; only reachability and finiteness are checked.
    /// At a singularity some derived scalars are infinite.
    pub fn unchecked(g: &Geometry, x: &Vector2<T>) -> Result<Self, KinError> {
        let (phi, gamma) = (x[0], x[1]);
        check_pose(g, phi, gamma)?;
        let c = T::lift;
        let (sa, ca, sb) = (c(g.sa), c(g.ca), c(g.sb));
        let (sg, cg) = gamma.sin_cos();
        let (sphi, cphi) = phi.sin_cos();
        let Triangle {
            cos_a,
            sin_a,
            cos_b,
            sin_b,
            p,
            dp,
            k,
            k_prime,
        } = Triangle::at(g, sg, cg);
        let a = sin_a.atan2(cos_a);
        // μ = (b×d)·(∂d/∂γ + K a×d)/s²β in closed form.
        let s2b = sb * sb;
        let mu = (-sa * sin_a + k * p) / s2b;
        let mu_prime = (-sa * cos_a * k + k_prime * p + k * dp) / s2b;

        // θ1 = φ + A, θ2 = φ − A, (1)–(2); sines by angle addition.
        let (st1, ct1) = (sphi * cos_a + cphi * sin_a, cphi * cos_a - sphi * sin_a);
        let (st2, ct2) = (sphi * cos_a - cphi * sin_a, cphi * cos_a + sphi * sin_a);
        Ok(Self {
            sin_gamma: sg,
            cos_gamma: cg,
            a,
            sin_a,
            sin_b,
            cos_b,
            k,
            k_prime,
            mu,
            mu_prime,
            theta1: phi + a,
            theta2: phi - a,
            sc1: (st1, ct1),
            sc2: (st2, ct2),
            b: Vector3::new(sa * ct2, sa * st2, ca),
            c: Vector3::new(sa * ct1, sa * st1, ca),
            d: Vector3::new(sg * cphi, sg * sphi, cg),
        })
    }
}

/// The spherical triangle (a, b or c, d) at a polar angle γ: what depends
/// on γ alone, shared by [`Pose`] and the lean forward motion.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Triangle<T: Scalar = f64> {
    pub cos_a: T,
    pub sin_a: T,
    pub cos_b: T,
    pub sin_b: T,
    /// P = cα − cβ cγ.
    pub p: T,
    /// dP/dγ = cβ sγ.
    pub dp: T,
    /// K = dA/dγ.
    pub k: T,
    /// dK/dγ.
    pub k_prime: T,
}

impl<T: Scalar> Triangle<T> {
    /// The triangle at `(sin γ, cos γ)`.
    pub fn at(g: &Geometry, sg: T, cg: T) -> Self {
        let c = T::lift;
        let (sa, ca, sb, cb) = (c(g.sa), c(g.ca), c(g.sb), c(g.cb));
        let (zero, one, two) = (T::zero(), T::one(), c(2.0));
        // Spherical cosine rule, (1) and (4). Rounding can push the
        // cosines a hair past ±1 at the reach limits; the sines are then 0
        // and the singularity check rejects the pose.
        let cos_a = ((cb - cg * ca) / (sg * sa)).clamp(-one, one);
        let sin_a = (one - cos_a * cos_a).max(zero).sqrt();
        let cos_b = ((cg - cb * ca) / (sb * sa)).clamp(-one, one);
        let sin_b = (one - cos_b * cos_b).max(zero).sqrt();
        // K = dA/dγ = −P/(sα s²γ sA), P = cα − cβ cγ (equal to
        // −(cot α − cos A cot γ)/sin A).
        let p = ca - cb * cg;
        let dp = cb * sg;
        let u = one / (sa * sg * sg * sin_a);
        let k = -p * u;
        let k_prime = u * (-dp + p * (two * cg / sg + k * cos_a / sin_a));
        Self {
            cos_a,
            sin_a,
            cos_b,
            sin_b,
            p,
            dp,
            k,
            k_prime,
        }
    }

    /// How far the triangle is from each singularity.
    pub fn distance(&self, sin_gamma: T) -> SingularityDistance {
        SingularityDistance {
            sin_a: self.sin_a.value(),
            sin_gamma: sin_gamma.value(),
            sin_b: self.sin_b.value(),
            parallel: self.k.value().abs(),
        }
    }
}

/// Which singularity a pose is near (`docs/kinematics.md`, "Singularities").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Singularity {
    /// `sin A = 0`: the proximal links are aligned.
    ProximalAligned,
    /// `sin γ = 0`: `d` lies on `a`, so φ is undefined.
    PolarAxis,
    /// `sin B = 0`: proximal and distal arcs aligned (reach boundary).
    ElbowStretched,
    /// `K = dA/dγ = 0`: γ moves without moving the motors (J singular).
    Parallel,
}

impl std::fmt::Display for Singularity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::ProximalAligned => "sin A (proximal links aligned)",
            Self::PolarAxis => "sin gamma (end-effector on the motor axis)",
            Self::ElbowStretched => "sin B (elbow stretched, reach boundary)",
            Self::Parallel => "|dA/dgamma| (Jacobian singular)",
        })
    }
}
