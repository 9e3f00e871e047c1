//! Motion limits: the workspace box and rate limits (77), an acceleration
//! limit, and their enforcement on a time grid with a rigorous margin.
//!
//! # Why a finite grid is enough
//!
//! Every constrained signal `f` (a coordinate's `X_i`, `Ẋ_i` or `Ẍ_i`) is a
//! trigonometric polynomial of degree at most `L·ω_f`. Bernstein's inequality
//! gives `‖f''‖∞ ≤ (L ω_f)² ‖f − c‖∞` for any constant `c`. At an extremum `t*`
//! of `f` (where `f' = 0`) the nearest point of a periodic grid with spacing
//! `h = T/N` is at most `h/2` away, so `|f(t*) − f(t_j)| ≤ q ‖f − c‖∞` with
//! `q = ½ (π L / N)²`. If the grid values stay inside the bounds tightened by
//! `δ = q R` on each side (`R` = half the allowed range, `c` its centre), then
//! the continuous signal stays inside the original bounds. The design
//! tightens by `1.01·q R` to absorb rounding.

use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OVector, U2, Vector2};

use crate::FourierTrajectory;
use crate::error::{ExciteError, check_finite};
use crate::param::{Grid, Layout, dot};

/// Default acceleration limit, 800°/s² per task coordinate (rad/s²).
///
/// The paper gives none. At the default period (10 s) and L = 5 the highest
/// harmonic turns at π rad/s, so the rate limit of 200°/s alone would allow
/// about 630°/s²; 800°/s² keeps motor torques of the capstan-driven links
/// modest while leaving the rate limit the usual active constraint.
pub const DEFAULT_MAX_ACCEL_DEG: f64 = 800.0;

/// The limits an excitation trajectory must respect at every instant: the
/// box and rate limits (77) and an acceleration limit, per coordinate of `X`
/// (for a serial arm, per joint). The number of coordinates is the type
/// `D`, as for [`crate::Motion`].
#[derive(Debug, Clone, PartialEq)]
pub struct Limits<D: Dim = U2>
where
    DefaultAllocator: Allocator<D>,
{
    /// Lower corner of the box, `min ≤ X` (rad).
    pub min: OVector<f64, D>,
    /// Upper corner of the box, `X ≤ max` (rad).
    pub max: OVector<f64, D>,
    /// Rate limit `|Ẋ_i| ≤ max_rate_i` (rad/s).
    pub max_rate: OVector<f64, D>,
    /// Acceleration limit `|Ẍ_i| ≤ max_accel_i` (rad/s²).
    pub max_accel: OVector<f64, D>,
}

impl Copy for Limits<U2> {}

impl Limits<U2> {
    /// The paper's identification box and rates (77), φ ∈ [30°, 140°],
    /// γ ∈ [40°, 80°], |φ̇|, |γ̇| ≤ 200°/s, and [`DEFAULT_MAX_ACCEL_DEG`].
    pub fn paper() -> Self {
        let d = f64::to_radians;
        let a = DEFAULT_MAX_ACCEL_DEG.to_radians();
        Self {
            min: Vector2::new(d(30.0), d(40.0)),
            max: Vector2::new(d(140.0), d(80.0)),
            max_rate: Vector2::new(d(200.0), d(200.0)),
            max_accel: Vector2::new(a, a),
        }
    }
}

