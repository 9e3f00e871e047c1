//! The shared tail of `pipeline` and `identify`: process the log, identify
//! (OLS + SDP), validate, and write params.json, params_ols.json, base.json,
//! summary.json and the report into the run's directory.

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use aras_dyn::Params;
use aras_excite::Design;
use aras_ident::BaseParameters;
use aras_log::Log;

use crate::config::Config;
use crate::identify::{
    friction_widths, identify, logged_derivatives_note, prepare, process_options,
};
use crate::output::OutDir;
use crate::plausibility;
use crate::report::run::{RunData, build};
use crate::stages::Stages;
use crate::summary::{PseudoInertia, SdpReport, Summary, base_file, fitness_list};
use crate::validate::{cross_validate, pd_region, workspace_box};
use aras_pipeline::validate::{
    ScoredModel, min_eigen_grid, parameter_errors, pd_check, pseudo_inertia_min,
};

/// What the fit needs.
pub struct FitInput<'a> {
    /// Settings.
    pub cfg: &'a Config,
    /// The nominal robot (SDP reference, geometry, gravity).
    pub nominal: &'a Params,
    /// The truth, when known (simulated logs).
    pub truth: Option<&'a Params>,
    /// The log's noise-free torques, one per row, when this run simulated
    /// it: the noise ceiling (`aras_pipeline::validate::ceiling`) is
    /// reported only then.
    pub clean_torque: Option<&'a [[f64; 2]]>,
    /// Simulate and score the cross-validation trajectories (79) with the truth.
    pub cross_validate: bool,
    /// The log.
    pub log: &'a Log,
    /// Period override (s).
    pub period: Option<f64>,
    /// The excitation design, if this run made one.
    pub design: Option<&'a Design>,
    /// Base parameters of the model.
    pub base: &'a BaseParameters,
    /// The identified model (the paper's, possibly with extra effects).
    pub model: &'a aras_dyn::Model,
    /// Command name for the summary.
    pub command: &'a str,
    /// Seed, for the summary.
    pub seed: Option<u64>,
    /// Torque noise of the simulated sensors (N·m).
    pub noise: Option<[f64; 2]>,
    /// Omit timings from summary.json.
    pub reproducible: bool,
    /// The report's first paragraph.
    pub intro: String,
}

