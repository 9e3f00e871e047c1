//! The design on the paper's 42-parameter model (aras-dyn), with a base
//! projection from the test-only QR helper (aras-ident will provide it).

#[path = "../src/test_support.rs"]
mod test_support;

use aras_excite::{DesignSettings, DynRegressor, Margins, assess, design, random_feasible};

/// 23 base parameters with g ⟂ a (spec §4 NOTE); the default design is
/// feasible on a 10× finer grid and beats every one of 100 random feasible
/// trajectories of the same form (scaled to touch the limits, the strongest
/// random baseline). Measured: κ ≈ 996 vs median ≈ 2453 (2.5×), best random
/// ≈ 1452; the 5× is not reached (see docs/excitation.md).
#[test]
fn paper_model_design() {
    let reg = DynRegressor::aras_diamond().unwrap();
    let e = test_support::base_projection(&reg, 400, 7);
    assert_eq!(e.ncols(), 23);
    let s = DesignSettings {
        ..DesignSettings::default()
    };
    let d = design(&reg, &e, &s).unwrap();
    assert!(d.margins.worst_relative >= 0.0, "{:?}", d.margins);
    assert_eq!(d.margins.points, 10 * s.constraint_points);
    let finer = Margins::measure(&d.trajectory, &s.limits, 23 * s.constraint_points + 7);
    assert!(finer.worst_relative >= 0.0, "{finer:?}");
    let mut k: Vec<f64> = random_feasible(&s, 100, 99)
        .unwrap()
        .iter()
        .map(|t| {
            assess(&reg, &e, t, s.criterion_points)
                .unwrap()
                .condition_number
        })
        .collect();
    k.sort_by(f64::total_cmp);
    let median = 0.5 * (k[49] + k[50]);
    println!(
        "paper model: designed κ = {:.1}, random feasible median {median:.1} (ratio {:.2}), best random {:.1}",
        d.condition_number,
        median / d.condition_number,
        k[0]
    );
    assert!(d.condition_number < k[0]);
    assert!(d.condition_number < median / 2.0);
}