impl<D: Dim> Limits<D>
where
    DefaultAllocator: Allocator<D>,
{
    /// Number of coordinates.
    pub fn coordinates(&self) -> usize {
        self.min.len()
    }

    /// Errors if a bound is not finite, the box is empty, or a rate or
    /// acceleration limit is not positive; the message names the setting.
    pub fn validate(&self) -> Result<(), ExciteError> {
        for i in 0..self.coordinates() {
            check_finite(|| format!("min[{i}]"), self.min[i])?;
            check_finite(|| format!("max[{i}]"), self.max[i])?;
            if self.min[i] >= self.max[i] {
                return Err(ExciteError::InvalidSetting {
                    name: "min/max",
                    value: self.min[i],
                    reason: format!(
                        "the box is empty in coordinate {i}: min {:.4}° is not below max {:.4}°",
                        self.min[i].to_degrees(),
                        self.max[i].to_degrees()
                    ),
                });
            }
            for (name, v) in [
                ("max_rate", self.max_rate[i]),
                ("max_accel", self.max_accel[i]),
            ] {
                check_finite(|| format!("{name}[{i}]"), v)?;
                if v <= 0.0 {
                    return Err(ExciteError::InvalidSetting {
                        name,
                        value: v,
                        reason: "the rate and acceleration limits must be positive (rad/s, rad/s²)"
                            .into(),
                    });
                }
            }
        }
        Ok(())
    }

    /// Per coordinate and kind (0 = position, 1 = velocity, 2 = acceleration)
    /// the centre and half-width of the allowed range.
    fn ranges(&self) -> Vec<[(f64, f64); 3]> {
        (0..self.coordinates())
            .map(|i| {
                [
                    (
                        0.5 * (self.min[i] + self.max[i]),
                        0.5 * (self.max[i] - self.min[i]),
                    ),
                    (0.0, self.max_rate[i]),
                    (0.0, self.max_accel[i]),
                ]
            })
            .collect()
    }
}

impl Default for Limits {
    fn default() -> Self {
        Self::paper()
    }
}

/// How close a trajectory comes to its limits, sampled on a grid.
///
/// Each margin is the smallest distance to the nearest bound over the grid
/// (rad, rad/s, rad/s²): positive means inside, negative a violation.
#[derive(Debug, Clone, PartialEq)]
pub struct Margins<D: Dim = U2>
where
    DefaultAllocator: Allocator<D>,
{
    /// Position margins per coordinate (for ARAS-Diamond `[φ, γ]`, rad).
    pub position: OVector<f64, D>,
    /// Velocity margins (rad/s).
    pub velocity: OVector<f64, D>,
    /// Acceleration margins (rad/s²).
    pub acceleration: OVector<f64, D>,
    /// The smallest margin relative to its allowed half-range
    /// (dimensionless; 0 = touching a limit, negative = violated).
    pub worst_relative: f64,
    /// Number of grid points per period the margins were measured on.
    pub points: usize,
}

impl Copy for Margins<U2> {}

impl<D: Dim> Margins<D>
where
    DefaultAllocator: Allocator<D>,
{
    /// Measures the margins of `trajectory` on `points` equally spaced
    /// instants of one period (the trajectory is periodic, so one period
    /// covers all time).
    pub fn measure(trajectory: &FourierTrajectory<D>, limits: &Limits<D>, points: usize) -> Self {
        let ranges = limits.ranges();
        let n = ranges.len();
        let mut m = vec![[f64::INFINITY; 3]; n];
        for row in trajectory.sample(points.max(1), 1) {
            let v = [&row.state.pos, &row.state.vel, &row.state.acc];
            for i in 0..n {
                for k in 0..3 {
                    let (c, r) = ranges[i][k];
                    m[i][k] = m[i][k].min(r - (v[k][i] - c).abs());
                }
            }
        }
        let mut worst = f64::INFINITY;
        for i in 0..n {
            for k in 0..3 {
                worst = worst.min(m[i][k] / ranges[i][k].1);
            }
        }
        let column = |k: usize| {
            let mut v = limits.min.clone();
            v.iter_mut().zip(&m).for_each(|(v, m)| *v = m[k]);
            v
        };
        Self {
            position: column(0),
            velocity: column(1),
            acceleration: column(2),
            worst_relative: worst,
            points,
        }
    }
}

/// The tightening factor `q = ½ (π L / N)²` of the module docs.
pub(crate) fn grid_factor(harmonics: usize, points: usize) -> f64 {
    let r = std::f64::consts::PI * harmonics as f64 / points as f64;
    0.5 * r * r
}

/// The constraints on a grid as `F1(p) ∈ [lo, hi]`, linear in the decision
/// vector. `F1` is laid out in blocks of `N` values: for coordinate `i` and
/// kind `k` (position, velocity, acceleration) the block index is `3 i + k`.
#[derive(Debug, Clone)]
pub(crate) struct GridConstraints {
    pub grid: Grid,
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    /// Tightened `(centre, half-range)` per coordinate and kind.
    tight: Vec<[(f64, f64); 3]>,
}

