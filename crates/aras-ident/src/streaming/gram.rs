//! Blocked normal equations: the Gram matrix `[W | T]ᵀ[W | T]` summed block
//! by block, turned into a triangular factor at the end, with a check of
//! the accuracy this costs.
//!
//! Why: the per-block QR was two thirds of the streaming stage's time
//! (faer's blocked Householder QR of a 2048 × 24 block: 490 µs); a Gram
//! update `AᵀA` is one matrix product (53 µs, 44 GFlop/s). The price is accuracy: forming `AᵀA` squares the
//! condition number, so the estimate's relative error grows from about
//! `κ ε` (QR) to about `κ² ε` (`κ` of the column-scaled regressor). The
//! check [`GramCheck`] measures `κ` on the final factor and says when the QR
//! accumulation ([`Accumulation::Qr`]) should be used instead.

use faer::{Mat, MatRef};
use serde::Serialize;

use crate::error::IdentError;

/// How a streaming least-squares problem is accumulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum Accumulation {
    /// Blocked normal equations (default): per block one Gram update
    /// `G += AᵀA` (compensated summation across blocks), one factorisation
    /// at the end. About 2× faster than [`Accumulation::Qr`]; relative error
    /// of the estimate ≈ `κ² ε`, checked by [`GramCheck`].
    #[default]
    Gram,
    /// Incremental QR (TSQR): per block a Householder QR merged into a
    /// running factor. Relative error ≈ `κ ε` whatever the conditioning.
    Qr,
}

/// Largest accepted `κ² ε` of a Gram-accumulated problem (`κ` ≤ 6.7e4).
///
/// `κ² ε` is a worst-case order of the relative error the normal equations
/// add; measured on the ARAS base regressor it overestimates 20–700×
/// (`κ` = 4.5e3…2.8e4, bound 5e-9…2e-7, actual difference to in-memory QR
/// 1.5e-10…4.6e-10; docs/scale.md). 1e-6 relative is at most 1 % of the
/// estimates' statistical standard errors on realistic logs (≥ 1e-4
/// relative), so the normal equations cost nothing that matters below it;
/// above it use [`Accumulation::Qr`] (relative error `κ ε`).
pub const GRAM_ERROR_LIMIT: f64 = 1e-6;

/// The accuracy check of a problem accumulated as normal equations
/// ([`Accumulation::Gram`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GramCheck {
    /// 2-norm condition number `κ` of the column-scaled regressor
    /// (`W D⁻¹`, `D` = column norms; columns that are zero everywhere are
    /// left out), from the final factor.
    pub condition: f64,
    /// `κ² ε`: the order of the relative error the normal equations add to
    /// the estimate (`ε` = `f64::EPSILON`).
    pub error_bound: f64,
    /// The accepted bound ([`GRAM_ERROR_LIMIT`]).
    pub limit: f64,
    /// `error_bound ≤ limit`. If false, rerun with [`Accumulation::Qr`].
    pub passed: bool,
}

impl GramCheck {
    /// The check of the upper-triangular factor `r` (`b × b`, `RᵀR = WᵀW`).
    pub(crate) fn of_factor(r: MatRef<'_, f64>) -> Self {
        let b = r.ncols();
        let norms: Vec<f64> = (0..b)
            .map(|j| (0..=j).map(|i| r[(i, j)] * r[(i, j)]).sum::<f64>().sqrt())
            .collect();
        let cols: Vec<usize> = (0..b).filter(|&j| norms[j] > 0.0).collect();
        let scaled = Mat::from_fn(cols.len(), cols.len(), |i, j| {
            let (ci, cj) = (cols[i], cols[j]);
            r[(ci, cj)] / norms[cj]
        });
        let condition = match crate::linalg::singular_values(scaled.as_ref()) {
            Ok(s) if !s.is_empty() => {
                let (hi, lo) = (s[0], s[s.len() - 1]);
                if lo > 0.0 { hi / lo } else { f64::INFINITY }
            }
            _ => f64::INFINITY,
        };
        let error_bound = condition * condition * f64::EPSILON;
        Self {
            condition,
            error_bound,
            limit: GRAM_ERROR_LIMIT,
            passed: error_bound <= GRAM_ERROR_LIMIT,
        }
    }

    /// An error saying the check failed and what to do, `None` if it passed.
    pub fn error(&self) -> Option<IdentError> {
        (!self.passed).then_some(IdentError::InvalidSetting {
            name: "accumulation (normal equations)",
            value: self.condition,
            reason: "the column-scaled regressor's condition number κ is so large that the \
                     normal equations may lose more than 1e-6 relative accuracy (κ²ε > 1e-6); \
                     accumulate with Accumulation::Qr (CLI: --accumulation qr)",
        })
    }
}

/// A running Gram matrix (lower triangle) with Neumaier compensation across
/// blocks, and the scratch for one block's product: no allocation per block.
#[derive(Debug, Clone)]
pub(crate) struct GramSum {
    sum: Mat<f64>,
    comp: Mat<f64>,
    block: Mat<f64>,
}

impl GramSum {
    /// Zero `c × c` Gram.
    pub(crate) fn new(c: usize) -> Self {
        Self {
            sum: Mat::zeros(c, c),
            comp: Mat::zeros(c, c),
            block: Mat::zeros(c, c),
        }
    }

