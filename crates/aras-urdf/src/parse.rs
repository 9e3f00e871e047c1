//! URDF text to the raw links and joints, element by element, with the
//! source line of each for messages. Only what the dynamics needs is read
//! (`<link>/<inertial>`, `<joint>` with `origin`, `axis`, `limit`,
//! `mimic`); visuals, collisions, transmissions and Gazebo tags are
//! ignored.

use roxmltree::{Document, Node};

use crate::error::UrdfError;
use crate::spatial::V3;

/// A link's `<inertial>` as written: mass, the inertial frame's origin and
/// the inertia about the centre of mass in that frame.
#[derive(Debug, Clone)]
pub(crate) struct RawInertial {
    pub mass: f64,
    pub xyz: V3<f64>,
    pub rpy: V3<f64>,
    /// `ixx, ixy, ixz, iyy, iyz, izz`.
    pub inertia: [f64; 6],
}

#[derive(Debug, Clone)]
pub(crate) struct RawLink {
    pub name: String,
    pub line: u32,
    pub inertial: Option<RawInertial>,
}

/// Joint types the model expresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RawKind {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
}

#[derive(Debug, Clone)]
pub(crate) struct RawLimit {
    pub lower: Option<f64>,
    pub upper: Option<f64>,
    pub effort: Option<f64>,
    pub velocity: Option<f64>,
}

#[derive(Debug, Clone)]
pub(crate) struct RawJoint {
    pub name: String,
    pub line: u32,
    pub kind: RawKind,
    pub parent: String,
    pub child: String,
    pub xyz: V3<f64>,
    pub rpy: V3<f64>,
    /// Unit axis in the joint frame.
    pub axis: V3<f64>,
    pub limit: Option<RawLimit>,
}

#[derive(Debug, Clone)]
pub(crate) struct RawRobot {
    pub name: String,
    pub links: Vec<RawLink>,
    pub joints: Vec<RawJoint>,
}

/// Where an element is, for messages.
struct Site<'a> {
    file: &'a str,
    doc: &'a Document<'a>,
}

impl Site<'_> {
    fn line(&self, node: Node) -> u32 {
        self.doc.text_pos_at(node.range().start).row
    }

    fn describe(node: Node) -> String {
        match node.attribute("name") {
            Some(n) => format!("<{} name=\"{n}\">", node.tag_name().name()),
            None => format!("<{}>", node.tag_name().name()),
        }
    }

    /// An error about `node`, described inside `owner` (e.g. a joint's
    /// `<axis>`).
    fn err(&self, node: Node, owner: Option<Node>, problem: String, fix: &str) -> UrdfError {
        let element = match owner {
            Some(o) if o != node => format!("{} {}", Self::describe(o), Self::describe(node)),
            _ => Self::describe(node),
        };
        UrdfError::Element {
            file: self.file.to_owned(),
            line: self.line(node),
            element,
            problem,
            fix: fix.to_owned(),
        }
    }

    fn number(&self, node: Node, owner: Node, attr: &str) -> Result<Option<f64>, UrdfError> {
        let Some(text) = node.attribute(attr) else {
            return Ok(None);
        };
        match text.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(self.err(
                node,
                Some(owner),
                format!("attribute {attr}=\"{text}\" is not a finite number"),
                "write a decimal number (SI units: m, kg, kg·m², rad)",
            )),
        }
    }

    fn required(&self, node: Node, owner: Node, attr: &str, fix: &str) -> Result<f64, UrdfError> {
        self.number(node, owner, attr)?.ok_or_else(|| {
            self.err(
                node,
                Some(owner),
                format!("attribute `{attr}` is missing"),
                fix,
            )
        })
    }

    fn triple(&self, node: Node, owner: Node, attr: &str) -> Result<Option<V3<f64>>, UrdfError> {
        let Some(text) = node.attribute(attr) else {
            return Ok(None);
        };
        let parts: Vec<Option<f64>> = text
            .split_whitespace()
            .map(|p| p.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect();
        match parts.as_slice() {
            [Some(a), Some(b), Some(c)] => Ok(Some([*a, *b, *c])),
            _ => Err(self.err(
                node,
                Some(owner),
                format!("attribute {attr}=\"{text}\" is not three finite numbers"),
                "write three numbers separated by spaces, e.g. \"0 0 1\"",
            )),
        }
    }

    /// The `<origin>` child of `owner` (identity if absent).
    fn origin(&self, owner: Node) -> Result<(V3<f64>, V3<f64>), UrdfError> {
        match child(owner, "origin") {
            None => Ok(([0.0; 3], [0.0; 3])),
            Some(o) => Ok((
                self.triple(o, owner, "xyz")?.unwrap_or([0.0; 3]),
                self.triple(o, owner, "rpy")?.unwrap_or([0.0; 3]),
            )),
        }
    }

    fn name(&self, node: Node) -> Result<String, UrdfError> {
        match node.attribute("name") {
            Some(n) if !n.trim().is_empty() => Ok(n.to_owned()),
            _ => Err(self.err(
                node,
                None,
                "has no name".to_owned(),
                "give every link and joint a unique, non-empty `name`",
            )),
        }
    }
}

