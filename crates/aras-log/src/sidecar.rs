//! The optional JSON sidecar `LOG.json` next to `LOG.csv` (see
//! `docs/log-format.md`): sensor constants and the excitation period.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::SidecarSource;
use crate::error::LogError;

/// The format tag this reader understands.
pub const FORMAT: &str = "aras-log/1";

/// Contents of a log's JSON sidecar. Every key is optional.
///
/// Unknown keys are errors (a misspelt `gear_ratio` must not silently leave
/// the default in place), except the top-level `truth` and `notes`, which
/// belong to whoever wrote the log (the simulator stores its ground truth in
/// `truth`) and are kept as JSON, unchecked.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sidecar {
    /// Format tag; if present it must be `"aras-log/1"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<String>,
    /// Sensor constants for currents and encoder counts.
    #[serde(default, skip_serializing_if = "Sensors::is_empty")]
    pub sensors: Sensors,
    /// What the robot was made to do.
    #[serde(default, skip_serializing_if = "Excitation::is_empty")]
    pub excitation: Excitation,
    /// How the logged torques relate to the sample times (absent: not
    /// stated, taken as [`TorqueTiming::Sampled`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torques: Option<TorqueTiming>,
    /// Whatever the log's writer knows and wants kept with it (the
    /// simulator: its ground truth); neither read nor checked here.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<serde_json::Value>,
    /// Free notes of the log's writer; neither read nor checked here.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub notes: Option<serde_json::Value>,
}

/// What a logged torque sample stands for in time.
///
/// Why it matters: a digital amplifier holds each commanded torque over the
/// controller step `[t_k, t_{k+1})`, so the held torque `τ_k` acts on the
/// motion between the samples, on average at `t_k + h/2`: against the motion
/// at `t_k` it lags by half a sample, which at 1 kHz costs a few tenths of a
/// fitness point at 2.5 Hz. A measured torque (a current sensor sampled with
/// the angles) belongs to `t_k` itself.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TorqueTiming {
    /// `τ_k` is measured at `t_k`, like the angles (the default).
    #[default]
    Sampled,
    /// `τ_k` is a command held over `[t_k, t_{k+1})` (zero-order hold):
    /// the processing evaluates the motion at the hold's midpoint.
    Held,
}

impl TorqueTiming {
    /// The name written in sidecars and accepted on the command line:
    /// `sampled` or `held`.
    pub fn name(self) -> &'static str {
        match self {
            TorqueTiming::Sampled => "sampled",
            TorqueTiming::Held => "held",
        }
    }

    /// Where in the sample step the torque acts, as a fraction of the step
    /// after `t_k`: 0 for sampled torques, ½ for held commands.
    pub fn offset_steps(self) -> f64 {
        match self {
            TorqueTiming::Sampled => 0.0,
            TorqueTiming::Held => 0.5,
        }
    }
}

impl std::fmt::Display for TorqueTiming {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Sensor constants, one per actuator `[motor 1, motor 2, …]` (as many as
/// the log has joints).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sensors {
    /// Motor torque constants (N·m/A at the motor shaft).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_constants: Option<Vec<f64>>,
    /// Gear ratios: motor turns per joint turn (capstan drive).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gear_ratios: Option<Vec<f64>>,
    /// Encoder counts per motor revolution (written as integers when whole).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "whole_as_integer"
    )]
    pub counts_per_rev: Option<Vec<f64>>,
}

/// Writes whole counts as JSON integers (`4096`, not `4096.0`), as a person
/// would write them.
fn whole_as_integer<S: serde::Serializer>(v: &Option<Vec<f64>>, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeSeq;
    let Some(pair) = v else {
        return s.serialize_none();
    };
    let mut seq = s.serialize_seq(Some(pair.len()))?;
    for x in pair {
        if x.fract() == 0.0 && x.abs() < 9.0e15 {
            seq.serialize_element(&(*x as i64))?;
        } else {
            seq.serialize_element(x)?;
        }
    }
    seq.end()
}

/// Excitation description.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Excitation {
    /// Period of a periodic excitation (s), enabling period averaging.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period_s: Option<f64>,
}

