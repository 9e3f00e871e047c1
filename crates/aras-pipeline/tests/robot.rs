//! The adapter on the ARAS-Diamond model: base-parameter counts, OLS and SDP
//! on the default robot, parallel filtering.
#![allow(clippy::needless_range_loop)]

mod common;

use aras_dyn::{Effect, Model, Params};
use aras_ident::validate::{fitness_per_group, predict};
use aras_ident::{BaseParameters, ReducedLs, RowGroups};
use aras_kin::Motion;
use aras_kin::Workspace;
use aras_pipeline::robot::{FilterMode, consistent_problem, filter, params_from_solution, stack};
use aras_signal::{Butterworth, Samples};
use faer::Mat;
use nalgebra::{Vector2, Vector3};
use rand::RngExt;

/// Stacked regressor of `n` random workspace states (uniform pose in the
/// box (77), uniform rates within the limits, Gaussian accelerations).
fn random_regressor(model: &Model, n: usize, seed: u64) -> Mat<f64> {
    let p = Params::aras_diamond();
    let g = p.geometry().unwrap();
    let ws = Workspace::paper();
    let mut r = common::rng(seed);
    let (lo, hi, rate) = (ws.min(), ws.max(), ws.max_rate());
    let task: Vec<Motion> = (0..n)
        .map(|_| {
            Motion::new(
                Vector2::new(r.random_range(lo[0]..hi[0]), r.random_range(lo[1]..hi[1])),
                Vector2::new(
                    r.random_range(-rate[0]..rate[0]),
                    r.random_range(-rate[1]..rate[1]),
                ),
                Vector2::new(5.0 * common::normal(&mut r), 5.0 * common::normal(&mut r)),
            )
        })
        .collect();
    let w = model.stacked_from_states(&g, &task).unwrap();
    faer::MatRef::from_column_major_slice(w.as_slice(), 2 * n, model.columns()).to_owned()
}

fn count(effects: Vec<Effect>, gravity: [f64; 3]) -> (usize, BaseParameters) {
    let model = Model::new(effects, Vector3::from(gravity)).unwrap();
    let w = random_regressor(&model, 500, 3);
    let base = BaseParameters::from_regressor(w.as_ref(), &model.names(), 1e-8).unwrap();
    (base.n_base(), base)
}

#[test]
fn base_counts_match_the_independent_count() {
    let full = vec![
        Effect::RigidLinks,
        Effect::FRICTION_SIGN_LAW,
        Effect::Elasticity,
    ];
    let links = vec![Effect::RigidLinks];
    // docs/model.md, "Base parameters": g ⊥ a: 17 link / 23 full; g along a: 13 / 19.
    let (b, base) = count(full.clone(), [0.0, -9.81, 0.0]);
    assert_eq!(b, 23, "{base}");
    let m = base.rank_margin();
    assert!(m.smallest_kept > 1e-6 && m.largest_dropped < 1e-10, "{m:?}");
    assert_eq!(count(links.clone(), [0.0, -9.81, 0.0]).0, 17);
    assert_eq!(count(full, [0.0, 0.0, -9.81]).0, 19);
    assert_eq!(count(links, [0.0, 0.0, -9.81]).0, 13);
}

