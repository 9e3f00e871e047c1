//! Candidate effects beyond a friction model, as regressor column blocks,
//! and the residual's profile against the joint's state.
//!
//! A diagnosis fits a friction model, then asks which of these effects the
//! residual still contains. Each [`Effect`] is linear in its coefficients
//! given the log (and, for the delay, the model's own prediction), so a
//! forward selection can test them as column blocks added to the model's
//! columns:
//!
//! | effect | columns | coefficients |
//! |---|---|---|
//! | [`Effect::Ripple`] `k` | `sin(k q)`, `cos(k q)` | `a`, `b`: amplitude `√(a²+b²)` N·m; `k` found by [`position_lines`] |
//! | [`Effect::ViscousAsymmetry`] | `|v|` | N·m·s/rad: viscous friction differs by `±` that between directions |
//! | [`Effect::CoulombDrift`] | `(t − t₀) sgn(v)` | N·m/s: the Coulomb level drifts (warming) |
//! | [`Effect::OffsetDrift`] | `t − t₀` | N·m/s: the offset drifts |
//! | [`Effect::Hysteresis`] `x_d` | Dahl state `w(x_d)` | N·m: a presliding hysteresis of length `x_d` |
//! | [`Effect::Delay`] | `−dτ̂/dt` | s: the torque lags the motion |
//! | [`Effect::Inertia`] | `q̈` | kg·m²: inertia not removed by the rigid-body model |
//! | [`Effect::PositionMap`] `m` | `P_j(x) · [w, 1, v]`, `j = 1…m` | N·m, N·m, N·m·s/rad: friction that depends on position and direction |
//! | [`Effect::Load`] `x_d` | `|L| w(x_d)` | N·m per N·m: the Coulomb level grows with the load torque `L` (the log's `load` column) |
//!
//! `t₀` is each log's first time stamp: every log starts its own drift.
//! In the position map, `P_j` is the Legendre polynomial of degree `j` of
//! the position scaled to the TRAIN stroke, `x = (2q − lo − hi)/(hi − lo)`,
//! held at ±1 beyond it (a polynomial extrapolated off the stroke diverges;
//! a held edge value is the least surprising guess), and `w` is the
//! direction as a presliding state: the normalised Dahl state, `sgn v`
//! while sliding, that does not chatter on sensor noise at rest and follows
//! the joint's transition at a reversal with the length the diagnosis
//! chooses on held-out error. Degree 0 is left out: it is the model's own
//! offset, Coulomb and viscous terms.

use aras_ident::stats::equal_count_bins;
use serde::{Deserialize, Serialize};

use crate::{
    Dahl, FrictionError, JointLog, JointMotion, Separable, Track,
    log::derivative,
    sgn,
    spectrum::{PositionSpectrum, SpectrumSettings, position_lines},
};

/// A candidate effect (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Effect {
    /// Position ripple or load: `a sin(k q) + b cos(k q)`, `k` cycles per
    /// revolution (`k = 1`: gravity-like load), any positive real `k` (a
    /// gear's teeth seen through a reduction are rarely an integer count).
    Ripple {
        /// Cycles per revolution `k`.
        #[serde(alias = "harmonic")]
        cycles: f64,
    },
    /// Viscous friction that differs between directions: `c |v|`.
    ViscousAsymmetry,
    /// Drift of the Coulomb level in time: `c (t − t₀) sgn(v)`.
    CoulombDrift,
    /// Drift of the offset in time: `c (t − t₀)`.
    OffsetDrift,
    /// A presliding hysteresis element: `c w(x_d)`, `w` the normalised Dahl
    /// state with presliding length `x_d`.
    Hysteresis {
        /// Presliding length `x_d`, rad.
        length: f64,
    },
    /// Delay of the torque behind the motion: `τ(t − d) ≈ τ̂ − d dτ̂/dt`.
    Delay,
    /// Residual inertia: `J q̈`.
    Inertia,
    /// Friction that depends on position and direction: a Legendre series
    /// of degree `order` over the TRAIN stroke `[lo, hi]` times the
    /// direction (presliding state), times 1 and times the velocity. Low
    /// orders only: a fine map memorises the trajectory.
    PositionMap {
        /// Highest Legendre degree `m` (`3m` columns).
        order: u32,
        /// Lower end of the stroke the map is scaled to, rad.
        lo: f64,
        /// Upper end of the stroke, rad.
        hi: f64,
        /// Presliding length of the direction state `w` (normalised Dahl
        /// state), rad: the map follows the joint's own transition at a
        /// reversal, which the diagnosis searches for.
        length: f64,
    },
    /// Friction that grows with the torque the joint carries: `μ |L| w`,
    /// `L` the log's `load` column, `w` the normalised Dahl state with
    /// presliding length `x_d` (offered only when TRAIN has a load column).
    Load {
        /// Presliding length `x_d`, rad.
        length: f64,
    },
}

