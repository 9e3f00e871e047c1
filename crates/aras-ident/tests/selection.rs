//! The selection engine against direct dense solves (nalgebra SVD on the
//! stacked rows, an independent code path), chunking/merging invariance,
//! and forward selection recovering a hidden term with its value.

use aras_ident::IdentError;
use aras_ident::selection::{
    Accumulator, CandidateSpec, EvaluationStatus, Layout, SelectionOptions, SelectionStatus,
    fit_model, select,
};
use aras_ident::validate::fitness;
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use rand::{SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, StandardNormal};

/// Rows `[base(3) | cand a (2) | cand b (1) | target]` of one group.
fn rows(seed: u64, n: usize, truth: &[f64], noise: f64) -> Vec<[f64; 7]> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut g = || -> f64 { StandardNormal.sample(&mut rng) };
    (0..n)
        .map(|_| {
            let mut r = [0.0; 7];
            r[0] = 1.0;
            for v in r.iter_mut().take(6).skip(1) {
                *v = g();
            }
            let y: f64 = (0..6).map(|k| truth[k] * r[k]).sum::<f64>() + noise * g();
            r[6] = y;
            r
        })
        .collect()
}

fn layout() -> Layout {
    Layout::new(
        3,
        vec![
            CandidateSpec::columns("a", 2),
            CandidateSpec::columns("b", 1),
        ],
        2,
    )
    .unwrap()
}

fn accumulate(layout: &Layout, groups: &[Vec<[f64; 7]>], chunk: usize) -> Accumulator {
    let mut acc = Accumulator::new(layout);
    for (g, rs) in groups.iter().enumerate() {
        for c in rs.chunks(chunk.max(1)) {
            let flat: Vec<f64> = c.iter().flatten().copied().collect();
            acc.push_rows(g, &flat).unwrap();
        }
    }
    acc
}

