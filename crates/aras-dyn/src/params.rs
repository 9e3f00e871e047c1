//! Standard parameters of the robot and their JSON file format
//! (`docs/parameter-format.md`).
//!
//! Per link (1–4, paper numbering): the inertia tensor about the RCM in the
//! link frame and the first moment of mass `h = m ρ`, (28)–(30), (46),
//! plus the mass for consistency checks only (the links only rotate about the
//! RCM, so `m` never enters the dynamics); friction (49), elasticity (50),
//! gravity, geometry, and optional parameters of the extra effects.

use std::path::Path;

use aras_kin::Geometry;
use nalgebra::{Matrix4, Vector3};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::Value;

use crate::ParamError;
use crate::effects::{
    COULOMB_ASYMMETRY_NAMES, ELASTICITY_NAMES, FRICTION_NAMES, PASSIVE_JOINT_VISCOUS_NAMES,
    PRESLIDING_FRICTION_NAMES, QUADRATIC_DAMPING_NAMES, STRIBECK_FRICTION_NAMES,
    TORQUE_OFFSET_NAMES, cogging_names,
};
use crate::json::{Obj, finite, parse};
use crate::{Effect, EffectId, Inertia};

/// JSON keys of a link, in file order (`mass` last).
pub(crate) const LINK_KEYS: [&str; 10] = [
    "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz", "hx", "hy", "hz", "mass",
];

/// Viscous and Coulomb friction per actuator:
/// `τ_j = Fv_j θ̇_j + Fc_j tanh(θ̇_j / w_j)`, the sign law (49) where `w_j = 0`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Friction {
    /// Viscous coefficients `[Fv1, Fv2]` (N·m·s/rad).
    pub viscous: [f64; 2],
    /// Coulomb levels `[Fc1, Fc2]` (N·m).
    pub coulomb: [f64; 2],
    /// Coulomb transition widths `[w1, w2]` (rad/s, ≥ 0; 0 = `sign`, (49)):
    /// the file's optional `friction.w`, absent = `[0, 0]`.
    pub width: [f64; 2],
}

/// Stribeck friction: `τ_j = Fs_j sign(θ̇_j) exp(−(θ̇_j/v_s)²)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stribeck {
    /// Shape velocity `v_s` (rad/s, > 0), a fixed non-linear setting.
    pub v_s: f64,
    /// Levels `[Fs1, Fs2]` (N·m).
    pub level: [f64; 2],
}

/// Presliding (LuGre bristle) friction: `τ_j = Fb_j s_j + Db_j ż_j` with the
/// bristle state `s_j` and rate `ż_j` of
/// [`Effect::PreslidingFriction`](crate::Effect::PreslidingFriction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Presliding {
    /// Presliding displacement `δ = Fc/σ0` (rad, > 0), a fixed non-linear
    /// setting.
    pub displacement: f64,
    /// Levels `[Fb1, Fb2]` (N·m).
    pub level: [f64; 2],
    /// Bristle dampings `[Db1, Db2]` (N·m·s/rad).
    pub damping: [f64; 2],
}

impl Presliding {
    /// The coefficients in the effect's column order, `[Fb1, Fb2, Db1, Db2]`.
    pub fn coefficients(&self) -> [f64; 4] {
        [
            self.level[0],
            self.level[1],
            self.damping[0],
            self.damping[1],
        ]
    }
}

/// Cogging torque per joint: `Σ_h Cs_jh sin(h n_c θ_j) + Cc_jh cos(h n_c θ_j)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Cogging {
    /// Cycles per joint revolution `n_c` (> 0).
    pub cycles_per_rev: f64,
    /// Sine amplitudes per joint, one per harmonic (N·m); both joints have
    /// the same number of harmonics (the order).
    pub sin: [Vec<f64>; 2],
    /// Cosine amplitudes per joint (N·m), same lengths as `sin`.
    pub cos: [Vec<f64>; 2],
}

