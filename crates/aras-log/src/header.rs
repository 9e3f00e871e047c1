//! Header parsing: which column holds what, and how raw sensor values become
//! SI angles and torques.
//!
//! A log has `n ≥ 1` joints, numbered from 1 in its column names
//! (`theta1 … thetaN`); `n` is read from the header, or fixed by
//! [`ReadOptions::joints`](crate::ReadOptions::joints).

use std::f64::consts::TAU;

use super::sidecar::Sensors;
use crate::error::LogError;

/// A per-joint column of the format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Role {
    /// `thetaJ`: joint angle (rad).
    Theta = 0,
    /// `tauJ`: joint torque (N·m).
    Tau = 1,
    /// `iJ`: motor current (A).
    Current = 2,
    /// `encJ`: encoder counts.
    Enc = 3,
    /// `dthetaJ`: logged joint rate (rad/s).
    Dtheta = 4,
    /// `ddthetaJ`: logged joint acceleration (rad/s²).
    Ddtheta = 5,
}

/// The roles in slot order, with their column-name prefixes.
const ROLES: [(Role, &str); 6] = [
    (Role::Theta, "theta"),
    (Role::Tau, "tau"),
    (Role::Current, "i"),
    (Role::Enc, "enc"),
    (Role::Dtheta, "dtheta"),
    (Role::Ddtheta, "ddtheta"),
];

/// A column of the format: time, or a role of joint `j` (0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Field {
    /// `t`: time.
    T,
    /// A per-joint column.
    Joint(Role, usize),
}

impl Field {
    /// The field a standard column name stands for (`t`, `theta3`, `i1`, …;
    /// joint numbers from 1, without leading zeros).
    pub(crate) fn parse(name: &str) -> Option<Self> {
        if name == "t" {
            return Some(Self::T);
        }
        let digits = name.len() - name.trim_end_matches(|c: char| c.is_ascii_digit()).len();
        let (prefix, number) = name.split_at(name.len() - digits);
        if number.is_empty() || number.starts_with('0') || number.len() > 6 {
            return None;
        }
        let j: usize = number.parse().ok()?;
        let role = ROLES.iter().find(|(_, p)| *p == prefix)?.0;
        Some(Self::Joint(role, j - 1))
    }

    /// The standard column name (`t`, `theta1`, …).
    pub(crate) fn name(self) -> String {
        match self {
            Self::T => "t".into(),
            Self::Joint(role, j) => format!("{}{}", ROLES[role as usize].1, j + 1),
        }
    }

    /// The slot of this field in a row of a log of `joints` joints.
    pub(crate) fn slot(self, joints: usize) -> usize {
        match self {
            Self::T => 0,
            Self::Joint(role, j) => 1 + role as usize * joints + j,
        }
    }
}

/// Number of value slots a row of a log of `joints` joints is parsed into.
pub(crate) fn slots(joints: usize) -> usize {
    1 + ROLES.len() * joints
}

/// The standard names of the roles, for messages.
fn role_list() -> String {
    "t, thetaJ, tauJ, iJ, encJ, dthetaJ, ddthetaJ (J = 1, 2, …: the joint)".into()
}

/// A lab's own column names: which header name holds which column of the
/// format (`t`, and per joint J = 1, 2, …: `thetaJ`, `tauJ`, `iJ`, `encJ`,
/// `dthetaJ`, `ddthetaJ`). Roles not renamed keep their standard name; a
/// standard name whose role was given another column is an ordinary,
/// ignored column. Matching ignores case and surrounding quotes, like the
/// header itself.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ColumnNames {
    /// `(field, header name)`, cleaned like header names.
    renamed: Vec<(Field, String)>,
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
                    role_list()
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
        let Some(field) = Field::parse(&role) else {
            return Err(format!(
                "unknown role `{role}`: the roles are {}",
                role_list()
            ));
        };
        if name.is_empty() {
            return Err(format!("role `{role}` has an empty column name"));
        }
        if self.renamed.iter().any(|(f, _)| *f == field) {
            return Err(format!("role `{role}` is named twice"));
        }
        if let Some((f, _)) = self.renamed.iter().find(|(_, n)| *n == name) {
            return Err(format!(
                "column `{name}` is given to both `{}` and `{role}`",
                f.name()
            ));
        }
        self.renamed.push((field, name));
        Ok(())
    }

    /// True when no role is renamed.
    pub fn is_empty(&self) -> bool {
        self.renamed.is_empty()
    }

    /// The field a (cleaned) header name holds, if any.
    fn field_of(&self, name: &str) -> Option<Field> {
        if let Some((f, _)) = self.renamed.iter().find(|(_, n)| n == name) {
            return Some(*f);
        }
        Field::parse(name).filter(|f| !self.renamed.iter().any(|(r, _)| r == f))
    }

    /// How messages name a field: `theta1`, or `q1 (theta1)` when renamed.
    fn label(&self, field: Field) -> String {
        match self.renamed.iter().find(|(f, _)| *f == field) {
            Some((_, n)) => format!("{n} ({})", field.name()),
            None => field.name(),
        }
    }
}

