//! The candidate library: effects the paper's model may be missing, each
//! with a stable identifier, a physical explanation and the grid over which
//! its non-linear setting is scanned. Every candidate except `time_delay`
//! is an [`aras_dyn::Effect`], so the extended model is an ordinary
//! [`aras_dyn::Model`] that identification and prediction use unchanged.
//! A [`Candidate`] is an [`aras_diagnose::Candidate`] of the engine.

use aras_diagnose::SearchScale;
use aras_dyn::{Effect, EffectId};
use serde::Serialize;

/// Identifier of the one candidate that is not a model effect.
pub const TIME_DELAY: &str = "time_delay";

/// Stable identifiers of the candidates, in the order they are tried: the
/// extra effects ([`EffectId::EXTRA`]), then [`TIME_DELAY`].
pub const CANDIDATE_IDS: [&str; EffectId::EXTRA.len() + 1] = {
    // Derived from the effect list, so a new extra effect is a candidate
    // without a second list to update.
    let mut ids = [TIME_DELAY; EffectId::EXTRA.len() + 1];
    let mut i = 0;
    while i < EffectId::EXTRA.len() {
        ids[i] = EffectId::EXTRA[i].as_str();
        i += 1;
    }
    ids
};

/// One candidate with one value of its non-linear setting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Candidate {
    /// A model effect: its regressor columns are appended to the model.
    Effect {
        /// The effect with its settings.
        effect: Effect,
    },
    /// The torque samples lag the angle samples by `samples` (negative:
    /// lead; a fraction interpolates linearly between samples). Not a
    /// regressor column: the torques are shifted against the angles and the
    /// same model is fitted again.
    TimeDelay {
        /// Shift in samples.
        samples: f64,
    },
}

impl Candidate {
    /// The stable identifier (one of [`CANDIDATE_IDS`]).
    pub fn id(&self) -> &'static str {
        match self {
            Candidate::Effect { effect } => effect.id(),
            Candidate::TimeDelay { .. } => TIME_DELAY,
        }
    }

    /// A short label including the scanned setting, e.g.
    /// `stribeck_friction(v_s = 0.1 rad/s)`.
    pub fn label(&self) -> String {
        match self {
            Candidate::Effect {
                effect: Effect::StribeckFriction { v_s },
            } => format!("stribeck_friction(v_s = {v_s} rad/s)"),
            Candidate::Effect {
                effect:
                    Effect::Cogging {
                        cycles_per_rev,
                        order,
                    },
            } => format!("cogging({cycles_per_rev} cycles/rev, order {order})"),
            Candidate::Effect {
                effect: Effect::PreslidingFriction { displacement },
            } => format!("presliding_friction(δ = {displacement:e} rad)"),
            Candidate::Effect { effect } => effect.id().to_owned(),
            Candidate::TimeDelay { samples } => format!("time_delay({samples:+} samples)"),
        }
    }

    /// Why such an effect exists physically, and how it shows in the data.
    pub fn explanation(&self) -> &'static str {
        explanation(self.id())
    }

    /// The continuous non-linear setting the diagnosis refines between the
    /// grid points once the candidate is added, `(name, value)`: `v_s`
    /// (rad/s) of Stribeck friction, `cycles_per_rev` of cogging,
    /// `displacement` (rad) of presliding friction, `delay_samples` of the
    /// time delay. `None` for the linear candidates.
    pub fn setting(&self) -> Option<(&'static str, f64)> {
        match self {
            Candidate::TimeDelay { samples } => Some(("delay_samples", *samples)),
            Candidate::Effect {
                effect: Effect::StribeckFriction { v_s },
            } => Some(("v_s", *v_s)),
            Candidate::Effect {
                effect: Effect::Cogging { cycles_per_rev, .. },
            } => Some(("cycles_per_rev", *cycles_per_rev)),
            Candidate::Effect {
                effect: Effect::PreslidingFriction { displacement },
            } => Some(("displacement", *displacement)),
            _ => None,
        }
    }

    /// Where the refinement searches around the grid value: for `v_s` a
    /// factor 3 either side on a log scale (its grid steps by 2 and its
    /// profile is smooth over decades); for cogging cycles a factor 1.25
    /// (its grid steps by 1.2–2 and its profile has side lobes one
    /// `2π / (range of θ)` apart, so a wider interval could hold another
    /// minimum); for the presliding displacement a factor 3 on a log scale
    /// (its grid steps by about 2.5 and its profile is smooth, with one
    /// minimum); for a delay of `d` samples `max(1, |d|/2)` either side on
    /// a linear scale, which reaches past the midpoint to each neighbour of
    /// the default grid (±1, 2, 3, 5, 8, 12, 20). `None` where
    /// [`Self::setting`] is.
    pub fn search_scale(&self) -> Option<SearchScale> {
        match self {
            Candidate::Effect {
                effect: Effect::StribeckFriction { .. } | Effect::PreslidingFriction { .. },
            } => Some(SearchScale::Log { factor: 3.0 }),
            Candidate::Effect {
                effect: Effect::Cogging { .. },
            } => Some(SearchScale::Log { factor: 1.25 }),
            Candidate::TimeDelay { samples } => Some(SearchScale::Linear {
                half_width: (0.5 * samples.abs()).max(1.0),
            }),
            _ => None,
        }
    }

    /// The values around which the refinement searches, the grid value
    /// first. For cogging of order `K` also its harmonic relatives
    /// `n · h / h′` (`h, h′ ≤ K`): a fundamental whose `h`-th harmonic
    /// meets the true `h′`-th is an alias the grid may pick instead (with
    /// order 2 and a true 14 cycles/rev, 8 — whose second harmonic is 16 —
    /// can beat 12 and 16); the search keeps the lowest residual.
    pub fn search_centres(&self) -> Vec<f64> {
        let Some((_, v)) = self.setting() else {
            return Vec::new();
        };
        let mut out = vec![v];
        if let Candidate::Effect {
            effect: Effect::Cogging { order, .. },
        } = self
        {
            for h in 1..=*order {
                for h2 in 1..=*order {
                    let c = v * h as f64 / h2 as f64;
                    if !out.iter().any(|o| (o / c).ln().abs() < 1e-9) {
                        out.push(c);
                    }
                }
            }
        }
        out
    }

    /// The candidate with its [`Self::setting`] replaced by `value`
    /// (unchanged if it has none).
    pub fn with_setting(&self, value: f64) -> Candidate {
        match *self {
            Candidate::Effect {
                effect: Effect::StribeckFriction { .. },
            } => Candidate::Effect {
                effect: Effect::StribeckFriction { v_s: value },
            },
            Candidate::Effect {
                effect: Effect::Cogging { order, .. },
            } => Candidate::Effect {
                effect: Effect::Cogging {
                    cycles_per_rev: value,
                    order,
                },
            },
            Candidate::Effect {
                effect: Effect::PreslidingFriction { .. },
            } => Candidate::Effect {
                effect: Effect::PreslidingFriction {
                    displacement: value,
                },
            },
            Candidate::TimeDelay { .. } => Candidate::TimeDelay { samples: value },
            other => other,
        }
    }
}

