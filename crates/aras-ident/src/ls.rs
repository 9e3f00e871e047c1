//! Ordinary and weighted least squares (62)–(66) through one QR.
//!
//! The stacked base regressor and the torques are factorised together (a
//! tall-skinny QR: blocks of rows in parallel, in cache),
//! `[W_b | T] = Q [[R, z], [0, ρ]]`, never through the normal equations
//! (which would square the condition number). Everything follows from the
//! small factor: `β̂ = R⁻¹ z`, the residual norm `|ρ|`, the covariance
//! `σ²_ρ R⁻¹R⁻ᵀ`, the singular values of `W_b` (those of `R`), and the
//! physically consistent problem's objective
//! `‖W_b K β − T‖² = ‖R K β − z‖² + ρ²` ([`ReducedLs`]), whose size no longer
//! depends on the number of samples.

use faer::{Mat, MatRef};
use serde::Serialize;

use crate::base::DEFAULT_RANK_TOLERANCE;
use crate::error::{IdentError, check_finite_mat, check_finite_vec};
use crate::groups::RowGroups;
use crate::rank::analyse;

/// A least-squares problem `min ‖W_b x − T‖` reduced to its `b × b` factor.
#[derive(Debug, Clone)]
pub struct ReducedLs {
    names: Vec<String>,
    r: Mat<f64>,
    z: Vec<f64>,
    rss: f64,
    rows: usize,
}

impl ReducedLs {
    /// Reduces `min ‖W x − T‖` (`w`: rows = samples, one named column per
    /// unknown).
    pub fn new<S: AsRef<str>>(
        w: MatRef<'_, f64>,
        t: &[f64],
        names: &[S],
    ) -> Result<Self, IdentError> {
        Self::build(w, t, names, None)
    }

    /// Reduces the weighted problem `min Σ_i (w_i (W x − T)_i)²` with one
    /// weight per row (e.g. `1/σ_joint`).
    pub fn weighted<S: AsRef<str>>(
        w: MatRef<'_, f64>,
        t: &[f64],
        names: &[S],
        row_weights: &[f64],
    ) -> Result<Self, IdentError> {
        PositiveList {
            what: "row weights",
            name: "row weight",
            hint: "give one weight per regressor row",
            reason: "weights must be positive (1/σ of the row's noise)",
        }
        .check(row_weights, w.nrows())?;
        Self::build(w, t, names, Some(row_weights))
    }

    fn build<S: AsRef<str>>(
        w: MatRef<'_, f64>,
        t: &[f64],
        names: &[S],
        weights: Option<&[f64]>,
    ) -> Result<Self, IdentError> {
        let names: Vec<String> = names.iter().map(|s| s.as_ref().to_owned()).collect();
        let (m, b) = (w.nrows(), w.ncols());
        if names.len() != b {
            return Err(IdentError::DimensionMismatch {
                what: "parameter names for the regressor's columns",
                expected: b,
                found: names.len(),
                hint: "give exactly one name per regressor column",
            });
        }
        if t.len() != m {
            return Err(IdentError::DimensionMismatch {
                what: "torque vector T",
                expected: m,
                found: t.len(),
                hint: "stack the torques in the same row order as the regressor",
            });
        }
        if b == 0 {
            return Err(IdentError::NoExcitation {
                what: "least squares",
                rows: m,
            });
        }
        if m <= b {
            return Err(IdentError::TooFewRows {
                what: "least squares",
                rows: m,
                columns: b,
                needed: b + 1,
            });
        }
        check_finite_mat("regressor", w, &names)?;
        check_finite_vec("torque vector T", t)?;
        // Tall-skinny QR of [W | T] (rows scaled by the weights), block by
        // block in cache and in parallel; see `dense::compress_with`.
        let raug = crate::dense::compress_with(m, b + 1, |start, mut blk| {
            let rows = blk.nrows();
            blk.as_mut()
                .subcols_mut(0, b)
                .copy_from(w.subrows(start, rows));
            for i in 0..rows {
                blk[(i, b)] = t[start + i];
            }
            if let Some(v) = weights {
                for j in 0..=b {
                    let mut col = blk.as_mut().col_mut(j);
                    for i in 0..rows {
                        col[i] *= v[start + i];
                    }
                }
            }
        });
        let r = Mat::from_fn(b, b, |i, j| raug[(i, j)]);
        let z = (0..b).map(|i| raug[(i, b)]).collect();
        let rss = raug[(b, b)] * raug[(b, b)];
        Ok(Self {
            names,
            r,
            z,
            rss,
            rows: m,
        })
    }