impl Sidecar {
    /// Parses sidecar JSON text; `file` names it in error messages.
    pub fn parse(text: &str, file: &str) -> Result<Self, LogError> {
        let start = text.trim_start();
        if !start.starts_with('{') {
            let found = if start.is_empty() {
                "the file is empty".to_string()
            } else {
                format!("it starts with {:?}", start.chars().next().unwrap_or(' '))
            };
            return Err(LogError::Sidecar {
                file: file.to_string(),
                line: 1,
                column: 1,
                message: format!(
                    "{found}; the sidecar must be one JSON object `{{ … }}` (docs/log-format.md), \
                     or remove the file"
                ),
            });
        }
        let sidecar: Sidecar = serde_json::from_str(text).map_err(|e| {
            let full = e.to_string();
            let suffix = format!(" at line {} column {}", e.line(), e.column());
            let message = full.strip_suffix(&suffix).unwrap_or(&full).to_string();
            let advice = if message.starts_with("unknown field") {
                "; remove or rename the key (only `truth` and `notes` may hold extra data)"
            } else if e.is_syntax() || e.is_eof() {
                "; the sidecar must be one JSON object (JSON has no NaN or Infinity: write finite numbers)"
            } else {
                "; see docs/log-format.md for each key's type (numbers in SI units, pairs as [motor 1, motor 2])"
            };
            LogError::Sidecar {
                file: file.to_string(),
                line: e.line(),
                column: e.column(),
                message: format!("{message}{advice}"),
            }
        })?;
        sidecar.validate(file)?;
        Ok(sidecar)
    }

