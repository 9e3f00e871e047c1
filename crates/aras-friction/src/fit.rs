//! Fitting friction models to a log by variable projection.
//!
//! Every model is `τ ≈ Φ(θ) β` ([`Separable`]). For fixed structural
//! parameters `θ` the best coefficients `β` follow from bounded linear least
//! squares (QR, with an active set for the physical bounds such as
//! `F_c ≥ 0`); the outer problem `min_θ ‖τ − Φ(θ) β*(θ)‖²` has only one to
//! four unknowns. It is solved by Levenberg–Marquardt in `ln θ` (all
//! structural parameters are positive scales) with projection onto the
//! physical box, started from the best few points of a coarse grid over the
//! data's own ranges (several starts against local minima).
//!
//! Uncertainty: `σ` of every physical parameter from the Jacobian of the
//! prediction at the optimum, `cov = s² (JᵀJ)⁻¹` with `s² = RSS/(n − p)`. It
//! assumes independent residuals; correlated residuals (unmodelled effects,
//! filtered signals) make the true uncertainty larger.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{
    CoulombViscous, Dahl, FrictionError, LuGre, ParamInfo, Separable, Stribeck, Track,
    linalg::{Qr, bounded_lstsq},
    models::MaxwellSlip,
};

/// Fitting settings (defaults in [`FitSettings::default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FitSettings {
    /// Number of local searches, started from the best points of the start
    /// grid.
    pub starts: usize,
    /// Iteration limit of each local search.
    pub max_iterations: usize,
    /// Fixed Stribeck shape exponent `δ` for the Stribeck and LuGre models;
    /// `None` fits it.
    pub shape: Option<f64>,
    /// Logs with more samples are searched coarse-to-fine (see
    /// [`Problem::solve`]); 0 disables it. 3000 samples keep the coarse
    /// steps within about 0.1 s on 1–16 ms logs.
    pub coarse_rows: usize,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self {
            starts: 3,
            max_iterations: 80,
            shape: None,
            coarse_rows: 3000,
        }
    }
}

/// How a local search ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitStatus {
    /// The cost stopped decreasing (relative change below 1e-8), the step
    /// became smaller than 1e-7 relative, or the model is linear.
    Converged,
    /// The iteration limit was reached first.
    IterationLimit,
}

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// Parameter name.
    pub name: String,
    /// SI unit.
    pub unit: String,
    /// Fitted value.
    pub value: f64,
    /// Standard deviation from the Jacobian; `None` when the data do not
    /// determine the parameter (dependent Jacobian columns).
    pub sigma: Option<f64>,
    /// True when the value sits on its physical bound.
    pub at_bound: bool,
    /// True when the parameter was held fixed (not fitted).
    pub fixed: bool,
}

/// Fit quality on one log.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Number of samples.
    pub rows: usize,
    /// Root mean square of `τ − τ̂`, N·m.
    pub rms: f64,
    /// Fitness (78) in percent, `100 (1 − ‖τ − τ̂‖ / ‖τ − mean τ‖)`; `None`
    /// for a constant torque.
    pub fitness: Option<f64>,
}

/// Fitness (78), `100 (1 − ‖τ − τ̂‖ / ‖τ − mean(τ)‖)`: the identification's
/// own ([`aras_ident::validate::fitness`]), so a friction model and a
/// rigid-body model are scored alike. [`Metrics::fitness`] holds it as an
/// `Option`: `None` where it is an error (lengths that differ, an empty,
/// constant or non-finite input).
pub use aras_ident::validate::fitness;

/// RMS and fitness of a prediction.
pub fn metrics(measured: &[f64], estimated: &[f64]) -> Metrics {
    let n = measured.len().min(estimated.len());
    let ss: f64 = measured
        .iter()
        .zip(estimated)
        .map(|(m, e)| (m - e) * (m - e))
        .sum();
    Metrics {
        rows: n,
        rms: (ss / n.max(1) as f64).sqrt(),
        fitness: fitness(measured, estimated).ok(),
    }
}

