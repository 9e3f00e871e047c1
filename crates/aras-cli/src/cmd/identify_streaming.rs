//! `aras identify --streaming`: identification from a log of any length in
//! bounded memory (`aras_pipeline::streaming::identify_log`, docs/scale.md),
//! with the same settings as the in-memory path (processing, parallel
//! filter, reversal exclusion, filter-corrected σ, OLS/WLS, SDP) and the
//! same output files. What a single bounded pass cannot give: the fitness
//! (78) on *all* rows (only the fitted rows are accumulated: both fitness
//! columns report them) and the report's time-series figures. The Coulomb
//! widths of `identification.rows = "all"` are refined on the period route
//! only (its averaged period is in memory); a log without a period is
//! fitted away from reversals with the sign law, and the report says so.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result};
use aras_dyn::{Model, Params};
use aras_ident::BaseParameters;
use aras_ident::streaming::Accumulation;
use aras_kin::Geometry;
use aras_pipeline::identify::{StreamedIdentification, identify_streamed};
use aras_pipeline::streaming::{StreamingOptions, StreamingResult, identify_log_with_progress};
use indicatif::ProgressBar;

use crate::cli::{AccumulationArg, IdentifyArgs, LogArgs};
use crate::config::Config;
use crate::identify::process_options;
use crate::output::OutDir;
use crate::stages::Stages;
use crate::summary::{
    BASE_FORMAT, BaseEntry, BaseFile, DataKind, Fitness, PseudoInertia, SdpReport, SigmaMethod,
    Summary,
};
use crate::validate::pd_region;
use aras_pipeline::validate::{parameter_errors, pd_check, pseudo_inertia_min};

/// The streaming options `identify` uses: [`log_options`] with the
/// command line's accumulation.
pub fn options(args: &IdentifyArgs, cfg: &Config, nominal: &Params) -> Result<StreamingOptions> {
    Ok(StreamingOptions {
        accumulation: match args.accumulation {
            AccumulationArg::Gram => Accumulation::Gram,
            AccumulationArg::Qr => Accumulation::Qr,
        },
        ..log_options(&args.log, cfg, nominal.geometry()?)?
    })
}

/// The streaming identification of a log read with `log`'s settings: the
/// configuration's processing (logged derivatives ignored, as in memory),
/// filtering mode, reversal exclusion and Coulomb widths
/// (`identification.rows`).
pub fn log_options(log: &LogArgs, cfg: &Config, geometry: Geometry) -> Result<StreamingOptions> {
    Ok(StreamingOptions {
        read: super::streaming_read_options(log, cfg)?,
        process: process_options(cfg, log.period, false),
        geometry,
        ..StreamingOptions::default()
    }
    .with_identification(&cfg.identification))
}

/// Streams the log; reruns with the QR accumulation if the normal
/// equations' accuracy check fails (a second pass, said on stderr). The
/// stage's bar shows the rows read of the total estimated from the file
/// size and the time left (an hour at 10 kHz takes minutes).
pub fn stream(
    data: &Path,
    model: &Model,
    base: &BaseParameters,
    opts: &StreamingOptions,
    bar: &ProgressBar,
) -> Result<StreamingResult> {
    let show = |pass: &str| track_rows(bar, data, format!("stream log → least squares{pass}"));
    let r = identify_log_with_progress(data, model, base, opts, &mut show(""))
        .with_context(|| format!("streaming identification of {}", data.display()))?;
    match r.gram_check {
        Some(c) if !c.passed => {
            bar.suspend(|| {
                eprintln!(
                    "note: κ = {:.3e} makes the normal equations too inaccurate (κ²ε = {:.1e} > {:.0e}); \
                     accumulating again with incremental QR",
                    c.condition, c.error_bound, c.limit
                )
            });
            let mut q = opts.clone();
            q.accumulation = Accumulation::Qr;
            identify_log_with_progress(data, model, base, &q, &mut show(", QR pass"))
                .with_context(|| format!("streaming identification of {}", data.display()))
        }
        _ => Ok(r),
    }
}

