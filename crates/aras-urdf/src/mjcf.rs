//! The model as MuJoCo MJCF: the body tree with identified inertials,
//! armature and viscous damping, for simulation in MuJoCo.

use std::fmt::Write;

use crate::UrdfError;
use crate::model::{JointKind, LINK_COLUMNS, UrdfModel};

impl UrdfModel {
    /// MJCF text of this robot with the standard parameters `params`
    /// (`docs/urdf.md`, "MJCF"): one `<body>` per movable joint, nested as
    /// the tree, at the joint's origin in its parent (`pos`, `quat`), with
    /// its `hinge` or `slide` joint (axis, limits as `range`), its
    /// `<inertial>` at the centre of mass (`fullinertia` about it, in the
    /// body's axes) and, where the model has the columns, `armature` (the
    /// rotor inertia `Ia`) and `damping` (the viscous `Fv`). The base sits
    /// in the world at the settings' `base_xyz`, turned by `base_rpy`;
    /// gravity is the settings'. MuJoCo has no smooth Coulomb law, constant
    /// joint torque or Stribeck hump: their values are listed in a comment,
    /// not simulated.
    /// Refused: a wrong parameter count and a body that is not physical
    /// (mass ≤ 0, a central inertia that is not positive semidefinite,
    /// negative armature or damping).
    pub fn to_mjcf(&self, params: &[f64]) -> Result<String, UrdfError> {
        self.check_parameters(params)?;
        let n = self.dof();
        let names = self.parameter_names();
        let joint_value = |j: usize, kind: &str| -> Option<f64> {
            let want = format!("{}.{kind}", self.joints()[j].name);
            names.iter().position(|p| *p == want).map(|i| params[i])
        };
        let mut bodies = Vec::with_capacity(n);
        for (j, joint) in self.joints().iter().enumerate() {
            let p = &params[LINK_COLUMNS * j..LINK_COLUMNS * (j + 1)];
            let unphysical = |what: &str| UrdfError::Setting {
                name: format!("parameters of link `{}`", joint.link),
                problem: format!("{what}; export a physically consistent identification"),
            };
            let (mass, c, ic) =
                crate::write::central(p).ok_or_else(|| unphysical("not a physical body"))?;
            let mut attrs = String::new();
            for (kind, attr) in [("Ia", "armature"), ("Fv", "damping")] {
                if let Some(v) = joint_value(j, kind) {
                    if !(v.is_finite() && v >= 0.0) {
                        return Err(unphysical(&format!("{attr} {v} is negative")));
                    }
                    let _ = write!(attrs, " {attr}=\"{v}\"");
                }
            }
            bodies.push(Body { mass, c, ic, attrs });
        }
        let g = self.settings().gravity;
        let mut s = String::new();
        let _ = writeln!(s, "<mujoco model=\"{}\">", xml_escape(self.name()));
        let _ = writeln!(
            s,
            "  <compiler angle=\"radian\" autolimits=\"true\" inertiafromgeom=\"false\"/>"
        );
        let _ = writeln!(
            s,
            "  <option gravity=\"{} {} {}\" timestep=\"0.001\"/>",
            g[0], g[1], g[2]
        );
        let friction: Vec<String> = (0..n)
            .filter_map(|j| {
                let name = &self.joints()[j].name;
                let parts: Vec<String> = [
                    ("Fc", "Coulomb"),
                    ("offset", "offset"),
                    ("Fs", "Stribeck level"),
                ]
                .iter()
                .filter_map(|(k, label)| {
                    joint_value(j, k)
                        .filter(|v| *v != 0.0)
                        .map(|v| format!("{label} {v}"))
                })
                .collect();
                (!parts.is_empty()).then(|| format!("{name}: {}", parts.join(", ")))
            })
            .collect();
        if !friction.is_empty() {
            let _ = writeln!(
                s,
                "  <!-- not simulated (MuJoCo has no smooth Coulomb law, constant joint \
                 torque or Stribeck hump): {} -->",
                friction.join("; ")
            );
        }
        let _ = writeln!(s, "  <worldbody>");
        let base = quat_of(&crate::spatial::rpy_matrix(self.settings().base_rpy));
        let at = self.settings().base_xyz;
        let _ = writeln!(
            s,
            "    <body name=\"base\" pos=\"{} {} {}\" quat=\"{} {} {} {}\">",
            at[0], at[1], at[2], base[0], base[1], base[2], base[3]
        );
        for j in (0..n).filter(|&j| self.joints()[j].parent.is_none()) {
            self.body_xml(j, &bodies, 3, &mut s);
        }
        let _ = writeln!(s, "    </body>");
        let _ = writeln!(s, "  </worldbody>");
        let _ = writeln!(s, "</mujoco>");
        Ok(s)
    }