impl Cogging {
    /// Number of harmonics.
    pub fn order(&self) -> usize {
        self.sin[0].len()
    }
}

/// Parameters of the optional extra effects (see [`Effect`](crate::Effect)).
/// `None` means the effect is absent (zero).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Extras {
    /// Constant torque offsets `[tau0_1, tau0_2]` (N·m).
    pub torque_offset: Option<[f64; 2]>,
    /// Coulomb asymmetry `[Fca1, Fca2]` (N·m): the Coulomb level is
    /// `Fc + Fca` moving forward and `Fc − Fca` moving backward.
    pub coulomb_asymmetry: Option<[f64; 2]>,
    /// Stribeck friction.
    pub stribeck_friction: Option<Stribeck>,
    /// Viscous friction in the passive hinges `[Fpb, Fpc, Fpd]` (N·m·s/rad).
    pub passive_joint_viscous: Option<[f64; 3]>,
    /// Cogging torque.
    pub cogging: Option<Cogging>,
    /// Quadratic damping `[Fq1, Fq2]` (N·m·s²/rad²): `τ = Fq θ̇|θ̇|`.
    pub quadratic_damping: Option<[f64; 2]>,
    /// Presliding (bristle) friction, a state along the motion.
    pub presliding_friction: Option<Presliding>,
}

impl Extras {
    /// True if no extra effect is present.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// The robot's standard parameters: the JSON parameter file in memory.
///
/// Fields are public for convenience; every consumer calls
/// [`Params::validate`] (file reading does it), so non-finite values are
/// reported, never propagated.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// Proximal arc α (degrees), as in the file.
    pub alpha_deg: f64,
    /// Distal arc β (degrees).
    pub beta_deg: f64,
    /// Gravity in the base frame {0} (m/s²); default `[0, −9.81, 0]`.
    pub gravity: Vector3<f64>,
    /// Links 1–4 (paper numbering) at index 0–3.
    pub links: [Inertia; 4],
    /// Viscous + Coulomb friction (49).
    pub friction: Friction,
    /// Capstan elasticity `[Ke1, Ke2]` (N·m/rad), (50).
    pub elasticity: [f64; 2],
    /// Optional extra effects.
    pub extra: Extras,
}

/// Default gravity `[0, −9.81, 0]` m/s²: the real robot's axis `a` is horizontal.
pub const DEFAULT_GRAVITY: [f64; 3] = [0.0, -9.81, 0.0];

impl Params {
    /// All-zero parameters on the given geometry (degrees) with default gravity.
    pub fn zero(alpha_deg: f64, beta_deg: f64) -> Self {
        Self {
            alpha_deg,
            beta_deg,
            gravity: Vector3::from(DEFAULT_GRAVITY),
            links: [Inertia::default(); 4],
            friction: Friction::default(),
            elasticity: [0.0; 2],
            extra: Extras::default(),
        }
    }

    /// The validated geometry.
    pub fn geometry(&self) -> Result<Geometry, ParamError> {
        for (key, v) in [
            ("geometry.alpha_deg", self.alpha_deg),
            ("geometry.beta_deg", self.beta_deg),
        ] {
            finite(v, key)?;
            if !(v > 0.0 && v < 180.0) {
                return Err(ParamError::Invalid {
                    key: key.into(),
                    value: v,
                    reason: "arc angles must lie strictly between 0 and 180 degrees",
                });
            }
        }
        Geometry::from_degrees(self.alpha_deg, self.beta_deg).map_err(|_| ParamError::Invalid {
            key: "geometry".into(),
            value: self.alpha_deg,
            reason: "the arcs do not form a valid geometry",
        })
    }