/// A fitted model with its estimates and training metrics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fitted<M> {
    /// The model.
    pub model: M,
    /// Every parameter with its σ, in [`crate::FrictionModel::parameters`] order.
    pub estimates: Vec<Estimate>,
    /// Metrics on the training log.
    pub train: Metrics,
    /// Iterations of the winning local search.
    pub iterations: usize,
    /// Cost evaluations over all starts.
    pub evaluations: usize,
    /// How the winning local search ended.
    pub status: FitStatus,
}

/// The result of a separable fit: structure, coefficients (model
/// coefficients followed by those of any extra columns) and cost.
#[derive(Debug, Clone, PartialEq)]
pub struct SeparableFit {
    /// Structural parameters `θ`.
    pub theta: Vec<f64>,
    /// Linear coefficients: the model's `β`, then one per extra column.
    pub beta: Vec<f64>,
    /// Residual sum of squares, N²·m².
    pub rss: f64,
    /// Iterations of the winning local search.
    pub iterations: usize,
    /// Cost evaluations over all starts.
    pub evaluations: usize,
    /// How the winning local search ended.
    pub status: FitStatus,
}

/// The outer problem of variable projection for model `M` plus optional
/// extra columns with free coefficients.
pub struct Problem<'a, M: Separable + Sync> {
    motion: Track<'a>,
    y: &'a [f64],
    extra: &'a [Vec<f64>],
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// Box of `ln θ`.
    box_lo: Vec<f64>,
    box_hi: Vec<f64>,
    _m: std::marker::PhantomData<M>,
}