/// Where the joint angles come from.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum AngleSource {
    /// `thetaJ` in radians.
    Theta,
    /// `θ = counts · scale` with `scale = 2π/(counts_per_rev · gear_ratio)`,
    /// per joint.
    Encoder { scale: Vec<f64> },
}

/// Where the joint torques come from.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum TorqueSource {
    /// `tauJ` in N·m.
    Tau,
    /// `τ = i · torque_constant · gear_ratio`, per joint.
    Current { scale: Vec<f64> },
}

impl AngleSource {
    /// The field joint `j`'s angle is read from, and its factor to radians
    /// (1 for `thetaJ`: `x · 1` is `x` exactly).
    pub fn field(&self, j: usize) -> (Field, f64) {
        match self {
            Self::Theta => (Field::Joint(Role::Theta, j), 1.0),
            Self::Encoder { scale } => (Field::Joint(Role::Enc, j), scale[j]),
        }
    }
}

impl TorqueSource {
    /// The field joint `j`'s torque is read from, and its factor to N·m.
    pub fn field(&self, j: usize) -> (Field, f64) {
        match self {
            Self::Tau => (Field::Joint(Role::Tau, j), 1.0),
            Self::Current { scale } => (Field::Joint(Role::Current, j), scale[j]),
        }
    }
}

/// The resolved meaning of every column.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    /// Number of joints.
    pub joints: usize,
    /// Number of fields every row must have.
    pub fields: usize,
    /// Column names as written (trimmed).
    pub names: Vec<String>,
    /// For each column, the slot it is parsed into, or `None` if ignored.
    pub slot_of: Vec<Option<usize>>,
    /// 1-based column of each slot (0 if absent).
    pub column_of: Vec<usize>,
    /// The standard name of each slot, for messages.
    pub slot_names: Vec<String>,
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

/// `theta1, theta2`, `enc1 … enc7`: the columns of a role, for messages.
fn columns_of(role: Role, joints: usize) -> String {
    let name = |j: usize| Field::Joint(role, j).name();
    match joints {
        1 => name(0),
        2 => format!("{}, {}", name(0), name(1)),
        n => format!("{} … {}", name(0), name(n - 1)),
    }
}

/// Where a sensor constant is needed, for [`per_joint`]'s messages.
struct Place<'p> {
    joints: usize,
    file: &'p str,
    sidecar: &'p str,
}

/// A per-joint sensor constant of the sidecar, checked to cover every joint.
fn per_joint<'a>(
    values: Option<&'a [f64]>,
    key: &str,
    role: Role,
    at: &Place<'_>,
) -> Result<&'a [f64], LogError> {
    let joints = at.joints;
    let v = values.ok_or_else(|| LogError::MissingSensor {
        file: at.file.into(),
        columns: columns_of(role, joints),
        key: format!("sensors.{key}"),
        sidecar: at.sidecar.into(),
    })?;
    if v.len() != joints {
        return Err(LogError::SidecarValue {
            file: at.sidecar.into(),
            key: format!("sensors.{key}"),
            value: format!("{v:?}"),
            reason: format!(
                "it has {} values but the log has {joints} joints: give one per joint",
                v.len()
            ),
        });
    }
    Ok(v)
}