    /// Pseudo-inertia of link `k` (1–4, paper numbering; index `k − 1`),
    /// see [`Inertia::pseudo_inertia`]. A link number outside 1–4 is a
    /// [`ParamError::Invalid`] (it used to panic: a caller's off-by-one
    /// must not abort a long identification run).
    pub fn pseudo_inertia(&self, k: usize) -> Result<Matrix4<f64>, ParamError> {
        match k.checked_sub(1).and_then(|i| self.links.get(i)) {
            Some(l) => Ok(l.pseudo_inertia()),
            None => Err(ParamError::Invalid {
                key: "link".into(),
                value: k as f64,
                reason: "links are numbered 1 to 4 (paper numbering); use 1..=4",
            }),
        }
    }

    /// Physical consistency of every link, (67)–(69): a positive mass
    /// and a positive-definite pseudo-inertia (positive-definite inertia
    /// about the COM satisfying the triangle inequality); and the signs of
    /// the friction, damping and stiffness coefficients
    /// ([`Params::check_signs`]). [`Params::validate`]
    /// does not ask this, because an OLS estimate may legitimately violate
    /// it; call this where the parameters must describe real bodies.
    ///
    /// A pseudo-inertia eigenvalue below `−1e-9·‖𝒥‖` (far below the rounding
    /// of a parameter file's 17 digits) fails; a point mass (a zero
    /// eigenvalue) passes.
    pub fn check_physical(&self) -> Result<(), ParamError> {
        for (k, l) in self.links.iter().enumerate() {
            let link = k + 1;
            if l.mass.is_nan() || l.mass <= 0.0 {
                return Err(ParamError::NotPhysical {
                    link,
                    reason: format!("mass = {} kg is not positive", l.mass),
                });
            }
            let j = l.pseudo_inertia();
            let scale = j.norm();
            let eig = j.symmetric_eigenvalues();
            let min = eig.min();
            if !min.is_finite() || min < -1e-9 * scale {
                return Err(ParamError::NotPhysical {
                    link,
                    reason: format!(
                        "its pseudo-inertia has the negative eigenvalue {min:.4e} (largest {:.4e}): \
                         the inertia about the centre of mass is not positive definite or breaks \
                         the triangle inequality",
                        eig.max()
                    ),
                });
            }
        }
        self.check_signs()
    }

    /// Checks the signs physics requires of the dissipative and elastic
    /// coefficients of every effect in the file ([`Effect::nonnegative`]:
    /// viscous and Coulomb friction, stiffness, Stribeck, passive-joint and
    /// quadratic damping ≥ 0). Part of [`Params::check_physical`].
    pub fn check_signs(&self) -> Result<(), ParamError> {
        let model = self.model().map_err(|_| ParamError::Invalid {
            key: "extra".into(),
            value: f64::NAN,
            reason: "the extra effects do not form a model",
        })?;
        let values = self
            .standard_vector(&model)
            .map_err(|_| ParamError::Invalid {
                key: "extra".into(),
                value: f64::NAN,
                reason: "the extra effects do not form a model",
            })?;
        let mut column = 0;
        for effect in model.effects() {
            let names = effect.names();
            let nonnegative = effect.nonnegative();
            for (k, name) in names.iter().enumerate() {
                let value = values[column + k];
                if nonnegative.contains(&name.as_str()) && value < 0.0 {
                    return Err(ParamError::NegativeCoefficient {
                        key: format!("{}.{name}", effect.id()),
                        value,
                    });
                }
            }
            column += names.len();
        }
        Ok(())
    }