/// One physical value of a fitted effect.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EffectValue {
    /// Name (`amplitude`, `phase`, `rate`, …).
    pub name: String,
    /// Value.
    pub value: f64,
    /// Standard deviation, when known.
    pub sigma: Option<f64>,
    /// SI unit.
    pub unit: String,
}

impl Effect {
    /// Short identifier, e.g. `ripple:12`, `coulomb_drift`.
    pub fn id(&self) -> String {
        match self {
            Effect::Ripple { cycles } => format!("ripple:{}", cycles_id(*cycles)),
            Effect::ViscousAsymmetry => "viscous_asymmetry".into(),
            Effect::CoulombDrift => "coulomb_drift".into(),
            Effect::OffsetDrift => "offset_drift".into(),
            Effect::Hysteresis { length } => format!("hysteresis:{length:.3e}"),
            Effect::Delay => "delay".into(),
            Effect::Inertia => "inertia".into(),
            Effect::PositionMap { order, .. } => format!("position_map:{order}"),
            Effect::Load { length } => format!("load:{length:.3e}"),
        }
    }

    /// The family: members of a grid over one nonlinear setting share it
    /// (at most one of them is added). Every ripple harmonic is its own
    /// family, so several harmonics can be found.
    pub fn family(&self) -> String {
        match self {
            Effect::Hysteresis { .. } => "hysteresis".into(),
            Effect::PositionMap { .. } => "position_map".into(),
            Effect::Load { .. } => "load".into(),
            other => other.id(),
        }
    }

    /// What the effect means, in words.
    pub fn label(&self) -> String {
        match self {
            Effect::Ripple { cycles } if *cycles == 1.0 => {
                "position-dependent load (one cycle per revolution)".into()
            }
            Effect::Ripple { cycles } => {
                format!(
                    "position ripple, {} cycles per revolution (period {:.3e} rad)",
                    cycles_id(*cycles),
                    std::f64::consts::TAU / cycles
                )
            }
            Effect::ViscousAsymmetry => "direction asymmetry of the viscous friction".into(),
            Effect::CoulombDrift => "slow drift of the Coulomb level (e.g. warming)".into(),
            Effect::OffsetDrift => "slow drift of the torque offset".into(),
            Effect::Hysteresis { length } => {
                format!("presliding hysteresis over {length:.2e} rad")
            }
            Effect::Delay => "delay of the torque behind the motion".into(),
            Effect::Inertia => "inertia not removed by the rigid-body model".into(),
            Effect::PositionMap { order, lo, hi, .. } => format!(
                "friction depending on position and direction (degree {order} over {lo:.4} … {hi:.4} rad)"
            ),
            Effect::Load { .. } => "friction growing with the load torque".into(),
        }
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        match self {
            Effect::Ripple { .. } => 2,
            Effect::PositionMap { order, .. } => MAP_FACTORS * *order as usize,
            _ => 1,
        }
    }

