//! How strong the "random feasible" baseline of the κ comparison is:
//! the median condition number of 100 random trajectories of the design's
//! form when each is scaled to touch a limit (the baseline the tests use),
//! and when the same trajectories keep only a fraction of that motion —
//! every one of them is still feasible. Shows why the ratio depends on the
//! baseline and why the tests keep the strongest one.
//!
//! `cargo run --release -p aras-excite --example random_baselines`

#[path = "../src/test_support.rs"]
mod test_support;

use aras_dyn::TaskRegressor;
use aras_excite::{DesignSettings, FourierTrajectory, assess, random_feasible};

fn scaled(t: &FourierTrajectory, s: f64) -> FourierTrajectory {
    let o = t.offset();
    let m = |v: &[f64]| -> Vec<f64> { v.iter().map(|c| c * s).collect() };
    FourierTrajectory::new(
        t.omega_f(),
        [o[0], o[1]],
        [m(t.a(0)), m(t.a(1))],
        [m(t.b(0)), m(t.b(1))],
    )
    .expect("a scaled feasible trajectory is valid")
}

fn main() {
    let reg = TaskRegressor::aras_diamond().expect("the paper's model");
    let e = test_support::base_projection(&reg, 400, 7);
    let s = DesignSettings {
        ..DesignSettings::default()
    };
    let random = random_feasible(&s, 100, 99).expect("default settings are valid");
    println!("median κ of 100 random feasible trajectories (seed 99), motion scaled by:");
    for f in [1.0, 0.9, 0.75, 0.5, 0.25] {
        let mut k: Vec<f64> = random
            .iter()
            .map(|t| {
                assess(&reg, &e, &scaled(t, f), s.criterion_points)
                    .expect("feasible trajectories stay in the workspace")
                    .condition_number
            })
            .collect();
        k.sort_by(f64::total_cmp);
        println!(
            "  {f:>4}: median {:8.1}  best {:8.1}  worst {:8.1}",
            0.5 * (k[49] + k[50]),
            k[0],
            k[99]
        );
    }
}
