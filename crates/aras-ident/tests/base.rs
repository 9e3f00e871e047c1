//! Base parameters on constructed regressors with known structure.
#![allow(clippy::needless_range_loop)]

mod common;

use aras_ident::{BaseParameters, DEFAULT_RANK_TOLERANCE, IdentError};
use faer::Mat;
use proptest::prelude::*;

/// Six columns: p2 = p0 + 0.5 p1, p4 = 0, p5 = (p3 − p1)/2·… built so that
/// W β = c0 (β0 + β2) + c1 (β1 + 0.5 β2 − β5) + c3 (β3 + 2 β5).
fn constructed(rows: usize) -> (Mat<f64>, Vec<String>) {
    let mut r = common::rng(7);
    let w = Mat::from_fn(rows, 6, |_, _| 0.0);
    let mut w = w;
    for i in 0..rows {
        let (c0, c1, c3) = (
            common::normal(&mut r),
            3.0 * common::normal(&mut r),
            0.01 * common::normal(&mut r),
        );
        w[(i, 0)] = c0;
        w[(i, 1)] = c1;
        w[(i, 2)] = c0 + 0.5 * c1;
        w[(i, 3)] = c3;
        w[(i, 4)] = 0.0;
        w[(i, 5)] = 2.0 * c3 - c1;
    }
    (w, (0..6).map(|i| format!("p{i}")).collect())
}

#[test]
fn constructed_rank_deficiency_is_found_and_named() {
    let (w, names) = constructed(500);
    let base = BaseParameters::from_regressor(w.as_ref(), &names, DEFAULT_RANK_TOLERANCE).unwrap();
    assert_eq!(base.n_base(), 3);
    assert_eq!(base.independent(), &[0, 1, 3]);
    assert_eq!(base.unidentifiable(), vec!["p4"]);
    assert_eq!(base.grouped(), vec!["p2", "p5"]);
    assert_eq!(
        base.expressions(),
        vec!["b1 = p0 + p2", "b2 = p1 + 0.5·p2 - p5", "b3 = p3 + 2·p5"]
    );
    // The rank decision is far from the tolerance on both sides.
    let m = base.rank_margin();
    assert!(m.smallest_kept > 1e-2 && m.largest_dropped < 1e-13, "{m:?}");
    let text = base.to_string();
    assert!(
        text.contains("unidentifiable (no effect on the data): p4"),
        "{text}"
    );
}

#[test]
fn base_regressor_reproduces_every_torque() {
    let (w, names) = constructed(200);
    let base = BaseParameters::from_regressor(w.as_ref(), &names, DEFAULT_RANK_TOLERANCE).unwrap();
    let wb = base.base_regressor(w.as_ref()).unwrap();
    let beta = [0.3, -1.2, 0.7, 2.0, 5.0, -0.4];
    let bb = base.to_base(&beta).unwrap();
    for i in 0..w.nrows() {
        let full: f64 = (0..6).map(|j| w[(i, j)] * beta[j]).sum();
        let red: f64 = (0..3).map(|j| wb[(i, j)] * bb[j]).sum();
        // Relative 1e-12: a handful of roundings on O(10) values.
        assert!(
            (full - red).abs() <= 1e-12 * (1.0 + full.abs()),
            "row {i}: {full} vs {red}"
        );
    }
}

#[test]
fn standard_representatives_map_back() {
    let (w, names) = constructed(200);
    let base = BaseParameters::from_regressor(w.as_ref(), &names, DEFAULT_RANK_TOLERANCE).unwrap();
    let bb = [1.0, 2.0, 3.0];
    let e = base.to_standard(&bb).unwrap();
    assert_eq!(e, vec![1.0, 2.0, 0.0, 3.0, 0.0, 0.0]);
    let reference = [0.9, 2.1, 0.05, 2.8, 7.0, 0.1];
    let near = base.to_standard_near(&bb, &reference).unwrap();
    let back = base.to_base(&near).unwrap();
    for (a, b) in back.iter().zip(&bb) {
        assert!((a - b).abs() < 1e-12, "{back:?}");
    }
    // The unidentifiable parameter keeps its reference value.
    assert_eq!(near[4], 7.0);
    // Nearer to the reference than the zero-completion.
    let dist = |v: &[f64]| {
        v.iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
    };
    assert!(dist(&near) < dist(&e));
}

#[test]
fn rigid_body_gravity_direction_sets_the_count() {
    // One body with random motion: all 9 parameters identifiable when
    // gravity takes every direction in the body frame...
    let mut r = common::rng(1);
    let (w, names) = common::multi_body(&mut r, 300, 1, false, false);
    let base = BaseParameters::from_regressor(w.as_ref(), &names, DEFAULT_RANK_TOLERANCE).unwrap();
    assert_eq!(base.n_base(), 9);
    // ...two bodies moving together: only sums are identifiable.
    let (w, names) = common::multi_body(&mut r, 300, 2, true, true);
    let base = BaseParameters::from_regressor(w.as_ref(), &names, DEFAULT_RANK_TOLERANCE).unwrap();
    assert_eq!(base.n_base(), 9 + 6);
    assert_eq!(base.grouped().len(), 9);
    assert_eq!(base.expression(0), "b1 = L1.Ixx + L2.Ixx");
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let (mut w, names) = constructed(50);
    assert!(matches!(
        BaseParameters::from_regressor(w.as_ref(), &names[..5], 1e-8),
        Err(IdentError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        BaseParameters::from_regressor(w.as_ref(), &names, 0.0),
        Err(IdentError::InvalidSetting { .. })
    ));
    w[(3, 2)] = f64::NAN;
    let e = BaseParameters::from_regressor(w.as_ref(), &names, 1e-8).unwrap_err();
    assert!(e.to_string().contains("row 3, column 2 (`p2`)"), "{e}");
    let z = Mat::<f64>::zeros(10, 3);
    assert!(matches!(
        BaseParameters::from_regressor(z.as_ref(), &["a", "b", "c"], 1e-8),
        Err(IdentError::NoExcitation { .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// W = A C with A random (rows × r) and C random (r × n): the base count
    /// is r, W = W_b K to rounding, and K restricted to the kept columns is I.
    #[test]
    fn random_low_rank_structure(seed in 0u64..10_000, r in 1usize..6, extra in 0usize..5) {
        let n = r + extra;
        let mut g = common::rng(seed);
        let rows = 40 + 3 * n;
        let a = Mat::from_fn(rows, r, |_, _| common::normal(&mut g));
        let c = Mat::from_fn(r, n, |_, _| common::normal(&mut g));
        let w = &a * &c;
        let names: Vec<String> = (0..n).map(|i| format!("q{i}")).collect();
        let base = BaseParameters::from_regressor(w.as_ref(), &names, DEFAULT_RANK_TOLERANCE).unwrap();
        prop_assert_eq!(base.n_base(), r);
        let k = base.k();
        for (i, &j) in base.independent().iter().enumerate() {
            for l in 0..r {
                prop_assert_eq!(k[(l, j)], if l == i { 1.0 } else { 0.0 });
            }
        }
        let wb = base.base_regressor(w.as_ref()).unwrap();
        let rec = &wb * k;
        let err = (&rec - &w).norm_max();
        // Random Gaussian factors: cond(W_S) stays below ~1e4 with high
        // probability, so reconstruction error ≤ 1e-9 · max|W|.
        prop_assert!(err <= 1e-9 * w.norm_max(), "err {}", err);
    }
}
