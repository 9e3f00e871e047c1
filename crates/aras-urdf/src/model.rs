//! The model built from a URDF: movable joints in tree order, each with the
//! rigid body it moves (its child link and every link fixed to it), and the
//! settings that choose gravity, the base placement and the friction and
//! armature columns.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::UrdfError;
use crate::parse::{self, RawRobot};
use crate::spatial::{IDENTITY, M3, V3, mat_mul, mul, rpy_matrix, skew, transpose};

mod tree;

use tree::Tree;

/// Standard parameters per body, in Pinocchio's order of dynamic
/// parameters: `m, m·cx, m·cy, m·cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz`, the
/// inertia about the body frame's origin (the joint frame), in that frame.
pub const LINK_COLUMNS: usize = 10;

/// The names of a body's [`LINK_COLUMNS`] parameters, after `link.`.
pub const LINK_PARAMETERS: [&str; LINK_COLUMNS] = [
    "m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz",
];

/// How a joint moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// A rotation about the axis with position limits (rad).
    Revolute,
    /// A rotation about the axis without limits (rad).
    Continuous,
    /// A translation along the axis (m).
    Prismatic,
}

impl JointKind {
    /// Whether the joint rotates (revolute or continuous).
    pub fn rotates(self) -> bool {
        !matches!(self, JointKind::Prismatic)
    }
}

/// A joint's `<limit>` as the URDF gives it (absent entries are `None`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct JointLimits {
    /// Lowest position (rad or m).
    pub lower: Option<f64>,
    /// Highest position (rad or m).
    pub upper: Option<f64>,
    /// Largest effort (N·m or N).
    pub effort: Option<f64>,
    /// Largest rate (rad/s or m/s).
    pub velocity: Option<f64>,
}

/// One movable joint and the body it moves.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// The URDF joint's name.
    pub name: String,
    /// The URDF name of its child link (the body's frame; links fixed to it
    /// are merged into its inertia).
    pub link: String,
    /// The URDF links merged into this body by fixed joints.
    pub merged: Vec<String>,
    /// How it moves.
    pub kind: JointKind,
    /// Index of the parent body's joint, `None` for a joint on the base.
    pub parent: Option<usize>,
    /// Unit axis in the joint (body) frame.
    pub axis: [f64; 3],
    /// The joint frame at zero position in the parent body's frame:
    /// rotation (row-major) …
    pub origin_rotation: [[f64; 3]; 3],
    /// … and position (m).
    pub origin_translation: [f64; 3],
    /// Its limits, if the URDF gives any.
    pub limits: Option<JointLimits>,
    /// The body's standard parameters from the URDF's inertials, in the
    /// order of [`LINK_PARAMETERS`].
    pub inertial: [f64; LINK_COLUMNS],
}

/// Which per-joint columns follow the link columns, in this order per
/// joint: viscous `Fv q̇`, Coulomb `Fc tanh(q̇/w)`, offset `τ₀`, armature
/// `Ia q̈`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct JointColumns {
    /// Viscous friction `Fv q̇` (N·m·s/rad).
    pub viscous: bool,
    /// Coulomb friction `Fc tanh(q̇ / w)` (N·m), `sign(q̇)` for `w = 0`.
    pub coulomb: bool,
    /// A constant torque offset `τ₀` (N·m), e.g. a sensor bias.
    pub offset: bool,
    /// Rotor inertia reflected to the joint (armature) `Ia q̈` (kg·m²).
    pub armature: bool,
}

impl Default for JointColumns {
    /// Viscous, Coulomb and armature: the effects every geared arm shows;
    /// the offset only where a torque sensor needs it.
    fn default() -> Self {
        Self {
            viscous: true,
            coulomb: true,
            offset: false,
            armature: true,
        }
    }
}

impl JointColumns {
    /// No friction or armature columns: the rigid bodies only.
    pub fn none() -> Self {
        Self {
            viscous: false,
            coulomb: false,
            offset: false,
            armature: false,
        }
    }

    /// Number of columns per joint.
    pub fn count(&self) -> usize {
        [self.viscous, self.coulomb, self.offset, self.armature]
            .iter()
            .filter(|&&b| b)
            .count()
    }
}

/// The width `w` of the smooth Coulomb column `tanh(q̇ / w)` (rad/s or
/// m/s): one for every joint, or one per joint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum CoulombWidth {
    /// The same width at every joint.
    Uniform(f64),
    /// One width per movable joint, in the model's joint order.
    PerJoint(Vec<f64>),
}

