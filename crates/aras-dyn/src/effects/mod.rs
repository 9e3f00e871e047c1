//! The effects a model is made of, one file each: its columns, parameter
//! names, settings, physical explanation and sign constraints. [`Effect`]
//! (with its settings) and [`EffectId`] (without) are the one spelling of
//! the effect identifiers, shared by the parameter file's `extra` sections,
//! the MJCF notes, `aras identify --effects` and the diagnosis candidates.

mod cogging;
mod coulomb_asymmetry;
mod elasticity;
mod friction;
mod passive_joint_viscous;
mod presliding_friction;
mod quadratic_damping;
mod rigid_links;
mod stribeck_friction;
mod torque_offset;

// The parameter names of the fixed-size effects, spelled once in their
// files: the parameter file's keys and the MJCF notes use them.
pub(crate) use cogging::names as cogging_names;
pub(crate) use coulomb_asymmetry::NAMES as COULOMB_ASYMMETRY_NAMES;
pub(crate) use elasticity::NAMES as ELASTICITY_NAMES;
pub(crate) use friction::NAMES as FRICTION_NAMES;
pub use friction::{coulomb_law, coulomb_law_dw};
pub(crate) use passive_joint_viscous::NAMES as PASSIVE_JOINT_VISCOUS_NAMES;
pub(crate) use presliding_friction::NAMES as PRESLIDING_FRICTION_NAMES;
pub(crate) use presliding_friction::states as presliding_states;
pub(crate) use quadratic_damping::NAMES as QUADRATIC_DAMPING_NAMES;
pub(crate) use stribeck_friction::NAMES as STRIBECK_FRICTION_NAMES;
pub(crate) use torque_offset::NAMES as TORQUE_OFFSET_NAMES;

use std::fmt;
use std::str::FromStr;

use aras_kin::{KinematicSample, Scalar};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::{DynError, Sign};

/// One physical effect of the model, with its non-linear settings.
///
/// Serialised as an object tagged by `id`, e.g.
/// `{"id": "stribeck_friction", "v_s": 0.05}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "id", rename_all = "snake_case", deny_unknown_fields)]
pub enum Effect {
    /// Rigid links 1–4: 9 columns each (`Lk.Ixx … Lk.hz`), (38)–(46).
    RigidLinks,
    /// Viscous + Coulomb friction per actuator: `Fv1, Fc1, Fv2, Fc2`, with
    /// the Coulomb law `Fc_j tanh(θ̇_j / w_j)`; `w_j = 0` is the sign law (49).
    /// Serialised as `{"id": "friction", "w": [w1, w2]}`; an absent `w` is
    /// `[0, 0]`.
    Friction {
        /// Coulomb transition width per joint (rad/s, finite, ≥ 0).
        #[serde(default)]
        w: [f64; 2],
    },
    /// Capstan elasticity `τ_e = K_e θ`: `Ke1, Ke2`, (50).
    Elasticity,
    /// Constant torque offset per actuator: `tau0_1, tau0_2`.
    TorqueOffset,
    /// Direction-dependent Coulomb level: `Fca1, Fca2`, columns `|sign θ̇_j|`
    /// (1 while moving, 0 at rest). While the joint moves this is
    /// indistinguishable from a torque offset; the two differ only at rest.
    CoulombAsymmetry,
    /// Stribeck friction, columns `sign(θ̇_j) exp(−(θ̇_j/v_s)²)`: `Fs1, Fs2`.
    StribeckFriction {
        /// Shape velocity (rad/s, > 0).
        v_s: f64,
    },
    /// Viscous friction in the passive hinges about `b`, `c`, `d`:
    /// `Fpb, Fpc, Fpd`. The hinges' relative angular velocities
    /// (`Ω3 − Ω1`, `Ω4 − Ω2`, `Ω3 − Ω4`) are mapped to the motors by virtual
    /// work: column `J⁻ᵀ (J_ωi − J_ωj)ᵀ (Ω_i − Ω_j)`.
    PassiveJointViscous,
    /// Cogging per joint, harmonics `h = 1..order` of `sin/cos(h n_c θ_j)`:
    /// `Cs{j}_{h}, Cc{j}_{h}`.
    Cogging {
        /// Cycles per joint revolution `n_c` (> 0).
        cycles_per_rev: f64,
        /// Number of harmonics (1–16).
        order: usize,
    },
    /// Quadratic damping, columns `θ̇_j |θ̇_j|`: `Fq1, Fq2`.
    QuadraticDamping,
    /// Presliding (LuGre bristle) friction: `Fb1, Fb2, Db1, Db2`, columns
    /// the normalised bristle deflection of each joint and its rate, a state
    /// integrated along the stacked samples (never per sample; see
    /// [`Effect::is_stateful`]).
    PreslidingFriction {
        /// Presliding displacement `δ = Fc/σ0` (rad, > 0).
        displacement: f64,
    },
}

