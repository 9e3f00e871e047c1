//! Vector-unit hygiene after faer (see [`aras_kin::simd`]): every faer
//! factorisation in this crate is followed by [`clear_upper_state`].

pub(crate) use aras_kin::simd::clear_upper_state;

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use faer::Mat;

    use aras_kin::simd::upper_state_dirty;

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
    }
}