    /// Checks every value: finite numbers, valid geometry, valid effect
    /// settings. Errors name the key path as in the file.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.geometry()?;
        for (i, g) in self.gravity.iter().enumerate() {
            finite(*g, &format!("gravity[{i}]"))?;
        }
        for (k, l) in self.links.iter().enumerate() {
            let vals = l.standard();
            for (key, v) in LINK_KEYS.iter().zip(vals.iter().chain([l.mass].iter())) {
                finite(*v, &format!("links.{}.{key}", k + 1))?;
            }
        }
        for j in 0..2 {
            finite(self.friction.viscous[j], &format!("friction.Fv{}", j + 1))?;
            finite(self.friction.coulomb[j], &format!("friction.Fc{}", j + 1))?;
            finite(self.elasticity[j], &format!("elasticity.Ke{}", j + 1))?;
            let w = self.friction.width[j];
            let key = format!("friction.w[{j}]");
            finite(w, &key)?;
            if w < 0.0 {
                return Err(ParamError::Invalid {
                    key,
                    value: w,
                    reason: "the Coulomb transition width must be ≥ 0 rad/s (0 is the sign law \
                             (49)); give a non-negative width or leave `w` out",
                });
            }
        }
        let e = &self.extra;
        // Keys `extra.<effect>.<parameter>`, the parameters named by the
        // effect itself.
        let check = |effect: Effect, v: &[f64]| -> Result<(), ParamError> {
            for (n, x) in effect.names().iter().zip(v) {
                finite(*x, &format!("extra.{}.{n}", effect.id()))?;
            }
            Ok(())
        };
        if let Some(v) = &e.torque_offset {
            check(Effect::TorqueOffset, v)?;
        }
        if let Some(v) = &e.coulomb_asymmetry {
            check(Effect::CoulombAsymmetry, v)?;
        }
        if let Some(s) = &e.stribeck_friction {
            finite(s.v_s, "extra.stribeck_friction.v_s")?;
            check(Effect::StribeckFriction { v_s: s.v_s }, &s.level)?;
            if s.v_s <= 0.0 {
                return Err(ParamError::Invalid {
                    key: "extra.stribeck_friction.v_s".into(),
                    value: s.v_s,
                    reason: "the Stribeck velocity must be positive (rad/s)",
                });
            }
        }
        if let Some(v) = &e.passive_joint_viscous {
            check(Effect::PassiveJointViscous, v)?;
        }
        if let Some(b) = &e.presliding_friction {
            let key = "extra.presliding_friction.displacement";
            finite(b.displacement, key)?;
            check(
                Effect::PreslidingFriction {
                    displacement: b.displacement,
                },
                &b.coefficients(),
            )?;
            if b.displacement <= 0.0 {
                return Err(ParamError::Invalid {
                    key: key.into(),
                    value: b.displacement,
                    reason: "the presliding displacement must be positive (rad)",
                });
            }
        }
        if let Some(c) = &e.cogging {
            let key = "extra.cogging.cycles_per_rev";
            finite(c.cycles_per_rev, key)?;
            if c.cycles_per_rev <= 0.0 {
                return Err(ParamError::Invalid {
                    key: key.into(),
                    value: c.cycles_per_rev,
                    reason: "the number of cogging cycles per revolution must be positive",
                });
            }
            let n = c.order();
            if n == 0 || n > MAX_COGGING_ORDER {
                return Err(ParamError::Invalid {
                    key: "extra.cogging.order".into(),
                    value: n as f64,
                    reason: "the cogging order must be between 1 and 16",
                });
            }
            for j in 0..2 {
                for (kind, v) in [("Cs", &c.sin[j]), ("Cc", &c.cos[j])] {
                    if v.len() != n {
                        return Err(ParamError::Invalid {
                            key: format!("extra.cogging.{kind}{}_*", j + 1),
                            value: v.len() as f64,
                            reason: "every joint needs one sine and one cosine amplitude per harmonic",
                        });
                    }
                    for (h, x) in v.iter().enumerate() {
                        finite(*x, &format!("extra.cogging.{kind}{}_{}", j + 1, h + 1))?;
                    }
                }
            }
        }
        if let Some(v) = &e.quadratic_damping {
            check(Effect::QuadraticDamping, v)?;
        }
        Ok(())
    }

    /// Reads and validates a parameter file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ParamError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ParamError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json_str(&text).map_err(|e| ParamError::InFile {
            path: path.to_path_buf(),
            source: Box::new(e),
        })
    }

    /// Writes the parameter file (pretty JSON, shortest round-trip numbers),
    /// atomically ([`aras_log::write_atomic`]: a new temporary file in the
    /// same directory, then a rename; no other file is touched).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), ParamError> {
        let path = path.as_ref();
        self.validate()?;
        let io = |source| ParamError::Io {
            path: path.to_path_buf(),
            source,
        };
        let mut text = self.to_json_string();
        text.push('\n');
        aras_log::write_atomic(path, |w| w.write_all(text.as_bytes())).map_err(io)
    }

    /// Pretty JSON text of the parameter file.
    pub fn to_json_string(&self) -> String {
        serde_json::to_string_pretty(self).expect("parameters always serialise")
    }

    /// Parses and validates parameter-file text.
    pub fn from_json_str(text: &str) -> Result<Self, ParamError> {
        Self::from_value(&parse(text)?)
    }

    /// Reads and validates a parsed JSON value (strict: every key required
    /// except `gravity` and `extra`, no unknown keys, finite numbers).
    pub fn from_value(v: &Value) -> Result<Self, ParamError> {
        let top = Obj::new(v, "")?;
        top.only(&[
            "geometry",
            "gravity",
            "links",
            "friction",
            "elasticity",
            "extra",
        ])?;
        let geo = top.obj("geometry")?;
        geo.only(&["alpha_deg", "beta_deg"])?;
        let mut p = Self::zero(geo.num("alpha_deg")?, geo.num("beta_deg")?);
        if top.opt("gravity").is_some() {
            p.gravity = Vector3::from(top.nums::<3>("gravity")?);
        }
        let links = top.obj("links")?;
        links.only(&["1", "2", "3", "4"])?;
        for (k, l) in p.links.iter_mut().enumerate() {
            let o = links.obj(&(k + 1).to_string())?;
            o.only(&LINK_KEYS)?;
            let mut std9 = [0.0; 9];
            for (s, key) in std9.iter_mut().zip(LINK_KEYS) {
                *s = o.num(key)?;
            }
            l.set_standard(&std9);
            l.mass = o.num("mass")?;
        }
        let f = top.obj("friction")?;
        let [fv1, fc1, fv2, fc2] = FRICTION_NAMES;
        f.only(&[fv1, fc1, fv2, fc2, "w"])?;
        p.friction = Friction {
            viscous: [f.num(fv1)?, f.num(fv2)?],
            coulomb: [f.num(fc1)?, f.num(fc2)?],
            width: if f.opt("w").is_some() {
                f.nums::<2>("w")?
            } else {
                [0.0; 2]
            },
        };
        let e = top.obj("elasticity")?;
        p.elasticity = pair(&e, ELASTICITY_NAMES)?;
        if top.opt("extra").is_some() {
            p.extra = read_extras(&top.obj("extra")?)?;
        }
        p.validate()?;
        Ok(p)
    }
}

