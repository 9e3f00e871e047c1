//! A rigid link's inertial parameters and its pseudo-inertia.

use nalgebra::{Matrix3, Matrix4, Vector3};

/// Inertial parameters of one rigid link in its own frame, about its pivot
/// (for ARAS-Diamond, the remote centre of motion): the inertia tensor
/// `I_O`, the first moment of mass `h = m ρ` and the mass, (28)–(30), (46).
///
/// The nine standard parameters `[Ixx Ixy Ixz Iyy Iyz Izz hx hy hz]` are
/// what a linear-in-parameters model identifies; [`Inertia::pseudo_inertia`]
/// is what physical consistency constrains.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Inertia {
    /// `I[0,0]` (kg·m²).
    pub ixx: f64,
    /// `I[0,1]` (kg·m²), a tensor entry: `−Σ m x y`.
    pub ixy: f64,
    /// `I[0,2]` (kg·m²).
    pub ixz: f64,
    /// `I[1,1]` (kg·m²).
    pub iyy: f64,
    /// `I[1,2]` (kg·m²).
    pub iyz: f64,
    /// `I[2,2]` (kg·m²).
    pub izz: f64,
    /// First moment of mass `h = m ρ` (kg·m), `ρ` the centre of mass.
    pub h: Vector3<f64>,
    /// Mass (kg). A link that only rotates about its pivot never shows it
    /// in its dynamics; it enters only the consistency conditions.
    pub mass: f64,
}

/// `m [ρ]×ᵀ [ρ]× = m (|ρ|² 1 − ρ ρᵀ)`: the parallel-axis shift (28).
fn shift(mass: f64, rho: &Vector3<f64>) -> Matrix3<f64> {
    (Matrix3::identity() * rho.norm_squared() - rho * rho.transpose()) * mass
}

impl Inertia {
    /// A link from its nine standard parameters
    /// `[Ixx Ixy Ixz Iyy Iyz Izz hx hy hz]` (46) and its mass.
    pub fn from_standard(standard: &[f64; 9], mass: f64) -> Self {
        let mut l = Self {
            mass,
            ..Self::default()
        };
        l.set_standard(standard);
        l
    }

    /// A link from its mass, its inertia about the centre of mass `I_G`
    /// (link frame) and the centre of mass `ρ` (link frame, from the pivot),
    /// by the parallel-axis theorem (28): `I_O = I_G + m[ρ]×ᵀ[ρ]×`, `h = mρ`.
    pub fn from_com(mass: f64, inertia_com: &Matrix3<f64>, rho: &Vector3<f64>) -> Self {
        let mut l = Self {
            h: rho * mass,
            mass,
            ..Self::default()
        };
        l.set_inertia(&(inertia_com + shift(mass, rho)));
        l
    }

    /// A point mass `m` at `p` (link frame, from the pivot): the
    /// parallel-axis shift (28) of nothing.
    pub fn point_mass(mass: f64, p: &Vector3<f64>) -> Self {
        let mut l = Self {
            h: p * mass,
            mass,
            ..Self::default()
        };
        l.set_inertia(&shift(mass, p));
        l
    }

    /// The inertia tensor about the pivot (symmetric 3×3, link frame).
    pub fn inertia(&self) -> Matrix3<f64> {
        Matrix3::new(
            self.ixx, self.ixy, self.ixz, self.ixy, self.iyy, self.iyz, self.ixz, self.iyz,
            self.izz,
        )
    }

    /// Sets the six entries from a symmetric tensor (upper triangle read).
    pub fn set_inertia(&mut self, i: &Matrix3<f64>) {
        self.ixx = i[(0, 0)];
        self.ixy = i[(0, 1)];
        self.ixz = i[(0, 2)];
        self.iyy = i[(1, 1)];
        self.iyz = i[(1, 2)];
        self.izz = i[(2, 2)];
    }

    /// The 9 standard parameters `[Ixx Ixy Ixz Iyy Iyz Izz hx hy hz]`, (46).
    pub fn standard(&self) -> [f64; 9] {
        [
            self.ixx, self.ixy, self.ixz, self.iyy, self.iyz, self.izz, self.h.x, self.h.y,
            self.h.z,
        ]
    }

    /// Sets the 9 standard parameters (mass unchanged).
    pub fn set_standard(&mut self, v: &[f64; 9]) {
        [
            self.ixx, self.ixy, self.ixz, self.iyy, self.iyz, self.izz, self.h.x, self.h.y,
            self.h.z,
        ] = *v;
    }

