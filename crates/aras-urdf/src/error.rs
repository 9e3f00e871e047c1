//! Why a URDF or a model evaluation was refused.

use std::path::PathBuf;

/// Everything [`crate::UrdfModel`] refuses, with where and what to do.
///
/// Parse errors name the file, the line of the element and the element
/// (`<joint name="elbow">`), say what is wrong and how to fix it.
#[derive(Debug, thiserror::Error)]
pub enum UrdfError {
    /// The file could not be read.
    #[error("cannot read the URDF {path}: {source}; check the path and its permissions")]
    Io {
        /// The path given.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: std::io::Error,
    },

    /// The text is not well-formed XML.
    #[error(
        "{file}: not well-formed XML: {source}; fix the XML (a URDF made by xacro must be expanded first: `xacro robot.urdf.xacro > robot.urdf`)"
    )]
    Xml {
        /// The file (or label) of the text.
        file: String,
        /// The XML parser's message (with line and column).
        #[source]
        source: roxmltree::Error,
    },

    /// One element is wrong or cannot be expressed by the model.
    #[error("{file}:{line}: {element}: {problem}; {fix}")]
    Element {
        /// The file (or label) of the text.
        file: String,
        /// Line of the element's start tag (1-based).
        line: u32,
        /// The element, e.g. `<joint name="elbow">`.
        element: String,
        /// What is wrong.
        problem: String,
        /// What to do about it.
        fix: String,
    },

    /// The robot's structure as a whole cannot be modelled (no or several
    /// roots, a closed loop, no movable joint).
    #[error("{file}: {problem}; {fix}")]
    Structure {
        /// The file (or label) of the text.
        file: String,
        /// What is wrong.
        problem: String,
        /// What to do about it.
        fix: String,
    },

    /// A model setting is out of range.
    #[error("model setting `{name}`: {problem}")]
    Setting {
        /// The setting's name.
        name: String,
        /// What is wrong and the accepted range.
        problem: String,
    },

    /// A slice handed to an evaluation has the wrong length.
    #[error("{what}: expected {expected} entries, found {found}")]
    Dimension {
        /// Which argument.
        what: &'static str,
        /// The length the model needs.
        expected: usize,
        /// The length given.
        found: usize,
    },

    /// A state entry is NaN or infinite (it would spread NaN into every
    /// torque and regressor entry).
    #[error("{what}[{index}] is {value}: give finite joint positions, rates and accelerations")]
    NonFinite {
        /// Which argument (`q`, `q_dot`, `q_ddot`, `parameters`).
        what: &'static str,
        /// Index of the entry.
        index: usize,
        /// The value found.
        value: f64,
    },
}