impl aras_diagnose::Candidate for Candidate {
    fn id(&self) -> String {
        Candidate::id(self).to_owned()
    }
    fn label(&self) -> String {
        Candidate::label(self)
    }
    fn explanation(&self) -> String {
        Candidate::explanation(self).to_owned()
    }
    fn parameter_names(&self) -> Vec<String> {
        match self {
            Candidate::Effect { effect } => effect.names(),
            Candidate::TimeDelay { .. } => Vec::new(),
        }
    }
    fn torque_shift(&self) -> Option<f64> {
        match self {
            Candidate::TimeDelay { samples } => Some(*samples),
            Candidate::Effect { .. } => None,
        }
    }
    fn setting(&self) -> Option<(&str, f64)> {
        Candidate::setting(self)
    }
    fn search_scale(&self) -> Option<SearchScale> {
        Candidate::search_scale(self)
    }
    fn search_centres(&self) -> Vec<f64> {
        Candidate::search_centres(self)
    }
    fn with_setting(&self, value: f64) -> Self {
        Candidate::with_setting(self, value)
    }
}

/// The physical explanation of a candidate identifier (the effect's own,
/// [`EffectId::explanation`]; empty for an unknown identifier).
pub fn explanation(id: &str) -> &'static str {
    if id == TIME_DELAY {
        return "torque and angle samples are not simultaneous (current-loop or communication \
                latency, filter group delay in the drive); the residual is proportional to the \
                torque's rate of change";
    }
    id.parse::<EffectId>().map_or("", EffectId::explanation)
}

