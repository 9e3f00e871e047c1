//! Small dense least squares on tall column sets: Householder QR (never the
//! normal equations) and bounded least squares by an active set.

/// Householder QR of a tall matrix stored as columns, with the triangular
/// factor and the transformed right-hand side.
pub(crate) struct Qr {
    /// Upper-triangular factor, `r[j][i]` for `i ≤ j` (column-major rows).
    r: Vec<Vec<f64>>,
    /// `Qᵀ y`, first `p` entries.
    qty: Vec<f64>,
    /// Column scale factors (columns are equilibrated to unit norm).
    scale: Vec<f64>,
}

/// Relative size of a diagonal entry of `R` (columns at unit norm) below
/// which a column counts as dependent on the others.
pub(crate) const RANK_TOL: f64 = 1e-10;

impl Qr {
    /// Factors the columns `a` (each of length n) together with `y`.
    pub(crate) fn new(a: &[&[f64]], y: &[f64]) -> Self {
        let p = a.len();
        let n = y.len();
        let mut scale = Vec::with_capacity(p);
        let mut cols: Vec<Vec<f64>> = a
            .iter()
            .map(|c| {
                let nrm = c.iter().map(|x| x * x).sum::<f64>().sqrt();
                let s = if nrm > 0.0 { 1.0 / nrm } else { 1.0 };
                scale.push(s);
                c.iter().map(|x| x * s).collect()
            })
            .collect();
        let mut b = y.to_vec();
        for j in 0..p.min(n) {
            // Householder vector for column j, rows j..n.
            let (head, tail) = cols.split_at_mut(j + 1);
            let cj = &mut head[j];
            let alpha = cj[j..].iter().map(|x| x * x).sum::<f64>().sqrt();
            if alpha == 0.0 {
                continue;
            }
            let alpha = if cj[j] > 0.0 { -alpha } else { alpha };
            cj[j] -= alpha;
            let vnorm2 = cj[j..].iter().map(|x| x * x).sum::<f64>();
            if vnorm2 == 0.0 {
                cj[j] = alpha;
                continue;
            }
            let apply = |x: &mut [f64], v: &[f64]| {
                let d: f64 = x[j..].iter().zip(&v[j..]).map(|(a, b)| a * b).sum();
                let f = 2.0 * d / vnorm2;
                for (xi, vi) in x[j..].iter_mut().zip(&v[j..]) {
                    *xi -= f * vi;
                }
            };
            for ck in tail.iter_mut() {
                apply(ck, cj);
            }
            apply(&mut b, cj);
            cj[j] = alpha;
        }
        let r: Vec<Vec<f64>> = cols.iter().map(|c| c[..p.min(n)].to_vec()).collect();
        let qty = b[..p.min(n)].to_vec();
        Self { r, qty, scale }
    }

    /// Whether column `j` is independent of the columns before it.
    fn rdiag_ok(&self, j: usize) -> bool {
        let d = self.r[j].get(j).copied().unwrap_or(0.0);
        d.abs() > RANK_TOL
    }

    /// Unconstrained solution; `None` if the columns are dependent.
    pub(crate) fn solve(&self) -> Option<Vec<f64>> {
        let p = self.r.len();
        if p > self.qty.len() || !(0..p).all(|j| self.rdiag_ok(j)) {
            return None;
        }
        let mut x = vec![0.0; p];
        for i in (0..p).rev() {
            let mut s = self.qty[i];
            for k in i + 1..p {
                s -= self.r[k][i] * x[k];
            }
            x[i] = s / self.r[i][i];
        }
        Some(x.iter().zip(&self.scale).map(|(x, s)| x * s).collect())
    }

