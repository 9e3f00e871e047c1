//! The selection loop: fit every candidate with the current model, score,
//! add the best significant one, repeat; then re-identify consistently.

use std::time::Instant;

use aras_dyn::{Effect, Model, Params};
use aras_kin::{Geometry, Workspace};
use faer::{Col, Mat};
use rayon::prelude::*;
use serde::Serialize;

use super::candidates::{Candidate, CandidateGrid};
use super::data::{Dataset, Design, columns, design, effect_columns, moving_mask};
use super::residual::{JointData, ResidualAnalysis, analyse};
use aras_ident::stats::{f_sf, integrated_time};
use aras_ident::validate::fitness;
use aras_ident::{BaseParameters, IdentError, ReducedLs};

use crate::robot::{Stacked, consistent_problem};

/// Settings of [`diagnose`]; `Default` gives the documented values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnoseOptions {
    /// Candidates and their grids.
    pub grid: CandidateGrid,
    /// Family-wise significance level of one round (default 0.01), split
    /// over the candidate settings of the round.
    pub alpha: f64,
    /// Smallest validation fitness gain (percentage points of (78),
    /// averaged over the joints) a candidate must bring on **every**
    /// validation set to be added (default 0.1): a statistically real but
    /// practically invisible effect is not worth parameters, and a gain on
    /// one motion only is more likely an accident of that motion than a
    /// property of the robot.
    pub min_gain: f64,
    /// At most this many effects are added (default 7).
    pub max_steps: usize,
    /// Quasi-random states for the structural base parameters (default 600).
    pub base_samples: usize,
    /// Joint `j`'s rows where `|θ̇_j|` is below this (rad/s), widened by the
    /// filter's reach, are left out of fits and scores (default 0.2, the
    /// identification's threshold, `robot::reversal_mask`): at velocity
    /// reversals the exact `sign` of (49) misfits the real friction
    /// (sticking, creeping, the simulator's `tanh`) by far more than the
    /// noise. Stribeck friction stays visible above this speed only for
    /// `v_s ≳ min_speed / 2` (`exp(−4) ≈ 2 %` of its level at `v_s =
    /// min_speed / 2`).
    pub min_speed: f64,
    /// TRAIN's exclusion is widened by the zero-phase filter's reach down
    /// to this fraction of its impulse-response peak (default 1e-3, as in
    /// identification: 253 samples at 10 Hz and 1 kHz).
    pub reach_tol: f64,
    /// The same for the validation sets (default 0.5: the filter's main
    /// lobe only, so that fast validation motions keep rows; the
    /// identification's cross-validation uses the same).
    pub validation_reach_tol: f64,
    /// Reference parameters (e.g. CAD) for the final physically consistent
    /// re-identification; `None` skips it.
    pub reference: Option<Params>,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            grid: CandidateGrid::default(),
            alpha: 0.01,
            min_gain: 0.1,
            max_steps: 7,
            base_samples: 600,
            min_speed: 0.2,
            reach_tol: 1e-3,
            validation_reach_tol: 0.5,
            reference: None,
        }
    }
}

/// A named number with its standard deviation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedValue {
    /// Parameter name.
    pub name: String,
    /// Value (SI).
    pub value: f64,
    /// Standard deviation from the HAC sandwich covariance
    /// ([`aras_ident::covariance`]), which accounts for the filtered residual's
    /// correlation; 0 if unknown (never NaN).
    pub std_dev: f64,
}