#[test]
fn default_robot_ols_and_sdp_round_trip() {
    let cad = Params::aras_diamond();
    let model = cad.model().unwrap();
    let names = model.names();
    let w = random_regressor(&model, 2000, 5);
    let base = BaseParameters::from_regressor(w.as_ref(), &names, 1e-8).unwrap();
    let truth = cad.standard_vector(&model).unwrap();
    let truth_b = base.to_base(truth.as_slice()).unwrap();
    let t = predict(w.as_ref(), truth.as_slice()).unwrap();
    let wb = base.base_regressor(w.as_ref()).unwrap();
    let red = ReducedLs::new(wb.as_ref(), &t, &base.base_names()).unwrap();
    let ols = red.ols().unwrap();
    // Noise-free: OLS recovers the true base parameters (condition number of
    // the random regressor ~1e3–1e4, rounding 1e-16: far inside 1e-6).
    let scale = truth_b.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    for i in 0..base.n_base() {
        assert!(
            (ols.estimate[i] - truth_b[i]).abs() <= 1e-6 * scale,
            "{}",
            base.expression(i)
        );
    }
    let groups = RowGroups::contiguous(&[2000, 2000]).unwrap();
    let fit =
        fitness_per_group(&t, &predict(wb.as_ref(), &ols.estimate).unwrap(), &groups).unwrap();
    assert!(fit.iter().all(|f| *f > 99.9999), "{fit:?}");
    // SDP towards a 10 % heavier CAD (physical, but wrong): the data pull
    // the identifiable combinations back to the truth.
    let mut heavy = cad.clone();
    for l in heavy.links.iter_mut() {
        l.ixx *= 1.1;
        l.ixy *= 1.1;
        l.ixz *= 1.1;
        l.iyy *= 1.1;
        l.iyz *= 1.1;
        l.izz *= 1.1;
        l.h *= 1.1;
        l.mass *= 1.1;
    }
    let problem = consistent_problem(&model, &heavy).unwrap();
    let sol = problem.solve(&base, &red).unwrap();
    eprintln!("{base}\n{sol}");
    assert!(
        sol.status == aras_ident::SolverStatus::Solved
            || sol.status == aras_ident::SolverStatus::AlmostSolved,
        "{sol}"
    );
    for i in 0..base.n_base() {
        // The truth is feasible, so the optimum is the truth up to the
        // regulariser's pull (λ = 1e-6) and solver accuracy.
        assert!(
            (sol.base[i] - truth_b[i]).abs() <= 1e-4 * scale,
            "{}: {} vs {}",
            base.expression(i),
            sol.base[i],
            truth_b[i]
        );
    }
    assert!(sol.links.iter().all(|l| l.min_eigenvalue >= 0.0), "{sol}");
    let identified = params_from_solution(&heavy, &model, &sol).unwrap();
    for k in 0..4 {
        assert!(
            identified
                .pseudo_inertia(k + 1)
                .unwrap()
                .symmetric_eigenvalues()
                .min()
                >= 0.0
        );
    }
    // The identified robot's mass matrix (80) is positive definite over the workspace.
    let rep = common::task_mass_pd(&identified, 21, 2000);
    assert!(rep.positive_definite(), "{rep:?}");
}

/// A smooth multi-sine trajectory inside the workspace, sampled at 200 Hz,
/// with its exact derivatives and the model's noise-free torques.
fn trajectory(model: &Model, beta: &[f64]) -> Samples {
    let p = Params::aras_diamond();
    let geo = p.geometry().unwrap();
    let fs = 200.0;
    let n = 4000;
    let d = f64::to_radians;
    // (amplitude rad, angular frequency rad/s, phase) per axis.
    let comps = [
        [(d(30.0), 0.9, 0.0), (d(10.0), 2.3, 1.0), (d(5.0), 4.1, 2.0)],
        [(d(12.0), 1.3, 0.5), (d(5.0), 3.1, 0.2), (d(3.0), 5.3, 1.7)],
    ];
    let centre = [d(85.0), d(60.0)];
    let mut s = Samples::with_joints(2);
    for i in 0..n {
        let t = i as f64 / fs;
        s.t.push(t);
        for a in 0..2 {
            let (mut x, mut xd, mut xdd) = (centre[a], 0.0, 0.0);
            for &(amp, w, ph) in &comps[a] {
                x += amp * (w * t + ph).sin();
                xd += amp * w * (w * t + ph).cos();
                xdd -= amp * w * w * (w * t + ph).sin();
            }
            s.x[a].push(x);
            s.x_dot[a].push(xd);
            s.x_ddot[a].push(xdd);
            s.tau[a].push(0.0);
        }
    }
    let _ = geo;
    let st = stack(model, &p.geometry().unwrap(), &s).unwrap();
    let tau = predict(st.w.as_ref(), beta).unwrap();
    for a in 0..2 {
        s.tau[a] = tau[a * n..(a + 1) * n].to_vec();
    }
    s
}

#[test]
fn parallel_filtering_keeps_the_fit_torque_only_does_not() {
    let cad = Params::aras_diamond();
    let model = cad.model().unwrap();
    let geo = cad.geometry().unwrap();
    let beta = cad.standard_vector(&model).unwrap();
    let w_rich = random_regressor(&model, 500, 9);
    let base = BaseParameters::from_regressor(w_rich.as_ref(), &model.names(), 1e-8).unwrap();
    let samples = trajectory(&model, beta.as_slice());
    let sos = Butterworth::lowpass(4, 5.0, 200.0).unwrap();
    let mut fits = Vec::new();
    for mode in [FilterMode::Parallel, FilterMode::TorqueOnly] {
        let mut st = stack(&model, &geo, &samples).unwrap();
        filter(&mut st, &sos, mode, false).unwrap();
        let wb = base.base_regressor(st.w.as_ref()).unwrap();
        let ols = ReducedLs::new(wb.as_ref(), &st.t, &base.base_names())
            .unwrap()
            .ols()
            .unwrap();
        let f = fitness_per_group(
            &st.t,
            &predict(wb.as_ref(), &ols.estimate).unwrap(),
            &st.groups,
        )
        .unwrap();
        fits.push(f);
    }
    // Filtering is linear: with parallel filtering T_f = W_f β holds exactly,
    // so the fit stays perfect; filtering only T smears the Coulomb jumps
    // while sign(θ̇) stays sharp.
    eprintln!("fitness parallel {:?}, torque-only {:?}", fits[0], fits[1]);
    assert!(fits[0].iter().all(|f| *f > 99.99), "{fits:?}");
    assert!(fits[1].iter().any(|f| *f < fits[0][0] - 0.1), "{fits:?}");
}