/// A progress callback for a stage reading the rows of `path`: the
/// stage's bar becomes a bar over the rows estimated from the file size
/// and shows `what`, the rows read of that total and the time left
/// ([`crate::stages::progress_text`]); the time counts from this call.
pub fn track_rows(bar: &ProgressBar, path: &Path, what: String) -> impl FnMut(u64) + use<> {
    let total = estimated_rows(path);
    if let Some(t) = total {
        crate::stages::determinate(bar, t);
    }
    let start = std::time::Instant::now();
    let bar = bar.clone();
    move |rows| {
        if total.is_some() {
            bar.set_position(rows);
        }
        bar.set_message(format!(
            "{what}: {}",
            crate::stages::progress_text(rows, total, "rows", start.elapsed())
        ));
    }
}

/// Rows of a CSV log estimated from its size and the mean length of the
/// lines in its first 64 KiB; `None` if that cannot be read.
fn estimated_rows(path: &Path) -> Option<u64> {
    use std::io::Read;
    let size = std::fs::metadata(path).ok()?.len();
    let mut head = vec![0u8; 64 * 1024];
    let n = std::fs::File::open(path).ok()?.read(&mut head).ok()?;
    let lines = head[..n].iter().filter(|&&b| b == b'\n').count() as u64;
    (lines > 1).then(|| size * lines / n as u64)
}