    /// A running Gram starting from the symmetric `g` (its lower triangle).
    pub(crate) fn from_value(g: MatRef<'_, f64>) -> Self {
        let c = g.ncols();
        Self {
            sum: Mat::from_fn(c, c, |i, j| if i >= j { g[(i, j)] } else { 0.0 }),
            comp: Mat::zeros(c, c),
            block: Mat::zeros(c, c),
        }
    }

    /// `G += AᵀA` for a block `a` (`rows × c`): one matrix product (faer), then a compensated addition, so the error of the sum
    /// over any number of blocks stays that of a single block's product.
    pub(crate) fn add(&mut self, a: MatRef<'_, f64>) {
        // The full product, though only the lower triangle is used: faer's
        // triangular-destination product was 2.4× slower at this shape
        // (2048 × 24: 129 µs vs 53 µs, 44 GFlop/s).
        crate::linalg::gram_into(self.block.as_mut(), a);
        let c = self.sum.ncols();
        for j in 0..c {
            for i in j..c {
                self.add_entry(i, j, self.block[(i, j)]);
            }
        }
    }

    /// `G[i, j] += x` with Neumaier compensation.
    fn add_entry(&mut self, i: usize, j: usize, x: f64) {
        let s = self.sum[(i, j)];
        let t = s + x;
        self.comp[(i, j)] += if s.abs() >= x.abs() {
            (s - t) + x
        } else {
            (x - t) + s
        };
        self.sum[(i, j)] = t;
    }

    /// `G += AᵀA` for a block whose other columns are zero: `a` holds
    /// columns `cols` (increasing) of it, so only their products are
    /// formed.
    pub(crate) fn add_columns(&mut self, a: MatRef<'_, f64>, cols: &[usize]) {
        let k = cols.len();
        crate::linalg::gram_into(self.block.as_mut().submatrix_mut(0, 0, k, k), a);
        for (q, &j) in cols.iter().enumerate() {
            for (p, &i) in cols.iter().enumerate().skip(q) {
                self.add_entry(i, j, self.block[(p, q)]);
            }
        }
    }

    /// `G += AᵀA` for a block given transposed (`at`: `c × rows`).
    pub(crate) fn add_transposed(&mut self, at: MatRef<'_, f64>) {
        self.add(at.transpose());
    }

    /// Adds another running Gram of the same size (compensated), e.g. the
    /// sums of another thread's share of the rows.
    pub(crate) fn absorb(&mut self, other: &GramSum) {
        let c = self.sum.ncols();
        for j in 0..c {
            for i in j..c {
                for x in [other.sum[(i, j)], other.comp[(i, j)]] {
                    self.add_entry(i, j, x);
                }
            }
        }
    }

    /// The accumulated Gram as a full symmetric matrix (sum plus its
    /// compensation).
    pub(crate) fn value(&self) -> Mat<f64> {
        let c = self.sum.ncols();
        Mat::from_fn(c, c, |i, j| {
            let (i, j) = if i >= j { (i, j) } else { (j, i) };
            self.sum[(i, j)] + self.comp[(i, j)]
        })
    }

    /// True if every accumulated entry is finite.
    pub(crate) fn is_finite(&self) -> bool {
        let c = self.sum.ncols();
        (0..c).all(|j| (j..c).all(|i| (self.sum[(i, j)] + self.comp[(i, j)]).is_finite()))
    }

    /// An upper-triangular `c × c` factor `R` with `RᵀR = G` up to rounding
    /// of the Gram itself.
    ///
    /// How: columns are equilibrated (`G̃ = D⁻¹GD⁻¹`, unit diagonal), `G̃ =
    /// V Λ Vᵀ` (faer's symmetric eigensolver), negative eigenvalues (rounding
    /// of an exactly singular Gram, e.g. exact data, where the residual
    /// column depends on the others) are clamped to 0, and the square
    /// factor `Λ^½ Vᵀ D` is made triangular by a Householder QR. Unlike a
    /// Cholesky factorisation this never fails and never drops a column: the
    /// change is at most the clamped eigenvalues, `O(ε)` relative to the
    /// column norms, the same order as the Gram's own rounding.
    pub(crate) fn factor(&self) -> Mat<f64> {
        let c = self.sum.ncols();
        let g = |i: usize, j: usize| {
            let (i, j) = if i >= j { (i, j) } else { (j, i) };
            self.sum[(i, j)] + self.comp[(i, j)]
        };
        let d: Vec<f64> = (0..c)
            .map(|j| {
                let v = g(j, j).max(0.0).sqrt();
                if v > 0.0 { v } else { 1.0 }
            })
            .collect();
        let scaled = Mat::from_fn(c, c, |i, j| g(i, j) / (d[i] * d[j]));
        let mut data = vec![0.0; c * c];
        match crate::linalg::symmetric_eigen(scaled.as_ref()) {
            Ok((u, s)) => {
                // Row k of F = sqrt(λ_k) v_kᵀ D, column-major.
                for j in 0..c {
                    for k in 0..c {
                        let lam = s[k].max(0.0).sqrt();
                        data[j * c + k] = lam * u[(j, k)] * d[j];
                    }
                }
            }
            // The eigensolver did not converge (not seen in practice): a
            // NaN factor, which the accumulator reports as non-finite
            // instead of returning a wrong estimate.
            Err(_) => data.iter_mut().for_each(|v| *v = f64::NAN),
        }
        crate::dense::HouseholderQr::new(data, c, c).r()
    }
}