impl Default for CoulombWidth {
    /// `w = 0`: the sign of the rate, the textbook Coulomb model.
    fn default() -> Self {
        CoulombWidth::Uniform(0.0)
    }
}

/// Friction above the Coulomb level at low speed on one joint, as a column
/// of the model: `Fs s(q̇) exp(−(q̇/v_s)²)` with `s` the joint's Coulomb
/// law (`tanh(q̇/w)`, or the sign for `w = 0`) and `Fs ≥ 0` its parameter
/// `joint.Fs`. The effect the diagnosis names as `stribeck_friction`,
/// with the Stribeck velocity it refined, so that the model identified
/// afterwards has it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StribeckColumn {
    /// The URDF joint's name.
    pub joint: String,
    /// Stribeck velocity `v_s` (rad/s or m/s), > 0.
    pub v_s: f64,
}

/// Settings of a model, with their defaults in one place
/// ([`Default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ModelSettings {
    /// Gravity in the world frame (m/s²); tilt it for a robot mounted on a
    /// slope or to check a model. Default `[0, 0, −9.81]`.
    pub gravity: [f64; 3],
    /// Orientation of the URDF's root link in the world (URDF `rpy`, rad).
    /// Default zero (root frame = world frame).
    pub base_rpy: [f64; 3],
    /// Position of the root link in the world (m); changes only the
    /// forward kinematics. Default zero.
    pub base_xyz: [f64; 3],
    /// Which per-joint columns the regressor has.
    pub columns: JointColumns,
    /// The Coulomb columns' width.
    pub coulomb_width: CoulombWidth,
    /// Stribeck columns, after every per-joint column, in this order
    /// (default none; at most one per joint).
    pub stribeck: Vec<StribeckColumn>,
}

impl Default for ModelSettings {
    fn default() -> Self {
        Self {
            gravity: [0.0, 0.0, -9.81],
            base_rpy: [0.0; 3],
            base_xyz: [0.0; 3],
            columns: JointColumns::default(),
            coulomb_width: CoulombWidth::default(),
            stribeck: Vec::new(),
        }
    }
}

/// A constant part of a body's motion, precomputed for the hot path: the
/// rotation `R(q) = c A + s B + (1 − c) C` of a revolute joint
/// (Rodrigues, with `A` the origin's rotation, `B = A [a]×`,
/// `C = (A a) aᵀ`), the translation `p(q) = p₀ + (A a) q` of a prismatic
/// one.
#[derive(Debug, Clone)]
pub(crate) struct Body {
    pub parent: Option<usize>,
    pub rotates: bool,
    pub axis: V3<f64>,
    pub a: M3<f64>,
    pub b: M3<f64>,
    pub c: M3<f64>,
    pub p0: V3<f64>,
    pub aa: V3<f64>,
}

/// A serial or tree robot from its URDF, with a fixed base: forward
/// kinematics, inverse dynamics (RNEA) and the joint-torque regressor
/// `τ = Y(q, q̇, q̈) π`, linear in the standard parameters `π` (the
/// [`LINK_COLUMNS`] of every body, then the enabled [`JointColumns`] of
/// every joint).
///
/// It is `aras-ident`'s [`aras_ident::LinearModel`] and `aras-excite`'s
/// [`aras_excite::Regressor`], so base parameters, least squares, the SDP,
/// streaming and the excitation design apply to it unchanged.
#[derive(Debug, Clone)]
pub struct UrdfModel {
    pub(crate) name: String,
    pub(crate) joints: Vec<Joint>,
    pub(crate) bodies: Vec<Body>,
    /// Gravity in the root frame.
    pub(crate) gravity_root: V3<f64>,
    pub(crate) base_rotation: M3<f64>,
    pub(crate) base_translation: V3<f64>,
    pub(crate) columns: JointColumns,
    /// The Coulomb width per joint.
    pub(crate) widths: Vec<f64>,
    /// The Stribeck columns: joint index and `v_s`.
    pub(crate) stribeck: Vec<(usize, f64)>,
    pub(crate) settings: ModelSettings,
}

/// A rigid transform `x_parent = R x_child + p` (f64).
#[derive(Debug, Clone, Copy)]
struct Frame {
    r: M3<f64>,
    p: V3<f64>,
}

