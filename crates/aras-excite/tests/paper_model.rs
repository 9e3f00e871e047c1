//! The design on the paper's 42-parameter model (aras-dyn), with a base
//! projection from the test-only QR helper (`src/test_support.rs`; the
//! product uses `aras_excite::base_projection`, whose column scaling
//! gives slightly different condition numbers, see docs/excitation.md).
//!
//! The acceptance of the design: feasible on a finer grid, within 5 % of
//! the best condition number found over 32 starts, and well below random
//! feasible trajectories that touch a limit. The σ% acceptance on
//! simulated data is in `crates/aras-ident/tests/acceptance.rs`
//! (`design_sigma_percent_below_5_for_parameters_above_1_percent_of_torque`),
//! which identifies from the design's logs.

#[path = "../src/test_support.rs"]
mod test_support;

use std::sync::OnceLock;

use aras_dyn::TaskRegressor;
use aras_excite::{Design, DesignSettings, Margins, assess, design, random_feasible};
use nalgebra::DMatrix;

struct Case {
    reg: TaskRegressor,
    e: DMatrix<f64>,
    settings: DesignSettings,
    /// The default design (8 starts, seed 1).
    default: Design,
}

fn case() -> &'static Case {
    static C: OnceLock<Case> = OnceLock::new();
    C.get_or_init(|| {
        let reg = TaskRegressor::aras_diamond().unwrap();
        let e = test_support::base_projection(&reg, 400, 7);
        let settings = DesignSettings::default();
        let default = design(&reg, &e, &settings).unwrap();
        Case {
            reg,
            e,
            settings,
            default,
        }
    })
}

/// 23 base parameters with g ⟂ a (`docs/model.md`, "Base parameters"); the
/// default design is feasible on a grid 23× finer (off the optimisation
/// grid) and on the 10× grid of its own margins.
#[test]
fn default_design_is_feasible_on_a_finer_grid() {
    let c = case();
    assert_eq!(c.e.ncols(), 23);
    let d = &c.default;
    assert!(d.margins.worst_relative >= 0.0, "{:?}", d.margins);
    assert_eq!(d.margins.points, 10 * c.settings.constraint_points);
    let finer = Margins::measure(
        &d.trajectory,
        &c.settings.limits,
        23 * c.settings.constraint_points + 7,
    );
    assert!(finer.worst_relative >= 0.0, "{finer:?}");
}

/// The default design (8 starts) is within 5 % of the best condition
/// number found over 32 starts of another seed: more starts would not
/// buy a meaningfully better excitation.
#[test]
fn default_design_condition_number_within_5_percent_of_best_over_32_starts() {
    let c = case();
    let wide = design(
        &c.reg,
        &c.e,
        &DesignSettings {
            starts: 32,
            seed: 2,
            ..c.settings.clone()
        },
    )
    .unwrap();
    let best = wide.condition_number.min(c.default.condition_number);
    println!(
        "default design κ = {:.1}; best over 32 starts (seed 2) κ = {:.1} (ratio {:.3})",
        c.default.condition_number,
        wide.condition_number,
        c.default.condition_number / best
    );
    assert!(
        c.default.condition_number <= 1.05 * best,
        "{} vs best {best}",
        c.default.condition_number
    );
}

/// The default design against 100 random feasible trajectories of the same
/// form, each scaled until it touches a limit (the strongest random
/// baseline): it beats every one, and its κ is at least 2× below their
/// median with this crate's test projection (measured 996 vs 2453, 2.46×).
/// The 2.5× acceptance uses the product's base projection:
/// `designed_excitation_2_5x_below_median_of_100_random_at_the_limits` in
/// `crates/aras-pipeline/tests/acceptance.rs` (2.82×).
#[test]
fn default_design_condition_number_2x_below_median_of_100_random_at_the_limits() {
    let c = case();
    let mut k: Vec<f64> = random_feasible(&c.settings, 100, 99)
        .unwrap()
        .iter()
        .map(|t| {
            assess(&c.reg, &c.e, t, c.settings.criterion_points)
                .unwrap()
                .condition_number
        })
        .collect();
    k.sort_by(f64::total_cmp);
    let median = 0.5 * (k[49] + k[50]);
    let d = c.default.condition_number;
    println!(
        "paper model: designed κ = {d:.1}, random feasible median {median:.1} (ratio {:.2}), best random {:.1}",
        median / d,
        k[0]
    );
    assert!(d < k[0]);
    assert!(2.0 * d <= median, "ratio {:.3}", median / d);
}
