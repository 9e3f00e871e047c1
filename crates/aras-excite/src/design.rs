//! The optimal-excitation design: multi-start constrained optimisation of the
//! Fourier coefficients with `optimization_engine` (ALM + PANOC).
//!
//! Problem, per start:
//!
//! ```text
//! minimise    c(p)                    ln κ or −ln det, on the criterion grid
//! subject to  F1(p) ∈ [lo, hi]        X, Ẋ, Ẍ on the constraint grid, tightened (77)
//!             p ∈ U                   a box implied by the limits (for PANOC's projection)
//! ```
//!
//! `F1` is linear and handled by the augmented Lagrangian (ALM) outer loop;
//! PANOC (an L-BFGS forward–backward method) solves the inner problems with
//! the exact gradients of [`criterion`](crate::criterion). The best start's
//! point is finally pulled exactly onto the tightened grid bounds by scaling
//! its motion about the box centre (a no-op up to the ALM tolerance), so the
//! grid theorem of [`constraints`](crate::constraints) guarantees the limits
//! in continuous time.
//!
//! With a user [`PoseConstraint`] ([`design_constrained`]), `F1` also
//! holds `g(X(t_j)) ≤ −margin` on the constraint grid, and the repair then
//! scales the motion about a feasible rest pose until the constraint's
//! check holds ([`pose`](crate::pose)).

use std::cell::RefCell;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use nalgebra::allocator::Allocator;
use nalgebra::{DMatrix, DefaultAllocator, Dim, U2};
use optimization_engine::alm::{
    AlmCache, AlmFactory, AlmOptimizer, AlmProblem, NO_JACOBIAN_MAPPING, NO_MAPPING,
};
use optimization_engine::constraints::Rectangle;
use optimization_engine::core::ExitStatus;
use optimization_engine::panoc::PANOCCache;
use optimization_engine::{FunctionCallResult, SolverError};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;

use crate::constraints::{GridConstraints, Limits, Margins, grid_factor};
use crate::criterion::{Assessment, Criterion, Evaluator, check_projection};
use crate::error::{ExciteError, check_finite, with_causes};
use crate::fourier::{DEFAULT_HARMONICS, DEFAULT_OMEGA_F, check_omega, coordinate_name};
use crate::param::{Grid, Layout};
use crate::pose::{ConstraintCheck, ConstraintSettings, PoseConstraint, PoseGrid};
use crate::{FourierTrajectory, Regressor};

/// Settings of [`design`]. `Default` gives the paper's problem (L = 5,
/// ω_f = 2π/10, box and rates (77)) with the documented defaults below.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignSettings<D: Dim = U2>
where
    DefaultAllocator: Allocator<D>,
{
    /// Number of harmonics L ≥ 1 (default 5).
    pub harmonics: usize,
    /// Base frequency ω_f (rad/s, default 2π/10).
    pub omega_f: f64,
    /// Box, rate and acceleration limits (default [`Limits::paper`]).
    pub limits: Limits<D>,
    /// What to minimise (default [`Criterion::Condition`]).
    pub criterion: Criterion,
    /// Constraint grid points per period (default 200; the limits are
    /// tightened by `q = ½(πL/N)²` of their half-range, 0.3 % at the
    /// defaults, which makes grid feasibility imply continuous feasibility).
    pub constraint_points: usize,
    /// Regressor samples per period for the criterion (default 100, offset
    /// by half a step so no sample sits at the velocity reversal at `t = 0`).
    pub criterion_points: usize,
    /// Number of random feasible starts (default 8).
    pub starts: usize,
    /// Seed of the start generator (default 1). Results are a deterministic
    /// function of the settings, the regressor and the projection.
    pub seed: u64,
    /// Smallest useful peak-to-peak excursion of each coordinate (rad,
    /// default 1°); limits that allow less are an error.
    pub min_excursion: f64,
    /// PANOC tolerance on the inner problems' optimality (default 1e-5).
    pub tolerance: f64,
    /// Tolerance on the constraint infeasibility of the ALM (default 1e-5,
    /// in constraint units; the final point is repaired exactly anyway).
    pub infeasibility_tolerance: f64,
    /// Outer (ALM) iteration limit per start (default 20).
    pub max_outer_iterations: usize,
    /// Inner (PANOC) iteration limit per outer iteration (default 200).
    pub max_inner_iterations: usize,
    /// Optional wall-clock limit per start. Off by default: a time limit
    /// makes the result depend on machine speed, breaking determinism.
    pub max_time_per_start: Option<Duration>,
    /// Worker threads for the starts (0 = rayon's global pool).
    pub threads: usize,
    /// How a pose constraint is met (margin, check grid, anchor); read only
    /// by [`design_constrained`] and [`random_feasible_constrained`].
    pub constraint: ConstraintSettings,
}