impl<'a, M: Separable + Sync> Problem<'a, M> {
    /// Sets up the fit of `y` along `motion` with extra columns (each of the
    /// log's length; their coefficients are unbounded). `theta_bounds`
    /// narrows the physical ranges of `θ` (e.g. to the data's velocity
    /// range); equal bounds hold a parameter fixed.
    pub fn new(
        motion: Track<'a>,
        y: &'a [f64],
        extra: &'a [Vec<f64>],
        theta_bounds: &[(f64, f64)],
    ) -> Result<Self, FrictionError> {
        let n = motion.len();
        if y.len() != n {
            return Err(FrictionError::LengthMismatch {
                what: "torque tau",
                expected: n,
                found: y.len(),
            });
        }
        for (k, e) in extra.iter().enumerate() {
            if e.len() != n {
                return Err(FrictionError::LengthMismatch {
                    what: "extra column",
                    expected: n,
                    found: e.len(),
                });
            }
            if let Some((i, &v)) = e.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                let _ = k;
                return Err(FrictionError::NonFinite {
                    what: "extra column",
                    index: i,
                    value: v,
                });
            }
        }
        if let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(FrictionError::NonFinite {
                what: "torque tau",
                index,
                value,
            });
        }
        check_motion(&motion)?;
        let p = M::coefficient_info().len() + extra.len();
        if n < p + 2 {
            return Err(FrictionError::TooFewSamples {
                what: "fit",
                found: n,
                needed: p + 2,
            });
        }
        let info = M::coefficient_info();
        let mut lower: Vec<f64> = info.iter().map(|i| bound(i.lower)).collect();
        let mut upper: Vec<f64> = info.iter().map(|i| bound(i.upper)).collect();
        lower.extend(std::iter::repeat_n(f64::NEG_INFINITY, extra.len()));
        upper.extend(std::iter::repeat_n(f64::INFINITY, extra.len()));
        let sinfo = M::structure_info();
        let mut box_lo = Vec::with_capacity(sinfo.len());
        let mut box_hi = Vec::with_capacity(sinfo.len());
        for (i, s) in sinfo.iter().enumerate() {
            let (lo, hi) = theta_bounds.get(i).copied().unwrap_or((s.lower, s.upper));
            let (lo, hi) = (lo.max(s.lower), hi.min(s.upper));
            box_lo.push(lo.ln());
            box_hi.push(hi.max(lo).ln());
        }
        Ok(Self {
            motion,
            y,
            extra,
            lower,
            upper,
            box_lo,
            box_hi,
            _m: std::marker::PhantomData,
        })
    }

    fn theta(&self, u: &[f64]) -> Vec<f64> {
        u.iter().map(|u| u.exp()).collect()
    }

    /// Coefficients, prediction and RSS at `ln θ = u`.
    fn eval(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>, f64)> {
        let theta = self.theta(u);
        let cols = M::columns(&theta, &self.motion);
        let refs: Vec<&[f64]> = cols
            .iter()
            .map(Vec::as_slice)
            .chain(self.extra.iter().map(Vec::as_slice))
            .collect();
        let (beta, rss) = bounded_lstsq(&refs, self.y, &self.lower, &self.upper)?;
        let mut pred = vec![0.0; self.y.len()];
        for (c, b) in refs.iter().zip(&beta) {
            for (p, x) in pred.iter_mut().zip(c.iter()) {
                *p += b * x;
            }
        }
        rss.is_finite().then_some((beta, pred, rss))
    }

    /// Cost (RSS) at the structural parameters `θ`; `None` when the columns
    /// are dependent there.
    pub fn cost(&self, theta: &[f64]) -> Option<f64> {
        let u: Vec<f64> = theta.iter().map(|t| t.ln()).collect();
        self.eval(&u).map(|e| e.2)
    }

    /// Runs the multi-start search from the given starting `θ`s; the best
    /// `settings.starts` of them (by cost) start a local search.
    ///
    /// Logs longer than [`FitSettings::coarse_rows`] are searched
    /// coarse-to-fine: the multi-start search runs on every `k`-th sample
    /// (the state models integrate exactly over the longer steps), and its
    /// winner is refined on all samples.
    pub fn solve(
        &self,
        starts: &[Vec<f64>],
        settings: &FitSettings,
    ) -> Result<SeparableFit, FrictionError> {
        let n = self.y.len();
        let d = self.box_lo.len();
        if d == 0 || settings.coarse_rows == 0 || n <= settings.coarse_rows {
            return self.multistart(starts, settings, FINE_TOL);
        }
        let k = n.div_ceil(settings.coarse_rows);
        let mut idx: Vec<usize> = (0..n).step_by(k).collect();
        if idx.last() != Some(&(n - 1)) {
            idx.push(n - 1);
        }
        let pick = |v: &[f64]| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        let (t, q, dq) = (
            pick(self.motion.t()),
            pick(self.motion.q()),
            pick(self.motion.dq()),
        );
        let y = pick(self.y);
        let extra: Vec<Vec<f64>> = self.extra.iter().map(|e| pick(e)).collect();
        let coarse = Problem::<M> {
            motion: Track::new(&t, &q, &dq)?,
            y: &y,
            extra: &extra,
            lower: self.lower.clone(),
            upper: self.upper.clone(),
            box_lo: self.box_lo.clone(),
            box_hi: self.box_hi.clone(),
            _m: std::marker::PhantomData,
        };
        let c = coarse.multistart(starts, settings, COARSE_TOL)?;
        let u0: Vec<f64> = c.theta.iter().map(|t| t.ln()).collect();
        let mut fine = self.levenberg_marquardt(u0, settings.max_iterations, FINE_TOL);
        if !fine.rss.is_finite() {
            return self.multistart(starts, settings, FINE_TOL);
        }
        fine.evaluations += c.evaluations;
        Ok(fine)
    }

    fn multistart(
        &self,
        starts: &[Vec<f64>],
        settings: &FitSettings,
        tol: f64,
    ) -> Result<SeparableFit, FrictionError> {
        let d = self.box_lo.len();
        let grid: Vec<Vec<f64>> = if d == 0 {
            vec![Vec::new()]
        } else {
            starts.to_vec()
        };
        // The starts are independent: scored and refined in parallel, then
        // reduced in their original order, so the result does not depend on
        // the thread count.
        let mut evaluations = grid.len();
        let mut scored: Vec<(f64, Vec<f64>)> = grid
            .par_iter()
            .filter_map(|s| {
                let u: Vec<f64> = s
                    .iter()
                    .enumerate()
                    .map(|(j, t)| t.ln().clamp(self.box_lo[j], self.box_hi[j]))
                    .collect();
                self.eval(&u).map(|(_, _, rss)| (rss, u))
            })
            .collect();
        scored.sort_by(|a, b| a.0.total_cmp(&b.0));
        scored.dedup_by(|a, b| a.1 == b.1);
        scored.truncate(settings.starts.max(1));
        let runs: Vec<SeparableFit> = scored
            .into_par_iter()
            .map(|(_, u0)| self.levenberg_marquardt(u0, settings.max_iterations, tol))
            .collect();
        let mut best: Option<SeparableFit> = None;
        for r in runs {
            evaluations += r.evaluations;
            if best.as_ref().is_none_or(|b| r.rss < b.rss) {
                best = Some(r);
            }
        }
        let mut best = best.ok_or(FrictionError::NoFit {
            model: M::structure_info()
                .first()
                .map_or("linear model", |_| "separable model"),
        })?;
        best.evaluations = evaluations;
        Ok(best)
    }

    fn levenberg_marquardt(
        &self,
        mut u: Vec<f64>,
        max_iterations: usize,
        tol: f64,
    ) -> SeparableFit {
        let d = u.len();
        let mut evaluations = 1;
        let Some((mut beta, mut pred, mut rss)) = self.eval(&u) else {
            return SeparableFit {
                theta: self.theta(&u),
                beta: Vec::new(),
                rss: f64::INFINITY,
                iterations: 0,
                evaluations,
                status: FitStatus::IterationLimit,
            };
        };
        let mut status = FitStatus::Converged;
        let mut iterations = 0;
        let mut lambda: f64 = 1e-3;
        let n = self.y.len();
        if d > 0 {
            status = FitStatus::IterationLimit;
            'outer: while iterations < max_iterations {
                iterations += 1;
                // Forward-difference Jacobian of the prediction in ln θ.
                let jac: Vec<Vec<f64>> = (0..d)
                    .into_par_iter()
                    .map(|j| {
                        let h = if u[j] + 1e-6 <= self.box_hi[j] {
                            1e-6
                        } else {
                            -1e-6
                        };
                        let mut up = u.clone();
                        up[j] += h;
                        match self.eval(&up) {
                            Some((_, p2, _)) => {
                                p2.iter().zip(&pred).map(|(a, b)| (a - b) / h).collect()
                            }
                            None => vec![0.0; n],
                        }
                    })
                    .collect();
                evaluations += d;
                let resid: Vec<f64> = self.y.iter().zip(&pred).map(|(y, p)| y - p).collect();
                let norms: Vec<f64> = jac
                    .iter()
                    .map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt())
                    .collect();
                if norms.iter().all(|&x| x == 0.0) {
                    status = FitStatus::Converged;
                    break;
                }
                loop {
                    // Solve [J; √λ D] δ = [r; 0] by QR.
                    let aug: Vec<Vec<f64>> = (0..d)
                        .map(|j| {
                            let mut c = jac[j].clone();
                            c.extend((0..d).map(|k| {
                                if k == j {
                                    lambda.sqrt() * norms[j].max(1e-12)
                                } else {
                                    0.0
                                }
                            }));
                            c
                        })
                        .collect();
                    let mut rhs = resid.clone();
                    rhs.extend(std::iter::repeat_n(0.0, d));
                    let refs: Vec<&[f64]> = aug.iter().map(Vec::as_slice).collect();
                    let Some(step) = Qr::new(&refs, &rhs).solve() else {
                        lambda *= 10.0;
                        if lambda > 1e12 {
                            status = FitStatus::Converged;
                            break 'outer;
                        }
                        continue;
                    };
                    let trial: Vec<f64> = (0..d)
                        .map(|j| (u[j] + step[j]).clamp(self.box_lo[j], self.box_hi[j]))
                        .collect();
                    // Converged when the step no longer moves any parameter
                    // by more than 1e-7 relative (ln θ is relative).
                    if trial.iter().zip(&u).all(|(a, b)| (a - b).abs() < 1e-7) {
                        status = FitStatus::Converged;
                        break 'outer;
                    }
                    evaluations += 1;
                    match self.eval(&trial) {
                        Some((b2, p2, r2)) if r2 < rss => {
                            let rel = (rss - r2) / rss.max(1e-300);
                            u = trial;
                            beta = b2;
                            pred = p2;
                            rss = r2;
                            lambda = (lambda / 3.0).max(1e-12);
                            if rel < tol {
                                status = FitStatus::Converged;
                                break 'outer;
                            }
                            break;
                        }
                        _ => {
                            lambda *= 4.0;
                            if lambda > 1e12 {
                                status = FitStatus::Converged;
                                break 'outer;
                            }
                        }
                    }
                }
            }
        }
        SeparableFit {
            theta: self.theta(&u),
            beta,
            rss,
            iterations,
            evaluations,
            status,
        }
    }
}

