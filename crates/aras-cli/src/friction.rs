//! `aras friction`: the friction of one joint of any robot from its log —
//! the classical and dynamic models of `aras-friction` fitted on TRAIN and
//! scored on every validation log, then the diagnosis of what the best model
//! still misses. This module holds the analysis (no files); `cmd::friction`
//! reads the logs and writes `friction.json`, `report.html` and the
//! predictions.

use anyhow::{Context, Result, bail};
use aras_friction::{
    CoulombViscous, Dahl, FrictionModel, JointLog, LuGre, Separable, Stribeck, Track,
    effects::{Effect, EffectValue, LibrarySettings, Profile, library, residual_profiles},
    fit::{
        Estimate, FitSettings, FitStatus, Fitted, Metrics, Problem, estimates_with_extra,
        fit_coulomb_viscous, fit_dahl, fit_lugre, fit_stribeck, lugre_starts, metrics,
    },
    models::combine,
};
use aras_ident::selection::{
    Accumulator, CandidateEvaluation, CandidateSpec, Layout, SelectionOptions, SelectionStatus,
    select,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Format tag of `friction.json`.
pub const FORMAT: &str = "aras-friction/1";

/// Settings of a friction run (defaults in one place).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FrictionSettings {
    /// Model fitting.
    pub fit: FitSettings,
    /// The candidate effects of the diagnosis.
    pub library: LibrarySettings,
    /// Significance level of a diagnosis round (Bonferroni over its
    /// candidates).
    pub alpha: f64,
    /// Smallest fitness gain (points of (78)) an effect must bring on every
    /// validation log.
    pub min_gain: f64,
    /// At most this many effects are added.
    pub max_steps: usize,
}

impl Default for FrictionSettings {
    fn default() -> Self {
        let s = SelectionOptions::default();
        Self {
            fit: FitSettings::default(),
            library: LibrarySettings::default(),
            alpha: s.alpha,
            min_gain: s.min_gain,
            max_steps: s.max_steps,
        }
    }
}

/// Facts about one log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LogInfo {
    /// Name (file stem).
    pub name: String,
    /// Samples.
    pub rows: usize,
    /// Duration, s.
    pub duration: f64,
    /// Smallest and largest time step, s.
    pub steps: [f64; 2],
    /// True when the velocity was computed from the position.
    pub dq_from_q: bool,
}

impl LogInfo {
    fn of(log: &JointLog) -> Self {
        let (lo, hi) = log
            .t
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold((f64::INFINITY, 0.0f64), |(a, b), d| (a.min(d), b.max(d)));
        Self {
            name: log.name.clone(),
            rows: log.len(),
            duration: log.t.last().copied().unwrap_or(0.0) - log.t.first().copied().unwrap_or(0.0),
            steps: [if lo.is_finite() { lo } else { 0.0 }, hi],
            dq_from_q: log.dq_from_q,
        }
    }
}

/// One model's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelResult {
    /// Model name.
    pub name: String,
    /// The fitted parameters with σ.
    pub parameters: Vec<Estimate>,
    /// Metrics on TRAIN.
    pub train: Metrics,
    /// Metrics on each validation log, in order.
    pub validation: Vec<Metrics>,
    /// Iterations of the winning local search.
    pub iterations: usize,
    /// Cost evaluations.
    pub evaluations: usize,
    /// How the search ended.
    pub status: FitStatus,
}

/// A fitted model of any kind.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum AnyModel {
    /// Offset + Coulomb + viscous.
    CoulombViscous(CoulombViscous),
    /// Stribeck.
    Stribeck(Stribeck),
    /// Dahl.
    Dahl(Dahl),
    /// LuGre.
    Lugre(LuGre),
}

impl AnyModel {
    /// Prediction along a log.
    pub fn predict(&self, log: &JointLog) -> Result<Vec<f64>> {
        let m = Track::new(&log.t, &log.q, &log.dq)?;
        Ok(match self {
            AnyModel::CoulombViscous(x) => x.predict(&m),
            AnyModel::Stribeck(x) => x.predict(&m),
            AnyModel::Dahl(x) => x.predict(&m),
            AnyModel::Lugre(x) => x.predict(&m),
        })
    }