    /// A reduced problem from an already accumulated augmented factor
    /// `R_aug` (`(b+1) × (b+1)`, upper triangular, `R_augᵀR_aug = [W|T]ᵀ[W|T]`)
    /// over `rows` stacked rows: the result of a streaming (incremental) QR,
    /// see [`crate::streaming`]. The caller guarantees the shape and
    /// finiteness (checked in debug builds).
    pub(crate) fn from_factor(names: Vec<String>, r_aug: MatRef<'_, f64>, rows: usize) -> Self {
        let b = names.len();
        debug_assert_eq!((r_aug.nrows(), r_aug.ncols()), (b + 1, b + 1));
        Self {
            r: Mat::from_fn(b, b, |i, j| if i <= j { r_aug[(i, j)] } else { 0.0 }),
            z: (0..b).map(|i| r_aug[(i, b)]).collect(),
            rss: r_aug[(b, b)] * r_aug[(b, b)],
            rows,
            names,
        }
    }

    /// Column names (the unknowns).
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// The `b × b` upper-triangular factor `R` (`RᵀR = W_bᵀW_b`).
    pub fn r(&self) -> MatRef<'_, f64> {
        self.r.as_ref()
    }
    /// `z = Qᵀ T` (first `b` entries).
    pub fn z(&self) -> &[f64] {
        &self.z
    }
    /// Smallest achievable residual sum of squares `ρ² = ‖T − W_b β̂‖²`.
    pub fn min_rss(&self) -> f64 {
        self.rss
    }
    /// Number of stacked rows.
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// Residual sum of squares `‖W x − T‖² = ‖R x − z‖² + ρ²` of any `x`.
    pub fn rss(&self, x: &[f64]) -> Result<f64, IdentError> {
        if x.len() != self.names.len() {
            return Err(IdentError::DimensionMismatch {
                what: "parameter vector",
                expected: self.names.len(),
                found: x.len(),
                hint: "give one value per regressor column",
            });
        }
        let b = x.len();
        let extra: f64 = (0..b)
            .map(|i| {
                let v: f64 = (i..b).map(|j| self.r[(i, j)] * x[j]).sum::<f64>() - self.z[i];
                v * v
            })
            .sum();
        Ok(extra + self.rss)
    }

    /// Ordinary least squares (63)–(66) with the default rank tolerance.
    pub fn ols(&self) -> Result<OlsEstimate, IdentError> {
        self.ols_with_tolerance(DEFAULT_RANK_TOLERANCE)
    }

    /// Ordinary least squares (63)–(66). Fails with
    /// [`IdentError::NotExcited`], naming the columns, when the data do not
    /// determine every unknown (relative rank tolerance `tol`, see
    /// [`crate::DEFAULT_RANK_TOLERANCE`]).
    pub fn ols_with_tolerance(&self, tol: f64) -> Result<OlsEstimate, IdentError> {
        let b = self.names.len();
        let a = analyse(self.r.as_ref(), tol);
        if a.independent.len() < b {
            let mut lost: Vec<usize> = a.dependent.iter().chain(&a.zero).copied().collect();
            lost.sort_unstable();
            return Err(IdentError::NotExcited {
                lost_names: lost.iter().map(|&j| self.names[j].clone()).collect(),
                lost,
                rank: a.independent.len(),
                total: b,
                tolerance: tol,
            });
        }
        let mut beta = self.z.clone();
        crate::dense::solve_upper(self.r.as_ref(), &mut beta);
        let dof = self.rows - b;
        let var = self.rss / dof as f64;
        let rinv = crate::dense::inverse_upper(self.r.as_ref());
        let covariance = Mat::from_fn(b, b, |i, j| {
            var * (i.max(j)..b)
                .map(|k| rinv[(i, k)] * rinv[(j, k)])
                .sum::<f64>()
        });
        let std_dev: Vec<f64> = (0..b).map(|i| covariance[(i, i)].sqrt()).collect();
        let rel_std_percent = beta
            .iter()
            .zip(&std_dev)
            .map(|(x, s)| 100.0 * s / x.abs())
            .collect();
        let mut singular_values = crate::linalg::singular_values(self.r.as_ref())?;
        singular_values.sort_by(|x, y| y.total_cmp(x));
        let condition_number = singular_values[0] / singular_values[b - 1];
        Ok(OlsEstimate {
            names: self.names.clone(),
            estimate: beta,
            std_dev,
            rel_std_percent,
            residual_variance: var,
            residual_norm: self.rss.sqrt(),
            dof,
            singular_values,
            condition_number,
            covariance,
        })
    }
}