impl Default for DesignSettings {
    /// [`DesignSettings::new`] with the paper's limits ([`Limits::paper`]).
    fn default() -> Self {
        Self::new(Limits::paper())
    }
}

impl<D: Dim> DesignSettings<D>
where
    DefaultAllocator: Allocator<D>,
{
    /// The default settings (the paper's where it gives them,
    /// `docs/excitation.md`) for a robot with the motion limits `limits`.
    pub fn new(limits: Limits<D>) -> Self {
        Self {
            harmonics: DEFAULT_HARMONICS,
            omega_f: DEFAULT_OMEGA_F,
            limits,
            criterion: Criterion::Condition,
            constraint_points: 200,
            criterion_points: 100,
            starts: 8,
            seed: 1,
            min_excursion: 1f64.to_radians(),
            tolerance: 1e-5,
            infeasibility_tolerance: 1e-5,
            max_outer_iterations: 20,
            max_inner_iterations: 200,
            max_time_per_start: None,
            threads: 0,
            constraint: ConstraintSettings::default(),
        }
    }
}

impl<D: Dim> DesignSettings<D>
where
    DefaultAllocator: Allocator<D>,
{
    /// Checks every setting; errors name the setting, its value and the fix.
    pub fn validate(&self) -> Result<(), ExciteError> {
        if self.harmonics == 0 {
            return Err(ExciteError::InvalidSetting {
                name: "harmonics",
                value: 0.0,
                reason: "the trajectory needs at least one harmonic (L ≥ 1; the paper uses 5)"
                    .into(),
            });
        }
        check_omega(self.omega_f)?;
        self.limits.validate()?;
        let q = grid_factor(self.harmonics, self.constraint_points.max(1));
        if q > 0.1 {
            return Err(ExciteError::InvalidSetting {
                name: "constraint_points",
                value: self.constraint_points as f64,
                reason: format!(
                    "too coarse for {} harmonics: use at least {} points per period",
                    self.harmonics,
                    (std::f64::consts::PI * self.harmonics as f64 / 0.2f64.sqrt()).ceil()
                ),
            });
        }
        if self.criterion_points < 2 * self.harmonics + 1 {
            return Err(ExciteError::InvalidSetting {
                name: "criterion_points",
                value: self.criterion_points as f64,
                reason: format!(
                    "use at least 2L + 1 = {} samples per period",
                    2 * self.harmonics + 1
                ),
            });
        }
        if self.starts == 0 {
            return Err(ExciteError::InvalidSetting {
                name: "starts",
                value: 0.0,
                reason: "at least one start is needed".into(),
            });
        }
        for (name, v) in [
            ("tolerance", self.tolerance),
            ("infeasibility_tolerance", self.infeasibility_tolerance),
        ] {
            check_finite(|| name.into(), v)?;
            if v <= 0.0 {
                return Err(ExciteError::InvalidSetting {
                    name,
                    value: v,
                    reason: "must be positive".into(),
                });
            }
        }
        check_finite(|| "min_excursion".into(), self.min_excursion)?;
        self.constraint.validate()?;
        if self.max_outer_iterations == 0 || self.max_inner_iterations == 0 {
            return Err(ExciteError::InvalidSetting {
                name: "max_outer_iterations/max_inner_iterations",
                value: 0.0,
                reason: "iteration limits must be at least 1".into(),
            });
        }
        self.check_motion()
    }

    /// Errors if the limits leave a coordinate less than `min_excursion`
    /// of peak-to-peak motion. The fundamental harmonic moves most per unit
    /// of rate and acceleration: `2v/ω_f` and `2a/ω_f²` peak to peak.
    fn check_motion(&self) -> Result<(), ExciteError> {
        let l = &self.limits;
        let n = l.coordinates();
        for i in 0..n {
            let coordinate = coordinate_name(i, n);
            let width = l.max[i] - l.min[i];
            let (v, a) = (l.max_rate[i], l.max_accel[i]);
            let reach = width
                .min(2.0 * v / self.omega_f)
                .min(2.0 * a / (self.omega_f * self.omega_f));
            if reach < self.min_excursion {
                return Err(ExciteError::TooLittleMotion {
                    coordinate,
                    reach,
                    max_rate: v,
                    max_accel: a,
                    width,
                    omega: self.omega_f,
                    required: self.min_excursion,
                });
            }
        }
        Ok(())
    }

    fn layout(&self) -> Layout {
        Layout {
            harmonics: self.harmonics,
            omega_f: self.omega_f,
            coords: self.limits.coordinates(),
        }
    }
}

