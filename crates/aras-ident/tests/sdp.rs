//! The physically consistent SDP on synthetic rigid bodies with known answers.
#![cfg(feature = "sdp")]
#![allow(clippy::needless_range_loop)]

mod common;

use aras_ident::{
    BaseParameters, ConsistentLs, ConstraintKind, IdentError, LinkLayout, ReducedLs, SdpSolution,
    pseudo_inertia_min_eigenvalue,
};
use aras_testkit::assert_source_not_repeated;
use faer::Mat;

const FRICTION: [&str; 6] = ["Fv1", "Fc1", "Fv2", "Fc2", "Fv3", "Fc3"];

fn truth_body() -> Vec<f64> {
    common::body_params(0.5, [0.1, 0.02, 0.3], [4e-3, 5e-3, 2e-3])
}

struct Problem {
    w: Mat<f64>,
    names: Vec<String>,
    base: BaseParameters,
    red: ReducedLs,
}

fn problem(seed: u64, beta: &[f64], bodies: usize, shared: bool, sigma: f64) -> Problem {
    let mut r = common::rng(seed);
    let (w, names) = common::multi_body(&mut r, 400, bodies, shared, true);
    let base = BaseParameters::from_regressor(w.as_ref(), &names, 1e-8).unwrap();
    let t = common::torques(&w, beta, sigma, &mut r);
    let wb = base.base_regressor(w.as_ref()).unwrap();
    let red = ReducedLs::new(wb.as_ref(), &t, &base.base_names()).unwrap();
    Problem {
        w,
        names,
        base,
        red,
    }
}

fn one_body_problem(p: &Problem, reference: Vec<f64>, mass_ref: f64) -> ConsistentLs {
    let mut c = ConsistentLs::new(&p.names, reference).unwrap();
    c.link(LinkLayout::new(
        "L1",
        [0, 1, 2, 3, 4, 5],
        [6, 7, 8],
        mass_ref,
    ))
    .unwrap();
    c.nonnegative(&FRICTION).unwrap();
    c
}

fn with_friction(body: Vec<f64>, friction: [f64; 6]) -> Vec<f64> {
    body.into_iter().chain(friction).collect()
}

fn kinds(s: &SdpSolution) -> Vec<(ConstraintKind, String)> {
    s.active.iter().map(|a| (a.kind, a.name.clone())).collect()
}

#[test]
fn feasible_ols_is_reproduced() {
    let beta = with_friction(truth_body(), [0.03, 0.08, 0.01, 0.3, 0.02, 0.1]);
    let p = problem(1, &beta, 1, false, 1e-3);
    let ols = p.red.ols().unwrap();
    // CAD-like reference: 10 % heavier body (still physical), other friction.
    let reference = with_friction(truth_body().iter().map(|v| 1.1 * v).collect(), [0.05; 6]);
    let sol = one_body_problem(&p, reference, 0.55)
        .solve(&p.base, &p.red)
        .unwrap();
    assert_eq!(sol.status, aras_ident::SolverStatus::Solved);
    assert!(sol.active.is_empty(), "{sol}");
    for i in 0..p.base.n_base() {
        // λ = 1e-6 on a column-scaled problem of condition ~10: bias ~1e-4
        // relative to σ at most; 0.02 σ leaves room for solver tolerance.
        let dz = (sol.base[i] - ols.estimate[i]) / ols.std_dev[i];
        assert!(dz.abs() < 0.02, "{}: {dz} σ", p.base.expression(i));
    }
    assert!(sol.residual_norm <= ols.residual_norm * (1.0 + 1e-6));
    assert!(sol.links[0].min_eigenvalue > 0.0);
    // The mass is not in the data: the regulariser takes the reference.
    assert!((sol.masses[0] - 0.55).abs() < 1e-4, "{}", sol.masses[0]);
    assert!(sol.iterations < 60);
}