    /// The effect's columns along a log. `prediction` is the friction
    /// model's prediction on that log (used by [`Effect::Delay`]).
    pub fn columns(
        &self,
        log: &JointMotion,
        prediction: &[f64],
    ) -> Result<Vec<Vec<f64>>, FrictionError> {
        let n = log.len();
        let t0 = log.t.first().copied().unwrap_or(0.0);
        Ok(match *self {
            Effect::Ripple { cycles: k } => {
                let (s, c): (Vec<f64>, Vec<f64>) = log.q.iter().map(|&q| (k * q).sin_cos()).unzip();
                vec![s, c]
            }
            Effect::ViscousAsymmetry => vec![log.dq.iter().map(|v| v.abs()).collect()],
            Effect::CoulombDrift => vec![
                log.t
                    .iter()
                    .zip(&log.dq)
                    .map(|(t, &v)| (t - t0) * sgn(v))
                    .collect(),
            ],
            Effect::OffsetDrift => vec![log.t.iter().map(|t| t - t0).collect()],
            Effect::Hysteresis { length } => {
                let m = Track::new(&log.t, &log.q, &log.dq)?;
                let cols = Dahl::columns(&[length], &m);
                vec![cols[1].clone()]
            }
            Effect::Delay => {
                if prediction.len() != n {
                    return Err(FrictionError::LengthMismatch {
                        what: "model prediction",
                        expected: n,
                        found: prediction.len(),
                    });
                }
                vec![
                    derivative(&log.t, prediction)
                        .into_iter()
                        .map(|d| -d)
                        .collect(),
                ]
            }
            Effect::Inertia => vec![log.acceleration()],
            Effect::PositionMap {
                order,
                lo,
                hi,
                length,
            } => position_map(log, order, lo, hi, length)?,
            Effect::Load { length } => {
                let load = log
                    .load
                    .as_ref()
                    .ok_or_else(|| FrictionError::MissingLoad {
                        log: log.name.clone(),
                    })?;
                let w = Dahl::normalised_state(length, &log.track()?);
                vec![load.iter().zip(&w).map(|(l, w)| l.abs() * w).collect()]
            }
        })
    }

