//! Incremental QR of `[W | T]`: one running `(b+1) × (b+1)` factor per row
//! group, updated block by block (TSQR), so that any number of rows fits in
//! constant memory and the result is the same [`ReducedLs`] as in memory.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor::{qr_in_place_scratch, recommended_block_size};
use faer::{Mat, MatMut, MatRef, Par};

use crate::error::{IdentError, check_finite_mat, check_finite_vec};
use crate::ls::{NoiseVariances, OlsEstimate, ReducedLs, WlsEstimate};

/// Rows per block of [`QrAccumulator::push_rows`]: a 4096 × 24 block
/// (800 kB) is factorised in the L2 cache.
const PUSH_BLOCK_ROWS: usize = 4096;

/// Streaming least squares `min ‖W x − T‖`: rows arrive in blocks, each
/// block's QR factor is merged into a running factor (tall-skinny QR), and
/// only `(b+1)²` numbers per row group are kept.
///
/// Rows are kept per *group* (e.g. per joint) so that weighted least squares
/// with per-group weights, including weights estimated from the first pass's
/// per-group residuals ([`NoiseVariances::FromResiduals`]), needs one pass
/// over the data only: scaling group `g` by `w_g` scales its factor by `w_g`
/// exactly, and its residual `‖W_g x − T_g‖² = ‖R_g x − z_g‖² + ρ_g²`.
///
/// Accuracy: the result equals the in-memory [`ReducedLs`] to rounding
/// (orthogonal transformations only; tested to 1e-10 relative on the
/// estimates in `tests/streaming.rs`). The merge order is fixed by the
/// order of the calls, so a given sequence of blocks always gives
/// bit-identical results.
#[derive(Debug, Clone)]
pub struct QrAccumulator {
    names: Vec<String>,
    factors: Vec<Mat<f64>>,
    rows: Vec<usize>,
    gram_rows: usize,
}

impl QrAccumulator {
    /// An empty accumulator for the unknowns `names` (the base parameters)
    /// and `groups` row groups (≥ 1; 2 for the two joints).
    pub fn new<S: AsRef<str>>(names: &[S], groups: usize) -> Result<Self, IdentError> {
        if names.is_empty() {
            return Err(IdentError::NoExcitation {
                what: "streaming least squares (no unknowns)",
                rows: 0,
            });
        }
        if groups == 0 {
            return Err(IdentError::InvalidSetting {
                name: "row groups",
                value: 0.0,
                reason: "give at least one row group (one per joint)",
            });
        }
        let c = names.len() + 1;
        Ok(Self {
            names: names.iter().map(|s| s.as_ref().to_owned()).collect(),
            factors: vec![Mat::zeros(c, c); groups],
            rows: vec![0; groups],
            gram_rows: 0,
        })
    }

    /// Unknowns (column names).
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Number of row groups.
    pub fn n_groups(&self) -> usize {
        self.factors.len()
    }

    /// Rows accumulated, all groups.
    pub fn rows(&self) -> usize {
        self.rows.iter().sum()
    }

    /// Rows accumulated per group.
    pub fn group_rows(&self) -> &[usize] {
        &self.rows
    }

