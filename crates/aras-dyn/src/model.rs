//! A model is an ordered list of effects ([`Effect`], one file each under
//! `effects/`); each contributes named regressor columns and the matching
//! standard parameters, (51)–(53).
//!
//! The paper's model is [`Model::paper`]: rigid links (36 columns,
//! (38)–(46)), viscous + Coulomb friction (49) and elasticity (50), 42 in
//! all. The extra effects are candidates for the discrepancy workflow and
//! are used by the simulator; their identifiers ([`Effect::id`]) and
//! parameter names are stable.

use std::ops::Range;

use nalgebra::{DVector, Vector3};

use crate::params::{Cogging, Presliding, Stribeck};
use crate::{DynError, Effect, Params};

/// An ordered list of effects plus the gravity vector the rigid-link
/// columns use. Columns are laid out effect after effect, in list order.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    effects: Vec<Effect>,
    offsets: Vec<usize>,
    columns: usize,
    gravity: Vector3<f64>,
}

impl Model {
    /// A model from a list of effects (each at most once, valid settings)
    /// and a finite gravity vector in {0} (m/s²).
    pub fn new(effects: Vec<Effect>, gravity: Vector3<f64>) -> Result<Self, DynError> {
        for (i, g) in gravity.iter().enumerate() {
            if !g.is_finite() {
                return Err(DynError::NonFinite {
                    name: ["gravity.x", "gravity.y", "gravity.z"][i],
                    value: *g,
                });
            }
        }
        let mut offsets = Vec::with_capacity(effects.len());
        let mut columns = 0;
        for (i, e) in effects.iter().enumerate() {
            e.validate()?;
            if effects[..i].iter().any(|o| o.id() == e.id()) {
                return Err(DynError::DuplicateEffect { id: e.id() });
            }
            offsets.push(columns);
            columns += e.columns();
        }
        Ok(Self {
            effects,
            offsets,
            columns,
            gravity,
        })
    }

    /// The paper's 42-column model: rigid links, friction, elasticity.
    pub fn paper(gravity: Vector3<f64>) -> Result<Self, DynError> {
        Self::new(
            vec![
                Effect::RigidLinks,
                Effect::FRICTION_SIGN_LAW,
                Effect::Elasticity,
            ],
            gravity,
        )
    }

    /// This model with one more effect appended (its columns come last).
    pub fn with_effect(&self, e: Effect) -> Result<Self, DynError> {
        let mut v = self.effects.clone();
        v.push(e);
        Self::new(v, self.gravity)
    }

    /// The effects, in column order.
    pub fn effects(&self) -> &[Effect] {
        &self.effects
    }

    /// Gravity in {0} (m/s²).
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }

    /// Total number of columns `n` (standard parameters).
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// Column names (standard parameter names) in order.
    pub fn names(&self) -> Vec<String> {
        self.effects.iter().flat_map(|e| e.names()).collect()
    }

    /// Columns of the effect with identifier `id`, if present.
    pub fn column_range(&self, id: &str) -> Option<Range<usize>> {
        self.effects
            .iter()
            .zip(&self.offsets)
            .find(|(e, _)| e.id() == id)
            .map(|(e, &o)| o..o + e.columns())
    }

    /// Effects with their first column.
    pub(crate) fn layout(&self) -> impl Iterator<Item = (&Effect, usize)> {
        self.effects.iter().zip(self.offsets.iter().copied())
    }
}

impl Params {
    /// The model these parameters describe: the paper's three effects, then
    /// every extra effect present (in the order of [`Extras`](crate::Extras)'s
    /// fields), with these parameters' gravity.
    pub fn model(&self) -> Result<Model, DynError> {
        let mut v = vec![
            Effect::RigidLinks,
            Effect::Friction {
                w: self.friction.width,
            },
            Effect::Elasticity,
        ];
        let e = &self.extra;
        if e.torque_offset.is_some() {
            v.push(Effect::TorqueOffset);
        }
        if e.coulomb_asymmetry.is_some() {
            v.push(Effect::CoulombAsymmetry);
        }
        if let Some(s) = &e.stribeck_friction {
            v.push(Effect::StribeckFriction { v_s: s.v_s });
        }
        if e.passive_joint_viscous.is_some() {
            v.push(Effect::PassiveJointViscous);
        }
        if let Some(c) = &e.cogging {
            v.push(Effect::Cogging {
                cycles_per_rev: c.cycles_per_rev,
                order: c.order(),
            });
        }
        if e.quadratic_damping.is_some() {
            v.push(Effect::QuadraticDamping);
        }
        if let Some(b) = &e.presliding_friction {
            v.push(Effect::PreslidingFriction {
                displacement: b.displacement,
            });
        }
        Model::new(v, self.gravity)
    }

