//! One round of the forward selection: every unused candidate fitted with
//! the current model and scored (the nested-model F-test, ΔBIC, the
//! validation gains), then the one to add chosen among the significant.

use rayon::prelude::*;

use super::super::accumulate::{CandidateSpec, Layout, Sums};
use super::super::fit::{ModelFit, fit};
use super::{
    CandidateEvaluation, EvaluationStatus, SelectionOptions, SelectionStep, model_columns,
};
use crate::error::IdentError;
use crate::stats::f_sf;

/// A candidate's evidence, with the fit that adds it when it is
/// significant.
pub(super) type Scored = (CandidateEvaluation, Option<ModelFit>);

/// The sums every nested fit of a selection is computed from.
pub(super) struct Sets<'a> {
    /// The columns' layout.
    pub layout: &'a Layout,
    /// The training sums.
    pub train: Sums,
    /// The sums of every validation set.
    pub validation: Vec<Sums>,
    /// The selection's settings.
    pub opts: &'a SelectionOptions,
    /// Training rows, all groups.
    pub rows: f64,
}

impl Sets<'_> {
    /// The model "base + `added`" fitted on the training sums and evaluated
    /// on every validation set.
    pub fn fit(&self, added: &[usize]) -> Result<ModelFit, IdentError> {
        let (cols, target) = model_columns(self.layout, added);
        fit(
            &self.train,
            &self.validation,
            &cols,
            target,
            self.opts.rank_tolerance,
            self.opts.noise_gain,
        )
    }

    /// The candidates whose family has no member among `added` (at most one
    /// candidate per family is added).
    pub fn untried(&self, added: &[usize]) -> Vec<usize> {
        let candidates = self.layout.candidates();
        let used: Vec<&str> = added
            .iter()
            .map(|&k| candidates[k].family.as_str())
            .collect();
        (0..candidates.len())
            .filter(|&k| !used.contains(&candidates[k].family.as_str()))
            .collect()
    }
}

/// The current model a round's candidates are compared with.
pub(super) struct Round<'a> {
    /// The sums.
    sets: &'a Sets<'a>,
    /// The candidates in the current model.
    added: &'a [usize],
    /// The current model's fit.
    current: &'a ModelFit,
    /// Significance level of each test: `alpha` over the candidates tried
    /// (Bonferroni).
    level: f64,
    /// The current model's mean validation fitness per group.
    before: Vec<f64>,
    /// Alternative targets among the candidates added: each a parameter of
    /// the model beyond its columns.
    target_swaps: usize,
}

impl<'a> Round<'a> {
    /// The round after the candidates `added` (fit `current`), with `tried`
    /// candidates to try.
    pub fn new(
        sets: &'a Sets<'a>,
        added: &'a [usize],
        current: &'a ModelFit,
        tried: usize,
    ) -> Self {
        let level = sets.opts.alpha / tried as f64;
        let before = current.mean_fitness();
        let target_swaps = added
            .iter()
            .filter(|&&k| sets.layout.candidates()[k].replaces_target)
            .count();
        Self {
            sets,
            added,
            current,
            level,
            before,
            target_swaps,
        }
    }

    /// Every candidate of `trial` scored, in parallel, in `trial`'s order.
    pub fn score<F>(&self, trial: &[usize], effective: &F) -> Vec<Scored>
    where
        F: Fn(&ModelFit) -> f64 + Sync,
    {
        trial
            .par_iter()
            .map(|&k| self.evaluate(k, effective))
            .collect()
    }