/// The evidence for one candidate setting in one round.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateScore {
    /// The candidate with its setting.
    pub candidate: Candidate,
    /// Its label.
    pub label: String,
    /// Base parameters it adds (0: an alias of what the model has).
    pub added_parameters: usize,
    /// Relative drop of the TRAIN residual sum of squares (%).
    pub rss_drop_percent: f64,
    /// Effective independent samples (both joints) used by the F-test.
    pub n_eff: f64,
    /// F statistic of the nested-model test.
    pub f: f64,
    /// Its p-value.
    pub p_value: f64,
    /// Change of the Bayesian information criterion on TRAIN with the
    /// effective sample count, `N_eff ln(RSS₁/RSS₀) + k ln N_eff` (negative:
    /// better). Significant candidates are ranked by it, not by the raw
    /// validation gain, so that a flexible many-parameter candidate (e.g.
    /// slow cogging, 8 parameters) does not win over the 2-parameter effect
    /// it imitates.
    pub delta_bic: f64,
    /// Validation fitness gain per joint (percentage points, mean over the
    /// validation sets).
    pub gain: [f64; 2],
    /// Mean of `gain`.
    pub mean_gain: f64,
    /// Gain per validation set (mean over the joints, percentage points).
    pub gain_per_set: Vec<f64>,
    /// Significant: p below the round's corrected level and a gain of at
    /// least `min_gain` on every validation set.
    pub significant: bool,
    /// Why the candidate could not be scored (e.g. not excited by the
    /// kept rows); empty if it was.
    pub note: String,
}

/// One effect added.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    /// Stable identifier.
    pub id: String,
    /// Label with setting.
    pub label: String,
    /// The candidate.
    pub candidate: Candidate,
    /// Physical explanation.
    pub explanation: String,
    /// Other candidates that explain the data equally well (their TRAIN
    /// residual drop is within 0.1 % of this one's and they add as many
    /// parameters): on these data they are the same hypothesis. Typical:
    /// `coulomb_asymmetry` and `torque_offset` on data without rest
    /// periods, where `|sign θ̇| = 1` on every row kept.
    pub aliases: Vec<String>,
    /// Its fitted parameters (OLS on TRAIN, with the current model).
    pub parameters: Vec<NamedValue>,
    /// The evidence.
    pub evidence: CandidateScore,
}

/// Validation fitness after a step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitnessRow {
    /// 0 = starting model, k = after the k-th added effect.
    pub step: usize,
    /// What the model is at this step.
    pub model: String,
    /// Fitness (78) per validation set, per joint (%).
    pub fitness: Vec<[f64; 2]>,
}

/// The physically consistent re-identification of the final model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConsistentFit {
    /// Solver status.
    pub status: String,
    /// Validation fitness per set per joint (%).
    pub fitness: Vec<[f64; 2]>,
    /// Standard parameters of the final model.
    pub parameters: Vec<NamedValue>,
}

/// The result of [`diagnose`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    /// Starting model.
    pub initial_model: Vec<Effect>,
    /// Final model (starting model + effects added, in order).
    pub final_model: Vec<Effect>,
    /// Torque-against-angle shift found (samples; 0 if none).
    pub delay_samples: i64,
    /// Effects added, in order.
    pub steps: Vec<Step>,
    /// Every candidate's score in every round.
    pub rounds: Vec<Vec<CandidateScore>>,
    /// Validation fitness per step.
    pub fitness: Vec<FitnessRow>,
    /// Residual analysis of each validation set with the starting model.
    pub before: Vec<ResidualAnalysis>,
    /// The same with the final model.
    pub after: Vec<ResidualAnalysis>,
    /// True if the final residual is white with no systematic bin.
    pub noise_like: bool,
    /// The conclusion in words.
    pub conclusion: String,
    /// Final OLS base parameters (readable definitions as names).
    pub estimate: Vec<NamedValue>,
    /// Physically consistent re-identification, if a reference was given.
    pub consistent: Option<ConsistentFit>,
    /// Wall time (s).
    pub elapsed_s: f64,
}

/// Per data set: the starting model's filtered columns and every candidate
/// block.
struct Prepared {
    base: Stacked,
    blocks: Vec<Option<Mat<f64>>>,
    mask: [Vec<bool>; 2],
}

/// One candidate's outcome in a round: index, score, state, and its fit if
/// significant.
type Scored = (
    usize,
    CandidateScore,
    State,
    Option<(BaseParameters, Fit, Vec<[f64; 2]>)>,
);

struct Fit {
    beta: Vec<f64>,
    std_dev: Vec<f64>,
    rss: f64,
    residual: Vec<f64>,
    split: usize,
}

