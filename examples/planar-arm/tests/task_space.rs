//! A task-space limit through `aras-excite`'s pose-constraint hook: the
//! 3-link chain's joints 2, 3 and its tip stay above a table, `y ≥ h`,
//! while the design runs in joint space. `g(q) = h − y_k(q)` for the two
//! elbows and the tip, written once in dual numbers.

use aras_excite::{
    DesignSettings, Dual, DualConstraint, FourierTrajectory, Margins, PoseConstraint,
    random_feasible_constrained,
};
use nalgebra::Dyn;
use num_dual::DualNum;
use planar_arm::chain::{Chain, limits};
use proptest::prelude::*;

/// Table height (m): the base is at y = 0, the links 0.3, 0.25, 0.15 m.
const TABLE: f64 = -0.1;

/// `g_k = h − y_{k+1}(q)`: heights of joint 2, joint 3 and the tip.
fn above_table(length: Vec<f64>) -> DualConstraint<impl Fn(&[Dual], &mut [Dual]) + Sync> {
    let n = length.len();
    DualConstraint::new(n, n, move |q: &[Dual], g: &mut [Dual]| {
        let (mut theta, mut y) = (Dual::from_re(0.0), Dual::from_re(0.0));
        for i in 0..n {
            theta += q[i];
            y += theta.sin() * length[i];
            g[i] = -y + TABLE;
        }
    })
    .with_names(["joint 2", "joint 3", "tip"])
}

/// Largest `g_k` along `t` on `points` instants of a period.
fn worst(c: &impl PoseConstraint, t: &FourierTrajectory<Dyn>, points: usize) -> f64 {
    let (n, m) = (c.coordinates(), c.values());
    let (mut q, mut qd, mut qdd, mut g) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; m]);
    let mut w = f64::NEG_INFINITY;
    for j in 0..points {
        t.eval_into(
            j as f64 * t.period() / points as f64,
            &mut q,
            &mut qd,
            &mut qdd,
        );
        c.eval(&q, &mut g).unwrap();
        w = g.iter().copied().fold(w, f64::max);
    }
    w
}

/// The chain's design settings (as `planar_arm::chain::identify`'s).
fn settings() -> DesignSettings<Dyn> {
    DesignSettings {
        harmonics: 3,
        omega_f: std::f64::consts::TAU / 5.0,
        starts: 6,
        ..DesignSettings::new(limits(3))
    }
}

/// The unconstrained design dips below the table; the constrained one
/// stays above it on its check grid (10× the constraint grid) and on a grid
/// 37× finer than the constraint grid, keeps the joint limits and its
/// scaled base regressor stays well conditioned.
#[test]
fn constrained_design_stays_above_the_table() {
    let chain = Chain::three_links();
    let model = chain.model();
    let base = planar_arm::base_parameters_of(&model, 400).unwrap();
    let e = aras_excite::base_projection(&base);
    let s = settings();
    let c = above_table(chain.length.clone());
    let fine = 37 * s.constraint_points + 1;

    let free = aras_excite::design(&model, &e, &s).unwrap();
    let free_worst = worst(&c, &free.trajectory, fine);
    assert!(
        free_worst > 0.02,
        "the unconstrained design should go below the table: max g = {free_worst}"
    );

    let d = aras_excite::design_constrained(&model, &e, &s, &c, &|_| {}).unwrap();
    let check = d.constraint.clone().unwrap();
    assert!(check.estimated_max <= 0.0, "{check:?}");
    let fine_worst = worst(&c, &d.trajectory, fine);
    assert!(
        fine_worst <= 1e-12,
        "{fine_worst} m above the limit ({check:?})"
    );
    assert!(d.margins.worst_relative >= 0.0, "{:?}", d.margins);
    let finer = Margins::measure(&d.trajectory, &s.limits, fine);
    assert!(finer.worst_relative >= 0.0, "{finer:?}");
    println!(
        "3-link chain, table at y = {TABLE} m: unconstrained κ = {:.2} (lowest point {:.4} m below \
         the table), constrained κ = {:.2} (closest: {} {:.3e} m above the table on the check \
         grid, curvature allowance {:.2e} m; on 37× finer {:.3e} m); anchor {:?}",
        free.condition_number,
        free_worst,
        d.condition_number,
        check.worst_name,
        -check.worst,
        check.allowance,
        -fine_worst,
        check.anchor
    );
    assert!(d.condition_number.is_finite());
    // The constraint costs conditioning, but the design is still far better
    // than a typical random feasible trajectory that meets it.
    let mut random: Vec<f64> = random_feasible_constrained(&s, &c, 15, 7)
        .unwrap()
        .iter()
        .map(|t| aras_excite::assess(&model, &e, t, s.criterion_points).unwrap())
        .map(|a| a.condition_number)
        .collect();
    random.sort_by(f64::total_cmp);
    println!(
        "random feasible κ (meeting the table) median {:.2}",
        random[7]
    );
    assert!(d.condition_number < random[7]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    // Random feasible trajectories meet the table (37× finer than the
    // constraint grid) and the joint limits, whatever the seed.
    #[test]
    fn random_feasible_stays_above_the_table(seed in 0u64..100_000) {
        let chain = Chain::three_links();
        let c = above_table(chain.length.clone());
        let s = settings();
        for t in random_feasible_constrained(&s, &c, 4, seed).unwrap() {
            let w = worst(&c, &t, 37 * s.constraint_points + 1);
            prop_assert!(w <= 1e-12, "{w}");
            prop_assert!(Margins::measure(&t, &s.limits, 2000).worst_relative >= 0.0);
        }
    }
}
