//! The diagnosis of the best classical model: which candidate effects its
//! TRAIN residual still holds (forward selection by
//! [`aras_ident::selection`]), then the nonlinear refit of the model with
//! the effects found.
//!
//! Stages: [`LogColumns`] (every log's model and candidate columns), the
//! selection on their sums, the summary of every step, the refinement.

use aras_ident::selection::{
    Accumulator, CandidateEvaluation, CandidateSpec, Layout, ModelFit, Selection, SelectionOptions,
    SelectionStatus, select,
};
use rayon::prelude::*;
use serde::Serialize;

use super::{AnalysisError, AnyModel, FrictionSettings, ModelResult};
use crate::{
    FrictionError, JointLog, Separable, Track,
    effects::{Effect, EffectValue, library},
    fit::{Estimate, FitSettings, Problem, estimates_with_extra, lugre_starts, metrics},
    models::combine,
};

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

/// The refined final model: its result, base model and effects with
/// coefficients.
pub(super) struct Refined {
    pub(super) result: ModelResult,
    pub(super) base: AnyModel,
    pub(super) effects: Vec<(Effect, Vec<f64>)>,
}

/// The diagnosis of `base`, the best classical model fitted on `train`.
pub(super) fn diagnose(
    base: &AnyModel,
    train: &JointLog,
    vals: &[JointLog],
    settings: &FrictionSettings,
) -> Result<(DiagnosisResult, Option<Refined>), AnalysisError> {
    match base {
        AnyModel::CoulombViscous(m) => diagnose_with(m, base, train, vals, settings),
        AnyModel::Stribeck(m) => diagnose_with(m, base, train, vals, settings),
        AnyModel::Dahl(m) => diagnose_with(m, base, train, vals, settings),
        AnyModel::Lugre(m) => diagnose_with(m, base, train, vals, settings),
    }
}

/// Rows per chunk pushed into the selection sums (bounded memory).
const CHUNK: usize = 4096;

/// Every log's columns: the model's own, its prediction (their combination
/// with its coefficients) and every candidate effect's block.
struct LogColumns {
    base: Vec<Vec<f64>>,
    prediction: Vec<f64>,
    candidates: Vec<Vec<Vec<f64>>>,
}

impl LogColumns {
    /// The columns of `m` and of `effects` on every log. The logs, and the
    /// effects on one log, are independent: computed in parallel (the
    /// state models integrate a whole log per column), collected in order.
    fn of_all<M: Separable + Sync>(
        m: &M,
        logs: &[&JointLog],
        effects: &[Effect],
    ) -> Result<Vec<Self>, FrictionError> {
        let coefficients = m.coefficients();
        logs.par_iter()
            .map(|l| {
                let base = M::columns(&m.structure(), &l.motion()?);
                // The prediction is the columns times the coefficients: no
                // second integration of the state.
                Ok((base, l))
            })
            .collect::<Result<Vec<_>, FrictionError>>()?
            .into_iter()
            .map(|(base, l)| {
                let prediction = combine(&base, &coefficients);
                let candidates = effects
                    .par_iter()
                    .map(|e| e.columns(l, &prediction))
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(Self {
                    base,
                    prediction,
                    candidates,
                })
            })
            .collect()
    }

    /// The columns in the selection layout's row order (model columns,
    /// then every candidate's block), checked against `layout`.
    fn in_layout(&self, layout: &Layout) -> Result<Vec<&[f64]>, AnalysisError> {
        let cols: Vec<&[f64]> = self
            .base
            .iter()
            .chain(self.candidates.iter().flatten())
            .map(Vec::as_slice)
            .collect();
        if cols.len() != layout.target_column() {
            return Err(AnalysisError::Layout {
                column: cols.len(),
                columns: layout.target_column(),
            });
        }
        Ok(cols)
    }

    /// The selection sums of this log with target `y`.
    fn accumulate(&self, layout: &Layout, y: &[f64]) -> Result<Accumulator, AnalysisError> {
        let cols = self.in_layout(layout)?;
        let mut acc = Accumulator::new(layout);
        let n = y.len();
        let mut rows = Vec::with_capacity(CHUNK * layout.width());
        let mut start = 0;
        while start < n {
            let end = (start + CHUNK).min(n);
            rows.clear();
            for i in start..end {
                rows.extend(cols.iter().map(|c| c[i]));
                rows.push(y[i]);
            }
            acc.push_rows(0, &rows)?;
            start = end;
        }
        Ok(acc)
    }
}