/// Relative cost decrease below which the final search stops: far below
/// any parameter's uncertainty (a cost change of 1e-8 is a parameter change
/// of 1e-4 σ).
const FINE_TOL: f64 = 1e-8;

/// The coarse searches only choose the basin the final search refines.
const COARSE_TOL: f64 = 1e-4;

fn bound(x: f64) -> f64 {
    // The parameter tables use ±1e6 for "unbounded" offsets and levels.
    if x <= -1e6 {
        f64::NEG_INFINITY
    } else if x >= 1e6 {
        f64::INFINITY
    } else {
        x
    }
}

/// `count` values spaced logarithmically over `[lo, hi]`.
pub fn log_grid(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    if count <= 1 || hi <= lo {
        return vec![lo];
    }
    (0..count)
        .map(|i| lo * (hi / lo).powf(i as f64 / (count - 1) as f64))
        .collect()
}

/// Velocity and position scales of a motion used to set start grids and
/// search boxes: the 99th percentile of `|dq|` and the travelled range of `q`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Scales {
    pub(crate) vmax: f64,
    pub(crate) range: f64,
}

/// Smallest range of the position (rad) a fit accepts: below it the joint
/// is taken as still (the presliding lengths searched start at 1e-7 rad).
pub const MIN_TRAVEL: f64 = 1e-6;