/// Largest cogging order accepted.
pub const MAX_COGGING_ORDER: usize = 16;

fn pair(o: &Obj, [a, b]: [&str; 2]) -> Result<[f64; 2], ParamError> {
    o.only(&[a, b])?;
    Ok([o.num(a)?, o.num(b)?])
}

fn read_extras(x: &Obj) -> Result<Extras, ParamError> {
    x.only(&EffectId::EXTRA.map(EffectId::as_str))?;
    let mut e = Extras::default();
    let has = |k: &str| x.opt(k).is_some();
    if has(EffectId::TorqueOffset.as_str()) {
        e.torque_offset = Some(pair(
            &x.obj(EffectId::TorqueOffset.as_str())?,
            TORQUE_OFFSET_NAMES,
        )?);
    }
    if has(EffectId::CoulombAsymmetry.as_str()) {
        e.coulomb_asymmetry = Some(pair(
            &x.obj(EffectId::CoulombAsymmetry.as_str())?,
            COULOMB_ASYMMETRY_NAMES,
        )?);
    }
    if has(EffectId::StribeckFriction.as_str()) {
        let o = x.obj(EffectId::StribeckFriction.as_str())?;
        let [fs1, fs2] = STRIBECK_FRICTION_NAMES;
        o.only(&["v_s", fs1, fs2])?;
        e.stribeck_friction = Some(Stribeck {
            v_s: o.num("v_s")?,
            level: [o.num(fs1)?, o.num(fs2)?],
        });
    }
    if has(EffectId::PassiveJointViscous.as_str()) {
        let o = x.obj(EffectId::PassiveJointViscous.as_str())?;
        o.only(&PASSIVE_JOINT_VISCOUS_NAMES)?;
        let [b, c, d] = PASSIVE_JOINT_VISCOUS_NAMES;
        e.passive_joint_viscous = Some([o.num(b)?, o.num(c)?, o.num(d)?]);
    }
    if has(EffectId::Cogging.as_str()) {
        let o = x.obj(EffectId::Cogging.as_str())?;
        let order_v = o.num("order")?;
        if order_v.fract() != 0.0 || order_v < 1.0 || order_v > MAX_COGGING_ORDER as f64 {
            return Err(ParamError::Invalid {
                key: o.key_path("order"),
                value: order_v,
                reason: "the cogging order must be an integer between 1 and 16",
            });
        }
        let order = order_v as usize;
        let names = cogging_names(order);
        let mut keys = vec!["cycles_per_rev", "order"];
        keys.extend(names.iter().map(String::as_str));
        o.only(&keys)?;
        let mut c = Cogging {
            cycles_per_rev: o.num("cycles_per_rev")?,
            sin: [vec![0.0; order], vec![0.0; order]],
            cos: [vec![0.0; order], vec![0.0; order]],
        };
        // Names in column order: per joint, per harmonic the sine then the
        // cosine.
        let slots = (0..2).flat_map(|j| (0..order).map(move |h| (j, h)));
        for ((j, h), pair) in slots.zip(names.chunks_exact(2)) {
            c.sin[j][h] = o.num(&pair[0])?;
            c.cos[j][h] = o.num(&pair[1])?;
        }
        e.cogging = Some(c);
    }
    if has(EffectId::QuadraticDamping.as_str()) {
        e.quadratic_damping = Some(pair(
            &x.obj(EffectId::QuadraticDamping.as_str())?,
            QUADRATIC_DAMPING_NAMES,
        )?);
    }
    if has(EffectId::PreslidingFriction.as_str()) {
        let o = x.obj(EffectId::PreslidingFriction.as_str())?;
        let [fb1, fb2, db1, db2] = PRESLIDING_FRICTION_NAMES;
        o.only(&["displacement", fb1, fb2, db1, db2])?;
        e.presliding_friction = Some(Presliding {
            displacement: o.num("displacement")?,
            level: [o.num(fb1)?, o.num(fb2)?],
            damping: [o.num(db1)?, o.num(db2)?],
        });
    }
    Ok(e)
}