    fn body_xml(&self, j: usize, bodies: &[Body], depth: usize, s: &mut String) {
        let pad = "  ".repeat(depth);
        let joint = &self.joints()[j];
        let Body { mass, c, ic, attrs } = &bodies[j];
        let p = joint.origin_translation;
        let q = quat_of(&joint.origin_rotation);
        let _ = writeln!(
            s,
            "{pad}<body name=\"{}\" pos=\"{} {} {}\" quat=\"{} {} {} {}\">",
            xml_escape(&joint.link),
            p[0],
            p[1],
            p[2],
            q[0],
            q[1],
            q[2],
            q[3]
        );
        let kind = match joint.kind {
            JointKind::Prismatic => "slide",
            _ => "hinge",
        };
        let range = match (joint.kind, joint.limits) {
            (JointKind::Continuous, _) => String::new(),
            (_, Some(l)) => match (l.lower, l.upper) {
                (Some(a), Some(b)) if b > a => format!(" range=\"{a} {b}\""),
                _ => String::new(),
            },
            _ => String::new(),
        };
        let a = joint.axis;
        let _ = writeln!(
            s,
            "{pad}  <joint name=\"{}\" type=\"{kind}\" axis=\"{} {} {}\"{range}{attrs}/>",
            xml_escape(&joint.name),
            a[0],
            a[1],
            a[2]
        );
        let _ = writeln!(
            s,
            "{pad}  <inertial pos=\"{} {} {}\" mass=\"{mass}\" fullinertia=\"{} {} {} {} {} {}\"/>",
            c[0], c[1], c[2], ic[0][0], ic[1][1], ic[2][2], ic[0][1], ic[0][2], ic[1][2]
        );
        for k in (0..self.dof()).filter(|&k| self.joints()[k].parent == Some(j)) {
            self.body_xml(k, bodies, depth + 1, s);
        }
        let _ = writeln!(s, "{pad}</body>");
    }
}

/// One body's inertial (mass, centre of mass, central inertia) and its
/// joint's MuJoCo attributes.
struct Body {
    mass: f64,
    c: [f64; 3],
    ic: [[f64; 3]; 3],
    attrs: String,
}

/// The unit quaternion `w x y z` of a rotation matrix (row-major), by the
/// largest of its four squared components (Shepperd).
fn quat_of(r: &[[f64; 3]; 3]) -> [f64; 4] {
    let t = r[0][0] + r[1][1] + r[2][2];
    let q = if t > r[0][0].max(r[1][1]).max(r[2][2]) {
        let w = 0.5 * (1.0 + t).sqrt();
        let f = 0.25 / w;
        [
            w,
            (r[2][1] - r[1][2]) * f,
            (r[0][2] - r[2][0]) * f,
            (r[1][0] - r[0][1]) * f,
        ]
    } else if r[0][0] >= r[1][1] && r[0][0] >= r[2][2] {
        let x = 0.5 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
        let f = 0.25 / x;
        [
            (r[2][1] - r[1][2]) * f,
            x,
            (r[0][1] + r[1][0]) * f,
            (r[0][2] + r[2][0]) * f,
        ]
    } else if r[1][1] >= r[2][2] {
        let y = 0.5 * (1.0 - r[0][0] + r[1][1] - r[2][2]).sqrt();
        let f = 0.25 / y;
        [
            (r[0][2] - r[2][0]) * f,
            (r[0][1] + r[1][0]) * f,
            y,
            (r[1][2] + r[2][1]) * f,
        ]
    } else {
        let z = 0.5 * (1.0 - r[0][0] - r[1][1] + r[2][2]).sqrt();
        let f = 0.25 / z;
        [
            (r[1][0] - r[0][1]) * f,
            (r[0][2] + r[2][0]) * f,
            (r[1][2] + r[2][1]) * f,
            z,
        ]
    };
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| x / norm)
}

/// `&`, `<`, `>` and `"` as XML entities.
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every branch of Shepperd's choice gives back the rotation.
    #[test]
    fn quaternions_give_back_their_rotation() {
        for rpy in [
            [0.0, 0.0, 0.0],
            [0.3, -0.2, 0.1],
            [3.0, 0.1, -0.2],
            [0.1, 3.0, 0.2],
            [0.2, -0.1, 3.1],
            [1.5, 1.5, -1.5],
        ] {
            let r = crate::spatial::rpy_matrix(rpy);
            let [w, x, y, z] = quat_of(&r);
            let back = [
                [
                    1.0 - 2.0 * (y * y + z * z),
                    2.0 * (x * y - w * z),
                    2.0 * (x * z + w * y),
                ],
                [
                    2.0 * (x * y + w * z),
                    1.0 - 2.0 * (x * x + z * z),
                    2.0 * (y * z - w * x),
                ],
                [
                    2.0 * (x * z - w * y),
                    2.0 * (y * z + w * x),
                    1.0 - 2.0 * (x * x + y * y),
                ],
            ];
            for i in 0..3 {
                for k in 0..3 {
                    assert!((back[i][k] - r[i][k]).abs() < 1e-14, "{rpy:?}");
                }
            }
        }
    }
}
