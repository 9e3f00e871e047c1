//! A user constraint on the pose, `g(X) ≤ 0`: limits that are not a box
//! per coordinate, such as a tool tip kept above a table, a serial arm's
//! task-space workspace while the design runs in joint space, or
//! ARAS-Diamond's cone of directions (77) for a design in motor angles.
//!
//! # How it enters the design
//!
//! * **Optimiser.** `g` is evaluated at every point of the constraint grid
//!   and appended to the augmented Lagrangian's path constraints
//!   `F1(p) ∈ C` with `C = (−∞, −margin]` for each value, next to the box,
//!   rate and acceleration bounds (the ALM's multipliers handle nonlinear
//!   `F1` with its exact transposed Jacobian, here from
//!   [`PoseConstraint::jacobian`] chained through the linear position rows).
//! * **Repair.** The ALM ends within its infeasibility tolerance, not
//!   inside. After the box repair, the motion is scaled about a feasible
//!   *anchor* rest pose `X_a`, `X ← X_a + s (X − X_a)` (the box is convex and
//!   contains `X_a`, so it stays satisfied), with the largest `s ∈ [0, 1]`
//!   found by bisection that satisfies the check below; `s = 0` is the
//!   feasible rest at `X_a`, so the repair always ends feasible.
//! * **Check.** On a grid [`ConstraintSettings::check_factor`] times finer
//!   than the constraint grid (which it contains),
//!   `g_k(X(t_j)) + c_j ≤ −margin` for every value `k` and point `j`, where
//!   `c_j = ⅛·max |Δ²g_k|` over the neighbouring second differences is the
//!   curvature allowance: for a smooth `g(X(t))` the maximum between two
//!   check points exceeds the larger of them by at most `⅛ h² |g''|`, and
//!   `Δ²g ≈ h² g''`. A box limit is proven continuous by Bernstein's
//!   inequality ([`crate::constraints`]); a general `g` has no such bound,
//!   so this allowance is second-order accurate, not a proof: the designs'
//!   tests measure the remaining excess on grids 10× finer still.
//! * **Random trajectories.** [`random_feasible_constrained`](crate::random_feasible_constrained)
//!   and the design's starts draw as without a constraint, then scale about
//!   the anchor in the same way until `g` is touched, so a constraint the
//!   random motion never reaches changes nothing.
//!
//! The anchor is [`ConstraintSettings::anchor`] when given, otherwise the
//! pose of the tightened box (its centre and 1681 quasi-random poses)
//! where `max_k g_k` is smallest.

use std::convert::Infallible;

use serde::{Deserialize, Serialize};

use crate::Dual;
use crate::constraints::GridConstraints;
use crate::error::ExciteError;
use crate::param::{Grid, dot};

/// A constraint `g(X) ≤ 0` (each of its [`values`](Self::values)) on the
/// positions `X` of the design's coordinates, with its Jacobian.
///
/// Implement it directly with an analytic Jacobian, or wrap a function of
/// [`Dual`] numbers in [`DualConstraint`] to get the Jacobian exactly by
/// forward differentiation. `Sync`: the design's starts run in parallel.
///
/// A pose where the constraint cannot be evaluated is an error; so is a
/// non-finite value or derivative (the design stops with
/// [`ExciteError::Constraint`]).
pub trait PoseConstraint: Sync {
    /// What evaluation reports when it fails.
    type Error: std::error::Error + Send + Sync + 'static;

    /// Number of coordinates `n` of `X` (the design's coordinates).
    fn coordinates(&self) -> usize;

    /// Number of constraint values `m` (each must stay `≤ 0`).
    fn values(&self) -> usize;

    /// Name of value `k`, for reports and messages (default `g[k]`).
    fn name(&self, k: usize) -> String {
        format!("g[{k}]")
    }

    /// `g(X)` into `g` (`m` entries).
    fn eval(&self, x: &[f64], g: &mut [f64]) -> Result<(), Self::Error>;

