//! Keeping the CPU's vector unit in the state scalar code runs fast in.
//!
//! Why this lives here: this crate is the workspace's one caller of faer,
//! and scalar per-sample code (kinematics, regressors) is what suffers.
//! Vectorised linear algebra (faer's blocked QR and SVD, measured) can
//! return with the upper halves of the AVX registers "dirty". On Intel
//! cores from Skylake on, every later legacy-SSE instruction — which is
//! what scalar `f64` Rust compiles to for the baseline x86-64 target — then
//! carries a false dependency on those upper halves: measured on this
//! project's machine, `evaluate` went from 97 ns to 520–560 ns per sample
//! for the rest of the thread's life. `vzeroupper` (what compilers emit at
//! the end of their own AVX functions) restores the clean state.
//!
//! Call [`clear_upper_state`] after foreign vectorised code and before a
//! long scalar loop, on the thread that ran it. This crate does so after
//! each faer factorisation.

/// Clears the upper halves of the vector registers if the CPU has AVX; a
/// no-op elsewhere. Costs one instruction after a cached feature check.
#[inline]
pub fn clear_upper_state() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is available (checked above), and `vzeroupper`
            // changes only the upper register halves, which hold no live
            // value across this non-AVX call boundary.
            unsafe { zero_upper() }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn zero_upper() {
    std::arch::x86_64::_mm256_zeroupper();
}

/// Whether the upper halves of the AVX registers are in use ("dirty") on
/// this thread, from the XINUSE bitmap (`xgetbv` with ECX = 1, bit 2);
/// `None` where the CPU cannot report it. A diagnostic for tests and
/// profiling: exact, unlike timing.
pub fn upper_state_dirty() -> Option<bool> {
    #[cfg(target_arch = "x86_64")]
    {
        if !std::arch::is_x86_feature_detected!("xsave") {
            return None;
        }
        let leaf = std::arch::x86_64::__cpuid_count(0xD, 1);
        if leaf.eax & 0b100 == 0 {
            return None;
        }
        // SAFETY: XSAVE and XGETBV with ECX = 1 are supported (checked).
        Some(unsafe { xinuse() } & 0b100 != 0)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        None
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "xsave")]
unsafe fn xinuse() -> u64 {
    // SAFETY: the caller has checked XSAVE and XGETBV with ECX = 1.
    unsafe { std::arch::x86_64::_xgetbv(1) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 256-bit work leaves the state dirty; the clear makes it clean.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn clear_makes_the_state_clean() {
        if upper_state_dirty().is_none() || !std::arch::is_x86_feature_detected!("avx") {
            eprintln!("CPU cannot report XINUSE or has no AVX; nothing to check");
            return;
        }
        // SAFETY: AVX is available (checked above).
        unsafe { dirty() };
        assert_eq!(
            upper_state_dirty(),
            Some(true),
            "a raw 256-bit load must dirty it"
        );
        clear_upper_state();
        assert_eq!(upper_state_dirty(), Some(false));
    }

    /// Loads a 256-bit register behind the compiler's back: the function is
    /// not an AVX function and declares only `xmm0` clobbered, so no
    /// `vzeroupper` is emitted after it (as with foreign AVX code).
    #[cfg(target_arch = "x86_64")]
    #[inline(never)]
    unsafe fn dirty() {
        let v = [1.0f64; 4];
        // SAFETY: the caller checked AVX; reads 32 bytes from a live array;
        // xmm0 (the only architectural register written) is declared clobbered.
        unsafe {
            std::arch::asm!("vmovupd ymm0, [{p}]", p = in(reg) v.as_ptr(), out("xmm0") _);
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod factorisation_tests {
    use faer::Mat;

    use super::upper_state_dirty;

    #[test]
    fn factorisations_leave_the_upper_state_clean() {
        let Some(_) = upper_state_dirty() else {
            eprintln!("CPU cannot report XINUSE; nothing to check");
            return;
        };
        // A block like the stacked regressors: tall, 24 columns, full rank.
        let a = Mat::<f64>::from_fn(4000, 24, |i, j| {
            ((i * 7 + j * 13) % 17) as f64 + (i as f64 * (j + 1) as f64).sin()
        });
        let r = crate::dense::compress(a.as_ref());
        assert_eq!(upper_state_dirty(), Some(false), "after dense::compress");
        assert_eq!(r.ncols(), 24);
        let mut qr = crate::streaming::accumulator::BlockQr::new(4000, 24);
        let r = qr.factor(4000, |mut m| m.copy_from(&a)).to_owned();
        assert_eq!(
            upper_state_dirty(),
            Some(false),
            "after BlockQr::factor_filled"
        );
        assert!(r[(23, 23)].abs() > 0.0);
        // The normal equations: faer's matrix product, eigensolver and SVD.
        let mut g = crate::streaming::gram::GramSum::new(24);
        g.add(a.as_ref());
        assert_eq!(upper_state_dirty(), Some(false), "after GramSum::add");
        let f = g.factor();
        assert_eq!(upper_state_dirty(), Some(false), "after GramSum::factor");
        let c = crate::streaming::GramCheck::of_factor(f.as_ref());
        assert_eq!(upper_state_dirty(), Some(false), "after GramCheck");
        assert!(c.condition.is_finite());
        // Least squares: QR of the stacked data, then the SVD of R for the
        // condition number in `ols`.
        let t: Vec<f64> = (0..4000).map(|i| (i as f64 * 0.01).cos()).collect();
        let names: Vec<String> = (0..24).map(|j| format!("p{j}")).collect();
        let ls = crate::ReducedLs::new(a.as_ref(), &t, &names).unwrap();
        assert_eq!(upper_state_dirty(), Some(false), "after ReducedLs::new");
        let est = ls.ols().unwrap();
        assert_eq!(upper_state_dirty(), Some(false), "after ReducedLs::ols");
        assert!(est.condition_number.is_finite());
        // The facade's remaining kernels.
        let p = crate::linalg::product(a.as_ref(), f.as_ref());
        assert_eq!(upper_state_dirty(), Some(false), "after linalg::product");
        let svd = crate::linalg::thin_svd(a.as_ref()).unwrap();
        assert_eq!(upper_state_dirty(), Some(false), "after linalg::thin_svd");
        assert_eq!((p.nrows(), svd.s.len()), (4000, 24));
    }
}