    /// Candidate `k` added to the current model: its evidence, significant
    /// when the F-test passes at the round's level with the fraction of
    /// independent rows `effective` gives for its fit, *and* it gains at
    /// least `min_gain` on every validation set.
    fn evaluate<F>(&self, k: usize, effective: &F) -> Scored
    where
        F: Fn(&ModelFit) -> f64 + Sync,
    {
        let (opts, n) = (self.sets.opts, self.sets.rows);
        let spec = &self.sets.layout.candidates()[k];
        let mut eval = self.unscored(k, spec);
        let mut with = self.added.to_vec();
        with.push(k);
        let f1 = match self.sets.fit(&with) {
            Ok(f) => f,
            Err(e) => {
                eval.note = e.to_string();
                return (eval, None);
            }
        };
        let k_add = if spec.replaces_target {
            1
        } else {
            f1.columns.len().saturating_sub(self.current.columns.len())
        };
        let swaps = self.target_swaps + usize::from(spec.replaces_target);
        let p1 = (f1.columns.len() + swaps) as f64;
        let (rss0, rss1) = (self.current.total_rss(), f1.total_rss());
        eval.added_parameters = k_add;
        eval.rss_drop_percent = if rss0 > 0.0 {
            100.0 * (rss0 - rss1) / rss0
        } else {
            0.0
        };
        self.gains(&mut eval, spec, &f1);
        if k_add == 0 {
            eval.status = EvaluationStatus::NoNewParameters;
            return (eval, None);
        }
        let every = eval.gain_per_set.iter().all(|g| *g >= opts.min_gain);
        let test = |ne: f64| nested_test(rss0, rss1, k_add, p1, ne);
        // Fewer samples only weaken the F-test: a candidate that fails with
        // every row, or on a validation set, fails at any fraction, and its
        // own fraction is not measured.
        let hopeless = !every || test(n).is_none_or(|(_, p, _)| p >= self.level);
        let fraction = if hopeless { f64::NAN } else { effective(&f1) };
        let fraction = if fraction.is_nan() {
            opts.effective_fraction
        } else {
            fraction.clamp(1e-9, 1.0)
        };
        let ne = fraction * n;
        eval.n_eff = ne;
        if let Some((f, p, bic)) = test(ne) {
            eval.f = f;
            eval.p_value = p;
            eval.delta_bic = bic;
        }
        if eval.p_value < self.level && every {
            eval.status = EvaluationStatus::Significant;
            (eval, Some(f1))
        } else {
            eval.status = EvaluationStatus::NotSignificant;
            (eval, None)
        }
    }

    /// Candidate `k`'s evaluation before it is fitted: nothing gained, not
    /// significant, [`EvaluationStatus::Failed`] until scored.
    fn unscored(&self, k: usize, spec: &CandidateSpec) -> CandidateEvaluation {
        CandidateEvaluation {
            candidate: k,
            name: spec.name.clone(),
            family: spec.family.clone(),
            added_parameters: 0,
            rss_drop_percent: 0.0,
            n_eff: self.sets.opts.effective_fraction * self.sets.rows,
            f: 0.0,
            p_value: 1.0,
            delta_bic: 0.0,
            gain: vec![0.0; self.before.len()],
            mean_gain: 0.0,
            gain_per_set: vec![0.0; self.sets.validation.len()],
            status: EvaluationStatus::Failed,
            note: String::new(),
        }
    }

    /// The validation fitness (78) gained by the fit `f1` over the current
    /// model: per group (mean over the sets), and judged on the groups the
    /// candidate acts on (every group by default), overall and per set.
    fn gains(&self, eval: &mut CandidateEvaluation, spec: &CandidateSpec, f1: &ModelFit) {
        let after = f1.mean_fitness();
        eval.gain = after.iter().zip(&self.before).map(|(a, b)| a - b).collect();
        let on = |g: &[f64]| on_groups(spec.groups.as_deref(), g);
        eval.mean_gain = on(&eval.gain);
        eval.gain_per_set = f1
            .fitness
            .iter()
            .zip(&self.current.fitness)
            .map(|(a, b)| on(&a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>()))
            .collect();
    }
}