    /// The standard parameter vector `β` for `model` (column order of
    /// [`Model::names`]). Effects absent from the parameters are zero; an
    /// effect present with other settings than the model's is an error.
    pub fn standard_vector(&self, model: &Model) -> Result<DVector<f64>, DynError> {
        self.validate()?;
        let mut out = DVector::zeros(model.columns());
        for (e, o) in model.layout() {
            let dst = &mut out.as_mut_slice()[o..o + e.columns()];
            let x = &self.extra;
            match *e {
                Effect::RigidLinks => {
                    for (k, l) in self.links.iter().enumerate() {
                        dst[9 * k..9 * k + 9].copy_from_slice(&l.standard());
                    }
                }
                // The widths shape the columns; the coefficients are the
                // same whatever they are (a reference robot with the sign
                // law serves a model with refined widths).
                Effect::Friction { .. } => {
                    let f = &self.friction;
                    dst.copy_from_slice(&[f.viscous[0], f.coulomb[0], f.viscous[1], f.coulomb[1]]);
                }
                Effect::Elasticity => dst.copy_from_slice(&self.elasticity),
                Effect::TorqueOffset => dst.copy_from_slice(&x.torque_offset.unwrap_or_default()),
                Effect::CoulombAsymmetry => {
                    dst.copy_from_slice(&x.coulomb_asymmetry.unwrap_or_default())
                }
                Effect::StribeckFriction { v_s } => {
                    if let Some(s) = &x.stribeck_friction {
                        same(e, "v_s", s.v_s, v_s)?;
                        dst.copy_from_slice(&s.level);
                    }
                }
                Effect::PassiveJointViscous => {
                    dst.copy_from_slice(&x.passive_joint_viscous.unwrap_or_default())
                }
                Effect::Cogging {
                    cycles_per_rev,
                    order,
                } => {
                    if let Some(c) = &x.cogging {
                        same(e, "cycles_per_rev", c.cycles_per_rev, cycles_per_rev)?;
                        same(e, "order", c.order() as f64, order as f64)?;
                        let mut i = 0;
                        for j in 0..2 {
                            for h in 0..order {
                                dst[i] = c.sin[j][h];
                                dst[i + 1] = c.cos[j][h];
                                i += 2;
                            }
                        }
                    }
                }
                Effect::QuadraticDamping => {
                    dst.copy_from_slice(&x.quadratic_damping.unwrap_or_default())
                }
                Effect::PreslidingFriction { displacement } => {
                    if let Some(b) = &x.presliding_friction {
                        same(e, "displacement", b.displacement, displacement)?;
                        dst.copy_from_slice(&b.coefficients());
                    }
                }
            }
        }
        Ok(out)
    }

    /// Sets every parameter of `model`'s effects from a standard vector;
    /// everything else (geometry, gravity, masses, effects not in the model)
    /// is kept. Extra effects in the model become present with the model's
    /// settings. Errors on a wrong length or a non-finite entry (naming its
    /// parameter).
    pub fn set_standard_vector(&mut self, model: &Model, v: &[f64]) -> Result<(), DynError> {
        if v.len() != model.columns() {
            return Err(DynError::Length {
                what: "standard parameter vector",
                expected: model.columns(),
                found: v.len(),
            });
        }
        let names = model.names();
        for (x, n) in v.iter().zip(&names) {
            if !x.is_finite() {
                return Err(DynError::Param(crate::ParamError::NonFinite {
                    key: n.clone(),
                    value: *x,
                }));
            }
        }
        for (e, o) in model.layout() {
            let src = &v[o..o + e.columns()];
            let two = || [src[0], src[1]];
            let x = &mut self.extra;
            match *e {
                Effect::RigidLinks => {
                    for (k, l) in self.links.iter_mut().enumerate() {
                        let mut a = [0.0; 9];
                        a.copy_from_slice(&src[9 * k..9 * k + 9]);
                        l.set_standard(&a);
                    }
                }
                Effect::Friction { w } => {
                    self.friction.width = w;
                    self.friction.viscous = [src[0], src[2]];
                    self.friction.coulomb = [src[1], src[3]];
                }
                Effect::Elasticity => self.elasticity = two(),
                Effect::TorqueOffset => x.torque_offset = Some(two()),
                Effect::CoulombAsymmetry => x.coulomb_asymmetry = Some(two()),
                Effect::StribeckFriction { v_s } => {
                    x.stribeck_friction = Some(Stribeck { v_s, level: two() })
                }
                Effect::PassiveJointViscous => {
                    x.passive_joint_viscous = Some([src[0], src[1], src[2]])
                }
                Effect::Cogging {
                    cycles_per_rev,
                    order,
                } => {
                    let mut c = Cogging {
                        cycles_per_rev,
                        sin: [vec![0.0; order], vec![0.0; order]],
                        cos: [vec![0.0; order], vec![0.0; order]],
                    };
                    let mut i = 0;
                    for j in 0..2 {
                        for h in 0..order {
                            c.sin[j][h] = src[i];
                            c.cos[j][h] = src[i + 1];
                            i += 2;
                        }
                    }
                    x.cogging = Some(c);
                }
                Effect::QuadraticDamping => x.quadratic_damping = Some(two()),
                Effect::PreslidingFriction { displacement } => {
                    x.presliding_friction = Some(Presliding {
                        displacement,
                        level: two(),
                        damping: [src[2], src[3]],
                    })
                }
            }
        }
        Ok(())
    }
}

fn same(
    e: &Effect,
    setting: &'static str,
    params_value: f64,
    model_value: f64,
) -> Result<(), DynError> {
    if params_value == model_value {
        Ok(())
    } else {
        Err(DynError::SettingMismatch {
            id: e.id(),
            setting,
            params_value,
            model_value,
        })
    }
}
