//! Isolated glitches: single samples far off their neighbours (a bad
//! encoder read, a torque spike), found with robust statistics and reported
//! by file line and column, then refused, kept, dropped or repaired.
//!
//! * Angles: the residual of each sample against the cubic through its
//!   four neighbours at their logged times (on a uniform grid
//!   `r_i = θ_i − (−θ_{i−2} + 4θ_{i−1} + 4θ_{i+1} − θ_{i+2})/6`), so jitter
//!   and missing samples are not glitches.
//!   A smooth motion leaves `O(h⁴ θ⁗)` (nothing at 1 kHz), noise and encoder
//!   quantisation a few counts; a spike of height `A` leaves `A` at its
//!   sample and `2A/3` at its neighbours, so it is flagged where `|r|` is
//!   largest.
//! * Torques: a Hampel-type residual against the median of the six
//!   neighbours (three each side; exact on a ramp), taken as the distance to
//!   the nearest of that median and the linear extrapolations from the left
//!   and from the right: a sample on either side of a step (the sharp
//!   torque reversal of Coulomb friction) is near one of them and is not a
//!   glitch; a single spike is far from all three.
//!
//! The scale of each channel is the median absolute deviation (×1.4826, σ
//! for Gaussian noise) of its residuals (for torques: against the median); a sample is a glitch when its residual
//! exceeds [`GlitchOptions::threshold`] scales and is the largest within
//! ±2 (±3) samples. The scale is at least [`ANGLE_FLOOR`] /
//! [`TORQUE_FLOOR`] of the channel's range, and for quantised angles at
//! least the encoder step, so a motionless joint or a noise-free record (a
//! MAD of 0) does not turn single counts or curvature into glitches.

use serde::{Deserialize, Serialize};

use crate::header::{Field, Role};
use crate::{Log, LogError, Warning};

/// Default [`GlitchOptions::threshold`]: 10 robust standard deviations. For
/// Gaussian noise a false alarm is a 10σ event (p ≈ 1.5·10⁻²³ a sample);
/// a gross glitch sits tens to thousands of σ away.
pub const DEFAULT_GLITCH_THRESHOLD: f64 = 10.0;

/// Least scale of an angle channel, as a share of its range: a noise-free
/// record (a simulation) has a MAD near 0, and its start-up transient
/// would otherwise stand out; with the default threshold a glitch is then
/// at least 0.1 % of the range off.
pub const ANGLE_FLOOR: f64 = 1e-4;

/// Least scale of a torque channel, as a share of its range (a glitch is
/// then at least 1 % of the range off with the default threshold).
pub const TORQUE_FLOOR: f64 = 1e-3;

/// Glitches listed in messages; more are counted.
const LISTED: usize = 10;

/// What to do with glitches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GlitchAction {
    /// Refuse the log, naming the lines.
    Refuse,
    /// Keep the samples as they are, with a warning naming the lines and
    /// the other actions (default: a silent repair would hide a sensor
    /// fault, and a refusal would block healthy logs whose torque chatters
    /// at reversals, which a neighbour test cannot tell from a glitch).
    #[default]
    Warn,
    /// Remove the rows (the time grid then has holes: the processing
    /// interpolates onto a uniform grid).
    Drop,
    /// Replace each sample by the interpolation of its neighbours (angles:
    /// the cubic through the four neighbours; torques: their median).
    Repair,
    /// Do not look for glitches.
    Off,
}

impl GlitchAction {
    /// The name used in config files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Refuse => "refuse",
            Self::Warn => "warn",
            Self::Drop => "drop",
            Self::Repair => "repair",
            Self::Off => "off",
        }
    }
}

/// Options of [`find_glitches`] and [`apply_glitches`]. `Default` gives the
/// documented defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GlitchOptions {
    /// What to do (default [`GlitchAction::Warn`]).
    pub action: GlitchAction,
    /// Residual, in robust standard deviations of the channel, beyond which
    /// an isolated sample is a glitch (default
    /// [`DEFAULT_GLITCH_THRESHOLD`]).
    pub threshold: f64,
    /// The robot's torque limits (N·m), one per joint, if known: a torque
    /// beyond `limit_factor` times its limit is a glitch too.
    pub torque_limit: Option<Vec<f64>>,
    /// Factor on [`torque_limit`](Self::torque_limit) (default 1.5: a
    /// controller saturates at its limit, so half as much again is not a
    /// real torque).
    pub limit_factor: f64,
}

