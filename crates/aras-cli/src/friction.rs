//! `aras friction`: the friction of one joint of any robot from its log —
//! the classical and dynamic models of `aras-friction` fitted on TRAIN and
//! scored on every validation log, then the diagnosis of what the best model
//! still misses. This module holds the analysis (no files); `cmd::friction`
//! reads the logs and writes `friction.json`, `report.html` and the
//! predictions.

use anyhow::{Context, Result};
use aras_friction::{
    CoulombViscous, Dahl, FrictionModel, JointLog, LuGre, Motion, Separable, Stribeck,
    effects::{Effect, Profile, residual_profiles},
    fit::{
        Estimate, FitSettings, FitStatus, Fitted, Metrics, fit_coulomb_viscous, fit_dahl,
        fit_lugre, fit_stribeck, metrics,
    },
};
use serde::{Deserialize, Serialize};

/// Format tag of `friction.json`.
pub const FORMAT: &str = "aras-friction/1";

/// Settings of a friction run (defaults in one place).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct FrictionSettings {
    /// Model fitting.
    pub fit: FitSettings,
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
        let m = Motion::new(&log.t, &log.q, &log.dq)?;
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
        let base = self.final_base.predict(log)?;
        let mut out = base.clone();
        for (e, coef) in &self.final_effects {
            for (c, b) in e.columns(log, &base)?.iter().zip(coef) {
                for (o, x) in out.iter_mut().zip(c) {
                    *o += b * x;
                }
            }
        }
        Ok(out)
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
        if self.final_effects.is_empty() {
            s.push_str(" No further effect was added.");
        } else {
            let names: Vec<String> = self.final_effects.iter().map(|(e, _)| e.label()).collect();
            s.push_str(&format!(" Added: {}.", names.join("; ")));
        }
        s
    }
}

/// The diagnosis part of the report.
pub fn report_diagnosis(run: &FrictionRun, r: &mut crate::report::Report) {
    r.heading(2, "Diagnosis");
    if run.final_effects.is_empty() {
        r.paragraph("No effect was added to the best classical model.");
    }
}

fn result<M: Separable>(f: &Fitted<M>, vals: &[JointLog]) -> Result<ModelResult> {
    let validation = vals
        .iter()
        .map(|v| {
            let m = Motion::new(&v.t, &v.q, &v.dq)?;
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
    let m = Motion::new(&train.t, &train.q, &train.dq)
        .with_context(|| format!("log {}", train.name))?;
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
    Ok(FrictionRun {
        format: FORMAT.into(),
        settings: settings.clone(),
        train: LogInfo::of(train),
        validation: vals.iter().map(LogInfo::of).collect(),
        models,
        fitted: fitted.clone(),
        best,
        residual: residual_profiles(train, &resid, 12),
        final_model: None,
        final_base: fitted[best].clone(),
        final_effects: Vec::new(),
    })
}