    /// The running augmented factor `[[R_g, z_g], [0, ρ_g]]` of group `g`.
    pub fn factor(&self, group: usize) -> Option<MatRef<'_, f64>> {
        self.factors.get(group).map(|m| m.as_ref())
    }

    fn check_group(&self, group: usize) -> Result<(), IdentError> {
        if group >= self.factors.len() {
            return Err(IdentError::IndexOutOfRange {
                what: "row group".into(),
                index: group,
                count: self.factors.len(),
            });
        }
        Ok(())
    }

    fn check_block(&self, group: usize, w: MatRef<'_, f64>, t: &[f64]) -> Result<(), IdentError> {
        self.check_group(group)?;
        let b = self.names.len();
        if w.ncols() != b {
            return Err(IdentError::DimensionMismatch {
                what: "regressor block columns",
                expected: b,
                found: w.ncols(),
                hint: "give one column per unknown, in the accumulator's order",
            });
        }
        if t.len() != w.nrows() {
            return Err(IdentError::DimensionMismatch {
                what: "torques of the block",
                expected: w.nrows(),
                found: t.len(),
                hint: "give one torque per regressor row",
            });
        }
        check_finite_mat("regressor block", w, &self.names)?;
        check_finite_vec("torques of the block", t)
    }

    /// Appends the rows `w` (one column per unknown) with torques `t` to
    /// group `group`. Any number of rows; pass blocks of many rows (a row
    /// at a time works but wastes the blocked QR). For per-sample robot
    /// data use [`super::RegressorStage`], which builds the blocks itself.
    pub fn push_rows(
        &mut self,
        group: usize,
        w: MatRef<'_, f64>,
        t: &[f64],
    ) -> Result<(), IdentError> {
        self.check_block(group, w, t)?;
        let b = self.names.len();
        let m = w.nrows();
        let mut qr = BlockQr::new(PUSH_BLOCK_ROWS.min(m.max(1)), b + 1);
        for start in (0..m).step_by(PUSH_BLOCK_ROWS) {
            let rows = PUSH_BLOCK_ROWS.min(m - start);
            let r = qr.factor(rows, |mut a| {
                a.as_mut()
                    .subcols_mut(0, b)
                    .copy_from(w.subrows(start, rows));
                for i in 0..rows {
                    a[(i, b)] = t[start + i];
                }
            });
            self.merge_factor(group, r, rows);
        }
        Ok(())
    }

    /// Like [`Self::push_rows`], but through the normal equations
    /// ([`super::Accumulation::Gram`]): the rows' Gram matrix is summed in
    /// blocks and factorised once, then merged. Faster for many rows, less
    /// accurate for ill-conditioned ones: see [`Self::gram_check`].
    pub fn push_rows_gram(
        &mut self,
        group: usize,
        w: MatRef<'_, f64>,
        t: &[f64],
    ) -> Result<(), IdentError> {
        self.check_block(group, w, t)?;
        let (m, b) = (w.nrows(), self.names.len());
        let mut gram = super::gram::GramSum::new(b + 1);
        let mut a = Mat::<f64>::zeros(PUSH_BLOCK_ROWS.min(m.max(1)), b + 1);
        for start in (0..m).step_by(PUSH_BLOCK_ROWS) {
            let rows = PUSH_BLOCK_ROWS.min(m - start);
            a.as_mut()
                .subrows_mut(0, rows)
                .subcols_mut(0, b)
                .copy_from(w.subrows(start, rows));
            for i in 0..rows {
                a[(i, b)] = t[start + i];
            }
            gram.add(a.as_ref().subrows(0, rows));
        }
        self.merge_gram(group, &gram, m);
        Ok(())
    }

    /// Merges the factor of a Gram sum of `rows` rows into group `group`.
    pub(crate) fn merge_gram(&mut self, group: usize, gram: &super::gram::GramSum, rows: usize) {
        let r = gram.factor();
        self.merge_factor(group, r.as_ref(), rows);
        self.gram_rows += rows;
    }

    /// Rows accumulated through the normal equations (all groups).
    pub fn gram_rows(&self) -> usize {
        self.gram_rows
    }

    /// The accuracy check of the normal equations (condition number of the
    /// column-scaled regressor of all groups, `κ² ε` against
    /// [`super::GRAM_ERROR_LIMIT`]); `None` if no row went through them.
    pub fn gram_check(&self) -> Option<super::GramCheck> {
        if self.gram_rows == 0 {
            return None;
        }
        let b = self.names.len();
        let mut r = Mat::<f64>::zeros(b + 1, b + 1);
        for f in &self.factors {
            let mut s = f.clone();
            merge_upper(r.as_mut(), s.as_mut());
        }
        Some(super::GramCheck::of_factor(
            r.as_ref().submatrix(0, 0, b, b),
        ))
    }

    /// Merges an upper-triangular `(b+1) × (b+1)` factor of `rows` rows into
    /// group `group` (caller checks shape and finiteness).
    pub(crate) fn merge_factor(&mut self, group: usize, r: MatRef<'_, f64>, rows: usize) {
        let mut s = r.to_owned();
        merge_upper(self.factors[group].as_mut(), s.as_mut());
        self.rows[group] += rows;
    }

    /// Adds everything `other` accumulated (same unknowns and groups), as if
    /// its rows had been pushed here.
    pub fn merge(&mut self, other: &QrAccumulator) -> Result<(), IdentError> {
        if other.names != self.names || other.factors.len() != self.factors.len() {
            return Err(IdentError::DimensionMismatch {
                what: "accumulator to merge (unknowns × groups)",
                expected: self.names.len() * self.factors.len(),
                found: other.names.len() * other.factors.len(),
                hint: "merge only accumulators built with the same names and groups",
            });
        }
        for g in 0..self.factors.len() {
            self.merge_factor(g, other.factors[g].as_ref(), other.rows[g]);
        }
        self.gram_rows += other.gram_rows;
        Ok(())
    }

    /// The reduced problem over all groups, unweighted: the same
    /// [`ReducedLs`] as `ReducedLs::new` on all rows in memory.
    pub fn reduced(&self) -> Result<ReducedLs, IdentError> {
        self.combine(&vec![1.0; self.factors.len()])
    }

    /// The reduced weighted problem, rows of group `g` scaled by
    /// `group_weights[g]` (e.g. `1/σ_g`): the same as `ReducedLs::weighted`
    /// in memory.
    pub fn reduced_weighted(&self, group_weights: &[f64]) -> Result<ReducedLs, IdentError> {
        crate::ls::PositiveList {
            what: "group weights",
            name: "group weight",
            hint: "give one weight per row group",
            reason: "weights must be positive (1/σ of the group's noise)",
        }
        .check(group_weights, self.factors.len())?;
        self.combine(group_weights)
    }

    fn combine(&self, weights: &[f64]) -> Result<ReducedLs, IdentError> {
        let b = self.names.len();
        let rows = self.rows();
        if rows <= b {
            return Err(IdentError::TooFewRows {
                what: "streaming least squares",
                rows,
                columns: b,
                needed: b + 1,
            });
        }
        let mut r = Mat::<f64>::zeros(b + 1, b + 1);
        for (f, &wg) in self.factors.iter().zip(weights) {
            let mut s = Mat::from_fn(b + 1, b + 1, |i, j| wg * f[(i, j)]);
            merge_upper(r.as_mut(), s.as_mut());
        }
        for j in 0..=b {
            for i in 0..=j {
                if !r[(i, j)].is_finite() {
                    return Err(IdentError::NonFinite {
                        what: "accumulated factor [R | z]",
                        row: i,
                        column: j,
                        name: self.names.get(j).cloned().unwrap_or_else(|| "T".into()),
                        value: r[(i, j)],
                    });
                }
            }
        }
        Ok(ReducedLs::from_factor(self.names.clone(), r.as_ref(), rows))
    }

    /// Residual sum of squares `‖W_g x − T_g‖²` of each group for the
    /// parameters `x`.
    pub fn group_rss(&self, x: &[f64]) -> Result<Vec<f64>, IdentError> {
        let b = self.names.len();
        if x.len() != b {
            return Err(IdentError::DimensionMismatch {
                what: "parameter vector",
                expected: b,
                found: x.len(),
                hint: "give one value per unknown",
            });
        }
        Ok(self
            .factors
            .iter()
            .map(|f| {
                let head: f64 = (0..b)
                    .map(|i| {
                        let v: f64 = (i..b).map(|j| f[(i, j)] * x[j]).sum::<f64>() - f[(i, b)];
                        v * v
                    })
                    .sum();
                head + f[(b, b)] * f[(b, b)]
            })
            .collect())
    }

    /// Ordinary least squares (63)–(66) over all groups.
    pub fn ols(&self) -> Result<OlsEstimate, IdentError> {
        self.reduced()?.ols()
    }

    /// Weighted least squares with per-group noise variances, exactly as
    /// [`crate::wls`] in memory (the same variance estimate from the first
    /// pass's per-group residuals, the same floor), in one pass over the
    /// data.
    pub fn wls(&self, noise: NoiseVariances) -> Result<WlsEstimate, IdentError> {
        let ng = self.factors.len();
        let (variances, first_pass) = match noise {
            NoiseVariances::Known(v) => (crate::ls::checked_variances(v, ng)?, None),
            NoiseVariances::FromResiduals => {
                let first = self.ols()?;
                let ss = self.group_rss(&first.estimate)?;
                let v =
                    crate::ls::variances_from_rss(&ss, &self.rows, self.rows(), self.names.len());
                (v, Some(first))
            }
        };
        let weights: Vec<f64> = variances.iter().map(|v| 1.0 / v.sqrt()).collect();
        let reduced = self.reduced_weighted(&weights)?;
        let estimate = reduced.ols()?;
        Ok(WlsEstimate {
            estimate,
            variances,
            first_pass,
            reduced,
        })
    }
}

