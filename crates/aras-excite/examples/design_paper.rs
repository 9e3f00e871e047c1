//! Designs the default excitation for the paper's 42-parameter model and
//! times it: `cargo run --release -p aras-excite --example design_paper`.
//! The base projection comes from the test-only QR helper until
//! `aras-ident` provides it.

#[path = "../src/test_support.rs"]
mod test_support;

use aras_excite::{DesignSettings, DynRegressor, assess, design, random_feasible};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let reg = DynRegressor::aras_diamond()?;
    let e = test_support::base_projection(&reg, 400, 7);
    println!("{} columns, {} base parameters", e.nrows(), e.ncols());
    let settings = DesignSettings::default();
    let d = design(&reg, &e, &settings)?;
    println!(
        "designed κ = {:.2}, worst relative margin {:.5} on {} points/period, best start {}, {:.2} s",
        d.condition_number,
        d.margins.worst_relative,
        d.margins.points,
        d.best_start,
        d.elapsed.as_secs_f64()
    );
    for (k, s) in d.starts.iter().enumerate() {
        println!(
            "  start {k}: {:.1} -> {:?}, converged {}, outer {}, inner {}, {:.2} s",
            s.initial_value,
            s.outcome.as_ref().map(|v| format!("{v:.2}")),
            s.converged,
            s.outer_iterations,
            s.inner_iterations,
            s.time.as_secs_f64()
        );
    }
    let mut k: Vec<f64> = random_feasible(&settings, 100, 99)?
        .iter()
        .map(|t| assess(&reg, &e, t, settings.criterion_points).map(|a| a.condition_number))
        .collect::<Result<_, _>>()?;
    k.sort_by(f64::total_cmp);
    let med = 0.5 * (k[49] + k[50]);
    println!(
        "median κ of 100 random feasible: {med:.2} (ratio {:.2}); min {:.2}, max {:.2}",
        med / d.condition_number,
        k[0],
        k[99]
    );
    println!("{}", d.trajectory.to_json());
    Ok(())
}
