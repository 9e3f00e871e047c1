//! The one place the aras crates call faer's dense kernels.
//!
//! Every function here returns with the CPU's vector unit in the state
//! scalar code runs fast in ([`crate::simd::clear_upper_state`] after the
//! kernel): faer's vectorised code can leave the upper halves of the AVX
//! registers dirty, which makes every later scalar `f64` instruction on the
//! thread several times slower (see [`crate::simd`]). Calling faer through
//! these functions means no caller can forget the clear; a unit test checks
//! that no other module of this crate calls faer's kernels directly, and the
//! XINUSE tests check the state after each function.

use faer::dyn_stack::MemStack;
use faer::linalg::matmul::matmul;
use faer::linalg::qr::no_pivoting::factor::qr_in_place;
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

use crate::simd::clear_upper_state;

/// A factorisation that did not converge (not seen in practice on finite
/// input; reported instead of a wrong result).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{what} did not converge; check the matrix for extreme scaling")]
pub struct NoConvergence {
    /// Which factorisation.
    pub what: &'static str,
}

/// The matrix product `a b`.
pub fn product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let m = a * b;
    clear_upper_state();
    m
}

/// `dst = aᵀ a` (the full `c × c` product of a `rows × c` block), in place,
/// single-threaded (the callers parallelise over blocks).
pub(crate) fn gram_into(dst: MatMut<'_, f64>, a: MatRef<'_, f64>) {
    matmul(dst, Accum::Replace, a.transpose(), a, 1.0, Par::Seq);
    clear_upper_state();
}

/// Thin singular value decomposition `a = U diag(s) Vᵀ`.
#[derive(Debug, Clone)]
pub struct Svd {
    /// Left singular vectors (`m × k`, `k = min(m, n)`).
    pub u: Mat<f64>,
    /// Singular values, non-increasing.
    pub s: Vec<f64>,
    /// Right singular vectors (`n × k`).
    pub v: Mat<f64>,
}

/// The thin SVD of `a`.
pub fn thin_svd(a: MatRef<'_, f64>) -> Result<Svd, NoConvergence> {
    let r = a.thin_svd();
    let out = r.map(|svd| Svd {
        u: svd.U().to_owned(),
        s: svd.S().column_vector().iter().copied().collect(),
        v: svd.V().to_owned(),
    });
    clear_upper_state();
    out.map_err(|_| NoConvergence { what: "SVD" })
}

/// The singular values of `a`, non-increasing.
pub fn singular_values(a: MatRef<'_, f64>) -> Result<Vec<f64>, NoConvergence> {
    let r = a.singular_values();
    clear_upper_state();
    r.map_err(|_| NoConvergence {
        what: "singular values",
    })
}

/// Eigen-decomposition of the symmetric matrix `a` (its lower triangle is
/// read): eigenvectors (columns) and eigenvalues, non-decreasing.
pub fn symmetric_eigen(a: MatRef<'_, f64>) -> Result<(Mat<f64>, Vec<f64>), NoConvergence> {
    let r = a.self_adjoint_eigen(Side::Lower);
    let out = r.map(|evd| {
        (
            evd.U().to_owned(),
            evd.S().column_vector().iter().copied().collect(),
        )
    });
    clear_upper_state();
    out.map_err(|_| NoConvergence {
        what: "symmetric eigen-decomposition",
    })
}

/// faer's blocked Householder QR of `a` in place (`R` in the upper
/// triangle), with block size and scratch given; returns the rank faer
/// found (a column it finds dependent is skipped, so the factor is upper
/// triangular only if the rank is `min(rows, cols)`).
pub(crate) fn householder_qr_in_place(
    a: MatMut<'_, f64>,
    h: MatMut<'_, f64>,
    stack: &mut MemStack,
) -> usize {
    let info = qr_in_place(a, h, Par::Seq, stack, Default::default());
    clear_upper_state();
    info.rank
}

#[cfg(test)]
mod tests {
    /// Every source file of `dir` and its subfolders, with its text.
    fn sources(dir: &std::path::Path, out: &mut Vec<(std::path::PathBuf, String)>) {
        for entry in std::fs::read_dir(dir).expect("the crate's src folder") {
            let path = entry.expect("a folder entry").path();
            if path.is_dir() {
                sources(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).expect("a source file");
                out.push((path, text));
            }
        }
    }

    /// Every module of the crate but this one reaches faer's kernels only
    /// through it (so none can forget the upper-state clear). Every file
    /// under `src/` is read, so a new module is checked without being
    /// listed.
    #[test]
    fn only_this_module_calls_faer_kernels() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut all = Vec::new();
        sources(&root, &mut all);
        // The walk found the crate (not an empty folder): this file and the
        // modules that compute with faer.
        for known in ["linalg.rs", "ls.rs", "sdp.rs", "streaming/gram.rs"] {
            assert!(
                all.iter().any(|(p, _)| p.ends_with(known)),
                "{known} not found"
            );
        }
        let sources: Vec<_> = all
            .iter()
            .filter(|(p, _)| !p.ends_with("linalg.rs"))
            .map(|(p, src)| (p.display().to_string(), src.as_str()))
            .collect();
        let kernels = [
            ".singular_values()",
            ".thin_svd()",
            ".svd()",
            "self_adjoint_eigen(",
            "qr_in_place(",
            "matmul(",
            ".col_piv_qr()",
            ".qr()",
            ".llt(",
            ".partial_piv_lu()",
        ];
        // `k` as a call of its own, not the tail of a longer name (the
        // facade's `householder_qr_in_place(` is fine).
        let calls = |code: &str, k: &str| {
            code.match_indices(k).any(|(i, _)| {
                !k.starts_with(|c: char| c.is_alphabetic())
                    || !code[..i]
                        .chars()
                        .next_back()
                        .is_some_and(|c| c.is_alphanumeric() || c == '_')
            })
        };
        for (file, src) in &sources {
            // Unit tests may use faer freely (they check results, not speed).
            let code = src.split("#[cfg(test)]").next().unwrap_or(src);
            for k in kernels {
                assert!(
                    !calls(code, k),
                    "{file} calls faer's `{k}` directly; use crate::linalg"
                );
            }
        }
    }
}
