//! Design criteria on the stacked base regressor and their exact gradients.
//!
//! Along a trajectory sampled at `t_1 … t_N` the regressor rows stack into
//! `W` (`mN × n` for `m` actuators, actuator-major: rows `0..N` actuator 1,
//! `N..2N` actuator 2, …),
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
use nalgebra::DMatrix;

use aras_ident::BaseParameters;

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

/// Dual directions per evaluation of the rows: [`crate::Dual`]'s six. A
/// model of `n` coordinates has `3n` inputs `(X, Ẋ, Ẍ)`, differentiated in
/// `⌈3n/6⌉` passes (one for ARAS-Diamond's `φ, γ, φ̇, γ̇, φ̈, γ̈`).
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
        if n == 0 {
            return Err(ExciteError::InvalidSetting {
                name: "regressor",
                value: 0.0,
                reason: format!(
                    "the model has no {what}; the Fourier design moves at least one \
                     coordinate driven by at least one actuator"
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
    clamp: Option<(Vec<f64>, Vec<f64>)>,
    samples: usize,
    /// Coordinates `n` and outputs `m` of the model.
    coords: usize,
    outputs: usize,
    w: Mat<f64>,
    /// `∂W/∂z_k` for the `3n` inputs `z = (X, Ẋ, Ẍ)`.
    dw: Vec<Mat<f64>>,
    rows: Vec<f64>,
    drows: Vec<D6>,
    /// One sample's `[X, Ẋ, Ẍ]` and its dual seeds.
    state: Vec<f64>,
    seeds: Vec<D6>,
    clamped: Vec<bool>,
    /// Per sample `s` and input `k`, `⟨∂c/∂W, ∂W/∂z_k⟩` at `3n·s + k`.
    pub contraction: Vec<f64>,
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
        clamp: Option<(Vec<f64>, Vec<f64>)>,
    ) -> Self {
        let n = reg.columns();
        let (coords, outputs) = (reg.coordinates(), reg.outputs());
        Self {
            reg,
            criterion,
            e: Mat::from_fn(e.nrows(), e.ncols(), |i, j| e[(i, j)]),
            clamp,
            samples,
            coords,
            outputs,
            w: Mat::zeros(outputs * samples, n),
            dw: (0..3 * coords)
                .map(|_| Mat::zeros(outputs * samples, n))
                .collect(),
            rows: vec![0.0; outputs * n],
            drows: vec![D6::from_re(0.0); outputs * n],
            state: vec![0.0; 3 * coords],
            seeds: vec![D6::from_re(0.0); 3 * coords],
            clamped: vec![false; coords],
            contraction: vec![0.0; 3 * coords * samples],
        }
    }

    /// Clamps the positions of `self.state` into the box, noting which
    /// were moved.
    fn clamp_state(&mut self) {
        let n = self.coords;
        match &self.clamp {
            None => self.clamped.fill(false),
            Some((lo, hi)) => {
                for i in 0..n {
                    let x = self.state[i];
                    let c = x.clamp(lo[i], hi[i]);
                    self.state[i] = c;
                    self.clamped[i] = c != x;
                }
            }
        }
    }

    fn fail(x: &[f64], e: impl std::error::Error + Send + Sync + 'static) -> ExciteError {
        ExciteError::Regressor {
            at: x.to_vec(),
            source: Box::new(e),
        }
    }

    /// Fills `W` (values only) from the states of every sample:
    /// `state(s, out)` writes sample `s`'s `[X, Ẋ, Ẍ]` (`3n` entries).
    pub fn fill_values(&mut self, state: impl Fn(usize, &mut [f64])) -> Result<(), ExciteError> {
        // Start the scalar loop clean whatever ran on this thread before
        // (see `aras_ident::simd`).
        aras_ident::simd::clear_upper_state();
        let (n, m, ns, dims) = (self.w.ncols(), self.outputs, self.samples, self.coords);
        for s in 0..ns {
            state(s, &mut self.state);
            self.clamp_state();
            let (x, rest) = self.state.split_at(dims);
            let (xd, xdd) = rest.split_at(dims);
            self.rows.iter_mut().for_each(|v| *v = 0.0);
            self.reg
                .fill(x, xd, xdd, &mut self.rows)
                .map_err(|e| Self::fail(x, e))?;
            for r in 0..m {
                for c in 0..n {
                    self.w[(r * ns + s, c)] = self.rows[m * c + r];
                }
            }
        }
        Ok(())
    }

    /// Fills `W` and its derivatives `∂W/∂z_k` by dual numbers, six
    /// inputs per evaluation of the rows.
    pub fn fill_derivatives(
        &mut self,
        state: impl Fn(usize, &mut [f64]),
    ) -> Result<(), ExciteError> {
        // Start the scalar loop clean whatever ran on this thread before
        // (see `aras_ident::simd`).
        aras_ident::simd::clear_upper_state();
        let (n, m, ns, dims) = (self.w.ncols(), self.outputs, self.samples, self.coords);
        let inputs = 3 * dims;
        for s in 0..ns {
            state(s, &mut self.state);
            self.clamp_state();
            for first in (0..inputs).step_by(DIRS) {
                for (k, (d, &v)) in self.seeds.iter_mut().zip(&self.state).enumerate() {
                    let fixed = k < dims && self.clamped[k];
                    let slot = k.wrapping_sub(first);
                    *d = if slot < DIRS && !fixed {
                        D6::from_re(v).derivative(slot)
                    } else {
                        D6::from_re(v)
                    };
                }
                let (x, rest) = self.seeds.split_at(dims);
                let (xd, xdd) = rest.split_at(dims);
                self.drows.iter_mut().for_each(|v| *v = D6::from_re(0.0));
                self.reg
                    .fill_dual(x, xd, xdd, &mut self.drows)
                    .map_err(|e| Self::fail(&self.state[..dims], e))?;
                let block = first..(first + DIRS).min(inputs);
                for r in 0..m {
                    for c in 0..n {
                        let d = &self.drows[m * c + r];
                        let row = r * ns + s;
                        self.w[(row, c)] = d.re;
                        match &d.eps.0 {
                            Some(g) => {
                                for k in block.clone() {
                                    self.dw[k][(row, c)] = g[k - first];
                                }
                            }
                            None => {
                                for k in block.clone() {
                                    self.dw[k][(row, c)] = 0.0;
                                }
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
            let inputs = self.dw.len();
            for s in 0..ns {
                for (k, dk) in self.dw.iter().enumerate() {
                    let mut sum = 0.0;
                    for r in 0..self.outputs {
                        let row = r * ns + s;
                        for c in 0..n {
                            sum += a[(row, c)] * dk[(row, c)];
                        }
                    }
                    self.contraction[inputs * s + k] = sum;
                }
            }
        }
        Ok(Analysis {
            objective,
            assessment,
        })
    }

    /// Objective at a decision vector on `grid` (values only).
    pub fn objective(&mut self, grid: &Grid, p: &[f64]) -> Result<Analysis, ExciteError> {
        self.fill_values(|s, out| grid.state(p, s, out))?;
        self.analyse(false)
    }

    /// Objective and its exact gradient with respect to the decision vector.
    pub fn gradient(
        &mut self,
        grid: &Grid,
        p: &[f64],
        grad: &mut [f64],
    ) -> Result<Analysis, ExciteError> {
        self.fill_derivatives(|s, out| grid.state(p, s, out))?;
        let out = self.analyse(true)?;
        let w = grid.layout.per_coord();
        let n = self.coords;
        grad.iter_mut().for_each(|v| *v = 0.0);
        for (s, c) in self.contraction.chunks_exact(3 * n).enumerate() {
            let (pos, vel, acc) = (
                grid.row(&grid.pos, s),
                grid.row(&grid.vel, s),
                grid.row(&grid.acc, s),
            );
            for i in 0..n {
                let g = &mut grad[i * w..(i + 1) * w];
                for m in 0..w {
                    g[m] += c[i] * pos[m] + c[n + i] * vel[m] + c[2 * n + i] * acc[m];
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
            coords: 2,
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

    /// The exact gradient at `p` against central differences of the
    /// objective (bound: see the test below).
    fn check_gradient<R: Regressor>(
        ev: &mut Evaluator<'_, R>,
        grid: &Grid,
        p: &[f64],
        label: &str,
    ) {
        let mut g = vec![0.0; p.len()];
        let f0 = ev.gradient(grid, p, &mut g).unwrap().objective;
        let f0v = ev.objective(grid, p).unwrap().objective;
        assert!((f0 - f0v).abs() < 1e-12 * f0.abs().max(1.0));
        let scale = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for k in 0..p.len() {
            let h = 1e-6;
            let mut pp = p.to_vec();
            pp[k] += h;
            let fp = ev.objective(grid, &pp).unwrap().objective;
            pp[k] -= 2.0 * h;
            let fm = ev.objective(grid, &pp).unwrap().objective;
            let fd = (fp - fm) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() < 1e-6 * scale.max(1.0),
                "{label} k={k}: exact {} vs FD {fd}",
                g[k]
            );
        }
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
            let (_, grid, cons) = setup(l);
            let p = interior_point(&cons, seed);
            let box_ = Limits::paper();
            let clamp = (box_.min.as_slice().to_vec(), box_.max.as_slice().to_vec());
            let mut ev = Evaluator::new(&reg, &e, criterion, grid.len(), Some(clamp));
            check_gradient(&mut ev, &grid, &p, &format!("{criterion:?} L={l}"));
        }
    }

    /// A smooth toy model of three coordinates and three outputs, 8
    /// independent columns, in any number type.
    struct Three;

    impl Three {
        fn rows<T: num_dual::DualNum<Primitive = f64> + Copy>(
            x: &[T],
            xd: &[T],
            xdd: &[T],
            y: &mut [T],
        ) {
            let z = T::from(0.0);
            let cols = [
                [xdd[0], z, z],
                [x[0].sin(), z, z],
                [z, xdd[1] + xdd[0], z],
                [
                    x[1].cos() * xdd[0],
                    x[1].cos() * xdd[0] + x[1].sin() * xd[0] * xd[0],
                    z,
                ],
                [z, (x[0] + x[1]).sin(), z],
                [z, z, xdd[2] + x[0] * xd[1]],
                [x[2].sin() * xdd[1], z, x[2].cos() * xd[0] * xd[1]],
                [xd[0], xd[1] * x[2], xd[2]],
            ];
            for (c, col) in cols.iter().enumerate() {
                y[3 * c..3 * c + 3].copy_from_slice(col);
            }
        }
    }

    impl LinearModel for Three {
        type Error = std::convert::Infallible;
        fn coordinates(&self) -> usize {
            3
        }
        fn outputs(&self) -> usize {
            3
        }
        fn names(&self) -> Vec<String> {
            (0..8).map(|c| format!("c{c}")).collect()
        }
        fn fill(
            &self,
            q: &[f64],
            qd: &[f64],
            qdd: &[f64],
            y: &mut [f64],
        ) -> Result<(), Self::Error> {
            Self::rows(q, qd, qdd, y);
            Ok(())
        }
    }

    impl Regressor for Three {
        fn fill_dual(
            &self,
            q: &[Dual],
            qd: &[Dual],
            qdd: &[Dual],
            y: &mut [Dual],
        ) -> Result<(), Self::Error> {
            Self::rows(q, qd, qdd, y);
            Ok(())
        }
    }

    /// With three coordinates the nine inputs are differentiated in two
    /// passes of six: the exact gradient still matches central
    /// differences (bound as for two coordinates).
    #[test]
    fn gradients_of_three_coordinates_match_finite_differences() {
        let e = DMatrix::<f64>::identity(8, 8);
        let limits = Limits::<nalgebra::Dyn> {
            min: nalgebra::DVector::from_vec(vec![-0.8, -0.6, -1.0]),
            max: nalgebra::DVector::from_vec(vec![0.9, 0.7, 0.8]),
            max_rate: nalgebra::DVector::from_element(3, 2.0),
            max_accel: nalgebra::DVector::from_element(3, 8.0),
        };
        for (criterion, seed) in [(Criterion::Condition, 5), (Criterion::DOptimal, 6)] {
            let layout = Layout {
                harmonics: 3,
                omega_f: std::f64::consts::TAU / 5.0,
                coords: 3,
            };
            let cons = GridConstraints::new(layout, &limits, 200);
            let grid = Grid::new(layout, 40, 0.5);
            let p = interior_point(&cons, seed);
            let mut ev = Evaluator::new(&Three, &e, criterion, grid.len(), None);
            check_gradient(&mut ev, &grid, &p, &format!("{criterion:?}, 3 coordinates"));
        }
    }

    /// A wrong-shaped or non-finite projection, or a model with no
    /// coordinates or no outputs, is rejected by name.
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
        /// The stand-in claiming no coordinates.
        struct ThreeDof(StandIn);
        impl LinearModel for ThreeDof {
            type Error = <StandIn as LinearModel>::Error;
            fn coordinates(&self) -> usize {
                0
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
        assert!(m.contains("no coordinates"), "{m}");
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