impl GridConstraints {
    /// Constraints on `points` instants of a period, tightened so that grid
    /// feasibility implies continuous feasibility.
    pub fn new<D: Dim>(layout: Layout, limits: &Limits<D>, points: usize) -> Self
    where
        DefaultAllocator: Allocator<D>,
    {
        let grid = Grid::new(layout, points, 0.0);
        let q = 1.01 * grid_factor(layout.harmonics, points);
        let tight: Vec<[(f64, f64); 3]> = limits
            .ranges()
            .into_iter()
            .map(|r| r.map(|(c, h)| (c, h * (1.0 - q))))
            .collect();
        let mut lo = Vec::with_capacity(3 * tight.len() * points);
        let mut hi = Vec::with_capacity(3 * tight.len() * points);
        for coord in &tight {
            for &(c, h) in coord {
                lo.extend(std::iter::repeat_n(c - h, points));
                hi.extend(std::iter::repeat_n(c + h, points));
            }
        }
        Self {
            grid,
            lo,
            hi,
            tight,
        }
    }

    /// Tightened `(centre, half-range)` of coordinate `i`'s positions.
    pub fn position_range(&self, i: usize) -> (f64, f64) {
        self.tight[i][0]
    }

    /// Number of constraint values (3nN: three kinds per coordinate).
    pub fn len(&self) -> usize {
        self.lo.len()
    }

    fn basis(&self, k: usize) -> &[f64] {
        match k {
            0 => &self.grid.pos,
            1 => &self.grid.vel,
            _ => &self.grid.acc,
        }
    }

    /// `F1(p)`.
    pub fn map(&self, p: &[f64], out: &mut [f64]) {
        let n = self.grid.len();
        let w = self.grid.layout.per_coord();
        for i in 0..self.tight.len() {
            let block = &p[i * w..(i + 1) * w];
            for k in 0..3 {
                let b = self.basis(k);
                let o = &mut out[(3 * i + k) * n..(3 * i + k + 1) * n];
                for (j, v) in o.iter_mut().enumerate() {
                    *v = dot(&b[j * w..(j + 1) * w], block);
                }
            }
        }
    }

    /// `J_F1ᵀ d` (exact: `F1` is linear).
    pub fn jacobian_t(&self, d: &[f64], out: &mut [f64]) {
        let n = self.grid.len();
        let w = self.grid.layout.per_coord();
        out.iter_mut().for_each(|v| *v = 0.0);
        for i in 0..self.tight.len() {
            let g = &mut out[i * w..(i + 1) * w];
            for k in 0..3 {
                let b = self.basis(k);
                let dk = &d[(3 * i + k) * n..(3 * i + k + 1) * n];
                for (j, &dj) in dk.iter().enumerate() {
                    for (gv, bv) in g.iter_mut().zip(&b[j * w..(j + 1) * w]) {
                        *gv += dj * bv;
                    }
                }
            }
        }
    }

    /// Largest violation of the tightened grid bounds (0 if feasible).
    #[cfg(test)]
    pub fn violation(&self, p: &[f64]) -> f64 {
        let mut f = vec![0.0; self.len()];
        self.map(p, &mut f);
        f.iter()
            .zip(self.lo.iter().zip(&self.hi))
            .map(|(v, (lo, hi))| (lo - v).max(v - hi).max(0.0))
            .fold(0.0, f64::max)
    }

