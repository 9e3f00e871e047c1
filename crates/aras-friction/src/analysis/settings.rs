//! The settings of a friction analysis, with their defaults and checks.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::{effects::LibrarySettings, fit::FitSettings, models::DELTA};

/// Settings of [`analyse`](super::analyse): the fits, the candidate effects
/// and the forward selection. `Default` gives the documented defaults; the
/// selection's (`alpha`, `min_gain`, `max_steps`) are those of
/// [`aras_ident::selection::SelectionOptions::default`], the engine that
/// runs it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrictionSettings {
    /// Model fitting.
    pub fit: FitSettings,
    /// The candidate effects of the diagnosis.
    pub library: LibrarySettings,
    /// Significance level of a diagnosis round (Bonferroni over its
    /// candidates).
    pub alpha: f64,
    /// Smallest fitness gain (points of (78)) an effect must bring on every
    /// validation log.
    pub min_gain: f64,
    /// At most this many effects are added.
    pub max_steps: usize,
}

impl Default for FrictionSettings {
    fn default() -> Self {
        let s = aras_ident::selection::SelectionOptions::default();
        Self {
            fit: FitSettings::default(),
            library: LibrarySettings::default(),
            alpha: s.alpha,
            min_gain: s.min_gain,
            max_steps: s.max_steps,
        }
    }
}

/// A setting outside its valid range: `key` is its dotted path inside
/// [`FrictionSettings`] (`fit.starts`, `alpha`), `reason` says what is
/// accepted.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("setting `{key}`: {reason}")]
pub struct SettingError {
    /// Dotted path of the setting inside [`FrictionSettings`].
    pub key: &'static str,
    /// What is wrong and what is accepted.
    pub reason: String,
}

/// Highest degree [`crate::effects::LibrarySettings::position_map`] may
/// take: 3 columns a degree, and a map of more than 20 degrees over one
/// stroke fits the noise of the rows it passes through.
const MAX_MAP_DEGREE: u32 = 20;

impl FrictionSettings {
    /// Checks every setting; the first one out of range is the error.
    pub fn validate(&self) -> Result<(), SettingError> {
        let bad = |key, reason: String| Err(SettingError { key, reason });
        let f = &self.fit;
        if f.starts == 0 {
            return bad(
                "fit.starts",
                "must be at least 1 (local searches started per model; default 3)".into(),
            );
        }
        if f.max_iterations == 0 {
            return bad(
                "fit.max_iterations",
                "must be at least 1 (iterations of each local search; default 80)".into(),
            );
        }
        if let Some(d) = f.shape
            && !(d.is_finite() && (DELTA.lower..=DELTA.upper).contains(&d))
        {
            return bad(
                "fit.shape",
                format!(
                    "the Stribeck shape exponent must lie in [{}, {}] (2 is the classical \
                     LuGre shape; leave it out to fit it), found {d}",
                    DELTA.lower, DELTA.upper
                ),
            );
        }
        if !(self.alpha.is_finite() && self.alpha > 0.0 && self.alpha < 1.0) {
            return bad(
                "alpha",
                format!(
                    "must be a significance level in (0, 1) such as 0.01, found {}",
                    self.alpha
                ),
            );
        }
        if !(self.min_gain.is_finite() && self.min_gain >= 0.0) {
            return bad(
                "min_gain",
                format!(
                    "must be a finite number of fitness points ≥ 0, found {}",
                    self.min_gain
                ),
            );
        }
        if self.library.position_map > MAX_MAP_DEGREE {
            return bad(
                "library.position_map",
                format!(
                    "the position map's highest Legendre degree must be at most {MAX_MAP_DEGREE} \
                     (a finer map memorises the trajectory; default 6, 0 for none), found {}",
                    self.library.position_map
                ),
            );
        }
        if self.max_steps == 0 {
            return bad(
                "max_steps",
                "must be at least 1 (the number of effects the diagnosis may add)".into(),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_out_of_range_values_are_named() {
        assert_eq!(FrictionSettings::default().validate(), Ok(()));
        let with = |f: fn(&mut FrictionSettings)| {
            let mut s = FrictionSettings::default();
            f(&mut s);
            s.validate().unwrap_err()
        };
        assert_eq!(with(|s| s.fit.starts = 0).key, "fit.starts");
        assert_eq!(with(|s| s.fit.max_iterations = 0).key, "fit.max_iterations");
        let e = with(|s| s.fit.shape = Some(9.0));
        assert_eq!(e.key, "fit.shape");
        assert!(
            e.reason.contains("[0.25, 5]") && e.reason.contains("9"),
            "{e}"
        );
        assert!(with(|s| s.fit.shape = Some(f64::NAN)).key == "fit.shape");
        assert_eq!(with(|s| s.alpha = 1.5).key, "alpha");
        assert_eq!(with(|s| s.alpha = 0.0).key, "alpha");
        assert_eq!(with(|s| s.min_gain = -1.0).key, "min_gain");
        assert_eq!(with(|s| s.max_steps = 0).key, "max_steps");
        assert_eq!(
            with(|s| s.library.position_map = 21).key,
            "library.position_map"
        );
    }
}
