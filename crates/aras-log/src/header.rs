//! Header parsing: which column holds what, and how raw sensor values become
//! SI angles and torques.

use std::f64::consts::TAU;

use super::sidecar::Sensors;
use crate::error::LogError;

/// Number of value slots a row is parsed into.
pub(crate) const SLOTS: usize = 13;

/// Slot indices: `t`, θ, τ, currents, encoder counts, θ̇, θ̈.
pub(crate) const T: usize = 0;
pub(crate) const THETA: [usize; 2] = [1, 2];
pub(crate) const TAU_: [usize; 2] = [3, 4];
pub(crate) const CURRENT: [usize; 2] = [5, 6];
pub(crate) const ENC: [usize; 2] = [7, 8];
pub(crate) const DTHETA: [usize; 2] = [9, 10];
pub(crate) const DDTHETA: [usize; 2] = [11, 12];

/// Column names of the slots, in slot order.
pub(crate) const NAMES: [&str; SLOTS] = [
    "t", "theta1", "theta2", "tau1", "tau2", "i1", "i2", "enc1", "enc2", "dtheta1", "dtheta2",
    "ddtheta1", "ddtheta2",
];

/// A lab's own column names: which header name holds which column of the
/// format (`t`, `theta1`, `theta2`, `tau1`, `tau2`, `i1`, `i2`, `enc1`,
/// `enc2`, `dtheta1`, `dtheta2`, `ddtheta1`, `ddtheta2`). Roles not renamed
/// keep their standard name; a standard name whose role was given another
/// column is an ordinary, ignored column. Matching ignores case and
/// surrounding quotes, like the header itself.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ColumnNames {
    /// `(slot, header name)`, cleaned like header names.
    renamed: Vec<(usize, String)>,
}

impl ColumnNames {
    /// Parses `role=name,role=name,…` (e.g. `t=time,theta1=q1,tau1=torque_a`).
    pub fn parse(spec: &str) -> Result<Self, LogError> {
        let bad = |reason: String| LogError::InvalidOption {
            name: "columns",
            value: spec.into(),
            reason,
        };
        let mut out = Self::default();
        for item in spec.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let Some((role, name)) = item.split_once('=') else {
                return Err(bad(format!(
                    "`{item}` is not ROLE=NAME: write e.g. theta1=q1 (roles: {})",
                    NAMES.join(", ")
                )));
            };
            out.rename(role, name).map_err(&bad)?;
        }
        Ok(out)
    }

    /// Gives role `role` (a standard column name) the header name `name`.
    fn rename(&mut self, role: &str, name: &str) -> Result<(), String> {
        let role = clean(role);
        let name = clean(name);
        let Some(slot) = NAMES.iter().position(|n| *n == role) else {
            return Err(format!(
                "unknown role `{role}`: the roles are {}",
                NAMES.join(", ")
            ));
        };
        if name.is_empty() {
            return Err(format!("role `{role}` has an empty column name"));
        }
        if self.renamed.iter().any(|(s, _)| *s == slot) {
            return Err(format!("role `{role}` is named twice"));
        }
        if let Some((s, _)) = self.renamed.iter().find(|(_, n)| *n == name) {
            return Err(format!(
                "column `{name}` is given to both `{}` and `{role}`",
                NAMES[*s]
            ));
        }
        self.renamed.push((slot, name));
        Ok(())
    }

    /// True when no role is renamed.
    pub fn is_empty(&self) -> bool {
        self.renamed.is_empty()
    }

    /// The slot a (cleaned) header name holds, if any.
    fn slot_of(&self, name: &str) -> Option<usize> {
        if let Some((s, _)) = self.renamed.iter().find(|(_, n)| n == name) {
            return Some(*s);
        }
        NAMES
            .iter()
            .position(|n| *n == name)
            .filter(|s| !self.renamed.iter().any(|(r, _)| r == s))
    }

    /// How messages name a slot: `theta1`, or `q1 (theta1)` when renamed.
    fn label(&self, slot: usize) -> String {
        match self.renamed.iter().find(|(s, _)| *s == slot) {
            Some((_, n)) => format!("{n} ({})", NAMES[slot]),
            None => NAMES[slot].to_string(),
        }
    }
}

