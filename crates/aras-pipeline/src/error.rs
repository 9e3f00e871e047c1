//! The crate's error type.

use aras_ident::IdentError;

/// What went wrong in identification, diagnosis or validation of the
/// ARAS-Diamond. Every variant says what was wrong and how to fix it; a
/// variant caused by another error keeps it as its `source()`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// Estimation, data or a setting refused by `aras-ident` (its message
    /// names the setting or the data and the remedy); also the errors of
    /// the robot crates, which it carries with their context.
    #[error(transparent)]
    Ident(#[from] IdentError),
    /// A setting of this crate out of its range.
    #[error("setting `{name}` = {value} is invalid: {reason}")]
    InvalidSetting {
        /// The setting's name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What is allowed, and what to give instead.
        reason: &'static str,
    },
    /// The model lacks an effect that the operation works on.
    #[error("the model has no `{effect}` effect, which {needed_by} needs; add it to the model")]
    MissingEffect {
        /// The effect's identifier.
        effect: &'static str,
        /// What needs it.
        needed_by: &'static str,
    },
    /// A broken invariant of this crate: a bug, not a fault of the input.
    #[error(
        "internal error in aras-pipeline: {0}; please report it with the command that led here"
    )]
    Internal(&'static str),
}

impl PipelineError {
    /// The error as `aras-ident`'s, for the traits of `aras-diagnose` and
    /// `aras-ident` that this crate implements (their methods return
    /// [`IdentError`]): an `aras-ident` error as it is, any other wrapped
    /// with its source kept.
    pub fn into_ident(self) -> IdentError {
        match self {
            Self::Ident(e) => e,
            other => IdentError::external("aras-pipeline", other),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error as _;

    /// An `aras-ident` error passes through both ways unchanged; this
    /// crate's own errors cross into `IdentError` with their message kept
    /// as the source, so the chain a program prints still names them.
    #[test]
    fn errors_cross_into_aras_ident_with_their_message() {
        let ident = IdentError::InvalidData {
            context: "rows".into(),
            reason: "none".into(),
        };
        let text = ident.to_string();
        let back = PipelineError::from(ident).into_ident();
        assert_eq!(back.to_string(), text);

        let missing = PipelineError::MissingEffect {
            effect: "friction",
            needed_by: "refining the Coulomb transition widths",
        };
        let text = missing.to_string();
        assert!(
            text.contains("`friction`") && text.contains("add it"),
            "{text}"
        );
        let crossed = missing.into_ident();
        let source = crossed.source().expect("the pipeline error is the source");
        assert_eq!(source.to_string(), text);

        let internal = PipelineError::Internal("an invariant").to_string();
        assert!(
            internal.contains("an invariant") && internal.contains("report"),
            "{internal}"
        );
    }
}
