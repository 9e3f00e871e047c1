//! The one-pass sums: per output group the Gram matrix of
//! `[base columns | every candidate's columns | target]` and the column
//! sums, accumulated chunk by chunk in memory independent of the number of
//! rows.

use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

use crate::error::IdentError;
use crate::streaming::gram::GramSum;

/// One candidate: a named block of regressor columns that may be appended
/// to the model, or an alternative target.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CandidateSpec {
    /// Label, unique within a [`Layout`] (e.g. `stribeck(v_s = 0.05)`).
    pub name: String,
    /// Family: candidates of one family are alternative settings of one
    /// hypothesis (a grid scan); at most one member of a family is added.
    pub family: String,
    /// Number of regressor columns the candidate contributes to a row.
    pub columns: usize,
    /// If true the candidate is an alternative target (exactly one column,
    /// e.g. the target shifted in time): adding it replaces the target
    /// instead of appending columns, and counts as one added parameter.
    pub replaces_target: bool,
    /// The output groups (e.g. joints) the candidate acts on, whose
    /// validation gains judge it (default `None`: every group). A candidate
    /// on one joint of seven moves that joint's fitness only; averaged over
    /// all seven its gain would be a seventh of what it does.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groups: Option<Vec<usize>>,
}

impl CandidateSpec {
    /// A block of `columns` regressor columns, its own family.
    pub fn columns(name: impl Into<String>, columns: usize) -> Self {
        let name = name.into();
        Self {
            family: name.clone(),
            name,
            columns,
            replaces_target: false,
            groups: None,
        }
    }

    /// An alternative target (one column in the row), its own family.
    pub fn target(name: impl Into<String>) -> Self {
        let name = name.into();
        Self {
            family: name.clone(),
            name,
            columns: 1,
            replaces_target: true,
            groups: None,
        }
    }

    /// The same candidate as a member of `family`.
    pub fn in_family(mut self, family: impl Into<String>) -> Self {
        self.family = family.into();
        self
    }

    /// The same candidate judged on the output `groups` it acts on
    /// ([`Self::groups`]).
    pub fn on_groups(mut self, groups: Vec<usize>) -> Self {
        self.groups = Some(groups);
        self
    }
}

/// Where each value sits in a pushed row:
/// `[base (base_columns) | candidate 0 | candidate 1 | … | target]`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Layout {
    base_columns: usize,
    candidates: Vec<CandidateSpec>,
    offsets: Vec<usize>,
    groups: usize,
}

impl Layout {
    /// A layout with `base_columns` columns always in the model, the
    /// `candidates` in the order their columns appear in a row, and
    /// `groups` output groups (e.g. joints).
    pub fn new(
        base_columns: usize,
        candidates: Vec<CandidateSpec>,
        groups: usize,
    ) -> Result<Self, IdentError> {
        if groups == 0 {
            return Err(IdentError::InvalidSetting {
                name: "selection output groups",
                value: 0.0,
                reason: "give at least one output group (e.g. one per joint)",
            });
        }
        let mut offsets = Vec::with_capacity(candidates.len());
        let mut at = base_columns;
        for (i, c) in candidates.iter().enumerate() {
            if c.columns == 0 || (c.replaces_target && c.columns != 1) {
                return Err(IdentError::InvalidSetting {
                    name: "candidate columns",
                    value: c.columns as f64,
                    reason: "a column candidate needs at least one column and an alternative \
                             target exactly one",
                });
            }
            if candidates[..i].iter().any(|d| d.name == c.name) {
                return Err(IdentError::InvalidSelection {
                    reason: format!(
                        "candidate name `{}` appears twice; give every candidate a unique name",
                        c.name
                    ),
                });
            }
            offsets.push(at);
            at += c.columns;
        }
        Ok(Self {
            base_columns,
            candidates,
            offsets,
            groups,
        })
    }

    /// Columns always in the model.
    pub fn base_columns(&self) -> usize {
        self.base_columns
    }

    /// The candidates.
    pub fn candidates(&self) -> &[CandidateSpec] {
        &self.candidates
    }

    /// Output groups.
    pub fn groups(&self) -> usize {
        self.groups
    }

