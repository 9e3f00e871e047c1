//! Validation helpers: fitness (78), workspace PD scan, parameter errors.
#![allow(clippy::needless_range_loop)]

use aras_ident::stats::equal_count_bins;
use aras_ident::validate::{
    FitnessSums, PdRegion, check_positive_definite, fitness, fitness_per_group, parameter_errors,
    predict,
};
use aras_ident::{IdentError, RowGroups, symmetric_eigenvalues};
use faer::Mat;
use proptest::prelude::*;

#[test]
fn fitness_has_the_documented_anchors() {
    let m = [1.0, 2.0, 3.0, 4.0];
    assert_eq!(fitness(&m, &m).unwrap(), 100.0);
    assert!(fitness(&m, &[2.5; 4]).unwrap().abs() < 1e-12);
    // Error of half the spread: 50 %.
    let e: Vec<f64> = m
        .iter()
        .zip([1.0, -1.0, 1.0, -1.0])
        .map(|(a, s)| a + s * 0.5 * 1.118_033_988_749_895)
        .collect();
    assert!((fitness(&m, &e).unwrap() - 50.0).abs() < 1e-9);
    assert!(matches!(
        fitness(&[1.0; 3], &[1.0; 3]),
        Err(IdentError::ConstantSignal { .. })
    ));
    let g = RowGroups::contiguous(&[4, 3]).unwrap();
    let meas = [1.0, 2.0, 3.0, 4.0, 7.0, 7.0, 7.0];
    let e = fitness_per_group(&meas, &meas, &g).unwrap_err();
    assert!(e.to_string().contains("group 1"), "{e}");
    let g = RowGroups::interleaved(6, 2).unwrap();
    let meas = [1.0, 10.0, 2.0, 20.0, 3.0, 30.0];
    assert_eq!(
        fitness_per_group(&meas, &meas, &g).unwrap(),
        vec![100.0, 100.0]
    );
}

#[test]
fn predict_is_w_times_beta() {
    let w = Mat::from_fn(3, 2, |i, j| (i + 2 * j) as f64);
    assert_eq!(
        predict(w.as_ref(), &[1.0, 2.0]).unwrap(),
        vec![4.0, 7.0, 10.0]
    );
    assert!(predict(w.as_ref(), &[1.0]).is_err());
}

/// λ_min of M(x) = [[2 + cos x0, 0.5], [0.5, 1 + 0.5 sin x1]].
fn mass(x: &[f64; 2]) -> Result<[[f64; 2]; 2], String> {
    Ok([[2.0 + x[0].cos(), 0.5], [0.5, 1.0 + 0.5 * x[1].sin()]])
}

#[test]
fn pd_scan_finds_the_known_minimum() {
    let region = PdRegion::new([0.0, -1.0], [std::f64::consts::PI, 1.0]);
    assert!(region.n_points() >= 100_000);
    let rep = check_positive_definite(mass, &region);
    assert!(rep.positive_definite());
    assert_eq!(rep.points, region.n_points());
    // The minimum is at the grid corner (π, −1): M = [[1, .5], [.5, 1 − .5 sin 1]].
    let exact = symmetric_eigenvalues(&mass(&[std::f64::consts::PI, -1.0]).unwrap())[0];
    assert_eq!(rep.min_eigenvalue, exact);
    assert_eq!(rep.argmin, [std::f64::consts::PI, -1.0]);
    // Maximum at (0, 1).
    assert_eq!(rep.argmax, [0.0, 1.0]);
    // Deterministic: the same seed, the same report.
    assert_eq!(rep, check_positive_definite(mass, &region));
    // Brute force over the same points agrees.
    let brute = (0..region.n_points())
        .map(|i| symmetric_eigenvalues(&mass(&region.point(i)).unwrap())[0])
        .fold(f64::INFINITY, f64::min);
    assert_eq!(brute, rep.min_eigenvalue);
}

