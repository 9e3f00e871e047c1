//! Writes simulated joint logs with known friction:
//! `cargo run --release -p aras-friction --example simulate_joint -- DIR [EFFECT]`
//! with EFFECT one of `none` (default), `ripple`, `drift`, `asymmetry`.
//! Produces DIR/train.csv (speed 1), DIR/val_slow.csv (speed 0.6) and
//! DIR/val_fast.csv (speed 1.5), each 60 s.

use aras_friction::sim::{JointSimulation, Ripple};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = std::path::PathBuf::from(args.next().ok_or("usage: simulate_joint DIR [EFFECT]")?);
    let effect = args.next().unwrap_or_else(|| "none".into());
    std::fs::create_dir_all(&dir)?;
    let mut sim = JointSimulation::default();
    match effect.as_str() {
        "none" => {}
        "ripple" => sim.friction.ripple.push(Ripple {
            cycles: 12.0,
            amplitude: 0.04,
            phase: 0.3,
        }),
        "drift" => sim.friction.drift = -0.0015,
        "asymmetry" => sim.friction.asymmetry = 0.05,
        other => return Err(format!("unknown effect `{other}`").into()),
    }
    for (name, speed, seed) in [
        ("train", 1.0, 1),
        ("val_slow", 0.6, 2),
        ("val_fast", 1.5, 3),
    ] {
        let s = JointSimulation {
            speed,
            seed,
            ..sim.clone()
        };
        let log = s.run(name).log;
        std::fs::write(dir.join(format!("{name}.csv")), log.to_csv())?;
        println!("{}: {} rows", name, log.len());
    }
    Ok(())
}