impl Frame {
    const ID: Frame = Frame {
        r: IDENTITY,
        p: [0.0; 3],
    };

    fn from_origin(xyz: V3<f64>, rpy: V3<f64>) -> Self {
        Frame {
            r: rpy_matrix(rpy),
            p: xyz,
        }
    }

    /// `self ∘ other`.
    fn then(&self, other: &Frame) -> Frame {
        let rp = mul(&self.r, other.p);
        Frame {
            r: mat_mul(&self.r, &other.r),
            p: [rp[0] + self.p[0], rp[1] + self.p[1], rp[2] + self.p[2]],
        }
    }
}

/// The standard parameters of an inertial (`mass`, centre of mass `c` and
/// central inertia `ic` given in the frame `f` of a body): `m, m c, I_O`
/// about the body frame's origin, by rotation and the parallel-axis
/// theorem `I_O = R I_c Rᵀ + m ([c]×)ᵀ [c]×`.
fn standard_in(f: &Frame, mass: f64, ic: &M3<f64>) -> [f64; LINK_COLUMNS] {
    let rot = mat_mul(&mat_mul(&f.r, ic), &transpose(&f.r));
    let c = f.p;
    let s = skew(c);
    let sts = mat_mul(&transpose(&s), &s);
    let i = |r: usize, k: usize| rot[r][k] + mass * sts[r][k];
    [
        mass,
        mass * c[0],
        mass * c[1],
        mass * c[2],
        i(0, 0),
        i(0, 1),
        i(1, 1),
        i(0, 2),
        i(1, 2),
        i(2, 2),
    ]
}