/// Errors if the regressor cannot be evaluated at some pose of the box (at
/// rest): an unreachable or singular pose would stop the design half-way.
/// Two coordinates are checked on a 41 × 41 grid including the box's edges
/// and corners; more on the corners (up to 12 coordinates) and 1681
/// quasi-random poses inside.
fn check_box<R: Regressor, D: Dim>(regressor: &R, limits: &Limits<D>) -> Result<(), ExciteError>
where
    DefaultAllocator: Allocator<D>,
{
    let (lo, hi) = (limits.min.as_slice(), limits.max.as_slice());
    let n = lo.len();
    const K: usize = 41;
    let mut rows = vec![0.0; regressor.outputs() * regressor.columns()];
    let z = vec![0.0; n];
    let mut poses: Vec<Vec<f64>> = Vec::new();
    let at = |c: usize, u: f64| lo[c] + (hi[c] - lo[c]) * u;
    if n == 2 {
        for i in 0..K {
            for j in 0..K {
                let f = |k: usize| k as f64 / (K - 1) as f64;
                poses.push(vec![at(0, f(i)), at(1, f(j))]);
            }
        }
    } else {
        if n <= 12 {
            for corner in 0..1usize << n {
                poses.push((0..n).map(|c| at(c, ((corner >> c) & 1) as f64)).collect());
            }
        }
        poses.extend(kronecker_poses(lo, hi));
    }
    for x in poses {
        rows.iter_mut().for_each(|v| *v = 0.0);
        if let Err(e) = regressor.fill(&x, &z, &z, &mut rows) {
            return Err(ExciteError::InfeasibleBox {
                lo: lo.to_vec(),
                hi: hi.to_vec(),
                at: x,
                source: Box::new(e),
            });
        }
    }
    Ok(())
}

/// 1681 poses filling the box `[lo, hi]` evenly: a Kronecker sequence in
/// which coordinate `c` steps by the fractional part of √(c-th prime).
pub(crate) fn kronecker_poses<'a>(
    lo: &'a [f64],
    hi: &'a [f64],
) -> impl Iterator<Item = Vec<f64>> + 'a {
    const K: usize = 41;
    const PRIMES: [f64; 12] = [2., 3., 5., 7., 11., 13., 17., 19., 23., 29., 31., 37.];
    (0..K * K).map(move |k| {
        (0..lo.len())
            .map(|c| {
                let a = PRIMES[c % 12].sqrt() + (c / 12) as f64;
                lo[c] + (hi[c] - lo[c]) * ((k as f64 + 0.5) * a).fract()
            })
            .collect()
    })
}

