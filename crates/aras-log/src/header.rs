//! Header parsing: which column holds what, and how raw sensor values become
//! SI angles and torques.
//!
//! A log has `n ≥ 1` joints, numbered from 1 in its column names
//! (`theta1 … thetaN`); `n` is read from the header, or fixed by
//! [`ReadOptions::joints`](crate::ReadOptions::joints).

use std::f64::consts::TAU;

use super::sidecar::Sensors;
use crate::error::LogError;
use crate::table::{RowColumns, clean};

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
    /// Column names as written (cleaned).
    pub names: Vec<String>,
    /// Which columns a row is parsed from, into the slots of
    /// [`Field::slot`].
    pub row_columns: RowColumns,
    /// 1-based column of each slot (0 if absent).
    pub column_of: Vec<usize>,
    pub angles: AngleSource,
    pub torques: TorqueSource,
    pub has_velocity: bool,
    pub has_acceleration: bool,
    /// Human-readable notes (ignored columns, sources).
    pub notes: Vec<String>,
}

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

/// The header resolved against the format: which field each column holds
/// and which slots are read, with what a message about it needs.
struct Header<'h> {
    /// Number of joints.
    n: usize,
    /// The field of each column (`None`: not a column of the format).
    fields: Vec<Option<Field>>,
    /// 1-based column of each slot (0 if absent).
    column_of: Vec<usize>,
    /// The slots read.
    used: Vec<bool>,
    names: &'h [String],
    columns: &'h ColumnNames,
    file: &'h str,
    line: u64,
}

impl<'h> Header<'h> {
    /// The fields of `names`; joints as told, else the highest joint
    /// number of the header.
    fn new(
        names: &'h [String],
        columns: &'h ColumnNames,
        joints: Option<usize>,
        file: &'h str,
        line: u64,
    ) -> Self {
        let fields: Vec<Option<Field>> = names.iter().map(|n| columns.field_of(n)).collect();
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
        let mut column_of = vec![0usize; slots(n)];
        for (j, field) in fields.iter().enumerate() {
            if let Some(f) = field {
                column_of[f.slot(n)] = j + 1;
            }
        }
        let mut used = vec![false; slots(n)];
        used[Field::T.slot(n)] = true;
        Self {
            n,
            fields,
            column_of,
            used,
            names,
            columns,
            file,
            line,
        }
    }

    fn has(&self, f: Field) -> bool {
        self.column_of[f.slot(self.n)] != 0
    }

    fn any(&self, role: Role) -> bool {
        (0..self.n).any(|j| self.has(Field::Joint(role, j)))
    }

    /// Whether a role is given; it must be for every joint or for none.
    fn all(&self, role: Role) -> Result<bool, LogError> {
        let present: Vec<bool> = (0..self.n)
            .map(|j| self.has(Field::Joint(role, j)))
            .collect();
        match (
            present.iter().position(|p| *p),
            present.iter().position(|p| !p),
        ) {
            (None, _) => Ok(false),
            (Some(_), None) => Ok(true),
            (Some(p), Some(m)) => Err(LogError::UnpairedColumn {
                file: self.file.into(),
                line: self.line,
                present: self.columns.label(Field::Joint(role, p)),
                missing: self.columns.label(Field::Joint(role, m)),
            }),
        }
    }

    /// The label of the first joint's column of `role` that is missing.
    fn first_missing(&self, role: Role) -> String {
        (0..self.n)
            .map(|j| Field::Joint(role, j))
            .find(|f| !self.has(*f))
            .map_or_else(String::new, |f| self.columns.label(f))
    }

    /// A required column is missing; `hint` says what to give.
    fn missing(&self, name: &str, hint: &str) -> LogError {
        LogError::MissingColumn {
            file: self.file.into(),
            line: self.line,
            name: name.into(),
            header: self.names.join(", "),
            hint: hint.into(),
        }
    }

    /// Marks every joint's slot of `role` as read.
    fn use_role(&mut self, role: Role) {
        for j in 0..self.n {
            self.used[Field::Joint(role, j).slot(self.n)] = true;
        }
    }

    /// Angles: `thetaJ` columns, else encoder counts with the sensors'
    /// counts per revolution and gear ratios.
    fn angles(
        &mut self,
        place: &Place<'_>,
        sensors: &Sensors,
        notes: &mut Vec<String>,
    ) -> Result<AngleSource, LogError> {
        let n = self.n;
        let has_enc = self.all(Role::Enc)?;
        let thetas = columns_of(Role::Theta, n);
        if self.any(Role::Theta) {
            if !self.all(Role::Theta).unwrap_or(false) {
                return Err(self.missing(
                    &self.first_missing(Role::Theta),
                    &format!("give every joint angle {thetas} (rad)"),
                ));
            }
            self.use_role(Role::Theta);
            if has_enc {
                notes.push(format!(
                    "columns {} ignored: {thetas} are given",
                    columns_of(Role::Enc, n)
                ));
            }
            Ok(AngleSource::Theta)
        } else if has_enc {
            let cpr = per_joint(
                sensors.counts_per_rev.as_deref(),
                "counts_per_rev",
                Role::Enc,
                place,
            )?;
            let gear = per_joint(
                sensors.gear_ratios.as_deref(),
                "gear_ratios",
                Role::Enc,
                place,
            )?;
            self.use_role(Role::Enc);
            notes.push(format!(
                "joint angles from encoder counts: theta = 2π·enc/(counts_per_rev·gear_ratio), \
                 counts_per_rev = {cpr:?}, gear_ratios = {gear:?}"
            ));
            Ok(AngleSource::Encoder {
                scale: cpr.iter().zip(gear).map(|(c, g)| TAU / (c * g)).collect(),
            })
        } else {
            Err(self.missing(
                "theta1",
                &format!(
                    "give joint angles {thetas} (rad), or encoder counts {} with \
                     sensors.counts_per_rev and sensors.gear_ratios",
                    columns_of(Role::Enc, n)
                ),
            ))
        }
    }