    /// Diagonal of `(AᵀA)⁻¹` (unscaled columns); `None` if dependent.
    pub(crate) fn inverse_gram_diagonal(&self) -> Option<Vec<f64>> {
        let p = self.r.len();
        if p > self.qty.len() || !(0..p).all(|j| self.rdiag_ok(j)) {
            return None;
        }
        // (RᵀR)⁻¹ = R⁻¹ R⁻ᵀ: diagonal = row norms² of R⁻¹.
        let mut rinv = vec![vec![0.0; p]; p]; // rinv[i][j], upper
        for j in 0..p {
            rinv[j][j] = 1.0 / self.r[j][j];
            for i in (0..j).rev() {
                let mut s = 0.0;
                for k in i + 1..=j {
                    s += self.r[k][i] * rinv[k][j];
                }
                rinv[i][j] = -s / self.r[i][i];
            }
        }
        Some(
            (0..p)
                .map(|i| {
                    let d: f64 = (i..p).map(|j| rinv[i][j] * rinv[i][j]).sum();
                    d * self.scale[i] * self.scale[i]
                })
                .collect(),
        )
    }
}

/// Least squares `min ‖A x − y‖` with `lower ≤ x ≤ upper` (infinite bounds
/// allowed) by an active set: solve for the free variables by QR, step back
/// to the feasible set when a bound is crossed, release a bound when the
/// gradient points inside. Returns `None` if the free columns are dependent.
pub(crate) fn bounded_lstsq(
    a: &[&[f64]],
    y: &[f64],
    lower: &[f64],
    upper: &[f64],
) -> Option<(Vec<f64>, f64)> {
    let p = a.len();
    let n = y.len();
    let mut x: Vec<f64> = (0..p).map(|j| 0.0f64.clamp(lower[j], upper[j])).collect();
    // free[j]: not held at a bound. Unbounded variables start free; bounded
    // ones too, and are pinned only when a step would cross their bound.
    let mut free = vec![true; p];
    for _ in 0..(4 * p + 10) {
        // Solve for the free variables with the pinned ones moved to the rhs.
        let mut rhs = y.to_vec();
        for j in (0..p).filter(|&j| !free[j]) {
            if x[j] != 0.0 {
                for (r, c) in rhs.iter_mut().zip(a[j]) {
                    *r -= x[j] * c;
                }
            }
        }
        let idx: Vec<usize> = (0..p).filter(|&j| free[j]).collect();
        let cols: Vec<&[f64]> = idx.iter().map(|&j| a[j]).collect();
        let s = if cols.is_empty() {
            Vec::new()
        } else {
            Qr::new(&cols, &rhs).solve()?
        };
        // Step from x towards s, stopping at the first bound crossed.
        let mut alpha = 1.0f64;
        let mut hit = None;
        for (k, &j) in idx.iter().enumerate() {
            let target = s[k];
            if target < lower[j] {
                let a = (x[j] - lower[j]) / (x[j] - target);
                if a < alpha {
                    alpha = a;
                    hit = Some(j);
                }
            } else if target > upper[j] {
                let a = (upper[j] - x[j]) / (target - x[j]);
                if a < alpha {
                    alpha = a;
                    hit = Some(j);
                }
            }
        }
        for (k, &j) in idx.iter().enumerate() {
            x[j] += alpha.max(0.0) * (s[k] - x[j]);
        }
        if let Some(j) = hit {
            x[j] = if s[idx.iter().position(|&i| i == j).unwrap_or(0)] < lower[j] {
                lower[j]
            } else {
                upper[j]
            };
            free[j] = false;
            continue;
        }
        // Optimal on the free set: release a pinned variable whose gradient
        // points into the feasible box.
        let resid: Vec<f64> = (0..n)
            .map(|i| y[i] - (0..p).map(|j| a[j][i] * x[j]).sum::<f64>())
            .collect();
        let mut best: Option<(usize, f64)> = None;
        for j in (0..p).filter(|&j| !free[j]) {
            let norm = a[j].iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
            let g: f64 = a[j].iter().zip(&resid).map(|(c, r)| c * r).sum::<f64>() / norm;
            let inward = if x[j] <= lower[j] { g } else { -g };
            if inward > 1e-12 * resid.iter().map(|r| r * r).sum::<f64>().sqrt()
                && best.is_none_or(|(_, b)| inward > b)
            {
                best = Some((j, inward));
            }
        }
        match best {
            Some((j, _)) => free[j] = true,
            None => {
                let rss = resid.iter().map(|r| r * r).sum();
                return Some((x, rss));
            }
        }
    }
    let rss = (0..n)
        .map(|i| {
            let r = y[i] - (0..p).map(|j| a[j][i] * x[j]).sum::<f64>();
            r * r
        })
        .sum();
    Some((x, rss))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn columns(seed: u64, n: usize, p: usize) -> Vec<Vec<f64>> {
        (0..p)
            .map(|j| {
                (0..n)
                    .map(|i| ((i as f64 + 1.0) * (j as f64 + 1.3) * 0.731 + seed as f64).sin())
                    .collect()
            })
            .collect()
    }

    #[test]
    fn qr_solves_exact_system() {
        let a = columns(1, 50, 3);
        let x0 = [1.5, -2.0, 0.25];
        let mut y: Vec<f64> = (0..50)
            .map(|i| (0..3).map(|j| a[j][i] * x0[j]).sum())
            .collect();
        let refs: Vec<&[f64]> = a.iter().map(Vec::as_slice).collect();
        let x = Qr::new(&refs, &y).solve().unwrap();
        for (u, v) in x.iter().zip(x0) {
            assert!((u - v).abs() < 1e-12);
        }
        y[7] += 1.0;
        // Least-squares optimality: the residual is orthogonal to every column.
        let x = Qr::new(&refs, &y).solve().unwrap();
        let r: Vec<f64> = (0..50)
            .map(|i| y[i] - (0..3).map(|j| a[j][i] * x[j]).sum::<f64>())
            .collect();
        for c in &a {
            assert!(c.iter().zip(&r).map(|(c, r)| c * r).sum::<f64>().abs() < 1e-12);
        }
    }

    #[test]
    fn qr_detects_dependent_columns() {
        let a = columns(2, 30, 2);
        let c: Vec<f64> = a[0].iter().zip(&a[1]).map(|(x, y)| 2.0 * x - y).collect();
        let refs = vec![a[0].as_slice(), a[1].as_slice(), c.as_slice()];
        assert!(Qr::new(&refs, &a[0]).solve().is_none());
    }

    proptest! {
        /// The bounded solution satisfies the KKT conditions: feasible, zero
        /// gradient on free variables, gradient pointing outwards at bounds.
        #[test]
        fn bounded_lstsq_is_kkt_optimal(seed in 0u64..1000, y0 in prop::collection::vec(-3.0f64..3.0, 40)) {
            let a = columns(seed, 40, 4);
            let refs: Vec<&[f64]> = a.iter().map(Vec::as_slice).collect();
            let lower = [f64::NEG_INFINITY, 0.0, 0.0, -0.5];
            let upper = [f64::INFINITY, f64::INFINITY, 1.0, 0.5];
            let (x, rss) = bounded_lstsq(&refs, &y0, &lower, &upper).unwrap();
            let r: Vec<f64> = (0..40).map(|i| y0[i] - (0..4).map(|j| a[j][i] * x[j]).sum::<f64>()).collect();
            prop_assert!((r.iter().map(|v| v * v).sum::<f64>() - rss).abs() < 1e-9);
            for j in 0..4 {
                prop_assert!(x[j] >= lower[j] && x[j] <= upper[j]);
                let g: f64 = a[j].iter().zip(&r).map(|(c, r)| c * r).sum();
                // Tolerance: the QR solution's gradient is ~1e-13 for these
                // well-conditioned columns.
                if x[j] > lower[j] && x[j] < upper[j] {
                    prop_assert!(g.abs() < 1e-9, "free {j}: {g}");
                } else if x[j] == lower[j] {
                    prop_assert!(g < 1e-9, "at lower {j}: {g}");
                } else {
                    prop_assert!(g > -1e-9, "at upper {j}: {g}");
                }
            }
        }
    }
}