    /// Pseudo-inertia `𝒥 = [[½tr(I)·1 − I, h], [hᵀ, m]]` (Wensing et al.
    /// 2017): `𝒥 ≻ 0` exactly when the link is physically consistent
    /// (positive mass, positive-definite COM inertia, triangle inequality),
    /// (67)–(69); see `docs/model.md`, "Physical consistency". `𝒥` is linear
    /// in the standard parameters and the mass, which is what lets the
    /// identification impose it as a semidefinite constraint.
    pub fn pseudo_inertia(&self) -> Matrix4<f64> {
        let i = self.inertia();
        let s = Matrix3::identity() * (0.5 * i.trace()) - i;
        let mut p = Matrix4::zeros();
        p.fixed_view_mut::<3, 3>(0, 0).copy_from(&s);
        p.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.h);
        p.fixed_view_mut::<1, 3>(3, 0)
            .copy_from(&self.h.transpose());
        p[(3, 3)] = self.mass;
        p
    }

    /// The inertia about the centre of mass, `I_G = I_O − m[ρ]×ᵀ[ρ]×`
    /// (inverse of (28)); `None` if the mass is not positive.
    pub fn inertia_about_com(&self) -> Option<Matrix3<f64>> {
        if self.mass <= 0.0 {
            return None;
        }
        let rho = self.h / self.mass;
        Some(self.inertia() - shift(self.mass, &rho))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A link made of point masses `(m_i, p_i)`: `I_O = Σ m(|p|²1 − ppᵀ)`,
    /// `h = Σ m p`, built without any of the code under test.
    fn point_masses(points: &[(f64, [f64; 3])]) -> Inertia {
        let mut i = Matrix3::zeros();
        let mut h = Vector3::zeros();
        let mut mass = 0.0;
        for &(m, p) in points {
            let p = Vector3::from(p);
            i += (Matrix3::identity() * p.dot(&p) - p * p.transpose()) * m;
            h += p * m;
            mass += m;
        }
        let mut l = Inertia {
            h,
            mass,
            ..Inertia::default()
        };
        l.set_inertia(&i);
        l
    }

    /// Sum of the point masses' own `Inertia`s, for comparison.
    fn sum_of_point_masses(points: &[(f64, [f64; 3])]) -> Inertia {
        let mut s = Inertia::default();
        for &(m, p) in points {
            let q = Inertia::point_mass(m, &Vector3::from(p));
            s.set_inertia(&(s.inertia() + q.inertia()));
            s.h += q.h;
            s.mass += q.mass;
        }
        s
    }

    fn cloud() -> impl Strategy<Value = Vec<(f64, [f64; 3])>> {
        prop::collection::vec((0.01..1.0f64, prop::array::uniform3(-0.3..0.3f64)), 1..6)
    }

    proptest! {
        /// The pseudo-inertia is the second moment of mass in homogeneous
        /// coordinates, `𝒥 = Σ m [p; 1][p; 1]ᵀ` (the definition it is
        /// written from), so it is positive semidefinite for any body.
        #[test]
        fn pseudo_inertia_is_the_homogeneous_second_moment(points in cloud()) {
            let j = point_masses(&points).pseudo_inertia();
            let mut want = Matrix4::zeros();
            for &(m, p) in &points {
                let q = nalgebra::Vector4::new(p[0], p[1], p[2], 1.0);
                want += q * q.transpose() * m;
            }
            prop_assert!((j - want).abs().max() <= 1e-15 * (1.0 + want.abs().max()));
            prop_assert!(j.symmetric_eigenvalues().min() >= -1e-15);
        }

        /// `from_com` and `inertia_about_com` are inverse (28), and the
        /// standard vector round-trips.
        #[test]
        fn parallel_axis_and_standard_vector_round_trip(points in cloud()) {
            let l = point_masses(&points);
            let ig = l.inertia_about_com().unwrap();
            let back = Inertia::from_com(l.mass, &ig, &(l.h / l.mass));
            prop_assert!((back.inertia() - l.inertia()).abs().max() <= 1e-15);
            prop_assert!((back.h - l.h).abs().max() <= 1e-15);
            prop_assert_eq!(Inertia::from_standard(&l.standard(), l.mass), l);
            let sum = sum_of_point_masses(&points);
            prop_assert!((sum.inertia() - l.inertia()).abs().max() <= 1e-15);
            prop_assert!((sum.h - l.h).abs().max() <= 1e-15);
        }
    }

    /// Each way of being non-physical makes the smallest eigenvalue negative:
    /// a negative mass, and principal moments breaking the triangle
    /// inequality `I1 + I2 ≥ I3` (67)–(69).
    #[test]
    fn non_physical_links_have_a_negative_eigenvalue() {
        let rho = Vector3::new(0.0, 0.0, 0.1);
        let ok = Inertia::from_com(
            0.2,
            &Matrix3::from_diagonal(&Vector3::new(2e-4, 2e-4, 1e-4)),
            &rho,
        );
        assert!(ok.pseudo_inertia().symmetric_eigenvalues().min() > 0.0);
        let triangle = Inertia::from_com(
            0.2,
            &Matrix3::from_diagonal(&Vector3::new(1e-4, 1e-4, 3e-4)),
            &rho,
        );
        assert!(triangle.pseudo_inertia().symmetric_eigenvalues().min() < 0.0);
        let negative_mass = Inertia { mass: -0.1, ..ok };
        assert!(negative_mass.pseudo_inertia().symmetric_eigenvalues().min() < 0.0);
        assert_eq!(negative_mass.inertia_about_com(), None);
    }
}