/// Everything after streaming: OLS/WLS, SDP, checks, and the output files
/// (params.json, robot.xml, params_ols.json, base.json, summary.json, report.md).
#[allow(clippy::too_many_arguments)]
pub fn fit_and_write(
    r: &StreamingResult,
    cfg: &Config,
    nominal: &Params,
    truth: Option<&Params>,
    base: &BaseParameters,
    model: &Model,
    reproducible: bool,
    intro: &str,
    out: &OutDir,
    stages: &mut Stages,
) -> Result<Summary> {
    let id = stages.run("SDP (67)–(73)", |_| {
        identify_streamed(r, base, model, nominal, &cfg.identification)
            .context("OLS and the physically consistent fit (SDP) of the streamed log")
    })?;
    let StreamedIdentification {
        ols,
        sdp,
        ols_params,
        sdp_params,
        fitness_ols: f_ols,
        fitness_sdp: f_sdp,
    } = id;
    let fitness = vec![Fitness {
        dataset: "excitation".into(),
        frequency_hz: None,
        ols: f_ols,
        sdp: f_sdp,
        ols_kept: f_ols,
        sdp_kept: f_sdp,
        data: if truth.is_some() {
            DataKind::Simulated
        } else {
            DataKind::Measured
        },
        // Streaming keeps no samples to evaluate the truth on.
        noise_ceiling: None,
        noise_ceiling_kept: None,
        paper_real_robot: None,
    }];
    let region = pd_region(cfg);
    let mut pd = BTreeMap::new();
    pd.insert("ols".to_string(), pd_check(&ols_params, &region)?);
    pd.insert("sdp".to_string(), pd_check(&sdp_params, &region)?);
    // The streamed log keeps no samples: the RMS of the fitted torques is a
    // lower bound of their peak, enough to see a unit 1000× off.
    let torque_rms = [0, 1].map(|j| {
        let n = r.rows_fitted[j].max(1) as f64;
        (r.torque_sums[j][1] / n).max(0.0).sqrt()
    });
    let implausible = crate::plausibility::check(&crate::plausibility::Evidence {
        fitness: &fitness,
        status: sdp.status,
        sdp: &sdp_params,
        nominal,
        pd: (&pd["sdp"], &pd_check(nominal, &region)?),
        torque_limit: cfg.simulation.torque_limit,
        torque_peak: torque_rms,
    });
    crate::plausibility::print(&implausible);
    let truth_std: Option<Vec<f64>> =
        truth.and_then(|t| t.standard_vector(model).ok().map(|v| v.as_slice().to_vec()));
    let truth_base = match &truth_std {
        Some(t) => Some(base.to_base(t)?),
        None => None,
    };
    let errors = match &truth_std {
        Some(t) => {
            let mut m = BTreeMap::new();
            m.insert(
                "ols".to_string(),
                parameter_errors(base, &ols.estimate, &ols.std_dev, t)?,
            );
            m.insert(
                "sdp".to_string(),
                parameter_errors(base, &sdp.base, &ols.std_dev, t)?,
            );
            Some(m)
        }
        None => None,
    };
    out.write("params.json", sdp_params.to_json_string() + "\n")?;
    crate::cmd::export_mjcf::write_beside(out, &sdp_params)?;
    out.write("params_ols.json", ols_params.to_json_string() + "\n")?;
    out.write_json(
        "base.json",
        &BaseFile {
            format: BASE_FORMAT,
            standard: model.names(),
            unidentifiable: base
                .unidentifiable()
                .iter()
                .map(|s| s.to_string())
                .collect(),
            // (66) of the residual as fitted (filtered), as in memory: the
            // estimate's own figure is the pre-filter variance σ²_ρ / g.
            residual_variance: ols.residual_variance * r.noise_gain,
            condition_number: ols.condition_number,
            sigma_method: SigmaMethod::WhiteFiltered,
            rows_fitted: r.rows_fitted,
            parameters: (0..base.n_base())
                .map(|i| BaseEntry {
                    name: format!("b{}", i + 1),
                    definition: base.expression(i),
                    ols: ols.estimate[i],
                    sigma: ols.std_dev[i],
                    sigma_percent: ols.rel_std_percent[i],
                    sigma_white: ols.std_dev[i],
                    sigma_hac: None,
                    sdp: sdp.base[i],
                    truth: truth_base.as_ref().map(|t| t[i]),
                })
                .collect(),
        },
    )?;
    let mut summary = Summary {
        format: crate::summary::SUMMARY_FORMAT,
        command: "identify".into(),
        seed: None,
        standard_parameters: base.n_standard(),
        base_parameters: base.n_base(),
        excitation_condition_number: None,
        samples: r.samples_used,
        processing: None,
        logged_derivatives: None,
        torque_noise_std_nm: None,
        fitness,
        pd_check: pd,
        pseudo_inertia_min_eigenvalue: PseudoInertia {
            ols: pseudo_inertia_min(&ols_params),
            sdp: pseudo_inertia_min(&sdp_params),
            truth: truth.map(pseudo_inertia_min),
        },
        parameter_errors: errors,
        sdp: SdpReport::new(&sdp),
        implausible: implausible.clone(),
        friction_width: Some(r.widths.clone()),
        timings_s: None,
    };
    if !reproducible {
        summary.timings_s = Some(stages.timings().iter().cloned().collect());
    }
    out.write_json("summary.json", &summary)?;
    let check = match r.gram_check {
        Some(c) => format!(
            "normal equations, κ = {:.3e}, κ²ε = {:.1e} (limit {:.0e})",
            c.condition, c.error_bound, c.limit
        ),
        None => "incremental QR".into(),
    };
    let warning = if implausible.is_empty() {
        String::new()
    } else {
        let items: String = implausible
            .iter()
            .map(|i| format!("- {}\n", i.message))
            .collect();
        format!(
            "## WARNING: implausible result\n\nThe checks below failed (`summary.json`, key \
             `implausible`): the figures that follow should not be used before the cause is \
             found.\n\n{items}\n"
        )
    };
    out.write(
        "report.md",
        format!(
            "# ARAS-Diamond identification report (`aras identify --streaming`)\n\n{intro}\n\n{warning}\
             Streaming identification in bounded memory (docs/scale.md): route {:?}, \
             {} rows read, {} samples used, rows fitted {} / {} (joint 1 / 2; the rest are \
             near velocity reversals), accumulation: {check}; band-limit noise gain {:.4}.\n\n\
             | | τ1 | τ2 |\n|---|---|---|\n| fitness (78) OLS, fitted rows | {:.2} % | {:.2} % |\n\
             | fitness (78) SDP, fitted rows | {:.2} % | {:.2} % |\n\n\
             The fitness on all rows and the time-series figures need the whole log in \
             memory: run with `--streaming off` for them.\n",
            r.route,
            r.samples_read,
            r.samples_used,
            r.rows_fitted[0],
            r.rows_fitted[1],
            r.noise_gain,
            f_ols[0],
            f_ols[1],
            f_sdp[0],
            f_sdp[1],
        ),
    )?;
    Ok(summary)
}
