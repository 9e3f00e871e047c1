//! Design criteria on the stacked base regressor and their exact gradients.
//!
//! Along a trajectory sampled at `t_1 … t_N` the regressor rows stack into
//! `W` (`2N × n`, actuator-major: rows `0..N` actuator 1, `N..2N` actuator 2),
//! and the base regressor is `W_b = W E` for a base projection `E` (`n × b`,
//! (59)–(61), `docs/model.md`).
//!
//! * [`Criterion::Condition`]: the condition number `κ = σ_max/σ_min` of the
//!   column-scaled `W_s = W_b D`, `D = diag(1/‖W_b e_j‖)` (`docs/excitation.md`). Scaling
//!   makes `κ` independent of parameter units. The optimiser minimises
//!   `ln κ` (same minimiser, better scaled); its gradient follows from
//!   `dσ_i = u_iᵀ dW_s v_i`, including the derivative of the scaling:
//!   `dσ_i = Σ_j (v_ij u_i/‖w_j‖ − σ_i v_ij² w_j/‖w_j‖²)ᵀ dw_j`.
//! * [`Criterion::DOptimal`]: `−ln det(W_bᵀ W_b / N)`, minus the log-volume
//!   of the information matrix (unscaled: the minimiser does not depend on
//!   parameter units since scaling a column only adds a constant), gradient
//!   `−2 U Σ⁻¹ Vᵀ`.
//!
//! The adjoint `G = ∂c/∂W_b` is pulled back to the full regressor (`G Eᵀ`),
//! contracted per sample with the dual-number derivatives `∂Y/∂(X, Ẋ, Ẍ)`,
//! and chained through the linear maps from the decision vector.

use faer::Mat;
use nalgebra::{DMatrix, Vector2};

use aras_ident::BaseParameters;

use crate::Motion;
use crate::error::ExciteError;
use crate::param::Grid;
use crate::regressor::Regressor;

/// What the design minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Criterion {
    /// Condition number of the column-scaled base regressor (`docs/excitation.md`).
    #[default]
    Condition,
    /// D-optimality: `−ln det` of the (per-sample) information matrix
    /// `W_bᵀ W_b / N`.
    DOptimal,
}

/// Quality figures of the stacked base regressor along one trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct Assessment {
    /// Condition number of the column-scaled base regressor.
    pub condition_number: f64,
    /// `−ln det(W_bᵀ W_b / N)` (unscaled base regressor).
    pub d_criterion: f64,
    /// Singular values of the column-scaled base regressor, largest first.
    pub scaled_singular_values: Vec<f64>,
    /// Number of samples `N` the regressor was stacked on.
    pub samples: usize,
}

impl Assessment {
    /// The value of `criterion` (κ itself for [`Criterion::Condition`]).
    pub fn value(&self, criterion: Criterion) -> f64 {
        match criterion {
            Criterion::Condition => self.condition_number,
            Criterion::DOptimal => self.d_criterion,
        }
    }
}

/// Number of dual directions: `(φ, γ, φ̇, γ̇, φ̈, γ̈)`.
const DIRS: usize = 6;
type D6 = crate::regressor::Dual;

/// The base projection `E` (`n × b`, `W_b = W E`: column `j` selects the
/// standard column of base parameter `j`) of a base-parameter analysis, as
/// the dense matrix [`design`](crate::design) and [`assess`](crate::assess)
/// take.
pub fn base_projection(base: &BaseParameters) -> DMatrix<f64> {
    let mut e = DMatrix::zeros(base.n_standard(), base.n_base());
    for (j, &c) in base.independent().iter().enumerate() {
        e[(c, j)] = 1.0;
    }
    e
}

/// Checks the shape of a base projection against a regressor.
pub(crate) fn check_projection<R: Regressor>(
    e: &DMatrix<f64>,
    regressor: &R,
) -> Result<(), ExciteError> {
    for (what, n) in [
        ("coordinates", regressor.coordinates()),
        ("outputs", regressor.outputs()),
    ] {
        if n != 2 {
            return Err(ExciteError::InvalidSetting {
                name: "regressor",
                value: n as f64,
                reason: format!(
                    "the model has {n} {what}; the Fourier design moves two coordinates \
                     driven by two actuators"
                ),
            });
        }
    }
    let columns = regressor.columns();
    if e.nrows() != columns || e.ncols() == 0 {
        return Err(ExciteError::ProjectionShape {
            rows: e.nrows(),
            cols: e.ncols(),
            columns,
        });
    }
    for (k, v) in e.iter().enumerate() {
        crate::error::check_finite(|| format!("E[{}, {}]", k % e.nrows(), k / e.nrows()), *v)?;
    }
    Ok(())
}

