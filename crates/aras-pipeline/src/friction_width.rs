//! The friction effect's Coulomb transition widths `w_j` (`Fc_j tanh(θ̇_j /
//! w_j)`, `w = 0` the sign law (49)), refined on a prepared log by the one
//! refinement of the workspace ([`crate::refine`]): the profile RSS of the
//! least-squares fit over `ln w_j`, one joint at a time (a width changes
//! only joint `j`'s `Fc_j` column on joint `j`'s rows), alternating; `w = 0`
//! is a candidate too. Where a width is not identifiable, that joint falls
//! back to the rows away from its velocity reversals with the sign law.

use crate::PipelineError;
use aras_dyn::{Effect, Model};
use aras_ident::{BaseParameters, IdentError, ReducedLs};
use faer::Mat;
use serde::{Deserialize, Serialize};

use crate::prepare::Prepared;
use crate::refine::minimise_profile;
use crate::robot::FilterMode;

/// Which rows identification fits (`identification.rows`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitRows {
    /// Every row, with the Coulomb widths refined ([`refine_widths`]); a
    /// joint whose width is not identifiable falls back to
    /// [`FitRows::AwayFromReversals`]. The default: no drive reverses
    /// instantly, and the rows near reversals are where real friction and
    /// the paper's model disagree most (`docs/model.md`, "The Coulomb law").
    #[default]
    All,
    /// The rows of each joint away from its velocity reversals
    /// (`identification.min_speed`, widened by the filter's reach), the sign
    /// law (49) (`w = 0`): the paper's choice, and the robust fallback for a
    /// log whose low-speed regime cannot be estimated.
    AwayFromReversals,
}

/// How the widths are searched.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WidthSearch {
    /// Smallest width searched (rad/s, > 0).
    pub min: f64,
    /// Largest width searched (rad/s, > `min`).
    pub max: f64,
    /// Rounds of refining joint 1 then joint 2 (≥ 1).
    pub rounds: usize,
    /// Most that fitting every row may cost the rows away from velocity
    /// reversals, in points of fitness (78) per joint ([`moving_rows_cost`];
    /// default 1). Where the Coulomb law describes the reversals, the extra
    /// rows cost the others next to nothing (simulated, default excitation:
    /// ≤ 0.006 points without a hidden effect, ≤ 0.45 with a Stribeck hump
    /// `Fs = 1.3 Fc` at `v_s` = 0.015–0.07 rad/s); where the joints stick
    /// or preslide (LuGre friction, a state the law cannot hold) the fit
    /// trades the moving rows for the reversals: 1.9–8.5 points over four
    /// LuGre settings, with inertial parameters biased many times their
    /// σ. Such a joint falls back to the rows away from its reversals.
    pub max_moving_rows_cost: f64,
}

impl Default for WidthSearch {
    fn default() -> Self {
        Self {
            min: 1e-4,
            max: 1.0,
            rounds: 2,
            max_moving_rows_cost: 1.0,
        }
    }
}

impl WidthSearch {
    /// Errors unless `0 < min < max` (finite) and `rounds ≥ 1`.
    pub fn validate(&self) -> Result<(), PipelineError> {
        if !(self.min.is_finite() && self.max.is_finite() && self.min > 0.0 && self.max > self.min)
        {
            return Err(PipelineError::InvalidSetting {
                name: "Coulomb width search interval",
                value: self.min,
                reason: "give 0 < min < max in rad/s (e.g. 1e-4 … 1)",
            });
        }
        if !(self.max_moving_rows_cost.is_finite() && self.max_moving_rows_cost >= 0.0) {
            return Err(PipelineError::InvalidSetting {
                name: "most that every row may cost the moving rows",
                value: self.max_moving_rows_cost,
                reason: "give a finite number of fitness points ≥ 0 (e.g. 0.5)",
            });
        }
        if self.rounds == 0 {
            return Err(PipelineError::InvalidSetting {
                name: "Coulomb width search rounds",
                value: 0.0,
                reason: "give at least 1 round",
            });
        }
        Ok(())
    }
}

