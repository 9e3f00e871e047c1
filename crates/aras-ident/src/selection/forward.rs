//! Forward selection over the accumulated sums: every round each unused
//! candidate is fitted with the current model; one that is significant on
//! the training data *and* helps every validation set may be added (the
//! lowest ΔBIC wins, the held-out gain breaking a tie); repeat until none is.

use serde::Serialize;

use super::accumulate::{Accumulator, Layout, Sums};
use super::fit::{ModelFit, fit};
use crate::error::IdentError;

mod round;

use round::{Round, Sets};

/// Settings of [`select`]; `Default` gives the documented values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SelectionOptions {
    /// Family-wise significance level of one round (default 0.01), split
    /// over the candidates tried in the round (Bonferroni: a grid scan is
    /// many tests).
    pub alpha: f64,
    /// Smallest validation fitness gain (percentage points of (78), mean
    /// over the groups it acts on, [`CandidateSpec::groups`](super::CandidateSpec::groups)) a candidate must bring on **every** validation set
    /// (default 0.1): a real but invisible effect is not worth parameters,
    /// and a gain on one motion only is more likely an accident of that
    /// motion than a property of the system.
    pub min_gain: f64,
    /// At most this many candidates are added (default 7).
    pub max_steps: usize,
    /// Independent fraction of the training rows for the F-test's degrees
    /// of freedom (default 1): filtered or otherwise correlated rows carry
    /// fewer independent samples than rows (e.g. `2BT/N` of a zero-phase
    /// low-pass), and counting them all makes everything "significant".
    pub effective_fraction: f64,
    /// Noise power gain `g` in (0, 1] dividing the residual variance of σ
    /// (default 1: white noise). For a filter, `g = Σ h²`; with
    /// `effective_fraction = g` the F-test and σ account for the filter
    /// once each (for one added column `F ≈ (β/σ)²`).
    pub noise_gain: f64,
    /// A column whose part outside the span of the model's other columns is
    /// below this fraction of its norm is dependent (default 1e-6: exact
    /// aliases leave ≈ √ε ≈ 1e-8 after rounding; an independent column this
    /// weak would have σ ≥ 1e6 times its noise-free scale).
    pub rank_tolerance: f64,
    /// Two candidates of different families are aliases when they add as
    /// many parameters and their training RSS drops agree to this relative
    /// tolerance (default 1e-3).
    pub alias_tolerance: f64,
    /// Significant candidates whose ΔBIC on the training data lies within
    /// this much of the lowest are tied on those data, and the largest mean
    /// validation gain among them wins (default 2: a BIC difference below 2
    /// is "not worth more than a bare mention", Kass & Raftery 1995). Two
    /// different laws that the excitation cannot tell apart, such as a
    /// Stribeck dip and quadratic damping over the same speed range, are
    /// then told apart by the motions held out; 0 keeps the lowest ΔBIC.
    pub bic_tie: f64,
}

impl Default for SelectionOptions {
    fn default() -> Self {
        Self {
            alpha: 0.01,
            min_gain: 0.1,
            max_steps: 7,
            effective_fraction: 1.0,
            noise_gain: 1.0,
            rank_tolerance: 1e-6,
            alias_tolerance: 1e-3,
            bic_tie: 2.0,
        }
    }
}

impl SelectionOptions {
    fn check(&self) -> Result<(), IdentError> {
        let bad = |name, value, reason| {
            Err(IdentError::InvalidSetting {
                name,
                value,
                reason,
            })
        };
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return bad(
                "alpha",
                self.alpha,
                "the significance level must lie in (0, 1), e.g. 0.01",
            );
        }
        if !(self.min_gain.is_finite() && self.min_gain >= 0.0) {
            return bad(
                "min_gain",
                self.min_gain,
                "the minimum fitness gain must be a finite number of percentage points ≥ 0",
            );
        }
        if !(self.effective_fraction > 0.0 && self.effective_fraction <= 1.0) {
            return bad(
                "effective_fraction",
                self.effective_fraction,
                "the independent fraction of rows must lie in (0, 1]",
            );
        }
        if !(self.noise_gain > 0.0 && self.noise_gain <= 1.0) {
            return bad(
                "noise_gain",
                self.noise_gain,
                "the filter noise gain Σ h² must lie in (0, 1]",
            );
        }
        if !(self.rank_tolerance > 0.0 && self.rank_tolerance < 1.0) {
            return bad(
                "rank_tolerance",
                self.rank_tolerance,
                "the relative rank tolerance must lie in (0, 1), e.g. 1e-6",
            );
        }
        if !(self.bic_tie >= 0.0 && self.bic_tie.is_finite()) {
            return bad(
                "bic_tie",
                self.bic_tie,
                "the ΔBIC tie margin must be a finite number ≥ 0, e.g. 2",
            );
        }
        if !(self.alias_tolerance >= 0.0 && self.alias_tolerance.is_finite()) {
            return bad(
                "alias_tolerance",
                self.alias_tolerance,
                "the alias tolerance must be a finite number ≥ 0",
            );
        }
        Ok(())
    }
}

