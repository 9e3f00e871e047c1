//! `aras excite`: design the excitation trajectory alone.

use anyhow::Result;

use crate::cli::ExciteArgs;
use crate::identify::base_parameters;
use crate::output::{FileKind, NewFile};
use crate::robot::{nominal, paper_model};
use crate::stages::Stages;

/// Runs `excite`.
pub fn run(args: &ExciteArgs) -> Result<()> {
    if let Some(urdf) = &args.urdf {
        return super::urdf::excite(args, urdf);
    }
    let loaded = super::load_config(&args.common)?;
    let mut cfg = loaded.config.clone();
    if let Some(s) = args.seed {
        cfg.trajectory.seed = s;
    }
    let out = NewFile::create(
        &args.out,
        args.common.force,
        FileKind::Trajectory,
        &super::input_files(&args.common, &loaded, &[]),
    )?;
    let mut stages = Stages::new(args.common.quiet);
    let nominal = nominal(&cfg.robot, &loaded.dir)?;
    let model = paper_model(&nominal)?;
    let base = stages.run("base parameters (58)", |_| {
        base_parameters(&model, &nominal.geometry()?, &cfg)
    })?;
    let d = stages.run("excitation design (74)–(77)", |bar| {
        crate::excite::design(&cfg, &nominal, &base, bar)
    })?;
    out.write((d.trajectory.to_json() + "\n").as_bytes())?;
    out.commit()?;
    println!(
        "{}: condition number {:.3} ({} base parameters), worst relative limit margin {:.4}",
        args.out.display(),
        d.condition_number,
        base.n_base(),
        d.margins.worst_relative
    );
    Ok(())
}