/// What the refinement found for one joint's width.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WidthStatus {
    /// An interior minimum of the profile with σ from its curvature; the
    /// joint is fitted on every row.
    Refined,
    /// The sign law (`w = 0`) fits every row at least as well as any width
    /// in the interval, or the model holds a bristle (a friction state,
    /// `presliding_friction`) that describes the reversals and leaves the
    /// width unidentifiable; the joint is fitted on every row with `w = 0`.
    SignLaw,
    /// The minimum lies at an end of the interval, or the profile has no
    /// curvature there: the width is not identifiable from this log, so the
    /// joint falls back to the rows away from its reversals, with `w = 0`.
    NotIdentifiable,
    /// A width was refined, but fitting every row costs this joint's rows
    /// away from reversals more than [`WidthSearch::max_moving_rows_cost`]:
    /// the Coulomb law does not describe this log's reversals (sticking,
    /// presliding), so the joint falls back to the rows away from them. The
    /// refined width is kept: it changes nothing on those rows, and it
    /// predicts the reversals better than the sign law (on a simulated
    /// LuGre joint, (78) on every row of a 0.7 Hz validation log 94.6 /
    /// 85.9 % against 93.0 / 77.7 % with `w = 0`).
    ReversalsNotDescribed,
    /// `identification.rows = "away_from_reversals"`: not refined.
    NotRefined,
}

/// One joint's width.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct JointWidth {
    /// The width used (rad/s; 0 = the sign law).
    pub w: f64,
    /// Its standard deviation from the profile's curvature (rad/s; 0 if
    /// unknown).
    pub std_dev: f64,
    /// What the refinement found.
    pub status: WidthStatus,
    /// True when the joint is fitted on every row, false when on the rows
    /// away from its velocity reversals.
    pub all_rows: bool,
    /// The minimum of the profile (rad/s), whatever was used.
    pub profile_minimum: f64,
    /// What fitting every row cost the joint's rows away from reversals
    /// (points of fitness (78), [`moving_rows_cost`]); 0 when not checked.
    pub moving_rows_cost: f64,
}

/// The widths of both joints, with the reason of any fallback.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WidthRefinement {
    /// Joint 1, joint 2.
    pub joints: [JointWidth; 2],
    /// Why a joint fell back to the rows away from reversals (empty if
    /// none did).
    pub fallback: Vec<String>,
}

impl WidthRefinement {
    /// The widths used, `[w1, w2]` (rad/s).
    pub fn widths(&self) -> [f64; 2] {
        self.joints.map(|j| j.w)
    }

    /// The setting `rows = "away_from_reversals"`: sign law, no refinement.
    pub fn not_refined() -> Self {
        let j = JointWidth {
            w: 0.0,
            std_dev: 0.0,
            status: WidthStatus::NotRefined,
            all_rows: false,
            profile_minimum: 0.0,
            moving_rows_cost: 0.0,
        };
        Self {
            joints: [j, j],
            fallback: Vec::new(),
        }
    }

    /// Every joint falls back (the refinement failed with `reason`).
    pub fn failed(reason: String) -> Self {
        let j = JointWidth {
            w: 0.0,
            std_dev: 0.0,
            status: WidthStatus::NotIdentifiable,
            all_rows: false,
            profile_minimum: 0.0,
            moving_rows_cost: 0.0,
        };
        Self {
            joints: [j, j],
            fallback: vec![format!(
                "the width refinement failed ({reason}); both joints use the rows away from \
                 their velocity reversals with the sign law (49)"
            )],
        }
    }

    /// The rows to fit, joint-major: every row of a joint fitted on all
    /// rows, `away` (the reversal mask) on the others.
    pub fn keep(&self, away: &[bool]) -> Vec<bool> {
        let n = away.len() / 2;
        away.iter()
            .enumerate()
            .map(|(i, &k)| self.joints[i / n.max(1)].all_rows || k)
            .collect()
    }

    /// One sentence per joint for a report.
    pub fn sentence(&self) -> String {
        let mut s = String::from("Coulomb transition width w (Fc tanh(θ̇/w); 0 = sign (49)): ");
        let parts: Vec<String> = self
            .joints
            .iter()
            .enumerate()
            .map(|(j, x)| {
                let rows = if x.all_rows {
                    "all rows"
                } else {
                    "rows away from reversals"
                };
                match x.status {
                    WidthStatus::Refined => format!(
                        "joint {}: {:.4} ± {:.4} rad/s ({rows})",
                        j + 1,
                        x.w,
                        x.std_dev
                    ),
                    WidthStatus::SignLaw => {
                        format!("joint {}: 0, the sign law fits best ({rows})", j + 1)
                    }
                    WidthStatus::NotIdentifiable => format!(
                        "joint {}: not identifiable (profile minimum {:.3e} rad/s), sign law on \
                         the {rows}",
                        j + 1,
                        x.profile_minimum
                    ),
                    WidthStatus::NotRefined => format!("joint {}: 0, not refined ({rows})", j + 1),
                    WidthStatus::ReversalsNotDescribed => format!(
                        "joint {}: {:.4} rad/s does not describe the reversals (every row \
                         costs the moving rows {:.2} points), fitted on the {rows}",
                        j + 1,
                        x.w,
                        x.moving_rows_cost
                    ),
                }
            })
            .collect();
        s += &parts.join("; ");
        s.push('.');
        for f in &self.fallback {
            s += " ";
            s += f;
        }
        s
    }
}