/// Refuses a track along which the joint does not move: a position range
/// below [`MIN_TRAVEL`] or no velocity at all.
pub fn check_motion(motion: &Track) -> Result<(), FrictionError> {
    let q = motion.q();
    let range = q.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - q.iter().cloned().fold(f64::INFINITY, f64::min);
    let speed = motion.dq().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if range >= MIN_TRAVEL && speed > 0.0 {
        Ok(())
    } else {
        Err(FrictionError::NoMotion {
            range: range.max(0.0),
            speed,
            min_travel: MIN_TRAVEL,
        })
    }
}

pub(crate) fn scales(motion: &Track) -> Scales {
    let mut v: Vec<f64> = motion.dq().iter().map(|v| v.abs()).collect();
    let k = ((v.len() as f64) * 0.99) as usize;
    let vmax = if v.is_empty() {
        1.0
    } else {
        let k = k.min(v.len() - 1);
        *v.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let q = motion.q();
    let range = q.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - q.iter().cloned().fold(f64::INFINITY, f64::min);
    Scales {
        vmax: if vmax > 0.0 { vmax } else { 1.0 },
        range: if range > 0.0 { range } else { 1.0 },
    }
}

/// σ of every physical parameter and of the extra coefficients from the
/// finite-difference Jacobian of the prediction at the optimum.
fn estimates<M: Separable + Sync>(
    model: &M,
    base: &[f64],
    extra: &[Vec<f64>],
    extra_beta: &[f64],
    motion: &Track,
    rss: f64,
    fixed: &[bool],
) -> (Vec<Estimate>, Vec<Option<f64>>) {
    let info = model.parameter_info();
    let values = model.parameters();
    let n = base.len();
    let which: Vec<usize> = (0..info.len())
        .filter(|&j| !fixed.get(j).copied().unwrap_or(false))
        .collect();
    // One prediction per free parameter, independent of each other: in
    // parallel (a state model integrates the whole log for each).
    let mut jac: Vec<Vec<f64>> = which
        .par_iter()
        .map(|&j| {
            let x = values[j];
            let mut h = 1e-6 * x.abs().max(1e-3);
            if x + h > info[j].upper {
                h = -h;
            }
            let mut v = values.clone();
            v[j] = x + h;
            let p2 = M::from_vector(&v).predict(motion);
            p2.iter().zip(base).map(|(a, b)| (a - b) / h).collect()
        })
        .collect();
    for e in extra {
        jac.push(e.clone());
    }
    let dof = n.saturating_sub(jac.len()).max(1) as f64;
    let s2 = rss / dof;
    let refs: Vec<&[f64]> = jac.iter().map(Vec::as_slice).collect();
    let diag = Qr::new(&refs, &vec![0.0; n]).inverse_gram_diagonal();
    let sig = |k: usize| diag.as_ref().map(|d| (s2 * d[k]).sqrt());
    let mut out = Vec::with_capacity(info.len());
    for (j, inf) in info.iter().enumerate() {
        let k = which.iter().position(|&w| w == j);
        let x = values[j];
        out.push(Estimate {
            name: inf.name.to_string(),
            unit: inf.unit.to_string(),
            value: x,
            sigma: k.and_then(sig),
            at_bound: (x <= inf.lower || x >= inf.upper) && k.is_some(),
            fixed: k.is_none(),
        });
    }
    let extra_sigma = (0..extra_beta.len())
        .map(|i| sig(which.len() + i))
        .collect();
    (out, extra_sigma)
}

fn finish<M: Separable + Sync>(
    fit: &SeparableFit,
    motion: &Track,
    y: &[f64],
    settings: &FitSettings,
) -> Fitted<M> {
    let nb = M::coefficient_info().len();
    let model = M::from_parts(&fit.theta, &fit.beta[..nb]);
    let pred = model.predict(motion);
    let fixed = held(&model.parameter_info(), settings);
    let (estimates, _) = estimates(&model, &pred, &[], &[], motion, fit.rss, &fixed);
    Fitted {
        model,
        estimates,
        train: metrics(y, &pred),
        iterations: fit.iterations,
        evaluations: fit.evaluations,
        status: fit.status,
    }
}

/// Which parameters a fit holds instead of estimating: the Stribeck shape
/// `δ` when [`FitSettings::shape`] gives it.
pub(crate) fn held(info: &[ParamInfo], settings: &FitSettings) -> Vec<bool> {
    info.iter()
        .map(|i| settings.shape.is_some() && i.name == crate::models::DELTA.name)
        .collect()
}

/// σ and metrics for a model fitted with extra columns (the diagnosis'
/// final model): estimates of the model's parameters and of the extra
/// coefficients.
pub fn estimates_with_extra<M: Separable + Sync>(
    model: &M,
    extra: &[Vec<f64>],
    extra_beta: &[f64],
    motion: &Track,
    rss: f64,
    fixed: &[bool],
) -> (Vec<Estimate>, Vec<Option<f64>>) {
    let base = model.predict(motion);
    estimates(model, &base, extra, extra_beta, motion, rss, fixed)
}

/// Fits offset + Coulomb + viscous friction (linear least squares).
pub fn fit_coulomb_viscous(
    motion: &Track,
    tau: &[f64],
    settings: &FitSettings,
) -> Result<Fitted<CoulombViscous>, FrictionError> {
    let prob = Problem::<CoulombViscous>::new(*motion, tau, &[], &[])?;
    let fit = prob.solve(&[], settings)?;
    Ok(finish(&fit, motion, tau, settings))
}

/// Search box of the Stribeck velocity: from 1e-4 of the velocity scale
/// (below the resolution of any log) to the velocity scale.
fn vs_box(s: Scales) -> (f64, f64) {
    ((1e-4 * s.vmax).max(1e-5), s.vmax)
}

/// Fits the Stribeck model; starts on a grid of `v_s` (7 log-spaced values
/// over the data's velocity range) and `δ ∈ {0.7, 1, 2}`.
pub fn fit_stribeck(
    motion: &Track,
    tau: &[f64],
    settings: &FitSettings,
) -> Result<Fitted<Stribeck>, FrictionError> {
    let s = scales(motion);
    let vsb = vs_box(s);
    let db = settings.shape.map_or((0.3, 4.0), |d| (d, d));
    let prob = Problem::<Stribeck>::new(*motion, tau, &[], &[vsb, db])?;
    let deltas = settings.shape.map_or(vec![0.7, 1.0, 2.0], |d| vec![d]);
    let mut starts = Vec::new();
    for vs in log_grid(1e-3 * s.vmax, 0.5 * s.vmax, 7) {
        for &d in &deltas {
            starts.push(vec![vs, d]);
        }
    }
    let fit = prob.solve(&starts, settings)?;
    Ok(finish(&fit, motion, tau, settings))
}

/// Fits the Dahl model; starts on 9 log-spaced presliding displacements
/// from 1e-6 rad to a tenth of the travelled range.
pub fn fit_dahl(
    motion: &Track,
    tau: &[f64],
    settings: &FitSettings,
) -> Result<Fitted<Dahl>, FrictionError> {
    let s = scales(motion);
    let prob = Problem::<Dahl>::new(*motion, tau, &[], &[(1e-8, s.range)])?;
    let starts: Vec<Vec<f64>> = log_grid(1e-6, 0.1 * s.range, 9)
        .into_iter()
        .map(|x| vec![x])
        .collect();
    let fit = prob.solve(&starts, settings)?;
    Ok(finish(&fit, motion, tau, settings))
}

/// The search box and start grid of the LuGre structure
/// `θ = (κ, F_s/F_c, v_s, δ)` around a Stribeck fit of the same data: the
/// presliding displacement `F_c/σ₀ = 1/κ` from 1e-7 rad to the travelled
/// range, started on 9 log-spaced values up to a tenth of it.
pub fn lugre_starts(
    motion: &Track,
    stribeck: &Stribeck,
    settings: &FitSettings,
) -> (Vec<(f64, f64)>, Vec<Vec<f64>>) {
    let s = scales(motion);
    let kappa: Vec<f64> = log_grid(1e-6, 0.1 * s.range, 9)
        .into_iter()
        .map(|x| 1.0 / x)
        .collect();
    state_starts(motion, stribeck, settings, (1.0 / s.range, 1e7), &kappa)
}

/// The box and starts of a state model's structure `θ = (p, F_s/F_c, v_s,
/// δ)`: `p` (the presliding scale) over `p_box` from each of `p_starts`,
/// the static ratio from [`static_ratios`], the Stribeck velocity and shape
/// from the Stribeck fit (`δ` held when [`FitSettings::shape`] gives it).
fn state_starts(
    motion: &Track,
    stribeck: &Stribeck,
    settings: &FitSettings,
    p_box: (f64, f64),
    p_starts: &[f64],
) -> (Vec<(f64, f64)>, Vec<Vec<f64>>) {
    let vsb = vs_box(scales(motion));
    let db = settings.shape.map_or((0.3, 4.0), |d| (d, d));
    let ratios = static_ratios(stribeck);
    let vs = stribeck.stribeck_velocity.clamp(vsb.0, vsb.1);
    let delta = settings.shape.unwrap_or(stribeck.shape).clamp(db.0, db.1);
    let mut starts = Vec::new();
    for &p in p_starts {
        for &r in &ratios {
            starts.push(vec![p, r, vs, delta]);
        }
    }
    (vec![p_box, RATIO_BOX, vsb, db], starts)
}

/// Box of `F_s/F_c` in the state models' structure.
const RATIO_BOX: (f64, f64) = (0.05, 20.0);

/// The starts of `F_s/F_c`: the Stribeck fit's, and 1.3 in case a static
/// map could not see the breakaway (presliding hides it from a static
/// model).
fn static_ratios(stribeck: &Stribeck) -> Vec<f64> {
    let mut ratios = vec![1.3];
    if stribeck.coulomb > 0.0 {
        let r = (stribeck.static_friction / stribeck.coulomb).clamp(RATIO_BOX.0, RATIO_BOX.1);
        if (r - 1.3).abs() > 0.05 {
            ratios.push(r);
        }
    }
    ratios
}

/// Fits the LuGre model. The steady-state parameters start from a Stribeck
/// fit of the same data (LuGre's steady state is the Stribeck curve), the
/// presliding length `F_c/σ₀` from 9 log-spaced values.
pub fn fit_lugre(
    motion: &Track,
    tau: &[f64],
    stribeck: &Stribeck,
    settings: &FitSettings,
) -> Result<Fitted<LuGre>, FrictionError> {
    let (bounds, starts) = lugre_starts(motion, stribeck, settings);
    let prob = Problem::<LuGre>::new(*motion, tau, &[], &bounds)?;
    let fit = prob.solve(&starts, settings)?;
    Ok(finish(&fit, motion, tau, settings))
}

/// The search box and start grid of the Maxwell-slip structure
/// `θ = (L, F_s/F_c, v_s, δ)` around a Stribeck fit of the same data: the
/// longest presliding length `L` from 1e-6 rad to the travelled range,
/// started on 7 log-spaced values up to half of it (the shortest element
/// is a thousandth of `L`), the rest as for LuGre ([`lugre_starts`]).
pub fn maxwell_starts(
    motion: &Track,
    stribeck: &Stribeck,
    settings: &FitSettings,
) -> (Vec<(f64, f64)>, Vec<Vec<f64>>) {
    let s = scales(motion);
    let lengths = log_grid(1e-5f64.min(0.1 * s.range), 0.5 * s.range, 7);
    let l_box = (1e-6f64.min(0.5 * s.range), s.range);
    state_starts(motion, stribeck, settings, l_box, &lengths)
}

/// Fits the generalized Maxwell-slip model ([`MaxwellSlip`]), its levels
/// held ≥ 0, from [`maxwell_starts`].
pub fn fit_maxwell_slip(
    motion: &Track,
    tau: &[f64],
    stribeck: &Stribeck,
    settings: &FitSettings,
) -> Result<Fitted<MaxwellSlip>, FrictionError> {
    let (bounds, starts) = maxwell_starts(motion, stribeck, settings);
    let prob = Problem::<MaxwellSlip>::new(*motion, tau, &[], &bounds)?;
    let fit = prob.solve(&starts, settings)?;
    Ok(finish(&fit, motion, tau, settings))
}

/// Names of a model's parameters (for reports).
pub fn parameter_names(info: &[ParamInfo]) -> Vec<&'static str> {
    info.iter().map(|i| i.name).collect()
}
