//! The robot as a MuJoCo model: a parameter set → MJCF text (`docs/mjcf.md`).
//!
//! MJCF can express the closed chain that URDF cannot: the two motor chains
//! are open kinematic trees and one `connect` equality closes the loop at the
//! end-effector axis `d`.
//!
//! # Bodies, joints and frames
//!
//! Every body frame has its origin at the RCM and, at the joint angles the
//! tree is written in (all zero), the orientation of the link frame of
//! `aras_kin::links` at `θ1 = θ2 = 0` with the elbows stretched. So the
//! inertial parameters of link `k` are expressed in MuJoCo's body frame
//! exactly as in the parameter file: no rotation is applied to them.
//!
//! | body | parent | joint | joint axis | body frame (relative to the parent) |
//! |---|---|---|---|---|
//! | `link2` | world | `theta1` (motor 1) | `z` = `a` | identity: `R2 = Rz(θ1)` |
//! | `link4` | `link2` | `hinge_c` | `z` = `c` | `Ry(α)`: `R4 = R2 Ry(α) Rz(q_c)` |
//! | `link1` | world | `theta2` (motor 2) | `z` = `a` | identity: `R1 = Rz(θ2)` |
//! | `link3` | `link1` | `hinge_b` | `z` = `b` | `Ry(α)`: `R3 = R1 Ry(α) Rz(q_b)` |
//!
//! `qpos = [θ1, q_c, θ2, q_b]`. The passive angles `q_b`, `q_c` are zero
//! with the elbow stretched (distal arc continuing the proximal one); on the
//! working assembly `q_b = π − B` and `q_c = C − π` with the elbow angles
//! `B = C` of (4) ([`passive_hinge_angles`]).
//!
//! The loop is closed by `<connect>` between `link3` and `link4` at the
//! point `r·d` (`r` = [`MjcfOptions::anchor_radius`]), which both distal
//! links carry at `r [sin β, 0, cos β]` in their frames. Both bodies already
//! turn about the RCM, so making one more point common leaves exactly the
//! relative rotation about the line RCM–`r·d`: the hinge about `d`. A `weld`
//! would also lock that rotation and leave a 1-DOF mechanism. Of the
//! connect's three rows only two are independent (both points stay on the
//! sphere of radius `r`); MuJoCo's regularised constraint solver accepts the
//! redundant row.
//!
//! # Parameters
//!
//! * link `k`: `<inertial mass="m" pos="h/m" fullinertia="…"/>` with the
//!   inertia about the centre of mass `I_G = I_O − m(|ρ|²1 − ρρᵀ)` (inverse of
//!   (28)), written `Ixx Iyy Izz Ixy Ixz Iyz` (MuJoCo's order, tensor
//!   entries as in the parameter file);
//! * motors: `damping` = `Fv`, `stiffness` = `Ke` with `springref` 0,
//!   `frictionloss` = `Fc` on `theta1`/`theta2`; torque actuators `motor1`,
//!   `motor2` with gear 1 and no control limits;
//! * `passive_joint_viscous`: `damping` = `Fpb`, `Fpc` on `hinge_b`,
//!   `hinge_c`;
//! * gravity: `<option gravity>`.
//!
//! Effects MuJoCo has no element for (`Fpd`, torque offsets, asymmetric
//! Coulomb, Stribeck, cogging, quadratic damping) are listed with their
//! values in an XML comment ([`unrepresented`]).
//!
//! Only physically consistent links can be exported: MuJoCo needs a positive
//! mass and a positive-definite inertia about the centre of mass that obeys
//! the triangle inequality (the strict form of (67)–(69)).

use std::fmt::Write as _;