    /// Physical values from the fitted coefficients (and their σ).
    pub fn values(&self, coef: &[f64], sigma: &[Option<f64>]) -> Vec<EffectValue> {
        let v = |name: &str, value: f64, sigma: Option<f64>, unit: &str| EffectValue {
            name: name.into(),
            value,
            sigma,
            unit: unit.into(),
        };
        let s0 = sigma.first().copied().flatten();
        match self {
            Effect::Ripple { .. } => {
                let (a, b) = (coef[0], coef.get(1).copied().unwrap_or(0.0));
                let amp = a.hypot(b);
                // Delta method, covariance neglected (sin and cos columns are
                // nearly orthogonal over many cycles).
                let sa = match (s0, sigma.get(1).copied().flatten()) {
                    (Some(sa), Some(sb)) if amp > 0.0 => {
                        Some(((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp)
                    }
                    _ => None,
                };
                vec![
                    v("amplitude", amp, sa, "N·m"),
                    v("phase", b.atan2(a), None, "rad"),
                ]
            }
            Effect::ViscousAsymmetry => vec![v("coefficient", coef[0], s0, "N·m·s/rad")],
            Effect::CoulombDrift | Effect::OffsetDrift => vec![v("rate", coef[0], s0, "N·m/s")],
            Effect::Hysteresis { length } => vec![
                v("level", coef[0], s0, "N·m"),
                v("length", *length, None, "rad"),
            ],
            Effect::Delay => vec![v("delay", coef[0], s0, "s")],
            Effect::Load { length } => vec![
                v("coefficient", coef[0], s0, "N·m/N·m"),
                v("length", *length, None, "rad"),
            ],
            Effect::Inertia => vec![v("inertia", coef[0], s0, "kg·m²")],
            Effect::PositionMap { lo, hi, length, .. } => {
                // The map's swing over the stroke, per factor: what a user
                // reads first (the coefficients are in the model file).
                let swing = |factor: usize| {
                    let mut p = vec![0.0; coef.len() / MAP_FACTORS + 1];
                    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
                    for i in 0..=MAP_SWING_POINTS {
                        let x = -1.0 + 2.0 * i as f64 / MAP_SWING_POINTS as f64;
                        legendre(x, &mut p);
                        let f: f64 = coef
                            .chunks(MAP_FACTORS)
                            .zip(&p[1..])
                            .map(|(c, pj)| c[factor] * pj)
                            .sum();
                        min = min.min(f);
                        max = max.max(f);
                    }
                    if min.is_finite() { max - min } else { 0.0 }
                };
                vec![
                    v("direction_swing", swing(0), None, "N·m"),
                    v("offset_swing", swing(1), None, "N·m"),
                    v("viscous_swing", swing(2), None, "N·m·s/rad"),
                    v("lo", *lo, None, "rad"),
                    v("hi", *hi, None, "rad"),
                    v("length", *length, None, "rad"),
                ]
            }
        }
    }
}

/// Factors of each Legendre degree in the position map: direction, 1, v.
const MAP_FACTORS: usize = 3;

/// Points over the stroke at which the map's swing is evaluated.
const MAP_SWING_POINTS: usize = 200;

/// Shortest presliding length searched, rad (a stiff gear's presliding is
/// tens of µrad).
const PRESLIDING_MIN: f64 = 1e-5;

/// Longest presliding length searched on a stroke of `range` rad: a
/// hundredth of it.
fn presliding_max(range: f64) -> f64 {
    (0.01 * range).max(2.0 * PRESLIDING_MIN)
}

/// `count` presliding lengths, log-spaced from [`PRESLIDING_MIN`] to
/// [`presliding_max`]: the lengths searched for hysteresis and for the
/// position map's direction state.
pub(crate) fn presliding_lengths(range: f64, count: usize) -> Vec<f64> {
    crate::fit::log_grid(PRESLIDING_MIN, presliding_max(range), count)
}

/// `P_0(x) … P_{p.len()-1}(x)` by Bonnet's recursion.
fn legendre(x: f64, p: &mut [f64]) {
    if let Some(p0) = p.first_mut() {
        *p0 = 1.0;
    }
    if p.len() > 1 {
        p[1] = x;
    }
    for j in 2..p.len() {
        let jf = j as f64;
        p[j] = ((2.0 * jf - 1.0) * x * p[j - 1] - (jf - 1.0) * p[j - 2]) / jf;
    }
}

/// A ripple's columns `sin(kq)`, `cos(kq)` turned into `sin(kq + Δ)`,
/// `cos(kq + Δ)`: the same line on a log whose position zero puts it
/// `Δ` rad further on.
pub(crate) fn shift_ripple(columns: &mut [Vec<f64>], shift: f64) {
    if shift == 0.0 {
        return;
    }
    let (sd, cd) = shift.sin_cos();
    if let [s, c] = columns {
        for (s, c) in s.iter_mut().zip(c.iter_mut()) {
            let (a, b) = (*s, *c);
            *s = a * cd + b * sd;
            *c = b * cd - a * sd;
        }
    }
}

/// The position map's columns (degree by degree, each `P_j · [w, 1, v]`).
fn position_map(
    log: &JointMotion,
    order: u32,
    lo: f64,
    hi: f64,
    length: f64,
) -> Result<Vec<Vec<f64>>, FrictionError> {
    let n = log.len();
    let order = order as usize;
    let w = Dahl::normalised_state(length, &log.track()?);
    let mut cols = vec![Vec::with_capacity(n); MAP_FACTORS * order];
    let mut p = vec![0.0; order + 1];
    let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    for i in 0..n {
        let x = if half > 0.0 {
            ((log.q[i] - mid) / half).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        legendre(x, &mut p);
        for j in 1..=order {
            let c = MAP_FACTORS * (j - 1);
            cols[c].push(p[j] * w[i]);
            cols[c + 1].push(p[j]);
            cols[c + 2].push(p[j] * log.dq[i]);
        }
    }
    Ok(cols)
}

/// `k` as an identifier: an integer as such, otherwise to a hundredth.
fn cycles_id(k: f64) -> String {
    if k.fract() == 0.0 && k.abs() < 1e9 {
        format!("{k:.0}")
    } else {
        format!("{k:.2}")
    }
}

/// Settings of the candidate library.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LibrarySettings {
    /// Highest integer ripple harmonic (cycles per revolution) tried below
    /// the line search's band: the low-order position dependence (a load)
    /// over a stroke too short to hold two of its periods.
    pub max_harmonic: u32,
    /// The search for ripple lines at any spatial frequency in the
    /// residual.
    pub spectrum: SpectrumSettings,
    /// Hysteresis lengths tried: this many, log-spaced between 1e-5 rad and
    /// a hundredth of the travelled range (also the presliding lengths of
    /// the load term's direction state).
    pub hysteresis_lengths: usize,
    /// Try a delay of the torque.
    pub delay: bool,
    /// Try a residual inertia.
    pub inertia: bool,
    /// Highest Legendre degree of the position × direction map tried
    /// ([`Effect::PositionMap`]; 0: none). Every degree up to it is a
    /// member of one family; with validation logs the diagnosis keeps the
    /// degree with the best held-out fitness.
    pub position_map: u32,
}

impl Default for LibrarySettings {
    fn default() -> Self {
        Self {
            max_harmonic: 40,
            spectrum: SpectrumSettings::default(),
            hysteresis_lengths: 4,
            delay: true,
            inertia: true,
            position_map: 6,
        }
    }
}

/// The candidates of a training log and the position spectrum their
/// ripple lines come from.
#[derive(Debug, Clone, PartialEq)]
pub struct Library {
    /// The candidate effects.
    pub effects: Vec<Effect>,
    /// The line search of the model's residual against position.
    pub spectrum: PositionSpectrum,
}

/// The candidate effects for a training log and the residual of the model
/// being diagnosed on it:
/// * integer ripple harmonics from 1 below the line search's band, up to
///   the highest one the log resolves (at least 8 samples per period at
///   the 90th percentile of the position step) and at most
///   [`LibrarySettings::max_harmonic`];
/// * every line the search finds in the residual against position
///   ([`position_lines`]) with its harmonics up to the band's top, one
///   Fourier cell apart at least;
/// * asymmetry, drifts, hysteresis, delay and inertia;
/// * with a `load` column in TRAIN, the load term at each hysteresis length;
/// * the position × direction map of every degree up to
///   [`LibrarySettings::position_map`] over TRAIN's stroke.
pub fn library(train: &JointLog, residual: &[f64], settings: &LibrarySettings) -> Library {
    let spectrum = position_lines(&train.q, residual, &settings.spectrum);
    let mut steps: Vec<f64> = train.q.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let resolved = if steps.is_empty() {
        1
    } else {
        let k = ((steps.len() as f64) * 0.9) as usize;
        let k = k.min(steps.len() - 1);
        let dq90 = *steps.select_nth_unstable_by(k, f64::total_cmp).1;
        if dq90 > 0.0 {
            (std::f64::consts::TAU / (8.0 * dq90)).floor().min(1e6) as u32
        } else {
            settings.max_harmonic
        }
    };
    let below_band = if spectrum.lowest() > 1.0 {
        (spectrum.lowest().ceil() - 1.0) as u32
    } else {
        u32::MAX
    };
    let kmax = settings.max_harmonic.min(resolved).min(below_band).max(1);
    let mut v: Vec<Effect> = (1..=kmax)
        .map(|k| Effect::Ripple {
            cycles: f64::from(k),
        })
        .collect();
    // A Fourier cell: the band starts two of them above zero.
    let cell = 0.5 * spectrum.lowest();
    let mut ripples: Vec<f64> = Vec::new();
    for line in &spectrum.lines {
        for h in 1..=settings.spectrum.harmonics.max(1) {
            let k = f64::from(h) * line.cycles;
            if k > spectrum.band.1 {
                break;
            }
            if ripples.iter().all(|&r| (r - k).abs() >= cell) {
                ripples.push(k);
                v.push(Effect::Ripple { cycles: k });
            }
        }
    }
    v.extend([
        Effect::ViscousAsymmetry,
        Effect::CoulombDrift,
        Effect::OffsetDrift,
    ]);
    let lo = train.q.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = train.q.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let range = hi - lo;
    // One grid of presliding lengths for the hysteresis element and the
    // load term's direction state.
    let lengths = if settings.hysteresis_lengths > 0 && range > 0.0 {
        presliding_lengths(range, settings.hysteresis_lengths)
    } else {
        Vec::new()
    };
    v.extend(lengths.iter().map(|&length| Effect::Hysteresis { length }));
    if train.load.is_some() {
        v.extend(lengths.iter().map(|&length| Effect::Load { length }));
    }
    if settings.delay {
        v.push(Effect::Delay);
    }
    if settings.inertia {
        v.push(Effect::Inertia);
    }
    if range > 0.0 {
        // The grid's geometric middle: the diagnosis then searches the
        // length of the map it adds over the grid.
        let length = (PRESLIDING_MIN * presliding_max(range)).sqrt();
        v.extend(
            (1..=settings.position_map).map(|order| Effect::PositionMap {
                order,
                lo,
                hi,
                length,
            }),
        );
    }
    Library {
        effects: v,
        spectrum,
    }
}

/// What a residual is binned against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    /// Velocity `dq`, rad/s.
    Velocity,
    /// Position `q`, rad.
    Position,
    /// Time, s.
    Time,
    /// Acceleration, rad/s².
    Acceleration,
    /// Direction of motion (`sgn dq`: −1, 0, +1).
    Direction,
}

/// One bin of a residual profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Bin {
    /// Lower edge.
    pub lo: f64,
    /// Upper edge.
    pub hi: f64,
    /// Samples.
    pub count: usize,
    /// Mean residual, N·m.
    pub mean: f64,
    /// RMS residual, N·m.
    pub rms: f64,
}

