//! Numerical rank and column dependencies, in the caller's column order.
//!
//! Works on any square factor `R` with `RᵀR = WᵀW` (from [`crate::dense::compress`]
//! or an OLS QR): the angles between `W`'s columns are those between `R`'s.
//! Columns are first scaled to unit norm, because regressor columns carry
//! different units (inertia, first moments, friction) and a rank test on
//! unscaled columns would mostly measure those units. Then each column, in
//! order, is kept if its distance to the span of the kept earlier ones (the
//! sine of the angle, i.e. the `|R_jj|` of a QR of the kept columns, relative
//! to the largest, which is 1) exceeds the tolerance. This mirrors the
//! reduced row echelon form of (58)–(61): the earliest column of each
//! dependent group is the one kept, so the caller's order decides which
//! standard parameter names each base parameter.

use faer::{Mat, MatRef};

/// Result of the column analysis.
pub(crate) struct ColumnAnalysis {
    /// Euclidean norm of each column of `W`.
    pub norms: Vec<f64>,
    /// Columns numerically zero (norm ≤ tol · largest norm).
    pub zero: Vec<usize>,
    /// Columns kept, in increasing order.
    pub independent: Vec<usize>,
    /// Non-zero columns that are combinations of earlier kept columns.
    pub dependent: Vec<usize>,
    /// For every column: sine of its angle to the span of the earlier kept
    /// columns (1 for the first kept column, 0 for zero columns).
    pub sines: Vec<f64>,
}

impl ColumnAnalysis {
    /// Smallest sine among the kept columns (how far from losing rank).
    pub(crate) fn smallest_kept(&self) -> f64 {
        self.independent
            .iter()
            .map(|&j| self.sines[j])
            .fold(f64::INFINITY, f64::min)
    }
    /// Largest sine among the dropped non-zero columns (how far from being kept).
    pub(crate) fn largest_dropped(&self) -> f64 {
        self.dependent
            .iter()
            .map(|&j| self.sines[j])
            .fold(0.0, f64::max)
    }
}

/// Analyses the columns of a factor `r` (`k × n`, `RᵀR = WᵀW`).
pub(crate) fn analyse(r: MatRef<'_, f64>, tol: f64) -> ColumnAnalysis {
    let (k, n) = (r.nrows(), r.ncols());
    let norms: Vec<f64> = (0..n)
        .map(|j| (0..k).map(|i| r[(i, j)] * r[(i, j)]).sum::<f64>().sqrt())
        .collect();
    let max_norm = norms.iter().copied().fold(0.0, f64::max);
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut out = ColumnAnalysis {
        norms: norms.clone(),
        zero: Vec::new(),
        independent: Vec::new(),
        dependent: Vec::new(),
        sines: vec![0.0; n],
    };
    for j in 0..n {
        if max_norm == 0.0 || norms[j] <= tol * max_norm {
            out.zero.push(j);
            continue;
        }
        let mut v: Vec<f64> = (0..k).map(|i| r[(i, j)] / norms[j]).collect();
        // Modified Gram–Schmidt, twice: one pass loses orthogonality when the
        // column is nearly dependent, which is the case that matters here.
        for _ in 0..2 {
            for q in &basis {
                let d: f64 = q.iter().zip(&v).map(|(a, b)| a * b).sum();
                v.iter_mut().zip(q).for_each(|(vi, qi)| *vi -= d * qi);
            }
        }
        let s = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        out.sines[j] = s.min(1.0);
        if s > tol {
            v.iter_mut().for_each(|x| *x /= s);
            basis.push(v);
            out.independent.push(j);
        } else {
            out.dependent.push(j);
        }
    }
    out
}

/// Coefficients `Γ` (`|S| × n`) with `W[:, j] = Σ_i Γ_ij W[:, S_i]` for every
/// column `j` (identity on `S`, zero on zero columns), by least squares on the
/// unit-norm columns of `r`. Coefficients below `clean` (relative, in the
/// unit-norm scaling) are rounding noise and set to exactly zero.
pub(crate) fn combinations(r: MatRef<'_, f64>, a: &ColumnAnalysis, clean: f64) -> Mat<f64> {
    let k = r.nrows();
    let s = &a.independent;
    let n = r.ncols();
    let mut gamma = Mat::zeros(s.len(), n);
    for (i, &j) in s.iter().enumerate() {
        gamma[(i, j)] = 1.0;
    }
    if a.dependent.is_empty() || s.is_empty() {
        return gamma;
    }
    // Least squares R̃_S γ = r̃_j via a (never-skipping) Householder QR of R̃_S.
    let mut data = Vec::with_capacity(k * s.len());
    for &j in s {
        data.extend((0..k).map(|i| r[(i, j)] / a.norms[j]));
    }
    let qr = crate::dense::HouseholderQr::new(data, k, s.len());
    let rs = qr.r();
    let rs = rs.as_ref().submatrix(0, 0, s.len(), s.len());
    for &j in &a.dependent {
        let mut rhs: Vec<f64> = (0..k).map(|i| r[(i, j)] / a.norms[j]).collect();
        qr.apply_qt(&mut rhs);
        rhs.truncate(s.len());
        crate::dense::solve_upper(rs, &mut rhs);
        for (i, &si) in s.iter().enumerate() {
            let g = rhs[i];
            // Undo the unit-norm scaling: W_j = Σ γ̃_i (‖W_j‖/‖W_si‖) W_si.
            gamma[(i, j)] = if g.abs() < clean {
                0.0
            } else {
                g * a.norms[j] / a.norms[si]
            };
        }
    }
    gamma
}