#[test]
fn mass_tolerance_sets_every_links_bounds_and_rejects_bad_fractions() {
    let p = Params::aras_diamond();
    let model = p.model().unwrap();
    let mut problem = consistent_problem(&model, &p).unwrap();
    problem.mass_tolerance(0.05).unwrap();
    for (l, link) in problem.links().iter().zip(&p.links) {
        // Exact products of the reference mass: only rounding of (1 ± 0.05)·m.
        assert!((l.mass_bounds.0 - 0.95 * link.mass).abs() <= 1e-15 * link.mass);
        assert!((l.mass_bounds.1 - 1.05 * link.mass).abs() <= 1e-15 * link.mass);
    }
    for bad in [-0.1, 1.0, f64::NAN] {
        let e = problem.mass_tolerance(bad).unwrap_err().to_string();
        assert!(e.contains("mass tolerance"), "{e}");
    }
}

/// The reversal mask's O(n) sweep equals the definition (drop joint j's row
/// i if |θ̇_j| < v_min anywhere within `guard` samples, circularly when
/// periodic), for any rates, guards from 0 to beyond the record, both modes.
mod reversal_mask_sweep {
    use aras_pipeline::robot::reversal_mask;
    use proptest::prelude::*;

    fn by_definition(td: &[Vec<f64>; 2], v_min: f64, guard: usize, periodic: bool) -> Vec<bool> {
        let n = td[0].len();
        let mut keep = vec![true; 2 * n];
        for j in 0..2 {
            for i in 0..n {
                for (k, v) in td[j].iter().enumerate() {
                    let d = i.abs_diff(k);
                    let d = if periodic { d.min(n - d) } else { d };
                    if d <= guard && v.abs() < v_min {
                        keep[j * n + i] = false;
                    }
                }
            }
        }
        keep
    }

    proptest! {
        #[test]
        fn equals_definition(
            a in proptest::collection::vec(-1.0f64..1.0, 0..60),
            b_seed in proptest::collection::vec(-1.0f64..1.0, 60),
            guard in 0usize..70,
            periodic: bool,
            v_min in 0.0f64..0.6,
        ) {
            let b: Vec<f64> = b_seed[..a.len()].to_vec();
            let td = [a, b];
            let got = reversal_mask(&td, v_min, guard, periodic).unwrap();
            prop_assert_eq!(got, by_definition(&td, v_min, guard, periodic));
        }
    }
}

/// The pseudo-inertia has two homes that cannot share code: the model's
/// (`aras_dyn::Inertia::pseudo_inertia`, from a link's parameters) and the
/// robot-agnostic SDP's (`aras_ident`, from a parameter vector and a
/// `LinkLayout`, as its PSD constraint (67)–(69) needs). They must agree:
/// the smallest eigenvalue of every link, for the default robot and for
/// links made non-physical in each way (tensor, first moment, mass), to
/// rounding (1e-15 kg·m² on eigenvalues of order 1e-3).
#[test]
fn model_and_sdp_pseudo_inertias_agree() {
    let model = Model::paper(Vector3::new(0.0, -9.81, 0.0)).unwrap();
    let names = model.names();
    let index = |n: String| names.iter().position(|m| *m == n).unwrap();
    let mut variants = vec![Params::aras_diamond()];
    for k in 0..4 {
        let mut p = Params::aras_diamond();
        match k {
            0 => p.links[0].ixx = -p.links[0].ixx,
            1 => p.links[1].h.x *= 40.0,
            2 => p.links[2].mass *= 0.01,
            _ => p.links[3].iyz = 0.9 * p.links[3].iyy,
        }
        variants.push(p);
    }
    let mut negative = 0;
    for p in &variants {
        let beta = p.standard_vector(&model).unwrap();
        for (k, link) in p.links.iter().enumerate() {
            let f = |s: &str| index(format!("L{}.{s}", k + 1));
            let layout = aras_ident::LinkLayout::new(
                format!("L{}", k + 1),
                ["Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"].map(f),
                ["hx", "hy", "hz"].map(f),
                link.mass,
            );
            let sdp =
                aras_ident::pseudo_inertia_min_eigenvalue(beta.as_slice(), &layout, link.mass)
                    .unwrap();
            let j = link.pseudo_inertia();
            let a: [[f64; 4]; 4] = std::array::from_fn(|r| std::array::from_fn(|c| j[(r, c)]));
            let own = aras_ident::symmetric_eigenvalues(&a)[0];
            assert!((sdp - own).abs() < 1e-15, "link {}: {sdp} vs {own}", k + 1);
            negative += usize::from(own < 0.0);
        }
    }
    // Every broken variant breaks exactly its link.
    assert_eq!(negative, 4, "{negative}");
}