/// An OLS (or WLS) estimate with its uncertainty, (63)–(66).
#[derive(Debug, Clone, Serialize)]
pub struct OlsEstimate {
    /// Parameter names.
    pub names: Vec<String>,
    /// `β̂ = W† T` (63).
    pub estimate: Vec<f64>,
    /// `σ_β̂i = sqrt((σ²_ρ (WᵀW)⁻¹)_ii)` (64).
    pub std_dev: Vec<f64>,
    /// `σ%_i = 100 σ_β̂i / |β̂_i|` (65); infinite for an estimate of exactly 0.
    pub rel_std_percent: Vec<f64>,
    /// `σ²_ρ = ‖T − Wβ̂‖² / (r − c)` (66).
    pub residual_variance: f64,
    /// `‖T − Wβ̂‖`.
    pub residual_norm: f64,
    /// Degrees of freedom `r − c`.
    pub dof: usize,
    /// Singular values of the (weighted) regressor, descending.
    pub singular_values: Vec<f64>,
    /// `σ_max / σ_min` of the (weighted) regressor.
    pub condition_number: f64,
    /// Covariance `σ²_ρ (WᵀW)⁻¹`.
    #[serde(skip)]
    pub covariance: Mat<f64>,
}

impl OlsEstimate {
    /// Makes the uncertainty honest for data whose noise was low-pass
    /// filtered (e.g. the zero-phase filter of parallel filtering) before the
    /// fit; `noise_gain` is the filter's noise power gain `g = Σ h_k²`
    /// (`robot::noise_gain`).
    ///
    /// (64)–(66) assume white residuals. Filtering white noise of variance
    /// `σ²` leaves variance `g σ²`, correlated over about `1/g` samples, so
    /// the residual variance underestimates `σ²` by `g` while the data hold
    /// only about `g·rows` independent samples. When the regressor's content
    /// lies inside the pass band (the filter leaves `W` unchanged), the true
    /// covariance is `σ² (WᵀW)⁻¹` with `σ² = σ²_ρ / g`: the covariance is
    /// divided by `g`, standard deviations and σ% by `√g`, and
    /// `residual_variance` becomes the estimated pre-filter variance.
    /// Period averaging needs no correction (it keeps the noise white).
    pub fn with_filtered_noise(mut self, noise_gain: f64) -> Result<Self, IdentError> {
        if !(noise_gain.is_finite() && noise_gain > 0.0 && noise_gain <= 1.0) {
            return Err(IdentError::InvalidSetting {
                name: "filter noise gain",
                value: noise_gain,
                reason: "must lie in (0, 1]: Σ h_k² of a low-pass filter's impulse response",
            });
        }
        let s = noise_gain.sqrt();
        self.residual_variance /= noise_gain;
        self.std_dev.iter_mut().for_each(|v| *v /= s);
        self.rel_std_percent.iter_mut().for_each(|v| *v /= s);
        let b = self.covariance.nrows();
        for j in 0..b {
            for i in 0..b {
                self.covariance[(i, j)] /= noise_gain;
            }
        }
        Ok(self)
    }
}

/// OLS on a stacked base regressor `w_b` and torques `t`: a shortcut for
/// [`ReducedLs::new`] followed by [`ReducedLs::ols`].
pub fn ols<S: AsRef<str>>(
    w_b: MatRef<'_, f64>,
    t: &[f64],
    names: &[S],
) -> Result<OlsEstimate, IdentError> {
    ReducedLs::new(w_b, t, names)?.ols()
}

/// Per-joint noise variances for weighted least squares.
#[derive(Debug, Clone, PartialEq)]
pub enum NoiseVariances {
    /// Known variances, one per row group (N²·m²).
    Known(Vec<f64>),
    /// Estimated from the per-joint residuals of a first OLS pass (iterate once).
    FromResiduals,
}

/// A weighted least-squares estimate.
#[derive(Debug, Clone)]
pub struct WlsEstimate {
    /// The estimate; its uncertainty is (64)–(66) applied to the weighted
    /// system, so it stays right even if the variances are only right up
    /// to a common factor (`residual_variance` ≈ 1 when they are exact).
    pub estimate: OlsEstimate,
    /// The per-group variances used.
    pub variances: Vec<f64>,
    /// The first, unweighted pass (when the variances were estimated).
    pub first_pass: Option<OlsEstimate>,
    /// The weighted reduced problem (input of the physically consistent SDP).
    pub reduced: ReducedLs,
}