impl Default for GlitchOptions {
    fn default() -> Self {
        Self {
            action: GlitchAction::Warn,
            threshold: DEFAULT_GLITCH_THRESHOLD,
            torque_limit: None,
            limit_factor: 1.5,
        }
    }
}

/// Why a sample is a glitch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GlitchKind {
    /// Far off its neighbours.
    Spike,
    /// A torque beyond the stated limit by more than the factor.
    BeyondLimit,
}

/// One glitch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Glitch {
    /// Row index (0-based, data rows).
    pub row: usize,
    /// File line, if known.
    pub line: Option<u64>,
    /// 1-based file column of the channel's field (0 if unknown).
    pub column: usize,
    /// `theta1`, `theta2`, …, `tau1`, `tau2`, ….
    pub channel: String,
    /// The sample (rad or N·m).
    pub value: f64,
    /// What its neighbours say it should be (the repair value).
    pub expected: f64,
    /// `|value − expected|` in robust standard deviations of the channel.
    pub score: f64,
    /// Why.
    pub kind: GlitchKind,
}

impl std::fmt::Display for Glitch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.line {
            Some(l) => write!(f, "line {l}")?,
            None => write!(f, "row {}", self.row + 1)?,
        }
        if self.column > 0 {
            write!(f, ", column {}", self.column)?;
        }
        write!(
            f,
            ": {} = {} where its neighbours give {:.6}",
            self.channel, self.value, self.expected
        )?;
        match self.kind {
            GlitchKind::Spike => write!(f, " ({:.0} robust σ off)", self.score),
            GlitchKind::BeyondLimit => write!(f, " (beyond the stated torque limit)"),
        }
    }
}

/// Median of a small slice (sorted in place).
fn median(v: &mut [f64]) -> f64 {
    v.sort_unstable_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Robust scale: 1.4826 × the median of `|r|` over the finite entries.
fn mad_scale(r: &[f64]) -> f64 {
    let mut a: Vec<f64> = r
        .iter()
        .filter(|v| v.is_finite())
        .map(|v| v.abs())
        .collect();
    if a.is_empty() {
        return 0.0;
    }
    let mid = a.len() / 2;
    let (_, m, _) = a.select_nth_unstable_by(mid, f64::total_cmp);
    1.4826 * *m
}

/// Smallest positive step between consecutive samples that is clearly
/// above rounding: the quantisation step of an encoder channel.
fn quantum(x: &[f64]) -> f64 {
    let top = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let eps = 1e-12 * top.max(1e-300);
    x.windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > eps)
        .fold(f64::INFINITY, f64::min)
}

/// `(expected, residual)` of every sample of an angle channel: expected is
/// the cubic through the two neighbours on each side at their logged
/// times, evaluated at the sample's time (NaN residual for the first and
/// last two samples).
fn angle_residuals(t: &[f64], x: &[f64]) -> Vec<(f64, f64)> {
    let n = x.len();
    (0..n)
        .map(|i| {
            if i < 2 || i + 2 >= n {
                return (x[i], f64::NAN);
            }
            let idx = [i - 2, i - 1, i + 1, i + 2];
            let mut e = 0.0;
            for &j in &idx {
                let mut w = 1.0;
                for &k in &idx {
                    if k != j {
                        w *= (t[i] - t[k]) / (t[j] - t[k]);
                    }
                }
                e += w * x[j];
            }
            (e, x[i] - e)
        })
        .collect()
}