/// Which candidates are scanned, and over which grids.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CandidateGrid {
    /// Candidate identifiers to try (a subset of [`CANDIDATE_IDS`]).
    pub ids: Vec<String>,
    /// Stribeck velocities `v_s` (rad/s). Default 0.02–0.4 rad/s: the
    /// Stribeck velocities of lubricated gears and bearings lie around
    /// 0.001–0.1 m/s at the contact, i.e. a few hundredths to tenths of a
    /// rad/s at the joint; below ≈ 0.02 rad/s the effect hides inside the
    /// encoder's velocity resolution.
    pub stribeck_v_s: Vec<f64>,
    /// Cogging cycles per joint revolution. Default 1–60: a coarse grid over
    /// the periods a 10 Hz low-pass lets through at joint speeds of
    /// 0.2–2 rad/s (motor cogging of 6 per motor revolution through the
    /// 10:1 capstan is 60 per joint revolution).
    pub cogging_cycles: Vec<f64>,
    /// Presliding displacements `δ = Fc/σ0` (rad). Default 1e-4–5e-3 rad:
    /// the bristle of a geared or cable joint deforms over 1e-5–1e-3 m at
    /// the contact, i.e. about 1e-4 to a few 1e-3 rad at the joint; below
    /// ≈ 1e-4 rad the transition is shorter than the path of a sample at
    /// the reversals of a 1 kHz log and the state is the sign law (49).
    pub presliding_displacements: Vec<f64>,
    /// Cogging harmonics (1–16, default 2). Each cycle count is tried with
    /// its fundamental alone and with this many harmonics.
    pub cogging_order: usize,
    /// Torque-against-angle shifts in samples (both signs; fractions are
    /// interpolated). Default ±0.5, 1, 2, 3, 5, 8, 12, 20 samples (0.5–20
    /// ms at 1 kHz: a torque held over the sample step but logged as
    /// sampled, amplifier and bus latencies). The half sample is on the
    /// grid because a candidate's validation gain is judged at its grid
    /// value, before the refinement: a shift of 0.6 samples loses
    /// validation fitness at a whole sample.
    pub delays: Vec<f64>,
}

impl Default for CandidateGrid {
    fn default() -> Self {
        let d = [0.5, 1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 20.0];
        Self {
            ids: CANDIDATE_IDS.iter().map(|s| s.to_string()).collect(),
            stribeck_v_s: vec![0.05, 0.1, 0.2, 0.4],
            cogging_cycles: vec![
                1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 10.0, 12.0, 16.0, 20.0, 24.0, 30.0, 36.0, 48.0, 60.0,
            ],
            presliding_displacements: vec![1e-4, 2.5e-4, 6e-4, 1.5e-3, 4e-3],
            cogging_order: 2,
            delays: d.iter().flat_map(|&k| [k, -k]).collect(),
        }
    }
}

impl CandidateGrid {
    /// Every candidate setting of the grid, in a fixed order.
    pub fn expand(&self) -> Vec<Candidate> {
        let mut out = Vec::new();
        let eff = |effect| Candidate::Effect { effect };
        for id in CANDIDATE_IDS {
            if !self.ids.iter().any(|s| s == id) {
                continue;
            }
            match id.parse::<EffectId>() {
                Ok(EffectId::TorqueOffset) => out.push(eff(Effect::TorqueOffset)),
                Ok(EffectId::CoulombAsymmetry) => out.push(eff(Effect::CoulombAsymmetry)),
                Ok(EffectId::StribeckFriction) => out.extend(
                    self.stribeck_v_s
                        .iter()
                        .map(|&v_s| eff(Effect::StribeckFriction { v_s })),
                ),
                Ok(EffectId::PassiveJointViscous) => out.push(eff(Effect::PassiveJointViscous)),
                // Each cycle count with its fundamental alone and with
                // `cogging_order` harmonics: c cycles of order 2 hold the
                // 2c harmonic, so a pure 2c-cycle cogging is fitted as well
                // by both; the order-1 2c candidate does it with half the
                // parameters and wins the ΔBIC, so the name is the
                // fundamental actually present.
                Ok(EffectId::Cogging) => {
                    for &c in &self.cogging_cycles {
                        let orders: &[usize] = if self.cogging_order > 1 {
                            &[1, self.cogging_order]
                        } else {
                            &[self.cogging_order]
                        };
                        out.extend(orders.iter().map(|&order| {
                            eff(Effect::Cogging {
                                cycles_per_rev: c,
                                order,
                            })
                        }));
                    }
                }
                Ok(EffectId::QuadraticDamping) => out.push(eff(Effect::QuadraticDamping)),
                Ok(EffectId::PreslidingFriction) => out.extend(
                    self.presliding_displacements
                        .iter()
                        .map(|&displacement| eff(Effect::PreslidingFriction { displacement })),
                ),
                Ok(EffectId::RigidLinks | EffectId::Friction | EffectId::Elasticity) => {}
                Err(_) => out.extend(
                    self.delays
                        .iter()
                        .map(|&samples| Candidate::TimeDelay { samples }),
                ),
            }
        }
        out
    }
}