    /// Steady-state friction at constant velocity `v` (for LuGre the
    /// Stribeck curve, for Dahl `±F_c` plus viscous and offset).
    pub fn steady_state(&self, v: f64) -> f64 {
        use aras_friction::sgn;
        match self {
            AnyModel::CoulombViscous(x) => x.offset + x.coulomb * sgn(v) + x.viscous * v,
            AnyModel::Stribeck(x) => x.at(v),
            AnyModel::Dahl(x) => x.offset + x.coulomb * sgn(v) + x.viscous * v,
            AnyModel::Lugre(x) => x.steady_state().at(v),
        }
    }

    /// Model name.
    pub fn name(&self) -> &'static str {
        match self {
            AnyModel::CoulombViscous(x) => x.name(),
            AnyModel::Stribeck(x) => x.name(),
            AnyModel::Dahl(x) => x.name(),
            AnyModel::Lugre(x) => x.name(),
        }
    }
}

/// Everything a run found; serialised as `friction.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrictionRun {
    /// Always [`FORMAT`].
    pub format: String,
    /// The settings used.
    pub settings: FrictionSettings,
    /// The training log.
    pub train: LogInfo,
    /// The validation logs.
    pub validation: Vec<LogInfo>,
    /// The four classical models, in order: coulomb_viscous, stribeck, dahl,
    /// lugre.
    pub models: Vec<ModelResult>,
    /// The fitted models themselves (same order).
    pub fitted: Vec<AnyModel>,
    /// Index of the best classical model: lowest mean validation RMS, or
    /// lowest TRAIN RMS without validation logs.
    pub best: usize,
    /// The best model's TRAIN residual against velocity, position, time,
    /// acceleration and direction.
    pub residual: Vec<Profile>,
    /// The diagnosis (needs at least one validation log).
    pub diagnosis: Option<DiagnosisResult>,
    /// Why there is no diagnosis, when there is none.
    pub diagnosis_note: Option<String>,
    /// The final model (best classical model plus the effects the diagnosis
    /// added, refitted), when it differs from the best classical model.
    pub final_model: Option<ModelResult>,
    /// The final model's base friction model.
    pub final_base: AnyModel,
    /// Effects of the final model with their coefficients.
    pub final_effects: Vec<(Effect, Vec<f64>)>,
}

impl FrictionRun {
    /// The final model's prediction on a log: base model plus effects.
    pub fn final_prediction(&self, log: &JointLog) -> Result<Vec<f64>> {
        predict_with_effects(&self.final_base, &self.final_effects, log)
    }

    /// One paragraph: the best classical model and what the diagnosis found.
    pub fn conclusion(&self) -> String {
        let best = &self.models[self.best];
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
        if self.diagnosis.is_none() {
            s.push(' ');
            s.push_str(
                self.diagnosis_note
                    .as_deref()
                    .unwrap_or("No diagnosis was run."),
            );
        } else if self.final_effects.is_empty() {
            s.push_str(" No further effect was added.");
        } else {
            let names: Vec<String> = self.final_effects.iter().map(|(e, _)| e.label()).collect();
            s.push_str(&format!(" Added: {}.", names.join("; ")));
        }
        s
    }
}

/// One effect the diagnosis added.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnosisStep {
    /// The effect.
    pub effect: Effect,
    /// Its identifier.
    pub id: String,
    /// What it means.
    pub label: String,
    /// Its physical values in the linear fit of this step (before the
    /// nonlinear refinement).
    pub values: Vec<EffectValue>,
    /// The evidence: F-test on TRAIN, gains on every validation log.
    pub evaluation: CandidateEvaluation,
    /// Candidates of other families that explain TRAIN equally well.
    pub aliases: Vec<String>,
    /// RMS on TRAIN and on each validation log after this step, N·m.
    pub rms: Vec<f64>,
    /// Fitness (78) on each validation log after this step, %.
    pub fitness: Vec<f64>,
}

