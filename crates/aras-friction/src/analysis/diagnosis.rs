//! The diagnosis of the best classical model: which candidate effects its
//! TRAIN residual still holds (forward selection by
//! [`aras_ident::selection`]), then the nonlinear refit of the model with
//! the effects found.
//!
//! Stages: [`LogColumns`] (every log's model and candidate columns), the
//! selection on their sums, the summary of every step, the refinement.

use aras_ident::selection::{
    Accumulator, CandidateEvaluation, CandidateSpec, Layout, ModelFit, Selection, SelectionOptions,
    SelectionStatus, fit_model, select_with,
};
use rayon::prelude::*;
use serde::Serialize;

use super::{AnalysisError, AnyModel, FinalModel, FrictionSettings, ModelKind, ModelResult};
use crate::{
    FrictionError, JointLog, Separable, Track,
    effects::{Effect, EffectValue, Library, library, presliding_lengths, shift_ripple},
    fit::{
        Estimate, FitSettings, Problem, estimates_with_extra, fit_stribeck, held, lugre_starts,
        maxwell_starts, metrics,
    },
    models::combine,
    spectrum::{LinePhase, PositionSpectrum, line_phase, wrapped},
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
    /// The search for ripple lines in the base residual against position,
    /// where the ripple candidates above the integer harmonics come from.
    pub spectrum: PositionSpectrum,
    /// Each line on every log (TRAIN first): whether the logs share the
    /// position zero its phase is measured from.
    pub phases: Vec<LinePhases>,
    /// Effective fraction of independent TRAIN samples in the base residual
    /// (`1/τ`, `τ` its integrated autocorrelation time). Each candidate's
    /// F-test counts `1/τ` of the residual with that candidate instead
    /// (its evaluation's `n_eff`).
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
    /// Added effects that the refit of the model's structure left below
    /// 3σ (every coefficient): taken out of the final model again.
    pub dropped: Vec<String>,
    /// The models refitted with the effects: the diagnosed base, and LuGre
    /// (the most general classical model) when it was not the base; the
    /// lower mean validation RMS is the final model.
    pub refits: Vec<RefitScore>,
}

/// The refined final model: its result and the model itself.
pub(super) struct Refined {
    pub(super) result: ModelResult,
    /// The refined structure `θ`.
    structure: Vec<f64>,
    pub(super) model: FinalModel,
}

/// The diagnosis of `base`, the best classical model fitted on `train`;
/// `models` are every classical model fitted there (`base` among them).
pub(super) fn diagnose(
    base: &AnyModel,
    models: &[AnyModel],
    train: &JointLog,
    vals: &[JointLog],
    settings: &FrictionSettings,
) -> Result<(DiagnosisResult, Option<Refined>), AnalysisError> {
    let logs = Logs {
        train,
        vals,
        models,
    };
    match base {
        AnyModel::CoulombViscous(m) => diagnose_with(m, base, &logs, settings),
        AnyModel::Stribeck(m) => diagnose_with(m, base, &logs, settings),
        AnyModel::Dahl(m) => diagnose_with(m, base, &logs, settings),
        AnyModel::Lugre(m) => diagnose_with(m, base, &logs, settings),
        AnyModel::MaxwellSlip(m) => diagnose_with(m, base, &logs, settings),
    }
}

/// The logs of a diagnosis and the classical models fitted on TRAIN.
struct Logs<'a> {
    train: &'a JointLog,
    vals: &'a [JointLog],
    models: &'a [AnyModel],
}

/// One spectral line's phase on every log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinePhases {
    /// The line's `k`, cycles per revolution.
    pub cycles: f64,
    /// Its amplitude and phase on each log (TRAIN first), fitted at `k` on
    /// that log's base residual; `None` where the log cannot tell.
    pub per_log: Vec<Option<LinePhase>>,
    /// Whether every log's phase agrees with TRAIN's within 5σ: one phase,
    /// one position zero, serves them all. When not, the logs' encoder
    /// zeros (or the line's phase) differ, and a model with TRAIN's phase
    /// mispredicts the others.
    pub shared: bool,
}