/// The forward selection of effects on the model's columns: TRAIN's sums
/// for the F-test, every validation log's for the gains. The F-test counts
/// `1/τ` of the TRAIN rows as independent, `τ` the integrated
/// autocorrelation time of the model's residual.
fn run_selection(
    layout: &Layout,
    logs: &[&JointLog],
    columns: &[LogColumns],
    settings: &FrictionSettings,
) -> Result<(Selection, f64), AnalysisError> {
    let sets: Vec<Accumulator> = logs
        .iter()
        .zip(columns)
        .map(|(l, c)| c.accumulate(layout, &l.tau))
        .collect::<Result<_, _>>()?;
    let resid: Vec<f64> = logs[0]
        .tau
        .iter()
        .zip(&columns[0].prediction)
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
    Ok((
        select(&sets[0], &sets[1..], &opts)?,
        opts.effective_fraction,
    ))
}

/// Summaries of a selection: RMS per log, fitness per validation log and
/// the effects' values of one linear fit of the engine.
struct Summary<'a> {
    layout: &'a Layout,
    logs: &'a [&'a JointLog],
    columns: Vec<Vec<&'a [f64]>>,
}

impl Summary<'_> {
    /// RMS on every log of a linear fit (the engine's columns and
    /// estimates).
    fn rms(&self, fit: &ModelFit) -> Result<Vec<f64>, AnalysisError> {
        self.logs
            .iter()
            .zip(&self.columns)
            .map(|(l, cols)| {
                let mut p = vec![0.0; l.len()];
                for (&c, &b) in fit.columns.iter().zip(&fit.estimate) {
                    let col = cols.get(c).ok_or(AnalysisError::Layout {
                        column: c,
                        columns: cols.len(),
                    })?;
                    for (o, x) in p.iter_mut().zip(col.iter()) {
                        *o += b * x;
                    }
                }
                Ok(metrics(&l.tau, &p).rms)
            })
            .collect()
    }

    /// Candidate `k`'s coefficients and σ in a fit (0 and none for a
    /// column the fit does not hold).
    fn coefficients(&self, fit: &ModelFit, k: usize) -> (Vec<f64>, Vec<Option<f64>>) {
        self.layout
            .candidate_columns(k)
            .map(|c| match fit.columns.iter().position(|&x| x == c) {
                Some(i) => (fit.estimate[i], Some(fit.std_dev[i]).filter(|s| *s > 0.0)),
                None => (0.0, None),
            })
            .unzip()
    }
}

/// Fitness (78) on each validation log of a fit (the engine's, of its one
/// output group).
fn validation_fitness(fit: &ModelFit) -> Vec<f64> {
    fit.fitness.iter().map(|f| f[0]).collect()
}

/// The diagnosis of a separable base model `m` (`base` is the same model):
/// columns, selection, summary, and the refinement when an effect was
/// added.
fn diagnose_with<M: Separable + Sync + Clone + Into<AnyModel>>(
    m: &M,
    base: &AnyModel,
    train: &JointLog,
    vals: &[JointLog],
    settings: &FrictionSettings,
) -> Result<(DiagnosisResult, Option<Refined>), AnalysisError> {
    let effects = library(train, &settings.library);
    let logs: Vec<&JointLog> = std::iter::once(train).chain(vals).collect();
    let columns = LogColumns::of_all(m, &logs, &effects)?;
    let specs: Vec<CandidateSpec> = effects
        .iter()
        .map(|e| CandidateSpec::columns(e.id(), e.width()).in_family(e.family()))
        .collect();
    let layout = Layout::new(columns[0].base.len(), specs, 1)?;
    let (sel, effective_fraction) = run_selection(&layout, &logs, &columns, settings)?;
    let summary = Summary {
        layout: &layout,
        logs: &logs,
        columns: columns
            .iter()
            .map(|c| c.in_layout(&layout))
            .collect::<Result<_, _>>()?,
    };
    let steps = sel
        .steps
        .iter()
        .map(|st| {
            let e = effects[st.candidate];
            let (c, sg) = summary.coefficients(&st.fit, st.candidate);
            Ok(DiagnosisStep {
                effect: e,
                id: e.id(),
                label: e.label(),
                values: e.values(&c, &sg),
                evaluation: st.evaluation.clone(),
                aliases: st.aliases.clone(),
                rms: summary.rms(&st.fit)?,
                fitness: validation_fitness(&st.fit),
            })
        })
        .collect::<Result<Vec<_>, AnalysisError>>()?;
    let diagnosis = DiagnosisResult {
        base: m.name().to_string(),
        candidates: effects.iter().map(Effect::id).collect(),
        effective_fraction,
        initial_rms: summary.rms(&sel.initial)?,
        initial_fitness: validation_fitness(&sel.initial),
        steps,
        rounds: sel.rounds,
        status: sel.status,
    };
    if diagnosis.steps.is_empty() {
        return Ok((diagnosis, None));
    }
    let added: Vec<Effect> = diagnosis.steps.iter().map(|s| s.effect).collect();
    let refined = refine(m, base, &logs, &columns[0].prediction, &added, settings)?;
    Ok((diagnosis, Some(refined)))
}