impl UrdfModel {
    /// Reads and builds the model of the URDF file at `path`.
    pub fn from_file(path: impl AsRef<Path>, settings: ModelSettings) -> Result<Self, UrdfError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| UrdfError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_urdf_str(&text, &path.display().to_string(), settings)
    }

    /// Builds the model of the URDF text `text`; `file` names it in
    /// messages.
    pub fn from_urdf_str(
        text: &str,
        file: &str,
        settings: ModelSettings,
    ) -> Result<Self, UrdfError> {
        let raw = parse::parse(text, file)?;
        Self::build(raw, file, settings)
    }

    /// The model of the parsed URDF `raw` (from `file`) with `settings`:
    /// the settings checked, the links and joints resolved into one tree,
    /// its movable joints and their bodies with the inertials merged, then
    /// the per-joint settings resolved against those joints.
    fn build(raw: RawRobot, file: &str, settings: ModelSettings) -> Result<Self, UrdfError> {
        check_settings(&settings)?;
        let tree = Tree::new(&raw, file)?;
        let root = tree.root()?;
        let (mut joints, link_body) = tree.joints(root)?;
        tree.add_inertials(&link_body, &mut joints);
        let bodies = joints.iter().map(body_of).collect();
        let widths = coulomb_widths(&settings.coulomb_width, joints.len())?;
        let stribeck = stribeck_columns(&settings.stribeck, &joints)?;
        let base_rotation = rpy_matrix(settings.base_rpy);
        let g = settings.gravity;
        let gravity_root = crate::spatial::mul_t(&base_rotation, g);
        Ok(Self {
            name: raw.name,
            joints,
            bodies,
            gravity_root,
            base_rotation,
            base_translation: settings.base_xyz,
            columns: settings.columns,
            widths,
            stribeck,
            settings,
        })
    }

    /// The URDF robot's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The movable joints in the model's order: depth first from the root,
    /// children in the order of the file (a parent always before its
    /// children).
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Number of movable joints (coordinates and torques).
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The movable joints' names, in order.
    pub fn joint_names(&self) -> Vec<String> {
        self.joints.iter().map(|j| j.name.clone()).collect()
    }

    /// The settings the model was built with.
    pub fn settings(&self) -> &ModelSettings {
        &self.settings
    }

    /// Which per-joint columns the regressor has.
    pub fn joint_columns(&self) -> JointColumns {
        self.columns
    }

    /// Number of standard parameters (regressor columns).
    pub fn parameter_count(&self) -> usize {
        self.dof() * (LINK_COLUMNS + self.columns.count()) + self.stribeck.len()
    }

    /// The standard parameters' names, in column order: `link.m`,
    /// `link.mcx`, … ([`LINK_PARAMETERS`]) per body, then `joint.Fv`,
    /// `joint.Fc`, `joint.offset`, `joint.Ia` (the enabled ones) per joint,
    /// then `joint.Fs` per Stribeck column.
    pub fn parameter_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .joints
            .iter()
            .flat_map(|j| {
                LINK_PARAMETERS
                    .iter()
                    .map(move |p| format!("{}.{p}", j.link))
            })
            .collect();
        let c = self.columns;
        for j in &self.joints {
            for (on, tag) in [
                (c.viscous, "Fv"),
                (c.coulomb, "Fc"),
                (c.offset, "offset"),
                (c.armature, "Ia"),
            ] {
                if on {
                    names.push(format!("{}.{tag}", j.name));
                }
            }
        }
        for (j, _) in &self.stribeck {
            names.push(format!("{}.Fs", self.joints[*j].name));
        }
        names
    }

    /// The standard parameters of the URDF: every body's inertial (with
    /// the links fixed to it), zero friction, offset, armature and
    /// Stribeck levels.
    pub fn urdf_parameters(&self) -> Vec<f64> {
        let mut p: Vec<f64> = self.joints.iter().flat_map(|j| j.inertial).collect();
        p.resize(self.parameter_count(), 0.0);
        p
    }

    /// The excitation design's limits ([`aras_excite::Limits`]) from the
    /// URDF: each joint's `<limit lower upper velocity>` (positions in rad
    /// or m, rates per second), shrunk by `margin` (a fraction in `[0, 1)`
    /// of each half-range and of each rate, so the design stays clear of
    /// the hard stops), and `max_accel` for every joint. A joint without
    /// position or velocity limits (a continuous joint, an incomplete
    /// `<limit>`) is an error naming it: give the limits to excite it in.
    pub fn excitation_limits(
        &self,
        margin: f64,
        max_accel: f64,
    ) -> Result<aras_excite::Limits<nalgebra::Dyn>, UrdfError> {
        if !(0.0..1.0).contains(&margin) {
            return Err(UrdfError::Setting {
                name: "margin".into(),
                problem: format!("{margin} must be a fraction in [0, 1)"),
            });
        }
        if !(max_accel.is_finite() && max_accel > 0.0) {
            return Err(UrdfError::Setting {
                name: "max_accel".into(),
                problem: format!("{max_accel} must be a positive number"),
            });
        }
        let n = self.dof();
        let (mut lo, mut hi, mut rate) = (Vec::new(), Vec::new(), Vec::new());
        for j in &self.joints {
            let l = j.limits.unwrap_or(JointLimits {
                lower: None,
                upper: None,
                effort: None,
                velocity: None,
            });
            let bounded = j.kind != JointKind::Continuous;
            match (l.lower, l.upper, l.velocity) {
                (Some(a), Some(b), Some(v)) if bounded && b > a && v > 0.0 => {
                    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a) * (1.0 - margin));
                    lo.push(mid - half);
                    hi.push(mid + half);
                    rate.push(v * (1.0 - margin));
                }
                _ => {
                    return Err(UrdfError::Setting {
                        name: format!("limits of joint `{}`", j.name),
                        problem: "the URDF gives no lower < upper position limits (or the \
                                  joint is continuous) and a positive velocity limit: add them \
                                  to its <limit> (or give aras-excite the limits yourself)"
                            .into(),
                    });
                }
            }
        }
        let v = |x: &[f64]| nalgebra::DVector::from_column_slice(x);
        Ok(aras_excite::Limits {
            min: v(&lo),
            max: v(&hi),
            max_rate: v(&rate),
            max_accel: nalgebra::DVector::from_element(n, max_accel),
        })
    }

    /// Where each body's parameters sit in the standard vector, in the
    /// order `aras-ident`'s `LinkLayout` takes them, for the physically
    /// consistent identification (one pseudo-inertia per body).
    pub fn link_columns(&self) -> Vec<LinkColumns> {
        self.joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let c = i * LINK_COLUMNS;
                LinkColumns {
                    link: j.link.clone(),
                    mass: c,
                    first_moment: [c + 1, c + 2, c + 3],
                    inertia: [c + 4, c + 5, c + 7, c + 6, c + 8, c + 9],
                }
            })
            .collect()
    }

    /// Index of the first per-joint column of joint `j`, and the enabled
    /// kinds' offsets within it.
    pub(crate) fn joint_base(&self, j: usize) -> usize {
        self.dof() * LINK_COLUMNS + j * self.columns.count()
    }

    /// The Stribeck columns (joint index, `v_s`), in column order after
    /// every per-joint column.
    pub fn stribeck_columns(&self) -> &[(usize, f64)] {
        &self.stribeck
    }
}