    /// `g(X)` into `g` and its Jacobian `∂g_k/∂X_i` into `jac`, row-major
    /// `m × n` (`jac[k·n + i]`).
    fn jacobian(&self, x: &[f64], g: &mut [f64], jac: &mut [f64]) -> Result<(), Self::Error>;
}

impl<C: PoseConstraint> PoseConstraint for &C {
    type Error = C::Error;
    fn coordinates(&self) -> usize {
        (**self).coordinates()
    }
    fn values(&self) -> usize {
        (**self).values()
    }
    fn name(&self, k: usize) -> String {
        (**self).name(k)
    }
    fn eval(&self, x: &[f64], g: &mut [f64]) -> Result<(), Self::Error> {
        (**self).eval(x, g)
    }
    fn jacobian(&self, x: &[f64], g: &mut [f64], jac: &mut [f64]) -> Result<(), Self::Error> {
        (**self).jacobian(x, g, jac)
    }
}

/// A [`PoseConstraint`] from one function of [`Dual`] numbers: the values
/// are its real parts, the Jacobian its derivatives, seeded six coordinates
/// per evaluation (`⌈n/6⌉` evaluations per Jacobian), as the regressor's
/// [`fill_dual`](crate::Regressor::fill_dual).
///
/// ```
/// use aras_excite::{DualConstraint, PoseConstraint};
/// use num_dual::DualNum;
/// // A two-link arm's tip (lengths 0.3 m, 0.2 m) at least 0.1 m above its base.
/// let above = DualConstraint::new(2, 1, |q: &[aras_excite::Dual], g: &mut [aras_excite::Dual]| {
///     let y = (q[0]).sin() * 0.3 + (q[0] + q[1]).sin() * 0.2;
///     g[0] = -y + 0.1;
/// });
/// let (mut g, mut jac) = ([0.0], [0.0; 2]);
/// above.jacobian(&[0.5, 0.2], &mut g, &mut jac).unwrap();
/// assert!((jac[1] + 0.2 * 0.7f64.cos()).abs() < 1e-15);
/// ```
pub struct DualConstraint<F> {
    coordinates: usize,
    values: usize,
    names: Vec<String>,
    f: F,
}

impl<F> DualConstraint<F>
where
    F: Fn(&[Dual], &mut [Dual]) + Sync,
{
    /// `m = values` constraint values of `n = coordinates` positions,
    /// `f(X, g)` writing `g(X)` (the slice is zeroed before each call).
    pub fn new(coordinates: usize, values: usize, f: F) -> Self {
        Self {
            coordinates,
            values,
            names: Vec::new(),
            f,
        }
    }

    /// Names the values (for reports); missing names fall back to `g[k]`.
    pub fn with_names(mut self, names: impl IntoIterator<Item = impl Into<String>>) -> Self {
        self.names = names.into_iter().map(Into::into).collect();
        self
    }
}

impl<F> std::fmt::Debug for DualConstraint<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DualConstraint")
            .field("coordinates", &self.coordinates)
            .field("values", &self.values)
            .field("names", &self.names)
            .finish_non_exhaustive()
    }
}

/// Most coordinates a [`DualConstraint`] evaluates without allocating.
const STACK_COORDS: usize = 12;
/// Most values a [`DualConstraint`] evaluates without allocating.
const STACK_VALUES: usize = 16;

impl<F> PoseConstraint for DualConstraint<F>
where
    F: Fn(&[Dual], &mut [Dual]) + Sync,
{
    type Error = Infallible;

    fn coordinates(&self) -> usize {
        self.coordinates
    }

    fn values(&self) -> usize {
        self.values
    }

    fn name(&self, k: usize) -> String {
        self.names
            .get(k)
            .cloned()
            .unwrap_or_else(|| format!("g[{k}]"))
    }

    fn eval(&self, x: &[f64], g: &mut [f64]) -> Result<(), Infallible> {
        self.passes(x, g, None);
        Ok(())
    }

    fn jacobian(&self, x: &[f64], g: &mut [f64], jac: &mut [f64]) -> Result<(), Infallible> {
        self.passes(x, g, Some(jac));
        Ok(())
    }
}

