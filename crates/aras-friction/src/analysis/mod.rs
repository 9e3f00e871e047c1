//! The friction analysis of one joint: every classical model fitted on a
//! training log and scored on the validation logs, then the diagnosis of
//! what the best of them still misses ([`analyse`]).
//!
//! 1. Offset + Coulomb + viscous, Stribeck, Dahl and LuGre are fitted on
//!    TRAIN ([`crate::fit`]).
//! 2. Each is scored on every validation log (RMS and fitness (78)); the
//!    best is the one with the lowest mean validation RMS, or the lowest
//!    TRAIN RMS without validation logs ([`BestBy`]).
//! 3. With at least one validation log, the diagnosis tests the candidate
//!    effects of [`crate::effects`] against the best model's residual with
//!    the forward selection of [`aras_ident::selection`]: an effect is added
//!    when its F-test on TRAIN is significant and it raises the fitness on
//!    every validation log. The selected effects' columns then join the
//!    best model's own in a nonlinear refit of its structure (the refined
//!    final model).
//!
//! The result, [`FrictionRun`], serialises as the `aras-friction/1`
//! document ([`FORMAT`]).

mod diagnosis;
mod settings;

use rayon::prelude::*;
use serde::{Deserialize, Serialize, Serializer};
use thiserror::Error;

use crate::{
    CoulombViscous, Dahl, FrictionError, FrictionModel, JointLog, JointMotion, LuGre, MaxwellSlip,
    ParamInfo, Separable, Stribeck,
    effects::{Effect, Profile, residual_profiles},
    fit::{
        Estimate, FitStatus, Fitted, Metrics, fit_coulomb_viscous, fit_dahl, fit_lugre,
        fit_maxwell_slip, fit_stribeck, metrics,
    },
    sgn,
};

pub use diagnosis::{DiagnosisResult, DiagnosisStep, LinePhases, RefitScore};
pub use settings::{FrictionSettings, SettingError};

/// Format tag of the serialised [`FrictionRun`].
pub const FORMAT: &str = "aras-friction/1";

/// Errors of [`analyse`]. Each names the log or model it concerns.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum AnalysisError {
    /// A setting out of range.
    #[error("friction {0}")]
    Setting(#[from] SettingError),
    /// A log whose samples cannot be a motion (lengths, non-finite values,
    /// time not increasing).
    #[error("log {name}")]
    Log {
        /// The log's name.
        name: String,
        /// What is wrong.
        #[source]
        source: FrictionError,
    },
    /// A model could not be fitted on TRAIN.
    #[error("fitting {model}")]
    Fit {
        /// The model, in words.
        model: &'static str,
        /// Why.
        #[source]
        source: FrictionError,
    },
    /// A model or effect could not be evaluated on a log.
    #[error(transparent)]
    Friction(#[from] FrictionError),
    /// The forward selection refused its input.
    #[error(transparent)]
    Selection(#[from] aras_ident::IdentError),
    /// The selection engine named a column its layout does not have (a
    /// defect of this crate, never of the input).
    #[error(
        "internal: the selection used column {column} but the layout has {columns} columns; \
         please report this with the logs that caused it"
    )]
    Layout {
        /// The column asked for.
        column: usize,
        /// Columns of the layout.
        columns: usize,
    },
}

/// The classical models, by kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ModelKind {
    /// Offset + Coulomb + viscous.
    CoulombViscous,
    /// Stribeck.
    Stribeck,
    /// Dahl.
    Dahl,
    /// LuGre.
    Lugre,
    /// Generalized Maxwell-slip.
    MaxwellSlip,
}

impl ModelKind {
    /// Every kind, in the order [`FrictionRun::models`] lists them.
    pub const ALL: [ModelKind; 5] = [
        ModelKind::CoulombViscous,
        ModelKind::Stribeck,
        ModelKind::Dahl,
        ModelKind::Lugre,
        ModelKind::MaxwellSlip,
    ];