impl LinePhases {
    /// The line at `cycles` on every log, from each log's residual.
    fn of(cycles: f64, logs: &[&JointLog], residuals: &[Vec<f64>]) -> Self {
        let per_log: Vec<Option<LinePhase>> = logs
            .iter()
            .zip(residuals)
            .map(|(l, r)| line_phase(&l.q, r, cycles))
            .collect();
        let shared = match per_log.first() {
            Some(Some(t)) => per_log
                .iter()
                .skip(1)
                .flatten()
                .all(|p| wrapped(p.phase - t.phase).abs() <= 5.0 * t.sigma.hypot(p.sigma)),
            _ => true,
        };
        Self {
            cycles,
            per_log,
            shared,
        }
    }

    /// How far log `l`'s phase is from TRAIN's, rad (0 where either cannot
    /// tell).
    fn shift(&self, l: usize) -> f64 {
        match (self.per_log.first(), self.per_log.get(l)) {
            (Some(Some(t)), Some(Some(p))) => wrapped(p.phase - t.phase),
            _ => 0.0,
        }
    }
}

/// The ripple candidates whose phase each log sets, with log `l`'s shift
/// from TRAIN's for each (`shifts[l]`, TRAIN's empty): every harmonic `n k`
/// of a line `k` the logs do not share, turned by `n` times the line's
/// shift, as a position zero moved by `Δ/k` turns it.
fn per_log_shifts(
    effects: &[Effect],
    phases: &[LinePhases],
    logs: usize,
) -> (Vec<f64>, Vec<Vec<(f64, f64)>>) {
    let mut own = Vec::new();
    let mut shifts = vec![Vec::new(); logs];
    for e in effects {
        let Effect::Ripple { cycles } = *e else {
            continue;
        };
        let line = phases.iter().filter(|p| !p.shared).find_map(|p| {
            let n = (cycles / p.cycles).round();
            (n >= 1.0 && (cycles - n * p.cycles).abs() <= 1e-9 * cycles).then_some((p, n))
        });
        if let Some((p, n)) = line {
            own.push(cycles);
            for (l, s) in shifts.iter_mut().enumerate().skip(1) {
                s.push((cycles, wrapped(n * p.shift(l))));
            }
        }
    }
    (own, shifts)
}

/// One model's refit with the effects found: its validation RMS, N·m.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RefitScore {
    /// The model.
    pub model: String,
    /// RMS on each validation log.
    pub validation_rms: Vec<f64>,
}

/// [`refine`] of any classical model.
fn refine_any(
    model: &AnyModel,
    input: &RefineInput<'_>,
    settings: &FrictionSettings,
) -> Result<(Refined, Vec<f64>), AnalysisError> {
    match model {
        AnyModel::CoulombViscous(m) => refine(m, model, input, settings),
        AnyModel::Stribeck(m) => refine(m, model, input, settings),
        AnyModel::Dahl(m) => refine(m, model, input, settings),
        AnyModel::Lugre(m) => refine(m, model, input, settings),
        AnyModel::MaxwellSlip(m) => refine(m, model, input, settings),
    }
}

