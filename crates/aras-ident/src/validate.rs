//! Validation (`docs/validation.md`): fitness (78), mass-matrix positive definiteness over
//! the workspace, and parameter errors against a known truth.

use std::fmt::Display;

use faer::{Col, MatRef};
use rayon::prelude::*;
use serde::Serialize;

use crate::dense::symmetric_eigenvalues;
use crate::error::IdentError;
use crate::groups::RowGroups;

/// Predicted torques `W β`.
pub fn predict(w: MatRef<'_, f64>, beta: &[f64]) -> Result<Vec<f64>, IdentError> {
    if beta.len() != w.ncols() {
        return Err(IdentError::DimensionMismatch {
            what: "parameter vector for the regressor",
            expected: w.ncols(),
            found: beta.len(),
            hint: "give one parameter per regressor column",
        });
    }
    let b = Col::from_fn(beta.len(), |i| beta[i]);
    let y = crate::linalg::product(w, b.as_mat());
    Ok((0..y.nrows()).map(|i| y[(i, 0)]).collect())
}

/// NRMSE fitness (78) in percent:
/// `100 (1 − ‖τ_meas − τ_est‖ / ‖τ_meas − mean(τ_meas)‖)`.
/// 100 is a perfect fit, 0 is no better than the mean, negative is worse.
pub fn fitness(measured: &[f64], estimated: &[f64]) -> Result<f64, IdentError> {
    fitness_group(measured, estimated, 0)
}

fn fitness_group(measured: &[f64], estimated: &[f64], group: usize) -> Result<f64, IdentError> {
    if measured.len() != estimated.len() {
        return Err(IdentError::DimensionMismatch {
            what: "estimated torques",
            expected: measured.len(),
            found: estimated.len(),
            hint: "compare torques sample by sample",
        });
    }
    let mut sums = FitnessSums::default();
    for (m, e) in measured.iter().zip(estimated) {
        sums.push(*m, *e);
    }
    sums.fitness(group)
}

/// The sums behind [`fitness`], added sample by sample: the fitness of a
/// record read in pieces, in constant memory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FitnessSums {
    n: usize,
    /// The first measured value: the sums are of `τ_meas − shift`, so the
    /// variance does not cancel against a large mean.
    shift: Option<f64>,
    sum: f64,
    sum_sq: f64,
    error_sq: f64,
    /// The first non-finite sample: (index, is it the measured one, value).
    non_finite: Option<(usize, bool, f64)>,
}

impl FitnessSums {
    /// Adds one measured torque and its estimate.
    pub fn push(&mut self, measured: f64, estimated: f64) {
        if self.non_finite.is_none() {
            if !measured.is_finite() {
                self.non_finite = Some((self.n, true, measured));
            } else if !estimated.is_finite() {
                self.non_finite = Some((self.n, false, estimated));
            }
        }
        let y = measured - *self.shift.get_or_insert(measured);
        self.sum += y;
        self.sum_sq += y * y;
        self.error_sq += (measured - estimated) * (measured - estimated);
        self.n += 1;
    }

    /// Samples added.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Adds the samples of `other` (sums of another piece of the same
    /// record, e.g. from another thread): the result is that of pushing
    /// them here, up to rounding. `other`'s first non-finite sample counts
    /// only when this one has none (its row index is then `other`'s own).
    pub fn merge(&mut self, other: &FitnessSums) {
        let Some(theirs) = other.shift else {
            return;
        };
        if self.non_finite.is_none() {
            self.non_finite = other.non_finite;
        }
        let ours = *self.shift.get_or_insert(theirs);
        // `other`'s values are `y − theirs`; here they are `y − ours`.
        let d = theirs - ours;
        let n = other.n as f64;
        self.sum_sq += other.sum_sq + 2.0 * d * other.sum + n * d * d;
        self.sum += other.sum + n * d;
        self.error_sq += other.error_sq;
        self.n += other.n;
    }

    /// Fitness (78) in percent of the samples added; `group` names the row
    /// group (joint) in the error for a constant signal.
    pub fn fitness(&self, group: usize) -> Result<f64, IdentError> {
        if let Some((row, is_measured, value)) = self.non_finite {
            return Err(IdentError::NonFinite {
                what: if is_measured {
                    "measured torques"
                } else {
                    "estimated torques"
                },
                row,
                column: 0,
                name: String::new(),
                value,
            });
        }
        fitness_from_sums(self.error_sq, self.sum, self.sum_sq, self.n, group)
    }
}

/// Fitness (78) in percent from the residual sum of squares `rss` and the
/// measured signal's `n` values through their sum and sum of squares
/// (about any constant: the spread does not depend on it), for routes that
/// hold sums rather than samples (an accumulated Gram matrix or QR
/// factor): `100 (1 − √rss / √(Σy² − (Σy)²/n))`. `group` names the row
/// group (joint) in the error for a constant signal.
pub fn fitness_from_sums(
    rss: f64,
    sum: f64,
    sum_sq: f64,
    n: usize,
    group: usize,
) -> Result<f64, IdentError> {
    let den = (sum_sq - sum * sum / (n as f64).max(1.0)).max(0.0).sqrt();
    if n == 0 || den == 0.0 {
        return Err(IdentError::ConstantSignal { group, len: n });
    }
    Ok(100.0 * (1.0 - rss.max(0.0).sqrt() / den))
}