    /// The model in words, for messages.
    pub fn label(self) -> &'static str {
        match self {
            ModelKind::CoulombViscous => "offset + Coulomb + viscous",
            ModelKind::Stribeck => "Stribeck",
            ModelKind::Dahl => "Dahl",
            ModelKind::Lugre => "LuGre",
            ModelKind::MaxwellSlip => "generalized Maxwell-slip",
        }
    }

    /// The structural parameters `θ` of the kind's separable form, with
    /// their physical ranges.
    pub fn structure_info(self) -> Vec<ParamInfo> {
        match self {
            ModelKind::CoulombViscous => CoulombViscous::structure_info(),
            ModelKind::Stribeck => Stribeck::structure_info(),
            ModelKind::Dahl => Dahl::structure_info(),
            ModelKind::Lugre => LuGre::structure_info(),
            ModelKind::MaxwellSlip => MaxwellSlip::structure_info(),
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
    /// The reader's notes on this log ([`JointMotion::notes`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

impl LogInfo {
    /// The facts of `log`.
    pub fn of(log: &JointMotion) -> Self {
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
            notes: log.notes.clone(),
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
    /// What makes the fit doubtful although it converged (a model that
    /// lost its Coulomb level, a parameter at its search bound).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<FitWarning>,
}

/// A fit that converged to a doubtful point: said in the report, not
/// left for the user to spot in the parameter table.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FitWarning {
    /// The Coulomb level `F_c` fell below [`COULOMB_VANISHED`] of the
    /// TRAIN torque's RMS: the fit collapsed onto its viscous and presliding
    /// terms (seen with LuGre on joints with several presliding lengths),
    /// and its presliding parameters are not identified.
    CoulombVanished {
        /// Fitted `F_c`, N·m.
        value: f64,
        /// RMS of the TRAIN torque about its mean, N·m.
        torque_rms: f64,
    },
    /// A free parameter ended on a bound of its search box or physical
    /// range: the unconstrained optimum lies outside, and its σ means
    /// little.
    AtBound {
        /// Parameter name.
        parameter: String,
        /// Its value, in `unit`.
        value: f64,
        /// SI unit.
        unit: String,
    },
}

impl std::fmt::Display for FitWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FitWarning::CoulombVanished { value, torque_rms } => write!(
                f,
                "its Coulomb level vanished (F_c = {value:.2e} N·m against a torque RMS of \
                 {torque_rms:.3} N·m): either the joint has no Coulomb friction, or the fit \
                 collapsed onto its other terms (a joint with several presliding lengths), and \
                 its presliding parameters are then not identified"
            ),
            FitWarning::AtBound {
                parameter,
                value,
                unit,
            } => write!(
                f,
                "`{parameter}` = {value:.3e} {unit} is on a bound of its search box or \
                 physical range: the unconstrained optimum lies outside, and its σ means little"
            ),
        }
    }
}

/// `F_c` below this fraction of the torque's RMS is a collapsed fit.
pub const COULOMB_VANISHED: f64 = 1e-3;

/// The warnings of a fit with `parameters` on a TRAIN torque `tau`.
fn fit_warnings(parameters: &[Estimate], tau: &[f64]) -> Vec<FitWarning> {
    let n = tau.len().max(1) as f64;
    let mean = tau.iter().sum::<f64>() / n;
    let torque_rms = (tau.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / n).sqrt();
    let mut out = Vec::new();
    for p in parameters {
        if p.name == "Fc" && p.value.abs() < COULOMB_VANISHED * torque_rms {
            out.push(FitWarning::CoulombVanished {
                value: p.value,
                torque_rms,
            });
        } else if p.at_bound && !p.fixed {
            out.push(FitWarning::AtBound {
                parameter: p.name.clone(),
                value: p.value,
                unit: p.unit.clone(),
            });
        }
    }
    out
}

/// A fitted model of any of the classical kinds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// Generalized Maxwell-slip.
    MaxwellSlip(MaxwellSlip),
}