/// `(name, value)` pairs of equally long name and value lists.
fn named<const N: usize>(names: [&'static str; N], values: [f64; N]) -> [(&'static str, f64); N] {
    std::array::from_fn(|i| (names[i], values[i]))
}

/// Serialises an ordered list of (key, number) pairs as a map.
struct Flat<'a>(&'a [(&'a str, f64)]);

impl Serialize for Flat<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

struct Links<'a>(&'a [Inertia; 4]);

impl Serialize for Links<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(4))?;
        for (k, l) in self.0.iter().enumerate() {
            let v = l.standard();
            let mut kv: Vec<(&str, f64)> = LINK_KEYS[..9].iter().copied().zip(v).collect();
            kv.push(("mass", l.mass));
            m.serialize_entry(&(k + 1).to_string(), &Flat(&kv))?;
        }
        m.end()
    }
}

/// The `friction` section: the four coefficients, then `w` when a width
/// is not zero (a file with the sign law (49) keeps its old form).
struct FrictionSer<'a>(&'a Friction);

impl Serialize for FrictionSer<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let f = self.0;
        let mut m = s.serialize_map(None)?;
        let kv = named(
            FRICTION_NAMES,
            [f.viscous[0], f.coulomb[0], f.viscous[1], f.coulomb[1]],
        );
        for (k, v) in kv {
            m.serialize_entry(k, &v)?;
        }
        if f.width != [0.0; 2] {
            m.serialize_entry("w", &f.width)?;
        }
        m.end()
    }
}

