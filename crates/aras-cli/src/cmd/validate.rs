//! `aras validate`: scores a parameter file on the cross-validation
//! trajectories (79) of the simulated robot, checks its mass matrix over
//! the workspace and its links' physical consistency.

use std::collections::BTreeMap;

use anyhow::Result;
use serde::Serialize;

use crate::cli::ValidateArgs;
use crate::output::OutDir;
use crate::paper;
use crate::report::Report;
use crate::robot::{ParamsUse, nominal, read_params};
use crate::simulate::truth;
use crate::stages::Stages;
use crate::validate::{cross_validate, pd_region};
use aras_pipeline::validate::{PdSummary, ScoredModel, pd_check, pseudo_inertia_min};

/// `summary.json` of `validate`.
#[derive(Debug, Serialize)]
struct ValidateSummary {
    format: &'static str,
    params: String,
    /// Fitness (78) per frequency of (79), on the simulated robot.
    fitness: Vec<XvFitness>,
    pd_check: PdSummary,
    pseudo_inertia_min_eigenvalue: [f64; 4],
}

/// One frequency of `validate`'s summary.
#[derive(Debug, Serialize)]
struct XvFitness {
    frequency_hz: f64,
    /// The parameter file's fitness `[τ1, τ2]` (%) on the simulated robot.
    simulated: [f64; 2],
    /// The true robot's noise-free torques on the same log
    /// (`aras_pipeline::validate::ceiling`); always known for the simulated
    /// logs of (79).
    noise_ceiling: Option<[f64; 2]>,
    /// Processing loss `[τ1, τ2]` (percentage points,
    /// `aras_pipeline::validate::loss`): the file's fitness with the
    /// simulator's exact θ̇, θ̈ minus its fitness from the angles alone, on
    /// the rows both cover.
    processing_loss: Option<[f64; 2]>,
    /// The paper's Table 2, measured on the real robot (another experiment).
    #[serde(skip_serializing_if = "Option::is_none")]
    paper_real_robot: Option<[f64; 2]>,
}