/// The mean of the per-group values `g` over the groups `groups` (every
/// group for `None`).
fn on_groups(groups: Option<&[usize]>, g: &[f64]) -> f64 {
    match groups {
        Some(idx) => idx.iter().filter_map(|&i| g.get(i)).sum::<f64>() / idx.len().max(1) as f64,
        None => g.iter().sum::<f64>() / g.len().max(1) as f64,
    }
}

/// The nested-model test of `k_add` parameters that take the training RSS
/// from `rss0` to `rss1` in a model of `p1` parameters, with `ne`
/// independent samples: the F statistic, its p-value and
/// `ΔBIC = N_eff ln(RSS₁/RSS₀) + k ln N_eff`. `None` without degrees of
/// freedom left or with a zero RSS.
fn nested_test(rss0: f64, rss1: f64, k_add: usize, p1: f64, ne: f64) -> Option<(f64, f64, f64)> {
    (ne > p1 + 1.0 && rss1 > 0.0 && rss0 > 0.0).then(|| {
        let kk = k_add as f64;
        let fs = (((rss0 - rss1) / kk) / (rss1 / (ne - p1))).max(0.0);
        (
            fs,
            f_sf(fs, kk, ne - p1),
            ne * (rss1 / rss0).ln() + kk * ne.ln(),
        )
    })
}

/// Two candidates of different families that add as many parameters and
/// whose training RSS drops agree to `tolerance` (relative): on these data
/// the same hypothesis.
fn alias_of(x: &CandidateEvaluation, best: &CandidateEvaluation, tolerance: f64) -> bool {
    x.family != best.family
        && x.added_parameters == best.added_parameters
        && (x.rss_drop_percent - best.rss_drop_percent).abs()
            <= tolerance * best.rss_drop_percent.abs()
}

/// The candidate to add, if any is significant: the lowest ΔBIC, among
/// those within `bic_tie` of it the largest mean validation gain (then the
/// lower ΔBIC, then the earlier candidate), and among its significant
/// aliases the first in the layout's order.
pub(super) fn choose(scored: &[Scored], opts: &SelectionOptions) -> Option<usize> {
    let significant = || {
        scored
            .iter()
            .filter(|x| x.0.status == EvaluationStatus::Significant)
    };
    let lowest = significant()
        .map(|x| x.0.delta_bic)
        .fold(f64::INFINITY, f64::min);
    let top = significant()
        .filter(|x| x.0.delta_bic <= lowest + opts.bic_tie)
        .max_by(|a, b| {
            a.0.mean_gain
                .total_cmp(&b.0.mean_gain)
                .then(b.0.delta_bic.total_cmp(&a.0.delta_bic))
                .then(b.0.candidate.cmp(&a.0.candidate))
        })
        .map(|x| &x.0)?;
    let chosen = significant()
        .filter(|x| x.0.candidate == top.candidate || alias_of(&x.0, top, opts.alias_tolerance))
        .map(|x| x.0.candidate)
        .min()
        .unwrap_or(top.candidate);
    Some(chosen)
}

/// The step that adds candidate `chosen` of a round (`scored`, whose
/// evaluations are `round`), with the families of its aliases.
pub(super) fn step(
    scored: Vec<Scored>,
    chosen: usize,
    round: &[CandidateEvaluation],
    opts: &SelectionOptions,
) -> Result<SelectionStep, IdentError> {
    let Some((eval, Some(f1))) = scored.into_iter().find(|x| x.0.candidate == chosen) else {
        return Err(IdentError::InvalidSelection {
            reason: "internal: the selected candidate lost its fit".into(),
        });
    };
    let mut aliases: Vec<String> = round
        .iter()
        .filter(|x| x.candidate != chosen && alias_of(x, &eval, opts.alias_tolerance))
        .map(|x| x.family.clone())
        .collect();
    aliases.sort();
    aliases.dedup();
    Ok(SelectionStep {
        candidate: chosen,
        name: eval.name.clone(),
        family: eval.family.clone(),
        aliases,
        evaluation: eval,
        fit: f1,
    })
}