/// Where the joint angles come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum AngleSource {
    /// `theta1, theta2` in radians.
    Theta,
    /// `θ = counts · scale` with `scale = 2π/(counts_per_rev · gear_ratio)`.
    Encoder { scale: [f64; 2] },
}

/// Where the joint torques come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum TorqueSource {
    /// `tau1, tau2` in N·m.
    Tau,
    /// `τ = i · torque_constant · gear_ratio`.
    Current { scale: [f64; 2] },
}

/// The resolved meaning of every column.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    /// Number of fields every row must have.
    pub fields: usize,
    /// Column names as written (trimmed).
    pub names: Vec<String>,
    /// For each column, the slot it is parsed into, or `None` if ignored.
    pub slot_of: Vec<Option<usize>>,
    /// 1-based column of each slot (0 if absent).
    pub column_of: [usize; SLOTS],
    pub angles: AngleSource,
    pub torques: TorqueSource,
    pub has_velocity: bool,
    pub has_acceleration: bool,
    /// Human-readable notes (ignored columns, sources).
    pub notes: Vec<String>,
}

fn clean(name: &str) -> String {
    let n = name.trim();
    let n = n
        .strip_prefix('"')
        .and_then(|n| n.strip_suffix('"'))
        .unwrap_or(n);
    n.trim().to_ascii_lowercase()
}

