//! The robot as the configuration describes it. The adapters between the
//! library crates live in them: `aras_excite::TaskRegressor` (the model as
//! the design's regressor), `aras_excite::FourierTrajectory` implements
//! `aras_dyn::Trajectory`, and `aras_pipeline::robot` stacks, filters and
//! builds the physically consistent problem.

use aras_pipeline::diagnose::Additions;
use std::path::Path;

use anyhow::{Context, Result};
use aras_dyn::{Effect, EffectId, Model, Params};
use aras_pipeline::diagnose::Candidate;
use nalgebra::Vector3;

use crate::config::RobotConfig;

/// The nominal robot: its parameters (the CAD values, the reference of the
/// physically consistent fit) with the configured overrides applied.
pub fn nominal(cfg: &RobotConfig, dir: &Path) -> Result<Params> {
    let mut p = load_params(&cfg.params, dir).context("key `robot.params`")?;
    if let Some(a) = cfg.alpha_deg {
        p.alpha_deg = a;
    }
    if let Some(b) = cfg.beta_deg {
        p.beta_deg = b;
    }
    if let Some(g) = cfg.gravity {
        p.gravity = Vector3::from(g);
    }
    p.validate()
        .context("the robot's parameters with the overrides of [robot]")?;
    p.check_physical().context(
        "the nominal robot (key `robot.params`) is the reference of the physically consistent fit \
         and the simulated robot, so it must be physically consistent",
    )?;
    Ok(p)
}

/// What a parameter file given on the command line is read for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamsUse {
    /// A model of real bodies (`validate`, `export-mjcf`): a file that is
    /// not physically consistent ([`Params::check_physical`]: masses,
    /// pseudo-inertias, signs of friction and stiffness) is refused, with
    /// why it is needed.
    Physical(&'static str),
    /// An estimate to predict with (`predict`): an OLS estimate may break
    /// physical consistency, so the file is accepted with a note saying so.
    Estimate,
}

/// Reads the parameter file `path` with the one check every command
/// applies: the format's own ([`Params::load`]: keys, types, finite
/// values, geometry) and, for `use_`, physical consistency.
pub fn read_params(path: &Path, use_: ParamsUse) -> Result<Params> {
    let p = Params::load(path).with_context(|| format!("reading {}", path.display()))?;
    if let Err(e) = p.check_physical() {
        match use_ {
            ParamsUse::Physical(why) => {
                return Err(anyhow::Error::from(e).context(format!("{}: {why}", path.display())));
            }
            ParamsUse::Estimate => eprintln!(
                "note: {} is not physically consistent ({e}); predicting with it as an \
                 estimate",
                path.display()
            ),
        }
    }
    Ok(p)
}

/// `"default"` → the embedded ARAS-Diamond (`docs/model.md`); anything else is a
/// parameter-file path, relative to `dir`.
pub fn load_params(spec: &str, dir: &Path) -> Result<Params> {
    if spec == "default" {
        return Ok(Params::aras_diamond());
    }
    let path = dir.join(spec);
    Params::load(&path).with_context(|| format!("cannot load parameter file {}", path.display()))
}

/// The paper's model (rigid links, friction, elasticity; 42 columns) with
/// the robot's gravity: what is identified.
pub fn paper_model(p: &Params) -> Result<Model> {
    Model::paper(p.gravity).context("building the paper's model")
}

/// Parses one `--effects` entry: `ID` or `ID:ARG[:ARG]`, where
/// `stribeck_friction:V_S` takes the Stribeck velocity (rad/s, default 0.2),
/// `presliding_friction:DELTA` the presliding displacement (rad, default
/// 6e-4) and `cogging:CYCLES[:ORDER]` the cycles per joint revolution and
/// the number of harmonics (default 2). The names are those `diagnose` reports.
pub fn parse_effect(spec: &str) -> Result<Effect> {
    let mut parts = spec.trim().split(':');
    let id = parts.next().unwrap_or_default();
    let args: Vec<&str> = parts.collect();
    let num = |i: usize, what: &str| -> Result<Option<f64>> {
        match args.get(i) {
            None => Ok(None),
            Some(a) => match a.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Ok(Some(v)),
                _ => anyhow::bail!("effect `{spec}`: {what} `{a}` must be a positive number"),
            },
        }
    };
    let kind = id
        .parse::<EffectId>()
        .ok()
        .filter(|k| EffectId::EXTRA.contains(k));
    let max_args = match kind {
        Some(EffectId::StribeckFriction | EffectId::PreslidingFriction) => 1,
        Some(EffectId::Cogging) => 2,
        _ => 0,
    };
    if args.len() > max_args {
        anyhow::bail!("effect `{spec}`: `{id}` takes at most {max_args} `:` argument(s)");
    }
    Ok(match kind {
        Some(EffectId::TorqueOffset) => Effect::TorqueOffset,
        Some(EffectId::CoulombAsymmetry) => Effect::CoulombAsymmetry,
        Some(EffectId::StribeckFriction) => Effect::StribeckFriction {
            v_s: num(0, "the Stribeck velocity (rad/s)")?.unwrap_or(0.2),
        },
        Some(EffectId::PassiveJointViscous) => Effect::PassiveJointViscous,
        Some(EffectId::Cogging) => Effect::Cogging {
            cycles_per_rev: num(0, "the cycles per revolution")?.ok_or_else(|| {
                anyhow::anyhow!(
                    "effect `{spec}`: cogging needs its cycles per joint revolution, \
                     e.g. `cogging:12` (as `diagnose` reports it)"
                )
            })?,
            order: num(1, "the number of harmonics")?.map_or(2, |v| v.round() as usize),
        },
        Some(EffectId::QuadraticDamping) => Effect::QuadraticDamping,
        Some(EffectId::PreslidingFriction) => Effect::PreslidingFriction {
            displacement: num(0, "the presliding displacement (rad)")?.unwrap_or(6e-4),
        },
        _ => anyhow::bail!(
            "unknown effect `{id}` in `--effects`; known: {}",
            EffectId::EXTRA.map(EffectId::as_str).join(", ")
        ),
    })
}