/// The friction effect of `model` with the widths `w`, in place of its own.
pub fn with_widths(model: &Model, w: [f64; 2]) -> Result<Model, PipelineError> {
    let effects: Vec<Effect> = model
        .effects()
        .iter()
        .map(|e| match e {
            Effect::Friction { .. } => Effect::Friction { w },
            other => *other,
        })
        .collect();
    Model::new(effects, model.gravity())
        .map_err(|e| IdentError::external("the model with the Coulomb widths", e))
        .map_err(PipelineError::from)
}

/// Column of `Fc_j` in `model`, or an error naming the missing effect.
fn coulomb_column(model: &Model, j: usize) -> Result<usize, PipelineError> {
    model
        .column_range("friction")
        .map(|r| r.start + 1 + 2 * j)
        .ok_or(PipelineError::MissingEffect {
            effect: "friction",
            needed_by: "refining the Coulomb transition widths",
        })
}

/// Joint `j`'s Coulomb column (`2N` rows, zero on the other joint's) at width
/// `w`, filtered as `prepared`'s regressor was (`mode`).
fn coulomb_values(
    prepared: &Prepared,
    mode: FilterMode,
    j: usize,
    w: f64,
) -> Result<Mat<f64>, PipelineError> {
    let v = &prepared.processed.samples.theta_dot[j];
    let n = v.len();
    let mut c = Mat::zeros(2 * n, 1);
    for (i, x) in v.iter().enumerate() {
        c[(j * n + i, 0)] = aras_dyn::coulomb_law(*x, w);
    }
    prepared.limit_columns(&mut c, mode)?;
    Ok(c)
}

/// Writes joint `j`'s Coulomb column at width `w` into `prepared`'s
/// regressor (filtered as it was) and its unfiltered copy.
fn write_column(
    prepared: &mut Prepared,
    mode: FilterMode,
    col: usize,
    j: usize,
    w: f64,
) -> Result<(), PipelineError> {
    let filtered = coulomb_values(prepared, mode, j, w)?;
    let n = prepared.n();
    for i in 0..2 * n {
        prepared.stacked.w[(i, col)] = filtered[(i, 0)];
    }
    if let Some(u) = prepared.unfiltered.as_mut() {
        let v = &prepared.processed.samples.theta_dot[j];
        for i in 0..2 * n {
            u.w[(i, col)] = if i / n == j {
                aras_dyn::coulomb_law(v[i - j * n], w)
            } else {
                0.0
            };
        }
    }
    Ok(())
}

/// Sets both widths: `prepared`'s Coulomb columns (filtered and unfiltered)
/// and the model's friction effect. Returns the model with the widths.
pub(crate) fn apply_widths(
    prepared: &mut Prepared,
    model: &Model,
    mode: FilterMode,
    w: [f64; 2],
) -> Result<Model, PipelineError> {
    for (j, wj) in w.iter().enumerate() {
        write_column(prepared, mode, coulomb_column(model, j)?, j, *wj)?;
    }
    with_widths(model, w)
}