/// The search box of the refit of `base`'s structure: LuGre's own fit box
/// around its steady state; for the others their parameters' physical
/// ranges, with a held Stribeck shape `δ` ([`FitSettings::shape`]) held
/// here too.
fn refinement_box(base: &AnyModel, motion: &Track, fit: &FitSettings) -> Vec<(f64, f64)> {
    match base {
        AnyModel::Lugre(l) => lugre_starts(motion, &l.steady_state(), fit).0,
        other => other
            .kind()
            .structure_info()
            .iter()
            .map(|i| match fit.shape {
                Some(d) if i.name == "delta" => (d, d),
                _ => (i.lower, i.upper),
            })
            .collect(),
    }
}

/// Nonlinear refinement: refits the structure of `m` on TRAIN with the
/// added effects' columns as extra free columns, from `m`'s own structure,
/// and scores the refined model on every log.
fn refine<M: Separable + Sync + Clone + Into<AnyModel>>(
    m: &M,
    base: &AnyModel,
    logs: &[&JointLog],
    train_prediction: &[f64],
    added: &[Effect],
    settings: &FrictionSettings,
) -> Result<Refined, AnalysisError> {
    let train = logs[0];
    let motion = train.motion()?;
    let extra: Vec<Vec<f64>> = added
        .iter()
        .map(|e| e.columns(train, train_prediction))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
        .collect();
    let bounds = refinement_box(base, &motion, &settings.fit);
    let prob = Problem::<M>::new(motion, &train.tau, &extra, &bounds)?;
    // One start, the base model's own fitted structure, already near the
    // optimum: a local search on every row, no coarse search first.
    let fit = prob.solve(
        &[m.structure()],
        &FitSettings {
            starts: 1,
            coarse_rows: 0,
            ..settings.fit.clone()
        },
    )?;
    let nc = M::coefficient_info().len();
    let refined = M::from_parts(&fit.theta, &fit.beta[..nc]);
    let extra_beta = &fit.beta[nc..];
    let fixed: Vec<bool> = refined
        .parameter_info()
        .iter()
        .map(|i| settings.fit.shape.is_some() && i.name == "delta")
        .collect();
    let (mut estimates, extra_sigma) =
        estimates_with_extra(&refined, &extra, extra_beta, &motion, fit.rss, &fixed);
    let mut effects = Vec::with_capacity(added.len());
    let mut k = 0;
    for e in added {
        let w = e.width();
        let c = extra_beta[k..k + w].to_vec();
        for v in e.values(&c, &extra_sigma[k..k + w]) {
            estimates.push(Estimate {
                name: format!("{}.{}", e.id(), v.name),
                unit: v.unit,
                value: v.value,
                sigma: v.sigma,
                at_bound: false,
                fixed: false,
            });
        }
        effects.push((*e, c));
        k += w;
    }
    let base_out: AnyModel = refined.into();
    // Every log's prediction integrates the refined state: in parallel.
    let mut scored = logs
        .par_iter()
        .map(|l| {
            Ok(metrics(
                &l.tau,
                &super::predict_with_effects(&base_out, &effects, l)?,
            ))
        })
        .collect::<Result<Vec<_>, FrictionError>>()?;
    let validation = scored.split_off(1);
    let name = std::iter::once(m.name().to_string())
        .chain(added.iter().map(Effect::id))
        .collect::<Vec<_>>()
        .join(" + ");
    Ok(Refined {
        result: ModelResult {
            name,
            parameters: estimates,
            train: scored[0],
            validation,
            iterations: fit.iterations,
            evaluations: fit.evaluations,
            status: fit.status,
        },
        base: base_out,
        effects,
    })
}