/// `(expected, residual, scale residual)` of every sample of a torque
/// channel: expected is the median of three neighbours on each side (exact
/// on a ramp); the residual is the distance to the nearest of it and the
/// linear extrapolations from either side, so a sample next to a step (a
/// friction reversal) is near one of them and is not off. The scale
/// residual is the distance to the median alone: the noise the scale is
/// measured from (the nearest of three would understate it).
fn torque_residuals(t: &[f64], x: &[f64]) -> Vec<(f64, f64, f64)> {
    let n = x.len();
    let mut w = Vec::with_capacity(6);
    (0..n)
        .map(|i| {
            if i < 3 || i + 3 >= n {
                return (x[i], f64::NAN, f64::NAN);
            }
            w.clear();
            w.extend_from_slice(&x[i - 3..i]);
            w.extend_from_slice(&x[i + 1..i + 4]);
            let e = median(&mut w);
            let left = x[i - 1] + (x[i - 1] - x[i - 2]) * (t[i] - t[i - 1]) / (t[i - 1] - t[i - 2]);
            let right =
                x[i + 1] + (x[i + 1] - x[i + 2]) * (t[i + 1] - t[i]) / (t[i + 2] - t[i + 1]);
            let d = [x[i] - e, x[i] - left, x[i] - right]
                .into_iter()
                .min_by(|a, b| a.abs().total_cmp(&b.abs()))
                .unwrap_or(f64::NAN);
            (e, d, x[i] - e)
        })
        .collect()
}

/// Finds the isolated glitches of `log` (sorted by row, then channel).
/// Nothing is found in logs shorter than 7 rows, or with
/// [`GlitchAction::Off`].
pub fn find_glitches(log: &Log, opts: &GlitchOptions) -> Vec<Glitch> {
    let mut out = Vec::new();
    if opts.action == GlitchAction::Off || log.len() < 7 {
        return out;
    }
    let joints = log.joints();
    for c in 0..2 * joints {
        let angle = c < joints;
        let x: &[f64] = if angle {
            &log.theta[c]
        } else {
            &log.tau[c - joints]
        };
        let channel = if angle {
            Field::Joint(Role::Theta, c)
        } else {
            Field::Joint(Role::Tau, c - joints)
        }
        .name();
        let (res, reach) = if angle {
            let a = angle_residuals(&log.t, x);
            (a.into_iter().map(|(e, r)| (e, r, r)).collect::<Vec<_>>(), 2)
        } else {
            (torque_residuals(&log.t, x), 3)
        };
        let r: Vec<f64> = res.iter().map(|p| p.1).collect();
        let for_scale: Vec<f64> = res.iter().map(|p| p.2).collect();
        let (lo, hi) = x
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        let floor_share = if angle { ANGLE_FLOOR } else { TORQUE_FLOOR };
        let mut scale = mad_scale(&for_scale).max(floor_share * (hi - lo));
        if angle {
            let q = quantum(x);
            if q.is_finite() {
                scale = scale.max(q);
            }
        }
        // A channel without any spread (constant, or exactly smooth) has no
        // noise to measure against: only rounding-level residuals are
        // ignored.
        let top = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let floor = 1e-9 * top.max(1e-12);
        let limit = opts
            .torque_limit
            .as_deref()
            .filter(|_| !angle)
            .and_then(|l| l.get(c - joints))
            .map(|l| l.abs() * opts.limit_factor);
        for i in 0..x.len() {
            let (expected, ri, _) = res[i];
            let beyond = limit.is_some_and(|l| x[i].abs() > l);
            let spike = ri.is_finite() && {
                let a = ri.abs();
                a > floor
                    && a > opts.threshold * scale
                    && (i.saturating_sub(reach)..(i + reach + 1).min(x.len()))
                        .all(|j| j == i || r[j].is_nan() || r[j].abs() <= a)
            };
            if spike || beyond {
                out.push(Glitch {
                    row: i,
                    line: log.summary.lines.line(i),
                    column: log.summary.channel_columns.get(c).copied().unwrap_or(0),
                    channel: channel.clone(),
                    value: x[i],
                    expected,
                    score: if scale > 0.0 {
                        ri.abs() / scale
                    } else {
                        f64::INFINITY
                    },
                    kind: if spike {
                        GlitchKind::Spike
                    } else {
                        GlitchKind::BeyondLimit
                    },
                });
            }
        }
    }
    out.sort_by(|a, b| (a.row, &a.channel).cmp(&(b.row, &b.channel)));
    out
}