/// Runs the fit and writes every output into `out`; returns the summary
/// (with timings, whatever `reproducible` says).
pub fn run(input: FitInput, out: &OutDir, stages: &mut Stages) -> Result<Summary> {
    let cfg = input.cfg;
    let model = input.model;
    let geometry = input.nominal.geometry()?;
    let options = process_options(cfg, input.period, false);
    // Said where the user gave the log (the pipeline's simulated log has
    // its derivative columns as a record of the truth).
    if input.command == "identify"
        && let Some(note) = logged_derivatives_note(input.log)
    {
        eprintln!("note: {}: {note}", input.log.name);
    }
    let mut prepared = stages.run("process log + regressor", |_| {
        prepare(
            input.log,
            &options,
            cfg.identification.filtering,
            model,
            &geometry,
        )
    })?;
    let (refined_model, widths, keep) = stages.run("Coulomb widths", |_| {
        friction_widths(&mut prepared, input.base, model, cfg)
    })?;
    for f in &widths.fallback {
        eprintln!("note: {f}");
    }
    let model = &refined_model;
    let id = stages.run("identify (OLS + SDP)", |_| {
        identify(&prepared, input.base, model, input.nominal, cfg, &keep)
    })?;
    let ols_std = id.ols_params.standard_vector(model)?.as_slice().to_vec();
    let sdp_std = id.sdp.standard.clone();

    let xv = match (input.truth, input.cross_validate) {
        (Some(truth), true) => {
            let dir = out.path("validation");
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            let n = cfg.validation.frequencies_hz.len() as u64;
            let bar = stages.bar(n, "cross-validation");
            let r = stages.run("cross-validation (79)", |_| {
                cross_validate(
                    truth,
                    input.nominal,
                    ScoredModel {
                        geometry: &geometry,
                        model,
                    },
                    &[ols_std.clone(), sdp_std.clone()],
                    cfg,
                    &dir,
                    &bar,
                )
            })?;
            bar.finish_and_clear();
            r
        }
        _ => Vec::new(),
    };

    let (pd, heat, nominal_pd) = stages.run("workspace PD check (80)", |_| -> Result<_> {
        let region = pd_region(cfg);
        let mut pd = BTreeMap::new();
        pd.insert("ols".to_string(), pd_check(&id.ols_params, &region)?);
        pd.insert("sdp".to_string(), pd_check(&id.sdp_params, &region)?);
        let nominal_pd = pd_check(input.nominal, &region)?;
        let (lower, upper) = workspace_box(cfg);
        let heat = min_eigen_grid(&id.sdp_params, lower, upper, cfg.validation.heatmap)?;
        Ok((pd, heat, nominal_pd))
    })?;
    let pseudo = PseudoInertia {
        ols: pseudo_inertia_min(&id.ols_params),
        sdp: pseudo_inertia_min(&id.sdp_params),
        truth: input.truth.map(pseudo_inertia_min),
    };
    // The truth in the identified model's columns (effects the model lacks
    // are simply not compared; absent extras count as zero).
    let truth_std: Option<Vec<f64>> = input
        .truth
        .and_then(|t| t.standard_vector(model).ok().map(|v| v.as_slice().to_vec()));
    let truth_base = match &truth_std {
        Some(t) => Some(id.base.to_base(t)?),
        None => None,
    };
    let errors = match &truth_std {
        Some(t) => {
            let mut m = BTreeMap::new();
            m.insert(
                "ols".to_string(),
                parameter_errors(&id.base, &id.ols.estimate, &id.ols.std_dev, t)?,
            );
            m.insert(
                "sdp".to_string(),
                parameter_errors(&id.base, &id.sdp.base, &id.ols.std_dev, t)?,
            );
            Some(m)
        }
        None => None,
    };
    let ceiling = match input.clean_torque {
        Some(clean) => Some(aras_pipeline::validate::ceiling::noise_ceiling(
            input.log, clean, &prepared, &options, &geometry, &keep,
        )?),
        None => None,
    };
    let fitness = fitness_list(&id, &xv, input.design.is_some(), ceiling);
    let implausible = plausibility::check(&plausibility::Evidence {
        fitness: &fitness,
        status: id.sdp.status,
        sdp: &id.sdp_params,
        nominal: input.nominal,
        pd: (&pd["sdp"], &nominal_pd),
        torque_limit: cfg.simulation.torque_limit,
        torque_peak: plausibility::torque_peak(&input.log.tau),
    });
    plausibility::print(&implausible);

    out.write("params.json", id.sdp_params.to_json_string() + "\n")?;
    crate::cmd::export_mjcf::write_beside(out, &id.sdp_params)?;
    out.write("params_ols.json", id.ols_params.to_json_string() + "\n")?;
    out.write_json("base.json", &base_file(&id, truth_base.as_deref()))?;

    let timings: BTreeMap<String, f64> = stages.timings().iter().cloned().collect();
    let mut summary = Summary {
        format: crate::summary::SUMMARY_FORMAT,
        command: input.command.into(),
        seed: input.seed,
        standard_parameters: id.base.n_standard(),
        base_parameters: id.base.n_base(),
        excitation_condition_number: input.design.map(|d| d.condition_number),
        samples: prepared.n(),
        processing: Some(crate::summary::ProcessingRecord::new(
            &prepared.processed.summary,
        )),
        logged_derivatives: logged_derivatives_note(input.log),
        torque_noise_std_nm: input.noise,
        fitness: fitness.clone(),
        pd_check: pd.clone(),
        pseudo_inertia_min_eigenvalue: pseudo.clone(),
        parameter_errors: errors.clone(),
        sdp: SdpReport::new(&id.sdp),
        implausible: implausible.clone(),
        friction_width: Some(widths.clone()),
        timings_s: None,
    };
    if !input.reproducible {
        summary.timings_s = Some(timings);
    }
    out.write_json("summary.json", &summary)?;

    let data = RunData {
        title: format!(
            "ARAS-Diamond identification report (`aras {}`)",
            input.command
        ),
        intro: format!("{} {}", input.intro, widths.sentence()),
        timings: stages.timings(),
        design: input.design,
        processing: &prepared.processed.summary,
        t: &prepared.processed.samples.t,
        measured: prepared.t(),
        id: &id,
        fitness: &fitness,
        xv: &xv,
        pd: &pd,
        heat: Some(&heat),
        pseudo: &pseudo,
        errors: errors.as_ref(),
        truth_base: truth_base.as_deref(),
        implausible: &implausible,
    };
    let report = build(&data)?;
    for (file, svg) in report.figures() {
        out.write(file, svg)?;
    }
    out.write("report.md", report.to_markdown())?;
    out.write("report.html", report.to_html())?;
    summary.timings_s = Some(stages.timings().iter().cloned().collect());
    Ok(summary)
}