/// Fitness (78) for each row group (joint) of stacked torques.
pub fn fitness_per_group(
    measured: &[f64],
    estimated: &[f64],
    groups: &RowGroups,
) -> Result<Vec<f64>, IdentError> {
    groups.check_rows(measured.len())?;
    (0..groups.n_groups())
        .map(|g| {
            let (m, e): (Vec<f64>, Vec<f64>) = groups
                .labels()
                .iter()
                .zip(measured.iter().zip(estimated))
                .filter(|(l, _)| **l == g)
                .map(|(_, (m, e))| (*m, *e))
                .unzip();
            fitness_group(&m, &e, g)
        })
        .collect()
}

/// Where to test positive definiteness: a box in the robot's coordinates
/// (e.g. the workspace (77)), a grid and random points.
#[derive(Debug, Clone, PartialEq)]
pub struct PdRegion<const D: usize> {
    /// Lower corner.
    pub lower: [f64; D],
    /// Upper corner.
    pub upper: [f64; D],
    /// Grid points per axis (corners included); `grid_per_axis^D` points.
    pub grid_per_axis: usize,
    /// Uniform random points in the box, in addition to the grid.
    pub random: usize,
    /// Seed of the counter-based generator: the same seed gives the same points.
    pub seed: u64,
}

impl<const D: usize> PdRegion<D> {
    /// A box with the defaults: 101 points per axis when `D = 2` (10 201
    /// grid points) and 100 000 random points, seed 0.
    pub fn new(lower: [f64; D], upper: [f64; D]) -> Self {
        Self {
            lower,
            upper,
            grid_per_axis: if D <= 2 { 101 } else { 11 },
            random: 100_000,
            seed: 0,
        }
    }

    fn grid_points(&self) -> usize {
        if self.grid_per_axis == 0 {
            0
        } else {
            self.grid_per_axis.pow(D as u32)
        }
    }

    /// Total number of points tested.
    pub fn n_points(&self) -> usize {
        self.grid_points() + self.random
    }

    /// The `i`-th test point (`i < n_points()`): grid points first.
    pub fn point(&self, i: usize) -> [f64; D] {
        let mut x = [0.0; D];
        let g = self.grid_points();
        if i < g {
            let mut k = i;
            let n = self.grid_per_axis;
            for d in 0..D {
                let idx = k % n;
                k /= n;
                let u = if n == 1 {
                    0.5
                } else {
                    idx as f64 / (n - 1) as f64
                };
                x[d] = self.lower[d] + u * (self.upper[d] - self.lower[d]);
            }
        } else {
            let j = (i - g) as u64;
            for d in 0..D {
                let u = uniform(self.seed, j.wrapping_mul(D as u64).wrapping_add(d as u64));
                x[d] = self.lower[d] + u * (self.upper[d] - self.lower[d]);
            }
        }
        x
    }
}