#[test]
fn pd_scan_reports_failures_and_indefinite_points() {
    let mut region = PdRegion::new([0.0, 0.0], [std::f64::consts::PI, 1.0]);
    region.random = 1000;
    let rep = check_positive_definite(
        |x: &[f64; 2]| Ok::<_, String>([[x[0].cos(), 0.0], [0.0, 1.0]]),
        &region,
    );
    assert!(!rep.positive_definite());
    assert!(rep.non_positive > 0);
    assert!(rep.min_eigenvalue <= -0.999);
    let rep = check_positive_definite(
        |x: &[f64; 2]| {
            if x[0] > 3.0 {
                Err("outside the reachable set".to_string())
            } else {
                Ok([[1.0, 0.0], [0.0, 1.0]])
            }
        },
        &region,
    );
    assert!(rep.failures > 0 && !rep.positive_definite());
    let (x, msg) = rep.first_failure.unwrap();
    assert!(x[0] > 3.0 && msg == "outside the reachable set");
}

#[test]
fn parameter_errors_in_sigma() {
    let e = parameter_errors(&["a", "b"], &[1.1, 2.0], &[0.05, 0.1], &[1.0, 2.0]).unwrap();
    assert!((e[0].in_sigma - 2.0).abs() < 1e-12);
    assert!((e[0].error - 0.1).abs() < 1e-12);
    assert_eq!(e[1].in_sigma, 0.0);
    assert!(parameter_errors(&["a"], &[1.0, 2.0], &[1.0], &[1.0]).is_err());
}