impl<F> DualConstraint<F>
where
    F: Fn(&[Dual], &mut [Dual]) + Sync,
{
    /// Values, and with `jac` the Jacobian in `⌈n/6⌉` seeded passes (one
    /// unseeded pass for the values alone). No allocation up to
    /// 12 coordinates and 16 values.
    fn passes(&self, x: &[f64], g: &mut [f64], mut jac: Option<&mut [f64]>) {
        let (n, m) = (self.coordinates, self.values);
        let zero = Dual::from_re(0.0);
        let (mut xs, mut gs) = ([zero; STACK_COORDS], [zero; STACK_VALUES]);
        let (mut xh, mut gh) = (Vec::new(), Vec::new());
        let (xd, gd): (&mut [Dual], &mut [Dual]) = if n <= STACK_COORDS && m <= STACK_VALUES {
            (&mut xs[..n], &mut gs[..m])
        } else {
            xh.resize(n, zero);
            gh.resize(m, zero);
            (&mut xh, &mut gh)
        };
        let firsts = if jac.is_some() { n.max(1) } else { 1 };
        for first in (0..firsts).step_by(6) {
            for (i, (d, &v)) in xd.iter_mut().zip(x).enumerate() {
                let slot = i.wrapping_sub(first);
                *d = if jac.is_some() && slot < 6 {
                    Dual::from_re(v).derivative(slot)
                } else {
                    Dual::from_re(v)
                };
            }
            gd.fill(zero);
            (self.f)(xd, gd);
            for (gk, d) in g.iter_mut().zip(gd.iter()) {
                *gk = d.re;
            }
            if let Some(jac) = jac.as_deref_mut() {
                for (k, d) in gd.iter().enumerate() {
                    for i in first..(first + 6).min(n) {
                        jac[k * n + i] = d.eps.0.as_ref().map_or(0.0, |e| e[i - first]);
                    }
                }
            }
        }
    }
}

/// Settings of a pose constraint in the design (serde, defaults in
/// [`Default`]): how far inside `g ≤ 0` to stay, how finely to check, and
/// which rest pose the repair scales towards.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConstraintSettings {
    /// Required clearance: `g ≤ −margin` at every check point, including
    /// the curvature allowance (in `g`'s units, default 0, ≥ 0).
    pub margin: f64,
    /// The check grid is this many times finer than the constraint grid
    /// (default 10, ≥ 1; 1 checks on the constraint grid itself).
    pub check_factor: usize,
    /// Rest pose the repair and the random trajectories scale towards
    /// (rad, one per coordinate, inside the tightened box with
    /// `g ≤ −margin`); `None` (default) takes the pose of the box where
    /// `max_k g_k` is smallest.
    pub anchor: Option<Vec<f64>>,
}

impl Default for ConstraintSettings {
    fn default() -> Self {
        Self {
            margin: 0.0,
            check_factor: 10,
            anchor: None,
        }
    }
}

impl ConstraintSettings {
    /// Errors on a negative or non-finite margin or a zero check factor.
    pub fn validate(&self) -> Result<(), ExciteError> {
        crate::error::check_finite(|| "constraint.margin".into(), self.margin)?;
        if self.margin < 0.0 {
            return Err(ExciteError::InvalidSetting {
                name: "constraint.margin",
                value: self.margin,
                reason: "the clearance must be ≥ 0 (g ≤ −margin)".into(),
            });
        }
        if self.check_factor == 0 {
            return Err(ExciteError::InvalidSetting {
                name: "constraint.check_factor",
                value: 0.0,
                reason: "the check grid needs at least the constraint grid's points (≥ 1)".into(),
            });
        }
        if let Some(a) = &self.anchor {
            for (i, v) in a.iter().enumerate() {
                crate::error::check_finite(|| format!("constraint.anchor[{i}]"), *v)?;
            }
        }
        Ok(())
    }
}

