//! The commands on a serial or tree robot from its URDF (`--urdf`,
//! `docs/urdf.md`): excite, simulate, identify, predict, validate and
//! diagnose. They read, write and report; every recipe is `aras-urdf`'s.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use aras_urdf::identify::{IdentifySettings, UrdfIdentification};
use aras_urdf::{ModelSettings, StribeckColumn, UrdfModel};
use serde::Serialize;

use aras_excite::FourierTrajectory;
use aras_urdf::diagnose::DiagnoseSettings;
use aras_urdf::excite::{ExciteSettings, design_excitation};
use aras_urdf::predict::PredictSettings;
use aras_urdf::sim::{ArmController, ArmSensors, ArmSimulation, DriveTruth, HiddenEffect};

use crate::cli::{DiagnoseArgs, ExciteArgs, IdentifyArgs, PredictArgs, SimulateArgs, ValidateArgs};
use crate::output::{FileKind, NewFile, OutDir};
use crate::stages::Stages;

/// `format` of the `params.json` a URDF identification writes.
pub const FORMAT: &str = "aras-urdf-params/1";

/// The `params.json` of a URDF identification.
#[derive(Serialize)]
struct UrdfParams<'a> {
    format: &'static str,
    urdf: String,
    log: String,
    joints: Vec<String>,
    /// The Stribeck columns the model was identified with.
    stribeck: Vec<StribeckColumn>,
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

/// The robot of `urdf` with [`model_settings`], and the URDF's text.
fn load_model(urdf: &Path) -> Result<(UrdfModel, String)> {
    load_model_with(urdf, &[])
}

/// [`load_model`] with the Stribeck columns `stribeck` added.
fn load_model_with(urdf: &Path, stribeck: &[StribeckColumn]) -> Result<(UrdfModel, String)> {
    let text = std::fs::read_to_string(urdf)
        .with_context(|| format!("cannot read the URDF {}", urdf.display()))?;
    let settings = ModelSettings {
        stribeck: stribeck.to_vec(),
        ..model_settings()
    };
    let model = UrdfModel::from_urdf_str(&text, &urdf.display().to_string(), settings)?;
    Ok((model, text))
}

/// The effects `identify --urdf --effects` adds to the model: what the
/// diagnosis names, with the setting it refined
/// (`stribeck_friction:JOINT:V_S`, `V_S` in rad/s).
fn urdf_effects(effects: &[String]) -> Result<Vec<StribeckColumn>> {
    effects
        .iter()
        .map(|e| {
            let parts: Vec<&str> = e.split(':').collect();
            match parts.as_slice() {
                ["stribeck_friction", joint, v_s] => {
                    let v_s: f64 = v_s.parse().map_err(|_| {
                        anyhow::anyhow!(
                            "--effects {e}: `{v_s}` is not a Stribeck velocity in rad/s"
                        )
                    })?;
                    Ok(StribeckColumn {
                        joint: (*joint).to_owned(),
                        v_s,
                    })
                }
                _ => bail!(
                    "--effects {e}: a URDF robot's model takes `stribeck_friction:JOINT:V_S` \
                     (the diagnosis's `stribeck_friction:JOINT` with its refined v_s in rad/s); \
                     its bodies, viscous and Coulomb friction and armature are always in it"
                ),
            }
        })
        .collect()
}

