//! The pose-constraint hook on the stand-in regressor (ARAS-Diamond's task
//! coordinates `X = [φ, γ]`): a cone of directions about the box centre's,
//! `angle(d(X), d_c) ≤ ρ` with `d = [sin γ cos φ, sin γ sin φ, cos γ]`,
//! which cuts the corners of the box (77).

#[path = "../src/test_support.rs"]
mod test_support;

use aras_excite::{
    ConstraintSettings, DesignSettings, Dual, DualConstraint, ExciteError, FourierTrajectory,
    Margins, PoseConstraint, design, design_constrained, random_feasible_constrained,
};
use num_dual::DualNum;
use proptest::prelude::*;
use test_support::{StandIn, base_projection};

/// Cone half-angle (rad): the box's corners are up to 46° from its centre.
const RHO: f64 = 0.5;

/// `g(X) = cos ρ − d(X)·d_c ≤ 0`.
fn cone() -> DualConstraint<impl Fn(&[Dual], &mut [Dual]) + Sync> {
    let (pc, gc) = (85f64.to_radians(), 60f64.to_radians());
    let dc = [gc.sin() * pc.cos(), gc.sin() * pc.sin(), gc.cos()];
    DualConstraint::new(2, 1, move |x: &[Dual], g: &mut [Dual]| {
        let (p, y) = (x[0], x[1]);
        let d = [y.sin() * p.cos(), y.sin() * p.sin(), y.cos()];
        g[0] = -(d[0] * dc[0] + d[1] * dc[1] + d[2] * dc[2]) + RHO.cos();
    })
    .with_names(["cone"])
}

/// Largest `g` along `t` on `points` instants of a period.
fn worst(c: &impl PoseConstraint, t: &FourierTrajectory, points: usize) -> f64 {
    let mut g = [0.0];
    t.sample(points, 1)
        .iter()
        .map(|r| {
            c.eval(r.state.pos.as_slice(), &mut g).unwrap();
            g[0]
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

fn quick() -> DesignSettings {
    DesignSettings {
        starts: 3,
        ..DesignSettings::default()
    }
}

/// The unconstrained design leaves the cone; the constrained one stays
/// inside it on its check grid and on a grid 37× finer than the constraint
/// grid (off the check grid), keeps the box, and is still well conditioned.
#[test]
fn constrained_design_stays_in_the_cone() {
    let reg = StandIn::default();
    let e = base_projection(&reg, 300, 7);
    let s = quick();
    let c = cone();
    let free = design(&reg, &e, &s).unwrap();
    assert!(free.constraint.is_none());
    let fine = 37 * s.constraint_points + 1;
    let free_worst = worst(&c, &free.trajectory, fine);
    assert!(
        free_worst > 0.01,
        "the free design should leave the cone: {free_worst}"
    );

    let d = design_constrained(&reg, &e, &s, &c, &|_| {}).unwrap();
    let check = d.constraint.clone().unwrap();
    assert_eq!(check.points, 10 * s.constraint_points);
    assert_eq!(check.worst_name, "cone");
    assert!(check.estimated_max <= 0.0, "{check:?}");
    // The curvature allowance covers the maximum between check points.
    let fine_worst = worst(&c, &d.trajectory, fine);
    assert!(fine_worst <= 1e-12, "{fine_worst} ({check:?})");
    assert!(d.margins.worst_relative >= 0.0, "{:?}", d.margins);
    assert!(d.trajectory.eval(0.0).vel.norm() < 1e-12);
    println!(
        "cone ρ = {RHO} rad: free design κ = {:.3} (max g {free_worst:.4}), constrained κ = {:.3} \
         (max g on the check grid {:.3e}, allowance {:.3e}, on 37× finer {fine_worst:.3e}); \
         constraint scales {:?}",
        free.condition_number,
        d.condition_number,
        check.worst,
        check.allowance,
        d.starts
            .iter()
            .map(|r| r.constraint_scale)
            .collect::<Vec<_>>()
    );
    assert!(d.condition_number.is_finite() && d.condition_number > 1.0);
    // Same seed, same result.
    let again = design_constrained(&reg, &e, &s, &c, &|_| {}).unwrap();
    assert_eq!(again.trajectory, d.trajectory);
}

/// A margin is kept as clearance, and a constraint no rest pose meets is a
/// clear error naming the fix.
#[test]
fn margin_and_infeasible_constraint() {
    let s = DesignSettings {
        constraint: ConstraintSettings {
            margin: 0.02,
            ..Default::default()
        },
        ..quick()
    };
    let c = cone();
    for t in random_feasible_constrained(&s, &c, 10, 3).unwrap() {
        assert!(worst(&c, &t, 37 * s.constraint_points + 1) <= -0.02 + 1e-12);
    }
    let nowhere = DualConstraint::new(2, 1, |x: &[Dual], g: &mut [Dual]| {
        g[0] = x[1] * 0.0 + 0.5;
    });
    let e = random_feasible_constrained(&s, &nowhere, 1, 3).unwrap_err();
    assert!(matches!(e, ExciteError::ConstraintInfeasible { .. }), "{e}");
    assert!(e.to_string().contains("constraint.anchor"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    // Random feasible trajectories meet the constraint (37× finer than the
    // constraint grid) and the box, whatever the seed and cone.
    #[test]
    fn random_feasible_meets_the_constraint(seed in 0u64..10_000, rho in 0.3..0.9f64) {
        let (pc, gc) = (85f64.to_radians(), 60f64.to_radians());
        let dc = [gc.sin() * pc.cos(), gc.sin() * pc.sin(), gc.cos()];
        let c = DualConstraint::new(2, 1, move |x: &[Dual], g: &mut [Dual]| {
            let (p, y) = (x[0], x[1]);
            let d = [y.sin() * p.cos(), y.sin() * p.sin(), y.cos()];
            g[0] = -(d[0] * dc[0] + d[1] * dc[1] + d[2] * dc[2]) + rho.cos();
        });
        let s = DesignSettings::default();
        for t in random_feasible_constrained(&s, &c, 3, seed).unwrap() {
            let w = worst(&c, &t, 37 * s.constraint_points + 1);
            prop_assert!(w <= 1e-12, "{w}");
            prop_assert!(Margins::measure(&t, &s.limits, 2000).worst_relative >= 0.0);
        }
    }
}