/// How a trajectory meets a [`PoseConstraint`] on the check grid.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstraintCheck {
    /// Largest constraint value over the check grid (`≤ −margin` after the
    /// design's repair; in `g`'s units).
    pub worst: f64,
    /// Which value it is (`k` of `g_k`) and its name.
    pub worst_value: usize,
    /// [`PoseConstraint::name`] of `worst_value`.
    pub worst_name: String,
    /// When in the period it occurs (s).
    pub worst_time: f64,
    /// The largest curvature allowance `⅛ max |Δ²g|` on the grid.
    pub allowance: f64,
    /// The estimated continuous maximum: the largest `g_k(X(t_j)) + c_j`
    /// (value plus its point's curvature allowance, `≤ −margin` after the
    /// design's repair).
    pub estimated_max: f64,
    /// Check points per period.
    pub points: usize,
    /// The anchor rest pose used (rad).
    pub anchor: Vec<f64>,
}

/// The constraint on the design's grids: its part of `F1`, the anchor, the
/// repair and the check.
pub(crate) struct PoseGrid<'a, C: PoseConstraint> {
    pub constraint: &'a C,
    pub settings: &'a ConstraintSettings,
    pub anchor: Vec<f64>,
    /// The check grid (`check_factor` × the constraint grid, unshifted).
    check: Grid,
}

impl<'a, C: PoseConstraint> PoseGrid<'a, C> {
    /// Validates the constraint against the grid and finds the anchor.
    pub fn new(
        constraint: &'a C,
        settings: &'a ConstraintSettings,
        cons: &GridConstraints,
    ) -> Result<Self, ExciteError> {
        settings.validate()?;
        let layout = cons.grid.layout;
        let n = layout.coords;
        if constraint.coordinates() != n {
            return Err(ExciteError::InvalidSetting {
                name: "constraint",
                value: constraint.coordinates() as f64,
                reason: format!(
                    "the pose constraint is written for {} coordinates, the design moves {n}",
                    constraint.coordinates()
                ),
            });
        }
        if constraint.values() == 0 {
            return Err(ExciteError::InvalidSetting {
                name: "constraint",
                value: 0.0,
                reason: "the pose constraint has no values; give at least one g_k".into(),
            });
        }
        let check = Grid::new(layout, settings.check_factor * cons.grid.len(), 0.0);
        let mut me = Self {
            constraint,
            settings,
            anchor: Vec::new(),
            check,
        };
        me.anchor = me.find_anchor(cons)?;
        Ok(me)
    }

    /// Number of values `m`.
    pub fn values(&self) -> usize {
        self.constraint.values()
    }

    fn eval(&self, x: &[f64], g: &mut [f64]) -> Result<(), ExciteError> {
        self.constraint
            .eval(x, g)
            .map_err(|e| ExciteError::Constraint {
                at: x.to_vec(),
                source: Box::new(e),
            })?;
        check_values(x, g)
    }