fn listing(glitches: &[Glitch]) -> Vec<String> {
    let mut v: Vec<String> = glitches
        .iter()
        .take(LISTED)
        .map(|g| g.to_string())
        .collect();
    if glitches.len() > LISTED {
        v.push(format!("and {} more", glitches.len() - LISTED));
    }
    v
}

/// Finds the glitches of `log` and does what `opts.action` says: refuse
/// ([`LogError::Glitches`]), warn ([`Warning::Glitches`], samples kept),
/// drop the rows or repair the samples (both with the warning). Returns the
/// log and the glitches found.
pub fn apply_glitches(mut log: Log, opts: &GlitchOptions) -> Result<(Log, Vec<Glitch>), LogError> {
    if !(opts.threshold.is_finite() && opts.threshold > 0.0) {
        return Err(LogError::InvalidOption {
            name: "glitch threshold",
            value: opts.threshold.to_string(),
            reason: "give a positive number of robust standard deviations such as 10".into(),
        });
    }
    if !(opts.limit_factor.is_finite() && opts.limit_factor >= 1.0) {
        return Err(LogError::InvalidOption {
            name: "torque limit factor",
            value: opts.limit_factor.to_string(),
            reason: "give a factor of at least 1 such as 1.5".into(),
        });
    }
    if let Some(l) = &opts.torque_limit
        && (l.len() != log.joints() || !l.iter().all(|v| v.is_finite() && *v > 0.0))
    {
        return Err(LogError::InvalidOption {
            name: "torque limit",
            value: format!("{l:?}"),
            reason: format!(
                "give {} positive torques (N·m), one per joint of the log",
                log.joints()
            ),
        });
    }
    let glitches = find_glitches(&log, opts);
    if glitches.is_empty() {
        return Ok((log, glitches));
    }
    let list = listing(&glitches);
    let action = match opts.action {
        GlitchAction::Off => return Ok((log, glitches)),
        GlitchAction::Refuse => {
            return Err(LogError::Glitches {
                file: log.name.clone(),
                count: glitches.len(),
                list: list.iter().map(|l| format!("\n  {l}")).collect(),
            });
        }
        GlitchAction::Warn => "kept as logged (--glitches warn)",
        GlitchAction::Repair => {
            for g in &glitches {
                let ch = match Field::parse(&g.channel) {
                    Some(Field::Joint(Role::Theta, j)) => &mut log.theta[j],
                    Some(Field::Joint(Role::Tau, j)) => &mut log.tau[j],
                    _ => continue,
                };
                ch[g.row] = g.expected;
            }
            "repaired by the interpolation of their neighbours (--glitches repair)"
        }
        GlitchAction::Drop => {
            let mut drop = vec![false; log.len()];
            for g in &glitches {
                drop[g.row] = true;
            }
            let keep: Vec<usize> = (0..log.len()).filter(|&i| !drop[i]).collect();
            let pick = |v: &Vec<f64>| keep.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            log.t = pick(&log.t);
            let pick_all = |v: &mut Vec<Vec<f64>>| v.iter_mut().for_each(|c| *c = pick(c));
            pick_all(&mut log.theta);
            pick_all(&mut log.tau);
            if let Some(d) = &mut log.theta_dot {
                pick_all(d);
            }
            if let Some(d) = &mut log.theta_ddot {
                pick_all(d);
            }
            log.summary.lines = log.summary.lines.filtered(keep.iter().copied());
            log.summary.rows = log.t.len();
            // The largest step now spans a dropped row: the processing sees
            // an irregular grid and interpolates onto the nominal one.
            let dt = log.summary.nominal_step_s;
            log.summary.worst_step = log
                .t
                .windows(2)
                .enumerate()
                .map(|(i, w)| crate::StepDeviation {
                    line: log.summary.lines.line(i + 1).unwrap_or(0),
                    t: w[1],
                    step_s: w[1] - w[0],
                    ratio: (w[1] - w[0]) / dt,
                })
                .max_by(|a, b| (a.ratio - 1.0).abs().total_cmp(&(b.ratio - 1.0).abs()));
            "dropped (--glitches drop; the rows' gaps are interpolated)"
        }
    };
    log.warnings.push(Warning::Glitches {
        action: action.into(),
        count: glitches.len(),
        list,
    });
    Ok((log, glitches))
}