/// Buffers for evaluating a criterion on one grid (one per optimiser run;
/// nothing is allocated per sample).
pub(crate) struct Evaluator<'a, R: Regressor> {
    reg: &'a R,
    criterion: Criterion,
    e: Mat<f64>,
    /// Poses are clamped into this box before evaluation (the optimiser's
    /// intermediate iterates may leave it; inside it everything is exact).
    clamp: Option<(Vector2<f64>, Vector2<f64>)>,
    samples: usize,
    w: Mat<f64>,
    dw: Vec<Mat<f64>>,
    rows: Vec<f64>,
    drows: Vec<D6>,
    /// Per sample and direction, `⟨∂c/∂W, ∂W/∂z_k⟩`.
    pub contraction: Vec<[f64; DIRS]>,
}

/// The outcome of one analysis of `W_b`.
pub(crate) struct Analysis {
    /// The optimiser's objective (ln κ, or −ln det).
    pub objective: f64,
    pub assessment: Assessment,
}

impl<'a, R: Regressor> Evaluator<'a, R> {
    pub fn new(
        reg: &'a R,
        e: &DMatrix<f64>,
        criterion: Criterion,
        samples: usize,
        clamp: Option<(Vector2<f64>, Vector2<f64>)>,
    ) -> Self {
        let n = reg.columns();
        Self {
            reg,
            criterion,
            e: Mat::from_fn(e.nrows(), e.ncols(), |i, j| e[(i, j)]),
            clamp,
            samples,
            w: Mat::zeros(2 * samples, n),
            dw: (0..DIRS).map(|_| Mat::zeros(2 * samples, n)).collect(),
            rows: vec![0.0; 2 * n],
            drows: vec![D6::from_re(0.0); 2 * n],
            contraction: vec![[0.0; DIRS]; samples],
        }
    }

    fn clamped(&self, x: Vector2<f64>) -> (Vector2<f64>, [bool; 2]) {
        match self.clamp {
            None => (x, [false; 2]),
            Some((lo, hi)) => {
                let c = Vector2::new(x[0].clamp(lo[0], hi[0]), x[1].clamp(lo[1], hi[1]));
                (c, [c[0] != x[0], c[1] != x[1]])
            }
        }
    }

    fn fail(x: &Vector2<f64>, e: impl std::error::Error + Send + Sync + 'static) -> ExciteError {
        ExciteError::Regressor {
            at: [x[0], x[1]],
            source: Box::new(e),
        }
    }

    /// Fills `W` (values only) from the states of every sample.
    pub fn fill_values(&mut self, state: impl Fn(usize) -> Motion) -> Result<(), ExciteError> {
        // Start the scalar loop clean whatever ran on this thread before
        // (see `aras_ident::simd`).
        aras_ident::simd::clear_upper_state();
        let n = self.w.ncols();
        let ns = self.samples;
        for s in 0..ns {
            let Motion {
                pos: x,
                vel: xd,
                acc: xdd,
            } = state(s);
            let (x, _) = self.clamped(x);
            self.rows.iter_mut().for_each(|v| *v = 0.0);
            self.reg
                .fill(x.as_slice(), xd.as_slice(), xdd.as_slice(), &mut self.rows)
                .map_err(|e| Self::fail(&x, e))?;
            for r in 0..2 {
                for c in 0..n {
                    self.w[(r * ns + s, c)] = self.rows[2 * c + r];
                }
            }
        }
        Ok(())
    }