    /// The user's anchor (checked), or the deepest pose of the box.
    fn find_anchor(&self, cons: &GridConstraints) -> Result<Vec<f64>, ExciteError> {
        let n = cons.grid.layout.coords;
        let m = self.values();
        let mut g = vec![0.0; m];
        let inside = |x: &[f64]| {
            (0..n).all(|i| {
                let (c, h) = cons.position_range(i);
                (x[i] - c).abs() <= h
            })
        };
        let margin = self.settings.margin;
        if let Some(a) = &self.settings.anchor {
            if a.len() != n || !inside(a) {
                return Err(ExciteError::InvalidSetting {
                    name: "constraint.anchor",
                    value: a.len() as f64,
                    reason: format!(
                        "the anchor must give {n} positions inside the box tightened by the \
                         grid margin"
                    ),
                });
            }
            self.eval(a, &mut g)?;
            let worst = g.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if worst > -margin {
                return Err(ExciteError::ConstraintInfeasible {
                    at: a.clone(),
                    worst,
                    margin,
                });
            }
            return Ok(a.clone());
        }
        let (lo, hi): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|i| {
                let (c, h) = cons.position_range(i);
                (c - h, c + h)
            })
            .unzip();
        let centre: Vec<f64> = (0..n).map(|i| cons.position_range(i).0).collect();
        let mut best: Option<(f64, Vec<f64>)> = None;
        for x in std::iter::once(centre).chain(crate::design::kronecker_poses(&lo, &hi)) {
            self.eval(&x, &mut g)?;
            let worst = g.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if best.as_ref().is_none_or(|(b, _)| worst < *b) {
                best = Some((worst, x));
            }
        }
        let (worst, at) = best.expect("the centre is always a candidate");
        if worst > -margin {
            return Err(ExciteError::ConstraintInfeasible { at, worst, margin });
        }
        Ok(at)
    }

    /// The constraint's part of `F1`: `out[k·N + j] = g_k(X(t_j))` on the
    /// constraint grid `grid`.
    pub fn map(&self, grid: &Grid, p: &[f64], out: &mut [f64]) -> Result<(), ExciteError> {
        let (n, m, pts) = (grid.layout.coords, self.values(), grid.len());
        let (mut x, mut g) = (vec![0.0; n], vec![0.0; m]);
        for j in 0..pts {
            positions(grid, p, j, &mut x);
            self.eval(&x, &mut g)?;
            for k in 0..m {
                out[k * pts + j] = g[k];
            }
        }
        Ok(())
    }

    /// Adds `J_gᵀ d` (the constraint's part of `J_F1ᵀ d`, `d` laid out as
    /// [`map`](Self::map)'s output) to `out`.
    pub fn add_jacobian_t(
        &self,
        grid: &Grid,
        p: &[f64],
        d: &[f64],
        out: &mut [f64],
    ) -> Result<(), ExciteError> {
        let (n, m, pts) = (grid.layout.coords, self.values(), grid.len());
        let w = grid.layout.per_coord();
        let (mut x, mut g, mut jac) = (vec![0.0; n], vec![0.0; m], vec![0.0; m * n]);
        for j in 0..pts {
            if (0..m).all(|k| d[k * pts + j] == 0.0) {
                continue;
            }
            positions(grid, p, j, &mut x);
            self.constraint
                .jacobian(&x, &mut g, &mut jac)
                .map_err(|e| ExciteError::Constraint {
                    at: x.clone(),
                    source: Box::new(e),
                })?;
            check_values(&x, &jac)?;
            let row = grid.row(&grid.pos, j);
            for i in 0..n {
                let c: f64 = (0..m).map(|k| d[k * pts + j] * jac[k * n + i]).sum();
                if c != 0.0 {
                    for (o, r) in out[i * w..(i + 1) * w].iter_mut().zip(row) {
                        *o += c * r;
                    }
                }
            }
        }
        Ok(())
    }

    /// The check-grid values of `p` scaled by `s` about the anchor, and
    /// their curvature allowances: `(values[k·P + j], allowance[j])`.
    fn check_values(
        &self,
        base: &[f64],
        s: f64,
        values: &mut [f64],
        allowance: &mut [f64],
    ) -> Result<(), ExciteError> {
        let n = self.check.layout.coords;
        let (m, pts) = (self.values(), self.check.len());
        let (mut x, mut g) = (vec![0.0; n], vec![0.0; m]);
        for j in 0..pts {
            for i in 0..n {
                x[i] = self.anchor[i] + s * (base[j * n + i] - self.anchor[i]);
            }
            self.eval(&x, &mut g)?;
            for k in 0..m {
                values[k * pts + j] = g[k];
            }
        }
        // ⅛ of the largest neighbouring second difference, per point.
        allowance.fill(0.0);
        if pts >= 3 {
            let mut dd = vec![0.0; pts];
            for k in 0..m {
                let v = &values[k * pts..(k + 1) * pts];
                for j in 0..pts {
                    let (a, b) = ((j + pts - 1) % pts, (j + 1) % pts);
                    dd[j] = (v[a] - 2.0 * v[j] + v[b]).abs();
                }
                for j in 0..pts {
                    let (a, b) = ((j + pts - 1) % pts, (j + 1) % pts);
                    let c = 0.125 * dd[a].max(dd[j]).max(dd[b]);
                    allowance[j] = allowance[j].max(c);
                }
            }
        }
        Ok(())
    }

    /// The positions of `p` on the check grid, point-major (`j·n + i`).
    fn check_positions(&self, p: &[f64]) -> Vec<f64> {
        let n = self.check.layout.coords;
        let mut base = vec![0.0; self.check.len() * n];
        for j in 0..self.check.len() {
            positions(&self.check, p, j, &mut base[j * n..(j + 1) * n]);
        }
        base
    }

    /// Scales the motion about the anchor, `X ← X_a + s (X − X_a)`, with
    /// the largest `s ∈ [0, s_max]` (bisection) that satisfies the check
    /// (`g + allowance ≤ −margin` on the check grid). Each trial scales the
    /// coefficients and evaluates the trajectory they stand for, so the
    /// point returned passes [`report`](Self::report) exactly, not only up
    /// to rounding. Returns `s`.
    pub fn fit(&self, p: &mut [f64], s_max: f64) -> Result<f64, ExciteError> {
        let (m, pts) = (self.values(), self.check.len());
        let (mut values, mut allowance) = (vec![0.0; m * pts], vec![0.0; pts]);
        let limit = -self.settings.margin;
        let original = p.to_vec();
        let mut trial = p.to_vec();
        let mut ok = |s: f64, trial: &mut Vec<f64>| -> Result<bool, ExciteError> {
            trial.copy_from_slice(&original);
            self.scale(trial, s);
            let base = self.check_positions(trial);
            self.check_values(&base, 1.0, &mut values, &mut allowance)?;
            Ok((0..m).all(|k| {
                values[k * pts..(k + 1) * pts]
                    .iter()
                    .zip(&allowance)
                    .all(|(v, c)| v + c <= limit)
            }))
        };
        let s = if ok(s_max, &mut trial)? {
            s_max
        } else {
            // The anchor at rest (s = 0) is feasible by construction.
            let (mut lo, mut hi) = (0.0, s_max);
            for _ in 0..50 {
                let mid = 0.5 * (lo + hi);
                if ok(mid, &mut trial)? {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        p.copy_from_slice(&original);
        self.scale(p, s);
        Ok(s)
    }

    /// `X ← X_a + s (X − X_a)` on the decision vector.
    pub fn scale(&self, p: &mut [f64], s: f64) {
        let w = self.check.layout.per_coord();
        for (i, a) in self.anchor.iter().enumerate() {
            let b = &mut p[i * w..(i + 1) * w];
            b[0] = a + s * (b[0] - a);
            b[1..].iter_mut().for_each(|v| *v *= s);
        }
    }

    /// The check of `p` on the check grid.
    pub fn report(&self, p: &[f64]) -> Result<ConstraintCheck, ExciteError> {
        let base = self.check_positions(p);
        let (m, pts) = (self.values(), self.check.len());
        let (mut values, mut allowance) = (vec![0.0; m * pts], vec![0.0; pts]);
        self.check_values(&base, 1.0, &mut values, &mut allowance)?;
        let (idx, worst) =
            values
                .iter()
                .copied()
                .enumerate()
                .fold(
                    (0, f64::NEG_INFINITY),
                    |b, (i, v)| if v > b.1 { (i, v) } else { b },
                );
        let k = idx / pts;
        let estimated_max = values
            .iter()
            .enumerate()
            .map(|(i, v)| v + allowance[i % pts])
            .fold(f64::NEG_INFINITY, f64::max);
        Ok(ConstraintCheck {
            estimated_max,
            worst,
            worst_value: k,
            worst_name: self.constraint.name(k),
            worst_time: self.check.times[idx % pts],
            allowance: allowance.iter().copied().fold(0.0, f64::max),
            points: pts,
            anchor: self.anchor.clone(),
        })
    }
}

/// Errors on a non-finite constraint value or derivative.
fn check_values(x: &[f64], v: &[f64]) -> Result<(), ExciteError> {
    if let Some(bad) = v.iter().find(|v| !v.is_finite()) {
        return Err(ExciteError::Constraint {
            at: x.to_vec(),
            source: format!("the pose constraint returned {bad}; it must be finite").into(),
        });
    }
    Ok(())
}

/// The positions `X(t_j)` of decision vector `p` on `grid`.
fn positions(grid: &Grid, p: &[f64], j: usize, x: &mut [f64]) {
    let w = grid.layout.per_coord();
    let row = grid.row(&grid.pos, j);
    for (i, xi) in x.iter_mut().enumerate() {
        *xi = dot(row, &p[i * w..(i + 1) * w]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Limits;
    use crate::param::Layout;
    use num_dual::DualNum;
    use proptest::prelude::*;

    fn layout() -> Layout {
        Layout {
            harmonics: 4,
            omega_f: std::f64::consts::TAU / 10.0,
            coords: 2,
        }
    }

    /// A disc `(φ − φc)² + (γ − γc)² ≤ r²` and a half-plane `φ + γ ≤ s`.
    fn disc() -> DualConstraint<impl Fn(&[Dual], &mut [Dual]) + Sync> {
        DualConstraint::new(2, 2, |x: &[Dual], g: &mut [Dual]| {
            let (a, b) = (x[0] - 1.5, x[1] - 1.05);
            g[0] = a * a + b * b - 0.3f64.powi(2);
            g[1] = (x[0] + x[1]).sin() - 0.9;
        })
    }

    proptest! {
        // The dual Jacobian matches central differences of the values.
        #[test]
        fn dual_jacobian_matches_differences(x0 in 0.5..2.5f64, x1 in 0.5..1.5f64) {
            let c = disc();
            let (mut g, mut jac) = ([0.0; 2], [0.0; 4]);
            c.jacobian(&[x0, x1], &mut g, &mut jac).unwrap();
            let h = 1e-6;
            for i in 0..2 {
                let (mut xp, mut xm) = ([x0, x1], [x0, x1]);
                xp[i] += h;
                xm[i] -= h;
                let (mut gp, mut gm) = ([0.0; 2], [0.0; 2]);
                c.eval(&xp, &mut gp).unwrap();
                c.eval(&xm, &mut gm).unwrap();
                for k in 0..2 {
                    let fd = (gp[k] - gm[k]) / (2.0 * h);
                    prop_assert!((fd - jac[k * 2 + i]).abs() < 1e-8, "{fd} {}", jac[k * 2 + i]);
                }
            }
            let mut v = [0.0; 2];
            c.eval(&[x0, x1], &mut v).unwrap();
            prop_assert_eq!(v, g);
        }

        // ⟨J_g δp, d⟩ = ⟨δp, J_gᵀ d⟩ by differences of the map along δp.
        #[test]
        fn jacobian_transpose_is_the_adjoint(
            dp in proptest::collection::vec(-1.0..1.0f64, 16),
            d in proptest::collection::vec(-1.0..1.0f64, 2 * 40),
            seed in 0u64..100,
        ) {
            use rand::SeedableRng;
            let cons = GridConstraints::new(layout(), &Limits::paper(), 40);
            let settings = ConstraintSettings { margin: 0.0, ..Default::default() };
            let c = disc();
            let pg = PoseGrid::new(&c, &settings, &cons).unwrap();
            let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(seed);
            let p = crate::design::random_point(&cons, &mut rng);
            let mut jt = vec![0.0; 16];
            pg.add_jacobian_t(&cons.grid, &p, &d, &mut jt).unwrap();
            let h = 1e-6;
            let (mut fp, mut fm) = (vec![0.0; 80], vec![0.0; 80]);
            let pp: Vec<f64> = p.iter().zip(&dp).map(|(a, b)| a + h * b).collect();
            let pm: Vec<f64> = p.iter().zip(&dp).map(|(a, b)| a - h * b).collect();
            pg.map(&cons.grid, &pp, &mut fp).unwrap();
            pg.map(&cons.grid, &pm, &mut fm).unwrap();
            let lhs: f64 = fp.iter().zip(&fm).zip(&d).map(|((a, b), d)| (a - b) / (2.0 * h) * d).sum();
            let rhs = dot(&dp, &jt);
            prop_assert!((lhs - rhs).abs() < 1e-6 * (1.0 + rhs.abs()), "{lhs} {rhs}");
        }

        // The fit ends inside (g + allowance ≤ −margin on the check grid)
        // and keeps the box (the anchor is inside it).
        #[test]
        fn fit_ends_feasible(seed in 0u64..1000, margin in 0.0..0.02f64) {
            use rand::SeedableRng;
            let cons = GridConstraints::new(layout(), &Limits::paper(), 40);
            let settings = ConstraintSettings { margin, ..Default::default() };
            let c = disc();
            let pg = PoseGrid::new(&c, &settings, &cons).unwrap();
            let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(seed);
            let mut p = crate::design::random_point(&cons, &mut rng);
            let s = pg.fit(&mut p, 1.0).unwrap();
            prop_assert!((0.0..=1.0).contains(&s));
            let r = pg.report(&p).unwrap();
            prop_assert!(r.estimated_max <= -margin, "{r:?}");
            prop_assert!(r.worst <= r.estimated_max);
            prop_assert!(cons.violation(&p) < 1e-12);
        }
    }

    #[test]
    fn anchor_is_the_deepest_pose_and_a_bad_one_is_refused() {
        let cons = GridConstraints::new(layout(), &Limits::paper(), 40);
        let settings = ConstraintSettings::default();
        let c = disc();
        let pg = PoseGrid::new(&c, &settings, &cons).unwrap();
        let mut g = [0.0; 2];
        c.eval(&pg.anchor, &mut g).unwrap();
        assert!(g.iter().all(|v| *v < -0.01), "{g:?}");
        let bad = ConstraintSettings {
            anchor: Some(vec![2.4, 1.35]),
            ..Default::default()
        };
        let e = PoseGrid::new(&c, &bad, &cons).err().unwrap().to_string();
        assert!(e.contains("anchor") || e.contains("constraint"), "{e}");
        let nowhere = DualConstraint::new(2, 1, |_x: &[Dual], g: &mut [Dual]| {
            g[0] = Dual::from_re(1.0);
        });
        let e = PoseGrid::new(&nowhere, &settings, &cons).err().unwrap();
        assert!(matches!(e, ExciteError::ConstraintInfeasible { .. }), "{e}");
        let wrong = DualConstraint::new(3, 1, |x: &[Dual], g: &mut [Dual]| g[0] = x[0]);
        assert!(PoseGrid::new(&wrong, &settings, &cons).is_err());
        let nan = DualConstraint::new(2, 1, |x: &[Dual], g: &mut [Dual]| {
            g[0] = x[0].sqrt() * f64::NAN
        });
        assert!(matches!(
            PoseGrid::new(&nan, &settings, &cons).err().unwrap(),
            ExciteError::Constraint { .. }
        ));
    }

    #[test]
    fn settings_round_trip_and_are_validated() {
        let s = ConstraintSettings {
            margin: 0.01,
            check_factor: 4,
            anchor: Some(vec![1.0, 0.9]),
        };
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(
            serde_json::from_str::<ConstraintSettings>(&json).unwrap(),
            s
        );
        assert_eq!(
            serde_json::from_str::<ConstraintSettings>("{}").unwrap(),
            ConstraintSettings::default()
        );
        assert!(serde_json::from_str::<ConstraintSettings>(r#"{"margn": 1}"#).is_err());
        for bad in [
            ConstraintSettings {
                margin: -1.0,
                ..Default::default()
            },
            ConstraintSettings {
                check_factor: 0,
                ..Default::default()
            },
            ConstraintSettings {
                anchor: Some(vec![f64::NAN]),
                ..Default::default()
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }
}
