//! Which rows of a stacked regressor belong to which joint.

use crate::error::IdentError;

/// A label (joint index `0..n_groups`) for every row of a stacked
/// regressor, for per-joint weighting (WLS) and per-joint fitness (78), and
/// the time sample of every row.
///
/// The sample index tells which rows of different joints were measured at
/// the same instant: their residuals share the sensor noise, the
/// closed-loop error and the quantised angles, so the HAC covariance
/// ([`crate::hac_covariance`]) counts their correlation. By default a row's
/// sample is its position within its group, which is exact for joint-major
/// ([`RowGroups::contiguous`] with equal lengths) and sample-major
/// ([`RowGroups::interleaved`]) stacking of complete records; after rows
/// are dropped (a reversal mask), give the kept rows' samples with
/// [`RowGroups::with_samples`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RowGroups {
    labels: Vec<usize>,
    counts: Vec<usize>,
    samples: Vec<usize>,
    sample_count: usize,
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
        let mut next = vec![0; n];
        let samples: Vec<usize> = labels
            .iter()
            .map(|&l| {
                next[l] += 1;
                next[l] - 1
            })
            .collect();
        let sample_count = counts.iter().copied().max().unwrap_or(0);
        Ok(Self {
            labels,
            counts,
            samples,
            sample_count,
        })
    }

    /// The same groups with the time sample of every row given:
    /// `samples[row] < sample_count`, where `sample_count` is the length of
    /// the record the rows were taken from (for periodic data, the samples
    /// of one period, so that lags wrap around it). Within a group, samples
    /// must increase with the row (rows in time order).
    pub fn with_samples(
        mut self,
        samples: Vec<usize>,
        sample_count: usize,
    ) -> Result<Self, IdentError> {
        self.check_rows(samples.len())
            .map_err(|_| IdentError::DimensionMismatch {
                what: "row samples",
                expected: self.n_rows(),
                found: samples.len(),
                hint: "give the time sample of every row of the stacked regressor",
            })?;
        let mut last: Vec<Option<usize>> = vec![None; self.n_groups()];
        for (row, (&g, &s)) in self.labels.iter().zip(&samples).enumerate() {
            if s >= sample_count {
                return Err(IdentError::InvalidSetting {
                    name: "row samples",
                    value: s as f64,
                    reason: "a row's sample is not below the record's sample count",
                });
            }
            if last[g].is_some_and(|p| p >= s) {
                return Err(IdentError::InvalidSetting {
                    name: "row samples",
                    value: row as f64,
                    reason: "within a group the samples must increase with the row (this row's does not)",
                });
            }
            last[g] = Some(s);
        }
        self.samples = samples;
        self.sample_count = sample_count;
        Ok(self)
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

    /// The time sample of every row (see the type's docs).
    pub fn samples(&self) -> &[usize] {
        &self.samples
    }

    /// Length of the record the rows' samples index.
    pub fn sample_count(&self) -> usize {
        self.sample_count
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
