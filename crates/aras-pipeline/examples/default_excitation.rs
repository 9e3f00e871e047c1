//! Designs the default excitation trajectory and writes the fixture the
//! acceptance tests use:
//!
//! ```text
//! cargo run --release -p aras-pipeline --example default_excitation
//! ```
//!
//! Paper model (42 columns, 23 base parameters) of `Params::aras_diamond()`,
//! base projection from [`aras_pipeline::robot::base_parameters`] (400 Halton
//! states), `DesignSettings::default()` (L = 5, ω_f = 2π/10, box and rates
//! (77), condition criterion, 8 starts) with seed 1. Writes
//! `fixtures/trajectories/default-excitation.json` (or the path given as the
//! first argument) and prints κ.

use std::path::PathBuf;

use aras_dyn::Params;
use aras_dyn::TaskRegressor;
use aras_excite::{DesignSettings, design};
use aras_kin::Workspace;
use aras_pipeline::robot::base_parameters;

/// Samples of the base analysis (the acceptance tests use the same number).
pub const BASE_SAMPLES: usize = 400;
/// Seed of the design.
pub const SEED: u64 = 1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let truth = Params::aras_diamond();
    let model = truth.model()?;
    let geometry = truth.geometry()?;
    let base = base_parameters(&model, &geometry, &Workspace::paper(), BASE_SAMPLES)?;
    let e = aras_excite::base_projection(&base);
    let settings = DesignSettings {
        seed: SEED,
        ..DesignSettings::default()
    };
    let d = design(&TaskRegressor::new(model, geometry), &e, &settings)?;
    let out = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../fixtures/trajectories/default-excitation.json")
        });
    d.trajectory.save(&out)?;
    println!(
        "{} base parameters; designed κ = {:.2} (worst margin {:.5}), {:.1} s; wrote {}",
        base.n_base(),
        d.condition_number,
        d.margins.worst_relative,
        d.elapsed.as_secs_f64(),
        out.display()
    );
    Ok(())
}
