//! `aras simulate`: the simulated robot tracking a trajectory file or (79).

use std::path::Path;

use anyhow::{Context, Result, bail};
use aras_dyn::Sinusoid;
use aras_excite::FourierTrajectory;

use crate::cli::SimulateArgs;
use crate::output::{FileKind, NewFile};
use crate::robot::nominal;
use crate::simulate::{run_and_write, sim_config, truth};
use crate::stages::Stages;

/// Runs `simulate`.
pub fn run(args: &SimulateArgs) -> Result<()> {
    if let Some(urdf) = &args.urdf {
        return super::urdf::simulate(args, urdf);
    }
    let loaded = super::load_config(&args.common)?;
    let mut cfg = loaded.config.clone();
    if let Some(s) = args.seed {
        cfg.simulation.seed = s;
    }
    let trajectory: Vec<&Path> = args.trajectory.iter().map(|p| p.as_path()).collect();
    let out = NewFile::create(
        &args.out,
        args.common.force,
        FileKind::SimulatedLog,
        &super::input_files(&args.common, &loaded, &trajectory),
    )?;
    let mut stages = Stages::new(args.common.quiet);
    let nominal = nominal(&cfg.robot, &loaded.dir)?;
    let truth = truth(&cfg, &loaded.dir, &nominal)?;
    let periods = cfg.simulation.periods as f64;
    let log = match (&args.trajectory, args.frequency) {
        (Some(path), _) => {
            let tr = FourierTrajectory::load(path)
                .with_context(|| format!("reading the trajectory {}", path.display()))?;
            check_in_box(&tr, &cfg, path)?;
            let sim = sim_config(&cfg, &nominal, periods * tr.period(), cfg.simulation.seed);
            stages.run("simulate robot", |_| {
                run_and_write(&truth, &tr, &sim, &out.path())
            })?
        }
        (None, Some(f)) => {
            let tr = Sinusoid::paper_79(f).context("option --frequency")?;
            let sim = sim_config(&cfg, &nominal, periods / f, cfg.simulation.seed);
            stages.run("simulate robot", |_| {
                run_and_write(&truth, &tr, &sim, &out.path())
            })?
        }
        (None, None) => {
            bail!("give --trajectory FILE (from `aras excite`) or --frequency HZ (trajectory (79))")
        }
    };
    out.commit()?;
    println!(
        "{} ({} rows) and {}",
        args.out.display(),
        log.len(),
        aras_log::sidecar_path(&args.out).display()
    );
    Ok(())
}

/// A trajectory file must stay in the workspace box (77) of
/// `[trajectory]` (the designed ones do, by construction): found before the
/// simulation rather than as a robot driven into its stops or through a
/// singularity. Checked on 2000 instants of a period (the trajectory is
/// periodic).
fn check_in_box(tr: &FourierTrajectory, cfg: &crate::config::Config, path: &Path) -> Result<()> {
    let (lo, hi) = (cfg.trajectory.min_deg, cfg.trajectory.max_deg);
    let names = ["φ", "γ"];
    for row in tr.sample(2000, 1) {
        for i in 0..2 {
            let deg = row.state.pos[i].to_degrees();
            if !(lo[i]..=hi[i]).contains(&deg) {
                bail!(
                    "{}: the trajectory leaves the workspace box (77): {} = {deg:.2}° at t = {:.4} s, \
                     outside [{}, {}]° (config keys trajectory.min_deg / trajectory.max_deg); \
                     shift its offset or scale its coefficients down, or design one with `aras excite`",
                    path.display(),
                    names[i],
                    row.t,
                    lo[i],
                    hi[i]
                );
            }
        }
    }
    Ok(())
}