    /// Torques: `tauJ` columns, else motor currents with the sensors'
    /// torque constants and gear ratios.
    fn torques(
        &mut self,
        place: &Place<'_>,
        sensors: &Sensors,
        notes: &mut Vec<String>,
    ) -> Result<TorqueSource, LogError> {
        let n = self.n;
        let has_i = self.all(Role::Current)?;
        let taus = columns_of(Role::Tau, n);
        let currents = columns_of(Role::Current, n);
        if self.any(Role::Tau) {
            if !self.all(Role::Tau).unwrap_or(false) {
                return Err(self.missing(
                    &self.first_missing(Role::Tau),
                    &format!("give every joint torque {taus} (N·m)"),
                ));
            }
            self.use_role(Role::Tau);
            if has_i {
                notes.push(format!("columns {currents} ignored: {taus} are given"));
            }
            Ok(TorqueSource::Tau)
        } else if has_i {
            let kt = per_joint(
                sensors.torque_constants.as_deref(),
                "torque_constants",
                Role::Current,
                place,
            )?;
            let gear = per_joint(
                sensors.gear_ratios.as_deref(),
                "gear_ratios",
                Role::Current,
                place,
            )?;
            if let Some(i) = kt.iter().position(|k| *k == 0.0) {
                return Err(LogError::SidecarValue {
                    file: place.sidecar.into(),
                    key: format!("sensors.torque_constants[{i}]"),
                    value: "0".into(),
                    reason: "a zero torque constant turns every current into zero torque: \
                             give the motor's constant in N·m/A"
                        .into(),
                });
            }
            self.use_role(Role::Current);
            notes.push(format!(
                "joint torques from motor currents: tau = i·torque_constant·gear_ratio, \
                 torque_constants = {kt:?} N·m/A, gear_ratios = {gear:?}"
            ));
            Ok(TorqueSource::Current {
                scale: kt.iter().zip(gear).map(|(k, g)| k * g).collect(),
            })
        } else {
            Err(self.missing(
                "tau1",
                &format!(
                    "give joint torques {taus} (N·m), or motor currents {currents} with \
                     sensors.torque_constants and sensors.gear_ratios"
                ),
            ))
        }
    }

    /// The logged derivatives: each role for every joint or none.
    fn rates(&mut self) -> Result<(bool, bool), LogError> {
        let has_velocity = self.all(Role::Dtheta)?;
        let has_acceleration = self.all(Role::Ddtheta)?;
        if has_velocity {
            self.use_role(Role::Dtheta);
        }
        if has_acceleration {
            self.use_role(Role::Ddtheta);
        }
        Ok((has_velocity, has_acceleration))
    }

    /// The columns that are not of the format, for a note.
    fn extra(&self) -> Vec<&str> {
        self.names
            .iter()
            .zip(&self.fields)
            .filter(|(_, f)| f.is_none())
            .map(|(name, _)| name.as_str())
            .collect()
    }

    /// The columns a row is parsed from: each read field into its slot.
    fn row_columns(&self) -> RowColumns {
        let n = self.n;
        let slot_of = self
            .fields
            .iter()
            .map(|f| f.map(|f| f.slot(n)).filter(|&slot| self.used[slot]))
            .collect();
        let mut slot_names = vec![String::new(); slots(n)];
        slot_names[0] = Field::T.name();
        for (role, _) in ROLES {
            for j in 0..n {
                let f = Field::Joint(role, j);
                slot_names[f.slot(n)] = f.name();
            }
        }
        RowColumns::from_slots(slot_of, slot_names)
    }
}

impl Layout {
    /// Resolves a header's (cleaned) column names against the format;
    /// `sensors` are the effective constants (sidecar with overrides),
    /// `sidecar_name` where the sidecar was (for messages), `joints` the
    /// expected joint count (`None`: as many as the header's highest joint
    /// number).
    pub fn parse(
        names: &[String],
        file: &str,
        line: u64,
        sensors: &Sensors,
        sidecar_name: &str,
        columns: &ColumnNames,
        joints: Option<usize>,
    ) -> Result<Self, LogError> {
        let mut header = Header::new(names, columns, joints, file, line);
        if !header.has(Field::T) {
            return Err(header.missing(
                &columns.label(Field::T),
                "name the time column `t` (seconds), or map yours with columns t=NAME",
            ));
        }
        let place = Place {
            joints: header.n,
            file,
            sidecar: sidecar_name,
        };
        let mut notes = Vec::new();
        let angles = header.angles(&place, sensors, &mut notes)?;
        let torques = header.torques(&place, sensors, &mut notes)?;
        let (has_velocity, has_acceleration) = header.rates()?;
        let extra = header.extra();
        if !extra.is_empty() {
            notes.push(format!("extra columns ignored: {}", extra.join(", ")));
        }
        Ok(Self {
            joints: header.n,
            names: names.to_vec(),
            row_columns: header.row_columns(),
            column_of: header.column_of,
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