struct ExtrasSer<'a>(&'a Extras);

impl Serialize for ExtrasSer<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let e = self.0;
        let mut m = s.serialize_map(None)?;
        if let Some([a, b]) = e.torque_offset {
            m.serialize_entry(
                EffectId::TorqueOffset.as_str(),
                &Flat(&named(TORQUE_OFFSET_NAMES, [a, b])),
            )?;
        }
        if let Some([a, b]) = e.coulomb_asymmetry {
            m.serialize_entry(
                EffectId::CoulombAsymmetry.as_str(),
                &Flat(&named(COULOMB_ASYMMETRY_NAMES, [a, b])),
            )?;
        }
        if let Some(st) = &e.stribeck_friction {
            let [fs1, fs2] = named(STRIBECK_FRICTION_NAMES, st.level);
            let kv = [("v_s", st.v_s), fs1, fs2];
            m.serialize_entry(EffectId::StribeckFriction.as_str(), &Flat(&kv))?;
        }
        if let Some([a, b, c]) = e.passive_joint_viscous {
            let kv = named(PASSIVE_JOINT_VISCOUS_NAMES, [a, b, c]);
            m.serialize_entry(EffectId::PassiveJointViscous.as_str(), &Flat(&kv))?;
        }
        if let Some(c) = &e.cogging {
            let names = cogging_names(c.order());
            let mut kv: Vec<(&str, f64)> = vec![
                ("cycles_per_rev", c.cycles_per_rev),
                ("order", c.order() as f64),
            ];
            let mut vals = Vec::with_capacity(names.len());
            for j in 0..2 {
                for h in 0..c.order() {
                    vals.push(c.sin[j][h]);
                    vals.push(c.cos[j][h]);
                }
            }
            kv.extend(names.iter().map(String::as_str).zip(vals));
            m.serialize_entry(EffectId::Cogging.as_str(), &Flat(&kv))?;
        }
        if let Some([a, b]) = e.quadratic_damping {
            m.serialize_entry(
                EffectId::QuadraticDamping.as_str(),
                &Flat(&named(QUADRATIC_DAMPING_NAMES, [a, b])),
            )?;
        }
        if let Some(b) = &e.presliding_friction {
            let [fb1, fb2, db1, db2] = named(PRESLIDING_FRICTION_NAMES, b.coefficients());
            let kv = [("displacement", b.displacement), fb1, fb2, db1, db2];
            m.serialize_entry(EffectId::PreslidingFriction.as_str(), &Flat(&kv))?;
        }
        m.end()
    }
}

impl Serialize for Params {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        m.serialize_entry(
            "geometry",
            &Flat(&[("alpha_deg", self.alpha_deg), ("beta_deg", self.beta_deg)]),
        )?;
        m.serialize_entry("gravity", &[self.gravity.x, self.gravity.y, self.gravity.z])?;
        m.serialize_entry("links", &Links(&self.links))?;
        m.serialize_entry("friction", &FrictionSer(&self.friction))?;
        m.serialize_entry(
            "elasticity",
            &Flat(&named(ELASTICITY_NAMES, self.elasticity)),
        )?;
        if !self.extra.is_empty() {
            m.serialize_entry("extra", &ExtrasSer(&self.extra))?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for Params {
    /// Strict: the same checks as [`Params::from_value`], with the key path
    /// in the message.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        Self::from_value(&v).map_err(serde::de::Error::custom)
    }
}
