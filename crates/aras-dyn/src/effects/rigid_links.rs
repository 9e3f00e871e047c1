//! Rigid links 1–4, (38)–(46): 9 columns per link, `Lk.Ixx … Lk.hz` (the
//! inertia tensor about the RCM and the first moment of mass, in the link's
//! frame). Physical consistency is not a sign: each link's pseudo-inertia
//! must be positive semidefinite, (67)–(69), which the SDP imposes from the
//! link layout (`aras_pipeline::robot::consistent_problem`).

use aras_kin::{KinematicSample, Scalar};
use nalgebra::Vector3;

/// Number of columns: 9 per link, 4 links.
pub(super) const COLUMNS: usize = 36;

/// Why the effect exists and how it shows in the data.
pub(super) const EXPLANATION: &str = "the inertia, first moment and weight of the four links: \
    torque from acceleration, from velocity products (Coriolis and centripetal) and from \
    gravity, (38)–(46)";

/// `L1.Ixx … L4.hz`.
pub(super) fn names() -> Vec<String> {
    (1..=4)
        .flat_map(|k| {
            crate::params::LINK_KEYS[..9]
                .iter()
                .map(move |p| format!("L{k}.{p}"))
        })
        .collect()
}

/// The 2×36 block of (45): per link `J⁻ᵀ J_ωkᵀ R_k [Λ_k, [g^k]×]` with
/// `Λ_k = L(Ω̇^k) + [Ω^k]× L(Ω^k)` (40).
#[inline(always)]
pub(super) fn fill<T: Scalar>(s: &KinematicSample<T>, g: &Vector3<T>, out: &mut [T]) {
    let k_inv = T::one() / s.jacobian.k();
    let half = T::lift(0.5);
    for k in 0..4 {
        let r = &s.rotations[k];
        let w = r.tr_mul(&s.omega[k]);
        let wd = r.tr_mul(&s.omega_dot[k]);
        let gk = r.tr_mul(g);
        // Link-frame Jacobian B = Rᵀ J_ω; rows of A = J⁻ᵀ Bᵀ are u0ᵀ, u1ᵀ.
        let b = r.tr_mul(&s.link_jacobians[k]);
        let c0 = b.column(0);
        let c1 = b.column(1) * k_inv;
        let u0 = (c0 + c1) * half;
        let u1 = (c0 - c1) * half;
        let (wx, wy, wz) = (w.x, w.y, w.z);
        let (ax, ay, az) = (wd.x, wd.y, wd.z);
        let (gx, gy, gz) = (gk.x, gk.y, gk.z);
        let z = T::zero();
        let cols: [[T; 3]; 9] = [
            [ax, wx * wz, -(wx * wy)],
            [ay - wx * wz, ax + wy * wz, wx * wx - wy * wy],
            [az + wx * wy, wz * wz - wx * wx, ax - wy * wz],
            [-(wy * wz), ay, wx * wy],
            [wy * wy - wz * wz, az - wx * wy, ay + wx * wz],
            [wy * wz, -(wx * wz), az],
            [z, gz, -gy],
            [-gz, z, gx],
            [gy, -gx, z],
        ];
        let base = 18 * k;
        for (j, c) in cols.iter().enumerate() {
            out[base + 2 * j] = u0.x * c[0] + u0.y * c[1] + u0.z * c[2];
            out[base + 2 * j + 1] = u1.x * c[0] + u1.y * c[1] + u1.z * c[2];
        }
    }
}