/// Which effect, without its settings: the one spelling of the effect
/// identifiers, shared by [`Effect`]'s serde tag, the parameter file's
/// `extra.<id>` sections, the `aras` CLI's `--effects` and the diagnosis
/// candidates. Parses from and prints as the identifier (`FromStr`,
/// `Display`, serde: `"stribeck_friction"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectId {
    /// [`Effect::RigidLinks`].
    RigidLinks,
    /// [`Effect::Friction`].
    Friction,
    /// [`Effect::Elasticity`].
    Elasticity,
    /// [`Effect::TorqueOffset`].
    TorqueOffset,
    /// [`Effect::CoulombAsymmetry`].
    CoulombAsymmetry,
    /// [`Effect::StribeckFriction`].
    StribeckFriction,
    /// [`Effect::PassiveJointViscous`].
    PassiveJointViscous,
    /// [`Effect::Cogging`].
    Cogging,
    /// [`Effect::QuadraticDamping`].
    QuadraticDamping,
    /// [`Effect::PreslidingFriction`].
    PreslidingFriction,
}

impl EffectId {
    /// Every effect, in the order of [`Effect`].
    pub const ALL: [EffectId; 10] = [
        EffectId::RigidLinks,
        EffectId::Friction,
        EffectId::Elasticity,
        EffectId::TorqueOffset,
        EffectId::CoulombAsymmetry,
        EffectId::StribeckFriction,
        EffectId::PassiveJointViscous,
        EffectId::Cogging,
        EffectId::QuadraticDamping,
        EffectId::PreslidingFriction,
    ];

    /// How many of [`ALL`](Self::ALL) make the paper's model (rigid links,
    /// friction, elasticity); the rest are [`EXTRA`](Self::EXTRA).
    const PAPER: usize = 3;

    /// The effects beyond the paper's model (the parameter file's `extra`
    /// section, the candidates of the diagnosis), in that order: the tail of
    /// [`ALL`](Self::ALL).
    pub const EXTRA: [EffectId; Self::ALL.len() - Self::PAPER] = {
        let mut out = [EffectId::RigidLinks; Self::ALL.len() - Self::PAPER];
        let mut i = 0;
        while i < out.len() {
            out[i] = Self::ALL[Self::PAPER + i];
            i += 1;
        }
        out
    };

    /// The stable identifier, e.g. `"stribeck_friction"`.
    pub const fn as_str(self) -> &'static str {
        match self {
            EffectId::RigidLinks => "rigid_links",
            EffectId::Friction => "friction",
            EffectId::Elasticity => "elasticity",
            EffectId::TorqueOffset => "torque_offset",
            EffectId::CoulombAsymmetry => "coulomb_asymmetry",
            EffectId::StribeckFriction => "stribeck_friction",
            EffectId::PassiveJointViscous => "passive_joint_viscous",
            EffectId::Cogging => "cogging",
            EffectId::QuadraticDamping => "quadratic_damping",
            EffectId::PreslidingFriction => "presliding_friction",
        }
    }
}

impl EffectId {
    /// Why such an effect exists physically, and how it shows in the data.
    pub const fn explanation(self) -> &'static str {
        match self {
            EffectId::RigidLinks => rigid_links::EXPLANATION,
            EffectId::Friction => friction::EXPLANATION,
            EffectId::Elasticity => elasticity::EXPLANATION,
            EffectId::TorqueOffset => torque_offset::EXPLANATION,
            EffectId::CoulombAsymmetry => coulomb_asymmetry::EXPLANATION,
            EffectId::StribeckFriction => stribeck_friction::EXPLANATION,
            EffectId::PassiveJointViscous => passive_joint_viscous::EXPLANATION,
            EffectId::Cogging => cogging::EXPLANATION,
            EffectId::QuadraticDamping => quadratic_damping::EXPLANATION,
            EffectId::PreslidingFriction => presliding_friction::EXPLANATION,
        }
    }
}

impl fmt::Display for EffectId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for EffectId {
    type Err = UnknownEffect;

    fn from_str(s: &str) -> Result<Self, UnknownEffect> {
        EffectId::ALL
            .into_iter()
            .find(|e| e.as_str() == s)
            .ok_or_else(|| UnknownEffect { id: s.to_owned() })
    }
}

/// A name that is not an effect identifier.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown effect `{id}`; known effects: {}", known_effects())]
pub struct UnknownEffect {
    /// The name given.
    pub id: String,
}