/// Dense least squares on the stacked rows of both groups with `cols`.
fn dense(groups: &[Vec<[f64; 7]>], cols: &[usize]) -> (Vec<f64>, Vec<f64>) {
    let all: Vec<&[f64; 7]> = groups.iter().flatten().collect();
    let x = DMatrix::from_fn(all.len(), cols.len(), |i, j| all[i][cols[j]]);
    let y = DVector::from_fn(all.len(), |i, _| all[i][6]);
    let beta = x.clone().svd(true, true).solve(&y, 1e-14).unwrap();
    let rss = groups
        .iter()
        .map(|rs| {
            rs.iter()
                .map(|r| {
                    let p: f64 = cols.iter().zip(beta.iter()).map(|(c, b)| r[*c] * b).sum();
                    (r[6] - p).powi(2)
                })
                .sum()
        })
        .collect();
    (beta.iter().copied().collect(), rss)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Every nested fit equals the dense solve: estimates, per-group RSS
    /// and validation fitness (78), whatever the chunking. Random Gaussian
    /// columns have κ < 10, so the normal equations' error κ²ε < 1e-13;
    /// 1e-9 relative leaves room for the RSS cancellation.
    #[test]
    fn nested_fits_match_dense_solves(
        seed in 0u64..1000,
        n in 40usize..400,
        chunk in 1usize..97,
        subset in 0usize..4,
    ) {
        let truth = [0.5, -1.0, 2.0, 0.3, 0.0, -0.7];
        let tr = vec![rows(seed, n, &truth, 0.1), rows(seed + 7, n + 13, &truth, 0.1)];
        let va = vec![rows(seed + 1, 150, &truth, 0.2), rows(seed + 2, 170, &truth, 0.2)];
        let l = layout();
        let (t, v) = (accumulate(&l, &tr, chunk), accumulate(&l, &va, 64));
        let added: Vec<usize> = match subset { 0 => vec![], 1 => vec![0], 2 => vec![1], _ => vec![1, 0] };
        let f = fit_model(&t, std::slice::from_ref(&v), &added, &SelectionOptions::default()).unwrap();
        let mut cols = vec![0, 1, 2];
        for k in &added {
            cols.extend(if *k == 0 { vec![3, 4] } else { vec![5] });
        }
        prop_assert_eq!(&f.columns, &cols);
        let (beta, rss) = dense(&tr, &cols);
        for (a, b) in f.estimate.iter().zip(&beta) {
            prop_assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "{} vs {}", a, b);
        }
        for (a, b) in f.rss.iter().zip(&rss) {
            prop_assert!((a - b).abs() <= 1e-9 * b, "rss {} vs {}", a, b);
        }
        for (g, vg) in va.iter().enumerate() {
            let m: Vec<f64> = vg.iter().map(|r| r[6]).collect();
            let p: Vec<f64> = vg
                .iter()
                .map(|r| cols.iter().zip(&beta).map(|(c, b)| r[*c] * b).sum())
                .collect();
            let fit = fitness(&m, &p).unwrap();
            prop_assert!((f.fitness[0][g] - fit).abs() < 1e-8, "{} vs {}", f.fitness[0][g], fit);
        }
        prop_assert!(f.check.passed);
    }

    /// Merging two halves' sums equals accumulating all rows at once.
    #[test]
    fn merge_equals_one_pass(seed in 0u64..1000, cut in 1usize..199) {
        let truth = [0.5, -1.0, 2.0, 0.3, 0.1, -0.7];
        let all = vec![rows(seed, 200, &truth, 0.1), rows(seed + 3, 200, &truth, 0.1)];
        let l = layout();
        let one = accumulate(&l, &all, 200);
        let a: Vec<Vec<[f64; 7]>> = all.iter().map(|r| r[..cut].to_vec()).collect();
        let b: Vec<Vec<[f64; 7]>> = all.iter().map(|r| r[cut..].to_vec()).collect();
        let mut m = accumulate(&l, &a, 50);
        m.merge(&accumulate(&l, &b, 50)).unwrap();
        prop_assert_eq!(m.rows(), one.rows());
        let o = SelectionOptions::default();
        let f1 = fit_model(&one, std::slice::from_ref(&one), &[0, 1], &o).unwrap();
        let f2 = fit_model(&m, std::slice::from_ref(&m), &[0, 1], &o).unwrap();
        for (x, y) in f1.estimate.iter().zip(&f2.estimate) {
            prop_assert!((x - y).abs() <= 1e-12 * (1.0 + x.abs()));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// The sums of combined columns ([`Accumulator::combined`]) equal those
    /// accumulated from the combined rows: candidate `c` of the new layout
    /// is `w₁ a₁ + w₂ a₂ + w₃ b`, the base and the target kept. Fits agree
    /// to the normal equations' rounding (κ < 100 here: 1e-9 relative).
    #[test]
    fn combined_sums_equal_sums_of_combined_rows(
        seed in 0u64..1000,
        w in proptest::array::uniform3(-2.0f64..2.0),
    ) {
        let truth = [0.5, -1.0, 2.0, 0.3, 0.4, -0.7];
        let tr = vec![rows(seed, 120, &truth, 0.1), rows(seed + 5, 90, &truth, 0.1)];
        let l = layout();
        let acc = accumulate(&l, &tr, 37);
        let new = Layout::new(3, vec![CandidateSpec::columns("c", 1)], 2).unwrap();
        let combination = vec![
            vec![(0, 1.0)],
            vec![(1, 1.0)],
            vec![(2, 1.0)],
            vec![(3, w[0]), (4, w[1]), (5, w[2])],
            vec![(6, 1.0)],
        ];
        let got = acc.combined(&new, &combination).unwrap();
        let rows_c: Vec<Vec<f64>> = tr
            .iter()
            .map(|g| {
                g.iter()
                    .flat_map(|r| [r[0], r[1], r[2], w[0] * r[3] + w[1] * r[4] + w[2] * r[5], r[6]])
                    .collect()
            })
            .collect();
        let mut want = Accumulator::new(&new);
        for (g, v) in rows_c.iter().enumerate() {
            want.push_rows(g, v).unwrap();
        }
        prop_assert_eq!(got.rows(), want.rows());
        let o = SelectionOptions::default();
        for added in [vec![], vec![0]] {
            let a = fit_model(&got, std::slice::from_ref(&got), &added, &o).unwrap();
            let b = fit_model(&want, std::slice::from_ref(&want), &added, &o).unwrap();
            for (x, y) in a.estimate.iter().zip(&b.estimate) {
                prop_assert!((x - y).abs() <= 1e-9 * (1.0 + y.abs()), "{} vs {}", x, y);
            }
            for (x, y) in a.rss.iter().zip(&b.rss) {
                prop_assert!((x - y).abs() <= 1e-9 * y, "rss {} vs {}", x, y);
            }
            prop_assert!((a.fitness[0][0] - b.fitness[0][0]).abs() < 1e-8);
        }
        // A combination naming a column the sums do not have is refused.
        let mut bad = combination.clone();
        bad[3].push((7, 1.0));
        prop_assert!(acc.combined(&new, &bad).is_err());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Rows whose columns 4 and 5 are zero, pushed as their other columns
    /// ([`Accumulator::push_columns`]), give the sums of the full rows.
    #[test]
    fn pushing_the_nonzero_columns_equals_pushing_the_rows(seed in 0u64..1000, chunk in 1usize..97) {
        let truth = [0.5, -1.0, 2.0, 0.3, 0.4, -0.7];
        let mut tr = vec![rows(seed, 150, &truth, 0.1), rows(seed + 9, 110, &truth, 0.1)];
        for r in tr.iter_mut().flatten() {
            r[4] = 0.0;
            r[5] = 0.0;
        }
        let l = layout();
        let full = accumulate(&l, &tr, chunk);
        let cols = [0, 1, 2, 3, 6];
        let mut part = Accumulator::new(&l);
        for (g, rs) in tr.iter().enumerate() {
            for c in rs.chunks(chunk) {
                let m = faer::Mat::<f64>::from_fn(c.len(), cols.len(), |i, q| c[i][cols[q]]);
                part.push_columns(g, m.as_ref(), &cols).unwrap();
            }
        }
        prop_assert_eq!(part.rows(), full.rows());
        let o = SelectionOptions::default();
        let a = fit_model(&part, std::slice::from_ref(&part), &[0], &o).unwrap();
        let b = fit_model(&full, std::slice::from_ref(&full), &[0], &o).unwrap();
        for (x, y) in a.rss.iter().zip(&b.rss) {
            prop_assert!((x - y).abs() <= 1e-12 * y, "rss {} vs {}", x, y);
        }
        let m = faer::Mat::<f64>::zeros(3, 2);
        prop_assert!(part.push_columns(0, m.as_ref(), &[3, 1]).is_err(), "not increasing");
        prop_assert!(part.push_columns(0, m.as_ref(), &[3, 7]).is_err(), "outside the layout");
        prop_assert!(part.push_columns(0, m.as_ref(), &[3]).is_err(), "count");
    }
}

/// The hidden candidate `a` (two columns) is added with its values, `b`
/// (absent) is not; on data without any candidate nothing is added on any
/// of 10 seeds.
#[test]
fn selects_the_hidden_candidate_with_its_values() {
    let l = layout();
    let truth = [0.5, -1.0, 2.0, 0.3, -0.2, 0.0];
    let sets: Vec<Accumulator> = (0..3)
        .map(|s| {
            accumulate(
                &l,
                &[
                    rows(10 * s, 2000, &truth, 0.5),
                    rows(10 * s + 1, 2000, &truth, 0.5),
                ],
                256,
            )
        })
        .collect();
    let sel = select(&sets[0], &sets[1..], &SelectionOptions::default()).unwrap();
    assert_eq!(sel.added(), vec![0]);
    assert_eq!(sel.status, SelectionStatus::NothingSignificant);
    let f = sel.final_fit();
    // 4000 rows, noise 0.5, unit columns: σ ≈ 0.5/√4000 ≈ 0.008; 5σ.
    for (k, want) in [(3, 0.3), (4, -0.2)] {
        assert!(
            (f.estimate[k] - want).abs() < 5.0 * f.std_dev[k],
            "{k}: {}",
            f.estimate[k]
        );
        assert!((f.std_dev[k] - 0.5 / 4000f64.sqrt()).abs() < 0.2 * f.std_dev[k]);
    }
    // The step's evidence is recorded and significant; the last round has
    // `b` scored as not significant.
    assert_eq!(
        sel.steps[0].evaluation.status,
        EvaluationStatus::Significant
    );
    assert!(
        sel.steps[0]
            .evaluation
            .gain_per_set
            .iter()
            .all(|g| *g > 0.1)
    );
    let last = sel.rounds.last().unwrap();
    assert_eq!(last.len(), 1);
    assert_eq!(last[0].status, EvaluationStatus::NotSignificant);

    let null = [0.5, -1.0, 2.0, 0.0, 0.0, 0.0];
    for seed in 0..10 {
        let sets: Vec<Accumulator> = (0..3)
            .map(|s| {
                accumulate(
                    &l,
                    &[
                        rows(100 * seed + 10 * s, 2000, &null, 0.5),
                        rows(100 * seed + 10 * s + 1, 2000, &null, 0.5),
                    ],
                    256,
                )
            })
            .collect();
        let sel = select(&sets[0], &sets[1..], &SelectionOptions::default()).unwrap();
        assert!(sel.steps.is_empty(), "seed {seed}: {:?}", sel.added());
    }
}

/// A candidate that is a multiple of a base column adds no parameter, and
/// an alternative target that explains the data is chosen over it.
#[test]
fn aliases_and_alternative_targets() {
    let l = Layout::new(
        2,
        vec![
            CandidateSpec::columns("copy", 1).in_family("copies"),
            CandidateSpec::target("shifted"),
        ],
        1,
    )
    .unwrap();
    let mk = |seed: u64| {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut acc = Accumulator::new(&l);
        let mut flat = Vec::new();
        for _ in 0..3000 {
            let x: f64 = StandardNormal.sample(&mut rng);
            let e: f64 = StandardNormal.sample(&mut rng);
            let d: f64 = StandardNormal.sample(&mut rng);
            // Row: [1, x, 3x, alternative, target]; the measured target carries a disturbance `d`; the shifted
            // one is the clean relation.
            let clean = 1.0 + 2.0 * x + 0.05 * e;
            flat.extend([1.0, x, 3.0 * x, clean, clean + 0.5 * d]);
        }
        acc.push_rows(0, &flat).unwrap();
        acc
    };
    let sets = [mk(1), mk(2)];
    let sel = select(&sets[0], &sets[1..], &SelectionOptions::default()).unwrap();
    assert_eq!(sel.added(), vec![1], "{:#?}", sel.rounds);
    assert_eq!(sel.final_fit().target, 3);
    assert!((sel.final_fit().estimate[1] - 2.0).abs() < 0.01);
    let copy = &sel.rounds[0][0];
    assert_eq!(copy.status, EvaluationStatus::NoNewParameters);
    assert_eq!(copy.added_parameters, 0);
}

/// Bad input is refused with what and where.
#[test]
fn bad_input_is_refused() {
    let l = layout();
    let mut acc = Accumulator::new(&l);
    let mut row = vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
    row[4] = f64::NAN;
    match acc.push_rows(1, &row) {
        Err(IdentError::NonFinite {
            row: 0,
            column: 4,
            name,
            ..
        }) => {
            assert!(name.contains("`a`"), "{name}")
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        acc.push_rows(0, &row[..5]),
        Err(IdentError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        acc.push_rows(2, &[0.0; 7]),
        Err(IdentError::InvalidSelection { .. })
    ));
    assert!(
        Layout::new(
            1,
            vec![
                CandidateSpec::columns("x", 1),
                CandidateSpec::columns("x", 2)
            ],
            1
        )
        .is_err()
    );
    assert!(select(&acc, &[], &SelectionOptions::default()).is_err());
    let bad = SelectionOptions {
        alpha: 1.5,
        ..Default::default()
    };
    assert!(select(&acc, std::slice::from_ref(&acc), &bad).is_err());
}

/// Rows `[1 | x | y | target]` of one group: the target is `x` with noise;
/// the column `y` is `x` plus `mix` times an independent draw plus `lean`
/// times the target's own noise (a column that leans towards this draw's
/// noise fits it a hair better).
fn tie_rows(seed: u64, n: usize, mix: f64, lean: f64) -> Vec<f64> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut g = || -> f64 { StandardNormal.sample(&mut rng) };
    (0..n)
        .flat_map(|_| {
            let x = g();
            let e = 0.8 * g();
            let y = x + mix * g() + lean * e;
            [1.0, x, y, 0.8 * x + e]
        })
        .collect()
}

/// Two laws the training data cannot tell apart (ΔBIC within `bic_tie`):
/// the one that predicts the held-out motions better is chosen, and the
/// lowest ΔBIC alone (`bic_tie = 0`) would take the other.
#[test]
fn a_tie_on_training_data_is_broken_by_the_validation_gain() {
    let l = Layout::new(
        1,
        vec![
            CandidateSpec::columns("x", 1),
            CandidateSpec::columns("y", 1),
        ],
        1,
    )
    .unwrap();
    let acc = |rows: &[f64]| {
        let mut a = Accumulator::new(&l);
        a.push_rows(0, rows).unwrap();
        a
    };
    // TRAIN: y is x leaning 0.2 % towards the noise: a slightly larger RSS drop.
    let train = acc(&tie_rows(1, 400, 0.0, 0.002));
    // Held out: y is x blurred by an independent 30 % draw.
    let vals = [
        acc(&tie_rows(2, 400, 0.3, 0.0)),
        acc(&tie_rows(3, 400, 0.3, 0.0)),
    ];
    let run = |bic_tie| {
        let s = select(
            &train,
            &vals,
            &SelectionOptions {
                bic_tie,
                ..SelectionOptions::default()
            },
        )
        .unwrap();
        let round = &s.rounds[0];
        let bic = |name: &str| round.iter().find(|e| e.name == name).unwrap().delta_bic;
        let gain = |name: &str| round.iter().find(|e| e.name == name).unwrap().mean_gain;
        assert!(
            bic("y") < bic("x") && bic("x") < bic("y") + 2.0,
            "{round:?}"
        );
        assert!(gain("x") > gain("y") + 1.0, "{round:?}");
        s.steps[0].name.clone()
    };
    assert_eq!(run(2.0), "x");
    assert_eq!(run(0.0), "y");
}

/// `select_with` judges each candidate with the fraction it is given for
/// the fit that adds it: a constant is `select` with that fraction, and
/// the F-test's `n_eff` of every candidate is the fraction of its own fit.
#[test]
fn select_with_counts_each_candidates_own_samples() {
    let l = layout();
    let truth = [0.5, -1.0, 2.0, 0.1, -0.08, 0.0];
    let sets: Vec<Accumulator> = (0..3)
        .map(|s| {
            accumulate(
                &l,
                &[
                    rows(70 + s, 1500, &truth, 0.5),
                    rows(80 + s, 1500, &truth, 0.5),
                ],
                256,
            )
        })
        .collect();
    let few = SelectionOptions {
        effective_fraction: 0.02,
        ..SelectionOptions::default()
    };
    let starved = select(&sets[0], &sets[1..], &few).unwrap();
    let same = aras_ident::selection::select_with(&sets[0], &sets[1..], &few, |_| 0.02).unwrap();
    assert_eq!(starved.added(), same.added());
    assert_eq!(starved.rounds, same.rounds);
    // 60 samples cannot tell a 0.1 effect from noise 0.5 (1.5σ); 3000 can.
    assert!(starved.added().is_empty());
    // Fraction 1 for fits that hold candidate `a`'s columns (3, 4), 0.02
    // for the others: `a` is counted with every row, `b` with 2 %.
    let per = aras_ident::selection::select_with(&sets[0], &sets[1..], &few, |f| {
        if f.columns.contains(&3) { 1.0 } else { 0.02 }
    })
    .unwrap();
    assert_eq!(per.added(), vec![0]);
    let first = &per.rounds[0];
    assert_eq!(first[0].n_eff, 3000.0);
    assert_eq!(first[1].n_eff, 60.0);
}
