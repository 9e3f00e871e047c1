//! `aras diagnose`: where the model and the measurement disagree,
//! which missing effect explains it, and how much the gap shrinks once it
//! is added. The statistics live in `aras_pipeline::diagnose`; this command
//! reads and processes the logs, runs it, and writes
//! `diagnosis.json`, `diagnosis.md`, `diagnosis.html` and the plots.

use anyhow::{Context, Result};
use aras_pipeline::diagnose::residual::{ResidualAnalysis, RowSample, SampledRow};
use aras_pipeline::diagnose::{
    Dataset, DiagnoseOptions, Diagnosis, DiagnosisWithWidths, PassRows, PassStage,
    RefinementStatus, WidthSource, diagnose_with_widths,
};
use aras_pipeline::friction_width::{FitRows, WidthRefinement};

use crate::cli::{DiagnoseArgs, LogArgs};
use crate::identify::process_options;
use crate::output::OutDir;
use crate::report::Report;
use crate::report::plots::{Binned, Series, StepPanel, binned_means, lines, scatter_binned, steps};
use crate::robot::{effect_spec, nominal, paper_model};
use crate::stages::Stages;
use aras_pipeline::streaming::{StreamingOptions, spool_log};
use indicatif::ProgressBar;
use std::path::Path;

/// Log size above which `--streaming auto` processes it in bounded
/// memory: 64 MB, about 7 minutes at 1 kHz, which the in-memory diagnosis
/// holds in ≈ 130 MiB; its memory grows by ≈ 250 bytes per sample beyond
/// (`docs/scale.md`).
pub const STREAMING_BYTES: u64 = 64 << 20;