/// OLS of design `d` on `base`, with σ from the HAC sandwich
/// (`OlsEstimate::with_hac`, the covariance every σ of the toolkit uses),
/// which accounts for the filtered, correlated residual. The F-test does
/// not use σ but RSS ratios with the effective sample count `N_eff ≤ g N`
/// (see [`n_eff`]).
fn fit(d: &Design, base: &BaseParameters, periodic: bool) -> Result<Fit, IdentError> {
    let wb = base.base_regressor(d.w.as_ref())?;
    let red = ReducedLs::new(wb.as_ref(), &d.t, &base.base_names())?;
    let groups = aras_ident::RowGroups::contiguous(&[d.split(), d.t.len() - d.split()])?;
    let (ols, _) = red.ols()?.with_hac(wb.as_ref(), &d.t, &groups, periodic)?;
    let b = Col::from_fn(ols.estimate.len(), |i| ols.estimate[i]);
    let pred = &wb * &b;
    let residual: Vec<f64> = (0..d.t.len()).map(|i| d.t[i] - pred[i]).collect();
    let rss = residual.iter().map(|r| r * r).sum();
    Ok(Fit {
        std_dev: ols
            .std_dev
            .iter()
            .map(|s| if s.is_finite() { *s } else { 0.0 })
            .collect(),
        beta: ols.estimate,
        rss,
        residual,
        split: d.split(),
    })
}

/// Validation residual and fitness per joint of base parameters `beta`.
fn evaluate(
    d: &Design,
    base: &BaseParameters,
    beta: &[f64],
) -> Result<(Vec<f64>, [f64; 2]), IdentError> {
    let wb = base.base_regressor(d.w.as_ref())?;
    let b = Col::from_fn(beta.len(), |i| beta[i]);
    let pred = &wb * &b;
    let p: Vec<f64> = (0..d.t.len()).map(|i| pred[i]).collect();
    let residual = d.t.iter().zip(&p).map(|(t, p)| t - p).collect();
    let n = d.split();
    let f = [fitness(&d.t[..n], &p[..n])?, fitness(&d.t[n..], &p[n..])?];
    Ok((residual, f))
}

/// Effective independent samples of a two-joint residual: per joint
/// `min(2BT, N/τ_int)`.
/// `dof_ratio` is the filter's independent fraction of samples, `2BT/N`
/// ([`Dataset::filter_dof`]), equal to the noise gain `g` that corrects σ
/// in [`fit`]: the F-test accounts for the filter here, through its
/// degrees of freedom, and uses the *uncorrected* RSS; σ accounts for it
/// through `g`. `τ_int` additionally counts slow systematic misfit as
/// correlated, which the σ correction (pure noise) does not.
fn n_eff(residual: &[f64], split: usize, dof_ratio: f64) -> f64 {
    let (a, b) = residual.split_at(split);
    [a, b]
        .iter()
        .map(|r| {
            let n = r.len() as f64;
            let tau = integrated_time(r, r.len() / 4);
            (n / tau).min(dof_ratio * n)
        })
        .sum()
}

/// The state of the search: effects added (as candidate indices) and delay.
#[derive(Clone)]
struct State {
    blocks: Vec<usize>,
    delay: i64,
}

struct Context<'a> {
    geometry: &'a Geometry,
    start: &'a Model,
    cands: Vec<Candidate>,
    train: &'a Dataset,
    train_p: Prepared,
    vals: &'a [Dataset],
    vals_p: Vec<Prepared>,
    base_samples: usize,
}

impl Context<'_> {
    fn model(&self, s: &State) -> Result<Model, IdentError> {
        let mut m = self.start.clone();
        for &i in &s.blocks {
            if let Candidate::Effect { effect } = self.cands[i] {
                m = m.with_effect(effect).map_err(|e| IdentError::Adapter {
                    context: "extending the model".into(),
                    message: e.to_string(),
                })?;
            }
        }
        Ok(m)
    }

    fn design(&self, p: &Prepared, data: &Dataset, s: &State) -> Design {
        let blocks: Vec<&Mat<f64>> = s
            .blocks
            .iter()
            .filter_map(|&i| p.blocks[i].as_ref())
            .collect();
        design(&p.base, &blocks, s.delay, data.periodic, &p.mask)
    }

    /// Fit on TRAIN and validation fitness of state `s`.
    fn run(&self, s: &State) -> Result<(BaseParameters, Fit, Vec<[f64; 2]>), IdentError> {
        let model = self.model(s)?;
        let base = crate::robot::base_parameters(
            &model,
            self.geometry,
            &Workspace::paper(),
            self.base_samples,
        )?;
        let f = fit(
            &self.design(&self.train_p, self.train, s),
            &base,
            self.train.periodic,
        )?;
        let fits = self
            .vals
            .iter()
            .zip(&self.vals_p)
            .map(|(v, p)| evaluate(&self.design(p, v, s), &base, &f.beta).map(|r| r.1))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((base, f, fits))
    }
}

