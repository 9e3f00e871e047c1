//! `aras diagnose`: where the model and the measurement disagree,
//! which missing effect explains it, and how much the gap shrinks once it
//! is added. The statistics live in `aras_pipeline::diagnose`; this command
//! reads and processes the logs, runs it, and writes
//! `diagnosis.json`, `diagnosis.md`, `diagnosis.html` and the plots.

use anyhow::{Context, Result};
use aras_pipeline::diagnose::residual::Profile;
use aras_pipeline::diagnose::{Dataset, DiagnoseOptions, Diagnosis, RefinementStatus, diagnose};

use crate::cli::{DiagnoseArgs, LogArgs};
use crate::identify::process_options;
use crate::output::OutDir;
use crate::report::Report;
use crate::report::plots::{Series, lines};
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
    let load = |path: &Path, log_args: &LogArgs, streamed: bool, bar: &ProgressBar| {
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
            let read = super::identify_streaming::rows_read(path);
            let mut progress = |rows: u64| {
                bar.set_message(format!("read + process {name} (streamed): {}", read(rows)));
            };
            return spool_log(path, &opts, &out.path(""), &mut progress)
                .with_context(|| format!("processing {}", path.display()));
        }
        let log = super::load_log(path, log_args, &cfg)?;
        let p = aras_signal::process(
            &log,
            &process_options(&cfg, log_args.period, false),
            &aras_kin::task_motion(&geometry),
        )
        .with_context(|| format!("processing {}", path.display()))?;
        Ok(Dataset::from_processed_owned(name, p)?)
    };
    let label = |any: bool| if any { " (streamed)" } else { "" };
    let train_streams = streams(&args.data)?;
    let train = stages.run(
        &format!("read + process TRAIN{}", label(train_streams)),
        |bar| load(&args.data, &args.log, train_streams, bar),
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
                    // The lab's column names hold for every log; period and
                    // sidecar are TRAIN's.
                    let own = LogArgs {
                        columns: args.log.columns.clone(),
                        ..LogArgs::default()
                    };
                    load(p, &own, streamed, bar)
                })
                .collect::<Result<Vec<_>>>()
        },
    )?;
    // The rows identification fits: the same reversal exclusion and base
    // parameter sampling (`[identification]`), and cross-validation's
    // exclusion for the validation logs (`validation.reversal_reach`).
    let ic = &cfg.identification;
    let opts = DiagnoseOptions {
        reference: Some(nominal.clone()),
        base_samples: ic.base_samples,
        workspace: crate::identify::workspace(&cfg)?,
        min_speed: ic.min_speed,
        reach_tol: ic.reversal_reach,
        validation_reach_tol: cfg.validation.reversal_reach,
        ..DiagnoseOptions::default()
    };
    let d = stages.run("diagnose (candidates × rounds)", |_| {
        diagnose(&model, &geometry, &train, &vals, &opts)
    })?;
    let train_name = train.name.clone();
    // The scratch file of a streamed TRAIN goes before the outputs are
    // committed.
    drop(train);
    drop(vals);
    out.write_json("diagnosis.json", &d)?;
    let report = build(&d, &train_name)?;
    for (file, svg) in report.figures() {
        out.write(file, svg)?;
    }
    out.write("diagnosis.md", report.to_markdown())?;
    out.write("diagnosis.html", report.to_html())?;
    let dir = out.commit()?;
    println!("{}", d.conclusion);
    for r in &d.fitness {
        let f: Vec<String> = r
            .fitness
            .iter()
            .map(|x| format!("{:.2}/{:.2} %", x[0], x[1]))
            .collect();
        println!("step {}: {}  [{}]", r.step, f.join("  "), r.model);
    }
    println!("outputs in {}", dir.display());
    Ok(())
}

fn pct(x: f64) -> String {
    format!("{x:.2}")
}

