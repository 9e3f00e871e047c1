//! `aras friction`'s words: the conclusion and the diagnosis part of the
//! report, from the analysis of `aras_friction::analyse` (the library holds
//! the fitting, the scoring and the diagnosis; `cmd::friction` reads the
//! logs, writes the outputs and draws the figures).

use aras_friction::FrictionRun;

/// One paragraph: the best classical model and what the diagnosis found.
pub fn conclusion(run: &FrictionRun) -> String {
    let best = &run.models[run.best];
    let mut s = format!(
        "Best classical model: {} (RMS TRAIN {:.4} N·m{}).",
        best.name,
        best.train.rms,
        if best.validation.is_empty() {
            String::new()
        } else {
            format!(
                ", validation {}",
                best.validation
                    .iter()
                    .map(|m| format!("{:.4}", m.rms))
                    .collect::<Vec<_>>()
                    .join(" / ")
            )
        }
    );
    if run.diagnosis.is_none() {
        s.push(' ');
        match &run.diagnosis_note {
            Some(note) => s.push_str(&note.to_string()),
            None => s.push_str("No diagnosis was run."),
        }
    } else if run.model.effects.is_empty() {
        s.push_str(" No further effect was added.");
    } else {
        let names: Vec<String> = run.model.effects.iter().map(|(e, _)| e.label()).collect();
        if run.model.base.name() != best.name {
            s.push_str(&format!(
                " Final model: {} (its path predicts the validation logs better), with",
                run.model.base.name()
            ));
        } else {
            s.push_str(" Added:");
        }
        s.push_str(&format!(" {}.", names.join("; ")));
    }
    // A doubtful fit of a model the conclusion names is said here, where
    // the user reads first.
    for m in std::iter::once(best).chain(run.final_model.iter()) {
        for w in &m.warnings {
            s.push_str(&format!(" **`{}`: {w}.**", m.name));
        }
    }
    s
}