/// The first child element of `node` with tag `tag`.
pub(crate) fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

/// Parses the URDF text `text` (named `file` in messages).
pub(crate) fn parse(text: &str, file: &str) -> Result<RawRobot, UrdfError> {
    let doc = Document::parse(text).map_err(|source| UrdfError::Xml {
        file: file.to_owned(),
        source,
    })?;
    let site = Site { file, doc: &doc };
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(site.err(
            root,
            None,
            "is the top element, not <robot>".to_owned(),
            "give a URDF file: its top element is <robot name=\"…\">",
        ));
    }
    let name = root.attribute("name").unwrap_or("").to_owned();
    let mut links = Vec::new();
    let mut joints = Vec::new();
    for node in root.children().filter(Node::is_element) {
        match node.tag_name().name() {
            "link" => links.push(parse_link(&site, node)?),
            "joint" => joints.push(parse_joint(&site, node)?),
            "loop_joint" => {
                return Err(site.err(
                    node,
                    None,
                    "closes a kinematic loop, which the tree model cannot express".to_owned(),
                    "model a serial or tree robot; a closed chain needs its own model",
                ));
            }
            _ => {}
        }
    }
    Ok(RawRobot {
        name,
        links,
        joints,
    })
}

fn parse_link(site: &Site, node: Node) -> Result<RawLink, UrdfError> {
    let name = site.name(node)?;
    let inertial = match child(node, "inertial") {
        None => None,
        Some(i) => {
            let fix_mass = "give <mass value=\"…\"/> in kg (0 for a massless link)";
            let mass_node = child(i, "mass")
                .ok_or_else(|| site.err(i, Some(node), "has no <mass>".to_owned(), fix_mass))?;
            let mass = site.required(mass_node, node, "value", fix_mass)?;
            if mass < 0.0 {
                return Err(site.err(
                    mass_node,
                    Some(node),
                    format!("mass {mass} kg is negative"),
                    "give a mass ≥ 0 kg",
                ));
            }
            let (xyz, rpy) = site.origin(i)?;
            let fix_i = "give <inertia ixx=… ixy=… ixz=… iyy=… iyz=… izz=…/> in kg·m² about the centre of mass";
            let inertia = match child(i, "inertia") {
                None if mass == 0.0 => [0.0; 6],
                None => {
                    return Err(site.err(i, Some(node), "has no <inertia>".to_owned(), fix_i));
                }
                Some(t) => {
                    let mut v = [0.0; 6];
                    for (k, a) in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
                        .iter()
                        .enumerate()
                    {
                        v[k] = site.required(t, node, a, fix_i)?;
                    }
                    check_inertia(site, t, node, mass, &v)?;
                    v
                }
            };
            Some(RawInertial {
                mass,
                xyz,
                rpy,
                inertia,
            })
        }
    };
    Ok(RawLink {
        name,
        line: site.line(node),
        inertial,
    })
}