fn mean_validation_rms(r: &Refined) -> f64 {
    let v = &r.result.validation;
    v.iter().map(|m| m.rms).sum::<f64>() / v.len().max(1) as f64
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
    /// The columns and prediction of `m` on every log. The logs are
    /// independent: computed in parallel (the state models integrate a
    /// whole log per column), collected in order.
    fn of_model<M: Separable + Sync>(
        m: &M,
        logs: &[&JointLog],
    ) -> Result<Vec<Self>, FrictionError> {
        let coefficients = m.coefficients();
        logs.par_iter()
            .map(|l| {
                let base = M::columns(&m.structure(), &l.track()?);
                // The prediction is the columns times the coefficients: no
                // second integration of the state.
                let prediction = combine(&base, &coefficients);
                Ok(Self {
                    base,
                    prediction,
                    candidates: Vec::new(),
                })
            })
            .collect()
    }

    /// Adds every candidate effect's block on `log` (independent effects:
    /// in parallel), a ripple whose `k` is in `shifts` turned by its shift.
    fn with_effects(
        mut self,
        log: &JointLog,
        effects: &[Effect],
        shifts: &[(f64, f64)],
    ) -> Result<Self, FrictionError> {
        self.candidates = effects
            .par_iter()
            .map(|e| {
                let mut c = e.columns(log, &self.prediction)?;
                if let Effect::Ripple { cycles } = e
                    && let Some(&(_, shift)) = shifts.iter().find(|(k, _)| k == cycles)
                {
                    shift_ripple(&mut c, shift);
                }
                Ok(c)
            })
            .collect::<Result<Vec<_>, FrictionError>>()?;
        Ok(self)
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
/// for the F-test, every validation log's for the gains. The F-test of a
/// candidate counts `1/τ` of the TRAIN rows as independent, `τ` the
/// integrated autocorrelation time of the residual of the model *with* that
/// candidate ([`select_with`]): the base residual is autocorrelated because
/// of what it misses, and its `τ` would starve the candidate that explains
/// it. Also returns the base residual's fraction `1/τ`.
fn run_selection(
    layout: &Layout,
    logs: &[&JointLog],
    columns: &[LogColumns],
    train_residual: &[f64],
    settings: &FrictionSettings,
) -> Result<(Selection, f64), AnalysisError> {
    let sets: Vec<Accumulator> = logs
        .iter()
        .zip(columns)
        .map(|(l, c)| c.accumulate(layout, &l.tau))
        .collect::<Result<_, _>>()?;
    let train = logs[0];
    let cols = columns[0].in_layout(layout)?;
    let base_fraction = 1.0 / integrated_time(train_residual);
    let opts = SelectionOptions {
        alpha: settings.alpha,
        min_gain: settings.min_gain,
        max_steps: settings.max_steps,
        effective_fraction: base_fraction.clamp(1e-6, 1.0),
        ..SelectionOptions::default()
    };
    let effective = |fit: &ModelFit| {
        let mut r = train.tau.clone();
        for (&c, &b) in fit.columns.iter().zip(&fit.estimate) {
            let Some(col) = cols.get(c) else {
                return f64::NAN;
            };
            for (o, x) in r.iter_mut().zip(col.iter()) {
                *o -= b * x;
            }
        }
        1.0 / integrated_time(&r)
    };
    Ok((
        select_with(&sets[0], &sets[1..], &opts, effective)?,
        opts.effective_fraction,
    ))
}

/// The position map's direction length and degree chosen by held-out
/// error. The map of the highest degree is fitted on TRAIN with the
/// model's columns and scored on every validation log, first for each
/// presliding length of a log grid over the stroke (the direction state
/// must follow the joint's own transition at a reversal, or the map's
/// direction factor is wrong on every reversal), then at the best length
/// degree by degree (the series are nested): the lowest degree whose mean
/// validation fitness is within [`FrictionSettings::min_gain`] of the best
/// stays in the library with that length, the others leave it. A map's
/// training error falls with every degree, its error on motions it was not
/// fitted on does not: a fine map memorises the trajectory. Without
/// validation logs every degree stays at the library's length and the
/// selection's ΔBIC decides.
fn choose_map(
    effects: Vec<Effect>,
    logs: &[&JointLog],
    models: &[LogColumns],
    settings: &FrictionSettings,
) -> Result<Vec<Effect>, AnalysisError> {
    let top = effects
        .iter()
        .filter(|e| matches!(e, Effect::PositionMap { .. }))
        .max_by_key(|e| e.width())
        .copied();
    let Some(Effect::PositionMap { order, lo, hi, .. }) = top else {
        return Ok(effects);
    };
    if logs.len() < 2 {
        return Ok(effects);
    }
    let map = |length: f64| Effect::PositionMap {
        order,
        lo,
        hi,
        length,
    };
    // One candidate per degree: the degree's columns of the top map.
    let per_degree = map(0.0).width() / order as usize;
    let specs: Vec<CandidateSpec> = (1..=order)
        .map(|j| CandidateSpec::columns(format!("degree {j}"), per_degree))
        .collect();
    let layout = Layout::new(models[0].base.len(), specs, 1)?;
    let sets = |length: f64| -> Result<Vec<Accumulator>, AnalysisError> {
        logs.iter()
            .zip(models)
            .map(|(l, m)| {
                let columns = LogColumns {
                    base: m.base.clone(),
                    prediction: Vec::new(),
                    candidates: map(length)
                        .columns(l, &m.prediction)?
                        .chunks(per_degree)
                        .map(<[Vec<f64>]>::to_vec)
                        .collect(),
                };
                columns.accumulate(&layout, &l.tau)
            })
            .collect()
    };
    let opts = SelectionOptions::default();
    let score = |sets: &[Accumulator], degree: usize| -> Result<f64, AnalysisError> {
        let degrees: Vec<usize> = (0..degree).collect();
        let fit = fit_model(&sets[0], &sets[1..], &degrees, &opts)?;
        let v = validation_fitness(&fit);
        Ok(v.iter().sum::<f64>() / v.len().max(1) as f64)
    };
    // Each length's sums are kept: the degree search reuses the best's.
    let grid = presliding_lengths(hi - lo, MAP_LENGTHS);
    let mut scored: Vec<(f64, Vec<Accumulator>)> = grid
        .par_iter()
        .map(|&l| {
            let s = sets(l)?;
            Ok((score(&s, order as usize)?, s))
        })
        .collect::<Result<_, AnalysisError>>()?;
    let i = (0..grid.len())
        .max_by(|&a, &b| scored[a].0.total_cmp(&scored[b].0))
        .unwrap_or(0);
    let mut length = grid[i];
    let mut best_sets = None;
    // An interior best is refined by the parabola through it and its
    // neighbours in log length (the grid is uniform there).
    if i > 0 && i + 1 < grid.len() {
        let (a, b, c) = (scored[i - 1].0, scored[i].0, scored[i + 1].0);
        let curvature = a - 2.0 * b + c;
        if curvature < 0.0 {
            let step = 0.5 * (a - c) / curvature;
            let l = grid[i] * (grid[i + 1] / grid[i]).powf(step.clamp(-0.5, 0.5));
            let s = sets(l)?;
            if score(&s, order as usize)? > b {
                length = l;
                best_sets = Some(s);
            }
        }
    }
    let sets = best_sets.unwrap_or_else(|| scored.swap_remove(i).1);
    let scores: Vec<f64> = (1..=order as usize)
        .map(|m| score(&sets, m))
        .collect::<Result<_, AnalysisError>>()?;
    let best = scores.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let chosen = scores
        .iter()
        .position(|&s| s >= best - settings.min_gain)
        .map_or(1, |i| i as u32 + 1);
    Ok(effects
        .into_iter()
        .filter_map(|e| match e {
            Effect::PositionMap { order, lo, hi, .. } if order == chosen => {
                Some(Effect::PositionMap {
                    order,
                    lo,
                    hi,
                    length,
                })
            }
            Effect::PositionMap { .. } => None,
            other => Some(other),
        })
        .collect())
}

/// Presliding lengths searched for the position map's direction state
/// (neighbours under a factor 2 apart on a stroke of 2 rad, closer on a
/// shorter one).
const MAP_LENGTHS: usize = 13;

/// `τ − τ̂`.
fn residual_of(measured: &[f64], predicted: &[f64]) -> Vec<f64> {
    measured.iter().zip(predicted).map(|(a, b)| a - b).collect()
}

/// Most lags of an integrated autocorrelation time (as
/// [`aras_ident::stats::integrated_time`] is used elsewhere in the
/// workspace).
const MAX_LAG: usize = 1000;

/// `τ = 1 + 2 Σ ρ_k` over the initial run of positive `ρ_k` (Geyer's
/// initial positive sequence), at least 1. By FFT blocks
/// ([`aras_signal::Autocorrelation`]): `O(n log MAX_LAG)` whatever the
/// correlation length, so that it can be measured on every candidate's
/// residual.
fn integrated_time(x: &[f64]) -> f64 {
    let mut acf = aras_signal::Autocorrelation::new(MAX_LAG);
    for &v in x {
        acf.push(v);
    }
    aras_ident::stats::integrated_time_of(acf.finish()).max(1.0)
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
    given: &Logs<'_>,
    settings: &FrictionSettings,
) -> Result<(DiagnosisResult, Option<Refined>), AnalysisError> {
    let (train, vals) = (given.train, given.vals);
    let logs: Vec<&JointLog> = std::iter::once(train).chain(vals).collect();
    let models = LogColumns::of_model(m, &logs)?;
    // The base model's residual on every log, TRAIN first.
    let residuals: Vec<Vec<f64>> = logs
        .iter()
        .zip(&models)
        .map(|(l, c)| residual_of(&l.tau, &c.prediction))
        .collect();
    let Library { effects, spectrum } = library(train, &residuals[0], &settings.library);
    let effects = choose_map(effects, &logs, &models, settings)?;
    let phases: Vec<LinePhases> = spectrum
        .lines
        .iter()
        .map(|line| LinePhases::of(line.cycles, &logs, &residuals))
        .collect();
    // A line the logs do not share is fitted with each log's own phase.
    let (per_log, shifts) = per_log_shifts(&effects, &phases, logs.len());
    let columns = models
        .into_iter()
        .zip(&logs)
        .zip(&shifts)
        .map(|((c, l), s)| c.with_effects(l, &effects, s))
        .collect::<Result<Vec<_>, _>>()?;
    let specs: Vec<CandidateSpec> = effects
        .iter()
        .map(|e| CandidateSpec::columns(e.id(), e.width()).in_family(e.family()))
        .collect();
    let layout = Layout::new(columns[0].base.len(), specs, 1)?;
    let (sel, effective_fraction) =
        run_selection(&layout, &logs, &columns, &residuals[0], settings)?;
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
        phases,
        spectrum,
        effective_fraction,
        initial_rms: summary.rms(&sel.initial)?,
        initial_fitness: validation_fitness(&sel.initial),
        steps,
        rounds: sel.rounds,
        status: sel.status,
        dropped: Vec::new(),
        refits: Vec::new(),
    };
    if diagnosis.steps.is_empty() {
        return Ok((diagnosis, None));
    }
    let added: Vec<Effect> = diagnosis.steps.iter().map(|s| s.effect).collect();
    let mut diagnosis = diagnosis;
    // The effects' coefficients in the selection's last linear fit.
    let last = &sel.steps[sel.steps.len() - 1].fit;
    let selected: Vec<f64> = sel
        .steps
        .iter()
        .flat_map(|st| summary.coefficients(last, st.candidate).0)
        .collect();
    let mut input = RefineInput {
        logs: &logs,
        train_prediction: &columns[0].prediction,
        added,
        selected,
        spectrum: &diagnosis.spectrum,
        per_log: &per_log,
        from: None,
    };
    // A strong effect can make another classical model look best before
    // it is modelled (a ripple of two thirds of the Coulomb level hides
    // the Stribeck curve): LuGre, which holds every other classical model
    // as a limit, is refitted with the effects too when it was not the
    // base, and the lower mean validation RMS is the final model.
    let general = given
        .models
        .iter()
        .filter(|o| o.kind() == ModelKind::Lugre && base.kind() != ModelKind::Lugre);
    let mut best: Option<(AnyModel, Refined, Vec<f64>)> = None;
    for model in std::iter::once(base).chain(general) {
        let (r, strength) = refine_any(model, &input, settings)?;
        diagnosis.refits.push(RefitScore {
            model: model.name().into(),
            validation_rms: r.result.validation.iter().map(|v| v.rms).collect(),
        });
        if best
            .as_ref()
            .is_none_or(|(_, b, _)| mean_validation_rms(&r) < mean_validation_rms(b))
        {
            best = Some((model.clone(), r, strength));
        }
    }
    let Some((model, mut refined, strength)) = best else {
        return Ok((diagnosis, None));
    };
    // An effect the selection added for a distorted base (a strong ripple
    // bends the fixed-θ columns, and an inertia or hysteresis column makes
    // up for the bend) is not significant once the structure is refitted:
    // it leaves the model, which is refitted without it from the refined
    // structure.
    let weak: Vec<bool> = strength.iter().map(|&z| z < DROP_Z).collect();
    if weak.iter().any(|&w| w) {
        diagnosis.dropped = input
            .added
            .iter()
            .zip(&weak)
            .filter(|(_, w)| **w)
            .map(|(e, _)| e.id())
            .collect();
        if weak.iter().all(|&w| w) {
            return Ok((diagnosis, None));
        }
        let (mut added, mut selected) = (Vec::new(), Vec::new());
        let mut end = 0;
        for (e, &weak) in input.added.iter().zip(&weak) {
            let span = end..end + e.width();
            end = span.end;
            if !weak {
                added.push(*e);
                selected.extend_from_slice(&input.selected[span]);
            }
        }
        input.added = added;
        input.selected = selected;
        input.from = Some(refined.structure.clone());
        refined = refine_any(&model, &input, settings)?.0;
    }
    Ok((diagnosis, Some(refined)))
}

/// The search box of the refit of `base`'s structure: LuGre's own fit box
/// around its steady state; for the others their parameters' physical
/// ranges, with a held Stribeck shape `δ` ([`FitSettings::shape`]) held
/// here too.
fn refinement_box(base: &AnyModel, motion: &Track, fit: &FitSettings) -> Vec<(f64, f64)> {
    match base {
        AnyModel::Lugre(l) => lugre_starts(motion, &l.steady_state(), fit).0,
        AnyModel::MaxwellSlip(g) => maxwell_starts(motion, &g.steady_state(), fit).0,
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

/// The structure of `base`'s steady state refitted on `tau` (the TRAIN
/// torque with the selected effects removed): Stribeck's own, LuGre's from
/// a Stribeck fit with the base's presliding stiffness kept; none for the
/// models whose structure carries no steady-state shape.
fn cleaned_start(
    base: &AnyModel,
    motion: &Track,
    tau: &[f64],
    fit: &FitSettings,
) -> Result<Option<Vec<f64>>, FrictionError> {
    Ok(match base {
        AnyModel::Stribeck(_) => Some(fit_stribeck(motion, tau, fit)?.model.structure()),
        AnyModel::Lugre(l) => {
            let s = fit_stribeck(motion, tau, fit)?.model;
            (s.coulomb > 0.0).then(|| {
                vec![
                    l.sigma0 / s.coulomb,
                    s.static_friction / s.coulomb,
                    s.stribeck_velocity,
                    s.shape,
                ]
            })
        }
        AnyModel::MaxwellSlip(g) => {
            let s = fit_stribeck(motion, tau, fit)?.model;
            (s.coulomb > 0.0).then(|| {
                vec![
                    g.length,
                    s.static_friction / s.coulomb,
                    s.stribeck_velocity,
                    s.shape,
                ]
            })
        }
        AnyModel::CoulombViscous(_) | AnyModel::Dahl(_) => None,
    })
}

/// An effect stays in the refined model when one of its coefficients is at
/// least this many σ from zero.
const DROP_Z: f64 = 3.0;

/// What a refinement refits: the logs (TRAIN first), the base prediction on
/// TRAIN, the effects with their coefficients in the selection's last
/// linear fit, the spectrum their ripple lines come from, the ripples whose
/// phase each log sets, and a structure to start from instead of the base's
/// own and its cleaned refit.
struct RefineInput<'a> {
    logs: &'a [&'a JointLog],
    train_prediction: &'a [f64],
    added: Vec<Effect>,
    selected: Vec<f64>,
    spectrum: &'a PositionSpectrum,
    per_log: &'a [f64],
    from: Option<Vec<f64>>,
}

/// Nonlinear refinement: refits the structure of `m` on TRAIN with the
/// added effects' columns as extra free columns and scores the refined
/// model on every log. Also returns each effect's strength: its largest
/// `|coefficient| / σ` (infinite without σ).
fn refine<M: Separable + Sync + Clone + Into<AnyModel>>(
    m: &M,
    base: &AnyModel,
    input: &RefineInput<'_>,
    settings: &FrictionSettings,
) -> Result<(Refined, Vec<f64>), AnalysisError> {
    let RefineInput {
        logs,
        train_prediction,
        added,
        selected,
        spectrum,
        per_log,
        from,
    } = input;
    let train = logs[0];
    let motion = train.track()?;
    let extra: Vec<Vec<f64>> = added
        .iter()
        .map(|e| e.columns(train, train_prediction))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
        .collect();
    let bounds = refinement_box(base, &motion, &settings.fit);
    let prob = Problem::<M>::new(motion, &train.tau, &extra, &bounds)?;
    // Two starts: the base model's own fitted structure, and its steady
    // state refitted on TRAIN with the effects (at their selection
    // coefficients) removed. A strong effect distorts the base fit (a
    // ripple of a third of the Coulomb level bends the Stribeck curve), and
    // from there alone the refit can end in a degenerate optimum.
    let mut starts = vec![from.clone().unwrap_or_else(|| m.structure())];
    let cleaned: Vec<f64> = extra
        .iter()
        .zip(selected)
        .fold(train.tau.clone(), |mut y, (c, &b)| {
            for (o, x) in y.iter_mut().zip(c) {
                *o -= b * x;
            }
            y
        });
    if from.is_none()
        && let Some(start) = cleaned_start(base, &motion, &cleaned, &settings.fit)?
    {
        let clamped: Vec<f64> = start
            .iter()
            .zip(&bounds)
            .map(|(&x, &(lo, hi))| x.clamp(lo, hi))
            .collect();
        // A start within 5 % of the first in every component is the same
        // start (the effects did not distort the base): one search.
        let same = clamped
            .iter()
            .zip(&starts[0])
            .all(|(a, b)| (a - b).abs() <= 0.05 * a.abs().max(b.abs()));
        if !same {
            starts.push(clamped);
        }
    }
    let fit = prob.solve(
        &starts,
        &FitSettings {
            starts: starts.len(),
            // One start: a local search on every row. Two: each searched
            // on the coarse subsample first, the better refined on all.
            coarse_rows: if starts.len() > 1 {
                settings.fit.coarse_rows
            } else {
                0
            },
            ..settings.fit.clone()
        },
    )?;
    let nc = M::coefficient_info().len();
    let refined = M::from_parts(&fit.theta, &fit.beta[..nc]);
    let extra_beta = &fit.beta[nc..];
    let fixed = held(&refined.parameter_info(), &settings.fit);
    let (mut estimates, extra_sigma) =
        estimates_with_extra(&refined, &extra, extra_beta, &motion, fit.rss, &fixed);
    let mut effects = Vec::with_capacity(added.len());
    let mut strength = Vec::with_capacity(added.len());
    let mut k = 0;
    for e in added {
        let w = e.width();
        let c = extra_beta[k..k + w].to_vec();
        strength.push(
            c.iter()
                .zip(&extra_sigma[k..k + w])
                .map(|(c, s)| s.map_or(f64::INFINITY, |s| c.abs() / s))
                .fold(0.0, f64::max),
        );
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
        if let Effect::Ripple { cycles } = *e {
            estimates.push(Estimate {
                name: format!("{}.cycles", e.id()),
                unit: "cycles/rev".into(),
                value: cycles,
                sigma: spectrum.sigma_of(cycles),
                at_bound: false,
                // Held in the refit: found by the line search, or an
                // integer harmonic.
                fixed: true,
            });
        }
        effects.push((*e, c));
        k += w;
    }
    let model = FinalModel {
        base: refined.into(),
        per_log_phase: per_log
            .iter()
            .copied()
            .filter(|k| added.contains(&Effect::Ripple { cycles: *k }))
            .collect(),
        effects,
    };
    // Every log's prediction integrates the refined state: in parallel.
    // TRAIN holds the fitted phases; every other log gets its own phase of
    // the lines the logs do not share.
    let mut scored = logs
        .par_iter()
        .enumerate()
        .map(|(i, l)| {
            let p = if i == 0 {
                model.predict(l)?
            } else {
                model.predict_log(l)?
            };
            Ok(metrics(&l.tau, &p))
        })
        .collect::<Result<Vec<_>, FrictionError>>()?;
    let validation = scored.split_off(1);
    let name = std::iter::once(m.name().to_string())
        .chain(added.iter().map(Effect::id))
        .collect::<Vec<_>>()
        .join(" + ");
    let structure = fit.theta.clone();
    Ok((
        Refined {
            result: ModelResult {
                name,
                warnings: super::fit_warnings(&estimates, &train.tau),
                parameters: estimates,
                train: scored[0],
                validation,
                iterations: fit.iterations,
                evaluations: fit.evaluations,
                status: fit.status,
            },
            model,
            structure,
        },
        strength,
    ))
}