/// What became of a candidate in a round.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EvaluationStatus {
    /// Significant on the training data and a gain on every validation set.
    Significant,
    /// Scored, but not significant or not helpful on every validation set.
    NotSignificant,
    /// Its columns lie in the span of the model's: nothing new on these
    /// data.
    NoNewParameters,
    /// It could not be fitted (e.g. a constant alternative target); see
    /// the note.
    Failed,
}

/// The evidence for one candidate in one round.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateEvaluation {
    /// Candidate index in the [`Layout`].
    pub candidate: usize,
    /// Its name.
    pub name: String,
    /// Its family.
    pub family: String,
    /// Parameters it adds (0: an alias of what the model has).
    pub added_parameters: usize,
    /// Relative drop of the training RSS (%).
    pub rss_drop_percent: f64,
    /// Effective independent training samples of the F-test.
    pub n_eff: f64,
    /// F statistic of the nested-model test.
    pub f: f64,
    /// Its p-value.
    pub p_value: f64,
    /// `N_eff ln(RSS₁/RSS₀) + k ln N_eff` (negative: better). Significant
    /// candidates are ranked by it, so that a flexible many-parameter
    /// candidate does not win over the few-parameter one it imitates.
    pub delta_bic: f64,
    /// Validation fitness gain per group (points, mean over the sets).
    pub gain: Vec<f64>,
    /// Mean of `gain` over the groups the candidate acts on
    /// ([`CandidateSpec::groups`](super::CandidateSpec::groups)).
    pub mean_gain: f64,
    /// Gain per validation set (mean over the groups it acts on, points).
    pub gain_per_set: Vec<f64>,
    /// The outcome.
    pub status: EvaluationStatus,
    /// Why it failed, empty otherwise.
    pub note: String,
}

/// One candidate added.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SelectionStep {
    /// Candidate index in the [`Layout`].
    pub candidate: usize,
    /// Its name.
    pub name: String,
    /// Its family.
    pub family: String,
    /// Candidates of other families that explain the training data equally
    /// well (same parameters added, RSS drop within the alias tolerance):
    /// on these data the same hypothesis. Among them the first in the
    /// layout's order is the one added.
    pub aliases: Vec<String>,
    /// The evidence.
    pub evaluation: CandidateEvaluation,
    /// The model after the step.
    pub fit: ModelFit,
}

/// Why the selection stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SelectionStatus {
    /// No remaining candidate was significant and helpful on every set.
    NothingSignificant,
    /// The step limit was reached.
    StepLimit,
    /// Every family was added.
    CandidatesExhausted,
}

/// The result of [`select`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Selection {
    /// The base model's fit.
    pub initial: ModelFit,
    /// Candidates added, in order.
    pub steps: Vec<SelectionStep>,
    /// Every candidate's evaluation in every round, in layout order.
    pub rounds: Vec<Vec<CandidateEvaluation>>,
    /// Why it stopped.
    pub status: SelectionStatus,
}

impl Selection {
    /// The final model's fit.
    pub fn final_fit(&self) -> &ModelFit {
        self.steps.last().map(|s| &s.fit).unwrap_or(&self.initial)
    }

    /// Candidate indices added, in order.
    pub fn added(&self) -> Vec<usize> {
        self.steps.iter().map(|s| s.candidate).collect()
    }
}

/// The columns and target of the model "base + `added`".
fn model_columns(layout: &Layout, added: &[usize]) -> (Vec<usize>, usize) {
    let mut cols: Vec<usize> = (0..layout.base_columns()).collect();
    let mut target = layout.target_column();
    for &k in added {
        if layout.candidates()[k].replaces_target {
            target = layout.candidate_columns(k).start;
        } else {
            cols.extend(layout.candidate_columns(k));
        }
    }
    (cols, target)
}