/// Runs `diagnose`.
pub fn run(args: &DiagnoseArgs) -> Result<()> {
    if let Some(urdf) = &args.urdf {
        return super::urdf::diagnose(args, urdf);
    }
    let loaded = super::load_config(&args.common)?;
    let cfg = loaded.config.clone();
    // The logs and their sidecars.
    let logs: Vec<&std::path::Path> = std::iter::once(&args.data)
        .chain(&args.validate)
        .map(|p| p.as_path())
        .collect();
    let sidecars: Vec<std::path::PathBuf> = std::iter::once(args.log.sidecar_of(&args.data))
        .chain(args.validate.iter().map(|p| aras_log::sidecar_path(p)))
        .collect();
    let mut read = logs.clone();
    read.extend(sidecars.iter().map(|p| p.as_path()));
    let out = OutDir::create(
        &args.out,
        args.common.force,
        &super::input_files(&args.common, &loaded, &read),
    )?;
    let mut stages = Stages::new(args.common.quiet);
    let nominal = nominal(&cfg.robot, &loaded.dir)?;
    let model = paper_model(&nominal)?;
    let geometry = nominal.geometry()?;
    // TRAIN with the command line's period and sidecar, each validation log
    // with its own sidecar: the processing of `identify`. A log larger than
    // `STREAMING_BYTES` (or every log with `--streaming on`) is processed in
    // bounded memory into a scratch file in the staging directory.
    let streams = |path: &Path| super::identify::streams_log(args.streaming, path, STREAMING_BYTES);
    // `read`: the log already read (TRAIN, for the Coulomb widths).
    let load = |path: &Path,
                log_args: &LogArgs,
                streamed: bool,
                read: Option<&aras_log::Log>,
                bar: &ProgressBar| {
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |f| f.to_string_lossy().into(),
        );
        if streamed {
            let opts = StreamingOptions {
                read: super::streaming_read_options(log_args, &cfg)?,
                process: process_options(&cfg, log_args.period, false),
                geometry,
                ..StreamingOptions::default()
            };
            let mut progress = super::identify_streaming::track_rows(
                bar,
                path,
                format!("read + process {name} (streamed)"),
            );
            return spool_log(path, &opts, &out.path(""), &mut progress)
                .with_context(|| format!("processing {}", path.display()));
        }
        let owned;
        let log = match read {
            Some(log) => log,
            None => {
                owned = super::load_log(path, log_args, &cfg)?;
                &owned
            }
        };
        let p = aras_signal::process(
            log,
            &process_options(&cfg, log_args.period, false),
            &aras_kin::task_motion(&geometry),
        )
        .with_context(|| format!("processing {}", path.display()))?;
        Ok(Dataset::from_processed_owned(name, p)?)
    };
    let label = |any: bool| if any { " (streamed)" } else { "" };
    let train_streams = streams(&args.data)?;
    // The model identify fits (`identification.rows`): with `"all"` the
    // friction's Coulomb widths refined on TRAIN and every row of a joint
    // whose width was refined fitted and scored; a streamed TRAIN keeps
    // the rows away from reversals with the sign law (49) unless it has a
    // period (the streaming identification refines them on its average).
    let train_log = if train_streams || cfg.identification.rows == FitRows::AwayFromReversals {
        None
    } else {
        Some(stages.run("read TRAIN", |_| {
            super::load_log(&args.data, &args.log, &cfg)
        })?)
    };
    let train = stages.run(
        &format!("read + process TRAIN{}", label(train_streams)),
        |bar| {
            load(
                &args.data,
                &args.log,
                train_streams,
                train_log.as_ref(),
                bar,
            )
        },
    )?;
    let val_streams = args
        .validate
        .iter()
        .map(|p| streams(p))
        .collect::<Result<Vec<_>>>()?;
    let vals = stages.run(
        &format!(
            "read + process validation logs{}",
            label(val_streams.contains(&true))
        ),
        |bar| {
            args.validate
                .iter()
                .zip(&val_streams)
                .map(|(p, &streamed)| {
                    // The lab's column names and torque timing hold for
                    // every log; period and sidecar are TRAIN's.
                    let own = LogArgs {
                        columns: args.log.columns.clone(),
                        torques: args.log.torques,
                        ..LogArgs::default()
                    };
                    load(p, &own, streamed, None, bar)
                })
                .collect::<Result<Vec<_>>>()
        },
    )?;
    // The rows identification fits: the same reversal exclusion and base
    // parameter sampling (`[identification]`), and cross-validation's
    // exclusion for the validation logs (`validation.reversal_reach`).
    let ic = &cfg.identification;
    let dc = &cfg.diagnose;
    let opts = DiagnoseOptions {
        alpha: dc.alpha,
        min_gain: dc.min_gain,
        max_steps: dc.max_steps,
        grid: dc.grid.clone(),
        reference: Some(nominal.clone()),
        base_samples: ic.base_samples,
        workspace: crate::identify::workspace(&cfg)?,
        min_speed: ic.min_speed,
        reach_tol: ic.reversal_reach,
        validation_reach_tol: cfg.validation.reversal_reach,
        ..DiagnoseOptions::default()
    };
    // The starting model's Coulomb widths refined on TRAIN together with
    // the effects the diagnosis names (`aras_pipeline::diagnose::
    // diagnose_with_widths`): TRAIN in memory, streamed, or the sign law.
    let process = process_options(&cfg, args.log.period, false);
    let streamed_opts;
    let source = match &train_log {
        _ if cfg.identification.rows == FitRows::AwayFromReversals => WidthSource::SignLaw,
        Some(log) => WidthSource::Log {
            log,
            process: &process,
        },
        None => {
            streamed_opts = super::identify_streaming::log_options(&args.log, &cfg, geometry)?;
            WidthSource::Streamed {
                path: &args.data,
                options: &streamed_opts,
            }
        }
    };
    let DiagnosisWithWidths {
        diagnosis: d,
        widths,
        ..
    } = diagnose_with_widths(
        &model,
        &geometry,
        &train,
        &vals,
        &opts,
        &source,
        &cfg.identification,
        &mut |s| stages.begin(&stage_name(s)),
    )
    .context("diagnosing TRAIN")?;
    stages.end();
    let train_name = train.name.clone();
    // The scratch file of a streamed TRAIN goes before the outputs are
    // committed.
    let vals_names: Vec<String> = vals
        .iter()
        .map(|v| {
            std::path::Path::new(&v.name)
                .file_stem()
                .map_or_else(|| v.name.clone(), |s| s.to_string_lossy().into_owned())
        })
        .collect();
    drop(train);
    drop(vals);
    // The diagnosis, with the starting model's Coulomb widths.
    let mut json = serde_json::to_value(&d).context("serialising the diagnosis")?;
    if let Some(o) = json.as_object_mut() {
        o.insert(
            "friction_width".into(),
            serde_json::to_value(&widths).context("serialising the widths")?,
        );
    }
    out.write_json("diagnosis.json", &json)?;
    // The predictions behind the raw-torque fitness of the starting and
    // the final model, per validation set: `row,tau1,tau2` on every log row
    // that has a sample.
    let last = d.fitness.len().saturating_sub(1);
    for (tag, k) in [("start", 0), ("final", last)] {
        let Some(row) = d.fitness.get(k) else {
            continue;
        };
        for (v, p) in vals_names.iter().zip(&row.predicted) {
            let Some(p) = p else { continue };
            let mut csv = String::from("row,tau1,tau2\n");
            for (i, r) in p.rows.iter().enumerate() {
                use std::fmt::Write as _;
                let _ = writeln!(csv, "{r},{},{}", p.tau[0][i], p.tau[1][i]);
            }
            out.write(&format!("pred_{tag}_{v}.csv"), csv)?;
        }
    }
    let report = build(&d, &train_name, &widths, &cfg.diagnose)?;
    for (file, svg) in report.figures() {
        out.write(file, svg)?;
    }
    out.write("diagnosis.md", report.to_markdown())?;
    out.write("diagnosis.html", report.to_html())?;
    let dir = out.commit()?;
    println!("{}", widths.sentence());
    println!("{}", d.conclusion);
    println!(
        "validation fitness (78) vs the raw torques on every row, τ1/τ2 (in brackets: filtered, \
         on the fitted rows, as the selection scores it)"
    );
    for r in &d.fitness {
        let f: Vec<String> = r
            .fitness
            .iter()
            .zip(&r.fitness_filtered)
            .map(|(x, y)| {
                let raw = x
                    .as_ref()
                    .map_or("–".to_string(), |x| format!("{:.2}/{:.2} %", x[0], x[1]));
                format!("{raw} ({:.2}/{:.2} %)", y[0], y[1])
            })
            .collect();
        println!("step {}: {}  [{}]", r.step, f.join("  "), r.model);
    }
    println!("outputs in {}", dir.display());
    Ok(())
}