/// Refines both widths on every row of `prepared` (stacked with `model`,
/// filtered with `mode`), `base` its base parameters: the weighted RSS of
/// the least-squares fit (rows weighted by `1/σ_j` of each joint's residual
/// at the start) as a profile over `u = ln w_j` in `[ln min, ln max]`,
/// [`minimise_profile`]; σ_w = w σ_u from the curvature with `n_eff = 2N ×
/// noise_gain` (the filter leaves `noise_gain` of white noise's power, so
/// about that fraction of the rows carry independent residuals). `w = 0` is
/// compared at the end. Leaves `prepared`'s columns at the widths returned
/// (0 on a joint that fell back).
pub fn refine_widths(
    prepared: &mut Prepared,
    model: &Model,
    base: &BaseParameters,
    mode: FilterMode,
    search: &WidthSearch,
) -> Result<WidthRefinement, PipelineError> {
    search.validate()?;
    let n = prepared.n();
    let cols = [coulomb_column(model, 0)?, coulomb_column(model, 1)?];
    let names = base.base_names();
    let gain = prepared.noise_gain()?;
    let n_eff = 2.0 * n as f64 * gain;
    // Start in the middle of the interval (log scale).
    let mut w = [(search.min * search.max).sqrt(); 2];
    for j in 0..2 {
        write_column(prepared, mode, cols[j], j, w[j])?;
    }
    // Row weights 1/σ_j from the residual of the fit at the start.
    let w_b = base.base_regressor(prepared.stacked.w.as_ref())?;
    let fit = ReducedLs::new(w_b.as_ref(), &prepared.stacked.t, &names)?.ols()?;
    let pred = aras_ident::validate::predict(w_b.as_ref(), &fit.estimate)?;
    let t = &prepared.stacked.t;
    let sd: Vec<f64> = (0..2)
        .map(|j| {
            let r: f64 = (j * n..(j + 1) * n).map(|i| (t[i] - pred[i]).powi(2)).sum();
            (r / n as f64).sqrt().max(f64::MIN_POSITIVE)
        })
        .collect();
    let weights: Vec<f64> = (0..2 * n).map(|i| 1.0 / sd[i / n]).collect();
    let rss_at = |p: &Prepared, col: usize, j: usize, wj: f64| -> Result<f64, IdentError> {
        let c = coulomb_values(p, mode, j, wj).map_err(PipelineError::into_ident)?;
        let mut wm = p.stacked.w.clone();
        for i in 0..2 * n {
            wm[(i, col)] = c[(i, 0)];
        }
        let wb = base.base_regressor(wm.as_ref())?;
        Ok(ReducedLs::weighted(wb.as_ref(), &p.stacked.t, &names, &weights)?.min_rss())
    };
    let (lo, hi) = (search.min.ln(), search.max.ln());
    let mut out: [Option<crate::refine::ProfileMinimum>; 2] = [None, None];
    for _ in 0..search.rounds {
        for j in 0..2 {
            let snapshot: &Prepared = prepared;
            let min = minimise_profile(&[(lo, hi)], |us: &[f64]| {
                us.iter()
                    .map(|u| rss_at(snapshot, cols[j], j, u.exp()))
                    .collect::<Result<Vec<_>, _>>()
            })?;
            w[j] = min.u.exp();
            write_column(prepared, mode, cols[j], j, w[j])?;
            out[j] = Some(min);
        }
    }
    let mut joints = [JointWidth {
        w: 0.0,
        std_dev: 0.0,
        status: WidthStatus::NotIdentifiable,
        all_rows: false,
        profile_minimum: 0.0,
        moving_rows_cost: 0.0,
    }; 2];
    let mut fallback = Vec::new();
    // With a bristle (a friction state) in the model the Coulomb column is
    // redundant with it while sliding, and its width need not be
    // identifiable: the bristle describes the reversals, so the joint keeps
    // every row with the sign law (the moving-rows check still guards it).
    let bristle = model.has_state();
    for j in 0..2 {
        let Some(min) = &out[j] else { continue };
        let wj = min.u.exp();
        let at_w = rss_at(prepared, cols[j], j, wj)?;
        let at_zero = rss_at(prepared, cols[j], j, 0.0)?;
        let sigma = min.std_dev(n_eff);
        joints[j] = if at_zero <= at_w || (sigma.is_none() && bristle) {
            JointWidth {
                w: 0.0,
                std_dev: 0.0,
                status: WidthStatus::SignLaw,
                all_rows: true,
                profile_minimum: wj,
                moving_rows_cost: 0.0,
            }
        } else if let Some(su) = sigma {
            JointWidth {
                w: wj,
                std_dev: wj * su,
                status: WidthStatus::Refined,
                all_rows: true,
                profile_minimum: wj,
                moving_rows_cost: 0.0,
            }
        } else {
            fallback.push(format!(
                "joint {}: the RSS profile over w has its minimum at {wj:.3e} rad/s, {} of the \
                 search interval {:.0e} … {:.0e} rad/s, so the width is not identifiable from \
                 this log; the joint is fitted on the rows away from its velocity reversals \
                 with the sign law (49)",
                j + 1,
                if min.at_bound {
                    "at an end"
                } else {
                    "on a flat stretch"
                },
                search.min,
                search.max
            ));
            JointWidth {
                w: 0.0,
                std_dev: 0.0,
                status: WidthStatus::NotIdentifiable,
                all_rows: false,
                profile_minimum: wj,
                moving_rows_cost: 0.0,
            }
        };
    }
    for j in 0..2 {
        write_column(prepared, mode, cols[j], j, joints[j].w)?;
    }
    Ok(WidthRefinement { joints, fallback })
}

