//! The HAC covariance across joints and dropped rows, and the σ floor.
#![allow(clippy::needless_range_loop)]

mod common;

use aras_ident::{IdentError, RowGroups, hac_covariance, ols, symmetric_eigenvalues};
use faer::Mat;
use proptest::prelude::*;

/// Two joints measured at the same instants with the same noise (a shared
/// disturbance): the mean of all rows has the variance of one joint's mean,
/// σ²/n, not σ²/(2n). The HAC sums the joints' scores per sample, so it
/// finds σ²/n; treating the joints as independent would halve it.
#[test]
fn hac_counts_the_correlation_between_joints_at_the_same_sample() {
    let n = 20_000;
    let mut r = common::rng(7);
    let x: Vec<f64> = (0..n).map(|_| common::normal(&mut r)).collect();
    let mean = x.iter().sum::<f64>() / n as f64;
    let e: Vec<f64> = x.iter().chain(&x).map(|v| v - mean).collect();
    let w = Mat::from_fn(2 * n, 1, |_, _| 1.0);
    let groups = RowGroups::contiguous(&[n, n]).unwrap();
    let hac = hac_covariance(w.as_ref(), &e, &groups, false).unwrap();
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let ratio = hac.covariance[(0, 0)] / (var / n as f64);
    // White noise: the Bartlett estimate over L ≈ 4 lags has a relative
    // standard error of about √(2·4/(3n)) ≈ 1 %; 5 % is five of them.
    assert!((ratio - 1.0).abs() < 0.05, "HAC / (σ²/n) = {ratio}");
    // The same rows labelled as two unrelated records (sample indices that
    // never coincide): half of it.
    let apart = RowGroups::contiguous(&[n, n])
        .unwrap()
        .with_samples((0..2 * n).collect(), 2 * n)
        .unwrap();
    let h2 = hac_covariance(w.as_ref(), &e, &apart, false).unwrap();
    let ratio = h2.covariance[(0, 0)] / (var / n as f64);
    assert!((ratio - 0.5).abs() < 0.03, "{ratio}");
}

/// Row samples are checked: one per row, below the record length,
/// increasing within a group.
#[test]
fn row_samples_are_checked() {
    let g = || RowGroups::contiguous(&[3, 2]).unwrap();
    assert_eq!(g().samples(), &[0, 1, 2, 0, 1]);
    assert_eq!(g().sample_count(), 3);
    let ok = g().with_samples(vec![0, 2, 5, 1, 4], 6).unwrap();
    assert_eq!(ok.samples(), &[0, 2, 5, 1, 4]);
    assert!(matches!(
        g().with_samples(vec![0, 1, 2], 3),
        Err(IdentError::DimensionMismatch { .. })
    ));
    let too_big = g().with_samples(vec![0, 1, 6, 0, 1], 6).unwrap_err();
    assert!(too_big.to_string().contains("sample count"), "{too_big}");
    let unordered = g().with_samples(vec![0, 2, 1, 0, 1], 6).unwrap_err();
    assert!(unordered.to_string().contains("increase"), "{unordered}");
    let interleaved = RowGroups::interleaved(6, 2).unwrap();
    assert_eq!(interleaved.samples(), &[0, 0, 1, 1, 2, 2]);
}

proptest! {
    /// The floor raises exactly the σ below it, keeps every correlation,
    /// and leaves a positive semidefinite covariance.
    #[test]
    fn sigma_floor_raises_only_smaller_sigmas_and_keeps_correlations(
        seed in 0u64..1000,
        f in proptest::collection::vec(0.0f64..3.0, 3),
    ) {
        let mut r = common::rng(seed);
        let rows = 40;
        let w = Mat::from_fn(rows, 3, |i, j| {
            common::normal(&mut r) + if j == 1 { 0.8 * (i as f64 * 0.3).sin() } else { 0.0 }
        });
        let t: Vec<f64> = (0..rows).map(|_| common::normal(&mut r)).collect();
        let est = ols(w.as_ref(), &t, &["a", "b", "c"]).unwrap();
        let floor: Vec<f64> = (0..3).map(|i| f[i] * est.std_dev[i]).collect();
        let (out, raised) = est.clone().with_sigma_floor(&floor).unwrap();
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            prop_assert_eq!(raised[i], floor[i] > est.std_dev[i]);
            let want = est.std_dev[i].max(floor[i]);
            prop_assert!((out.std_dev[i] - want).abs() <= 1e-12 * want);
            prop_assert!((out.covariance[(i, i)].sqrt() - want).abs() <= 1e-9 * want);
            let pct = 100.0 * want / est.estimate[i].abs();
            prop_assert!((out.rel_std_percent[i] - pct).abs() <= 1e-9 * pct);
            for j in 0..3 {
                let corr = |m: &Mat<f64>| m[(i, j)] / (m[(i, i)] * m[(j, j)]).sqrt();
                prop_assert!((corr(&out.covariance) - corr(&est.covariance)).abs() < 1e-9);
                c[i][j] = out.covariance[(i, j)];
            }
        }
        let scale = c[0][0].max(c[1][1]).max(c[2][2]);
        prop_assert!(symmetric_eigenvalues(&c).iter().all(|&l| l >= -1e-12 * scale));
    }
}

#[test]
fn sigma_floor_of_the_wrong_length_or_not_finite_is_an_error() {
    let w = Mat::from_fn(10, 2, |i, j| (i * (j + 1)) as f64 + 1.0 + (i % 3) as f64);
    let t: Vec<f64> = (0..10).map(|i| (i as f64).sin()).collect();
    let est = ols(w.as_ref(), &t, &["a", "b"]).unwrap();
    assert!(matches!(
        est.clone().with_sigma_floor(&[1.0]),
        Err(IdentError::DimensionMismatch { .. })
    ));
    assert!(est.with_sigma_floor(&[1.0, f64::NAN]).is_err());
}