impl AnyModel {
    /// Which model this is.
    pub fn kind(&self) -> ModelKind {
        match self {
            AnyModel::CoulombViscous(_) => ModelKind::CoulombViscous,
            AnyModel::Stribeck(_) => ModelKind::Stribeck,
            AnyModel::Dahl(_) => ModelKind::Dahl,
            AnyModel::Lugre(_) => ModelKind::Lugre,
            AnyModel::MaxwellSlip(_) => ModelKind::MaxwellSlip,
        }
    }

    /// Prediction along a log's motion.
    pub fn predict(&self, log: &JointMotion) -> Result<Vec<f64>, FrictionError> {
        let m = log.track()?;
        Ok(match self {
            AnyModel::CoulombViscous(x) => x.predict(&m),
            AnyModel::Stribeck(x) => x.predict(&m),
            AnyModel::Dahl(x) => x.predict(&m),
            AnyModel::Lugre(x) => x.predict(&m),
            AnyModel::MaxwellSlip(x) => x.predict(&m),
        })
    }

    /// Steady-state friction at constant velocity `v` (for LuGre the
    /// Stribeck curve, for Dahl `±F_c` plus viscous and offset).
    pub fn steady_state(&self, v: f64) -> f64 {
        match self {
            AnyModel::CoulombViscous(x) => x.offset + x.coulomb * sgn(v) + x.viscous * v,
            AnyModel::Stribeck(x) => x.at(v),
            AnyModel::Dahl(x) => x.offset + x.coulomb * sgn(v) + x.viscous * v,
            AnyModel::Lugre(x) => x.steady_state().at(v),
            AnyModel::MaxwellSlip(x) => x.steady_state().at(v),
        }
    }

    /// Model name.
    pub fn name(&self) -> &'static str {
        match self {
            AnyModel::CoulombViscous(x) => x.name(),
            AnyModel::Stribeck(x) => x.name(),
            AnyModel::Dahl(x) => x.name(),
            AnyModel::Lugre(x) => x.name(),
            AnyModel::MaxwellSlip(x) => x.name(),
        }
    }
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
impl From<MaxwellSlip> for AnyModel {
    fn from(m: MaxwellSlip) -> Self {
        AnyModel::MaxwellSlip(m)
    }
}

/// How the best classical model was chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BestBy {
    /// Lowest mean RMS over the validation logs.
    ValidationRms,
    /// Lowest TRAIN RMS: there was no validation log.
    TrainRms,
}

/// Why no diagnosis was run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoDiagnosis {
    /// No validation log was given: an effect is only added when it helps
    /// every validation log.
    NoValidationLog,
}

impl std::fmt::Display for NoDiagnosis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NoDiagnosis::NoValidationLog => f.write_str(
                "No diagnosis: give at least one validation log (--validate); an effect is \
                 only added when it helps every validation log.",
            ),
        }
    }
}

/// Serialised as its sentence (the document's `diagnosis_note`).
impl Serialize for NoDiagnosis {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Everything an analysis found; serialised as the `aras-friction/1`
/// document.
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
    /// The classical models, in [`ModelKind::ALL`] order:
    /// coulomb_viscous, stribeck, dahl, lugre, maxwell_slip.
    pub models: Vec<ModelResult>,
    /// The fitted models themselves (same order).
    pub fitted: Vec<AnyModel>,
    /// Index of the best classical model (see [`FrictionRun::best_by`]).
    pub best: usize,
    /// How [`FrictionRun::best`] was chosen.
    #[serde(skip)]
    pub best_by: BestBy,
    /// The best model's TRAIN residual against velocity, position, time,
    /// acceleration and direction.
    pub residual: Vec<Profile>,
    /// The diagnosis (needs at least one validation log).
    pub diagnosis: Option<DiagnosisResult>,
    /// Why there is no diagnosis, when there is none.
    pub diagnosis_note: Option<NoDiagnosis>,
    /// The final model (best classical model plus the effects the diagnosis
    /// added, refitted), when it differs from the best classical model.
    pub final_model: Option<ModelResult>,
    /// The final model (its fields `final_base` and `final_effects` in the
    /// document), ready to predict on any log.
    #[serde(flatten)]
    pub model: FinalModel,
}