/// What the diagnosis tried and found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnosisResult {
    /// The model whose residual is diagnosed.
    pub base: String,
    /// Candidate effects tried.
    pub candidates: Vec<String>,
    /// Effective fraction of independent TRAIN samples used by the F-test
    /// (`1/τ`, `τ` the integrated autocorrelation time of the base residual).
    pub effective_fraction: f64,
    /// RMS on TRAIN and each validation log before any effect, N·m.
    pub initial_rms: Vec<f64>,
    /// Fitness (78) on each validation log before any effect, %.
    pub initial_fitness: Vec<f64>,
    /// The effects added, in order.
    pub steps: Vec<DiagnosisStep>,
    /// Every round's candidate evaluations.
    pub rounds: Vec<Vec<CandidateEvaluation>>,
    /// Why the selection stopped.
    pub status: SelectionStatus,
}

/// The diagnosis part of the report: the gap shrinking step by step.
pub fn report_diagnosis(run: &FrictionRun, r: &mut crate::report::Report) {
    r.heading(2, "Diagnosis");
    let Some(d) = &run.diagnosis else {
        r.paragraph(
            run.diagnosis_note
                .clone()
                .unwrap_or_else(|| "No diagnosis.".into()),
        );
        return;
    };
    r.paragraph(format!(
        "The residual of `{}` is tested against {} candidate effects. An effect is added when \
         its F-test on TRAIN is significant (α = {} over the round's candidates, N_eff = {:.0} % \
         of the rows) and it raises the fitness (78) by at least {} points on every validation \
         log; the refined model then refits the friction model's nonlinear parameters with the \
         added effects.",
        d.base,
        d.candidates.len(),
        run.settings.alpha,
        100.0 * d.effective_fraction,
        run.settings.min_gain
    ));
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

/// The refined final model: its result, base model and effects with
/// coefficients.
type Refined = (ModelResult, AnyModel, Vec<(Effect, Vec<f64>)>);

/// Prediction of a base model plus effects with their coefficients on one
/// log (the effects' columns may depend on the base prediction).
fn predict_with_effects(
    base: &AnyModel,
    effects: &[(Effect, Vec<f64>)],
    log: &JointLog,
) -> Result<Vec<f64>> {
    let base = base.predict(log)?;
    let mut out = base.clone();
    for (e, coef) in effects {
        for (c, b) in e.columns(log, &base)?.iter().zip(coef) {
            for (o, x) in out.iter_mut().zip(c) {
                *o += b * x;
            }
        }
    }
    Ok(out)
}

/// Columns of a separable model at its fitted structure, on one log.
fn base_columns<M: Separable>(m: &M, log: &JointLog) -> Result<Vec<Vec<f64>>> {
    let motion = Track::new(&log.t, &log.q, &log.dq)?;
    Ok(M::columns(&m.structure(), &motion))
}

/// Rows per chunk pushed into the selection sums (bounded memory).
const CHUNK: usize = 4096;

fn accumulate(
    layout: &Layout,
    base: &[Vec<f64>],
    cands: &[Vec<Vec<f64>>],
    y: &[f64],
) -> Result<Accumulator> {
    let mut acc = Accumulator::new(layout);
    let w = layout.width();
    let n = y.len();
    let mut rows = Vec::with_capacity(CHUNK * w);
    let mut start = 0;
    while start < n {
        let end = (start + CHUNK).min(n);
        rows.clear();
        for i in start..end {
            rows.extend(base.iter().map(|c| c[i]));
            for block in cands {
                rows.extend(block.iter().map(|c| c[i]));
            }
            rows.push(y[i]);
        }
        acc.push_rows(0, &rows)?;
        start = end;
    }
    Ok(acc)
}

fn rms_of(y: &[f64], p: &[f64]) -> f64 {
    metrics(y, p).rms
}

/// The diagnosis of a separable base model `m` (the best classical one):
/// forward selection of effects with the engine of `aras_ident::selection`,
/// then the nonlinear refinement of `m` with the selected effects. Returns
/// the diagnosis, the refined model's result, the refined base and effects.
fn diagnose_with<M: Separable + Sync + Clone + Into<AnyModel>>(
    m: &M,
    train: &JointLog,
    vals: &[JointLog],
    settings: &FrictionSettings,
) -> Result<(DiagnosisResult, Option<Refined>)> {
    let effects = library(train, &settings.library);
    let logs: Vec<&JointLog> = std::iter::once(train).chain(vals).collect();
    let motions: Vec<Track> = logs
        .iter()
        .map(|l| Track::new(&l.t, &l.q, &l.dq))
        .collect::<Result<_, _>>()?;
    // Every log's prediction, base columns and candidate columns are
    // independent: computed in parallel (the state models integrate a
    // whole log per column), collected in order.
    let bases: Vec<Vec<Vec<f64>>> = logs
        .par_iter()
        .map(|l| base_columns(m, l))
        .collect::<Result<_>>()?;
    // The base model's prediction is its columns times its coefficients:
    // no second integration of the state.
    let coefficients = m.coefficients();
    let preds: Vec<Vec<f64>> = bases
        .iter()
        .map(|cols| combine(cols, &coefficients))
        .collect();
    let cand_cols: Vec<Vec<Vec<Vec<f64>>>> = logs
        .iter()
        .zip(&preds)
        .map(|(l, p)| {
            effects
                .par_iter()
                .map(|e| e.columns(l, p))
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()?;
    let specs: Vec<CandidateSpec> = effects
        .iter()
        .map(|e| CandidateSpec::columns(e.id(), e.width()).in_family(e.family()))
        .collect();
    let nb = bases[0].len();
    let layout = Layout::new(nb, specs, 1)?;
    let sets: Vec<Accumulator> = logs
        .iter()
        .enumerate()
        .map(|(k, l)| accumulate(&layout, &bases[k], &cand_cols[k], &l.tau))
        .collect::<Result<_>>()?;
    let resid: Vec<f64> = train
        .tau
        .iter()
        .zip(&preds[0])
        .map(|(a, b)| a - b)
        .collect();
    let tau_int = aras_ident::stats::integrated_time(&resid, 1000).max(1.0);
    let opts = SelectionOptions {
        alpha: settings.alpha,
        min_gain: settings.min_gain,
        max_steps: settings.max_steps,
        effective_fraction: (1.0 / tau_int).clamp(1e-6, 1.0),
        ..SelectionOptions::default()
    };
    let sel = select(&sets[0], &sets[1..], &opts)?;
    // RMS per log of a linear fit (columns and estimates of the engine).
    let rms_for = |fit: &aras_ident::selection::ModelFit| -> Vec<f64> {
        logs.iter()
            .enumerate()
            .map(|(k, l)| {
                let mut p = vec![0.0; l.len()];
                for (&c, &b) in fit.columns.iter().zip(&fit.estimate) {
                    let col = column(c, nb, &layout, &bases[k], &cand_cols[k]);
                    for (o, x) in p.iter_mut().zip(col) {
                        *o += b * x;
                    }
                }
                rms_of(&l.tau, &p)
            })
            .collect()
    };
    let coefs_of =
        |fit: &aras_ident::selection::ModelFit, k: usize| -> (Vec<f64>, Vec<Option<f64>>) {
            layout
                .candidate_columns(k)
                .map(|c| match fit.columns.iter().position(|&x| x == c) {
                    Some(i) => (fit.estimate[i], Some(fit.std_dev[i]).filter(|s| *s > 0.0)),
                    None => (0.0, None),
                })
                .unzip()
        };
    let mean_fit = |fit: &aras_ident::selection::ModelFit| -> Vec<f64> {
        fit.fitness.iter().map(|f| f[0]).collect()
    };
    let steps: Vec<DiagnosisStep> = sel
        .steps
        .iter()
        .map(|st| {
            let e = effects[st.candidate];
            let (c, sg) = coefs_of(&st.fit, st.candidate);
            DiagnosisStep {
                effect: e,
                id: e.id(),
                label: e.label(),
                values: e.values(&c, &sg),
                evaluation: st.evaluation.clone(),
                aliases: st.aliases.clone(),
                rms: rms_for(&st.fit),
                fitness: mean_fit(&st.fit),
            }
        })
        .collect();
    let diagnosis = DiagnosisResult {
        base: m.name().to_string(),
        candidates: effects.iter().map(Effect::id).collect(),
        effective_fraction: opts.effective_fraction,
        initial_rms: rms_for(&sel.initial),
        initial_fitness: mean_fit(&sel.initial),
        steps,
        rounds: sel.rounds.clone(),
        status: sel.status,
    };
    if diagnosis.steps.is_empty() {
        return Ok((diagnosis, None));
    }
    // Nonlinear refinement: refit the base model's structure with the
    // selected effects' columns as extra free columns.
    let added: Vec<Effect> = diagnosis.steps.iter().map(|s| s.effect).collect();
    let extra: Vec<Vec<f64>> = added
        .iter()
        .map(|e| e.columns(train, &preds[0]))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
        .collect();
    let theta0 = m.structure();
    let bounds: Vec<(f64, f64)> = if M::structure_info().len() == 4 {
        // LuGre: the same search box as its own fit.
        let st = match m.clone().into() {
            AnyModel::Lugre(l) => l.steady_state(),
            _ => bail!("internal: a four-parameter structure is LuGre's"),
        };
        lugre_starts(&motions[0], &st, &settings.fit).0
    } else {
        M::structure_info()
            .iter()
            .map(|i| (i.lower, i.upper))
            .collect()
    };
    let prob = Problem::<M>::new(motions[0], &train.tau, &extra, &bounds)?;
    // One start, the base model's own fitted structure, already near the
    // optimum: a local search on every row, no coarse search first.
    let fit = prob.solve(
        &[theta0],
        &FitSettings {
            starts: 1,
            coarse_rows: 0,
            ..settings.fit.clone()
        },
    )?;
    let nc = M::coefficient_info().len();
    let refined = M::from_parts(&fit.theta, &fit.beta[..nc]);
    let extra_beta = fit.beta[nc..].to_vec();
    let fixed: Vec<bool> = refined
        .parameter_info()
        .iter()
        .map(|i| settings.fit.shape.is_some() && i.name == "delta")
        .collect();
    let (mut estimates, extra_sigma) =
        estimates_with_extra(&refined, &extra, &extra_beta, &motions[0], fit.rss, &fixed);
    let mut effects_out = Vec::new();
    let mut k = 0;
    for e in &added {
        let w = e.width();
        let c = extra_beta[k..k + w].to_vec();
        for (j, v) in e.values(&c, &extra_sigma[k..k + w]).into_iter().enumerate() {
            let _ = j;
            estimates.push(Estimate {
                name: format!("{}.{}", e.id(), v.name),
                unit: v.unit,
                value: v.value,
                sigma: v.sigma,
                at_bound: false,
                fixed: false,
            });
        }
        effects_out.push((*e, c));
        k += w;
    }
    let base_any: AnyModel = refined.clone().into();
    let run_pred = |l: &JointLog| predict_with_effects(&base_any, &effects_out, l);
    // Every log's prediction integrates the refined state: in parallel.
    let mut scored = logs
        .par_iter()
        .map(|l| Ok(metrics(&l.tau, &run_pred(l)?)))
        .collect::<Result<Vec<_>>>()?;
    let validation = scored.split_off(1);
    let train_m = scored[0];
    let name = std::iter::once(m.name().to_string())
        .chain(added.iter().map(Effect::id))
        .collect::<Vec<_>>()
        .join(" + ");
    let result = ModelResult {
        name,
        parameters: estimates,
        train: train_m,
        validation,
        iterations: fit.iterations,
        evaluations: fit.evaluations,
        status: fit.status,
    };
    Ok((diagnosis, Some((result, base_any, effects_out))))
}

/// Column `c` of the selection layout on one log.
fn column<'a>(
    c: usize,
    nb: usize,
    layout: &Layout,
    base: &'a [Vec<f64>],
    cands: &'a [Vec<Vec<f64>>],
) -> &'a [f64] {
    if c < nb {
        return &base[c];
    }
    for (k, block) in cands.iter().enumerate() {
        let r = layout.candidate_columns(k);
        if r.contains(&c) {
            return &block[c - r.start];
        }
    }
    &base[0]
}

impl From<CoulombViscous> for AnyModel {
    fn from(m: CoulombViscous) -> Self {
        AnyModel::CoulombViscous(m)
    }
}
impl From<Stribeck> for AnyModel {
    fn from(m: Stribeck) -> Self {
        AnyModel::Stribeck(m)
    }
}
impl From<Dahl> for AnyModel {
    fn from(m: Dahl) -> Self {
        AnyModel::Dahl(m)
    }
}
impl From<LuGre> for AnyModel {
    fn from(m: LuGre) -> Self {
        AnyModel::Lugre(m)
    }
}

fn result<M: Separable + Sync>(f: &Fitted<M>, vals: &[JointLog]) -> Result<ModelResult> {
    let validation = vals
        .par_iter()
        .map(|v| {
            let m = Track::new(&v.t, &v.q, &v.dq)?;
            Ok(metrics(&v.tau, &f.model.predict(&m)))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(ModelResult {
        name: f.model.name().to_string(),
        parameters: f.estimates.clone(),
        train: f.train,
        validation,
        iterations: f.iterations,
        evaluations: f.evaluations,
        status: f.status,
    })
}

/// Fits the four classical models on `train` and scores them on `vals`.
pub fn analyse(
    train: &JointLog,
    vals: &[JointLog],
    settings: &FrictionSettings,
) -> Result<FrictionRun> {
    let m =
        Track::new(&train.t, &train.q, &train.dq).with_context(|| format!("log {}", train.name))?;
    let fs = &settings.fit;
    let tau = &train.tau;
    let ((cv, st), dahl) = rayon::join(
        || (fit_coulomb_viscous(&m, tau, fs), fit_stribeck(&m, tau, fs)),
        || fit_dahl(&m, tau, fs),
    );
    let (cv, st, dahl) = (
        cv.context("fitting offset + Coulomb + viscous")?,
        st.context("fitting Stribeck")?,
        dahl.context("fitting Dahl")?,
    );
    let lugre = fit_lugre(&m, tau, &st.model, fs).context("fitting LuGre")?;
    let models = vec![
        result(&cv, vals)?,
        result(&st, vals)?,
        result(&dahl, vals)?,
        result(&lugre, vals)?,
    ];
    let fitted = vec![
        AnyModel::CoulombViscous(cv.model),
        AnyModel::Stribeck(st.model),
        AnyModel::Dahl(dahl.model),
        AnyModel::Lugre(lugre.model),
    ];
    let score = |r: &ModelResult| {
        if r.validation.is_empty() {
            r.train.rms
        } else {
            r.validation.iter().map(|m| m.rms).sum::<f64>() / r.validation.len() as f64
        }
    };
    let best = (0..models.len())
        .min_by(|&a, &b| score(&models[a]).total_cmp(&score(&models[b])))
        .unwrap_or(0);
    let pred = fitted[best].predict(train)?;
    let resid: Vec<f64> = tau.iter().zip(&pred).map(|(a, b)| a - b).collect();
    let (diagnosis, diagnosis_note, refined) = if vals.is_empty() {
        (
            None,
            Some(
                "No diagnosis: give at least one validation log (--validate); an effect is \
                 only added when it helps every validation log."
                    .to_string(),
            ),
            None,
        )
    } else {
        let (d, r) = match &fitted[best] {
            AnyModel::CoulombViscous(x) => diagnose_with(x, train, vals, settings)?,
            AnyModel::Stribeck(x) => diagnose_with(x, train, vals, settings)?,
            AnyModel::Dahl(x) => diagnose_with(x, train, vals, settings)?,
            AnyModel::Lugre(x) => diagnose_with(x, train, vals, settings)?,
        };
        (Some(d), None, r)
    };
    let (final_model, final_base, final_effects) = match refined {
        Some((r, b, e)) => (Some(r), b, e),
        None => (None, fitted[best].clone(), Vec::new()),
    };
    Ok(FrictionRun {
        format: FORMAT.into(),
        settings: settings.clone(),
        train: LogInfo::of(train),
        validation: vals.iter().map(LogInfo::of).collect(),
        models,
        fitted: fitted.clone(),
        best,
        residual: residual_profiles(train, &resid, 12),
        diagnosis,
        diagnosis_note,
        final_model,
        final_base,
        final_effects,
    })
}
