//! Designs the default excitation for the paper's 42-parameter model and
//! times it: `cargo run --release -p aras-excite --example design_paper`.
//! Settings can be changed with `key=value` arguments: `starts=24`,
//! `criterion_points=200`, `tolerance=1e-7`, `infeasibility_tolerance=1e-7`,
//! `max_outer_iterations=60`, `max_inner_iterations=1000`, `seed=2`,
//! `criterion=d_optimal` (`docs/excitation.md` names the runs it quotes).
//! The base projection comes from the test-only QR helper until
//! `aras-ident` provides it.

#[path = "../src/test_support.rs"]
mod test_support;

use aras_dyn::TaskRegressor;
use aras_excite::{Criterion, DesignSettings, assess, design, random_feasible};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let reg = TaskRegressor::aras_diamond()?;
    let e = test_support::base_projection(&reg, 400, 7);
    println!("{} columns, {} base parameters", e.nrows(), e.ncols());
    let mut settings = DesignSettings::default();
    for arg in std::env::args().skip(1) {
        let (key, value) = arg
            .split_once('=')
            .ok_or_else(|| format!("`{arg}`: give settings as key=value"))?;
        let bad = |e: &dyn std::fmt::Display| format!("`{arg}`: {e}");
        match key {
            "starts" => settings.starts = value.parse().map_err(|e| bad(&e))?,
            "seed" => settings.seed = value.parse().map_err(|e| bad(&e))?,
            "criterion_points" => settings.criterion_points = value.parse().map_err(|e| bad(&e))?,
            "tolerance" => settings.tolerance = value.parse().map_err(|e| bad(&e))?,
            "infeasibility_tolerance" => {
                settings.infeasibility_tolerance = value.parse().map_err(|e| bad(&e))?
            }
            "max_outer_iterations" => {
                settings.max_outer_iterations = value.parse().map_err(|e| bad(&e))?
            }
            "max_inner_iterations" => {
                settings.max_inner_iterations = value.parse().map_err(|e| bad(&e))?
            }
            "criterion" => {
                settings.criterion = match value {
                    "condition" => Criterion::Condition,
                    "d_optimal" => Criterion::DOptimal,
                    _ => return Err(bad(&"use condition or d_optimal").into()),
                }
            }
            _ => return Err(format!("`{arg}`: unknown setting `{key}`").into()),
        }
    }
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