/// The final model of an analysis: the best classical model, refitted, plus
/// the effects the diagnosis added with their coefficients. It predicts on
/// any log of the joint ([`FinalModel::predict`]) without refitting
/// anything, and reads back from an `aras-friction/1` document (the
/// document's other fields are ignored), so a model fitted once applies to
/// every later log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FinalModel {
    /// The base friction model.
    #[serde(rename = "final_base")]
    pub base: AnyModel,
    /// The effects with their coefficients (in the effect's column order).
    #[serde(rename = "final_effects")]
    pub effects: Vec<(Effect, Vec<f64>)>,
    /// The ripple effects (their `k`, cycles per revolution) whose phase
    /// each log sets: the logs the model was fitted on did not share a
    /// position zero (an encoder zeroed per log). Their coefficients hold
    /// TRAIN's phase; [`FinalModel::predict_log`] measures each log's own.
    #[serde(
        rename = "final_per_log_phase",
        default,
        skip_serializing_if = "Vec::is_empty"
    )]
    pub per_log_phase: Vec<f64>,
}

impl FinalModel {
    /// The model's friction torque along a motion: the base model's
    /// prediction, its state integrated from rest at the log's first
    /// sample, plus every effect's columns times their coefficients, every
    /// ripple at the phase it was fitted with (TRAIN's, also for the lines
    /// of [`FinalModel::per_log_phase`]). Every effect's coefficient count
    /// is checked.
    pub fn predict(&self, log: &JointMotion) -> Result<Vec<f64>, FrictionError> {
        self.check()?;
        predict_with_effects(&self.base, &self.effects, log, &[])
    }

    /// [`FinalModel::predict`] on a log with its measured torque, each line
    /// of [`FinalModel::per_log_phase`] at the log's own phase
    /// ([`FinalModel::phase_shifts`]). Without such lines it is
    /// [`FinalModel::predict`].
    pub fn predict_log(&self, log: &JointLog) -> Result<Vec<f64>, FrictionError> {
        self.check()?;
        let shifts: Vec<(f64, f64)> = self
            .per_log_phase
            .iter()
            .copied()
            .zip(self.phase_shifts(log)?)
            .collect();
        predict_with_effects(&self.base, &self.effects, log, &shifts)
    }

    /// How far each line of [`FinalModel::per_log_phase`] is turned on
    /// `log`, rad in (−π, π]: its phase fitted at its `k` on the log's
    /// residual (the torque minus the model without those lines) minus the
    /// model's phase. One nuisance parameter per line and log, like the
    /// log's position zero it stands for; 0 where the log cannot tell.
    pub fn phase_shifts(&self, log: &JointLog) -> Result<Vec<f64>, FrictionError> {
        if self.per_log_phase.is_empty() {
            return Ok(Vec::new());
        }
        self.check()?;
        let own = |e: &Effect| matches!(e, Effect::Ripple { cycles } if self.per_log_phase.contains(cycles));
        let others: Vec<(Effect, Vec<f64>)> = self
            .effects
            .iter()
            .filter(|(e, _)| !own(e))
            .cloned()
            .collect();
        let rest = predict_with_effects(&self.base, &others, log, &[])?;
        let residual: Vec<f64> = log.tau.iter().zip(&rest).map(|(a, b)| a - b).collect();
        Ok(self
            .per_log_phase
            .iter()
            .map(|&k| {
                let model = self.effects.iter().find_map(|(e, c)| match e {
                    Effect::Ripple { cycles } if *cycles == k => Some(c[1].atan2(c[0])),
                    _ => None,
                });
                match (model, crate::spectrum::line_phase(&log.q, &residual, k)) {
                    (Some(m), Some(p)) => crate::spectrum::wrapped(p.phase - m),
                    _ => 0.0,
                }
            })
            .collect())
    }

    /// Every effect's coefficient count against its width.
    fn check(&self) -> Result<(), FrictionError> {
        for (e, c) in &self.effects {
            if c.len() != e.width() {
                return Err(FrictionError::EffectCoefficients {
                    effect: e.id(),
                    expected: e.width(),
                    found: c.len(),
                });
            }
        }
        Ok(())
    }
}