fn mean_fit(v: &[[f64; 2]]) -> [f64; 2] {
    let k = v.len().max(1) as f64;
    [
        v.iter().map(|x| x[0]).sum::<f64>() / k,
        v.iter().map(|x| x[1]).sum::<f64>() / k,
    ]
}

fn describe(start: &Model, steps: &[Step]) -> String {
    let mut s: Vec<String> = start.effects().iter().map(|e| e.id().to_owned()).collect();
    s.extend(steps.iter().map(|st| st.label.clone()));
    s.join(" + ")
}

/// Runs the diagnosis: `start` (usually the paper's model) identified on
/// `train`, scored on `validation` (at least one set), candidates from
/// `opts.grid`, until no candidate is significant.
pub fn diagnose(
    start: &Model,
    geometry: &Geometry,
    train: &Dataset,
    validation: &[Dataset],
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, IdentError> {
    let clock = Instant::now();
    if validation.is_empty() {
        return Err(IdentError::InvalidSetting {
            name: "validation data sets",
            value: 0.0,
            reason: "give at least one validation log (e.g. --validate VAL.csv)",
        });
    }
    if !(opts.alpha > 0.0 && opts.alpha < 1.0) {
        return Err(IdentError::InvalidSetting {
            name: "alpha",
            value: opts.alpha,
            reason: "the significance level must lie in (0, 1), e.g. 0.01",
        });
    }
    if !(opts.min_gain.is_finite() && opts.min_gain >= 0.0) {
        return Err(IdentError::InvalidSetting {
            name: "min_gain",
            value: opts.min_gain,
            reason: "the minimum fitness gain must be a finite number of percentage points ≥ 0",
        });
    }
    train.check()?;
    for v in validation {
        v.check()?;
    }
    let cands: Vec<Candidate> = opts
        .grid
        .expand()
        .into_iter()
        .filter(|c| match c {
            Candidate::Effect { effect } => !start.effects().iter().any(|e| e.id() == effect.id()),
            Candidate::TimeDelay { .. } => true,
        })
        .collect();
    let prep = |d: &Dataset, tol: f64| -> Result<Prepared, IdentError> {
        let base = columns(start, geometry, d)?;
        let blocks = cands
            .par_iter()
            .map(|c| match c {
                Candidate::Effect { effect } => {
                    effect_columns(*effect, start.gravity(), geometry, d).map(Some)
                }
                Candidate::TimeDelay { .. } => Ok(None),
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mask = moving_mask(d, opts.min_speed, tol)?;
        Ok(Prepared { base, blocks, mask })
    };
    let ctx = Context {
        geometry,
        start,
        train_p: prep(train, opts.reach_tol)?,
        vals_p: validation
            .iter()
            .map(|v| prep(v, opts.validation_reach_tol))
            .collect::<Result<_, _>>()?,
        cands,
        train,
        vals: validation,
        base_samples: opts.base_samples.max(50),
    };
    // The filter's independent fraction of samples (= the σ correction's
    // noise gain, see `n_eff`), for the F-test's degrees of freedom.
    let dof_ratio = train.filter_dof() / train.len() as f64;

    let mut state = State {
        blocks: vec![],
        delay: 0,
    };
    let (mut cur_base, mut cur_fit, mut cur_val) = ctx.run(&state)?;
    let mut fitness_rows = vec![FitnessRow {
        step: 0,
        model: describe(start, &[]),
        fitness: cur_val.clone(),
    }];
    let initial_state = state.clone();
    let mut steps: Vec<Step> = Vec::new();
    let mut rounds = Vec::new();
    let mut used: Vec<&'static str> = Vec::new();
    let mut stopped_clean = false;
    while steps.len() < opts.max_steps {
        let trial: Vec<usize> = (0..ctx.cands.len())
            .filter(|&i| !used.contains(&ctx.cands[i].id()))
            .collect();
        if trial.is_empty() {
            break;
        }
        let level = opts.alpha / trial.len() as f64;
        let before = mean_fit(&cur_val);
        let p0 = cur_base.n_base();
        let scored: Vec<Scored> = trial
            .par_iter()
            .map(|&i| {
                let c = ctx.cands[i];
                let mut s = state.clone();
                match c {
                    Candidate::Effect { .. } => s.blocks.push(i),
                    Candidate::TimeDelay { samples } => s.delay = samples,
                }
                let (base, f, val) = match ctx.run(&s) {
                    Ok(x) => x,
                    // A candidate the kept rows do not excite (or that makes
                    // the fit rank deficient) is not evidence; it is scored
                    // as insignificant with the reason.
                    Err(e) => {
                        let score = CandidateScore {
                            candidate: c,
                            label: c.label(),
                            added_parameters: 0,
                            rss_drop_percent: 0.0,
                            n_eff: 0.0,
                            f: 0.0,
                            p_value: 1.0,
                            delta_bic: 0.0,
                            gain: [0.0; 2],
                            mean_gain: 0.0,
                            gain_per_set: vec![0.0; cur_val.len()],
                            significant: false,
                            note: e.to_string(),
                        };
                        return (i, score, s, None);
                    }
                };
                let added = match c {
                    Candidate::Effect { .. } => base.n_base().saturating_sub(p0),
                    Candidate::TimeDelay { .. } => 1,
                };
                let ne = n_eff(&f.residual, f.split, dof_ratio);
                let p1 = base.n_base() as f64;
                // A shifted record loses |d| rows: compare RSS per row.
                let rss0 = cur_fit.rss / cur_fit.residual.len() as f64;
                let rss1 = f.rss / f.residual.len() as f64;
                let drop = (rss0 - rss1) / rss0;
                let (fstat, p) = if added == 0 || ne <= p1 + 1.0 || rss1 <= 0.0 {
                    (0.0, 1.0)
                } else {
                    let k = added as f64;
                    let fs = ((rss0 - rss1) / k) / (rss1 / (ne - p1));
                    (fs.max(0.0), f_sf(fs, k, ne - p1))
                };
                let after = mean_fit(&val);
                let gain = [after[0] - before[0], after[1] - before[1]];
                let mean_gain = 0.5 * (gain[0] + gain[1]);
                let gain_per_set: Vec<f64> = val
                    .iter()
                    .zip(&cur_val)
                    .map(|(a, b)| 0.5 * ((a[0] - b[0]) + (a[1] - b[1])))
                    .collect();
                let every = gain_per_set.iter().all(|g| *g >= opts.min_gain);
                let score = CandidateScore {
                    candidate: c,
                    label: c.label(),
                    added_parameters: added,
                    rss_drop_percent: 100.0 * drop,
                    n_eff: ne,
                    f: fstat,
                    p_value: p,
                    delta_bic: if rss1 > 0.0 && rss0 > 0.0 && ne > 1.0 {
                        ne * (rss1 / rss0).ln() + added as f64 * ne.ln()
                    } else {
                        0.0
                    },
                    gain,
                    mean_gain,
                    gain_per_set,
                    significant: p < level && every,
                    note: String::new(),
                };
                let keep = score.significant.then_some((base, f, val));
                (i, score, s, keep)
            })
            .collect();
        let top = scored
            .iter()
            .filter(|x| x.1.significant)
            .min_by(|a, b| a.1.delta_bic.total_cmp(&b.1.delta_bic).then(a.0.cmp(&b.0)));
        // Candidates of other identifiers that explain the TRAIN data as
        // well as the best one (aliases) are listed with it; among them the
        // first in the library's order is named, so the choice does not hang
        // on round-off.
        let alias_of = |x: &Scored, best: &CandidateScore| {
            x.1.candidate.id() != best.candidate.id()
                && x.1.added_parameters == best.added_parameters
                && (x.1.rss_drop_percent - best.rss_drop_percent).abs()
                    <= 1e-3 * best.rss_drop_percent.abs()
        };
        let best = top.map(|t| {
            scored
                .iter()
                .filter(|x| x.1.significant && (x.0 == t.0 || alias_of(x, &t.1)))
                .map(|x| x.0)
                .min()
                .unwrap_or(t.0)
        });
        let mut round: Vec<CandidateScore> = scored.iter().map(|x| x.1.clone()).collect();
        round.sort_by(|a, b| b.mean_gain.total_cmp(&a.mean_gain));
        rounds.push(round);
        let Some(bi) = best else {
            stopped_clean = true;
            break;
        };
        let best_score = scored
            .iter()
            .find(|x| x.0 == bi)
            .map(|x| x.1.clone())
            .ok_or(IdentError::InvalidSetting {
                name: "selected candidate",
                value: bi as f64,
                reason: "internal: the selected candidate is missing from its round",
            })?;
        let mut aliases: Vec<String> = scored
            .iter()
            .filter(|x| x.0 != bi && alias_of(x, &best_score))
            .map(|x| x.1.candidate.id().to_owned())
            .collect();
        aliases.sort();
        aliases.dedup();
        let Some((i, score, s, Some((base, f, val)))) = scored.into_iter().find(|x| x.0 == bi)
        else {
            return Err(IdentError::InvalidSetting {
                name: "selected candidate",
                value: bi as f64,
                reason: "internal: a significant candidate lost its fit",
            });
        };
        let c = ctx.cands[i];
        let parameters = match c {
            Candidate::Effect { effect } => {
                // Base parameter k stands for standard column independent()[k]
                // (plus its regrouped aliases, none for an effect's own columns
                // unless they are collinear with the model's).
                let names = effect.names();
                let std_names = base.standard_names();
                base.independent()
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| names.contains(&std_names[**c]))
                    .map(|(k, _)| NamedValue {
                        name: base.expression(k),
                        value: f.beta[k],
                        std_dev: f.std_dev[k],
                    })
                    .collect()
            }
            Candidate::TimeDelay { samples } => vec![NamedValue {
                name: "delay_samples".into(),
                value: samples as f64,
                std_dev: 0.0,
            }],
        };
        used.push(c.id());
        state = s;
        steps.push(Step {
            id: c.id().to_owned(),
            label: c.label(),
            candidate: c,
            explanation: c.explanation().to_owned(),
            aliases,
            parameters,
            evidence: score,
        });
        fitness_rows.push(FitnessRow {
            step: steps.len(),
            model: describe(start, &steps),
            fitness: val.clone(),
        });
        cur_base = base;
        cur_fit = f;
        cur_val = val;
    }

    // Residual analyses before and after.
    let analyse_state = |s: &State, base: &BaseParameters, beta: &[f64]| {
        validation
            .iter()
            .zip(&ctx.vals_p)
            .map(|(v, p)| -> Result<ResidualAnalysis, IdentError> {
                let d = ctx.design(p, v, s);
                let (r, _) = evaluate(&d, base, beta)?;
                let m = d.split();
                let res = [&r[..m], &r[m..]];
                let sm = &v.samples;
                let rms = |x: &[f64]| {
                    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
                };
                let pick =
                    |x: &[f64], g: usize| -> Vec<f64> { d.idx[g].iter().map(|&i| x[i]).collect() };
                let cols: Vec<[Vec<f64>; 4]> = (0..2)
                    .map(|g| {
                        [
                            pick(&sm.theta[g], g),
                            pick(&sm.theta_dot[g], g),
                            pick(&sm.theta_ddot[g], g),
                            pick(&sm.t, g),
                        ]
                    })
                    .collect();
                let jd = |g: usize| JointData {
                    residual: res[g],
                    theta: &cols[g][0],
                    theta_dot: &cols[g][1],
                    theta_ddot: &cols[g][2],
                    t: &cols[g][3],
                };
                let sigma = [rms(res[0]), rms(res[1])];
                Ok(analyse(
                    &v.name,
                    &[jd(0), jd(1)],
                    sigma,
                    v.filter_dof() / v.len() as f64,
                ))
            })
            .collect::<Result<Vec<_>, _>>()
    };
    let (b0, f0, _) = ctx.run(&initial_state)?;
    let before = analyse_state(&initial_state, &b0, &f0.beta)?;
    let after = analyse_state(&state, &cur_base, &cur_fit.beta)?;
    let white = after
        .iter()
        .all(|a| a.whiteness.iter().all(|w| w.is_white()));
    let systematic = after
        .iter()
        .any(|a| a.findings.iter().any(|f| f.systematic));
    let noise_like = stopped_clean && white && !systematic;
    let added = if steps.is_empty() {
        "No effect was added".to_owned()
    } else {
        format!(
            "Added, in order: {}",
            steps
                .iter()
                .map(|s| s.label.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let conclusion = if !stopped_clean {
        format!(
            "{added}; stopped at the step limit ({}) or with every candidate used.",
            opts.max_steps
        )
    } else if noise_like {
        format!(
            "{added}. No remaining candidate is significant and the validation residual is \
             noise-like (white by Ljung–Box at 1 %, no bin beyond {:.0} standard errors).",
            super::residual::Z_SYSTEMATIC
        )
    } else {
        format!(
            "{added}. No remaining candidate is significant, but the validation residual is \
             not noise-like ({}{}): the rest is an effect outside the candidate library or a \
             processing artefact.",
            if white { "white" } else { "not white" },
            if systematic {
                ", systematic bins remain"
            } else {
                ""
            }
        )
    };

    let final_model = ctx.model(&state)?;
    let estimate = cur_base
        .base_names()
        .iter()
        .enumerate()
        .map(|(k, _)| NamedValue {
            name: cur_base.expression(k),
            value: cur_fit.beta[k],
            std_dev: cur_fit.std_dev[k],
        })
        .collect();
    let consistent = match &opts.reference {
        Some(reference) if final_model.effects().contains(&Effect::RigidLinks) => Some(
            consistent_fit(&ctx, &state, &final_model, &cur_base, reference)?,
        ),
        _ => None,
    };
    Ok(Diagnosis {
        initial_model: start.effects().to_vec(),
        final_model: final_model.effects().to_vec(),
        delay_samples: state.delay,
        steps,
        rounds,
        fitness: fitness_rows,
        before,
        after,
        noise_like,
        conclusion,
        estimate,
        consistent,
        elapsed_s: clock.elapsed().as_secs_f64(),
    })
}

/// Friction-like levels that must not be negative (dissipation).
const NONNEGATIVE: [&str; 7] = ["Fs1", "Fs2", "Fpb", "Fpc", "Fpd", "Fq1", "Fq2"];

fn consistent_fit(
    ctx: &Context<'_>,
    s: &State,
    model: &Model,
    base: &BaseParameters,
    reference: &Params,
) -> Result<ConsistentFit, IdentError> {
    let mut problem = consistent_problem(model, reference)?;
    let names = model.names();
    let extra: Vec<&str> = NONNEGATIVE
        .iter()
        .copied()
        .filter(|n| names.iter().any(|m| m == n))
        .collect();
    problem.nonnegative(&extra)?;
    let d = ctx.design(&ctx.train_p, ctx.train, s);
    let wb = base.base_regressor(d.w.as_ref())?;
    let red = ReducedLs::new(wb.as_ref(), &d.t, &base.base_names())?;
    let sol = problem.solve(base, &red)?;
    let beta_b = base.to_base(&sol.standard)?;
    let fitness = ctx
        .vals
        .iter()
        .zip(&ctx.vals_p)
        .map(|(v, p)| evaluate(&ctx.design(p, v, s), base, &beta_b).map(|r| r.1))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(ConsistentFit {
        status: sol.status.clone(),
        fitness,
        parameters: names
            .iter()
            .zip(&sol.standard)
            .map(|(n, v)| NamedValue {
                name: n.clone(),
                value: *v,
                std_dev: 0.0,
            })
            .collect(),
    })
}
