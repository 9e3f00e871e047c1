//! Leaving the CPU's vector unit in a state that scalar code runs fast in.
//!
//! faer's blocked QR (`qr_in_place`) can return with the upper halves of the
//! AVX registers "dirty". On Intel cores from Skylake on, every later
//! legacy-SSE instruction — which is what scalar `f64` Rust code compiles to
//! for the baseline x86-64 target — then carries a false dependency on those
//! upper halves: measured here, `aras_kin::evaluate` went from 97 ns to
//! 520–560 ns per sample for the rest of the thread's life. `vzeroupper`
//! (what compilers emit at the end of AVX functions) restores the clean
//! state; we issue it after each faer factorisation.

/// Clears the upper halves of the vector registers if the CPU has AVX; a
/// no-op elsewhere. Cheap (one instruction after a cached feature check).
#[inline]
pub(crate) fn clear_upper_state() {
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

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use faer::Mat;

    /// Whether the upper halves of the AVX registers are in use ("dirty"),
    /// read from the XINUSE bitmap (`xgetbv` with ECX = 1, bit 2); `None`
    /// where the CPU cannot report it. Exact, unlike timing.
    fn upper_dirty() -> Option<bool> {
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

    #[target_feature(enable = "xsave")]
    unsafe fn xinuse() -> u64 {
        // SAFETY: the caller has checked XSAVE and XGETBV with ECX = 1.
        unsafe { std::arch::x86_64::_xgetbv(1) }
    }

    #[test]
    fn factorisations_leave_the_upper_state_clean() {
        let Some(_) = upper_dirty() else {
            eprintln!("CPU cannot report XINUSE; nothing to check");
            return;
        };
        // A block like the stacked regressors: tall, 24 columns, full rank.
        let a = Mat::<f64>::from_fn(4000, 24, |i, j| {
            ((i * 7 + j * 13) % 17) as f64 + (i as f64 * (j + 1) as f64).sin()
        });
        let r = crate::dense::compress(a.as_ref());
        assert_eq!(upper_dirty(), Some(false), "after dense::compress");
        assert_eq!(r.ncols(), 24);
        let mut qr = crate::streaming::accumulator::BlockQr::new(4000, 24);
        let r = qr.factor(4000, |mut m| m.copy_from(&a)).to_owned();
        assert_eq!(upper_dirty(), Some(false), "after BlockQr::factor_filled");
        assert!(r[(23, 23)].abs() > 0.0);
    }
}