impl FrictionRun {
    /// The final model's prediction on a log: base model plus effects.
    pub fn final_prediction(&self, log: &JointMotion) -> Result<Vec<f64>, FrictionError> {
        self.model.predict(log)
    }

    /// The best classical model's result.
    pub fn best_model(&self) -> &ModelResult {
        &self.models[self.best]
    }
}

/// Prediction of a base model plus effects with their coefficients on one
/// log (the effects' columns may depend on the base prediction); a ripple
/// whose `k` is in `shifts` is turned by its shift there.
pub(crate) fn predict_with_effects(
    base: &AnyModel,
    effects: &[(Effect, Vec<f64>)],
    log: &JointMotion,
    shifts: &[(f64, f64)],
) -> Result<Vec<f64>, FrictionError> {
    let base = base.predict(log)?;
    let mut out = base.clone();
    for (e, coef) in effects {
        let mut columns = e.columns(log, &base)?;
        if let Effect::Ripple { cycles } = e
            && let Some(&(_, shift)) = shifts.iter().find(|(k, _)| k == cycles)
        {
            crate::effects::shift_ripple(&mut columns, shift);
        }
        for (c, b) in columns.iter().zip(coef) {
            for (o, x) in out.iter_mut().zip(c) {
                *o += b * x;
            }
        }
    }
    Ok(out)
}

/// A fitted model's result: its TRAIN fit and its metrics on every
/// validation log.
fn result<M: Separable + Sync>(
    f: &Fitted<M>,
    train: &JointLog,
    vals: &[JointLog],
) -> Result<ModelResult, FrictionError> {
    let validation = vals
        .par_iter()
        .map(|v| Ok(metrics(&v.tau, &f.model.predict(&v.track()?))))
        .collect::<Result<Vec<_>, FrictionError>>()?;
    Ok(ModelResult {
        name: f.model.name().to_string(),
        parameters: f.estimates.clone(),
        train: f.train,
        validation,
        iterations: f.iterations,
        evaluations: f.evaluations,
        status: f.status,
        warnings: fit_warnings(&f.estimates, &train.tau),
    })
}

/// The classical models fitted on `train` (in [`ModelKind::ALL`]
/// order), each scored on `vals`.
fn fit_classical(
    train: &JointLog,
    vals: &[JointLog],
    settings: &FrictionSettings,
) -> Result<(Vec<ModelResult>, Vec<AnyModel>), AnalysisError> {
    let m = train.track().map_err(|source| AnalysisError::Log {
        name: train.name.clone(),
        source,
    })?;
    let fs = &settings.fit;
    let tau = &train.tau;
    let fit_error = |kind: ModelKind| {
        move |source| AnalysisError::Fit {
            model: kind.label(),
            source,
        }
    };
    let ((cv, st), dahl) = rayon::join(
        || (fit_coulomb_viscous(&m, tau, fs), fit_stribeck(&m, tau, fs)),
        || fit_dahl(&m, tau, fs),
    );
    let cv = cv.map_err(fit_error(ModelKind::CoulombViscous))?;
    let st = st.map_err(fit_error(ModelKind::Stribeck))?;
    let dahl = dahl.map_err(fit_error(ModelKind::Dahl))?;
    // Both state models start from the Stribeck fit's steady state.
    let (lugre, gms) = rayon::join(
        || fit_lugre(&m, tau, &st.model, fs),
        || fit_maxwell_slip(&m, tau, &st.model, fs),
    );
    let lugre = lugre.map_err(fit_error(ModelKind::Lugre))?;
    let gms = gms.map_err(fit_error(ModelKind::MaxwellSlip))?;
    let models = vec![
        result(&cv, train, vals)?,
        result(&st, train, vals)?,
        result(&dahl, train, vals)?,
        result(&lugre, train, vals)?,
        result(&gms, train, vals)?,
    ];
    let fitted = vec![
        AnyModel::CoulombViscous(cv.model),
        AnyModel::Stribeck(st.model),
        AnyModel::Dahl(dahl.model),
        AnyModel::Lugre(lugre.model),
        AnyModel::MaxwellSlip(gms.model),
    ];
    Ok((models, fitted))
}