fn known_effects() -> String {
    EffectId::ALL.map(EffectId::as_str).join(", ")
}

impl Effect {
    /// The paper's friction (49): viscous + Coulomb with the exact sign
    /// (transition width 0 on both joints).
    pub const FRICTION_SIGN_LAW: Effect = Effect::Friction { w: [0.0; 2] };

    /// Which effect this is, without its settings.
    pub fn kind(&self) -> EffectId {
        match self {
            Effect::RigidLinks => EffectId::RigidLinks,
            Effect::Friction { .. } => EffectId::Friction,
            Effect::Elasticity => EffectId::Elasticity,
            Effect::TorqueOffset => EffectId::TorqueOffset,
            Effect::CoulombAsymmetry => EffectId::CoulombAsymmetry,
            Effect::StribeckFriction { .. } => EffectId::StribeckFriction,
            Effect::PassiveJointViscous => EffectId::PassiveJointViscous,
            Effect::Cogging { .. } => EffectId::Cogging,
            Effect::QuadraticDamping => EffectId::QuadraticDamping,
            Effect::PreslidingFriction { .. } => EffectId::PreslidingFriction,
        }
    }

    /// Stable identifier (the serde tag): [`EffectId::as_str`] of
    /// [`kind`](Self::kind).
    pub fn id(&self) -> &'static str {
        self.kind().as_str()
    }

    /// Number of regressor columns (= parameters).
    pub fn columns(&self) -> usize {
        match *self {
            Effect::RigidLinks => rigid_links::COLUMNS,
            Effect::Friction { .. } => friction::NAMES.len(),
            Effect::PassiveJointViscous => passive_joint_viscous::NAMES.len(),
            Effect::Cogging { order, .. } => cogging::columns(order),
            Effect::PreslidingFriction { .. } => presliding_friction::NAMES.len(),
            _ => 2,
        }
    }

    /// Parameter names in column order.
    pub fn names(&self) -> Vec<String> {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect();
        match *self {
            Effect::RigidLinks => rigid_links::names(),
            Effect::Friction { .. } => s(&friction::NAMES),
            Effect::Elasticity => s(&elasticity::NAMES),
            Effect::TorqueOffset => s(&torque_offset::NAMES),
            Effect::CoulombAsymmetry => s(&coulomb_asymmetry::NAMES),
            Effect::StribeckFriction { .. } => s(&stribeck_friction::NAMES),
            Effect::PassiveJointViscous => s(&passive_joint_viscous::NAMES),
            Effect::Cogging { order, .. } => cogging::names(order),
            Effect::QuadraticDamping => s(&quadratic_damping::NAMES),
            Effect::PreslidingFriction { .. } => s(&presliding_friction::NAMES),
        }
    }

    /// Checks the settings.
    pub fn validate(&self) -> Result<(), DynError> {
        match *self {
            Effect::Friction { w } => friction::validate(w),
            Effect::StribeckFriction { v_s } => stribeck_friction::validate(v_s),
            Effect::Cogging {
                cycles_per_rev,
                order,
            } => cogging::validate(cycles_per_rev, order),
            Effect::PreslidingFriction { displacement } => {
                presliding_friction::validate(displacement)
            }
            _ => Ok(()),
        }
    }

    /// Why such an effect exists physically, and how it shows in the data
    /// (the diagnosis quotes it when it names the effect).
    pub fn explanation(&self) -> &'static str {
        self.kind().explanation()
    }

    /// The parameters physics keeps non-negative, (70): what the physically
    /// consistent fit imposes (least squares leaves every sign free). Rigid
    /// links have a matrix constraint instead (the pseudo-inertia,
    /// (67)–(69)); an offset, a Coulomb asymmetry and cogging may have
    /// either sign.
    pub fn nonnegative(&self) -> &'static [&'static str] {
        match self {
            Effect::Friction { .. } => friction::NONNEGATIVE,
            Effect::Elasticity => elasticity::NONNEGATIVE,
            Effect::StribeckFriction { .. } => stribeck_friction::NONNEGATIVE,
            Effect::PassiveJointViscous => passive_joint_viscous::NONNEGATIVE,
            Effect::QuadraticDamping => quadratic_damping::NONNEGATIVE,
            Effect::PreslidingFriction { .. } => presliding_friction::NONNEGATIVE,
            Effect::RigidLinks
            | Effect::TorqueOffset
            | Effect::CoulombAsymmetry
            | Effect::Cogging { .. } => &[],
        }
    }

    /// True for the three effects of the paper's model.
    pub fn is_paper(&self) -> bool {
        !EffectId::EXTRA.contains(&self.kind())
    }

    /// True for an effect with an internal state ([`Effect::PreslidingFriction`]):
    /// its columns depend on the samples before, so they are computed along
    /// a stacked sequence ([`crate::Model::stacked`]) and one sample's
    /// regressor cannot hold them.
    pub fn is_stateful(&self) -> bool {
        matches!(self, Effect::PreslidingFriction { .. })
    }
}

