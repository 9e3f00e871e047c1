//! The decision vector of the design and the linear maps from it to
//! `X`, `Ẋ`, `Ẍ` on a time grid.
//!
//! Zero velocity at the period boundary, `Ẋ_i(0) = Σ_l a_l^i = 0`, is
//! eliminated by parametrisation: `a_L^i = −Σ_{l<L} a_l^i`. Per coordinate the
//! free variables are `[X_i0, a_1 … a_{L−1}, b_1 … b_L]` (2L numbers), and the
//! decision vector is the coordinates' blocks in order (`2L·n` numbers; for
//! ARAS-Diamond `[φ block, γ block]`). Every sample of `X`,
//! `Ẋ`, `Ẍ` is then an exact linear function of the decision vector, which is
//! what makes the constraint Jacobians and the chain rule of the criterion
//! gradient exact and cheap.

use nalgebra::Dim;

use crate::{ExciteError, FourierTrajectory};

/// Layout of the decision vector for `L` harmonics at base frequency ω_f
/// and `coords` coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Layout {
    pub harmonics: usize,
    pub omega_f: f64,
    pub coords: usize,
}

impl Layout {
    /// Free variables per coordinate (2L).
    pub fn per_coord(&self) -> usize {
        2 * self.harmonics
    }

    /// Length of the decision vector (2L·n).
    pub fn dim(&self) -> usize {
        self.per_coord() * self.coords
    }

    /// Fills the rows mapping one coordinate's block to `X_i(t)`, `Ẋ_i(t)`,
    /// `Ẍ_i(t)` (each of length 2L). No allocation.
    pub fn basis(&self, t: f64, pos: &mut [f64], vel: &mut [f64], acc: &mut [f64]) {
        let l_max = self.harmonics;
        let wl = self.omega_f * l_max as f64;
        let (sl, cl) = (wl * t).sin_cos();
        pos[0] = 1.0;
        vel[0] = 0.0;
        acc[0] = 0.0;
        for l in 1..=l_max {
            let w = self.omega_f * l as f64;
            let (s, c) = (w * t).sin_cos();
            if l < l_max {
                // a_l, with a_L = −Σ a_l folded in.
                pos[l] = s / w - sl / wl;
                vel[l] = c - cl;
                acc[l] = -w * s + wl * sl;
            }
            let k = l_max + l - 1; // b_l
            pos[k] = -c / w;
            vel[k] = s;
            acc[k] = w * c;
        }
    }

    /// The trajectory a decision vector stands for.
    pub fn trajectory<D: Dim>(&self, p: &[f64]) -> Result<FourierTrajectory<D>, ExciteError> {
        let n = self.per_coord();
        let l_max = self.harmonics;
        let mut offset = vec![0.0; self.coords];
        let mut a = vec![vec![0.0; l_max]; self.coords];
        let mut b = vec![vec![0.0; l_max]; self.coords];
        for i in 0..self.coords {
            let block = &p[i * n..(i + 1) * n];
            offset[i] = block[0];
            let mut sum = 0.0;
            for l in 1..l_max {
                a[i][l - 1] = block[l];
                sum += block[l];
            }
            a[i][l_max - 1] = -sum;
            b[i].copy_from_slice(&block[l_max..]);
        }
        FourierTrajectory::new(self.omega_f, offset, a, b)
    }
}

/// The basis rows of a layout on a fixed time grid: for each time `t_j`, the
/// rows giving `X_i(t_j)`, `Ẋ_i(t_j)`, `Ẍ_i(t_j)` from a coordinate block.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    pub layout: Layout,
    pub times: Vec<f64>,
    /// Row-major `N × 2L` each.
    pub pos: Vec<f64>,
    pub vel: Vec<f64>,
    pub acc: Vec<f64>,
}

impl Grid {
    /// The grid `t_j = (j + shift)·T/N`, `j = 0..N`.
    pub fn new(layout: Layout, points: usize, shift: f64) -> Self {
        let period = std::f64::consts::TAU / layout.omega_f;
        let times: Vec<f64> = (0..points)
            .map(|j| (j as f64 + shift) * period / points as f64)
            .collect();
        let m = layout.per_coord();
        let mut pos = vec![0.0; points * m];
        let mut vel = vec![0.0; points * m];
        let mut acc = vec![0.0; points * m];
        for (j, &t) in times.iter().enumerate() {
            let r = j * m..(j + 1) * m;
            layout.basis(
                t,
                &mut pos[r.clone()],
                &mut vel[r.clone()],
                &mut acc[r.clone()],
            );
        }
        Self {
            layout,
            times,
            pos,
            vel,
            acc,
        }
    }

    /// Number of grid points.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Row `j` of a basis matrix.
    pub fn row<'a>(&self, m: &'a [f64], j: usize) -> &'a [f64] {
        let w = self.layout.per_coord();
        &m[j * w..(j + 1) * w]
    }

    /// `[X, Ẋ, Ẍ]` at grid point `j` for decision vector `p`, into `out`
    /// (`3n` entries: the positions, then the rates, then the
    /// accelerations).
    pub fn state(&self, p: &[f64], j: usize, out: &mut [f64]) {
        let w = self.layout.per_coord();
        let n = self.layout.coords;
        for i in 0..n {
            let block = &p[i * w..(i + 1) * w];
            out[i] = dot(self.row(&self.pos, j), block);
            out[n + i] = dot(self.row(&self.vel, j), block);
            out[2 * n + i] = dot(self.row(&self.acc, j), block);
        }
    }
}

/// Dot product of equal-length slices.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        // The linear maps reproduce the trajectory's own evaluation (same
        // formulas, different summation order: 1e-12 covers rounding).
        #[test]
        fn basis_matches_trajectory(
            p in proptest::collection::vec(-1.0..1.0f64, 20),
            t in 0.0..10.0f64,
        ) {
            let layout = Layout { harmonics: 5, omega_f: 0.628, coords: 2 };
            let f: FourierTrajectory = layout.trajectory(&p).unwrap();
            let g = Grid { layout, times: vec![t], pos: vec![0.0; 10], vel: vec![0.0; 10], acc: vec![0.0; 10] };
            let mut g = g;
            let (mut a, mut b, mut c) = (vec![0.0; 10], vec![0.0; 10], vec![0.0; 10]);
            layout.basis(t, &mut a, &mut b, &mut c);
            g.pos = a; g.vel = b; g.acc = c;
            let s = f.eval(t);
            let mut v = [0.0; 6];
            g.state(&p, 0, &mut v);
            let at = |k: usize| nalgebra::Vector2::new(v[2 * k], v[2 * k + 1]);
            prop_assert!((at(0) - s.pos).norm() < 1e-12);
            prop_assert!((at(1) - s.vel).norm() < 1e-12);
            prop_assert!((at(2) - s.acc).norm() < 1e-12);
            // Zero velocity at the period boundary, by construction.
            prop_assert!(f.eval(0.0).vel.norm() < 1e-12);
        }
    }

    #[test]
    fn single_harmonic_has_only_b() {
        let layout = Layout {
            harmonics: 1,
            omega_f: 1.0,
            coords: 2,
        };
        let f: FourierTrajectory = layout.trajectory(&[1.0, 0.3, 0.9, -0.2]).unwrap();
        assert_eq!(f.a(0), &[0.0]);
        assert_eq!(f.b(1), &[-0.2]);
        assert_eq!(f.offset(), nalgebra::Vector2::new(1.0, 0.9));
    }
}