/// The filter's reach (how far the exclusion widens around a reversal)
/// equals the reach read off the impulse response on a record as long as
/// the whole log, for filters from 2 to 50 Hz at 1 and 10 kHz, although it
/// is computed on a short record: away from the ends the response does not
/// depend on the record's length.
#[test]
fn filter_reach_equals_the_whole_record_reach() {
    use aras_pipeline::robot::filter_reach;
    for (order, fc, fs) in [
        (2, 2.0, 1000.0),
        (4, 10.0, 1000.0),
        (4, 10.0, 10_000.0),
        (6, 50.0, 1000.0),
    ] {
        let sos = Butterworth::lowpass(order, fc, fs).unwrap();
        for n in [3000, 70_001] {
            for tol in [1e-3, 0.5] {
                let mut x = vec![0.0; n];
                x[n / 2] = 1.0;
                let h = sos.filtfilt(&x).unwrap();
                let peak = h.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                let want = h
                    .iter()
                    .enumerate()
                    .filter(|(_, v)| v.abs() > tol * peak)
                    .map(|(i, _)| i.abs_diff(n / 2))
                    .max()
                    .unwrap();
                let got = filter_reach(&sos, n, false, tol).unwrap();
                assert_eq!(
                    got, want,
                    "order {order}, {fc} Hz at {fs} Hz, n {n}, tol {tol}"
                );
            }
        }
    }
}

mod filtering_together {
    use super::*;
    use aras_pipeline::robot::{filter_columns, filter_many_columns};
    use proptest::prelude::*;
    use rand::SeedableRng;

    /// A `2n × k` joint-major matrix: random, with column `zero` (if any)
    /// zero in joint 2's rows (a per-joint effect's column).
    fn matrix(n: usize, k: usize, seed: u64, zero: Option<usize>) -> Mat<f64> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        Mat::from_fn(2 * n, k, |i, j| {
            let v: f64 = rng.random_range(-1.0..1.0);
            if Some(j) == zero && i >= n { 0.0 } else { v }
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// Several matrices filtered together (their joint blocks sharing
        /// the filter's lanes) equal each filtered on its own, zero blocks
        /// staying zero; the periodic filter too. The lanes run the same
        /// arithmetic, but a signal may take the single-lane or the
        /// eight-lane loop, which may contract to FMA differently: 1e-13
        /// of the column's scale.
        #[test]
        fn together_equals_one_by_one(
            n in 80usize..400,
            widths in proptest::collection::vec(1usize..6, 1..6),
            seed in 0u64..1000,
            periodic: bool,
        ) {
            let sos = Butterworth::lowpass(4, 10.0, 1000.0).unwrap();
            let mats: Vec<Mat<f64>> = widths
                .iter()
                .enumerate()
                .map(|(i, &k)| matrix(n, k, seed + i as u64, (i % 2 == 0).then_some(0)))
                .collect();
            let mut alone = mats.clone();
            for m in &mut alone {
                filter_columns(m, n, &sos, periodic).unwrap();
            }
            let mut together = mats.clone();
            let mut refs: Vec<&mut Mat<f64>> = together.iter_mut().collect();
            filter_many_columns(&mut refs, n, &sos, periodic).unwrap();
            for (a, b) in alone.iter().zip(&together) {
                for j in 0..a.ncols() {
                    for i in 0..a.nrows() {
                        prop_assert!((a[(i, j)] - b[(i, j)]).abs() <= 1e-13, "({i}, {j})");
                    }
                }
            }
            for (m, t) in mats.iter().zip(&together).step_by(2) {
                for i in n..2 * n {
                    prop_assert_eq!(m[(i, 0)], 0.0);
                    prop_assert_eq!(t[(i, 0)], 0.0);
                }
            }
            // A matrix of the wrong height is refused.
            let mut bad = Mat::<f64>::zeros(2 * n + 1, 1);
            prop_assert!(filter_many_columns(&mut [&mut bad], n, &sos, periodic).is_err());
        }
    }
}