fn check_sets(train: &Accumulator, validation: &[Accumulator]) -> Result<(), IdentError> {
    if validation.is_empty() {
        return Err(IdentError::InvalidSelection {
            reason: "give at least one validation set: a candidate is only added if it helps \
                     every validation set"
                .into(),
        });
    }
    if validation.iter().any(|v| v.layout() != train.layout()) {
        return Err(IdentError::InvalidSelection {
            reason: "the validation sums have a different layout than the training sums; build \
                     all from one Layout"
                .into(),
        });
    }
    Ok(())
}

/// Fits the model "base columns + the candidates `added`" (indices into the
/// layout; an alternative-target candidate replaces the target) on `train`
/// and evaluates it on every validation set. Used by [`select`] for every
/// nested fit, and by callers to refit or refine a chosen model.
pub fn fit_model(
    train: &Accumulator,
    validation: &[Accumulator],
    added: &[usize],
    opts: &SelectionOptions,
) -> Result<ModelFit, IdentError> {
    opts.check()?;
    check_sets(train, validation)?;
    let layout = train.layout();
    if let Some(&k) = added.iter().find(|&&k| k >= layout.candidates().len()) {
        return Err(IdentError::InvalidSelection {
            reason: format!(
                "candidate {k} does not exist (the layout has {})",
                layout.candidates().len()
            ),
        });
    }
    let t = train.snapshot();
    let v: Vec<Sums> = validation.iter().map(|a| a.snapshot()).collect();
    let (cols, target) = model_columns(layout, added);
    fit(&t, &v, &cols, target, opts.rank_tolerance, opts.noise_gain)
}

/// Forward selection: starting from the base columns, adds one candidate
/// per round while one is significant on `train` (nested-model F-test with
/// `effective_fraction` of the rows, level `alpha / candidates tried`) and
/// gains at least `min_gain` fitness points on every `validation` set; the
/// lowest ΔBIC wins (among those within `bic_tie` of it, the largest mean
/// validation gain), and among its aliases the first in the layout's order.
/// At most one candidate per family. Deterministic: the same sums give the
/// same selection whatever the thread count.
pub fn select(
    train: &Accumulator,
    validation: &[Accumulator],
    opts: &SelectionOptions,
) -> Result<Selection, IdentError> {
    select_with(train, validation, opts, |_| opts.effective_fraction)
}

/// [`select`] with the independent fraction of the training rows judged per
/// candidate: `effective(fit)` is the fraction for the F-test of the model
/// `fit` that adds the candidate (e.g. `1/τ` of that model's residual,
/// whose rows the caller holds), in (0, 1] (clamped there; a NaN counts
/// as [`SelectionOptions::effective_fraction`]). It is asked only for a
/// candidate that passes with every row and gains on every validation set:
/// the others fail at any fraction, and their evaluations count
/// [`SelectionOptions::effective_fraction`].
///
/// A residual autocorrelated *because* of an effect not yet modelled counts
/// few independent samples, and a fraction measured on it before the
/// effect is added would starve the very candidate that removes the
/// structure; measured after, the fraction of a useless candidate stays
/// that of the current residual.
pub fn select_with<F>(
    train: &Accumulator,
    validation: &[Accumulator],
    opts: &SelectionOptions,
    effective: F,
) -> Result<Selection, IdentError>
where
    F: Fn(&ModelFit) -> f64 + Sync,
{
    opts.check()?;
    check_sets(train, validation)?;
    let t = train.snapshot();
    let rows = t.rows.iter().sum::<usize>() as f64;
    let sets = Sets {
        layout: train.layout(),
        train: t,
        validation: validation.iter().map(|a| a.snapshot()).collect(),
        opts,
        rows,
    };
    let initial = sets.fit(&[])?;
    let mut added: Vec<usize> = Vec::new();
    let mut current = initial.clone();
    let mut steps = Vec::new();
    let mut rounds = Vec::new();
    let status = loop {
        if steps.len() >= opts.max_steps {
            break SelectionStatus::StepLimit;
        }
        let trial = sets.untried(&added);
        if trial.is_empty() {
            break SelectionStatus::CandidatesExhausted;
        }
        let scored = Round::new(&sets, &added, &current, trial.len()).score(&trial, &effective);
        let chosen = round::choose(&scored, opts);
        let evaluations: Vec<CandidateEvaluation> = scored.iter().map(|x| x.0.clone()).collect();
        rounds.push(evaluations);
        let Some(chosen) = chosen else {
            break SelectionStatus::NothingSignificant;
        };
        let step = round::step(
            scored,
            chosen,
            rounds.last().map_or(&[], Vec::as_slice),
            opts,
        )?;
        added.push(chosen);
        current = step.fit.clone();
        steps.push(step);
    };
    Ok(Selection {
        initial,
        steps,
        rounds,
        status,
    })
}