/// Runs `identify --urdf`.
pub fn identify(args: &IdentifyArgs, urdf: &Path) -> Result<()> {
    let stribeck = urdf_effects(&args.effects)?;
    let (model, text) = load_model_with(urdf, &stribeck)?;
    let file = urdf.display().to_string();
    let inputs: Vec<PathBuf> = [args.data.clone(), urdf.to_path_buf()]
        .into_iter()
        .chain(args.common.config.iter().cloned())
        .collect();
    let out = OutDir::create(&args.out, args.common.force, &inputs)?;
    let cfg = super::load_config(&args.common)?.config;
    let log = super::load_log_of(&args.data, &args.log, &cfg, model.dof())?;
    let settings = IdentifySettings {
        period: args.log.period,
        ..IdentifySettings::default()
    };
    let id = aras_urdf::identify::identify(&model, &log, &settings)
        .with_context(|| format!("identifying {} from {}", file, args.data.display()))?;
    out.write_json(
        "params.json",
        &UrdfParams {
            format: FORMAT,
            urdf: file.clone(),
            log: args.data.display().to_string(),
            joints: model.joint_names(),
            stribeck,
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
        println!("  {name}: fitness (78) {f:.2} % against the log's raw torques, every row");
    }
    println!("outputs in {}", dir.display());
    Ok(())
}

/// Runs `excite --urdf`: the design of `aras_urdf::excite` with its
/// defaults (`--seed` overrides the seed), progress per start.
pub fn excite(args: &ExciteArgs, urdf: &Path) -> Result<()> {
    let (model, _) = load_model(urdf)?;
    let inputs: Vec<PathBuf> = std::iter::once(urdf.to_path_buf())
        .chain(args.common.config.iter().cloned())
        .collect();
    let out = NewFile::create(&args.out, args.common.force, FileKind::Trajectory, &inputs)?;
    let settings = ExciteSettings {
        seed: args.seed.unwrap_or(ExciteSettings::default().seed),
        ..ExciteSettings::default()
    };
    let mut stages = Stages::new(args.common.quiet);
    let d = stages.run("excitation design in the URDF's limits", |bar| {
        let progress = |p: aras_excite::DesignProgress| {
            bar.set_message(format!("excitation design: {}/{} starts", p.done, p.total));
        };
        design_excitation(&model, &settings, &progress)
    })?;
    out.write((d.trajectory.to_json() + "\n").as_bytes())?;
    out.commit()?;
    let random = d.random_median.map_or(String::new(), |m| {
        format!(
            "; median of {} random feasible trajectories {m:.3} ({:.1}× higher)",
            settings.random_trajectories,
            m / d.condition_number
        )
    });
    println!(
        "{}: {} joints, condition number {:.3} ({} base parameters){random}; worst relative \
         limit margin {:.4}",
        args.out.display(),
        model.dof(),
        d.condition_number,
        d.n_base,
        d.worst_relative_margin
    );
    Ok(())
}

/// The truth a `simulate --urdf` log is written with, in its sidecar's
/// `truth` (the keys of `params.json`, so `validate --urdf` reads either).
#[derive(Serialize)]
struct SimTruth<'a> {
    format: &'static str,
    joints: Vec<String>,
    parameter_names: Vec<String>,
    standard: &'a [f64],
    drives: DriveTruth,
    hidden: &'a [HiddenEffect],
    simulation: &'a ArmSimulation,
}

/// Parses `--hidden` (see its help) for a robot of `joints` joints.
fn hidden_effect(spec: &str, joints: usize) -> Result<HiddenEffect> {
    let parts: Vec<&str> = spec.split(':').collect();
    let number = |i: usize, what: &str| -> Result<f64> {
        let s = parts.get(i).with_context(|| {
            format!("--hidden {spec}: {what} is missing (stribeck:J:LEVEL:V_S or cubic_spring:J:K3[:Q0])")
        })?;
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .with_context(|| format!("--hidden {spec}: {what} `{s}` is not a finite number"))
    };
    let joint = number(1, "the joint J")?;
    if joint.fract() != 0.0 || joint < 1.0 || joint > joints as f64 {
        bail!("--hidden {spec}: joint {joint} is not one of the robot's joints 1–{joints}");
    }
    let joint = joint as usize - 1;
    match (parts[0], parts.len()) {
        ("stribeck", 4) => Ok(HiddenEffect::Stribeck {
            joint,
            level: number(2, "the level")?,
            v_s: number(3, "the Stribeck velocity")?,
        }),
        ("cubic_spring", 3 | 4) => Ok(HiddenEffect::CubicSpring {
            joint,
            k3: number(2, "the stiffness K3")?,
            q0: if parts.len() == 4 {
                number(3, "Q0")?
            } else {
                0.0
            },
        }),
        _ => bail!(
            "--hidden {spec}: give stribeck:J:LEVEL:V_S (N·m, rad/s) or cubic_spring:J:K3[:Q0] \
             (N·m/rad³, rad), J the joint from 1"
        ),
    }
}

