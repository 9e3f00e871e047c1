//! `aras pipeline`: the whole mission on the simulated robot.

use anyhow::{Context, Result};
use aras_log::{ReadOptions, read_log};

use crate::cli::PipelineArgs;
use crate::cmd::fit::{self, FitInput};
use crate::identify::base_parameters;
use crate::output::OutDir;
use crate::robot::{nominal, paper_model};
use crate::simulate::{run_and_write, sim_config, truth};
use crate::stages::Stages;

/// Runs the pipeline; prints the paper-vs-ours table on stdout.
pub fn run(args: &PipelineArgs) -> Result<()> {
    let loaded = super::load_config(&args.common)?;
    if args.print_config {
        print!("{}", loaded.config.to_toml());
        return Ok(());
    }
    let mut cfg = loaded.config.clone();
    if let Some(s) = args.seed {
        cfg.trajectory.seed = s;
        cfg.simulation.seed = s;
    }
    let out = OutDir::create(
        &args.out,
        args.common.force,
        &super::input_files(&args.common, &loaded, &[]),
    )?;
    let mut stages = Stages::new(args.common.quiet);
    let nominal = nominal(&cfg.robot, &loaded.dir)?;
    let truth = truth(&cfg, &loaded.dir, &nominal)?;
    let model = paper_model(&nominal)?;
    let geometry = nominal.geometry()?;

    let base = stages.run("base parameters (58)", |_| {
        base_parameters(&model, &geometry, &cfg)
    })?;
    let design = stages.run("excitation design (74)–(77)", |bar| {
        crate::excite::design(&cfg, &nominal, &base, bar)
    })?;
    out.write("trajectory.json", design.trajectory.to_json() + "\n")?;

    let period = design.trajectory.period();
    let sim = sim_config(
        &cfg,
        &nominal,
        cfg.simulation.periods as f64 * period,
        cfg.simulation.seed,
    );
    let noise = sim.sensors.torque_noise_std();
    let csv = out.path("log.csv");
    let simulated = stages.run("simulate robot", |_| {
        run_and_write(&truth, &design.trajectory, &sim, &csv)
    })?;
    let log = stages
        .run("read log", |_| read_log(&csv, &ReadOptions::default()))
        .context("reading back the simulated log")?;
    out.write("config.toml", cfg.to_toml())?;

    let intro = format!(
        "Simulated ARAS-Diamond ({}), {} periods of the designed excitation at {} Hz logged after a {} s lead-in, seed {}. \
         Sensor noise: current σ = {:?} A → joint torque σ = [{:.4}, {:.4}] N·m, encoder resolution {:.3e} rad \
         (docs/simulator.md: a Maxon RE 35-class motor, 10 mA current-sense noise, 1024-line encoder, capstan 10:1). \
         PD control (Kp = {:?}, Kd = {:?}){}.",
        if cfg.simulation.truth.is_some() {
            "truth from simulation.truth"
        } else {
            "truth = nominal robot"
        },
        cfg.simulation.periods,
        cfg.simulation.rate_hz,
        sim.lead_in_samples() as f64 / sim.output_rate_hz,
        cfg.simulation.seed,
        cfg.simulation.current_noise_std_a,
        noise[0],
        noise[1],
        sim.sensors.resolution()[0],
        cfg.simulation.kp,
        cfg.simulation.kd,
        if cfg.simulation.feedforward {
            " with model feedforward"
        } else {
            ""
        },
    );
    let summary = fit::run(
        FitInput {
            cfg: &cfg,
            nominal: &nominal,
            truth: Some(&truth),
            clean_torque: Some(&simulated.tau_clean),
            cross_validate: true,
            log: &log,
            period: None,
            design: Some(&design),
            base: &base,
            model: &model,
            command: "pipeline",
            seed: Some(cfg.simulation.seed),
            noise: Some(noise),
            reproducible: args.reproducible,
            intro,
        },
        &out,
        &mut stages,
    )?;
    let dir = out.commit()?;
    println!("{}", fit::terminal_table(&summary));
    println!(
        "outputs in {} (report.html, report.md, summary.json, params.json, robot.xml, base.json)",
        dir.display()
    );
    Ok(())
}