/// The residual binned against one axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Profile {
    /// The axis.
    pub axis: Axis,
    /// Bins in increasing order.
    pub bins: Vec<Bin>,
    /// Share of the residual's variance explained by the bin means, in
    /// [0, 1]: how much of the residual is a function of this axis.
    pub explained: f64,
}

/// The residual binned against velocity, position, time, acceleration
/// (equal-count bins) and direction.
pub fn residual_profiles(log: &JointMotion, residual: &[f64], bins: usize) -> Vec<Profile> {
    let acc = log.acceleration();
    let dir: Vec<f64> = log.dq.iter().map(|&v| sgn(v)).collect();
    let axes: [(Axis, &[f64]); 5] = [
        (Axis::Velocity, &log.dq),
        (Axis::Position, &log.q),
        (Axis::Time, &log.t),
        (Axis::Acceleration, &acc),
        (Axis::Direction, &dir),
    ];
    axes.iter()
        .map(|&(axis, x)| {
            profile(
                axis,
                x,
                residual,
                if axis == Axis::Direction { 3 } else { bins },
            )
        })
        .collect()
}

fn profile(axis: Axis, x: &[f64], r: &[f64], bins: usize) -> Profile {
    let n = x.len().min(r.len());
    let (x, r) = (&x[..n], &r[..n]);
    let total_mean = r.iter().sum::<f64>() / n.max(1) as f64;
    let total_var: f64 = r.iter().map(|v| (v - total_mean).powi(2)).sum();
    let out: Vec<Bin> = if axis == Axis::Direction {
        [-1.0, 0.0, 1.0]
            .into_iter()
            .filter_map(|s| {
                let idx: Vec<usize> = (0..n).filter(|&i| x[i] == s).collect();
                bin(&idx, s, s, r)
            })
            .collect()
    } else {
        equal_count_bins(x, r, bins)
            .into_iter()
            .map(|b| Bin {
                lo: b.lo,
                hi: b.hi,
                count: b.count,
                mean: b.mean,
                rms: b.rms,
            })
            .collect()
    };
    let between: f64 = out
        .iter()
        .map(|b| b.count as f64 * (b.mean - total_mean).powi(2))
        .sum();
    Profile {
        axis,
        bins: out,
        explained: if total_var > 0.0 {
            (between / total_var).min(1.0)
        } else {
            0.0
        },
    }
}

fn bin(idx: &[usize], lo: f64, hi: f64, r: &[f64]) -> Option<Bin> {
    if idx.is_empty() {
        return None;
    }
    let c = idx.len() as f64;
    let mean = idx.iter().map(|&i| r[i]).sum::<f64>() / c;
    let rms = (idx.iter().map(|&i| r[i] * r[i]).sum::<f64>() / c).sqrt();
    Some(Bin {
        lo,
        hi,
        count: idx.len(),
        mean,
        rms,
    })
}