use nalgebra::{Matrix3, SymmetricEigen, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::effects::{
    COULOMB_ASYMMETRY_NAMES, PASSIVE_JOINT_VISCOUS_NAMES, PRESLIDING_FRICTION_NAMES,
    QUADRATIC_DAMPING_NAMES, STRIBECK_FRICTION_NAMES, TORQUE_OFFSET_NAMES, cogging_names,
};
use crate::{EffectId, Inertia, ParamError, Params};

/// Words in the opening comment of every exported file: how a tool tells
/// a file it wrote (and may replace) from someone else's MJCF.
pub const GENERATOR_MARK: &str = "exported by `aras export-mjcf`";

/// Settings of the exported model; the defaults live in [`Default`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MjcfOptions {
    /// `<mujoco model="…">`.
    pub model_name: String,
    /// Simulation time step (s) of MuJoCo's RK4 integrator. 0.5 ms is the
    /// step of `aras simulate` (RK4 at 2 kHz, `docs/simulator.md`), so both
    /// simulators integrate the same way; it must be at most half the loop
    /// constraint's time constant.
    pub timestep: f64,
    /// Time constant of the loop-closing constraint (`solref`, s). MuJoCo's
    /// constraints are soft: the loop is pulled closed with this time
    /// constant (critically damped). 2 ms keeps the loop closed to about
    /// 1 µm on the real robot's motions while staying stable at 0.5 ms steps.
    pub constraint_time_constant: f64,
    /// Distance of the loop-closing point from the RCM along `d` (m). Any
    /// positive value closes the same loop; it sets the length scale of
    /// the soft constraint (its violation is a distance). 0.25 m is the
    /// size of the real links (their centres of mass lie at 0.20–0.28 m).
    pub anchor_radius: f64,
    /// Task pose `[φ, γ]` (rad) of the `home` keyframe, which also seeds
    /// the passive angles; default: the centre of the workspace (77),
    /// `[85°, 60°]`.
    pub home: [f64; 2],
}

impl Default for MjcfOptions {
    fn default() -> Self {
        Self {
            model_name: "aras-diamond".into(),
            timestep: 5e-4,
            constraint_time_constant: 2e-3,
            anchor_radius: 0.25,
            home: [85f64.to_radians(), 60f64.to_radians()],
        }
    }
}

/// Why a parameter set cannot become a MuJoCo model.
#[derive(Debug, thiserror::Error)]
pub enum MjcfError {
    /// The parameters themselves are invalid.
    #[error(transparent)]
    Params(#[from] ParamError),
    /// A link MuJoCo would reject.
    #[error(
        "link {link} cannot be a MuJoCo body: {reason}. MuJoCo needs a positive mass and a \
         positive-definite inertia about the centre of mass satisfying the triangle inequality \
         (the paper's (67)–(69)); export the physically consistent estimate (params.json of \
         `aras identify`, the SDP solution), not params_ols.json"
    )]
    NotPhysical {
        /// Link number (1–4).
        link: usize,
        /// What is wrong, with the numbers.
        reason: String,
    },
    /// A coefficient MuJoCo requires to be non-negative.
    #[error(
        "`{key}` = {value} is negative, but MuJoCo's `{attribute}` must be ≥ 0 (a negative \
         value would feed energy into the robot); use the physically consistent estimate, \
         which constrains it to be ≥ 0 (the paper's (70))"
    )]
    Negative {
        /// Parameter-file key.
        key: String,
        /// The value.
        value: f64,
        /// MJCF attribute it would go to.
        attribute: &'static str,
    },
    /// An option out of range.
    #[error("MJCF option `{name}` = {value} is invalid: {reason}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// The value.
        value: f64,
        /// The rule.
        reason: &'static str,
    },
    /// The home pose is not an assembled, non-singular pose.
    #[error("MJCF option `home` = [{phi}, {gamma}] rad is not a usable pose")]
    Home {
        /// φ (rad).
        phi: f64,
        /// γ (rad).
        gamma: f64,
        /// The kinematic reason.
        source: aras_kin::KinError,
    },
}

/// One exported body's inertial element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertial {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the body frame (m).
    pub pos: Vector3<f64>,
    /// Inertia about the centre of mass, body frame (kg·m²).
    pub inertia_com: Matrix3<f64>,
}