/// A stage of the diagnosis recipe in the progress lines.
fn stage_name(s: PassStage) -> String {
    match s {
        PassStage::Widths { pass } => format!("Coulomb widths on TRAIN (pass {pass})"),
        PassStage::Diagnose { pass, rows } => {
            let what = match rows {
                PassRows::Fitted => "",
                PassRows::EveryRow => ", every row",
                PassRows::IdentifyRows => ", rows identify fits",
            };
            format!("diagnose (candidates × rounds, pass {pass}{what})")
        }
    }
}

fn pct(x: f64) -> String {
    format!("{x:.2}")
}

/// The report: conclusion, effects added with evidence, fitness table and
/// plot, residual findings and plots before/after, candidate scores.
fn build(
    d: &Diagnosis,
    train: &str,
    widths: &WidthRefinement,
    settings: &crate::config::DiagnoseConfig,
) -> Result<Report> {
    let mut r = Report::new("Diagnosis: where the model and the measurement disagree");
    let names: Vec<&str> = d.before.iter().map(|a| a.dataset.as_str()).collect();
    r.paragraph(format!(
        "Model identified on `{train}` and scored on {}. Candidates are fitted with the \
         current model on TRAIN, tested with an F-test on the effective number of independent \
         samples (Bonferroni over the round's candidates, α = {} %), and must raise the \
         validation fitness (78) by ≥ {} points on every validation set; the significant one \
         with the lowest ΔBIC is added (docs/diagnose.md; `[diagnose]` settings).",
        names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", "),
        100.0 * settings.alpha,
        settings.min_gain
    ));
    r.paragraph(format!(
        "Starting model: identify's, on the rows it fits. {}",
        widths.sentence()
    ));
    r.heading(2, "Conclusion").paragraph(d.conclusion.clone());

    effects_added(&mut r, d, train)?;
    fitness_per_step(&mut r, d, &names)?;
    residual_before_after(&mut r, d)?;
    residual_against_time(&mut r, d)?;
    residual_spectra(&mut r, d)?;
    candidate_scores(&mut r, d)?;
    r.paragraph(format!("Diagnosis time: {:.2} s.", d.elapsed_s));
    Ok(r)
}

