//! Times the default design on the test-only stand-in regressor (until the
//! real model is wired in, see `design_paper`): `cargo run --release -p
//! aras-excite --example design_stand_in`.

#[path = "../src/test_support.rs"]
mod test_support;

use aras_excite::{DesignSettings, design};

fn main() -> Result<(), aras_excite::ExciteError> {
    let reg = test_support::StandIn::default();
    let e = test_support::base_projection(&reg, 300, 7);
    let settings = DesignSettings::default();
    let d = design(&reg, &e, &settings)?;
    println!(
        "κ = {:.3}, worst relative margin {:.4} (on {} points), best start {}, {:.2} s",
        d.condition_number,
        d.margins.worst_relative,
        d.margins.points,
        d.best_start,
        d.elapsed.as_secs_f64()
    );
    for (k, s) in d.starts.iter().enumerate() {
        println!(
            "start {k}: {:.3} -> {:?}, converged {}, outer {}, inner {}, repair {:.6}, {:.2} s",
            s.initial_value,
            s.outcome,
            s.converged,
            s.outer_iterations,
            s.inner_iterations,
            s.repair_scale,
            s.time.as_secs_f64()
        );
    }
    Ok(())
}
