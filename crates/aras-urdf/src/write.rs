//! The identified URDF: the robot's own file with each body's inertial
//! replaced by identified parameters, every other byte kept.

use roxmltree::{Document, Node};

use crate::model::{LINK_COLUMNS, UrdfModel};
use crate::{UrdfError, parse};

impl UrdfModel {
    /// The URDF text `source` (the file this model was built from, named
    /// `file` in messages) with the standard parameters `params` (e.g. a
    /// physically consistent identification) as its inertials.
    ///
    /// Each body's `m, m·c, I_O` go into its own link's `<inertial>`
    /// (frame at the centre of mass, axes of the link: `rpy="0 0 0"`,
    /// `I_c = I_O − m [c]×ᵀ[c]×`); links merged into the body by fixed
    /// joints lose theirs, since the body's parameters hold them, and get a
    /// comment saying so. Links fixed to the base, joints, visuals,
    /// collisions, comments and every other byte are kept. Refused: a text
    /// that is not this model's robot, a wrong parameter count, and a body
    /// whose parameters are not physical (mass ≤ 0, a central inertia that
    /// is not positive semidefinite), named by its link.
    pub fn identified_urdf(
        &self,
        source: &str,
        file: &str,
        params: &[f64],
    ) -> Result<String, UrdfError> {
        self.check_parameters(params)?;
        let again = UrdfModel::from_urdf_str(source, file, self.settings().clone())?;
        let same = again.joints().len() == self.joints().len()
            && again
                .joints()
                .iter()
                .zip(self.joints())
                .all(|(a, b)| a.name == b.name && a.link == b.link && a.merged == b.merged);
        if !same {
            return Err(UrdfError::Structure {
                file: file.to_owned(),
                problem: "is not the robot this model was built from (its joints or links differ)"
                    .to_owned(),
                fix: "give the URDF text the model was read from".to_owned(),
            });
        }
        let doc = Document::parse(source).map_err(|source| UrdfError::Xml {
            file: file.to_owned(),
            source,
        })?;
        let links: Vec<Node> = doc
            .root_element()
            .children()
            .filter(|n| n.is_element() && n.tag_name().name() == "link")
            .collect();
        let find = |name: &str| links.iter().find(|l| l.attribute("name") == Some(name));
        let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
        for (j, joint) in self.joints().iter().enumerate() {
            let p = &params[LINK_COLUMNS * j..LINK_COLUMNS * (j + 1)];
            let text = inertial_text(p).ok_or_else(|| UrdfError::Setting {
                name: format!("parameters of link `{}`", joint.link),
                problem: format!(
                    "{p:?} is not a physical body (mass ≤ 0 or a central inertia that is not \
                     positive semidefinite); write a physically consistent identification"
                ),
            })?;
            if let Some(link) = find(&joint.link) {
                edits.push(replace_inertial(source, *link, &text));
            }
            for merged in &joint.merged {
                if let Some(link) = find(merged)
                    && let Some(old) = parse::child(*link, "inertial")
                {
                    edits.push((
                        old.range(),
                        format!(
                            "<!-- inertial identified as part of link `{}` -->",
                            joint.link
                        ),
                    ));
                }
            }
        }
        edits.sort_by_key(|(r, _)| r.start);
        let mut out = String::with_capacity(source.len() + 256 * edits.len());
        let mut at = 0;
        for (range, text) in edits {
            out.push_str(&source[at..range.start]);
            out.push_str(&text);
            at = range.end;
        }
        out.push_str(&source[at..]);
        Ok(out)
    }
}

/// The edit that gives `link` the inertial `text`: in place of its
/// `<inertial>`, before its end tag, or opening a self-closed link.
fn replace_inertial(source: &str, link: Node, text: &str) -> (std::ops::Range<usize>, String) {
    let indent = |at: usize| {
        let line_start = source[..at].rfind('\n').map_or(0, |i| i + 1);
        source[line_start..at]
            .chars()
            .take_while(|c| c.is_whitespace())
            .collect::<String>()
    };
    if let Some(old) = parse::child(link, "inertial") {
        let r = old.range();
        return (r.clone(), indented(text, &indent(r.start)));
    }
    let r = link.range();
    let outer = indent(r.start);
    let inner = format!("{outer}  ");
    let element = &source[r.clone()];
    if let Some(open) = element.strip_suffix("/>") {
        let open = open.trim_end();
        return (
            r,
            format!("{open}>\n{inner}{}\n{outer}</link>", indented(text, &inner)),
        );
    }
    // Before `</link>`.
    let end = r.start + element.rfind("</").unwrap_or(element.len());
    (end..end, format!("  {}\n{outer}", indented(text, &inner)))
}

/// `text` with every line after the first indented by `indent`.
fn indented(text: &str, indent: &str) -> String {
    text.lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                l.to_owned()
            } else {
                format!("\n{indent}{l}")
            }
        })
        .collect()
}

/// A body's mass, centre of mass and central inertia from its standard
/// parameters (`m, m·c, I_O` about its frame's origin); `None` when they
/// are not physical (mass ≤ 0, not finite, or a central inertia that is not
/// positive semidefinite).
pub(crate) fn central(p: &[f64]) -> Option<(f64, [f64; 3], [[f64; 3]; 3])> {
    let m = p[0];
    if !(m.is_finite() && m > 0.0) || p.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let c = [p[1] / m, p[2] / m, p[3] / m];
    // I_c = I_O − m ([c]×ᵀ[c]×) = I_O − m (|c|² E − c cᵀ).
    let cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    let io = [[p[4], p[5], p[7]], [p[5], p[6], p[8]], [p[7], p[8], p[9]]];
    let mut ic = [[0.0; 3]; 3];
    for r in 0..3 {
        for k in 0..3 {
            let e = if r == k { cc } else { 0.0 };
            ic[r][k] = io[r][k] - m * (e - c[r] * c[k]);
        }
    }
    // Positive semidefinite: the leading minors of I_c + ε E positive, ε a
    // rounding allowance on its scale.
    let eps = 1e-12 * (ic[0][0].abs() + ic[1][1].abs() + ic[2][2].abs()).max(f64::MIN_POSITIVE);
    let a = |r: usize, k: usize| ic[r][k] + if r == k { eps } else { 0.0 };
    let d1 = a(0, 0);
    let d2 = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
    let d3 = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1))
        - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
        + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
    (d1 > 0.0 && d2 > 0.0 && d3 > 0.0).then_some((m, c, ic))
}

/// A body's standard parameters as a URDF `<inertial>` at its centre of
/// mass; `None` when they are not physical ([`central`]).
fn inertial_text(p: &[f64]) -> Option<String> {
    let (m, c, ic) = central(p)?;
    Some(format!(
        "<inertial>\n  <origin xyz=\"{} {} {}\" rpy=\"0 0 0\"/>\n  <mass value=\"{m}\"/>\n  \
         <inertia ixx=\"{}\" ixy=\"{}\" ixz=\"{}\" iyy=\"{}\" iyz=\"{}\" izz=\"{}\"/>\n</inertial>",
        c[0], c[1], c[2], ic[0][0], ic[0][1], ic[0][2], ic[1][1], ic[1][2], ic[2][2]
    ))
}
