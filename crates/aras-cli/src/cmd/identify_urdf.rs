//! `aras identify --urdf R.urdf --data LOG.csv`: a serial or tree robot
//! from its URDF, identified by `aras_urdf::identify` (`docs/urdf.md`).
//! The command reads, writes and reports; the recipe is the library's.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use aras_urdf::identify::{IdentifySettings, UrdfIdentification, identify};
use aras_urdf::{ModelSettings, UrdfModel};
use serde::Serialize;

use crate::cli::IdentifyArgs;
use crate::output::OutDir;

/// `format` of the `params.json` a URDF identification writes.
pub const FORMAT: &str = "aras-urdf-params/1";

/// The `params.json` of a URDF identification.
#[derive(Serialize)]
struct UrdfParams<'a> {
    format: &'static str,
    urdf: String,
    log: String,
    joints: Vec<String>,
    #[serde(flatten)]
    identification: &'a UrdfIdentification,
}

/// The model `identify --urdf` fits: the library's defaults (gravity
/// −9.81 m/s² along the root's `z`; viscous, Coulomb and armature per
/// joint) with the Coulomb law smoothed as `tanh(q̇ / 0.02 rad/s)`, the
/// sign law's jump at a reversal being what no drive shows.
pub fn model_settings() -> ModelSettings {
    ModelSettings {
        coulomb_width: aras_urdf::CoulombWidth::Uniform(COULOMB_WIDTH),
        ..ModelSettings::default()
    }
}

/// The Coulomb width of [`model_settings`], rad/s (m/s).
pub const COULOMB_WIDTH: f64 = 0.02;

/// Runs `identify --urdf`.
pub fn run(args: &IdentifyArgs, urdf: &Path) -> Result<()> {
    if !args.effects.is_empty() {
        bail!(
            "--effects names ARAS-Diamond's extra effects; a URDF robot's model is its bodies \
             with viscous and Coulomb friction and armature per joint (docs/urdf.md)"
        );
    }
    let text = std::fs::read_to_string(urdf)
        .with_context(|| format!("cannot read the URDF {}", urdf.display()))?;
    let file = urdf.display().to_string();
    let model = UrdfModel::from_urdf_str(&text, &file, model_settings())?;
    let inputs: Vec<PathBuf> = [args.data.clone(), urdf.to_path_buf()]
        .into_iter()
        .chain(args.common.config.iter().cloned())
        .collect();
    let out = OutDir::create(&args.out, args.common.force, &inputs)?;
    let options = aras_log::ReadOptions {
        joints: Some(model.dof()),
        ..aras_log::ReadOptions::default()
    };
    let log = aras_log::read_log(&args.data, &options)?;
    for n in &log.notes {
        eprintln!("note: {n}");
    }
    let settings = IdentifySettings {
        period: args.log.period,
        ..IdentifySettings::default()
    };
    let id = identify(&model, &log, &settings)
        .with_context(|| format!("identifying {} from {}", file, args.data.display()))?;
    out.write_json(
        "params.json",
        &UrdfParams {
            format: FORMAT,
            urdf: file.clone(),
            log: args.data.display().to_string(),
            joints: model.joint_names(),
            identification: &id,
        },
    )?;
    out.write(
        "robot_identified.urdf",
        model.identified_urdf(&text, &file, &id.standard)?,
    )?;
    out.write("robot.xml", model.to_mjcf(&id.standard)?)?;
    let dir = out.commit()?;
    println!(
        "{}: {} joints, {} processed samples, {} base parameters; physically consistent estimate: {:?}",
        model.name(),
        model.dof(),
        id.samples,
        id.ols.len(),
        id.status
    );
    for (name, f) in model.joint_names().iter().zip(&id.fitness) {
        println!("  {name}: fitness (78) {f:.2} % on the processed samples");
    }
    println!("outputs in {}", dir.display());
    Ok(())
}