/// The diagnosis of the best classical model and, when that is not LuGre,
/// of LuGre too: the two families hold different physics (LuGre a rate-
/// dependent bristle with one presliding length, Maxwell-slip several
/// rate-independent lengths), and what the diagnosis adds to the one can
/// make it better than the other. The path with the lower mean validation
/// RMS of its final model (its classical model's when nothing is added)
/// is kept.
fn diagnose_best(
    best: usize,
    models: &[ModelResult],
    fitted: &[AnyModel],
    train: &JointLog,
    vals: &[JointLog],
    settings: &FrictionSettings,
) -> Result<(DiagnosisResult, Option<diagnosis::Refined>), AnalysisError> {
    let mean = |v: &[Metrics]| v.iter().map(|m| m.rms).sum::<f64>() / v.len().max(1) as f64;
    let score = |i: usize, r: &Option<diagnosis::Refined>| {
        r.as_ref().map_or_else(
            || mean(&models[i].validation),
            |r| mean(&r.result.validation),
        )
    };
    let first = diagnosis::diagnose(&fitted[best], fitted, train, vals, settings)?;
    let Some(lugre) = fitted
        .iter()
        .position(|m| m.kind() == ModelKind::Lugre)
        .filter(|&i| i != best)
    else {
        return Ok(first);
    };
    let second = diagnosis::diagnose(&fitted[lugre], fitted, train, vals, settings)?;
    Ok(if score(lugre, &second.1) < score(best, &first.1) {
        second
    } else {
        first
    })
}

/// The index of the best model and how it was chosen: lowest mean
/// validation RMS, or lowest TRAIN RMS without validation logs. A NaN
/// score never wins (`total_cmp` orders it above every number).
fn best_model(models: &[ModelResult]) -> (usize, BestBy) {
    let by = if models.iter().all(|m| m.validation.is_empty()) {
        BestBy::TrainRms
    } else {
        BestBy::ValidationRms
    };
    let score = |r: &ModelResult| match by {
        BestBy::TrainRms => r.train.rms,
        BestBy::ValidationRms => {
            r.validation.iter().map(|m| m.rms).sum::<f64>() / r.validation.len() as f64
        }
    };
    let best = (0..models.len())
        .min_by(|&a, &b| score(&models[a]).total_cmp(&score(&models[b])))
        .unwrap_or(0);
    (best, by)
}

/// The friction analysis of one joint (see the module docs): fits the four
/// classical models on `train`, scores them on `vals`, and — with at least
/// one validation log — diagnoses what the best one misses and refits it
/// with the effects found.
pub fn analyse(
    train: &JointLog,
    vals: &[JointLog],
    settings: &FrictionSettings,
) -> Result<FrictionRun, AnalysisError> {
    settings.validate()?;
    let (models, fitted) = fit_classical(train, vals, settings)?;
    let (best, best_by) = best_model(&models);
    let base = &fitted[best];
    let pred = base.predict(train)?;
    let resid: Vec<f64> = train.tau.iter().zip(&pred).map(|(a, b)| a - b).collect();
    let (diagnosis, diagnosis_note, refined) = if vals.is_empty() {
        (None, Some(NoDiagnosis::NoValidationLog), None)
    } else {
        let (d, r) = diagnose_best(best, &models, &fitted, train, vals, settings)?;
        (Some(d), None, r)
    };
    let (final_model, model) = match refined {
        Some(r) => (Some(r.result), r.model),
        None => (
            None,
            FinalModel {
                base: base.clone(),
                effects: Vec::new(),
                per_log_phase: Vec::new(),
            },
        ),
    };
    Ok(FrictionRun {
        format: FORMAT.into(),
        settings: settings.clone(),
        train: LogInfo::of(train),
        validation: vals.iter().map(|v| LogInfo::of(v)).collect(),
        models,
        fitted,
        best,
        best_by,
        residual: residual_profiles(train, &resid, 12),
        diagnosis,
        diagnosis_note,
        final_model,
        model,
    })
}