/// Merges the upper-triangular `s` into the upper-triangular `r` (both
/// `c × c`) so that afterwards `rᵀr` equals the old `rᵀr + sᵀs`; `s` is
/// destroyed. Householder reflections on `[r_jj; s_0..=j,j]` column by
/// column (LAPACK `tpqrt` with a triangular second block): about `c³/3`
/// multiply-adds, no allocation, never skips a column (a zero column of
/// both stays zero), and a fixed operation order (deterministic).
pub(crate) fn merge_upper(mut r: MatMut<'_, f64>, mut s: MatMut<'_, f64>) {
    let c = r.ncols();
    for j in 0..c {
        let x0 = r[(j, j)];
        let mut sigma = 0.0;
        for i in 0..=j {
            sigma += s[(i, j)] * s[(i, j)];
        }
        if sigma == 0.0 {
            continue;
        }
        let norm = (x0 * x0 + sigma).sqrt();
        let beta = if x0 >= 0.0 { -norm } else { norm };
        let v0 = x0 - beta;
        let tau = (beta - x0) / beta;
        for i in 0..=j {
            s[(i, j)] /= v0;
        }
        r[(j, j)] = beta;
        for k in j + 1..c {
            let mut dot = r[(j, k)];
            for i in 0..=j {
                dot += s[(i, j)] * s[(i, k)];
            }
            let f = tau * dot;
            r[(j, k)] -= f;
            for i in 0..=j {
                let v = s[(i, j)];
                s[(i, k)] -= f * v;
            }
        }
        for i in 0..=j {
            s[(i, j)] = 0.0;
        }
    }
}