/// The report: conclusion, effects added with evidence, fitness table and
/// plot, residual findings and plots before/after, candidate scores.
fn build(d: &Diagnosis, train: &str) -> Result<Report> {
    let mut r = Report::new("Diagnosis: where the model and the measurement disagree");
    let names: Vec<&str> = d.before.iter().map(|a| a.dataset.as_str()).collect();
    r.paragraph(format!(
        "Model identified on `{train}` and scored on {}. Candidates are fitted with the \
         current model on TRAIN, tested with an F-test on the effective number of independent \
         samples (Bonferroni over the round's candidates, α = 1 %), and must raise the \
         validation fitness (78) by ≥ 0.1 points on every validation set; the significant one \
         with the lowest ΔBIC is added (docs/diagnose.md).",
        names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    r.heading(2, "Conclusion").paragraph(d.conclusion.clone());

    r.heading(2, "Effects added");
    if d.steps.is_empty() {
        r.paragraph("None.");
    } else {
        let specs: Vec<String> = d
            .steps
            .iter()
            .map(|s| effect_spec(&s.candidate, s.refinement.as_ref().map(|f| f.value)))
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

    r.heading(2, "Validation fitness per step (78), %");
    let mut header = vec!["step".to_string(), "model".to_string()];
    for n in &names {
        header.push(format!("{n} τ1"));
        header.push(format!("{n} τ2"));
    }
    let header_ref: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    let rows = d
        .fitness
        .iter()
        .map(|row| {
            let mut v = vec![row.step.to_string(), row.model.clone()];
            for f in &row.fitness {
                v.push(pct(f[0]));
                v.push(pct(f[1]));
            }
            v
        })
        .collect();
    r.table(&header_ref, rows);
    if let Some(c) = &d.consistent {
        r.paragraph(format!(
            "Physically consistent re-identification of the final model ({}): {}.",
            c.status,
            c.fitness
                .iter()
                .zip(&names)
                .map(|(f, n)| format!("{n} {:.2} / {:.2} %", f[0], f[1]))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let steps: Vec<f64> = d.fitness.iter().map(|f| f.step as f64).collect();
    let ys: Vec<(String, Vec<f64>)> = (0..names.len())
        .flat_map(|s| (0..2).map(move |j| (s, j)))
        .map(|(s, j)| {
            (
                format!("{} τ{}", names[s], j + 1),
                d.fitness.iter().map(|f| f.fitness[s][j]).collect(),
            )
        })
        .collect();
    let series: Vec<Series> = ys
        .iter()
        .map(|(n, y)| Series {
            name: n.clone(),
            x: &steps,
            y,
        })
        .collect();
    r.figure(
        "fitness_steps.svg",
        "Validation fitness per joint after each step (0 = starting model).",
        lines(
            "Validation fitness per step",
            "step",
            "fitness (78) %",
            &series,
            100,
        )?,
    );

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
                 {:.4} N·m (fitted rows {:.4}); validation fitness on all rows {:.2} %, on the \
                 fitted rows {:.2} %",
                l.rows, l.joint, l.rms, l.fitted_rms, l.fitness_all_rows, l.fitness_fitted_rows
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
        for j in 1..=2 {
            let (Some(pb), Some(pa)) = (b.velocity_profile(j), a.velocity_profile(j)) else {
                continue;
            };
            let (xb, yb) = centres(pb);
            let (xa, ya) = centres(pa);
            let (xl, yl) = a
                .left_out
                .iter()
                .find(|l| l.joint == j)
                .map_or((Vec::new(), Vec::new()), |l| centres(&l.profile));
            let file = format!("residual_{}_j{j}.svg", sanitize(&b.dataset));
            r.figure(
                file,
                format!(
                    "`{}`, joint {j}: mean residual binned against velocity, before and after, \
                     and after on the rows left out near velocity reversals.",
                    b.dataset
                ),
                lines(
                    &format!("{} joint {j}: residual vs velocity", b.dataset),
                    "θ̇ (rad/s)",
                    "mean residual (N·m)",
                    &[
                        Series {
                            name: "before".into(),
                            x: &xb,
                            y: &yb,
                        },
                        Series {
                            name: "after".into(),
                            x: &xa,
                            y: &ya,
                        },
                        Series {
                            name: "after, rows left out".into(),
                            x: &xl,
                            y: &yl,
                        },
                    ],
                    200,
                )?,
            );
        }
    }

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
    r.paragraph(format!("Diagnosis time: {:.2} s.", d.elapsed_s));
    Ok(r)
}

fn centres(p: &Profile) -> (Vec<f64>, Vec<f64>) {
    p.bins.iter().map(|b| (0.5 * (b.lo + b.hi), b.mean)).unzip()
}

fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}