/// The report's words for the torque delay, or nothing without one.
pub fn delay_clause(extras: &Additions) -> String {
    extras.torque_delay.map_or(String::new(), |d| {
        format!(
            "; the torque is taken {d} samples after the angles (`--effects time_delay:{d}`), \
             the rows without such a torque left out"
        )
    })
}

/// Parses every `--effects` entry (effects added to the model, and a
/// torque delay removed from the log before processing): [`parse_effect`], except `time_delay:D`
/// (a signed number of samples, at most once).
pub fn parse_extras(specs: &[String]) -> Result<Additions> {
    let mut out = Additions::default();
    for spec in specs {
        let mut parts = spec.trim().split(':');
        if parts.next() != Some(aras_pipeline::diagnose::TIME_DELAY) {
            out.effects.push(parse_effect(spec)?);
            continue;
        }
        let d = match (parts.next(), parts.next()) {
            (Some(a), None) => a.parse::<f64>().ok().filter(|v| v.is_finite()),
            _ => None,
        }
        .ok_or_else(|| {
            anyhow::anyhow!(
                "effect `{spec}`: time_delay needs the delay in samples, a signed number \
                 such as `time_delay:2.9` (as `diagnose` reports it)"
            )
        })?;
        if out.torque_delay.replace(d).is_some() {
            anyhow::bail!("`--effects` gives time_delay twice; give one delay");
        }
    }
    Ok(out)
}

/// The `--effects` entry that adds what the diagnosis named as `candidate`,
/// with its setting replaced by `refined` (a refinement's value) when
/// given: the inverse of [`parse_extras`].
pub fn effect_spec(candidate: &Candidate, refined: Option<f64>) -> String {
    let c = refined.map_or(*candidate, |v| candidate.with_setting(v));
    match c {
        Candidate::TimeDelay { samples } => format!("{}:{samples}", c.id()),
        Candidate::Effect { effect } => match effect {
            Effect::StribeckFriction { v_s } => format!("{}:{v_s}", c.id()),
            Effect::PreslidingFriction { displacement } => format!("{}:{displacement}", c.id()),
            Effect::Cogging {
                cycles_per_rev,
                order,
            } => format!("{}:{cycles_per_rev}:{order}", c.id()),
            _ => c.id().to_string(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every candidate the diagnosis can name, as an `--effects` entry,
    /// parses back to itself (a refined setting included).
    #[test]
    fn effect_specs_parse_back() {
        let effects: Vec<Effect> = EffectId::EXTRA
            .iter()
            .map(|id| match id {
                EffectId::TorqueOffset => Effect::TorqueOffset,
                EffectId::CoulombAsymmetry => Effect::CoulombAsymmetry,
                EffectId::StribeckFriction => Effect::StribeckFriction { v_s: 0.05 },
                EffectId::PassiveJointViscous => Effect::PassiveJointViscous,
                EffectId::Cogging => Effect::Cogging {
                    cycles_per_rev: 12.0,
                    order: 2,
                },
                EffectId::QuadraticDamping => Effect::QuadraticDamping,
                EffectId::PreslidingFriction => Effect::PreslidingFriction {
                    displacement: 4.5e-4,
                },
                other => panic!("an extra effect without an --effects entry: {other}"),
            })
            .collect();
        for effect in &effects {
            let c = Candidate::Effect { effect: *effect };
            let back = parse_extras(&[effect_spec(&c, None)]).unwrap();
            assert_eq!(back.effects, vec![*effect]);
            assert_eq!(back.torque_delay, None);
        }
        let stribeck = Candidate::Effect {
            effect: Effect::StribeckFriction { v_s: 0.05 },
        };
        let back = parse_extras(&[effect_spec(&stribeck, Some(0.0734))]).unwrap();
        assert_eq!(back.effects, vec![Effect::StribeckFriction { v_s: 0.0734 }]);
        let cogging = Candidate::Effect {
            effect: Effect::Cogging {
                cycles_per_rev: 8.0,
                order: 3,
            },
        };
        let back = parse_extras(&[effect_spec(&cogging, Some(13.998))]).unwrap();
        assert_eq!(
            back.effects,
            vec![Effect::Cogging {
                cycles_per_rev: 13.998,
                order: 3
            }]
        );
        let delay = Candidate::TimeDelay { samples: 3.0 };
        for (refined, want) in [(None, 3.0), (Some(-2.94), -2.94)] {
            let back = parse_extras(&[effect_spec(&delay, refined)]).unwrap();
            assert_eq!(back.torque_delay, Some(want));
            assert!(back.effects.is_empty());
        }
    }
}