/// The diagnosis part of the report: the gap shrinking step by step.
pub fn report_diagnosis(run: &FrictionRun, r: &mut crate::report::Report) {
    r.heading(2, "Diagnosis");
    let Some(d) = &run.diagnosis else {
        r.paragraph(
            run.diagnosis_note
                .map_or_else(|| "No diagnosis.".into(), |n| n.to_string()),
        );
        return;
    };
    r.paragraph(format!(
        "The residual of `{}` is tested against {} candidate effects. An effect is added when \
         its F-test on TRAIN is significant (α = {} over the round's candidates, with N_eff the \
         independent samples of the residual with that effect; the base residual's are {:.0} % \
         of the rows) and it raises the fitness (78) by at least {} points on every validation \
         log; the refined model then refits the friction model's nonlinear parameters with the \
         added effects.",
        d.base,
        d.candidates.len(),
        run.settings.alpha,
        100.0 * d.effective_fraction,
        run.settings.min_gain
    ));
    let best = &run.models[run.best].name;
    if &d.base != best {
        r.paragraph(format!(
            "`{best}` is the best classical model, but `{}` with the effects its diagnosis \
             adds predicts the validation logs better than `{best}`'s own path: this is the \
             diagnosis shown, and its final model is the one kept.",
            d.base
        ));
    }
    let sp = &d.spectrum;
    if sp.band.1 > sp.band.0 {
        let mut text = format!(
            "Ripple lines searched in the residual against position from {:.1} to {:.0} \
             cycles/rev (threshold z > {:.1}, false-alarm probability {} over the band): ",
            sp.band.0, sp.band.1, sp.threshold, run.settings.library.spectrum.false_alarm
        );
        if sp.lines.is_empty() {
            text.push_str("none found.");
        } else {
            let lines: Vec<String> = sp
                .lines
                .iter()
                .map(|l| {
                    format!(
                        "{:.2} ± {:.2} cycles/rev ({:.2e} N·m, z = {:.1})",
                        l.cycles, l.sigma, l.amplitude, l.z
                    )
                })
                .collect();
            text.push_str(&lines.join("; "));
            text.push_str(". Each line and its harmonics are candidates.");
        }
        r.paragraph(text);
        for lp in d.phases.iter().filter(|p| !p.shared) {
            let phases: Vec<String> = std::iter::once(&run.train.name)
                .chain(run.validation.iter().map(|v| &v.name))
                .zip(&lp.per_log)
                .map(|(name, p)| match p {
                    Some(p) => format!("{name} {:.2} ± {:.2} rad", p.phase, p.sigma),
                    None => format!("{name} —"),
                })
                .collect();
            let harmonic = |k: f64| {
                let n = (k / lp.cycles).round();
                n >= 1.0 && (k - n * lp.cycles).abs() <= 1e-9 * k
            };
            let modelled = if !run.model.per_log_phase.iter().any(|&k| harmonic(k)) {
                "The final model has no ripple from this line, so nothing is set per log."
            } else {
                "The final model sets the phase of its ripple from this line per log: on every \
                 log with a torque it is measured from that torque (one parameter per line and \
                 log, like the position zero it stands for); a log without torque gets TRAIN's."
            };
            r.paragraph(format!(
                "**The line at {:.2} cycles/rev has another phase on another log** ({}): the \
                 logs do not share a position zero (an encoder zeroed per log) or the ripple \
                 moved, and one phase, TRAIN's, cannot predict them. {modelled}",
                lp.cycles,
                phases.join(", ")
            ));
        }
    }
    let mut header = vec!["step".to_string(), "RMS TRAIN".into()];
    for v in &run.validation {
        header.push(format!("RMS {}", v.name));
        header.push(format!("fit {} %", v.name));
    }
    let row = |name: String, rms: &[f64], fit: &[f64]| {
        let mut row = vec![name, format!("{:.5}", rms[0])];
        for (k, f) in fit.iter().enumerate() {
            row.push(format!(
                "{:.5}",
                rms.get(k + 1).copied().unwrap_or(f64::NAN)
            ));
            row.push(format!("{f:.2}"));
        }
        row
    };
    let mut rows = vec![row(d.base.clone(), &d.initial_rms, &d.initial_fitness)];
    for (k, st) in d.steps.iter().enumerate() {
        rows.push(row(format!("{}. + {}", k + 1, st.id), &st.rms, &st.fitness));
    }
    if let Some(f) = &run.final_model {
        let mut rms = vec![f.train.rms];
        rms.extend(f.validation.iter().map(|m| m.rms));
        let fit: Vec<f64> = f
            .validation
            .iter()
            .map(|m| m.fitness.unwrap_or(f64::NAN))
            .collect();
        rows.push(row("refined (nonlinear refit)".into(), &rms, &fit));
    }
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    r.table(&h, rows);
    if d.steps.is_empty() {
        r.paragraph("No effect was added: the best classical model explains the logs.");
    }
    if !d.dropped.is_empty() {
        r.paragraph(format!(
            "Taken out again after the refit of the model's structure (every coefficient below \
             3σ: the selection added them for the unrefined model): {}.",
            d.dropped
                .iter()
                .map(|id| format!("`{id}`"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    for (k, st) in d.steps.iter().enumerate() {
        r.heading(3, format!("{}. {} (`{}`)", k + 1, st.label, st.id));
        let e = &st.evaluation;
        let mut items = vec![
            format!(
                "F = {:.1}, p = {:.1e}, ΔBIC = {:.1}, RSS −{:.2} % on TRAIN",
                e.f, e.p_value, e.delta_bic, e.rss_drop_percent
            ),
            format!(
                "fitness gain per validation log: {}",
                e.gain_per_set
                    .iter()
                    .map(|g| format!("{g:+.2}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ];
        for v in &st.values {
            items.push(format!(
                "{} = {} {}{}",
                v.name,
                v.value,
                v.unit,
                v.sigma.map_or(String::new(), |s| format!(" (σ {s:.2e})"))
            ));
        }
        if !st.aliases.is_empty() {
            items.push(format!("indistinguishable from: {}", st.aliases.join(", ")));
        }
        r.list(items);
    }
}
