//! Which rows of a stacked regressor belong to which joint.

use crate::error::IdentError;

/// A label (joint index `0..n_groups`) for every row of a stacked
/// regressor, for per-joint weighting (WLS) and per-joint fitness (78).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RowGroups {
    labels: Vec<usize>,
    counts: Vec<usize>,
}

impl RowGroups {
    /// Joint-major stacking: the first `lengths[0]` rows are joint 0, the
    /// next `lengths[1]` joint 1, and so on (rows `0..n` joint 1, `n..2n`
    /// joint 2 for a 2-DOF robot with `n` samples).
    pub fn contiguous(lengths: &[usize]) -> Result<Self, IdentError> {
        let labels = lengths
            .iter()
            .enumerate()
            .flat_map(|(g, &n)| std::iter::repeat_n(g, n))
            .collect();
        Self::from_labels(labels)
    }

    /// Sample-major stacking: row `i` belongs to joint `i % joints`.
    pub fn interleaved(rows: usize, joints: usize) -> Result<Self, IdentError> {
        if joints == 0 {
            return Err(IdentError::InvalidSetting {
                name: "joints",
                value: 0.0,
                reason: "at least one joint is needed",
            });
        }
        Self::from_labels((0..rows).map(|i| i % joints).collect())
    }

    /// Any assignment: `labels[row]` is the joint of `row`. Every joint
    /// `0..=max(labels)` must have at least one row.
    pub fn from_labels(labels: Vec<usize>) -> Result<Self, IdentError> {
        let n = labels.iter().copied().max().map_or(0, |m| m + 1);
        let mut counts = vec![0; n];
        for &l in &labels {
            counts[l] += 1;
        }
        if let Some(g) = counts.iter().position(|&c| c == 0) {
            return Err(IdentError::InvalidSetting {
                name: "row groups",
                value: g as f64,
                reason: "this group index has no rows; number the groups 0, 1, … without gaps",
            });
        }
        if labels.is_empty() {
            return Err(IdentError::InvalidSetting {
                name: "row groups",
                value: 0.0,
                reason: "no rows were given",
            });
        }
        Ok(Self { labels, counts })
    }

    /// Number of groups (joints).
    pub fn n_groups(&self) -> usize {
        self.counts.len()
    }

    /// Number of rows labelled.
    pub fn n_rows(&self) -> usize {
        self.labels.len()
    }

    /// Rows in each group.
    pub fn counts(&self) -> &[usize] {
        &self.counts
    }

    /// The group of every row.
    pub fn labels(&self) -> &[usize] {
        &self.labels
    }

    pub(crate) fn check_rows(&self, rows: usize) -> Result<(), IdentError> {
        if rows != self.n_rows() {
            return Err(IdentError::DimensionMismatch {
                what: "row-group labels",
                expected: rows,
                found: self.n_rows(),
                hint: "label every row of the stacked regressor exactly once",
            });
        }
        Ok(())
    }
}