/// Runs `simulate --urdf`: the robot of the URDF with [`DriveTruth`]'s
/// drives tracking `--trajectory` (from `excite --urdf`) under PD control
/// with feedforward of the URDF's inertials alone, the simulator's sensors,
/// the log's torques declared held commands.
pub fn simulate(args: &SimulateArgs, urdf: &Path) -> Result<()> {
    if args.frequency.is_some() {
        bail!(
            "--frequency is ARAS-Diamond's trajectory (79); with --urdf give --trajectory FILE from `aras excite --urdf`"
        );
    }
    let Some(path) = &args.trajectory else {
        bail!("give --trajectory FILE (from `aras excite --urdf R.urdf`)");
    };
    let (model, _) = load_model(urdf)?;
    let n = model.dof();
    let trajectory = FourierTrajectory::<nalgebra::Dyn>::load(path)
        .with_context(|| format!("reading the trajectory {}", path.display()))?;
    if trajectory.coordinates() != n {
        bail!(
            "{}: a trajectory of {} coordinates for a robot of {n} joints; design one with \
             `aras excite --urdf {}`",
            path.display(),
            trajectory.coordinates(),
            urdf.display()
        );
    }
    let hidden = args
        .hidden
        .iter()
        .map(|h| hidden_effect(h, n))
        .collect::<Result<Vec<_>>>()?;
    let inputs: Vec<PathBuf> = [urdf.to_path_buf(), path.clone()]
        .into_iter()
        .chain(args.common.config.iter().cloned())
        .collect();
    let out = NewFile::create(
        &args.out,
        args.common.force,
        FileKind::SimulatedLog,
        &inputs,
    )?;
    let drives = DriveTruth::default();
    let truth = drives.parameters(&model);
    let mut controller =
        ArmController::for_trajectory(&model, &truth, &trajectory, trajectory.period(), 10.0)?;
    controller.feedforward = Some(model.urdf_parameters());
    let sim = ArmSimulation {
        duration_s: args.duration.unwrap_or(60.0),
        seed: args.seed.unwrap_or(1),
        hidden,
        ..ArmSimulation::new(controller, ArmSensors::uniform(n))
    };
    let mut stages = Stages::new(args.common.quiet);
    let log = stages.run("simulate the arm", |_| {
        aras_urdf::sim::simulate(&model, &truth, &trajectory, &sim)
    })?;
    let sidecar = aras_log::Sidecar {
        format: Some(aras_log::FORMAT.into()),
        excitation: aras_log::Excitation {
            period_s: Some(trajectory.period()),
        },
        torques: Some(aras_log::TorqueTiming::Held),
        truth: Some(serde_json::to_value(SimTruth {
            format: FORMAT,
            joints: model.joint_names(),
            parameter_names: model.parameter_names(),
            standard: &truth,
            drives,
            hidden: &sim.hidden,
            simulation: &sim,
        })?),
        ..aras_log::Sidecar::default()
    };
    aras_log::write_log(&out.path(), &log.columns(true), &sidecar)?;
    out.commit()?;
    println!(
        "{} ({} rows, {n} joints: {}) and {}",
        args.out.display(),
        log.t.len(),
        model.joint_names().join(", "),
        aras_log::sidecar_path(&args.out).display()
    );
    Ok(())
}

/// The model of `urdf` a parameter file of `identify --urdf` was
/// identified with (its Stribeck columns added) and its standard
/// parameters.
fn read_urdf_params(path: &Path, urdf: &Path) -> Result<(UrdfModel, Vec<f64>)> {
    #[derive(serde::Deserialize)]
    struct Params {
        format: String,
        parameter_names: Vec<String>,
        standard: Vec<f64>,
        #[serde(default)]
        stribeck: Vec<StribeckColumn>,
    }
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the parameter file {}", path.display()))?;
    let p: Params = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not a parameter file of `aras identify --urdf` (format {FORMAT})",
            path.display()
        )
    })?;
    if p.format != FORMAT {
        bail!(
            "{}: format `{}`, expected `{FORMAT}` (from `aras identify --urdf`)",
            path.display(),
            p.format
        );
    }
    let (model, _) = load_model_with(urdf, &p.stribeck)
        .with_context(|| format!("{}: its model on {}", path.display(), urdf.display()))?;
    let names = model.parameter_names();
    if p.parameter_names != names || p.standard.len() != names.len() {
        bail!(
            "{}: its {} parameters are not this URDF model's {} ({} …); identify this robot \
             with `aras identify --urdf`",
            path.display(),
            p.parameter_names.len(),
            names.len(),
            names.iter().take(3).cloned().collect::<Vec<_>>().join(", ")
        );
    }
    if let Some(i) = p.standard.iter().position(|v| !v.is_finite()) {
        bail!(
            "{}: parameter `{}` is not a finite number",
            path.display(),
            names[i]
        );
    }
    Ok((model, p.standard))
}