/// How one start of the multi-start went.
#[derive(Debug, Clone, PartialEq)]
pub struct StartReport {
    /// Criterion value at the random feasible start.
    pub initial_value: f64,
    /// Criterion value at the (repaired, feasible) end point, or why the
    /// start failed.
    pub outcome: Result<f64, String>,
    /// Whether the ALM reported convergence.
    pub converged: bool,
    /// ALM outer iterations.
    pub outer_iterations: usize,
    /// PANOC iterations in total.
    pub inner_iterations: usize,
    /// Scale applied to pull the end point onto the tightened bounds
    /// (1 = already feasible).
    pub repair_scale: f64,
    /// Scale about the anchor applied after that to meet the pose
    /// constraint (1 = already met, or no constraint).
    pub constraint_scale: f64,
    /// Wall-clock time of the start.
    pub time: Duration,
}

/// The result of [`design`].
#[derive(Debug, Clone, PartialEq)]
pub struct Design<D: Dim = U2>
where
    DefaultAllocator: Allocator<D>,
{
    /// The best trajectory found (zero velocity at `t = 0`).
    pub trajectory: FourierTrajectory<D>,
    /// The criterion that was minimised.
    pub criterion: Criterion,
    /// Its value at `trajectory` (κ for [`Criterion::Condition`]).
    pub value: f64,
    /// Condition number of the column-scaled base regressor.
    pub condition_number: f64,
    /// Full assessment of the base regressor at `trajectory`.
    pub assessment: Assessment,
    /// Limit margins on a grid 10× finer than the constraint grid.
    pub margins: Margins<D>,
    /// How the pose constraint is met on its check grid
    /// ([`design_constrained`]; `None` without one).
    pub constraint: Option<ConstraintCheck>,
    /// Index of the winning start.
    pub best_start: usize,
    /// Every start, in order.
    pub starts: Vec<StartReport>,
    /// Total wall-clock time.
    pub elapsed: Duration,
}

/// Assesses the base regressor along any trajectory, sampled at
/// `points` instants per period (offset by half a step), without clamping.
///
/// `projection` is the base projection `E` (`n × b`, `W_b = W E`).
pub fn assess<R: Regressor, D: Dim>(
    regressor: &R,
    projection: &DMatrix<f64>,
    trajectory: &FourierTrajectory<D>,
    points: usize,
) -> Result<Assessment, ExciteError> {
    check_projection(projection, regressor)?;
    let points = points.max(1);
    let mut ev = Evaluator::new(regressor, projection, Criterion::Condition, points, None);
    let h = trajectory.period() / points as f64;
    if trajectory.coordinates() != regressor.coordinates() {
        return Err(ExciteError::InvalidSetting {
            name: "trajectory",
            value: trajectory.coordinates() as f64,
            reason: format!(
                "the trajectory moves {} coordinates, the model has {}",
                trajectory.coordinates(),
                regressor.coordinates()
            ),
        });
    }
    let n = trajectory.coordinates();
    ev.fill_values(|s, out| {
        let (pos, rest) = out.split_at_mut(n);
        let (vel, acc) = rest.split_at_mut(n);
        trajectory.eval_into((s as f64 + 0.5) * h, pos, vel, acc);
    })?;
    Ok(ev.analyse(false)?.assessment)
}

/// `count` random feasible trajectories of the design's form (the starts of
/// the multi-start use the same generator): coefficients uniform in
/// [−1, 1], then each coordinate centred in the box and scaled up until a
/// limit is touched on the (tightened) constraint grid, so every one
/// satisfies the limits in continuous time. Deterministic for a seed.
pub fn random_feasible<D: Dim>(
    settings: &DesignSettings<D>,
    count: usize,
    seed: u64,
) -> Result<Vec<FourierTrajectory<D>>, ExciteError>
where
    DefaultAllocator: Allocator<D>,
{
    settings.validate()?;
    let layout = settings.layout();
    let cons = GridConstraints::new(layout, &settings.limits, settings.constraint_points);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..count)
        .map(|_| layout.trajectory(&random_point(&cons, &mut rng)))
        .collect()
}