/// The effects added, each with its evidence, parameters and refinement.
fn effects_added(r: &mut Report, d: &Diagnosis, train: &str) -> Result<()> {
    r.heading(2, "Effects added");
    if d.steps.is_empty() {
        r.paragraph("None.");
    } else {
        let specs: Vec<String> = d
            .steps
            .iter()
            .map(|s| effect_spec(&s.refined_candidate(), None))
            .collect();
        r.paragraph(format!(
            "To identify the model with them (refined settings where refined): \
             `aras identify --data {train} --effects {}`.",
            specs.join(",")
        ));
    }
    for (k, s) in d.steps.iter().enumerate() {
        r.heading(3, format!("{}. `{}` — {}", k + 1, s.id, s.label));
        r.paragraph(s.explanation.clone());
        let e = &s.evidence;
        let mut items = vec![
            format!(
                "F = {:.2} with {} added parameters, p = {:.2e}, ΔBIC = {:.1}, N_eff = {:.0}",
                e.f, e.added_parameters, e.p_value, e.delta_bic, e.n_eff
            ),
            format!(
                "validation gain per joint {:+.2} / {:+.2} points; per set {}",
                e.gain[0],
                e.gain[1],
                e.gain_per_set
                    .iter()
                    .map(|g| format!("{g:+.2}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ];
        if !s.aliases.is_empty() {
            items.push(format!(
                "indistinguishable on these data from: {}",
                s.aliases.join(", ")
            ));
        }
        if let Some(f) = &s.refinement {
            items.push(format!(
                "`{}` refined between the grid points: {:.5} ± {:.1e} (grid value {}, {}); \
                 fitted at it: {}",
                f.name,
                f.value,
                f.std_dev,
                f.grid_value,
                match f.status {
                    RefinementStatus::Interior => "minimum inside the search interval",
                    RefinementStatus::AtBound =>
                        "minimum at the end of the search interval, σ unknown",
                },
                f.parameters
                    .iter()
                    .map(|p| format!("{} = {:.5} ± {:.1e}", p.name, p.value, p.std_dev))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        r.list(items);
        if !s.parameters.is_empty() {
            r.table(
                &["parameter", "value", "σ"],
                s.parameters
                    .iter()
                    .map(|p| {
                        vec![
                            p.name.clone(),
                            format!("{:.5}", p.value),
                            format!("{:.2e}", p.std_dev),
                        ]
                    })
                    .collect(),
            );
        }
    }
    Ok(())
}

/// The validation fitness (78) after each step: table and plot.
fn fitness_per_step(r: &mut Report, d: &Diagnosis, names: &[&str]) -> Result<()> {
    r.heading(2, "Validation fitness per step (78), %");
    let mut header = vec!["step".to_string(), "model".to_string()];
    for n in names {
        header.push(format!("{n} τ1"));
        header.push(format!("{n} τ2"));
        header.push(format!("{n} τ1 filtered"));
        header.push(format!("{n} τ2 filtered"));
    }
    let header_ref: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    let rows = d
        .fitness
        .iter()
        .map(|row| {
            let mut v = vec![row.step.to_string(), row.model.clone()];
            for (f, g) in row.fitness.iter().zip(&row.fitness_filtered) {
                v.push(f.as_ref().map_or("–".into(), |f| pct(f[0])));
                v.push(f.as_ref().map_or("–".into(), |f| pct(f[1])));
                v.push(pct(g[0]));
                v.push(pct(g[1]));
            }
            v
        })
        .collect();
    r.table(&header_ref, rows);
    r.paragraph(
        "τ1, τ2: the fitness (78) of the prediction from the processed motion against the \
         log's raw torques on every row, as `identify`, `predict` and `validate` report it \
         (– for a streamed validation log). Filtered: the selection's score, the fitness of \
         the filtered (and period-averaged) torques on the rows the fits keep away from \
         velocity reversals; the candidates' gains are differences of it. It is higher than \
         the raw-torque figure and can exceed the noise ceiling of the raw torques.",
    );
    if let Some(c) = &d.consistent {
        r.paragraph(format!(
            "Physically consistent re-identification of the final model ({}): filtered \
             validation fitness on the fitted rows {}.",
            c.status,
            c.fitness_filtered
                .iter()
                .zip(names)
                .map(|(f, n)| format!("{n} {:.2} / {:.2} %", f[0], f[1]))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    r.figure(
        "fitness_steps.svg",
        "Validation fitness (78) against the raw torques on every row, per joint after each step (start = starting model; one panel per \
         validation set and joint, each axis zoomed to its values).",
        fitness_steps(d, names)?,
    );
    Ok(())
}

/// The residual findings and profiles before and after the effects.
fn residual_before_after(r: &mut Report, d: &Diagnosis) -> Result<()> {
    r.heading(2, "Residual before and after");
    for (b, a) in d.before.iter().zip(&d.after) {
        r.heading(3, format!("`{}`", b.dataset));
        let mut items: Vec<String> = b
            .findings
            .iter()
            .filter(|f| f.systematic)
            .take(6)
            .map(|f| format!("before: {}", f.text))
            .collect();
        items.extend(
            a.findings
                .iter()
                .filter(|f| f.systematic)
                .take(6)
                .map(|f| format!("after: {}", f.text)),
        );
        for l in &a.left_out {
            items.push(format!(
                "after, the {} rows of joint {} left out near velocity reversals: residual RMS \
                 {:.4} N·m (fitted rows {:.4}); filtered validation fitness on all rows {:.2} %, on the \
                 fitted rows {:.2} %",
                l.rows, l.joint, l.rms, l.fitted_rms, l.fitness_filtered_all_rows, l.fitness_filtered_fitted_rows
            ));
            items.extend(
                l.findings
                    .iter()
                    .take(3)
                    .map(|f| format!("after: {}", f.text)),
            );
        }
        items.extend(
            a.spectra
                .iter()
                .filter_map(|sp| sp.finding.as_ref())
                .map(|f| format!("after: {}", f.text)),
        );
        for (tag, x) in [("before", b), ("after", a)] {
            for w in &x.whiteness {
                items.push(format!(
                    "{tag}: joint {} residual RMS {:.4} N·m, Ljung–Box p = {:.3} ({})",
                    w.joint,
                    w.rms,
                    w.p_value,
                    if w.is_white() { "white" } else { "not white" }
                ));
            }
        }
        r.list(items);
        let friction = friction_found(d, b, a);
        for j in 1..=2 {
            let (Some(sb), Some(sa)) = (sample(b, j), sample(a, j)) else {
                continue;
            };
            let ds = sanitize(&b.dataset);
            for (axis, symbol, unit) in [
                (ScatterAxis::Velocity, "θ̇", "rad/s"),
                (ScatterAxis::Position, "θ", "rad"),
            ] {
                let fitted = |s: &RowSample, fitted: bool| -> Vec<(f64, f64)> {
                    s.rows
                        .iter()
                        .filter(|r| r.fitted == fitted)
                        .map(|r| (axis.of(r), r.residual))
                        .collect()
                };
                let (before, after, left) = (fitted(sb, true), fitted(sa, true), fitted(sa, false));
                let mut groups = vec![
                    Binned {
                        name: "before, binned mean ± sd".into(),
                        bins: binned_means(&before, SCATTER_BINS),
                        points: Vec::new(),
                    },
                    Binned {
                        name: "after, binned mean ± sd (points: rows)".into(),
                        bins: binned_means(&after, SCATTER_BINS),
                        points: after,
                    },
                ];
                if axis == ScatterAxis::Velocity && !left.is_empty() {
                    groups.push(Binned {
                        name: "after, rows left out near reversals".into(),
                        bins: binned_means(&left, SCATTER_BINS / 2),
                        points: left,
                    });
                }
                let name = axis.name();
                r.figure(
                    format!("residual_{name}_{ds}_j{j}.svg"),
                    format!(
                        "`{}`, joint {j}: residual against {name}, a sample of {} rows (one in \
                         {}) after the final model, with the binned mean ± standard deviation \
                         before and after ({SCATTER_BINS} bins of equal count).",
                        b.dataset,
                        sa.rows.len(),
                        sa.stride
                    ),
                    scatter_binned(
                        &format!("{} joint {j}: residual vs {name}", b.dataset),
                        &format!("{symbol} ({unit})"),
                        "residual (N·m)",
                        &groups,
                    )?,
                );
            }
            if friction.contains(&j) {
                r.figure(
                    format!("hysteresis_{ds}_j{j}.svg"),
                    format!(
                        "`{}`, joint {j}: residual against velocity near the reversals, before \
                         the added effects, split by the sign of the acceleration: two branches \
                         apart are a loop (friction or backlash that depends on the direction \
                         of travel); after, the same rows.",
                        b.dataset
                    ),
                    scatter_binned(
                        &format!("{} joint {j}: hysteresis near reversals", b.dataset),
                        "θ̇ (rad/s)",
                        "residual (N·m)",
                        &hysteresis(sb, sa),
                    )?,
                );
            }
        }
    }
    Ok(())
}

/// The residual against time, per validation set and joint.
fn residual_against_time(r: &mut Report, d: &Diagnosis) -> Result<()> {
    r.heading(2, "Residual against time");
    r.paragraph(
        "The residual (every row) against time, decimated to at most a thousand points: each \
         point is the mean of a run of consecutive rows, with the run's smallest and largest \
         residual after the final model. A drift, a jump or a burst that the profiles average \
         away shows here.",
    );
    for (b, a) in d.before.iter().zip(&d.after) {
        for (tb, ta) in b.traces.iter().zip(&a.traces) {
            let j = ta.joint;
            r.figure(
                format!("residual_trace_{}_j{j}.svg", sanitize(&b.dataset)),
                format!(
                    "`{}`, joint {j}: residual against time, before and after ({} rows per \
                     point).",
                    b.dataset, ta.rows_per_point
                ),
                lines(
                    &format!("{} joint {j}: residual against time", b.dataset),
                    "t (s)",
                    "residual (N·m)",
                    &[
                        Series {
                            name: "before, mean".into(),
                            x: &tb.t,
                            y: &tb.mean,
                        },
                        Series {
                            name: "after, mean".into(),
                            x: &ta.t,
                            y: &ta.mean,
                        },
                        Series {
                            name: "after, smallest".into(),
                            x: &ta.t,
                            y: &ta.min,
                        },
                        Series {
                            name: "after, largest".into(),
                            x: &ta.t,
                            y: &ta.max,
                        },
                    ],
                    aras_pipeline::diagnose::TRACE_POINTS,
                )?,
            );
        }
    }
    Ok(())
}

/// The residual spectra, per validation set and joint.
fn residual_spectra(r: &mut Report, d: &Diagnosis) -> Result<()> {
    r.heading(2, "Residual spectra");
    r.paragraph(
        "Power density of the residual (every row) before and after, next to the measured \
         torque's, on a log scale: a band where the residual stands far above its flat floor \
         is where the model misses.",
    );
    for (b, a) in d.before.iter().zip(&d.after) {
        for (sb, sa) in b.spectra.iter().zip(&a.spectra) {
            let log = |v: &[f64]| -> Vec<f64> { v.iter().map(|x| x.max(1e-30).log10()).collect() };
            let (yb, ya, yt) = (
                log(&sb.residual_density),
                log(&sa.residual_density),
                log(&sa.torque_density),
            );
            let j = sa.joint;
            r.figure(
                format!("residual_spectrum_{}_j{j}.svg", sanitize(&b.dataset)),
                format!(
                    "`{}`, joint {j}: log10 power density (N²·m²/Hz) of the residual before and \
                     after, and of the measured torque.",
                    b.dataset
                ),
                lines(
                    &format!("{} joint {j}: residual spectrum", b.dataset),
                    "frequency (Hz)",
                    "log10 density (N²·m²/Hz)",
                    &[
                        Series {
                            name: "residual before".into(),
                            x: &sb.frequencies_hz,
                            y: &yb,
                        },
                        Series {
                            name: "residual after".into(),
                            x: &sa.frequencies_hz,
                            y: &ya,
                        },
                        Series {
                            name: "measured torque".into(),
                            x: &sa.frequencies_hz,
                            y: &yt,
                        },
                    ],
                    400,
                )?,
            );
        }
    }
    Ok(())
}

/// The scores of every candidate in every round.
fn candidate_scores(r: &mut Report, d: &Diagnosis) -> Result<()> {
    r.heading(2, "Candidate scores per round");
    for (k, round) in d.rounds.iter().enumerate() {
        r.heading(3, format!("Round {}", k + 1));
        r.table(
            &[
                "candidate",
                "k",
                "RSS drop %",
                "F",
                "p",
                "ΔBIC",
                "gain τ1",
                "gain τ2",
                "significant",
            ],
            round
                .iter()
                .take(12)
                .map(|c| {
                    vec![
                        c.label.clone(),
                        c.added_parameters.to_string(),
                        format!("{:.2}", c.rss_drop_percent),
                        format!("{:.2}", c.f),
                        format!("{:.1e}", c.p_value),
                        format!("{:.1}", c.delta_bic),
                        format!("{:+.2}", c.gain[0]),
                        format!("{:+.2}", c.gain[1]),
                        if c.significant { "yes" } else { "no" }.into(),
                    ]
                })
                .collect(),
        );
    }
    Ok(())
}

/// The step plot: one panel per validation set and joint, one point per
/// step named by the effect it added.
pub fn fitness_steps(d: &Diagnosis, names: &[&str]) -> Result<String> {
    let step_names: Vec<String> = d
        .fitness
        .iter()
        .map(
            |f| match f.step.checked_sub(1).and_then(|k| d.steps.get(k)) {
                Some(s) => format!("+ {}", s.id),
                None => "start".into(),
            },
        )
        .collect();
    let panels: Vec<StepPanel> = names
        .iter()
        .enumerate()
        .flat_map(|(s, n)| {
            (0..2).map(move |j| StepPanel {
                title: format!("{n}, τ{}", j + 1),
                values: d
                    .fitness
                    .iter()
                    .map(|f| {
                        f.fitness
                            .get(s)
                            .and_then(Option::as_ref)
                            .map_or(f64::NAN, |v| v[j])
                    })
                    .collect(),
                ceiling: None,
            })
        })
        .collect();
    steps(
        "Validation fitness per step",
        "fitness (78) %",
        &step_names,
        &panels,
    )
}

/// Bins of the residual scatter figures.
const SCATTER_BINS: usize = 16;

/// Effects whose evidence is a friction law or a direction-dependent
/// torque: the diagnosis then draws the hysteresis figure.
const FRICTION_EFFECTS: [&str; 3] = [
    "coulomb_asymmetry",
    "stribeck_friction",
    "passive_joint_viscous",
];

/// What the residual scatter figures put on x.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ScatterAxis {
    Velocity,
    Position,
}

impl ScatterAxis {
    fn of(self, r: &SampledRow) -> f64 {
        match self {
            ScatterAxis::Velocity => r.theta_dot,
            ScatterAxis::Position => r.theta,
        }
    }
    fn name(self) -> &'static str {
        match self {
            ScatterAxis::Velocity => "velocity",
            ScatterAxis::Position => "position",
        }
    }
}

fn sample(a: &ResidualAnalysis, joint: usize) -> Option<&RowSample> {
    a.samples
        .iter()
        .find(|s| s.joint == joint && !s.rows.is_empty())
}

/// The joints with friction findings: a friction-like effect added, or a
/// systematic residual near the velocity reversals (the jump at reversal,
/// or the rows left out there) before or after.
fn friction_found(d: &Diagnosis, b: &ResidualAnalysis, a: &ResidualAnalysis) -> Vec<usize> {
    let any_step = d
        .steps
        .iter()
        .any(|s| FRICTION_EFFECTS.contains(&s.id.as_str()));
    (1..=2)
        .filter(|&j| {
            any_step
                || [b, a].iter().any(|x| {
                    x.findings
                        .iter()
                        .any(|f| f.joint == j && f.systematic && f.text.contains("reversal"))
                        || x.left_out
                            .iter()
                            .any(|l| l.joint == j && !l.findings.is_empty())
                })
        })
        .collect()
}

/// Velocity below which a row is near a reversal for the hysteresis
/// figure: the fastest row left out near a reversal, or four times the
/// rest band when none was left out.
fn reversal_band(s: &RowSample) -> f64 {
    let left = s
        .rows
        .iter()
        .filter(|r| !r.fitted)
        .map(|r| r.theta_dot.abs())
        .fold(0.0, f64::max);
    if left > 0.0 {
        left
    } else {
        4.0 * aras_pipeline::diagnose::residual::REST_VELOCITY
    }
}

/// The hysteresis figure's groups: the rows near reversals before (points
/// and binned means) and after (binned means), split by the sign of θ̈.
fn hysteresis(before: &RowSample, after: &RowSample) -> Vec<Binned> {
    let band = reversal_band(before);
    let branch = |s: &RowSample, rising: bool| -> Vec<(f64, f64)> {
        s.rows
            .iter()
            .filter(|r| r.theta_dot.abs() <= band && (r.theta_ddot > 0.0) == rising)
            .map(|r| (r.theta_dot, r.residual))
            .collect()
    };
    let mut groups = Vec::new();
    for (tag, rising) in [("θ̈ > 0", true), ("θ̈ ≤ 0", false)] {
        let pts = branch(before, rising);
        groups.push(Binned {
            name: format!("before, {tag}"),
            bins: binned_means(&pts, 8),
            points: pts,
        });
    }
    for (tag, rising) in [("θ̈ > 0", true), ("θ̈ ≤ 0", false)] {
        let pts = branch(after, rising);
        groups.push(Binned {
            name: format!("after, {tag}"),
            bins: binned_means(&pts, 8),
            points: Vec::new(),
        });
    }
    groups
}

fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}