impl Effect {
    /// Writes this effect's 2×`columns()` block (column-major) for one
    /// sample. `out.len()` must be `2 * self.columns()`.
    #[inline]
    pub(crate) fn fill<T: Scalar>(
        &self,
        s: &KinematicSample<T>,
        g: &Vector3<T>,
        sign: Sign,
        out: &mut [T],
    ) {
        match *self {
            Effect::RigidLinks => rigid_links::fill(s, g, out),
            Effect::Friction { w } => friction::fill(s, w, sign, out),
            Effect::Elasticity => elasticity::fill(s, out),
            Effect::TorqueOffset => torque_offset::fill(out),
            Effect::CoulombAsymmetry => coulomb_asymmetry::fill(s, sign, out),
            Effect::StribeckFriction { v_s } => stribeck_friction::fill(s, v_s, sign, out),
            Effect::PassiveJointViscous => passive_joint_viscous::fill(s, out),
            Effect::Cogging {
                cycles_per_rev,
                order,
            } => cogging::fill(s, cycles_per_rev, order, out),
            Effect::QuadraticDamping => quadratic_damping::fill(s, out),
            // A state: filled along the stacked sequence, zero here.
            Effect::PreslidingFriction { .. } => out.fill(T::zero()),
        }
    }
}

/// A 2×2 diagonal block `diag(a, b)`, column-major: one column per joint.
#[inline(always)]
fn diagonal<T: Scalar>(a: T, b: T, out: &mut [T]) {
    let z = T::zero();
    out[0] = a;
    out[1] = z;
    out[2] = z;
    out[3] = b;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every effect: as many names as columns, distinct; an explanation;
    /// its sign constraints name its own parameters; the identifier round
    /// trips.
    #[test]
    fn each_effect_is_complete() {
        let all = [
            Effect::RigidLinks,
            Effect::Friction { w: [0.03, 0.0] },
            Effect::Elasticity,
            Effect::TorqueOffset,
            Effect::CoulombAsymmetry,
            Effect::StribeckFriction { v_s: 0.05 },
            Effect::PassiveJointViscous,
            Effect::Cogging {
                cycles_per_rev: 12.0,
                order: 3,
            },
            Effect::QuadraticDamping,
            Effect::PreslidingFriction { displacement: 5e-4 },
        ];
        assert_eq!(all.map(|e| e.kind()), EffectId::ALL);
        // The paper's model is rigid links, friction and elasticity (42);
        // every other effect is an extra, in `ALL`'s order.
        assert_eq!(
            all.map(|e| e.is_paper()),
            [
                true, true, true, false, false, false, false, false, false, false
            ]
        );
        // Only the bristle has a state.
        assert_eq!(
            all.map(|e| e.is_stateful()),
            [
                false, false, false, false, false, false, false, false, false, true
            ]
        );
        for bad in [0.0, -1e-3, f64::NAN] {
            assert!(
                Effect::PreslidingFriction { displacement: bad }
                    .validate()
                    .is_err()
            );
        }
        assert_eq!(EffectId::EXTRA[..], EffectId::ALL[3..]);
        for e in all {
            let names = e.names();
            assert_eq!(names.len(), e.columns(), "{e:?}");
            let mut unique = names.clone();
            unique.sort();
            unique.dedup();
            assert_eq!(unique.len(), names.len(), "{e:?}");
            assert!(e.explanation().len() > 40, "{e:?}");
            assert!(
                e.nonnegative().iter().all(|n| names.iter().any(|m| m == n)),
                "{e:?}"
            );
            assert_eq!(e.id().parse::<EffectId>().unwrap(), e.kind());
            e.validate().unwrap();
        }
        assert!(Effect::StribeckFriction { v_s: 0.0 }.validate().is_err());
        for bad in [-1e-3, f64::NAN, f64::INFINITY] {
            let e = Effect::Friction { w: [0.01, bad] }.validate().unwrap_err();
            let text = e.to_string();
            assert!(
                text.contains("w[1] (joint 2)") && text.contains("≥ 0"),
                "{text}"
            );
        }
        assert!(
            Effect::Cogging {
                cycles_per_rev: 1.0,
                order: 17
            }
            .validate()
            .is_err()
        );
    }
}