/// The short terminal table: ours (on the simulated robot or the given
/// log) next to the noise ceiling, and the paper's real-robot figures
/// labelled as such.
pub fn terminal_table(s: &Summary) -> String {
    use crate::summary::DataKind;
    let simulated = s.fitness.iter().any(|f| f.data == DataKind::Simulated);
    let mut t = String::from("fitness (78) %, all rows");
    if simulated {
        t += "; ours: on the SIMULATED robot's logs; ceiling: the true robot's noise-free \
              torques on the same log (the best attainable)";
    } else {
        t += "; ours: on the given log";
    }
    t += "; kept: OLS on the rows away from velocity reversals";
    if s.fitness.iter().any(|f| f.paper_real_robot.is_some()) {
        t += "; paper: the REAL robot (§7, Table 2), another experiment, for orientation only";
    }
    t += "\ndataset          ours τ1 (OLS/SDP)  ceiling τ1   ours τ2 (OLS/SDP)  ceiling τ2   kept τ1/τ2 (ceiling)              paper τ1/τ2\n";
    for f in &s.fitness {
        let ceil = |j: usize| {
            f.noise_ceiling
                .map_or("     –".to_string(), |c| format!("{:6.2}", c[j]))
        };
        let kept_ceiling = f
            .noise_ceiling_kept
            .map_or(String::new(), |c| format!(" ({:6.2} / {:6.2})", c[0], c[1]));
        let paper = f.paper_real_robot.map_or("   –".to_string(), |p| {
            format!("{:4.1} / {:4.1}", p[0], p[1])
        });
        t += &format!(
            "{:<16} {:6.2} / {:6.2}      {:>6}     {:6.2} / {:6.2}      {:>6}     {:6.2} / {:6.2}{:<20}   {}\n",
            f.dataset,
            f.ols[0],
            f.sdp[0],
            ceil(0),
            f.ols[1],
            f.sdp[1],
            ceil(1),
            f.ols_kept[0],
            f.ols_kept[1],
            kept_ceiling,
            paper
        );
    }
    t += &format!("base parameters: {}", s.base_parameters);
    if let Some(pd) = s.pd_check.get("sdp") {
        t += &format!(
            "; SDP mass matrix PD over the workspace: {} (eigenvalues {:.3e} … {:.3e} kg·m²)",
            if pd.positive_definite { "yes" } else { "NO" },
            pd.min_eigenvalue,
            pd.max_eigenvalue
        );
    }
    if let Some(ts) = &s.timings_s {
        t += &format!("\ntotal stage time: {:.2} s", ts.values().sum::<f64>());
    }
    t
}