    /// Reads and parses a sidecar file.
    pub fn read(path: &Path) -> Result<Self, LogError> {
        let text = std::fs::read_to_string(path).map_err(|source| LogError::SidecarIo {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Checks every present value's range.
    fn validate(&self, file: &str) -> Result<(), LogError> {
        if let Some(f) = &self.format
            && f != FORMAT
        {
            return Err(LogError::SidecarValue {
                file: file.into(),
                key: "format".into(),
                value: format!("{f:?}"),
                reason: format!("this reader understands only {FORMAT:?}"),
            });
        }
        self.sensors.validate(file)?;
        if let Some(p) = self.excitation.period_s
            && !(p.is_finite() && p > 0.0)
        {
            return Err(LogError::SidecarValue {
                file: file.into(),
                key: "excitation.period_s".into(),
                value: p.to_string(),
                reason: "the period must be a positive number of seconds".into(),
            });
        }
        Ok(())
    }
}

/// What the sidecar lookup of a log found ([`find_sidecar`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FoundSidecar {
    /// The sidecar (default if none was read).
    pub sidecar: Sidecar,
    /// Where it came from, if one was read.
    pub name: Option<String>,
    /// Why a file beside the log was not read as its sidecar, if so.
    pub note: Option<String>,
}

/// Whether JSON text declares itself an `aras-log` sidecar.
enum Declaration {
    /// `"format": "aras-log/…"` (any version: a wrong one is reported).
    Declared,
    /// Anything else: a lab's own JSON.
    Foreign(&'static str),
}

fn declaration(text: &str) -> Declaration {
    match serde_json::from_str::<serde_json::Value>(text) {
        Ok(serde_json::Value::Object(m)) => match m.get("format") {
            Some(serde_json::Value::String(f)) if f.starts_with("aras-log/") => {
                Declaration::Declared
            }
            _ => Declaration::Foreign("does not declare the aras-log/1 format"),
        },
        Ok(_) => {
            Declaration::Foreign("does not declare the aras-log/1 format (it is not a JSON object)")
        }
        // Broken JSON that names the format is a damaged sidecar: report it.
        Err(_) if text.contains("\"aras-log/") => Declaration::Declared,
        Err(_) => {
            Declaration::Foreign("does not declare the aras-log/1 format (it is not valid JSON)")
        }
    }
}

/// The sidecar of the log at `log` (`None`: a stream) per `source`:
///
/// * [`SidecarSource::Auto`]: `LOG.json` beside the log, if it exists *and
///   declares the format* (`"format": "aras-log/1"`); a lab's own JSON of
///   that name is not read, and [`FoundSidecar::note`] says so. A file that
///   declares the format but is broken is an error.
/// * [`SidecarSource::Path`], [`SidecarSource::Text`]: that sidecar; one that
///   does not declare the format is an error.
/// * With [`SidecarSource::None`], none.
pub fn find_sidecar(log: Option<&Path>, source: &SidecarSource) -> Result<FoundSidecar, LogError> {
    let explicit = |text: &str, name: String| {
        let sidecar = Sidecar::parse(text, &name)?;
        if sidecar.format.is_none() {
            return Err(LogError::SidecarUndeclared { file: name });
        }
        Ok(FoundSidecar {
            sidecar,
            name: Some(name),
            note: None,
        })
    };
    let read = |path: &Path| {
        std::fs::read_to_string(path).map_err(|source| LogError::SidecarIo {
            path: path.to_path_buf(),
            source,
        })
    };
    match source {
        SidecarSource::None => Ok(FoundSidecar::default()),
        SidecarSource::Auto => {
            let Some(candidate) = log.map(crate::sidecar_path).filter(|c| c.is_file()) else {
                return Ok(FoundSidecar::default());
            };
            let text = read(&candidate)?;
            let name = candidate.display().to_string();
            match declaration(&text) {
                Declaration::Declared => Ok(FoundSidecar {
                    sidecar: Sidecar::parse(&text, &name)?,
                    name: Some(name),
                    note: None,
                }),
                Declaration::Foreign(why) => Ok(FoundSidecar {
                    note: Some(format!(
                        "{name} {why}; not read as a sidecar (give it with --sidecar after adding \
                         \"format\": \"aras-log/1\" if it is one)"
                    )),
                    ..FoundSidecar::default()
                }),
            }
        }
        SidecarSource::Path(p) => explicit(&read(p)?, p.display().to_string()),
        SidecarSource::Text { name, json } => explicit(json, name.clone()),
    }
}

impl Excitation {
    /// True if nothing is known (the section is then not written).
    pub fn is_empty(&self) -> bool {
        self.period_s.is_none()
    }
}

impl Sensors {
    /// True if no constant is given (the section is then not written).
    pub fn is_empty(&self) -> bool {
        *self == Sensors::default()
    }

    /// Checks present values: finite everywhere; gear ratios and counts per
    /// revolution positive. Torque constants may be zero here (a placeholder
    /// when the log has torque columns); they are checked when used.
    pub(crate) fn validate(&self, file: &str) -> Result<(), LogError> {
        let check = |key: &str, v: &Option<Vec<f64>>, positive: bool| {
            for (i, x) in v.iter().flatten().enumerate() {
                let ok = x.is_finite() && (!positive || *x > 0.0);
                if !ok {
                    return Err(LogError::SidecarValue {
                        file: file.into(),
                        key: format!("sensors.{key}[{i}]"),
                        value: x.to_string(),
                        reason: if positive {
                            "it must be a positive finite number".into()
                        } else {
                            "it must be a finite number".into()
                        },
                    });
                }
            }
            Ok(())
        };
        check("torque_constants", &self.torque_constants, false)?;
        check("gear_ratios", &self.gear_ratios, true)?;
        check("counts_per_rev", &self.counts_per_rev, true)
    }

    /// These constants with every value present in `over` replacing ours.
    pub(crate) fn overridden_by(&self, over: &Sensors) -> Sensors {
        Sensors {
            torque_constants: over
                .torque_constants
                .clone()
                .or_else(|| self.torque_constants.clone()),
            gear_ratios: over
                .gear_ratios
                .clone()
                .or_else(|| self.gear_ratios.clone()),
            counts_per_rev: over
                .counts_per_rev
                .clone()
                .or_else(|| self.counts_per_rev.clone()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_example_parses_and_ignores_truth() {
        let s = Sidecar::parse(
            r#"{"format": "aras-log/1",
                "sensors": {"torque_constants": [0.05, 0.06], "gear_ratios": [10.0, 12.0], "counts_per_rev": [4096, 4096]},
                "excitation": {"period_s": 10.0},
                "truth": {"anything": [1, 2, {"deep": null}]}, "notes": "free text"}"#,
            "x.json",
        )
        .unwrap();
        assert_eq!(s.sensors.gear_ratios, Some(vec![10.0, 12.0]));
        assert_eq!(s.sensors.counts_per_rev, Some(vec![4096.0, 4096.0]));
        assert_eq!(s.excitation.period_s, Some(10.0));
        assert_eq!(Sidecar::parse("{}", "e.json").unwrap(), Sidecar::default());
    }

    #[test]
    fn nested_unknown_key_is_named_with_position() {
        let e = Sidecar::parse("{\n \"sensors\": {\"gear_ratio\": [1, 1]}}", "s.json").unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("s.json:2:"), "{m}");
        assert!(m.contains("unknown field `gear_ratio`"), "{m}");
    }
}