/// [`random_feasible`] that also meets a pose constraint: each trajectory
/// is drawn in the same way (the same sequence for a seed), then its motion
/// is scaled about the constraint's anchor until the constraint's check
/// holds (`g ≤ −margin` with the curvature allowance on the check grid of
/// [`DesignSettings::constraint`]), so it touches the box or the
/// constraint.
pub fn random_feasible_constrained<C: PoseConstraint, D: Dim>(
    settings: &DesignSettings<D>,
    constraint: &C,
    count: usize,
    seed: u64,
) -> Result<Vec<FourierTrajectory<D>>, ExciteError>
where
    DefaultAllocator: Allocator<D>,
{
    settings.validate()?;
    let layout = settings.layout();
    let cons = GridConstraints::new(layout, &settings.limits, settings.constraint_points);
    let pose = PoseGrid::new(constraint, &settings.constraint, &cons)?;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let mut p = random_point(&cons, &mut rng);
            pose.fit(&mut p, 1.0)?;
            layout.trajectory(&p)
        })
        .collect()
}

/// One random feasible coefficient vector (see [`random_feasible`]).
pub(crate) fn random_point(cons: &GridConstraints, rng: &mut Xoshiro256PlusPlus) -> Vec<f64> {
    let layout = cons.grid.layout;
    let w = layout.per_coord();
    let mut p: Vec<f64> = (0..layout.dim())
        .map(|k| {
            if k % w == 0 {
                0.0
            } else {
                rng.random_range(-1.0..1.0)
            }
        })
        .collect();
    cons.scale_to_fit(&mut p, true, true);
    p
}

/// Designs an optimal excitation trajectory ((74)–(77), `docs/excitation.md`): minimises the
/// criterion of the stacked base regressor `W_b = W E` over the Fourier
/// coefficients, subject to the limits at every instant and `Ẋ(0) = 0`.
///
/// `projection` is the base projection `E` (`n × b`) from the base-parameter
/// analysis. Runs `settings.starts` starts from random feasible points
/// (in parallel, deterministically for `settings.seed`) and returns the best.
pub fn design<R: Regressor, D: Dim>(
    regressor: &R,
    projection: &DMatrix<f64>,
    settings: &DesignSettings<D>,
) -> Result<Design<D>, ExciteError>
where
    DefaultAllocator: Allocator<D>,
    Limits<D>: Sync,
{
    design_with_progress(regressor, projection, settings, &|_| {})
}

/// [`design_with_progress`] subject also to the pose constraint
/// `constraint(X(t)) ≤ 0` ([`pose`](crate::pose)): the optimiser holds
/// `g ≤ −margin` on the constraint grid, the repair scales the end point
/// about a feasible rest pose until `g` plus its curvature allowance is
/// `≤ −margin` on the check grid ([`DesignSettings::constraint`]), and
/// [`Design::constraint`] reports the result. The starts meet the
/// constraint too.
pub fn design_constrained<R: Regressor, C: PoseConstraint, D: Dim>(
    regressor: &R,
    projection: &DMatrix<f64>,
    settings: &DesignSettings<D>,
    constraint: &C,
    progress: &(dyn Fn(DesignProgress) + Sync),
) -> Result<Design<D>, ExciteError>
where
    DefaultAllocator: Allocator<D>,
    Limits<D>: Sync,
{
    design_inner(regressor, projection, settings, Some(constraint), progress)
}

/// How far a [`design`] has come: starts finished of the total.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DesignProgress {
    /// Starts finished so far.
    pub done: usize,
    /// Starts in total ([`DesignSettings::starts`]).
    pub total: usize,
}

/// [`design`], calling `progress` after each finished start (from the
/// worker thread that ran it; the library draws nothing, a program shows
/// the progress as it likes).
pub fn design_with_progress<R: Regressor, D: Dim>(
    regressor: &R,
    projection: &DMatrix<f64>,
    settings: &DesignSettings<D>,
    progress: &(dyn Fn(DesignProgress) + Sync),
) -> Result<Design<D>, ExciteError>
where
    DefaultAllocator: Allocator<D>,
    Limits<D>: Sync,
{
    design_inner::<R, Unconstrained, D>(regressor, projection, settings, None, progress)
}

