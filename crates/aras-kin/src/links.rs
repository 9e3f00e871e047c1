//! Link frames and link angular-velocity Jacobians, (12)–(21) (`docs/kinematics.md`).
//!
//! Numbering (paper eqs. 12–15 and the robot authors' model):
//!
//! | index | link | turns about | elbow / next axis | frame `z`, `n` |
//! |---|---|---|---|---|
//! | 0 | 1, proximal | `a` by θ2 | `b` | `a`, `b` (`R1 = Rz(θ2)`) |
//! | 1 | 2, proximal | `a` by θ1 | `c` | `a`, `c` (`R2 = Rz(θ1)`) |
//! | 2 | 3, distal on `b` | `b` | `d` | `b`, `d` |
//! | 3 | 4, distal on `c` | `c` | `d` | `c`, `d` |
//!
//! Each frame: `y = (z × n)/|z × n|`, `x = y × z`, `R = [x y z]`.
//!
//! Angular velocities `Ω_k = J_ωk Ẋ` with (closed form of (14)–(19))
//!
//! ```text
//! J_ω1 = [a, −K a]          J_ω3 = [a, −K a + μ b]
//! J_ω2 = [a,  K a]          J_ω4 = [a,  K a − μ c]
//! μ = (−sin α sin A + K (cos α − cos β cos γ)) / sin²β
//! ```
//!
//! `μ` is the convention-free `λ = (e×d)·(ḋ − θ̇_e a×d)/sin²β` per
//! unit γ̇; it equals `−G` of (17). The authors' MATLAB `Q` does not match it
//! (`docs/kinematics.md`) and is not used.

use nalgebra::{Matrix3, Matrix3x2, Vector2, Vector3};

use crate::pose::Pose;
use crate::{Geometry, KinError, Scalar};

/// Number of links.
pub const LINKS: usize = 4;

/// Frame `R = [x y z]` from a joint axis `z` and the next axis `n` whose
/// arc to `z` has sine `s` (so `|z × n| = s`).
fn frame<T: Scalar>(z: &Vector3<T>, n: &Vector3<T>, s: T) -> Matrix3<T> {
    let y = z.cross(n) / s;
    let x = y.cross(z);
    Matrix3::from_columns(&[x, y, *z])
}

impl<T: Scalar> Pose<T> {
    pub(crate) fn frames(&self, g: &Geometry) -> [Matrix3<T>; LINKS] {
        let (z, o) = (T::zero(), T::one());
        let rz = |(s, c): (T, T)| Matrix3::new(c, -s, z, s, c, z, z, z, o);
        let sb = T::lift(g.sb);
        [
            rz(self.sc2),
            rz(self.sc1),
            frame(&self.b, &self.d, sb),
            frame(&self.c, &self.d, sb),
        ]
    }

    pub(crate) fn link_jacobians(&self) -> [Matrix3x2<T>; LINKS] {
        let a = Vector3::z();
        let ka = a * self.k;
        [
            Matrix3x2::from_columns(&[a, -ka]),
            Matrix3x2::from_columns(&[a, ka]),
            Matrix3x2::from_columns(&[a, -ka + self.b * self.mu]),
            Matrix3x2::from_columns(&[a, ka - self.c * self.mu]),
        ]
    }

    /// `J̇_ωk` along a motion with rate `x_dot` (only the γ column varies).
    pub(crate) fn link_jacobian_rates(&self, x_dot: &Vector2<T>) -> [Matrix3x2<T>; LINKS] {
        let gd = x_dot[1];
        let td1 = x_dot[0] + self.k * gd;
        let td2 = x_dot[0] - self.k * gd;
        let a = Vector3::z();
        let kpa = a * (self.k_prime * gd);
        // ḃ = θ̇2 a × b, ċ = θ̇1 a × c.
        let b_dot = Vector3::new(-self.b[1], self.b[0], T::zero()) * td2;
        let c_dot = Vector3::new(-self.c[1], self.c[0], T::zero()) * td1;
        let col3 = -kpa + self.b * (self.mu_prime * gd) + b_dot * self.mu;
        let col4 = kpa - self.c * (self.mu_prime * gd) - c_dot * self.mu;
        let z = Vector3::zeros();
        [
            Matrix3x2::from_columns(&[z, -kpa]),
            Matrix3x2::from_columns(&[z, kpa]),
            Matrix3x2::from_columns(&[z, col3]),
            Matrix3x2::from_columns(&[z, col4]),
        ]
    }
}

/// Rotation matrices `R_k` (link frame → base frame) of links 1–4 (index 0–3).
pub fn link_frames(g: &Geometry, x: &Vector2<f64>) -> Result<[Matrix3<f64>; LINKS], KinError> {
    Ok(Pose::new(g, x)?.frames(g))
}

/// Link angular-velocity Jacobians `J_ωk` (3×2, base frame), `Ω_k = J_ωk Ẋ`.
pub fn link_jacobians(g: &Geometry, x: &Vector2<f64>) -> Result<[Matrix3x2<f64>; LINKS], KinError> {
    Ok(Pose::new(g, x)?.link_jacobians())
}