impl Layout {
    /// Resolves a header line against the format; `sensors` are the
    /// effective constants (sidecar with overrides), `sidecar_name` where the
    /// sidecar was (for messages), `joints` the expected joint count (`None`:
    /// as many as the header's highest joint number).
    pub fn parse(
        header: &str,
        file: &str,
        line: u64,
        sensors: &Sensors,
        sidecar_name: &str,
        columns: &ColumnNames,
        joints: Option<usize>,
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
        let mut fields = Vec::with_capacity(names.len());
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
            fields.push(columns.field_of(name));
        }
        // Joints: as told, else the highest joint number of the header.
        let n = joints.unwrap_or_else(|| {
            fields
                .iter()
                .filter_map(|f| match f {
                    Some(Field::Joint(_, j)) => Some(j + 1),
                    _ => None,
                })
                .max()
                .unwrap_or(2)
        });
        let fields: Vec<Option<Field>> = fields
            .into_iter()
            .map(|f| f.filter(|f| !matches!(f, Field::Joint(_, j) if *j >= n)))
            .collect();
        let slot_count = slots(n);
        let mut column_of = vec![0usize; slot_count];
        let mut extra = Vec::new();
        for (j, (name, field)) in names.iter().zip(&fields).enumerate() {
            match field {
                Some(f) => column_of[f.slot(n)] = j + 1,
                None => extra.push(name.clone()),
            }
        }
        let has = |f: Field| column_of[f.slot(n)] != 0;
        let header_list = names.join(", ");
        let missing = |name: &str, hint: &str| LogError::MissingColumn {
            file: file.into(),
            line,
            name: name.into(),
            header: header_list.clone(),
            hint: hint.into(),
        };
        // A role is given for every joint or for none.
        let all = |role: Role| -> Result<bool, LogError> {
            let present: Vec<bool> = (0..n).map(|j| has(Field::Joint(role, j))).collect();
            match (
                present.iter().position(|p| *p),
                present.iter().position(|p| !p),
            ) {
                (None, _) => Ok(false),
                (Some(_), None) => Ok(true),
                (Some(p), Some(m)) => Err(LogError::UnpairedColumn {
                    file: file.into(),
                    line,
                    present: columns.label(Field::Joint(role, p)),
                    missing: columns.label(Field::Joint(role, m)),
                }),
            }
        };
        if !has(Field::T) {
            return Err(missing(
                &columns.label(Field::T),
                "name the time column `t` (seconds), or map yours with columns t=NAME",
            ));
        }
        let mut notes = Vec::new();
        let mut used = vec![false; slot_count];
        used[Field::T.slot(n)] = true;
        let mut use_role = |role: Role| {
            for j in 0..n {
                used[Field::Joint(role, j).slot(n)] = true;
            }
        };
        let any = |role: Role| (0..n).any(|j| has(Field::Joint(role, j)));
        let first_missing = |role: Role| {
            (0..n)
                .map(|j| Field::Joint(role, j))
                .find(|f| !has(*f))
                .map_or_else(String::new, |f| columns.label(f))
        };

        let place = Place {
            joints: n,
            file,
            sidecar: sidecar_name,
        };

        // Angles: theta columns, else encoder counts.
        let has_enc = all(Role::Enc)?;
        let thetas = columns_of(Role::Theta, n);
        let angles = if any(Role::Theta) {
            if !all(Role::Theta).unwrap_or(false) {
                return Err(missing(
                    &first_missing(Role::Theta),
                    &format!("give every joint angle {thetas} (rad)"),
                ));
            }
            use_role(Role::Theta);
            if has_enc {
                notes.push(format!(
                    "columns {} ignored: {thetas} are given",
                    columns_of(Role::Enc, n)
                ));
            }
            AngleSource::Theta
        } else if has_enc {
            let cpr = per_joint(
                sensors.counts_per_rev.as_deref(),
                "counts_per_rev",
                Role::Enc,
                &place,
            )?;
            let gear = per_joint(
                sensors.gear_ratios.as_deref(),
                "gear_ratios",
                Role::Enc,
                &place,
            )?;
            use_role(Role::Enc);
            notes.push(format!(
                "joint angles from encoder counts: theta = 2π·enc/(counts_per_rev·gear_ratio), \
                 counts_per_rev = {cpr:?}, gear_ratios = {gear:?}"
            ));
            AngleSource::Encoder {
                scale: cpr.iter().zip(gear).map(|(c, g)| TAU / (c * g)).collect(),
            }
        } else {
            return Err(missing(
                "theta1",
                &format!(
                    "give joint angles {thetas} (rad), or encoder counts {} with \
                     sensors.counts_per_rev and sensors.gear_ratios",
                    columns_of(Role::Enc, n)
                ),
            ));
        };