/// Runs `validate`.
pub fn run(args: &ValidateArgs) -> Result<()> {
    if let Some(urdf) = &args.urdf {
        return super::urdf::validate(args, urdf);
    }
    let loaded = super::load_config(&args.common)?;
    let cfg = loaded.config.clone();
    let out = OutDir::create(
        &args.out,
        args.common.force,
        &super::input_files(&args.common, &loaded, &[&args.params]),
    )?;
    let mut stages = Stages::new(args.common.quiet);
    let params = read_params(
        &args.params,
        ParamsUse::Physical(
            "`validate` checks a model for control, which needs physically consistent \
             parameters (an OLS estimate such as params_ols.json may not be; `predict` accepts it)",
        ),
    )?;
    let nominal = nominal(&cfg.robot, &loaded.dir)?;
    let truth = truth(&cfg, &loaded.dir, &nominal)?;
    // The file's whole model: its geometry, gravity and extra effects are
    // what is validated, against the configured simulated robot.
    let model = params.model()?;
    let geometry = params.geometry()?;
    let beta = params.standard_vector(&model)?.as_slice().to_vec();
    let bar = stages.bar(
        cfg.validation.frequencies_hz.len() as u64,
        "cross-validation",
    );
    let xv = stages.run("cross-validation (79)", |_| {
        cross_validate(
            &truth,
            &nominal,
            ScoredModel {
                geometry: &geometry,
                model: &model,
            },
            &[beta],
            &cfg,
            &out.path("."),
            &bar,
        )
    })?;
    bar.finish_and_clear();
    let pd = stages.run("workspace PD check (80)", |_| {
        pd_check(&params, &pd_region(&cfg))
    })?;
    let summary = ValidateSummary {
        format: "aras-validate/1",
        params: args.params.display().to_string(),
        fitness: xv
            .iter()
            .map(|x| XvFitness {
                frequency_hz: x.frequency_hz,
                simulated: x.fitness[0],
                noise_ceiling: x.ceiling.map(|c| c.all),
                processing_loss: x.processing_loss.first().map(|l| l.loss),
                paper_real_robot: paper::table2(x.frequency_hz),
            })
            .collect(),
        pd_check: pd.clone(),
        pseudo_inertia_min_eigenvalue: pseudo_inertia_min(&params),
    };
    out.write_json("summary.json", &summary)?;
    let mut r = Report::new(format!("Validation of `{}`", args.params.display()));
    let rows = summary
        .fitness
        .iter()
        .map(|x| {
            let ps = |j: usize| {
                x.paper_real_robot
                    .map_or("–".into(), |p: [f64; 2]| format!("{:.1}", p[j]))
            };
            let loss = |j: usize| {
                x.processing_loss
                    .map_or("–".into(), |l: [f64; 2]| format!("{:.2}", l[j]))
            };
            let ceiling = |j: usize| {
                x.noise_ceiling
                    .map_or("–".into(), |c: [f64; 2]| format!("{:.2}", c[j]))
            };
            vec![
                format!("{} Hz", x.frequency_hz),
                format!("{:.2}", x.simulated[0]),
                ceiling(0),
                loss(0),
                format!("{:.2}", x.simulated[1]),
                ceiling(1),
                loss(1),
                ps(0),
                ps(1),
            ]
        })
        .collect();
    r.table(
        &[
            "f",
            "ours τ1",
            "ceiling τ1",
            "loss τ1",
            "ours τ2",
            "ceiling τ2",
            "loss τ2",
            "paper τ1 (real robot)",
            "paper τ2 (real robot)",
        ],
        rows,
    );
    r.paragraph(
        "Fitness (78) in % on simulated logs of (79). Ceiling: the true robot's noise-free \
         torques against the same log, the best attainable. Loss: the processing loss, the \
         fitness with the simulator's exact θ̇, θ̈ minus the fitness from the angles alone \
         (percentage points, same parameters, the rows both cover). Paper: Table 2, measured on the \
         real robot (another experiment, for orientation only).",
    );
    let mut pdm = BTreeMap::new();
    pdm.insert("params", &pd);
    r.paragraph(format!(
        "Mass matrix (80) over the workspace: eigenvalues {:.4e} … {:.4e} kg·m², positive definite everywhere: {}.",
        pd.min_eigenvalue, pd.max_eigenvalue, pd.positive_definite
    ));
    r.paragraph(format!(
        "Pseudo-inertia minimum eigenvalues per link: {:?}.",
        summary.pseudo_inertia_min_eigenvalue
    ));
    out.write("report.md", r.to_markdown())?;
    out.write("report.html", r.to_html())?;
    let dir = out.commit()?;
    println!(
        "fitness (78) % on the SIMULATED robot, next to the noise ceiling (the true robot's \
         noise-free torques on the same log); paper: Table 2 on the REAL robot, for orientation"
    );
    for x in &summary.fitness {
        let paper = x
            .paper_real_robot
            .map_or("–".to_string(), |p| format!("{:.1} / {:.1}", p[0], p[1]));
        let loss = x
            .processing_loss
            .map_or("–".to_string(), |l| format!("{:.2} / {:.2}", l[0], l[1]));
        let ceiling = |j: usize| {
            x.noise_ceiling
                .map_or(format!("{:>6}", "–"), |c| format!("{:6.2}", c[j]))
        };
        println!(
            "{:>5} Hz  τ1 {:6.2} % (ceiling {})  τ2 {:6.2} % (ceiling {})  processing loss {loss} points  paper (real robot) {paper}",
            x.frequency_hz,
            x.simulated[0],
            ceiling(0),
            x.simulated[1],
            ceiling(1)
        );
    }
    println!(
        "mass matrix PD over the workspace: {}; outputs in {}",
        pd.positive_definite,
        dir.display()
    );
    Ok(())
}