/// Runs `predict --urdf`: `t,tau1…tauN` on every row the processing covers
/// and the fitness (78) of exactly that file against the raw torques.
pub fn predict(args: &PredictArgs, urdf: &Path) -> Result<()> {
    let sidecar = args.log.sidecar_of(&args.data);
    let inputs: Vec<PathBuf> = [
        urdf.to_path_buf(),
        args.params.clone(),
        args.data.clone(),
        sidecar,
    ]
    .into_iter()
    .chain(args.common.config.iter().cloned())
    .collect();
    let out = NewFile::create(&args.out, args.common.force, FileKind::Prediction, &inputs)?;
    if args.summary.is_some() {
        bail!("--summary is ARAS-Diamond's; with --urdf the figures are printed");
    }
    let (model, params) = read_urdf_params(&args.params, urdf)?;
    let cfg = super::load_config(&args.common)?.config;
    let log = super::load_log_of(&args.data, &args.log, &cfg, model.dof())?;
    let settings = PredictSettings {
        period: args.log.period,
        ..PredictSettings::default()
    };
    let p = aras_urdf::predict::predict(&model, &params, &log, &settings)?;
    let mut csv = String::from("t");
    for j in 1..=model.dof() {
        csv += &format!(",tau{j}");
    }
    csv.push('\n');
    for (r, t) in p.t.iter().enumerate() {
        csv += &t.to_string();
        for c in &p.tau {
            csv += &format!(",{}", c[r]);
        }
        csv.push('\n');
    }
    out.write(csv.as_bytes())?;
    out.commit()?;
    println!(
        "{}: {} of {} rows; q̇, q̈: {}; fitness (78) of this file vs the log's raw torques:",
        args.out.display(),
        p.rows,
        p.log_rows,
        p.derivatives
    );
    for (name, f) in model.joint_names().iter().zip(&p.fitness) {
        println!("  {name}: {f:.3} %");
    }
    Ok(())
}

/// One validation log's figures in `validation.json`.
#[derive(Serialize)]
struct Validated {
    log: String,
    rows: usize,
    fitness: Vec<f64>,
    /// The simulated robot's own parameters through the same route (its
    /// sidecar's `truth`), if the log has them: the best this model can do.
    truth_fitness: Option<Vec<f64>>,
}

/// Runs `validate --urdf`: every `--data` log predicted by `--params`.
pub fn validate(args: &ValidateArgs, urdf: &Path) -> Result<()> {
    if args.data.is_empty() {
        bail!("give at least one validation log with --data VAL.csv");
    }
    let inputs: Vec<PathBuf> = [urdf.to_path_buf(), args.params.clone()]
        .into_iter()
        .chain(args.data.iter().cloned())
        .chain(args.data.iter().map(|d| aras_log::sidecar_path(d)))
        .chain(args.common.config.iter().cloned())
        .collect();
    let out = OutDir::create(&args.out, args.common.force, &inputs)?;
    let (model, params) = read_urdf_params(&args.params, urdf)?;
    // A simulated log's truth is of the model without added columns.
    let (plain, _) = load_model(urdf)?;
    let cfg = super::load_config(&args.common)?.config;
    let mut results = Vec::new();
    for path in &args.data {
        let log = super::load_log_of(path, &crate::cli::LogArgs::default(), &cfg, model.dof())?;
        let settings = PredictSettings::default();
        let p = aras_urdf::predict::predict(&model, &params, &log, &settings)?;
        let truth = sidecar_truth(path, &plain)?;
        let truth_fitness = match truth {
            Some(t) => Some(aras_urdf::predict::predict(&plain, &t, &log, &settings)?.fitness),
            None => None,
        };
        println!("{}: {} rows", path.display(), p.rows);
        for (j, name) in model.joint_names().iter().enumerate() {
            let ceiling = truth_fitness.as_ref().map_or(String::new(), |t| {
                format!(" (the simulated robot's own parameters: {:.3} %)", t[j])
            });
            println!("  {name}: fitness (78) {:.3} %{ceiling}", p.fitness[j]);
        }
        results.push(Validated {
            log: path.display().to_string(),
            rows: p.rows,
            fitness: p.fitness,
            truth_fitness,
        });
    }
    out.write_json("validation.json", &results)?;
    let dir = out.commit()?;
    println!("outputs in {}", dir.display());
    Ok(())
}