    /// Scales each coordinate's motion about the centre of its tightened
    /// box, `X ← c + s (X − c)`, `Ẋ ← s Ẋ`, `Ẍ ← s Ẍ`, with the largest `s`
    /// that keeps every grid value within the tightened bounds. With `centre`
    /// the motion is first shifted so its excursion is centred in the box;
    /// with `grow` the scale may exceed 1 (to touch the limits). Keeps
    /// `Ẋ(0) = 0`. Returns the smallest scale applied.
    pub fn scale_to_fit(&self, p: &mut [f64], centre: bool, grow: bool) -> f64 {
        let n = self.grid.len();
        let w = self.grid.layout.per_coord();
        let mut f = vec![0.0; self.len()];
        let mut smallest = f64::INFINITY;
        for i in 0..self.tight.len() {
            self.map(p, &mut f);
            let block = |k: usize| &f[(3 * i + k) * n..(3 * i + k + 1) * n];
            let (c, r_pos) = self.tight[i][0];
            if centre {
                let (lo, hi) = block(0)
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                        (a.min(v), b.max(v))
                    });
                p[i * w] += c - 0.5 * (lo + hi);
                self.map(p, &mut f);
            }
            let block = |k: usize| &f[(3 * i + k) * n..(3 * i + k + 1) * n];
            let mut s = f64::INFINITY;
            for k in 0..3 {
                let (ck, rk) = if k == 0 { (c, r_pos) } else { self.tight[i][k] };
                let peak = block(k).iter().map(|v| (v - ck).abs()).fold(0.0, f64::max);
                if peak > 0.0 {
                    s = s.min(rk / peak);
                }
            }
            if !s.is_finite() {
                s = 1.0; // no motion and centred: nothing to scale
            }
            if !grow {
                s = s.min(1.0);
            }
            let b = &mut p[i * w..(i + 1) * w];
            b[0] = c + s * (b[0] - c);
            b[1..].iter_mut().for_each(|v| *v *= s);
            smallest = smallest.min(s);
        }
        smallest
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn layout() -> Layout {
        Layout {
            harmonics: 5,
            omega_f: std::f64::consts::TAU / 10.0,
            coords: 2,
        }
    }

    proptest! {
        // The grid margin theorem: any point scaled onto the tightened grid
        // bounds of a coarse grid (N = 60, so q ≈ 3.4 %) satisfies the true
        // limits on a grid 50× finer, with the limits touched on the coarse grid.
        #[test]
        fn coarse_grid_feasibility_is_continuous_feasibility(
            p in proptest::collection::vec(-1.0..1.0f64, 20),
        ) {
            let limits = Limits::paper();
            let c = GridConstraints::new(layout(), &limits, 60);
            let mut p = p;
            c.scale_to_fit(&mut p, true, true);
            prop_assert!(c.violation(&p) < 1e-12);
            let f: FourierTrajectory = layout().trajectory(&p).unwrap();
            let m = Margins::measure(&f, &limits, 3000);
            prop_assert!(m.worst_relative >= 0.0, "{m:?}");
        }

        // Jᵀ is the transpose of the linear map F1: ⟨F1(p), d⟩ = ⟨p, Jᵀd⟩
        // for a map with no constant term (offsets zero).
        #[test]
        fn jacobian_transpose_is_adjoint(
            p in proptest::collection::vec(-1.0..1.0f64, 20),
            d in proptest::collection::vec(-1.0..1.0f64, 6 * 16),
        ) {
            let c = GridConstraints::new(layout(), &Limits::paper(), 16);
            let mut f = vec![0.0; c.len()];
            c.map(&p, &mut f);
            let mut jt = vec![0.0; 20];
            c.jacobian_t(&d, &mut jt);
            let lhs = dot(&f, &d);
            let rhs = dot(&p, &jt);
            prop_assert!((lhs - rhs).abs() < 1e-10 * (1.0 + lhs.abs()));
        }
    }

    #[test]
    fn acceleration_limit_is_validated() {
        let mut l = Limits::paper();
        l.max_accel[1] = 0.0;
        assert!(l.validate().unwrap_err().to_string().contains("max_accel"));
        l.max_accel[1] = f64::NAN;
        assert!(l.validate().is_err());
    }

    #[test]
    fn margins_see_a_violation() {
        let f: FourierTrajectory = FourierTrajectory::new(
            1.0,
            [1.5, 1.0],
            [vec![5.0], vec![0.0]],
            [vec![0.0], vec![0.0]],
        )
        .unwrap();
        let m = Margins::measure(&f, &Limits::paper(), 100);
        assert!(m.velocity[0] < 0.0 && m.worst_relative < 0.0);
    }
}
