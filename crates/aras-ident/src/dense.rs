//! Small dense kernels that must behave predictably on rank-deficient input.
//!
//! faer's unpivoted QR skips columns it finds numerically dependent (its `R`
//! is then a staircase, not upper triangular), which is exactly the case the
//! base-parameter analysis lives in. So the rank analysis uses a plain
//! Householder QR that never skips a column (LAPACK `geqr2` semantics: a
//! zero column gets a zero diagonal), applied blockwise in parallel
//! ("tall-skinny QR") so that large stacked regressors stay fast. faer's fast
//! blocked QR factorises each block first; a block it reports as
//! rank-deficient is redone with the plain QR.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor::{qr_in_place_scratch, recommended_block_size};
use faer::{Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Householder QR of a column-major `m × n` matrix, stored in place: `R` in
/// the upper triangle, the reflectors' tails below it (unit leading entry
/// implied), and the reflector coefficients in `tau`.
pub(crate) struct HouseholderQr {
    a: Vec<f64>,
    tau: Vec<f64>,
    m: usize,
    n: usize,
}

impl HouseholderQr {
    /// Factorises the column-major data (length `m·n`).
    pub(crate) fn new(mut a: Vec<f64>, m: usize, n: usize) -> Self {
        debug_assert_eq!(a.len(), m * n);
        let k = m.min(n);
        let mut tau = vec![0.0; k];
        for j in 0..k {
            let (head, tail) = a.split_at_mut((j + 1) * m);
            let col = &mut head[j * m..];
            let x0 = col[j];
            let sigma: f64 = col[j + 1..].iter().map(|v| v * v).sum();
            if sigma == 0.0 {
                // Already upper triangular in this column: identity reflector.
                tau[j] = 0.0;
                continue;
            }
            let norm = (x0 * x0 + sigma).sqrt();
            let beta = if x0 >= 0.0 { -norm } else { norm };
            let v0 = x0 - beta;
            for v in &mut col[j + 1..] {
                *v /= v0;
            }
            tau[j] = (beta - x0) / beta;
            col[j] = beta;
            let v = &col[j + 1..];
            let t = tau[j];
            // Apply H = I − τ v vᵀ (v₀ = 1) to the remaining columns.
            tail.chunks_exact_mut(m).for_each(|c| {
                let dot = c[j] + v.iter().zip(&c[j + 1..]).map(|(a, b)| a * b).sum::<f64>();
                let s = t * dot;
                c[j] -= s;
                for (ci, vi) in c[j + 1..].iter_mut().zip(v) {
                    *ci -= s * vi;
                }
            });
        }
        Self { a, tau, m, n }
    }

    /// The `min(m, n) × n` upper-triangular factor.
    pub(crate) fn r(&self) -> Mat<f64> {
        let k = self.m.min(self.n);
        Mat::from_fn(
            k,
            self.n,
            |i, j| if i <= j { self.a[j * self.m + i] } else { 0.0 },
        )
    }

    /// Overwrites `x` (length `m`) with `Q x`.
    pub(crate) fn apply_q(&self, x: &mut [f64]) {
        for j in (0..self.tau.len()).rev() {
            self.reflect(j, x);
        }
    }

    fn reflect(&self, j: usize, x: &mut [f64]) {
        let t = self.tau[j];
        if t == 0.0 {
            return;
        }
        let v = &self.a[j * self.m + j + 1..(j + 1) * self.m];
        let dot = x[j] + v.iter().zip(&x[j + 1..]).map(|(a, b)| a * b).sum::<f64>();
        let s = t * dot;
        x[j] -= s;
        for (xi, vi) in x[j + 1..].iter_mut().zip(v) {
            *xi -= s * vi;
        }
    }
}

/// Rows per block of the tall-skinny QR: a 4096 × 24 block (800 kB) stays in
/// the L2 cache while it is factorised; one QR over the whole tall matrix
/// would stream it from memory once per column.
const TSQR_BLOCK_ROWS: usize = 4096;

/// Returns an upper-triangular `n × n` matrix `R` with `RᵀR = WᵀW` (to
/// rounding), for any `W` (rank-deficient allowed), without forming `WᵀW`.
pub(crate) fn compress(w: MatRef<'_, f64>) -> Mat<f64> {
    compress_with(w.nrows(), w.ncols(), |start, mut block| {
        let rows = block.nrows();
        block.copy_from(w.subrows(start, rows));
    })
}

/// Tall-skinny QR of an implicit `m × n` matrix whose rows `start..start+k`
/// `fill` writes into a `k × n` block: blocks are factorised in parallel
/// (faer's blocked QR, in cache; the never-skipping Householder QR when
/// faer reports a rank-deficient block, since its `R` is then a staircase),
/// their `R`s stacked and factorised again by the never-skipping QR.
pub(crate) fn compress_with<F>(m: usize, n: usize, fill: F) -> Mat<f64>
where
    F: Fn(usize, MatMut<'_, f64>) + Sync,
{
    let block = TSQR_BLOCK_ROWS.max(4 * n);
    let starts: Vec<usize> = (0..m).step_by(block.max(1)).collect();
    let rs: Vec<Mat<f64>> = starts
        .par_iter()
        .map(|&s| {
            let rows = block.min(m - s);
            let mut a = Mat::<f64>::zeros(rows, n);
            fill(s, a.as_mut());
            faer_block_r(a).unwrap_or_else(|| {
                // faer overwrote the block: fill it again for the plain QR.
                let mut a = Mat::<f64>::zeros(rows, n);
                fill(s, a.as_mut());
                plain_block_r(&a)
            })
        })
        .collect();
    let total: usize = rs.iter().map(Mat::nrows).sum();
    let stacked = if rs.len() == 1 {
        rs.into_iter().next().unwrap_or_else(|| Mat::zeros(0, n))
    } else {
        let mut data = Vec::with_capacity(total * n);
        for j in 0..n {
            for r in &rs {
                data.extend((0..r.nrows()).map(|i| r[(i, j)]));
            }
        }
        HouseholderQr::new(data, total, n).r()
    };
    // Pad to n × n so callers always get a square factor.
    Mat::from_fn(n, n, |i, j| {
        if i < stacked.nrows() {
            stacked[(i, j)]
        } else {
            0.0
        }
    })
}

/// `R` factor (`min(rows, n) × n`) of one block by faer's QR, or `None` if
/// faer skipped a column (its factor is then not upper triangular).
fn faer_block_r(mut a: Mat<f64>) -> Option<Mat<f64>> {
    let (rows, n) = (a.nrows(), a.ncols());
    let k = rows.min(n);
    if k == 0 {
        return Some(Mat::zeros(0, n));
    }
    let bs = recommended_block_size::<f64>(rows, n);
    let mut h = Mat::<f64>::zeros(bs, k);
    let mut mem = MemBuffer::new(qr_in_place_scratch::<f64>(
        rows,
        n,
        bs,
        Par::Seq,
        Default::default(),
    ));
    let rank =
        crate::linalg::householder_qr_in_place(a.as_mut(), h.as_mut(), MemStack::new(&mut mem));
    (rank == k).then(|| Mat::from_fn(k, n, |i, j| if i <= j { a[(i, j)] } else { 0.0 }))
}

/// `R` factor of one block by the never-skipping Householder QR.
fn plain_block_r(a: &Mat<f64>) -> Mat<f64> {
    let (rows, n) = (a.nrows(), a.ncols());
    let mut data = Vec::with_capacity(rows * n);
    for j in 0..n {
        data.extend((0..rows).map(|i| a[(i, j)]));
    }
    HouseholderQr::new(data, rows, n).r()
}

/// Solves `R x = b` in place for upper-triangular, non-singular `R` (`n × n`).
pub(crate) fn solve_upper(r: MatRef<'_, f64>, b: &mut [f64]) {
    let n = r.ncols();
    for i in (0..n).rev() {
        let mut s = b[i];
        for j in i + 1..n {
            s -= r[(i, j)] * b[j];
        }
        b[i] = s / r[(i, i)];
    }
}

/// Inverse of an upper-triangular, non-singular `n × n` matrix.
pub(crate) fn inverse_upper(r: MatRef<'_, f64>) -> Mat<f64> {
    let n = r.ncols();
    let mut inv = Mat::zeros(n, n);
    let mut e = vec![0.0; n];
    for j in 0..n {
        e.iter_mut().for_each(|v| *v = 0.0);
        e[j] = 1.0;
        solve_upper(r, &mut e);
        for i in 0..n {
            inv[(i, j)] = e[i];
        }
    }
    inv
}

/// Eigenvalues (ascending) of a small symmetric matrix by cyclic Jacobi
/// rotations; no allocation, so it can run per sample. Only the symmetric
/// part `(A + Aᵀ)/2` is used.
pub fn symmetric_eigenvalues<const D: usize>(a: &[[f64; D]; D]) -> [f64; D] {
    let mut m = [[0.0; D]; D];
    for i in 0..D {
        for j in 0..D {
            m[i][j] = 0.5 * (a[i][j] + a[j][i]);
        }
    }
    if D == 2 {
        // Closed form, the common case (2-DOF mass matrices in hot scans):
        // mean ± hypot(half-difference, off-diagonal), without cancellation
        // in the discriminant.
        let mean = 0.5 * (m[0][0] + m[1][1]);
        let r = (0.5 * (m[0][0] - m[1][1])).hypot(m[0][1]);
        let mut ev = [0.0; D];
        ev[0] = mean - r;
        ev[1] = mean + r;
        return ev;
    }
    let scale: f64 = m.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    if scale > 0.0 {
        // Jacobi converges quadratically: 30 sweeps are far more than enough
        // for D ≤ 10 to reach off-diagonal mass below 1e-15·‖A‖.
        for _ in 0..30 {
            let off: f64 = (0..D)
                .flat_map(|i| (0..D).filter(move |&j| j != i).map(move |j| (i, j)))
                .map(|(i, j)| m[i][j] * m[i][j])
                .sum::<f64>()
                .sqrt();
            if off <= 1e-15 * scale {
                break;
            }
            for p in 0..D {
                for q in p + 1..D {
                    let apq = m[p][q];
                    if apq == 0.0 {
                        continue;
                    }
                    let theta = (m[q][q] - m[p][p]) / (2.0 * apq);
                    let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                    let t = if theta == 0.0 { 1.0 } else { t };
                    let c = 1.0 / (t * t + 1.0).sqrt();
                    let s = t * c;
                    for k in 0..D {
                        let mkp = m[k][p];
                        let mkq = m[k][q];
                        m[k][p] = c * mkp - s * mkq;
                        m[k][q] = s * mkp + c * mkq;
                    }
                    for k in 0..D {
                        let mpk = m[p][k];
                        let mqk = m[q][k];
                        m[p][k] = c * mpk - s * mqk;
                        m[q][k] = s * mpk + c * mqk;
                    }
                }
            }
        }
    }
    let mut ev = [0.0; D];
    for i in 0..D {
        ev[i] = m[i][i];
    }
    ev.sort_by(f64::total_cmp);
    ev
}

impl HouseholderQr {
    /// Overwrites `x` (length `m`) with `Qᵀ x`.
    pub(crate) fn apply_qt(&self, x: &mut [f64]) {
        for j in 0..self.tau.len() {
            self.reflect(j, x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compress_matches_gram_on_rank_deficient() {
        // 5000 × 4 with column 2 = column 0 + column 1 and column 3 = 0:
        // RᵀR must equal WᵀW (relative 1e-12: a few hundred roundings).
        let w = Mat::from_fn(5000, 4, |i, j| {
            let a = ((i * 7 + 3) % 11) as f64 - 5.0;
            let b = ((i * 13 + 1) % 17) as f64 * 0.1;
            match j {
                0 => a,
                1 => b,
                2 => a + b,
                _ => 0.0,
            }
        });
        let r = compress(w.as_ref());
        let g1 = r.transpose() * &r;
        let g2 = w.transpose() * &w;
        let scale = g2.norm_max();
        assert!((&g1 - &g2).norm_max() <= 1e-12 * scale);
        for i in 0..4 {
            for j in 0..i {
                assert_eq!(r[(i, j)], 0.0);
            }
        }
    }

    #[test]
    fn jacobi_matches_closed_form_2x2() {
        let a = [[2.0, 1.0], [1.0, 3.0]];
        let ev = symmetric_eigenvalues(&a);
        let (tr, det) = (5.0_f64, 5.0_f64);
        let d = (tr * tr / 4.0 - det).sqrt();
        assert!((ev[0] - (tr / 2.0 - d)).abs() < 1e-14);
        assert!((ev[1] - (tr / 2.0 + d)).abs() < 1e-14);
    }

    #[test]
    fn apply_q_reconstructs() {
        let (m, n) = (7, 3);
        let data: Vec<f64> = (0..m * n).map(|k| ((k * 37 % 19) as f64) - 9.0).collect();
        let qr = HouseholderQr::new(data.clone(), m, n);
        let r = qr.r();
        for j in 0..n {
            let mut x = vec![0.0; m];
            for i in 0..n {
                x[i] = r[(i, j)];
            }
            qr.apply_q(&mut x);
            for i in 0..m {
                assert!((x[i] - data[j * m + i]).abs() < 1e-12);
            }
        }
    }
}