proptest! {
    /// The one-pass sums give the two-pass definition of (78), with a
    /// mean a thousand times the spread (the sums are taken about the
    /// first sample, so the variance does not cancel: 1e-9 points is
    /// rounding of 10³ terms, amplified by at most 10⁶ / 10⁶).
    #[test]
    fn fitness_sums_equal_the_two_pass_definition(
        v in proptest::collection::vec((-1.0f64..1.0, -0.3f64..0.3), 2..1000),
        offset in -1000.0f64..1000.0,
    ) {
        let m: Vec<f64> = v.iter().map(|(a, _)| offset + a).collect();
        let e: Vec<f64> = v.iter().map(|(a, d)| offset + a + d).collect();
        let mean = m.iter().sum::<f64>() / m.len() as f64;
        let den = m.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>().sqrt();
        prop_assume!(den > 1e-3);
        let num = m.iter().zip(&e).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
        let want = 100.0 * (1.0 - num / den);
        let mut sums = FitnessSums::default();
        for (a, b) in m.iter().zip(&e) {
            sums.push(*a, *b);
        }
        prop_assert_eq!(sums.len(), m.len());
        let got = sums.fitness(0).unwrap();
        prop_assert!((got - want).abs() < 1e-9, "{} vs {}", got, want);
        prop_assert_eq!(fitness(&m, &e).unwrap(), got);
    }

    /// Sums of the pieces of a record, merged in any split, give the sums
    /// of the whole record (the pieces' first samples differ, so their
    /// shifts do): the same fitness to rounding, the same count, and an
    /// empty piece changes nothing.
    #[test]
    fn merged_fitness_sums_equal_one_pass(
        v in proptest::collection::vec((-1.0f64..1.0, -0.3f64..0.3), 3..600),
        offset in -1000.0f64..1000.0,
        cuts in proptest::collection::vec(0.0f64..1.0, 0..4),
    ) {
        let m: Vec<f64> = v.iter().map(|(a, _)| offset + a).collect();
        let e: Vec<f64> = v.iter().map(|(a, d)| offset + a + d).collect();
        let mut whole = FitnessSums::default();
        for (a, b) in m.iter().zip(&e) {
            whole.push(*a, *b);
        }
        let Ok(want) = whole.fitness(0) else {
            return Ok(());
        };
        let mut at: Vec<usize> = cuts.iter().map(|c| (c * m.len() as f64) as usize).collect();
        at.push(0);
        at.push(m.len());
        at.sort_unstable();
        let mut merged = FitnessSums::default();
        for w in at.windows(2) {
            let mut piece = FitnessSums::default();
            for i in w[0]..w[1] {
                piece.push(m[i], e[i]);
            }
            merged.merge(&piece);
        }
        prop_assert_eq!(merged.len(), m.len());
        let got = merged.fitness(0).unwrap();
        prop_assert!((got - want).abs() < 1e-9, "{} vs {}", got, want);
    }

    /// Equal-count bins hold every finite pair once, in order of `x`, with
    /// counts that differ by at most one, and each bin's edges, means and
    /// RMS are those of its run of the sorted pairs.
    #[test]
    fn equal_count_bins_partition_the_pairs(
        v in proptest::collection::vec((-5.0f64..5.0, -2.0f64..2.0), 0..300),
        bins in 0usize..12,
        holes in proptest::collection::vec(0usize..300, 0..5),
    ) {
        let (mut x, y): (Vec<f64>, Vec<f64>) = v.iter().copied().unzip();
        for &h in &holes {
            if h < x.len() {
                x[h] = f64::NAN;
            }
        }
        let finite: Vec<(f64, f64)> = x
            .iter()
            .zip(&y)
            .filter(|(a, _)| a.is_finite())
            .map(|(a, b)| (*a, *b))
            .collect();
        let out = equal_count_bins(&x, &y, bins);
        prop_assert_eq!(out.iter().map(|b| b.count).sum::<usize>(), finite.len());
        prop_assert!(out.len() <= bins.max(1));
        let (lo, hi) = out.iter().fold((usize::MAX, 0), |(l, h), b| (l.min(b.count), h.max(b.count)));
        prop_assert!(out.is_empty() || hi - lo <= 1, "counts {}..{}", lo, hi);
        for w in out.windows(2) {
            prop_assert!(w[0].hi <= w[1].lo);
        }
        // The bins are consecutive runs of the pairs sorted by x.
        let mut sorted = finite.clone();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut at = 0;
        for b in &out {
            let run = &sorted[at..at + b.count];
            at += b.count;
            let m = run.len() as f64;
            let mean = run.iter().map(|p| p.1).sum::<f64>() / m;
            let rms = (run.iter().map(|p| p.1 * p.1).sum::<f64>() / m).sqrt();
            let xm = run.iter().map(|p| p.0).sum::<f64>() / m;
            prop_assert_eq!((b.lo, b.hi), (run[0].0, run[run.len() - 1].0));
            prop_assert!((b.mean - mean).abs() < 1e-12 && (b.rms - rms).abs() < 1e-12);
            prop_assert!((b.x_mean - xm).abs() < 1e-12 && b.std_dev >= 0.0);
        }
    }

    /// Jacobi eigenvalues of a symmetric 4×4: trace and determinant-free
    /// invariants (sum = trace, sum of squares = Frobenius²) to 1e-12 relative.
    #[test]
    fn jacobi_invariants(v in proptest::collection::vec(-10.0f64..10.0, 10)) {
        let mut a = [[0.0; 4]; 4];
        let mut k = 0;
        for i in 0..4 {
            for j in i..4 {
                a[i][j] = v[k];
                a[j][i] = v[k];
                k += 1;
            }
        }
        let ev = symmetric_eigenvalues(&a);
        let tr: f64 = (0..4).map(|i| a[i][i]).sum();
        let fro: f64 = a.iter().flatten().map(|x| x * x).sum();
        let scale = fro.sqrt().max(1.0);
        prop_assert!((ev.iter().sum::<f64>() - tr).abs() <= 1e-12 * scale);
        prop_assert!((ev.iter().map(|x| x * x).sum::<f64>() - fro).abs() <= 1e-12 * scale * scale);
        prop_assert!(ev.windows(2).all(|w| w[0] <= w[1]));
    }
}