/// A reusable block factoriser: faer's blocked QR in preallocated storage
/// (no allocation per block), with the never-skipping Householder QR as the
/// fallback when faer reports a rank-deficient block (its factor is then a
/// staircase, not triangular).
pub(crate) struct BlockQr {
    a: Mat<f64>,
    h: Mat<f64>,
    mem: MemBuffer,
    r: Mat<f64>,
    bs: usize,
}

impl BlockQr {
    /// Storage for blocks of up to `max_rows` rows and `cols` columns.
    pub(crate) fn new(max_rows: usize, cols: usize) -> Self {
        let max_rows = max_rows.max(1);
        let bs = recommended_block_size::<f64>(max_rows, cols).max(1);
        let k = max_rows.min(cols);
        Self {
            a: Mat::zeros(max_rows, cols),
            h: Mat::zeros(bs, k),
            mem: MemBuffer::new(qr_in_place_scratch::<f64>(
                max_rows,
                cols,
                bs,
                Par::Seq,
                Default::default(),
            )),
            r: Mat::zeros(cols, cols),
            bs,
        }
    }

    /// The block matrix (`max_rows × cols`): fill the first rows, then call
    /// [`Self::factor_filled`].
    pub(crate) fn block_mut(&mut self) -> MatMut<'_, f64> {
        self.a.as_mut()
    }

    /// Factorises the first `rows` rows that `fill` writes; returns the
    /// `cols × cols` upper-triangular factor (zero rows below `rows`).
    pub(crate) fn factor<F: Fn(MatMut<'_, f64>)>(
        &mut self,
        rows: usize,
        fill: F,
    ) -> MatRef<'_, f64> {
        let cols = self.a.ncols();
        fill(self.a.as_mut().submatrix_mut(0, 0, rows, cols));
        self.factor_filled(rows, fill)
    }

    /// Like [`Self::factor`] with the block already filled; `refill` writes
    /// it again if faer's factorisation has to be redone.
    pub(crate) fn factor_filled<F: Fn(MatMut<'_, f64>)>(
        &mut self,
        rows: usize,
        refill: F,
    ) -> MatRef<'_, f64> {
        let cols = self.a.ncols();
        self.r.fill(0.0);
        // Columns that are exactly zero in this block (e.g. joint 2's
        // friction in joint 1's rows) are left out of faer's QR, which
        // would otherwise report a rank deficiency and force the slow
        // path; they contribute nothing to `AᵀA`.
        let mut keep = [0usize; 64];
        let mut kc = 0;
        if cols <= keep.len() {
            for j in 0..cols {
                if self
                    .a
                    .as_ref()
                    .col(j)
                    .subrows(0, rows)
                    .iter()
                    .any(|&v| v != 0.0)
                {
                    keep[kc] = j;
                    kc += 1;
                }
            }
        } else {
            kc = cols;
        }
        let compact = kc < cols;
        if compact {
            for p in 0..kc {
                if keep[p] != p {
                    let (src, dst) = (keep[p], p);
                    for i in 0..rows {
                        self.a[(i, dst)] = self.a[(i, src)];
                    }
                }
            }
        }
        let k = rows.min(kc);
        if k == 0 {
            return self.r.as_ref();
        }
        let rank = crate::linalg::householder_qr_in_place(
            self.a.as_mut().submatrix_mut(0, 0, rows, kc),
            self.h.as_mut().submatrix_mut(0, 0, self.bs, k),
            MemStack::new(&mut self.mem),
        );
        if rank == k {
            for q in 0..kc {
                for p in 0..=q.min(k - 1) {
                    let (i, j) = if compact { (keep[p], keep[q]) } else { (p, q) };
                    self.r[(i, j)] = self.a[(p, q)];
                }
            }
            return self.r.as_ref();
        }
        let k = rows.min(cols);
        {
            refill(self.a.as_mut().submatrix_mut(0, 0, rows, cols));
            let mut data = Vec::with_capacity(rows * cols);
            for j in 0..cols {
                data.extend((0..rows).map(|i| self.a[(i, j)]));
            }
            let r = crate::dense::HouseholderQr::new(data, rows, cols).r();
            for j in 0..cols {
                for i in 0..=j.min(k - 1) {
                    self.r[(i, j)] = r[(i, j)];
                }
            }
        }
        self.r.as_ref()
    }
}