/// The pose constraint of a design without one (never evaluated).
struct Unconstrained;

impl PoseConstraint for Unconstrained {
    type Error = std::convert::Infallible;
    fn coordinates(&self) -> usize {
        0
    }
    fn values(&self) -> usize {
        0
    }
    fn eval(&self, _: &[f64], _: &mut [f64]) -> Result<(), Self::Error> {
        Ok(())
    }
    fn jacobian(&self, _: &[f64], _: &mut [f64], _: &mut [f64]) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// The design, with or without a pose constraint.
fn design_inner<R: Regressor, C: PoseConstraint, D: Dim>(
    regressor: &R,
    projection: &DMatrix<f64>,
    settings: &DesignSettings<D>,
    constraint: Option<&C>,
    progress: &(dyn Fn(DesignProgress) + Sync),
) -> Result<Design<D>, ExciteError>
where
    DefaultAllocator: Allocator<D>,
    Limits<D>: Sync,
{
    let started = Instant::now();
    settings.validate()?;
    check_projection(projection, regressor)?;
    if settings.limits.coordinates() != regressor.coordinates() {
        return Err(ExciteError::InvalidSetting {
            name: "limits",
            value: settings.limits.coordinates() as f64,
            reason: format!(
                "the limits are for {} coordinates, the model has {}: give one limit per \
                 coordinate",
                settings.limits.coordinates(),
                regressor.coordinates()
            ),
        });
    }
    check_box(regressor, &settings.limits)?;
    let layout = settings.layout();
    let cons = GridConstraints::new(layout, &settings.limits, settings.constraint_points);
    let grid = Grid::new(layout, settings.criterion_points, 0.5);
    let pose = constraint
        .map(|c| PoseGrid::new(c, &settings.constraint, &cons))
        .transpose()?;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(settings.seed);
    let points: Vec<Vec<f64>> = (0..settings.starts)
        .map(|_| {
            let mut p = random_point(&cons, &mut rng);
            // Start strictly inside, so the first iterations need no repair.
            cons.scale_to_fit(&mut p, false, false);
            match &pose {
                None => scale_motion(&cons, &mut p, 0.9),
                Some(pose) => {
                    pose.fit(&mut p, 1.0)?;
                    pose.scale(&mut p, 0.9);
                    pose.fit(&mut p, 1.0)?;
                }
            }
            Ok(p)
        })
        .collect::<Result<_, ExciteError>>()?;

    let done = AtomicUsize::new(0);
    let total = points.len();
    let run = || -> Vec<(Vec<f64>, StartReport)> {
        points
            .par_iter()
            .map(|p0| {
                let r = run_start(
                    regressor,
                    projection,
                    settings,
                    &cons,
                    pose.as_ref(),
                    &grid,
                    p0.clone(),
                );
                let done = done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(DesignProgress { done, total });
                r
            })
            .collect()
    };
    let outcomes = if settings.threads > 0 {
        rayon::ThreadPoolBuilder::new()
            .num_threads(settings.threads)
            .build()
            .map(|pool| pool.install(run))
            .unwrap_or_else(|_| run())
    } else {
        run()
    };

    let mut best: Option<(usize, f64)> = None;
    for (k, (_, rep)) in outcomes.iter().enumerate() {
        if let Ok(v) = rep.outcome
            && best.is_none_or(|(_, b)| v < b)
        {
            best = Some((k, v));
        }
    }
    let Some((best_start, _)) = best else {
        let last = outcomes
            .iter()
            .rev()
            .find_map(|(_, r)| r.outcome.clone().err())
            .unwrap_or_default();
        return Err(ExciteError::NoDesign {
            starts: outcomes.len(),
            last,
        });
    };
    let best_point = &outcomes[best_start].0;
    let trajectory = layout.trajectory(best_point)?;
    let constraint = pose.as_ref().map(|p| p.report(best_point)).transpose()?;
    let assessment = assess(
        regressor,
        projection,
        &trajectory,
        settings.criterion_points,
    )?;
    let margins = Margins::measure(
        &trajectory,
        &settings.limits,
        10 * settings.constraint_points,
    );
    Ok(Design {
        trajectory,
        criterion: settings.criterion,
        value: assessment.value(settings.criterion),
        condition_number: assessment.condition_number,
        assessment,
        margins,
        constraint,
        best_start,
        starts: outcomes.into_iter().map(|(_, r)| r).collect(),
        elapsed: started.elapsed(),
    })
}

/// Scales the motion of every coordinate by `s` about the box centre.
fn scale_motion(cons: &GridConstraints, p: &mut [f64], s: f64) {
    let w = cons.grid.layout.per_coord();
    for i in 0..cons.grid.layout.coords {
        let c = 0.5 * (cons.lo[3 * i * cons.grid.len()] + cons.hi[3 * i * cons.grid.len()]);
        let b = &mut p[i * w..(i + 1) * w];
        b[0] = c + s * (b[0] - c);
        b[1..].iter_mut().for_each(|v| *v *= s);
    }
}

/// One start: ALM/PANOC from `p`, then exact repair onto the tightened
/// bounds (and into the pose constraint).
fn run_start<R: Regressor, C: PoseConstraint, D: Dim>(
    regressor: &R,
    projection: &DMatrix<f64>,
    settings: &DesignSettings<D>,
    cons: &GridConstraints,
    pose: Option<&PoseGrid<'_, C>>,
    grid: &Grid,
    mut p: Vec<f64>,
) -> (Vec<f64>, StartReport)
where
    DefaultAllocator: Allocator<D>,
{
    let t0 = Instant::now();
    let limits = &settings.limits;
    let ev = RefCell::new(Evaluator::new(
        regressor,
        projection,
        settings.criterion,
        grid.len(),
        Some((
            limits.min.as_slice().to_vec(),
            limits.max.as_slice().to_vec(),
        )),
    ));
    let failure: RefCell<Option<ExciteError>> = RefCell::new(None);
    let mut report = StartReport {
        initial_value: f64::NAN,
        outcome: Err(String::new()),
        converged: false,
        outer_iterations: 0,
        inner_iterations: 0,
        repair_scale: 1.0,
        constraint_scale: 1.0,
        time: Duration::ZERO,
    };
    let value_at = |p: &[f64]| ev.borrow_mut().objective(grid, p).map(|a| a.assessment);
    match value_at(&p) {
        Ok(a) => report.initial_value = a.value(settings.criterion),
        Err(e) => {
            report.outcome = Err(with_causes(&e));
            report.time = t0.elapsed();
            return (p, report);
        }
    }

    let record = |e: ExciteError| {
        *failure.borrow_mut() = Some(e);
        SolverError::Cost("criterion evaluation failed")
    };
    let f = |u: &[f64], cost: &mut f64| -> FunctionCallResult {
        *cost = ev
            .borrow_mut()
            .objective(grid, u)
            .map_err(record)?
            .objective;
        Ok(())
    };
    let df = |u: &[f64], grad: &mut [f64]| -> FunctionCallResult {
        ev.borrow_mut().gradient(grid, u, grad).map_err(record)?;
        Ok(())
    };
    // F1 = [X, Ẋ, Ẍ on the grid (box blocks); g(X) on the grid].
    let nb = cons.len();
    let f1 = |u: &[f64], out: &mut [f64]| -> FunctionCallResult {
        cons.map(u, &mut out[..nb]);
        if let Some(pose) = pose {
            pose.map(&cons.grid, u, &mut out[nb..]).map_err(record)?;
        }
        Ok(())
    };
    let jf1t = |u: &[f64], d: &[f64], out: &mut [f64]| -> FunctionCallResult {
        cons.jacobian_t(&d[..nb], out);
        if let Some(pose) = pose {
            pose.add_jacobian_t(&cons.grid, u, &d[nb..], out)
                .map_err(record)?;
        }
        Ok(())
    };

    let dim = p.len();
    let gn = pose.map_or(0, |c| c.values() * cons.grid.len());
    let n1 = nb + gn;
    let (mut c_lo, mut c_hi) = (cons.lo.clone(), cons.hi.clone());
    if let Some(pose) = pose {
        c_lo.resize(n1, f64::NEG_INFINITY);
        c_hi.resize(n1, -pose.settings.margin);
    }
    let w = cons.grid.layout.per_coord();
    let (mut umin, mut umax) = (vec![0.0; dim], vec![0.0; dim]);
    for i in 0..limits.coordinates() {
        let v = 2.0 * limits.max_rate[i];
        for m in 0..w {
            let k = i * w + m;
            (umin[k], umax[k]) = if m == 0 {
                (limits.min[i], limits.max[i])
            } else {
                (-v, v)
            };
        }
    }
    let bounds = Rectangle::new(Some(&umin), Some(&umax));
    let set_c = Rectangle::new(Some(&c_lo), Some(&c_hi));
    let ymax = vec![1e12; n1];
    let ymin = vec![-1e12; n1];
    let set_y = Rectangle::new(Some(&ymin), Some(&ymax));
    let factory = AlmFactory::new(
        f,
        df,
        Some(f1),
        Some(jf1t),
        NO_MAPPING,
        NO_JACOBIAN_MAPPING,
        Some(set_c),
        0,
    );
    let problem = AlmProblem::new(
        bounds,
        Some(set_c),
        Some(set_y),
        |u: &[f64], xi: &[f64], cost: &mut f64| -> FunctionCallResult { factory.psi(u, xi, cost) },
        |u: &[f64], xi: &[f64], grad: &mut [f64]| -> FunctionCallResult {
            factory.d_psi(u, xi, grad)
        },
        Some(f1),
        NO_MAPPING,
        n1,
        0,
    );
    let mut cache = AlmCache::new(PANOCCache::new(dim, settings.tolerance, 10), n1, 0);
    let mut opt = AlmOptimizer::new(&mut cache, problem)
        .with_delta_tolerance(settings.infeasibility_tolerance)
        .with_epsilon_tolerance(settings.tolerance)
        .with_max_outer_iterations(settings.max_outer_iterations)
        .with_max_inner_iterations(settings.max_inner_iterations)
        .with_initial_penalty(10.0)
        .with_penalty_update_factor(5.0)
        .with_initial_inner_tolerance(1e-2);
    if let Some(t) = settings.max_time_per_start {
        opt = opt.with_max_duration(t);
    }
    let start = p.clone();
    match opt.solve(&mut p) {
        Ok(status) => {
            report.converged = status.exit_status() == ExitStatus::Converged;
            report.outer_iterations = status.num_outer_iterations();
            report.inner_iterations = status.num_inner_iterations();
        }
        Err(e) => {
            let why = failure
                .borrow_mut()
                .take()
                .map(|e| with_causes(&e))
                .unwrap_or_else(|| e.to_string());
            report.outcome = Err(format!("optimiser stopped: {why}"));
            report.time = t0.elapsed();
            return (start, report);
        }
    }
    if p.iter().any(|v| !v.is_finite()) {
        report.outcome = Err("optimiser returned a non-finite point".into());
        report.time = t0.elapsed();
        return (start, report);
    }
    report.repair_scale = cons.scale_to_fit(&mut p, false, false);
    if let Some(pose) = pose {
        match pose.fit(&mut p, 1.0) {
            Ok(s) => report.constraint_scale = s,
            Err(e) => {
                report.outcome = Err(with_causes(&e));
                report.time = t0.elapsed();
                return (start, report);
            }
        }
    }
    report.outcome = value_at(&p)
        .map(|a| a.value(settings.criterion))
        .map_err(|e| with_causes(&e));
    report.time = t0.elapsed();
    (p, report)
}