/// SplitMix64 finaliser of `(seed, counter)`: a counter-based uniform in
/// [0, 1), so parallel workers draw the same points in any order.
fn uniform(seed: u64, counter: u64) -> f64 {
    let mut z = seed ^ counter.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Result of a positive-definiteness scan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PdReport<const D: usize> {
    /// Points tested.
    pub points: usize,
    /// Smallest eigenvalue found.
    pub min_eigenvalue: f64,
    /// Where it occurs.
    #[serde(skip)]
    pub argmin: [f64; D],
    /// Largest eigenvalue found.
    pub max_eigenvalue: f64,
    /// Where it occurs.
    #[serde(skip)]
    pub argmax: [f64; D],
    /// Points whose smallest eigenvalue is ≤ 0.
    pub non_positive: usize,
    /// Points where the callback failed or returned a non-finite matrix.
    pub failures: usize,
    /// The first failure (lowest point index) and its message.
    #[serde(skip)]
    pub first_failure: Option<([f64; D], String)>,
    /// Largest `|M_ij − M_ji| / max|M|` seen (the matrix should be symmetric).
    pub max_asymmetry: f64,
}

impl<const D: usize> PdReport<D> {
    /// True when every point was evaluated and every matrix was positive definite.
    pub fn positive_definite(&self) -> bool {
        self.failures == 0 && self.non_positive == 0 && self.points > 0
    }
}

#[derive(Clone)]
struct Acc<const D: usize> {
    min: (f64, usize),
    max: (f64, usize),
    non_positive: usize,
    failures: usize,
    first_failure: Option<(usize, String)>,
    asym: f64,
}

impl<const D: usize> Acc<D> {
    fn empty() -> Self {
        Self {
            min: (f64::INFINITY, usize::MAX),
            max: (f64::NEG_INFINITY, usize::MAX),
            non_positive: 0,
            failures: 0,
            first_failure: None,
            asym: 0.0,
        }
    }
    fn merge(mut self, o: Self) -> Self {
        // Ties broken by point index, so the result does not depend on
        // how rayon split the work.
        if o.min.0 < self.min.0 || (o.min.0 == self.min.0 && o.min.1 < self.min.1) {
            self.min = o.min;
        }
        if o.max.0 > self.max.0 || (o.max.0 == self.max.0 && o.max.1 < self.max.1) {
            self.max = o.max;
        }
        self.non_positive += o.non_positive;
        self.failures += o.failures;
        self.first_failure = match (self.first_failure, o.first_failure) {
            (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
            (a, b) => a.or(b),
        };
        self.asym = self.asym.max(o.asym);
        self
    }
}

/// Scans a `D × D` matrix function (e.g. the mass matrix (80) of an
/// identified parameter set) over `region` in parallel and reports the
/// eigenvalue extremes and where they occur. The callback may fail (e.g. a
/// point the kinematics cannot reach); failures are counted and the first is
/// reported, never skipped silently. Allocation-free per point.
pub fn check_positive_definite<const D: usize, F, E>(f: F, region: &PdRegion<D>) -> PdReport<D>
where
    F: Fn(&[f64; D]) -> Result<[[f64; D]; D], E> + Sync,
    E: Display,
{
    let n = region.n_points();
    let acc = (0..n)
        .into_par_iter()
        .fold(Acc::<D>::empty, |mut acc, i| {
            let x = region.point(i);
            match f(&x) {
                Ok(m) if m.iter().flatten().all(|v| v.is_finite()) => {
                    let ev = symmetric_eigenvalues(&m);
                    let scale = m.iter().flatten().fold(0.0_f64, |a, v| a.max(v.abs()));
                    if scale > 0.0 {
                        for r in 0..D {
                            for c in r + 1..D {
                                acc.asym = acc.asym.max((m[r][c] - m[c][r]).abs() / scale);
                            }
                        }
                    }
                    if ev[0] < acc.min.0 || (ev[0] == acc.min.0 && i < acc.min.1) {
                        acc.min = (ev[0], i);
                    }
                    if ev[D - 1] > acc.max.0 || (ev[D - 1] == acc.max.0 && i < acc.max.1) {
                        acc.max = (ev[D - 1], i);
                    }
                    if ev[0] <= 0.0 {
                        acc.non_positive += 1;
                    }
                }
                Ok(_) => {
                    acc.failures += 1;
                    if acc.first_failure.as_ref().is_none_or(|(j, _)| i < *j) {
                        acc.first_failure = Some((i, "non-finite matrix entry".to_owned()));
                    }
                }
                Err(e) => {
                    acc.failures += 1;
                    if acc.first_failure.as_ref().is_none_or(|(j, _)| i < *j) {
                        acc.first_failure = Some((i, e.to_string()));
                    }
                }
            }
            acc
        })
        .reduce(Acc::<D>::empty, Acc::merge);
    let at = |i: usize| {
        if i < n {
            region.point(i)
        } else {
            [f64::NAN; D]
        }
    };
    PdReport {
        points: n,
        min_eigenvalue: acc.min.0,
        argmin: at(acc.min.1),
        max_eigenvalue: acc.max.0,
        argmax: at(acc.max.1),
        non_positive: acc.non_positive,
        failures: acc.failures,
        first_failure: acc.first_failure.map(|(i, s)| (region.point(i), s)),
        max_asymmetry: acc.asym,
    }
}

/// One parameter's error against a known truth.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterError {
    /// Parameter name.
    pub name: String,
    /// Estimated value.
    pub estimate: f64,
    /// True value.
    pub truth: f64,
    /// `estimate − truth`.
    pub error: f64,
    /// `(estimate − truth) / σ`; infinite if σ = 0 and the error is not.
    pub in_sigma: f64,
}

/// Errors of an estimate against the truth, absolute and in units of the
/// estimated standard deviation (simulated data).
pub fn parameter_errors<S: AsRef<str>>(
    names: &[S],
    estimate: &[f64],
    std_dev: &[f64],
    truth: &[f64],
) -> Result<Vec<ParameterError>, IdentError> {
    let n = names.len();
    for (what, v) in [
        ("estimate", estimate),
        ("standard deviations", std_dev),
        ("truth", truth),
    ] {
        if v.len() != n {
            return Err(IdentError::DimensionMismatch {
                what: "parameter vector for the error table",
                expected: n,
                found: v.len(),
                hint: match what {
                    "estimate" => "the estimate needs one value per name",
                    "truth" => "the truth needs one value per name",
                    _ => "the standard deviations need one value per name",
                },
            });
        }
    }
    Ok((0..n)
        .map(|i| {
            let error = estimate[i] - truth[i];
            let in_sigma = if error == 0.0 {
                0.0
            } else {
                error / std_dev[i]
            };
            ParameterError {
                name: names[i].as_ref().to_owned(),
                estimate: estimate[i],
                truth: truth[i],
                error,
                in_sigma,
            }
        })
        .collect())
}