    /// Fills `W` and its derivatives `∂W/∂z_k` by dual numbers.
    pub fn fill_derivatives(&mut self, state: impl Fn(usize) -> Motion) -> Result<(), ExciteError> {
        // Start the scalar loop clean whatever ran on this thread before
        // (see `aras_ident::simd`).
        aras_ident::simd::clear_upper_state();
        let n = self.w.ncols();
        let ns = self.samples;
        for s in 0..ns {
            let Motion {
                pos: x,
                vel: xd,
                acc: xdd,
            } = state(s);
            let (x, clamped) = self.clamped(x);
            let seed = |v: f64, k: usize, fixed: bool| {
                let d = D6::from_re(v);
                if fixed { d } else { d.derivative(k) }
            };
            let xs = [seed(x[0], 0, clamped[0]), seed(x[1], 1, clamped[1])];
            let xds = [seed(xd[0], 2, false), seed(xd[1], 3, false)];
            let xdds = [seed(xdd[0], 4, false), seed(xdd[1], 5, false)];
            self.drows.iter_mut().for_each(|v| *v = D6::from_re(0.0));
            self.reg
                .fill_dual(&xs, &xds, &xdds, &mut self.drows)
                .map_err(|e| Self::fail(&x, e))?;
            for r in 0..2 {
                for c in 0..n {
                    let d = &self.drows[2 * c + r];
                    let row = r * ns + s;
                    self.w[(row, c)] = d.re;
                    match &d.eps.0 {
                        Some(g) => {
                            for k in 0..DIRS {
                                self.dw[k][(row, c)] = g[k];
                            }
                        }
                        None => {
                            for k in 0..DIRS {
                                self.dw[k][(row, c)] = 0.0;
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Analyses the current `W`; with `adjoint`, also fills
    /// [`contraction`](Self::contraction) (needs [`fill_derivatives`](Self::fill_derivatives)).
    pub fn analyse(&mut self, adjoint: bool) -> Result<Analysis, ExciteError> {
        let wb = aras_ident::linalg::product(self.w.as_ref(), self.e.as_ref());
        let b = wb.ncols();
        let ns = self.samples;
        let norms: Vec<f64> = (0..b).map(|j| wb.col(j).norm_l2()).collect();
        let degenerate = |reason: String| ExciteError::Degenerate { reason };
        if let Some(j) = norms
            .iter()
            .position(|v| v.is_nan() || *v <= 0.0 || !v.is_finite())
        {
            return Err(degenerate(format!(
                "base column {j} is zero (or not finite) along the trajectory: the motion does \
                 not excite it"
            )));
        }
        let ws = Mat::from_fn(wb.nrows(), b, |i, j| wb[(i, j)] / norms[j]);
        // Through aras-ident's faer facade, which leaves the vector unit
        // clean for the scalar code after it (the contraction below, the
        // next iteration's dual-number kinematics).
        let svd_s = aras_ident::linalg::thin_svd(ws.as_ref())
            .map_err(|e| degenerate(format!("SVD failed: {e}")))?;
        let svd_b = aras_ident::linalg::thin_svd(wb.as_ref())
            .map_err(|e| degenerate(format!("SVD failed: {e}")))?;
        let ss: Vec<f64> = svd_s.s.clone();
        let sb: Vec<f64> = svd_b.s.clone();
        let (smax, smin) = (ss[0], ss[b - 1]);
        let kappa = smax / smin;
        let logdet: f64 = sb.iter().map(|s| (s * s / ns as f64).ln()).sum();
        if !kappa.is_finite() || !logdet.is_finite() || smin.is_nan() || smin <= 0.0 {
            return Err(degenerate(format!(
                "the base regressor is rank-deficient along the trajectory (σ_min = {smin:.3e}): \
                 some base parameter is not excited"
            )));
        }
        let assessment = Assessment {
            condition_number: kappa,
            d_criterion: -logdet,
            scaled_singular_values: ss.clone(),
            samples: ns,
        };
        let objective = match self.criterion {
            Criterion::Condition => kappa.ln(),
            Criterion::DOptimal => -logdet,
        };
        if adjoint {
            let g = match self.criterion {
                Criterion::Condition => {
                    let (u, v) = (&svd_s.u, &svd_s.v);
                    let mut g = Mat::<f64>::zeros(wb.nrows(), b);
                    for (idx, scale) in [(0, 1.0 / smax), (b - 1, -1.0 / smin)] {
                        let sigma = ss[idx];
                        for j in 0..b {
                            let vij = v[(j, idx)];
                            let a = scale * vij / norms[j];
                            let c = scale * sigma * vij * vij / (norms[j] * norms[j]);
                            for r in 0..wb.nrows() {
                                g[(r, j)] += a * u[(r, idx)] - c * wb[(r, j)];
                            }
                        }
                    }
                    g
                }
                Criterion::DOptimal => {
                    let (u, v) = (&svd_b.u, &svd_b.v);
                    let scaled = Mat::from_fn(u.nrows(), b, |r, i| -2.0 * u[(r, i)] / sb[i]);
                    aras_ident::linalg::product(scaled.as_ref(), v.transpose())
                }
            };
            let a = aras_ident::linalg::product(g.as_ref(), self.e.transpose());
            let n = a.ncols();
            for s in 0..ns {
                let mut acc = [0.0; DIRS];
                for (k, dk) in self.dw.iter().enumerate() {
                    let mut sum = 0.0;
                    for r in 0..2 {
                        let row = r * ns + s;
                        for c in 0..n {
                            sum += a[(row, c)] * dk[(row, c)];
                        }
                    }
                    acc[k] = sum;
                }
                self.contraction[s] = acc;
            }
        }
        Ok(Analysis {
            objective,
            assessment,
        })
    }

    /// Objective at a decision vector on `grid` (values only).
    pub fn objective(&mut self, grid: &Grid, p: &[f64]) -> Result<Analysis, ExciteError> {
        self.fill_values(|s| grid.state(p, s))?;
        self.analyse(false)
    }

    /// Objective and its exact gradient with respect to the decision vector.
    pub fn gradient(
        &mut self,
        grid: &Grid,
        p: &[f64],
        grad: &mut [f64],
    ) -> Result<Analysis, ExciteError> {
        self.fill_derivatives(|s| grid.state(p, s))?;
        let out = self.analyse(true)?;
        let w = grid.layout.per_coord();
        grad.iter_mut().for_each(|v| *v = 0.0);
        for (s, c) in self.contraction.iter().enumerate() {
            let (pos, vel, acc) = (
                grid.row(&grid.pos, s),
                grid.row(&grid.vel, s),
                grid.row(&grid.acc, s),
            );
            for i in 0..2 {
                let g = &mut grad[i * w..(i + 1) * w];
                for m in 0..w {
                    g[m] += c[i] * pos[m] + c[2 + i] * vel[m] + c[4 + i] * acc[m];
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Dual;
    use crate::constraints::{GridConstraints, Limits};
    use crate::param::Layout;
    use crate::test_support::{StandIn, base_projection};
    use aras_ident::LinearModel;
    use rand::SeedableRng;
    use rand::rngs::Xoshiro256PlusPlus;

    fn setup(l: usize) -> (Layout, Grid, GridConstraints) {
        let layout = Layout {
            harmonics: l,
            omega_f: std::f64::consts::TAU / 10.0,
        };
        let cons = GridConstraints::new(layout, &Limits::paper(), 200);
        (layout, Grid::new(layout, 60, 0.5), cons)
    }

    fn interior_point(cons: &GridConstraints, seed: u64) -> Vec<f64> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let w = cons.grid.layout.per_coord();
        let mut p = crate::design::random_point(cons, &mut rng);
        // Shrink to 80 % so finite-difference steps never reach the clamp.
        for (k, v) in p.iter_mut().enumerate() {
            if k % w != 0 {
                *v *= 0.8;
            }
        }
        p
    }

    /// The projection finds the stand-in's 10 independent columns and
    /// `W E` has full rank on fresh data.
    #[test]
    fn stand_in_base_projection_has_rank_10() {
        let reg = StandIn::default();
        let e = base_projection(&reg, 300, 7);
        assert_eq!((e.nrows(), e.ncols()), (12, 10));
        let (_, grid, cons) = setup(5);
        let p = interior_point(&cons, 3);
        let mut ev = Evaluator::new(&reg, &e, Criterion::Condition, grid.len(), None);
        let a = ev.objective(&grid, &p).unwrap().assessment;
        assert!(a.condition_number.is_finite() && a.condition_number > 1.0);
    }

    /// Exact gradients agree with central differences. Step 1e-6 on
    /// coefficients of order 0.1–1: truncation ~h²·|c'''| ≈ 1e-11, rounding
    /// ~1e-16·|c|/h ≈ 1e-9 (the SVD is accurate to ~1e-15 relative), so a
    /// 1e-6 bound relative to the largest gradient entry is tight yet robust
    /// (dropping the column-scaling term of the gradient fails it by 3e-3).
    #[test]
    fn gradients_match_finite_differences() {
        let reg = StandIn::default();
        let e = base_projection(&reg, 300, 7);
        for (criterion, l, seed) in [
            (Criterion::Condition, 5, 1),
            (Criterion::Condition, 2, 2),
            (Criterion::DOptimal, 5, 3),
            (Criterion::DOptimal, 1, 4),
        ] {
            let (layout, grid, cons) = setup(l);
            let p = interior_point(&cons, seed);
            let box_ = Limits::paper();
            let mut ev =
                Evaluator::new(&reg, &e, criterion, grid.len(), Some((box_.min, box_.max)));
            let mut g = vec![0.0; layout.dim()];
            let f0 = ev.gradient(&grid, &p, &mut g).unwrap().objective;
            let f0v = ev.objective(&grid, &p).unwrap().objective;
            assert!((f0 - f0v).abs() < 1e-12 * f0.abs().max(1.0));
            let scale = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..p.len() {
                let h = 1e-6;
                let mut pp = p.clone();
                pp[k] += h;
                let fp = ev.objective(&grid, &pp).unwrap().objective;
                pp[k] -= 2.0 * h;
                let fm = ev.objective(&grid, &pp).unwrap().objective;
                let fd = (fp - fm) / (2.0 * h);
                assert!(
                    (fd - g[k]).abs() < 1e-6 * scale.max(1.0),
                    "{criterion:?} L={l} k={k}: exact {} vs FD {fd}",
                    g[k]
                );
            }
        }
    }

    /// A wrong-shaped or non-finite projection, or a model that is not
    /// 2-DOF, is rejected by name.
    #[test]
    fn projection_is_checked() {
        let reg = StandIn::default();
        let e = DMatrix::<f64>::zeros(11, 3);
        assert!(
            check_projection(&e, &reg)
                .unwrap_err()
                .to_string()
                .contains("11×3")
        );
        let mut e = DMatrix::<f64>::zeros(12, 3);
        e[(2, 1)] = f64::NAN;
        assert!(
            check_projection(&e, &reg)
                .unwrap_err()
                .to_string()
                .contains("E[2, 1]")
        );
        /// The stand-in claiming a third coordinate.
        struct ThreeDof(StandIn);
        impl LinearModel for ThreeDof {
            type Error = <StandIn as LinearModel>::Error;
            fn coordinates(&self) -> usize {
                3
            }
            fn outputs(&self) -> usize {
                2
            }
            fn names(&self) -> Vec<String> {
                self.0.names()
            }
            fn fill(
                &self,
                q: &[f64],
                q_dot: &[f64],
                q_ddot: &[f64],
                rows: &mut [f64],
            ) -> Result<(), Self::Error> {
                self.0.fill(q, q_dot, q_ddot, rows)
            }
        }
        impl Regressor for ThreeDof {
            fn fill_dual(
                &self,
                q: &[Dual],
                q_dot: &[Dual],
                q_ddot: &[Dual],
                rows: &mut [Dual],
            ) -> Result<(), Self::Error> {
                self.0.fill_dual(q, q_dot, q_ddot, rows)
            }
        }
        let e = DMatrix::<f64>::zeros(12, 3);
        let m = check_projection(&e, &ThreeDof(StandIn::default()))
            .unwrap_err()
            .to_string();
        assert!(m.contains("3 coordinates"), "{m}");
    }

    /// Motionless trajectories cannot excite anything: a clear error.
    #[test]
    fn no_motion_is_degenerate() {
        let reg = StandIn::default();
        let e = base_projection(&reg, 300, 7);
        let (_, grid, _) = setup(5);
        let mut p = vec![0.0; 20];
        p[0] = 1.5;
        p[10] = 1.0;
        let mut ev = Evaluator::new(&reg, &e, Criterion::Condition, grid.len(), None);
        let err = ev.objective(&grid, &p).err().unwrap().to_string();
        assert!(err.contains("degenerate"), "{err}");
    }
}