impl Inertial {
    /// The inertial of a physically consistent link (the inverse of
    /// (28)); `link` (1–4) names it in errors.
    pub fn from_link(link: usize, l: &Inertia) -> Result<Self, MjcfError> {
        let bad = |reason: String| MjcfError::NotPhysical { link, reason };
        if l.mass.is_nan() || l.mass <= 0.0 {
            return Err(bad(format!("its mass {} kg is not positive", l.mass)));
        }
        let ig = l
            .inertia_about_com()
            .ok_or_else(|| bad(format!("its mass {} kg is not positive", l.mass)))?;
        let ig = 0.5 * (ig + ig.transpose());
        let eig = SymmetricEigen::new(ig).eigenvalues;
        let mut e = [eig[0], eig[1], eig[2]];
        e.sort_by(f64::total_cmp);
        if e.iter().any(|x| x.is_nan()) || e[0] <= 0.0 {
            return Err(bad(format!(
                "its inertia about the centre of mass has the principal moments \
                 [{:.6e}, {:.6e}, {:.6e}] kg·m², not all positive",
                e[0], e[1], e[2]
            )));
        }
        if e[0] + e[1] <= e[2] {
            return Err(bad(format!(
                "its principal moments about the centre of mass [{:.6e}, {:.6e}, {:.6e}] kg·m² \
                 break the triangle inequality ({:.6e} + {:.6e} < {:.6e})",
                e[0], e[1], e[2], e[0], e[1], e[2]
            )));
        }
        Ok(Self {
            mass: l.mass,
            pos: l.h / l.mass,
            inertia_com: ig,
        })
    }

    /// Back to the standard parameters by the parallel-axis theorem (28):
    /// `I_O = I_G + m(|ρ|²1 − ρρᵀ)`, `h = mρ`.
    pub fn to_link(&self) -> Inertia {
        Inertia::from_com(self.mass, &self.inertia_com, &self.pos)
    }
}

/// Passive hinge angles `[q_b, q_c]` (rad) of the exported tree at a task
/// pose: the rotation of `link3` (`link4`) about `b` (`c`) relative to
/// `link1` (`link2`), zero with the elbow stretched. Computed from the link
/// frames of `aras_kin` (`R3 = R1 Ry(α) Rz(q_b)`).
pub fn passive_hinge_angles(params: &Params, x: &Vector2<f64>) -> Result<[f64; 2], MjcfError> {
    let g = params.geometry()?;
    let r = aras_kin::link_frames(&g, x).map_err(|source| MjcfError::Home {
        phi: x[0],
        gamma: x[1],
        source,
    })?;
    let ry = ry(g.alpha());
    let angle = |parent: &Matrix3<f64>, child: &Matrix3<f64>| {
        let rel = ry.transpose() * parent.transpose() * child;
        rel[(1, 0)].atan2(rel[(0, 0)])
    };
    Ok([angle(&r[0], &r[2]), angle(&r[1], &r[3])])
}