/// What fitting every row costs the rows away from velocity reversals,
/// per joint: the fitness (78) on `away`'s rows (joint-major reversal mask)
/// of the least-squares fit on those rows, minus that of the fit on
/// `keep` (every row of the joints fitted on all rows, `away`'s of the
/// others), both on `prepared`'s filtered torques and base regressor
/// `base`. ≥ 0 up to rounding: the first fit is the best possible there.
///
/// Under a model that describes the reversals the two fits estimate the
/// same parameters and the cost is of the order of the parameters'
/// noise share (≪ 0.1 point); a friction the Coulomb law cannot follow
/// (sticking, presliding, a Stribeck hump far from `tanh`) pulls the
/// every-row fit away from the moving rows.
pub fn moving_rows_cost(
    prepared: &Prepared,
    base: &BaseParameters,
    away: &[bool],
    keep: &[bool],
) -> Result<[f64; 2], PipelineError> {
    let names = base.base_names();
    let fit_on = |rows: &[bool]| -> Result<Vec<f64>, IdentError> {
        let st =
            crate::robot::keep_rows(&prepared.stacked, rows).map_err(PipelineError::into_ident)?;
        let wb = base.base_regressor(st.w.as_ref())?;
        Ok(ReducedLs::new(wb.as_ref(), &st.t, &names)?.ols()?.estimate)
    };
    let on_away = crate::robot::keep_rows(&prepared.stacked, away)?;
    let best = crate::identify::fitness_of(&on_away, base, &fit_on(away)?)?;
    let every = crate::identify::fitness_of(&on_away, base, &fit_on(keep)?)?;
    Ok([best[0] - every[0], best[1] - every[1]])
}

/// [`refine_widths`], then the check that fitting every row does not cost
/// the rows away from reversals (`away`, the joint-major reversal mask)
/// more than `search.max_moving_rows_cost` on any joint
/// ([`moving_rows_cost`]): the joints beyond it fall back to those rows
/// ([`WidthStatus::ReversalsNotDescribed`]), the worst first, and the
/// others are checked again without them. A refinement that
/// fails falls back on both joints ([`WidthRefinement::failed`]).
pub(crate) fn refine_checked_widths(
    prepared: &mut Prepared,
    model: &Model,
    base: &BaseParameters,
    mode: FilterMode,
    search: &WidthSearch,
    away: &[bool],
) -> Result<WidthRefinement, PipelineError> {
    let mut r = match refine_widths(prepared, model, base, mode, search) {
        Ok(r) => r,
        Err(e) => return Ok(WidthRefinement::failed(e.to_string())),
    };
    while r.joints.iter().any(|j| j.all_rows) {
        let cost = moving_rows_cost(prepared, base, away, &r.keep(away))?;
        for j in 0..2 {
            if r.joints[j].all_rows {
                r.joints[j].moving_rows_cost = cost[j].max(0.0);
            }
        }
        let worst = (0..2)
            .filter(|&j| r.joints[j].all_rows && cost[j] > search.max_moving_rows_cost)
            .max_by(|&a, &b| cost[a].total_cmp(&cost[b]));
        let Some(j) = worst else { break };
        let x = &mut r.joints[j];
        r.fallback.push(format!(
            "joint {}: fitting every row with w = {:.4} rad/s costs its rows away from velocity \
             reversals {:.2} points of fitness (78) (more than {}): the Coulomb law does not \
             describe this log's reversals (sticking, presliding: a friction with an internal \
             state), so the joint is fitted on the rows away from its reversals (the width is \
             kept for predicting them)",
            j + 1,
            x.w,
            x.moving_rows_cost,
            search.max_moving_rows_cost
        ));
        x.status = WidthStatus::ReversalsNotDescribed;
        x.all_rows = false;
    }
    Ok(r)
}