/// The columns of one body in the standard vector.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkColumns {
    /// The body's URDF link.
    pub link: String,
    /// Index of `m`.
    pub mass: usize,
    /// Indices of `m·cx, m·cy, m·cz`.
    pub first_moment: [usize; 3],
    /// Indices of `Ixx, Ixy, Ixz, Iyy, Iyz, Izz` (note: not Pinocchio's
    /// order; the order `aras_ident::LinkLayout` takes).
    pub inertia: [usize; 6],
}

/// The constant parts of the motion of joint `j`'s body ([`Body`]).
fn body_of(j: &Joint) -> Body {
    let a = j.origin_rotation;
    let axis = j.axis;
    let b = mat_mul(&a, &skew(axis));
    let aa = mul(&a, axis);
    let mut c = [[0.0; 3]; 3];
    for r in 0..3 {
        for k in 0..3 {
            c[r][k] = aa[r] * axis[k];
        }
    }
    Body {
        parent: j.parent,
        rotates: j.kind.rotates(),
        axis,
        a,
        b,
        c,
        p0: j.origin_translation,
        aa,
    }
}

/// The Coulomb width of each of the `n` movable joints: the uniform one
/// for all, or one given per joint.
fn coulomb_widths(width: &CoulombWidth, n: usize) -> Result<Vec<f64>, UrdfError> {
    match width {
        CoulombWidth::Uniform(w) => Ok(vec![*w; n]),
        CoulombWidth::PerJoint(w) if w.len() == n => Ok(w.clone()),
        CoulombWidth::PerJoint(w) => Err(UrdfError::Setting {
            name: "coulomb_width".to_owned(),
            problem: format!(
                "{} widths for {n} movable joints; give one per joint or a single number",
                w.len()
            ),
        }),
    }
}

/// The Stribeck columns as (joint index, `v_s`) in the order given: each
/// on a movable joint of `joints`, with a finite `v_s > 0`, at most one
/// per joint.
fn stribeck_columns(
    columns: &[StribeckColumn],
    joints: &[Joint],
) -> Result<Vec<(usize, f64)>, UrdfError> {
    let mut stribeck: Vec<(usize, f64)> = Vec::new();
    for c in columns {
        let bad = |problem: String| UrdfError::Setting {
            name: "stribeck".to_owned(),
            problem,
        };
        let j = joints
            .iter()
            .position(|j| j.name == c.joint)
            .ok_or_else(|| {
                bad(format!(
                    "joint `{}` is not a movable joint of this URDF ({}); name one of them",
                    c.joint,
                    joints
                        .iter()
                        .map(|j| j.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })?;
        if !(c.v_s.is_finite() && c.v_s > 0.0) {
            return Err(bad(format!(
                "joint `{}`: v_s = {} must be a finite velocity > 0 (rad/s or m/s)",
                c.joint, c.v_s
            )));
        }
        if stribeck.iter().any(|(k, _)| *k == j) {
            return Err(bad(format!(
                "joint `{}` has two Stribeck columns; give one per joint",
                c.joint
            )));
        }
        stribeck.push((j, c.v_s));
    }
    Ok(stribeck)
}

/// Refuses non-finite gravity or base placement and a negative or
/// non-finite Coulomb width.
fn check_settings(s: &ModelSettings) -> Result<(), UrdfError> {
    let finite = |name: &str, v: &[f64]| {
        if v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(UrdfError::Setting {
                name: name.to_owned(),
                problem: format!("{v:?} has a non-finite entry; give finite numbers"),
            })
        }
    };
    finite("gravity", &s.gravity)?;
    finite("base_rpy", &s.base_rpy)?;
    finite("base_xyz", &s.base_xyz)?;
    let widths = match &s.coulomb_width {
        CoulombWidth::Uniform(w) => std::slice::from_ref(w),
        CoulombWidth::PerJoint(w) => w.as_slice(),
    };
    if let Some(w) = widths.iter().find(|w| !(w.is_finite() && **w >= 0.0)) {
        return Err(UrdfError::Setting {
            name: "coulomb_width".to_owned(),
            problem: format!("width {w} must be finite and ≥ 0 (rad/s; 0 is sign(q̇))"),
        });
    }
    Ok(())
}