    /// Values per row, target included.
    pub fn width(&self) -> usize {
        self.target_column() + 1
    }

    /// Index of the target in a row.
    pub fn target_column(&self) -> usize {
        self.base_columns + self.candidates.iter().map(|c| c.columns).sum::<usize>()
    }

    /// Row indices of candidate `k`'s columns.
    pub fn candidate_columns(&self, k: usize) -> std::ops::Range<usize> {
        let o = self.offsets[k];
        o..o + self.candidates[k].columns
    }
}

/// Running sums of one data set (training or one validation set).
#[derive(Debug, Clone)]
pub struct Accumulator {
    layout: Layout,
    grams: Vec<GramSum>,
    sums: Vec<Vec<f64>>,
    rows: Vec<usize>,
}

impl Accumulator {
    /// Empty sums for `layout`.
    pub fn new(layout: &Layout) -> Self {
        let w = layout.width();
        Self {
            layout: layout.clone(),
            grams: (0..layout.groups).map(|_| GramSum::new(w)).collect(),
            sums: vec![vec![0.0; w]; layout.groups],
            rows: vec![0; layout.groups],
        }
    }

    /// The layout.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Rows pushed per group.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// Adds a chunk of rows of `group` (`rows × width`, any strides; row
    /// layout as [`Layout`]). Non-finite values are refused with their
    /// position (row within the chunk, column) so they can be repaired.
    pub fn push(&mut self, group: usize, chunk: MatRef<'_, f64>) -> Result<(), IdentError> {
        let w = self.layout.width();
        if chunk.ncols() != w {
            return Err(IdentError::DimensionMismatch {
                what: "selection chunk columns",
                expected: w,
                found: chunk.ncols(),
                hint: "a row is [base columns | every candidate's columns | target]",
            });
        }
        self.add_chunk(group, chunk, None)
    }

    /// [`Self::push`] for a chunk whose columns other than `cols` are zero
    /// (e.g. a per-joint effect's columns in another joint's rows): `chunk`
    /// holds columns `cols` (strictly increasing, within the layout), so
    /// the Gram costs `cols.len()²` per row instead of `width²`.
    pub fn push_columns(
        &mut self,
        group: usize,
        chunk: MatRef<'_, f64>,
        cols: &[usize],
    ) -> Result<(), IdentError> {
        let w = self.layout.width();
        if chunk.ncols() != cols.len()
            || cols.windows(2).any(|p| p[0] >= p[1])
            || cols.last().is_some_and(|&c| c >= w)
        {
            return Err(IdentError::InvalidSelection {
                reason: format!(
                    "a chunk of {} columns given as columns {cols:?} of a layout of width {w}: \
                     name each chunk column once, increasing, inside the layout",
                    chunk.ncols()
                ),
            });
        }
        self.add_chunk(group, chunk, Some(cols))
    }

    /// Adds `chunk`'s rows to `group`: its column `q` is the layout's
    /// `cols[q]` (all columns in order if `None`), the others zero.
    fn add_chunk(
        &mut self,
        group: usize,
        chunk: MatRef<'_, f64>,
        cols: Option<&[usize]>,
    ) -> Result<(), IdentError> {
        if group >= self.layout.groups {
            return Err(IdentError::InvalidSelection {
                reason: format!(
                    "output group {group} does not exist (the layout has {} groups, 0-based)",
                    self.layout.groups
                ),
            });
        }
        for q in 0..chunk.ncols() {
            let j = cols.map_or(q, |c| c[q]);
            let mut s = 0.0;
            for i in 0..chunk.nrows() {
                let v = chunk[(i, q)];
                if !v.is_finite() {
                    return Err(IdentError::NonFinite {
                        what: "selection chunk",
                        row: i,
                        column: j,
                        name: self.column_name(j),
                        value: v,
                    });
                }
                s += v;
            }
            self.sums[group][j] += s;
        }
        if chunk.nrows() > 0 {
            match cols {
                None => self.grams[group].add(chunk),
                Some(c) => self.grams[group].add_columns(chunk, c),
            }
        }
        self.rows[group] += chunk.nrows();
        Ok(())
    }