#[test]
fn pseudo_inertia_violation_is_repaired_at_the_boundary() {
    // Non-physical data: Ixx > Iyy + Izz breaks the triangle inequality (69).
    let mut bad = truth_body();
    bad[0] = bad[3] + bad[5] + 0.02;
    let beta = with_friction(bad, [0.03, 0.08, 0.01, 0.3, 0.02, 0.1]);
    let p = problem(2, &beta, 1, false, 1e-4);
    let ols = p.red.ols().unwrap();
    let layout = LinkLayout::new("L1", [0, 1, 2, 3, 4, 5], [6, 7, 8], 0.5);
    // OLS violates (67)–(69) whatever the mass.
    for m in [0.4, 0.5, 0.6, 10.0] {
        assert!(pseudo_inertia_min_eigenvalue(&ols.estimate, &layout, m).unwrap() < 0.0);
    }
    let reference = with_friction(truth_body(), [0.05; 6]);
    let sol = one_body_problem(&p, reference.clone(), 0.5)
        .solve(&p.base, &p.red)
        .unwrap();
    assert_eq!(sol.status, aras_ident::SolverStatus::Solved);
    let link = &sol.links[0];
    assert!(link.psd_near_singular, "{sol}");
    assert!(
        kinds(&sol).contains(&(ConstraintKind::PseudoInertia, "L1".into())),
        "{sol}"
    );
    // Feasible, at the margin (to solver accuracy).
    assert!(
        link.min_eigenvalue_scaled >= link.margin * (1.0 - 1e-3),
        "{sol}"
    );
    assert!(link.min_eigenvalue >= 0.0);
    // Optimality: no worse than the best feasible point on the segment from
    // the (feasible) reference towards OLS, found by bisection.
    let point = |a: f64| -> Vec<f64> {
        reference
            .iter()
            .zip(&ols.estimate)
            .map(|(r, o)| r + a * (o - r))
            .collect()
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if pseudo_inertia_min_eigenvalue(&point(mid), &layout, 0.5).unwrap() >= 1e-6 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let seg = p
        .red
        .rss(&p.base.to_base(&point(lo)).unwrap())
        .unwrap()
        .sqrt();
    assert!(
        sol.residual_norm <= seg * 1.001,
        "SDP {} vs segment {seg}",
        sol.residual_norm
    );
    assert!(sol.residual_norm > ols.residual_norm);
}

#[test]
fn mass_upper_bound_binds_when_the_first_moment_needs_more_mass() {
    // True mass 0.5 kg, but the CAD says 0.3 kg (bounds 0.24–0.36 kg);
    // (67)–(69) need m ≥ hᵀΣ_O⁻¹h ≈ 0.47 kg for this body.
    let beta = with_friction(truth_body(), [0.03, 0.08, 0.01, 0.3, 0.02, 0.1]);
    let p = problem(3, &beta, 1, false, 1e-4);
    let reference = with_friction(
        common::body_params(0.3, [0.1, 0.02, 0.3], [4e-3, 5e-3, 2e-3]),
        [0.05; 6],
    );
    let sol = one_body_problem(&p, reference, 0.3)
        .solve(&p.base, &p.red)
        .unwrap();
    let k = kinds(&sol);
    assert!(
        k.contains(&(ConstraintKind::MassUpper, "L1".into())),
        "{sol}"
    );
    assert!(
        k.contains(&(ConstraintKind::PseudoInertia, "L1".into())),
        "{sol}"
    );
    assert!((sol.masses[0] - 0.36).abs() < 1e-6, "{}", sol.masses[0]);
}

#[test]
fn sign_constraint_binds_on_negative_friction() {
    // Fv1 = 0.1 stays positive when Fc1 is clamped: the best viscous-only
    // fit of 0.1 v − 0.05 sign v for v ~ U(−2, 2) is (0.1 − 0.05·E|v|/E v²) v
    // = 0.0625 v, so only Fc1 may be active.
    let beta = with_friction(truth_body(), [0.1, -0.05, 0.01, 0.3, 0.02, 0.1]);
    let p = problem(4, &beta, 1, false, 1e-3);
    let ols = p.red.ols().unwrap();
    assert!(ols.estimate[10] < -0.04);
    let reference = with_friction(truth_body(), [0.05; 6]);
    let sol = one_body_problem(&p, reference, 0.5)
        .solve(&p.base, &p.red)
        .unwrap();
    assert_eq!(
        kinds(&sol),
        vec![(ConstraintKind::NonNegative, "Fc1".to_string())],
        "{sol}"
    );
    assert!(sol.standard[10].abs() < 1e-7, "{}", sol.standard[10]);
}

#[test]
fn grouped_parameters_split_towards_the_reference() {
    // Two bodies moving together: only the sums are identifiable. The
    // regulariser weighs both bodies' (identical) columns equally, so the
    // data's correction to the reference sum is shared equally.
    let a = common::body_params(0.5, [0.1, 0.02, 0.3], [4e-3, 5e-3, 2e-3]);
    let b = common::body_params(0.3, [-0.05, 0.0, 0.2], [2e-3, 2e-3, 1e-3]);
    let beta: Vec<f64> = a
        .iter()
        .chain(&b)
        .copied()
        .chain([0.03, 0.08, 0.01, 0.3, 0.02, 0.1])
        .collect();
    let p = problem(5, &beta, 2, true, 1e-3);
    assert_eq!(p.base.n_base(), 15);
    let ols = p.red.ols().unwrap();
    // Reference: body A 4 % heavier in every parameter, body B exact, so the
    // data correct the sums by −0.04·A and each body takes half of that.
    let ra: Vec<f64> = a.iter().map(|v| 1.04 * v).collect();
    let rb = b.clone();
    let la = LinkLayout::new("L1", [0, 1, 2, 3, 4, 5], [6, 7, 8], 0.52);
    let lb = LinkLayout::new("L2", [0, 1, 2, 3, 4, 5], [6, 7, 8], 0.3);
    let half_a: Vec<f64> = a.iter().map(|v| 1.02 * v).collect();
    let half_b: Vec<f64> = b.iter().zip(&a).map(|(y, x)| y - 0.02 * x).collect();
    // Premise: the equal split is strictly physical, so no constraint binds.
    assert!(pseudo_inertia_min_eigenvalue(&half_a, &la, 0.52).unwrap() > 1e-5);
    assert!(pseudo_inertia_min_eigenvalue(&half_b, &lb, 0.3).unwrap() > 1e-5);
    let reference: Vec<f64> = ra.iter().chain(&rb).copied().chain([0.05; 6]).collect();
    let mut c = ConsistentLs::new(&p.names, reference.clone()).unwrap();
    c.link_by_names(
        "L1",
        ["L1.Ixx", "L1.Ixy", "L1.Ixz", "L1.Iyy", "L1.Iyz", "L1.Izz"],
        ["L1.hx", "L1.hy", "L1.hz"],
        0.52,
    )
    .unwrap()
    .link(LinkLayout::new(
        "L2",
        [9, 10, 11, 12, 13, 14],
        [15, 16, 17],
        0.3,
    ))
    .unwrap()
    .nonnegative(&FRICTION)
    .unwrap();
    let sol = c.solve(&p.base, &p.red).unwrap();
    assert!(sol.active.is_empty(), "{sol}");
    for i in 0..15 {
        let dz = (sol.base[i] - ols.estimate[i]) / ols.std_dev[i];
        assert!(dz.abs() < 0.02, "{}: {dz} σ", p.base.expression(i));
    }
    for j in 0..9 {
        let delta = ols.estimate[j] - (reference[j] + reference[9 + j]);
        let scale = reference[j].abs().max(reference[9 + j].abs());
        for (k, rk) in [(j, reference[j]), (9 + j, reference[9 + j])] {
            let expect = rk + 0.5 * delta;
            // Solver accuracy on a direction the data do not see: 1e-4 of the
            // parameter's scale.
            assert!(
                (sol.standard[k] - expect).abs() < 1e-4 * scale,
                "{}: {} vs {expect}",
                p.names[k],
                sol.standard[k]
            );
        }
    }
    assert!(sol.links.iter().all(|l| l.min_eigenvalue_scaled > l.margin));
    // Sanity of the data itself.
    assert_eq!(p.w.ncols(), 24);
}

#[test]
fn contradictory_bounds_are_reported_infeasible() {
    let beta = with_friction(truth_body(), [0.03, 0.08, 0.01, 0.3, 0.02, 0.1]);
    let p = problem(6, &beta, 1, false, 1e-3);
    let mut c = one_body_problem(&p, with_friction(truth_body(), [0.05; 6]), 0.5);
    // Pin Ixx ≫ Iyy + Izz: no physical body has that.
    c.bound(0, 1.0, 1.0)
        .unwrap()
        .bound(3, 0.01, 0.01)
        .unwrap()
        .bound(5, 0.01, 0.01)
        .unwrap();
    let e = c.solve(&p.base, &p.red).unwrap_err();
    assert!(matches!(e, IdentError::Infeasible { .. }), "{e}");
    assert!(e.to_string().contains("widen the mass bounds"), "{e}");
}

#[test]
fn layout_mistakes_are_named() {
    let names = common::body_names("L1");
    let mut c = ConsistentLs::new(&names, vec![0.0; 9]).unwrap();
    let e = c
        .link(LinkLayout::new("L1", [0, 1, 2, 3, 4, 4], [6, 7, 8], 0.5))
        .unwrap_err();
    assert!(e.to_string().contains("`L1.Iyz` is listed twice"), "{e}");
    let e = c
        .link(LinkLayout::new("L1", [0, 1, 2, 3, 4, 5], [6, 7, 9], 0.5))
        .unwrap_err();
    assert!(
        matches!(e, IdentError::IndexOutOfRange { index: 9, .. }),
        "{e}"
    );
    let e = c.nonnegative(&["Fv9"]).unwrap_err();
    assert!(e.to_string().contains("unknown parameter `Fv9`"), "{e}");
    let e = c
        .link(LinkLayout::new("L1", [0, 1, 2, 3, 4, 5], [6, 7, 8], -1.0))
        .unwrap_err();
    assert!(matches!(e, IdentError::InvalidLayout { .. }), "{e}");
    assert!(c.bound(2, 1.0, 0.0).is_err());
}

#[test]
fn external_errors_keep_their_source_and_statuses_are_typed() {
    let cause = std::io::Error::other("pose is singular");
    let e = aras_ident::IdentError::external("streaming regressor, sample 3", cause);
    assert_eq!(e.to_string(), "streaming regressor, sample 3");
    let src = std::error::Error::source(&e).expect("the model's error is the source");
    assert_eq!(src.to_string(), "pose is singular");
    assert!(src.downcast_ref::<std::io::Error>().is_some());
    assert_source_not_repeated(&e);

    use aras_ident::SolverStatus;
    // The names are the solver's, in messages and in JSON reports alike.
    assert_eq!(SolverStatus::AlmostSolved.to_string(), "AlmostSolved");
    assert_eq!(
        serde_json::to_string(&SolverStatus::AlmostSolved).unwrap(),
        "\"AlmostSolved\""
    );
    assert!(SolverStatus::Solved.is_solved() && SolverStatus::AlmostSolved.is_solved());
    assert!(!SolverStatus::MaxIterations.is_solved());
    let e = aras_ident::IdentError::SolverFailed {
        status: SolverStatus::MaxIterations,
        iterations: 7,
    };
    assert!(
        e.to_string()
            .contains("status MaxIterations after 7 iterations"),
        "{e}"
    );
}