/// Weighted least squares with per-joint noise variances: rows of group `g`
/// are scaled by `1/σ_g`. With [`NoiseVariances::FromResiduals`], `σ²_g` is
/// the first OLS pass's residual sum of squares over group `g` divided by its
/// share of the degrees of freedom, `n_g (1 − b/N)`; a group that fits
/// exactly gets a floor of 1e-12 of the largest variance (if all fit exactly,
/// the weights are uniform).
pub fn wls<S: AsRef<str>>(
    w_b: MatRef<'_, f64>,
    t: &[f64],
    names: &[S],
    groups: &RowGroups,
    noise: NoiseVariances,
) -> Result<WlsEstimate, IdentError> {
    groups.check_rows(w_b.nrows())?;
    let ng = groups.n_groups();
    let (variances, first_pass) = match noise {
        NoiseVariances::Known(v) => (checked_variances(v, ng)?, None),
        NoiseVariances::FromResiduals => {
            let first = ReducedLs::new(w_b, t, names)?.ols()?;
            let res = crate::validate::predict(w_b, &first.estimate)?;
            let mut ss = vec![0.0; ng];
            for (i, (&ti, &pi)) in t.iter().zip(&res).enumerate() {
                ss[groups.labels()[i]] += (ti - pi) * (ti - pi);
            }
            let v = variances_from_rss(&ss, groups.counts(), w_b.nrows(), w_b.ncols());
            (v, Some(first))
        }
    };
    let weights: Vec<f64> = groups
        .labels()
        .iter()
        .map(|&g| 1.0 / variances[g].sqrt())
        .collect();
    let reduced = ReducedLs::weighted(w_b, t, names, &weights)?;
    let estimate = reduced.ols()?;
    Ok(WlsEstimate {
        estimate,
        variances,
        first_pass,
        reduced,
    })
}

/// A caller-given list that needs one finite, positive value per item
/// (row weights, group weights, noise variances); the names go into the
/// error messages.
pub(crate) struct PositiveList {
    /// The list, plural (e.g. "row weights").
    pub what: &'static str,
    /// One item, singular (e.g. "row weight").
    pub name: &'static str,
    /// How to give the right number of values.
    pub hint: &'static str,
    /// Why the values must be positive.
    pub reason: &'static str,
}

impl PositiveList {
    /// Errors on a wrong length, a non-finite or a non-positive value.
    pub(crate) fn check(&self, values: &[f64], expected: usize) -> Result<(), IdentError> {
        if values.len() != expected {
            return Err(IdentError::DimensionMismatch {
                what: self.what,
                expected,
                found: values.len(),
                hint: self.hint,
            });
        }
        check_finite_vec(self.what, values)?;
        if let Some(i) = values.iter().position(|&x| x <= 0.0) {
            return Err(IdentError::InvalidSetting {
                name: self.name,
                value: values[i],
                reason: self.reason,
            });
        }
        Ok(())
    }
}

/// Per-group noise variances from the first pass's residual sums of squares
/// `ss` (group `g` has `counts[g]` of the `n` rows, `b` unknowns): each
/// divided by its share of the degrees of freedom, floored at 1e-12 of the
/// largest so a noise-free group keeps a finite weight (all 1 if every sum
/// is zero). Shared by the in-memory and the streaming WLS.
pub(crate) fn variances_from_rss(ss: &[f64], counts: &[usize], n: usize, b: usize) -> Vec<f64> {
    let (n, b) = (n as f64, b as f64);
    let mut v: Vec<f64> = ss
        .iter()
        .zip(counts)
        .map(|(s, &c)| s / (c as f64 * (1.0 - b / n)))
        .collect();
    let vmax = v.iter().copied().fold(0.0, f64::max);
    if vmax == 0.0 {
        v.iter_mut().for_each(|x| *x = 1.0);
    } else {
        v.iter_mut().for_each(|x| *x = x.max(1e-12 * vmax));
    }
    v
}

/// Validates caller-given per-group noise variances: one per group, finite
/// and positive (shared by the in-memory and streaming WLS).
pub(crate) fn checked_variances(v: Vec<f64>, groups: usize) -> Result<Vec<f64>, IdentError> {
    PositiveList {
        what: "noise variances",
        name: "noise variance",
        hint: "give one variance per row group (joint)",
        reason: "variances must be positive",
    }
    .check(&v, groups)?;
    Ok(v)
}