/// Refuses a central inertia that no body has: negative principal moments
/// (the tensor is not positive semidefinite), or inertia without mass.
fn check_inertia(
    site: &Site,
    t: Node,
    link: Node,
    mass: f64,
    v: &[f64; 6],
) -> Result<(), UrdfError> {
    let [xx, xy, xz, yy, yz, zz] = *v;
    let scale = xx.abs().max(yy.abs()).max(zz.abs());
    if mass == 0.0 {
        if scale > 0.0 || xy != 0.0 || xz != 0.0 || yz != 0.0 {
            return Err(site.err(
                t,
                Some(link),
                "has inertia but zero mass".to_owned(),
                "give the link its mass, or zero inertia for a massless link",
            ));
        }
        return Ok(());
    }
    // Positive semidefinite: the leading minors of every ordering are
    // covered by the diagonal, the 2 × 2 minors and the determinant
    // (with a tolerance relative to the largest moment).
    let tol = 1e-9 * scale * scale;
    let minors = [xx * yy - xy * xy, xx * zz - xz * xz, yy * zz - yz * yz];
    let det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    if xx < 0.0 || yy < 0.0 || zz < 0.0 || minors.iter().any(|&m| m < -tol) || det < -tol * scale {
        return Err(site.err(
            t,
            Some(link),
            format!(
                "the inertia (ixx {xx}, ixy {xy}, ixz {xz}, iyy {yy}, iyz {yz}, izz {zz}) kg·m² is not positive semidefinite"
            ),
            "give the tensor about the centre of mass with ixy, ixz, iyz as tensor entries (−Σ m x y); check signs and units",
        ));
    }
    Ok(())
}

fn parse_joint(site: &Site, node: Node) -> Result<RawJoint, UrdfError> {
    let name = site.name(node)?;
    let ty = node.attribute("type").unwrap_or("");
    let kind = match ty {
        "revolute" => RawKind::Revolute,
        "continuous" => RawKind::Continuous,
        "prismatic" => RawKind::Prismatic,
        "fixed" => RawKind::Fixed,
        "floating" | "planar" => {
            return Err(site.err(
                node,
                None,
                format!("type \"{ty}\" has several degrees of freedom, which this fixed-base model cannot express"),
                "make the joint fixed (the model's base is fixed; set its orientation with the base settings) or split it into revolute and prismatic joints",
            ));
        }
        _ => {
            return Err(site.err(
                node,
                None,
                format!("type \"{ty}\" is not a URDF joint type"),
                "use revolute, continuous, prismatic or fixed",
            ));
        }
    };
    if let Some(m) = child(node, "mimic") {
        return Err(site.err(
            m,
            Some(node),
            format!(
                "couples this joint to joint \"{}\", which the model cannot express",
                m.attribute("joint").unwrap_or("")
            ),
            "remove <mimic> to treat the joint as independent, or make it fixed",
        ));
    }
    let link_of = |tag: &str| -> Result<String, UrdfError> {
        match child(node, tag).and_then(|c| c.attribute("link")) {
            Some(l) if !l.is_empty() => Ok(l.to_owned()),
            _ => Err(site.err(
                node,
                None,
                format!("has no <{tag} link=\"…\"/>"),
                "name the parent and the child link of every joint",
            )),
        }
    };
    let parent = link_of("parent")?;
    let child_link = link_of("child")?;
    let (xyz, rpy) = site.origin(node)?;
    let axis = match child(node, "axis") {
        None => [1.0, 0.0, 0.0],
        Some(a) => {
            let v = site.triple(a, node, "xyz")?.unwrap_or([1.0, 0.0, 0.0]);
            let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if kind != RawKind::Fixed && (norm.is_nan() || norm <= 1e-9) {
                return Err(site.err(
                    a,
                    Some(node),
                    "the axis is zero".to_owned(),
                    "give the joint axis as a unit vector in the joint frame, e.g. xyz=\"0 0 1\"",
                ));
            }
            if norm > 0.0 {
                [v[0] / norm, v[1] / norm, v[2] / norm]
            } else {
                v
            }
        }
    };
    let limit = match child(node, "limit") {
        None => None,
        Some(l) => {
            let lim = RawLimit {
                lower: site.number(l, node, "lower")?,
                upper: site.number(l, node, "upper")?,
                effort: site.number(l, node, "effort")?,
                velocity: site.number(l, node, "velocity")?,
            };
            if let (Some(lo), Some(hi)) = (lim.lower, lim.upper)
                && lo > hi
            {
                return Err(site.err(
                    l,
                    Some(node),
                    format!("lower limit {lo} exceeds the upper limit {hi}"),
                    "swap the limits or correct them",
                ));
            }
            Some(lim)
        }
    };
    Ok(RawJoint {
        name,
        line: site.line(node),
        kind,
        parent,
        child: child_link,
        xyz,
        rpy,
        axis,
        limit,
    })
}