        // Torques: tau columns, else motor currents.
        let has_i = all(Role::Current)?;
        let taus = columns_of(Role::Tau, n);
        let currents = columns_of(Role::Current, n);
        let torques = if any(Role::Tau) {
            if !all(Role::Tau).unwrap_or(false) {
                return Err(missing(
                    &first_missing(Role::Tau),
                    &format!("give every joint torque {taus} (N·m)"),
                ));
            }
            use_role(Role::Tau);
            if has_i {
                notes.push(format!("columns {currents} ignored: {taus} are given"));
            }
            TorqueSource::Tau
        } else if has_i {
            let kt = per_joint(
                sensors.torque_constants.as_deref(),
                "torque_constants",
                Role::Current,
                &place,
            )?;
            let gear = per_joint(
                sensors.gear_ratios.as_deref(),
                "gear_ratios",
                Role::Current,
                &place,
            )?;
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
            use_role(Role::Current);
            notes.push(format!(
                "joint torques from motor currents: tau = i·torque_constant·gear_ratio, \
                 torque_constants = {kt:?} N·m/A, gear_ratios = {gear:?}"
            ));
            TorqueSource::Current {
                scale: kt.iter().zip(gear).map(|(k, g)| k * g).collect(),
            }
        } else {
            return Err(missing(
                "tau1",
                &format!(
                    "give joint torques {taus} (N·m), or motor currents {currents} with \
                     sensors.torque_constants and sensors.gear_ratios"
                ),
            ));
        };

        let has_velocity = all(Role::Dtheta)?;
        let has_acceleration = all(Role::Ddtheta)?;
        if has_velocity {
            use_role(Role::Dtheta);
        }
        if has_acceleration {
            use_role(Role::Ddtheta);
        }
        if !extra.is_empty() {
            notes.push(format!("extra columns ignored: {}", extra.join(", ")));
        }
        let slot_of = fields
            .iter()
            .map(|f| f.map(|f| f.slot(n)).filter(|&slot| used[slot]))
            .collect();
        let mut slot_names = vec![String::new(); slot_count];
        slot_names[0] = Field::T.name();
        for (role, _) in ROLES {
            for j in 0..n {
                let f = Field::Joint(role, j);
                slot_names[f.slot(n)] = f.name();
            }
        }
        Ok(Self {
            joints: n,
            fields: names.len(),
            names,
            slot_of,
            column_of,
            slot_names,
            angles,
            torques,
            has_velocity,
            has_acceleration,
            notes,
        })
    }

    /// 1-based column of `field` (0 if absent).
    pub fn column(&self, field: Field) -> usize {
        self.column_of[field.slot(self.joints)]
    }

    /// 1-based file columns of the angle channels, then the torque
    /// channels, as read (0 if unknown).
    pub fn channel_columns(&self) -> Vec<usize> {
        let angles = (0..self.joints).map(|j| self.angles.field(j).0);
        let torques = (0..self.joints).map(|j| self.torques.field(j).0);
        angles.chain(torques).map(|f| self.column(f)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_parse_and_name_round_trip() {
        for name in ["t", "theta1", "tau7", "i2", "enc12", "dtheta3", "ddtheta1"] {
            assert_eq!(Field::parse(name).unwrap().name(), name);
        }
        for name in ["theta", "theta0", "theta01", "x1", "thetax", "tau-1", ""] {
            assert_eq!(Field::parse(name), None, "{name}");
        }
        // Slots are distinct and dense for any joint count.
        for n in 1..5 {
            let mut seen = vec![false; slots(n)];
            seen[Field::T.slot(n)] = true;
            for (role, _) in ROLES {
                for j in 0..n {
                    let s = Field::Joint(role, j).slot(n);
                    assert!(!seen[s]);
                    seen[s] = true;
                }
            }
            assert!(seen.iter().all(|s| *s));
        }
    }
}