/// The standard parameters in a simulated log's sidecar `truth`, if it has
/// them for this model.
fn sidecar_truth(log: &Path, model: &UrdfModel) -> Result<Option<Vec<f64>>> {
    let side = aras_log::sidecar_path(log);
    if !side.exists() {
        return Ok(None);
    }
    let Ok(sidecar) = aras_log::Sidecar::read(&side) else {
        return Ok(None);
    };
    let Some(truth) = sidecar.truth else {
        return Ok(None);
    };
    let names: Option<Vec<String>> = truth
        .get("parameter_names")
        .and_then(|v| serde_json::from_value(v.clone()).ok());
    let values: Option<Vec<f64>> = truth
        .get("standard")
        .and_then(|v| serde_json::from_value(v.clone()).ok());
    Ok(match (names, values) {
        (Some(n), Some(v)) if n == model.parameter_names() && v.len() == n.len() => Some(v),
        _ => None,
    })
}

/// Runs `diagnose --urdf`: `aras_urdf::diagnose` on the training log and
/// the validation logs → `diagnosis.json` and the conclusion printed.
pub fn diagnose(args: &DiagnoseArgs, urdf: &Path) -> Result<()> {
    let (model, _) = load_model(urdf)?;
    let mut inputs: Vec<PathBuf> = vec![urdf.to_path_buf(), args.data.clone()];
    inputs.extend(args.validate.iter().cloned());
    inputs.extend(
        std::iter::once(&args.data)
            .chain(&args.validate)
            .map(|d| aras_log::sidecar_path(d)),
    );
    inputs.extend(args.common.config.iter().cloned());
    let out = OutDir::create(&args.out, args.common.force, &inputs)?;
    let cfg = super::load_config(&args.common)?.config;
    let n = model.dof();
    let train = super::load_log_of(&args.data, &args.log, &cfg, n)?;
    let validation = args
        .validate
        .iter()
        .map(|p| super::load_log_of(p, &crate::cli::LogArgs::default(), &cfg, n))
        .collect::<Result<Vec<_>>>()?;
    let settings = DiagnoseSettings {
        period: args.log.period,
        ..DiagnoseSettings::default()
    };
    let mut stages = Stages::new(args.common.quiet);
    let d = stages.run("diagnosis", |_| {
        aras_urdf::diagnose::diagnose(&model, &train, &validation, &settings)
    })?;
    out.write_json("diagnosis.json", &d)?;
    let dir = out.commit()?;
    if d.steps.is_empty() {
        println!("nothing added: no candidate effect improves every validation log");
    }
    for s in &d.steps {
        let values: Vec<String> = s
            .parameters
            .iter()
            .map(|p| format!("{} = {:.4} ± {:.4}", p.name, p.value, p.std_dev))
            .collect();
        let refined = s.refinement.as_ref().map_or(String::new(), |r| {
            let there: Vec<String> = r
                .parameters
                .iter()
                .map(|p| format!("{} = {:.4} ± {:.4}", p.name, p.value, p.std_dev))
                .collect();
            format!(
                "; {} refined to {:.4} ± {:.4}{}",
                r.name,
                r.value,
                r.std_dev,
                if there.is_empty() {
                    String::new()
                } else {
                    format!(", there {}", there.join(", "))
                }
            )
        });
        println!("added {}: {}{refined}", s.label, values.join(", "));
    }
    if let (Some(c), false) = (&d.consistent, d.steps.is_empty()) {
        let added: Vec<String> = d
            .steps
            .iter()
            .flat_map(|s| &s.parameters)
            .filter_map(|added| c.parameters.iter().find(|p| p.name == added.name))
            .map(|p| format!("{} = {:.4}", p.name, p.value))
            .collect();
        println!(
            "physically consistent refit of the final model ({}): {}",
            c.status,
            if added.is_empty() {
                "no added parameter".to_owned()
            } else {
                added.join(", ")
            }
        );
    }
    if let (Some(first), Some(last)) = (d.fitness.first(), d.fitness.last()) {
        for (k, name) in args.validate.iter().enumerate() {
            if let (Some(Some(a)), Some(Some(b))) = (first.fitness.get(k), last.fitness.get(k)) {
                let pairs: Vec<String> = a
                    .iter()
                    .zip(b)
                    .zip(model.joint_names())
                    .map(|((a, b), j)| format!("{j} {a:.2} → {b:.2} %"))
                    .collect();
                println!(
                    "{}: fitness (78), every row: {}",
                    name.display(),
                    pairs.join(", ")
                );
            }
        }
    }
    println!("{}", d.conclusion);
    println!("outputs in {}", dir.display());
    Ok(())
}