impl Layout {
    /// Resolves a header line against the format; `sensors` are the
    /// effective constants (sidecar with overrides), `sidecar_name` where the
    /// sidecar was (for messages).
    pub fn parse(
        header: &str,
        file: &str,
        line: u64,
        sensors: &Sensors,
        sidecar_name: &str,
        columns: &ColumnNames,
    ) -> Result<Self, LogError> {
        if header.contains(';') {
            return Err(LogError::Semicolon {
                file: file.into(),
                line,
            });
        }
        if header.contains('\t') && !header.contains(',') {
            return Err(LogError::TabSeparated {
                file: file.into(),
                line,
            });
        }
        let names: Vec<String> = header.split(',').map(clean).collect();
        let mut column_of = [0usize; SLOTS];
        let mut extra = Vec::new();
        for (j, name) in names.iter().enumerate() {
            if name.is_empty() {
                return Err(LogError::EmptyColumnName {
                    file: file.into(),
                    line,
                    column: j + 1,
                });
            }
            if let Some(first) = names[..j].iter().position(|n| n == name) {
                return Err(LogError::DuplicateColumn {
                    file: file.into(),
                    line,
                    column: j + 1,
                    first: first + 1,
                    name: name.clone(),
                });
            }
            match columns.slot_of(name) {
                Some(slot) => column_of[slot] = j + 1,
                None => extra.push(name.clone()),
            }
        }
        let has = |slot: usize| column_of[slot] != 0;
        let header_list = names.join(", ");
        let missing = |name: &str, hint: &str| LogError::MissingColumn {
            file: file.into(),
            line,
            name: name.into(),
            header: header_list.clone(),
            hint: hint.into(),
        };
        let pair = |slots: [usize; 2]| -> Result<bool, LogError> {
            match (has(slots[0]), has(slots[1])) {
                (true, true) => Ok(true),
                (false, false) => Ok(false),
                (a, _) => {
                    let (p, m) = if a { (0, 1) } else { (1, 0) };
                    Err(LogError::UnpairedColumn {
                        file: file.into(),
                        line,
                        present: columns.label(slots[p]),
                        missing: columns.label(slots[m]),
                    })
                }
            }
        };
        if !has(T) {
            return Err(missing(
                &columns.label(T),
                "name the time column `t` (seconds), or map yours with columns t=NAME",
            ));
        }
        let mut notes = Vec::new();
        let mut used = [false; SLOTS];
        used[T] = true;

        // Angles: theta columns, else encoder counts.
        let has_enc = pair(ENC)?;
        let angles = if has(THETA[0]) || has(THETA[1]) {
            for s in THETA {
                if !has(s) {
                    return Err(missing(
                        &columns.label(s),
                        "give both joint angles theta1, theta2 (rad)",
                    ));
                }
            }
            used[THETA[0]] = true;
            used[THETA[1]] = true;
            if has_enc {
                notes.push("columns enc1, enc2 ignored: theta1, theta2 are given".to_string());
            }
            AngleSource::Theta
        } else if has_enc {
            let cpr = sensors
                .counts_per_rev
                .ok_or_else(|| LogError::MissingSensor {
                    file: file.into(),
                    columns: "enc1, enc2".into(),
                    key: "sensors.counts_per_rev".into(),
                    sidecar: sidecar_name.into(),
                })?;
            let gear = sensors.gear_ratios.ok_or_else(|| LogError::MissingSensor {
                file: file.into(),
                columns: "enc1, enc2".into(),
                key: "sensors.gear_ratios".into(),
                sidecar: sidecar_name.into(),
            })?;
            used[ENC[0]] = true;
            used[ENC[1]] = true;
            notes.push(format!(
                "joint angles from encoder counts: theta = 2π·enc/(counts_per_rev·gear_ratio), \
                 counts_per_rev = {cpr:?}, gear_ratios = {gear:?}"
            ));
            AngleSource::Encoder {
                scale: [TAU / (cpr[0] * gear[0]), TAU / (cpr[1] * gear[1])],
            }
        } else {
            return Err(missing(
                "theta1",
                "give joint angles theta1, theta2 (rad), or encoder counts enc1, enc2 with \
                 sensors.counts_per_rev and sensors.gear_ratios",
            ));
        };

        // Torques: tau columns, else motor currents.
        let has_i = pair(CURRENT)?;
        let torques = if has(TAU_[0]) || has(TAU_[1]) {
            for s in TAU_ {
                if !has(s) {
                    return Err(missing(
                        &columns.label(s),
                        "give both joint torques tau1, tau2 (N·m)",
                    ));
                }
            }
            used[TAU_[0]] = true;
            used[TAU_[1]] = true;
            if has_i {
                notes.push("columns i1, i2 ignored: tau1, tau2 are given".to_string());
            }
            TorqueSource::Tau
        } else if has_i {
            let kt = sensors
                .torque_constants
                .ok_or_else(|| LogError::MissingSensor {
                    file: file.into(),
                    columns: "i1, i2".into(),
                    key: "sensors.torque_constants".into(),
                    sidecar: sidecar_name.into(),
                })?;
            let gear = sensors.gear_ratios.ok_or_else(|| LogError::MissingSensor {
                file: file.into(),
                columns: "i1, i2".into(),
                key: "sensors.gear_ratios".into(),
                sidecar: sidecar_name.into(),
            })?;
            for (i, k) in kt.iter().enumerate() {
                if *k == 0.0 {
                    return Err(LogError::SidecarValue {
                        file: sidecar_name.into(),
                        key: format!("sensors.torque_constants[{i}]"),
                        value: "0".into(),
                        reason: "a zero torque constant turns every current into zero torque: \
                                 give the motor's constant in N·m/A"
                            .into(),
                    });
                }
            }
            used[CURRENT[0]] = true;
            used[CURRENT[1]] = true;
            notes.push(format!(
                "joint torques from motor currents: tau = i·torque_constant·gear_ratio, \
                 torque_constants = {kt:?} N·m/A, gear_ratios = {gear:?}"
            ));
            TorqueSource::Current {
                scale: [kt[0] * gear[0], kt[1] * gear[1]],
            }
        } else {
            return Err(missing(
                "tau1",
                "give joint torques tau1, tau2 (N·m), or motor currents i1, i2 with \
                 sensors.torque_constants and sensors.gear_ratios",
            ));
        };

        let has_velocity = pair(DTHETA)?;
        let has_acceleration = pair(DDTHETA)?;
        for s in DTHETA.iter().chain(DDTHETA.iter()) {
            used[*s] = has(*s);
        }
        if !extra.is_empty() {
            notes.push(format!("extra columns ignored: {}", extra.join(", ")));
        }
        let slot_of = names
            .iter()
            .map(|n| columns.slot_of(n).filter(|&slot| used[slot]))
            .collect();
        Ok(Self {
            fields: names.len(),
            names,
            slot_of,
            column_of,
            angles,
            torques,
            has_velocity,
            has_acceleration,
            notes,
        })
    }
}