    /// Adds rows of `group` given row-major (`values.len()` a multiple of
    /// the layout's width).
    pub fn push_rows(&mut self, group: usize, values: &[f64]) -> Result<(), IdentError> {
        let w = self.layout.width();
        if !values.len().is_multiple_of(w) {
            return Err(IdentError::DimensionMismatch {
                what: "selection row-major values",
                expected: w * (values.len() / w + 1),
                found: values.len(),
                hint: "give whole rows: [base columns | every candidate's columns | target]",
            });
        }
        let m = MatRef::from_row_major_slice(values, values.len() / w, w);
        self.push(group, m)
    }

    /// Adds another accumulator's sums (same layout), e.g. another thread's
    /// share of the rows.
    pub fn merge(&mut self, other: &Accumulator) -> Result<(), IdentError> {
        if other.layout != self.layout {
            return Err(IdentError::InvalidSelection {
                reason: "merging selection sums of different layouts; build both from one Layout"
                    .into(),
            });
        }
        for g in 0..self.layout.groups {
            self.grams[g].absorb(&other.grams[g]);
            for (a, b) in self.sums[g].iter_mut().zip(&other.sums[g]) {
                *a += b;
            }
            self.rows[g] += other.rows[g];
        }
        Ok(())
    }

    fn column_name(&self, j: usize) -> String {
        if j < self.layout.base_columns {
            return format!("base column {j}");
        }
        if j == self.layout.target_column() {
            return "target".into();
        }
        (0..self.layout.candidates.len())
            .find(|&k| self.layout.candidate_columns(k).contains(&j))
            .map(|k| format!("candidate `{}`", self.layout.candidates[k].name))
            .unwrap_or_default()
    }

    /// The per-group Grams and column sums, as plain matrices.
    /// The sums of rows whose values are linear combinations of this
    /// accumulator's: column `j` of `layout` is `Σ w · (column i)` over the
    /// pairs `(i, w)` of `combination[j]`. The Gram becomes `Mᵀ G M`, the
    /// column sums `Mᵀ s`, so no pass over the data is needed; e.g. a
    /// candidate at a setting between trial settings, its columns
    /// interpolated from theirs.
    pub fn combined(
        &self,
        layout: &Layout,
        combination: &[Vec<(usize, f64)>],
    ) -> Result<Accumulator, IdentError> {
        let (w, w2) = (self.layout.width(), layout.width());
        if combination.len() != w2 || layout.groups != self.layout.groups {
            return Err(IdentError::DimensionMismatch {
                what: "columns of a combined selection layout",
                expected: w2,
                found: combination.len(),
                hint: "give one combination per column of the new layout, for as many groups",
            });
        }
        if let Some(&(i, _)) = combination.iter().flatten().find(|(i, _)| *i >= w) {
            return Err(IdentError::InvalidSelection {
                reason: format!("column {i} does not exist (the sums have {w} columns)"),
            });
        }
        let m = Mat::<f64>::from_fn(w, w2, |i, j| {
            combination[j]
                .iter()
                .filter(|(c, _)| *c == i)
                .map(|(_, x)| x)
                .sum()
        });
        let grams = self
            .grams
            .iter()
            .map(|g| GramSum::from_value((m.transpose() * g.value() * &m).as_ref()))
            .collect();
        let sums = self
            .sums
            .iter()
            .map(|s| {
                (0..w2)
                    .map(|j| combination[j].iter().map(|&(i, x)| x * s[i]).sum())
                    .collect()
            })
            .collect();
        Ok(Accumulator {
            layout: layout.clone(),
            grams,
            sums,
            rows: self.rows.clone(),
        })
    }

    pub(crate) fn snapshot(&self) -> Sums {
        Sums {
            grams: self.grams.iter().map(|g| g.value()).collect(),
            sums: self.sums.clone(),
            rows: self.rows.clone(),
        }
    }
}

/// Plain per-group sums of one data set.
pub(crate) struct Sums {
    pub grams: Vec<Mat<f64>>,
    pub sums: Vec<Vec<f64>>,
    pub rows: Vec<usize>,
}
