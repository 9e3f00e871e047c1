//! The URDF's links and joints as one kinematic tree: names checked and
//! resolved, the root found, and the rigid bodies the movable joints move
//! (each child link with every link fixed to it) collected depth first,
//! with their inertials.

use std::collections::HashMap;

use super::{Frame, Joint, JointKind, JointLimits, LINK_COLUMNS, standard_in};
use crate::error::UrdfError;
use crate::parse::{RawKind, RawRobot};

/// Where a link sits: the movable joint it moves with (`None` for the base)
/// and its frame in that joint's body.
pub(super) type Placement = (Option<usize>, Frame);

/// The links and joints of a URDF, resolved by name.
pub(super) struct Tree<'a> {
    /// The parsed URDF.
    raw: &'a RawRobot,
    /// `file` for messages.
    file: &'a str,
    /// Each link's index by name.
    link_index: HashMap<&'a str, usize>,
    /// The joint whose child each link is.
    parent_joint: Vec<Option<usize>>,
    /// The joints whose parent each link is, in the file's order.
    children: Vec<Vec<usize>>,
}

impl<'a> Tree<'a> {
    /// Resolves the names of `raw` (from `file`): unique link and joint
    /// names, every joint's links defined, and at most one parent joint per
    /// link (a second one would close a loop).
    pub fn new(raw: &'a RawRobot, file: &'a str) -> Result<Self, UrdfError> {
        let mut link_index = HashMap::new();
        for (k, l) in raw.links.iter().enumerate() {
            if link_index.insert(l.name.as_str(), k).is_some() {
                return Err(element(
                    file,
                    l.line,
                    format!("<link name=\"{}\">", l.name),
                    "repeats a link name".to_owned(),
                    "give every link a unique name",
                ));
            }
        }
        let mut joint_names = HashMap::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; raw.links.len()];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); raw.links.len()];
        for (k, j) in raw.joints.iter().enumerate() {
            let here = format!("<joint name=\"{}\">", j.name);
            if joint_names.insert(j.name.as_str(), k).is_some() {
                return Err(element(
                    file,
                    j.line,
                    here,
                    "repeats a joint name".to_owned(),
                    "give every joint a unique name",
                ));
            }
            let find = |l: &str, role: &str| {
                link_index.get(l).copied().ok_or_else(|| {
                    element(
                        file,
                        j.line,
                        here.clone(),
                        format!("its {role} link \"{l}\" is not defined"),
                        "define the link with <link name=\"…\"> or correct the name",
                    )
                })
            };
            let p = find(&j.parent, "parent")?;
            let c = find(&j.child, "child")?;
            if let Some(other) = parent_joint[c] {
                return Err(element(
                    file,
                    j.line,
                    here,
                    format!(
                        "link \"{}\" is already the child of joint \"{}\": this closes a kinematic loop",
                        j.child, raw.joints[other].name
                    ),
                    "the model takes trees only: every link has at most one parent joint",
                ));
            }
            parent_joint[c] = Some(k);
            children[p].push(k);
        }
        Ok(Self {
            raw,
            file,
            link_index,
            parent_joint,
            children,
        })
    }

    /// The one link that is no joint's child.
    pub fn root(&self) -> Result<usize, UrdfError> {
        let raw = self.raw;
        let roots: Vec<usize> = (0..raw.links.len())
            .filter(|&l| self.parent_joint[l].is_none())
            .collect();
        match roots.as_slice() {
            [r] => Ok(*r),
            [] if raw.links.is_empty() => Err(self.structure(
                "has no <link>".to_owned(),
                "give a URDF with links and joints",
            )),
            [] => Err(self.structure(
                "every link is some joint's child, so the joints form a closed loop".to_owned(),
                "the model takes trees only: remove the joint that closes the loop",
            )),
            many => {
                let names: Vec<&str> = many.iter().map(|&l| raw.links[l].name.as_str()).collect();
                Err(self.structure(
                    format!(
                        "has {} root links ({}), not one tree",
                        many.len(),
                        names.join(", ")
                    ),
                    "connect every part to the base by joints (a fixed joint for a rigid mount) or remove the unconnected links",
                ))
            }
        }
    }

    /// Depth first from `root`, children in the file's order: the movable
    /// joints (a parent before its children), and every link's
    /// [`Placement`]. Links the walk does not reach form a loop apart from
    /// the tree; a tree without a movable joint has nothing to identify.
    pub fn joints(&self, root: usize) -> Result<(Vec<Joint>, Vec<Option<Placement>>), UrdfError> {
        let raw = self.raw;
        let mut joints: Vec<Joint> = Vec::new();
        let mut link_body: Vec<Option<Placement>> = vec![None; raw.links.len()];
        link_body[root] = Some((None, Frame::ID));
        let mut stack: Vec<usize> = self.children[root].iter().rev().copied().collect();
        let mut visited = 1;
        while let Some(k) = stack.pop() {
            let j = &raw.joints[k];
            let (p, c) = (
                self.link_index[j.parent.as_str()],
                self.link_index[j.child.as_str()],
            );
            let (body, in_body) = link_body[p].expect("parents are visited first");
            let origin = in_body.then(&Frame::from_origin(j.xyz, j.rpy));
            let kind = match j.kind {
                RawKind::Fixed => None,
                RawKind::Revolute => Some(JointKind::Revolute),
                RawKind::Continuous => Some(JointKind::Continuous),
                RawKind::Prismatic => Some(JointKind::Prismatic),
            };
            link_body[c] = Some(match kind {
                None => (body, origin),
                Some(kind) => {
                    joints.push(Joint {
                        name: j.name.clone(),
                        link: j.child.clone(),
                        merged: Vec::new(),
                        kind,
                        parent: body,
                        axis: j.axis,
                        origin_rotation: origin.r,
                        origin_translation: origin.p,
                        limits: j.limit.as_ref().map(|l| JointLimits {
                            lower: l.lower,
                            upper: l.upper,
                            effort: l.effort,
                            velocity: l.velocity,
                        }),
                        inertial: [0.0; LINK_COLUMNS],
                    });
                    (Some(joints.len() - 1), Frame::ID)
                }
            });
            visited += 1;
            stack.extend(self.children[c].iter().rev().copied());
        }
        if visited != raw.links.len() {
            let stray: Vec<&str> = (0..raw.links.len())
                .filter(|&l| link_body[l].is_none())
                .map(|l| raw.links[l].name.as_str())
                .collect();
            return Err(self.structure(
                format!(
                    "links {} form a closed loop apart from the tree",
                    stray.join(", ")
                ),
                "the model takes trees only: remove the joint that closes the loop",
            ));
        }
        if joints.is_empty() {
            return Err(self.structure(
                "has no revolute, continuous or prismatic joint".to_owned(),
                "give a robot with at least one movable joint",
            ));
        }
        Ok((joints, link_body))
    }

    /// Adds every link's inertial to the standard parameters of the body it
    /// is placed in (`link_body`), noting the links merged into a body;
    /// links fixed to the base are part of the world and carry no
    /// parameter.
    pub fn add_inertials(&self, link_body: &[Option<Placement>], joints: &mut [Joint]) {
        for (l, link) in self.raw.links.iter().enumerate() {
            let (Some((Some(b), in_body)), Some(inertial)) = (link_body[l], &link.inertial) else {
                continue;
            };
            let f = in_body.then(&Frame::from_origin(inertial.xyz, inertial.rpy));
            let [xx, xy, xz, yy, yz, zz] = inertial.inertia;
            let ic = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]];
            let s = standard_in(&f, inertial.mass, &ic);
            let joint = &mut joints[b];
            for (t, v) in joint.inertial.iter_mut().zip(s) {
                *t += v;
            }
            if link.name != joint.link {
                joint.merged.push(link.name.clone());
            }
        }
    }

    /// A problem of the URDF's structure as a whole.
    fn structure(&self, problem: String, fix: &str) -> UrdfError {
        UrdfError::Structure {
            file: self.file.to_owned(),
            problem,
            fix: fix.to_owned(),
        }
    }
}

/// A problem of one element of `file`, at `line`.
fn element(file: &str, line: u32, element: String, problem: String, fix: &str) -> UrdfError {
    UrdfError::Element {
        file: file.to_owned(),
        line,
        element,
        problem,
        fix: fix.to_owned(),
    }
}