fn ry(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// An effect of the parameter set that the MJCF cannot express, with its
/// values (named as in the parameter file).
#[derive(Debug, Clone, PartialEq)]
pub struct Unrepresented {
    /// The effect (its id names the parameter file's section: `friction`
    /// for the Coulomb width, else an `extra` section).
    pub effect: EffectId,
    /// `(name, value)` pairs.
    pub values: Vec<(String, f64)>,
    /// Why MuJoCo has no element for it.
    pub why: &'static str,
}

/// Effects present in `params` (non-zero) that the exported model leaves
/// out; they are listed in the XML comment.
pub fn unrepresented(params: &Params) -> Vec<Unrepresented> {
    let e = &params.extra;
    let mut out = Vec::new();
    let named = |names: &[&str], v: &[f64]| -> Vec<(String, f64)> {
        names
            .iter()
            .map(|n| n.to_string())
            .zip(v.iter().copied())
            .collect()
    };
    let w = params.friction.width;
    if w.iter().any(|x| *x != 0.0) {
        out.push(Unrepresented {
            effect: EffectId::Friction,
            values: named(&["w1", "w2"], &w),
            why: "frictionloss is a hard Coulomb level (a constraint with MuJoCo's own \
                  regularisation); the tanh transition width has no MJCF attribute, so the \
                  exported Coulomb level acts as the sign law",
        });
    }
    if let Some([_, _, fpd]) = e.passive_joint_viscous
        && fpd != 0.0
    {
        out.push(Unrepresented {
            effect: EffectId::PassiveJointViscous,
            values: named(&PASSIVE_JOINT_VISCOUS_NAMES[2..], &[fpd]),
            why: "the hinge about d is the connect equality, not a joint, so it has no damping",
        });
    }
    if let Some(v) = e.torque_offset.filter(|v| v.iter().any(|x| *x != 0.0)) {
        out.push(Unrepresented {
            effect: EffectId::TorqueOffset,
            values: named(&TORQUE_OFFSET_NAMES, &v),
            why: "a constant joint torque is no passive element of MJCF",
        });
    }
    if let Some(v) = e.coulomb_asymmetry.filter(|v| v.iter().any(|x| *x != 0.0)) {
        out.push(Unrepresented {
            effect: EffectId::CoulombAsymmetry,
            values: named(&COULOMB_ASYMMETRY_NAMES, &v),
            why: "frictionloss is symmetric",
        });
    }
    if let Some(s) = e
        .stribeck_friction
        .filter(|s| s.level.iter().any(|x| *x != 0.0))
    {
        out.push(Unrepresented {
            effect: EffectId::StribeckFriction,
            values: named(
                &[&["v_s"][..], &STRIBECK_FRICTION_NAMES].concat(),
                &[s.v_s, s.level[0], s.level[1]],
            ),
            why: "frictionloss has one level, no velocity dependence",
        });
    }
    if let Some(c) = &e.cogging {
        let amplitudes =
            (0..2).flat_map(|j| (0..c.order()).flat_map(move |h| [c.sin[j][h], c.cos[j][h]]));
        let mut values = vec![("cycles_per_rev".to_string(), c.cycles_per_rev)];
        values.extend(cogging_names(c.order()).into_iter().zip(amplitudes));
        if values.iter().skip(1).any(|(_, v)| *v != 0.0) {
            out.push(Unrepresented {
                effect: EffectId::Cogging,
                values,
                why: "a position-periodic joint torque is no passive element of MJCF",
            });
        }
    }
    if let Some(v) = e.quadratic_damping.filter(|v| v.iter().any(|x| *x != 0.0)) {
        out.push(Unrepresented {
            effect: EffectId::QuadraticDamping,
            values: named(&QUADRATIC_DAMPING_NAMES, &v),
            why: "joint damping is linear in the velocity",
        });
    }
    if let Some(b) = e
        .presliding_friction
        .filter(|b| b.coefficients().iter().any(|x| *x != 0.0))
    {
        out.push(Unrepresented {
            effect: EffectId::PreslidingFriction,
            values: named(
                &[&["displacement"][..], &PRESLIDING_FRICTION_NAMES].concat(),
                &[&[b.displacement][..], &b.coefficients()].concat(),
            ),
            why: "frictionloss is a hard level without an internal state",
        });
    }
    out
}

/// Number formatting: shortest round-trip decimal, exponent form for very
/// small or large magnitudes (so `parse(fmt(x)) == x` bit for bit).
fn num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        "0".into()
    } else if (1e-4..1e7).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn nums(v: &[f64]) -> String {
    v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ")
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

/// Text of an XML comment: `--` is not allowed inside one.
fn comment_text(s: &str) -> String {
    s.replace("--", "- -")
}

fn check_options(o: &MjcfOptions) -> Result<(), MjcfError> {
    let bad = |name, value, reason| {
        Err(MjcfError::InvalidOption {
            name,
            value,
            reason,
        })
    };
    if !(o.timestep.is_finite() && o.timestep > 0.0 && o.timestep <= 0.01) {
        return bad(
            "timestep",
            o.timestep,
            "give a time step in (0, 0.01] s, e.g. 0.0005",
        );
    }
    if !(o.constraint_time_constant.is_finite() && o.constraint_time_constant >= 2.0 * o.timestep) {
        return bad(
            "constraint_time_constant",
            o.constraint_time_constant,
            "give at least twice the time step (MuJoCo's stability limit), e.g. 0.002 s",
        );
    }
    if !(o.anchor_radius.is_finite() && o.anchor_radius > 0.0) {
        return bad(
            "anchor_radius",
            o.anchor_radius,
            "give a positive distance in m, e.g. 0.25",
        );
    }
    Ok(())
}

/// The MJCF text of the robot (see the module docs for the mapping).
///
/// Errors: invalid parameters, a link that is not physically consistent,
/// negative `Fv`, `Fc`, `Ke`, `Fpb`, `Fpc`, or invalid options.
pub fn to_mjcf(params: &Params, opts: &MjcfOptions) -> Result<String, MjcfError> {
    params.validate()?;
    check_options(opts)?;
    let g = params.geometry()?;
    let inertials: Vec<Inertial> = params
        .links
        .iter()
        .enumerate()
        .map(|(k, l)| Inertial::from_link(k + 1, l))
        .collect::<Result<_, _>>()?;
    let nonneg = |key: String, value: f64, attribute| {
        if value < 0.0 {
            Err(MjcfError::Negative {
                key,
                value,
                attribute,
            })
        } else {
            Ok(value)
        }
    };
    let f = &params.friction;
    let mut motor = Vec::new();
    for j in 0..2 {
        motor.push((
            nonneg(format!("friction.Fv{}", j + 1), f.viscous[j], "damping")?,
            nonneg(
                format!("elasticity.Ke{}", j + 1),
                params.elasticity[j],
                "stiffness",
            )?,
            nonneg(
                format!("friction.Fc{}", j + 1),
                f.coulomb[j],
                "frictionloss",
            )?,
        ));
    }
    let [fpb, fpc, _] = params.extra.passive_joint_viscous.unwrap_or([0.0; 3]);
    let fpb = nonneg("extra.passive_joint_viscous.Fpb".into(), fpb, "damping")?;
    let fpc = nonneg("extra.passive_joint_viscous.Fpc".into(), fpc, "damping")?;
    let home = Vector2::new(opts.home[0], opts.home[1]);
    let home_err = |source| MjcfError::Home {
        phi: home[0],
        gamma: home[1],
        source,
    };
    let home_theta = aras_kin::inverse(&g, &home).map_err(home_err)?.theta;
    let [qb, qc] = passive_hinge_angles(params, &home)?;

    let (alpha, beta) = (g.alpha(), g.beta());
    let r = opts.anchor_radius;
    let anchor = [r * beta.sin(), 0.0, r * beta.cos()];
    let quat_ry = [(0.5 * alpha).cos(), 0.0, (0.5 * alpha).sin(), 0.0];

    let mut x = String::with_capacity(8192);
    let w = &mut x;
    let _ = writeln!(w, r#"<?xml version="1.0" encoding="utf-8"?>"#);
    let _ = writeln!(
        w,
        "<!--\n  ARAS-Diamond spherical parallel robot (coaxial spherical five-bar), \
         {GENERATOR_MARK}.\n  Frames, joints and the parameter mapping: \
         docs/mjcf.md. Units SI, angles in radians.\n  qpos = [theta1, hinge_c, theta2, \
         hinge_b]; motor1 drives theta1 (link 2), motor2 drives theta2 (link 1).\n  \
         Geometry: alpha = {} rad, beta = {} rad. The loop is closed by the connect \
         equality `hinge_d`.\n  Coulomb friction is MuJoCo's frictionloss, a soft \
         constraint (regularised Coulomb).\n-->",
        num(alpha),
        num(beta)
    );
    let missing = unrepresented(params);
    if missing.is_empty() {
        let _ = writeln!(
            w,
            "<!-- Every effect of the parameter file is represented in this model. -->"
        );
    } else {
        let _ = writeln!(
            w,
            "<!--\n  Effects of the parameter file NOT represented in this model (MuJoCo has \
             no element for them):"
        );
        for u in &missing {
            let vals: Vec<String> = u
                .values
                .iter()
                .map(|(n, v)| format!("{n} = {}", num(*v)))
                .collect();
            let _ = writeln!(
                w,
                "  {}: {} ({})",
                u.effect,
                comment_text(&vals.join(", ")),
                comment_text(u.why)
            );
        }
        let _ = writeln!(w, "-->");
    }
    let _ = writeln!(w, r#"<mujoco model="{}">"#, escape(&opts.model_name));
    let _ = writeln!(
        w,
        r#"  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>"#
    );
    let _ = writeln!(
        w,
        r#"  <option timestep="{}" gravity="{}" integrator="RK4"/>"#,
        num(opts.timestep),
        nums(params.gravity.as_slice())
    );
    let _ = writeln!(
        w,
        "  <default>\n    <geom type=\"capsule\" contype=\"0\" conaffinity=\"0\" \
         group=\"1\" size=\"0.006\"/>\n  </default>"
    );
    let _ = writeln!(w, "  <worldbody>");
    let _ = writeln!(
        w,
        r#"    <site name="rcm" pos="0 0 0" size="0.01" rgba="1 0 0 1"/>"#
    );
    // Chain of motor 1 (link 2, link 4), then of motor 2 (link 1, link 3).
    let chains = [
        (1usize, 3usize, "theta1", "hinge_c", 0usize, fpc),
        (0, 2, "theta2", "hinge_b", 1, fpb),
    ];
    for (prox, dist, motor_joint, hinge, j, hinge_damping) in chains {
        let (fv, ke, fc) = motor[j];
        let _ = writeln!(w, r#"    <body name="link{}">"#, prox + 1);
        let _ = writeln!(
            w,
            r#"      <joint name="{motor_joint}" type="hinge" axis="0 0 1" damping="{}" stiffness="{}" springref="0" frictionloss="{}"/>"#,
            num(fv),
            num(ke),
            num(fc)
        );
        inertial(w, "      ", &inertials[prox]);
        arc(w, "      ", &params.links[prox], alpha, r);
        let _ = writeln!(
            w,
            r#"      <body name="link{}" quat="{}">"#,
            dist + 1,
            nums(&quat_ry)
        );
        let _ = writeln!(
            w,
            r#"        <joint name="{hinge}" type="hinge" axis="0 0 1" damping="{}"/>"#,
            num(hinge_damping)
        );
        inertial(w, "        ", &inertials[dist]);
        arc(w, "        ", &params.links[dist], beta, r);
        let _ = writeln!(
            w,
            r#"        <site name="d_link{}" pos="{}" size="0.008"/>"#,
            dist + 1,
            nums(&anchor)
        );
        let _ = writeln!(w, "      </body>\n    </body>");
    }
    let _ = writeln!(w, "  </worldbody>");
    let _ = writeln!(
        w,
        "  <equality>\n    <!-- solimp near 1: the loop is held nearly rigidly (impedance \
         0.99-0.999 over 1 mm) -->\n    <connect name=\"hinge_d\" body1=\"link3\" \
         body2=\"link4\" anchor=\"{}\" solref=\"{} 1\" solimp=\"0.99 0.999 0.001\"/>\n  \
         </equality>",
        nums(&anchor),
        num(opts.constraint_time_constant)
    );
    let _ = writeln!(
        w,
        "  <actuator>\n    <motor name=\"motor1\" joint=\"theta1\" gear=\"1\"/>\n    \
         <motor name=\"motor2\" joint=\"theta2\" gear=\"1\"/>\n  </actuator>"
    );
    let _ = writeln!(
        w,
        "  <keyframe>\n    <!-- phi = {} rad, gamma = {} rad -->\n    <key name=\"home\" \
         qpos=\"{}\"/>\n  </keyframe>",
        num(home[0]),
        num(home[1]),
        nums(&[home_theta[0], qc, home_theta[1], qb])
    );
    let _ = writeln!(w, "</mujoco>");
    Ok(x)
}

fn inertial(w: &mut String, indent: &str, i: &Inertial) {
    let m = &i.inertia_com;
    let _ = writeln!(
        w,
        r#"{indent}<inertial pos="{}" mass="{}" fullinertia="{}"/>"#,
        nums(i.pos.as_slice()),
        num(i.mass),
        nums(&[
            m[(0, 0)],
            m[(1, 1)],
            m[(2, 2)],
            m[(0, 1)],
            m[(0, 2)],
            m[(1, 2)]
        ])
    );
}

/// Visual-only capsules along a link's arc (from its joint axis `z`
/// towards `x`, spanning `span`) at the radius of its centre of mass
/// (`fallback` if that is zero): no mass, no contacts.
fn arc(w: &mut String, indent: &str, l: &Inertia, span: f64, fallback: f64) {
    const SEGMENTS: usize = 6;
    let rho = if l.mass > 0.0 {
        (l.h / l.mass).norm()
    } else {
        0.0
    };
    let r = if rho > 1e-3 { rho } else { fallback };
    let p = |s: f64| [r * s.sin(), 0.0, r * s.cos()];
    for i in 0..SEGMENTS {
        let a = span * i as f64 / SEGMENTS as f64;
        let b = span * (i + 1) as f64 / SEGMENTS as f64;
        let mut ends = p(a).to_vec();
        ends.extend(p(b));
        let _ = writeln!(w, r#"{indent}<geom fromto="{}"/>"#, nums(&ends));
    }
}
