//! The regressor + accumulation stage: task-space states → base regressor
//! rows → running QR factors, in fixed-size blocks, in parallel, without
//! allocation per sample.

use faer::{Mat, MatMut};
use rayon::prelude::*;

use super::accumulator::{BlockQr, QrAccumulator};
use super::gram::{Accumulation, GramSum};
use crate::base::BaseParameters;
use crate::error::IdentError;
use crate::model::LinearModel;

/// Samples per block: two 2048 × (b+1) column-major blocks (one per joint,
/// 400 kB each for b = 23) stay in the L2 cache while they are filled and
/// factorised.
pub const STAGE_BLOCK_SAMPLES: usize = 2048;

/// A run of consecutive samples with their torques, structure-of-arrays,
/// SI units: one slice per model coordinate for `q` (rad or m), `q̇`, `q̈`
/// and one per output for `τ` (N·m or N), all of equal length. For
/// ARAS-Diamond `q = X = [φ, γ]`; for a serial arm the joint angles.
#[derive(Debug, Clone, Copy)]
pub struct States<'a> {
    /// Positions, one slice per coordinate.
    pub x: &'a [&'a [f64]],
    /// Rates, one slice per coordinate.
    pub x_dot: &'a [&'a [f64]],
    /// Accelerations, one slice per coordinate.
    pub x_ddot: &'a [&'a [f64]],
    /// Torques, one slice per output.
    pub tau: &'a [&'a [f64]],
}

impl States<'_> {
    /// Number of samples (of `x[0]`; [`RegressorStage::push`] checks the rest).
    pub fn len(&self) -> usize {
        self.x.first().map_or(0, |x| x.len())
    }

    /// True if there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Checks the numbers of slices against the model's and their lengths
    /// against `x[0]`'s.
    fn check(&self, coordinates: usize, outputs: usize) -> Result<(), IdentError> {
        let n = self.len();
        for (what, slices, want) in [
            ("x", self.x, coordinates),
            ("x_dot", self.x_dot, coordinates),
            ("x_ddot", self.x_ddot, coordinates),
            ("tau", self.tau, outputs),
        ] {
            if slices.len() != want {
                return Err(IdentError::InvalidData {
                    context: "streaming stage: states".into(),
                    reason: format!(
                        "`{what}` has {} slices, the model has {want}: give one slice per {}",
                        slices.len(),
                        if what == "tau" {
                            "output"
                        } else {
                            "coordinate"
                        }
                    ),
                });
            }
            for (i, v) in slices.iter().enumerate() {
                if v.len() != n {
                    return Err(IdentError::InvalidData {
                        context: "streaming stage: states".into(),
                        reason: format!(
                            "{what}{} has {} samples, x1 has {n}: all state and torque slices \
                             must have one entry per sample",
                            i + 1,
                            v.len()
                        ),
                    });
                }
            }
        }
        Ok(())
    }
}

/// Independent accumulation lanes: block `i` of a push goes to lane
/// `i % LANES`. A constant (not the thread count) so results never depend
/// on the machine.
const LANES: usize = 4;

/// One lane's running sums per output.
enum Sums {
    /// Running factors; the block storage holds `[R_lane; new rows]`.
    Qr(Vec<BlockQr>, Vec<Mat<f64>>),
    /// Running Gram matrices; the block storage holds the new rows only,
    /// transposed (`c × samples`, a sample's row contiguous: filling it is
    /// a run of contiguous stores, not 24 strided ones).
    Gram(Vec<Mat<f64>>, Vec<GramSum>),
}

/// One lane's storage: the block per output and its running sums, the
/// per-sample buffers (regressor, state), rows kept per output.
struct Work {
    sums: Sums,
    y: Vec<f64>,
    q: Vec<f64>,
    rows: Vec<usize>,
    error: Option<IdentError>,
}

/// Turns states into the base regressor of a [`LinearModel`] (any number
/// of coordinates and outputs) and accumulates `[W_b | T]` into a
/// [`QrAccumulator`] (one row group per output), the per-sample work of
/// streaming identification.
///
/// Per sample: [`LinearModel::fill`] (into a reused buffer), the base
/// columns `W_b = W E`
/// (61) copied into the joint's block. Per block of
/// [`STAGE_BLOCK_SAMPLES`], per joint, depending on [`Accumulation`]:
/// * **Gram** (default): `G += AᵀA` (one triangular matrix product,
///   compensated summation); factorised once at the end
///   ([`RegressorStage::accumulator`]); accuracy checked by
///   [`QrAccumulator::gram_check`].
/// * **Qr**: faer's blocked QR of `[R_lane; A]`, so after the first block
///   the matrix has full rank and faer's fast QR never has to fall back.
///
/// Blocks run in parallel (rayon) in waves of one block per lane; lanes are
/// merged in a fixed order, so the result does not depend on the number of
/// threads (bit-identical).
///
/// Rows are the regressor *unfiltered*; streaming with the parallel filter
/// is done by `aras_pipeline::streaming::identify_log`, which filters blocks with overlap
/// before they get here.
pub struct RegressorStage<M> {
    model: M,
    columns: Vec<usize>,
    names: Vec<String>,
    works: Vec<Work>,
    samples: usize,
    accumulation: Accumulation,
}

impl<M: LinearModel> RegressorStage<M> {
    /// A stage for `model`, keeping the base columns of `base` (which must
    /// have been found on the same model's columns), with the default
    /// [`Accumulation::Gram`].
    pub fn new(model: M, base: &BaseParameters) -> Result<Self, IdentError> {
        Self::with_accumulation(model, base, Accumulation::default())
    }

    /// [`Self::new`] with a chosen accumulation.
    pub fn with_accumulation(
        model: M,
        base: &BaseParameters,
        accumulation: Accumulation,
    ) -> Result<Self, IdentError> {
        let (dims, outputs) = (model.coordinates(), model.outputs());
        if dims == 0 || outputs == 0 {
            return Err(IdentError::DimensionMismatch {
                what: "streaming stage: model coordinates × outputs",
                expected: 1,
                found: dims.min(outputs),
                hint: "a model has at least one coordinate and one output",
            });
        }
        if base.standard_names() != model.names().as_slice() {
            return Err(IdentError::DimensionMismatch {
                what: "base analysis columns vs model columns",
                expected: model.columns(),
                found: base.n_standard(),
                hint: "find the base parameters on this model's regressor (same effects, same order)",
            });
        }
        let c = base.n_base() + 1;
        let works = (0..LANES)
            .map(|_| Work {
                sums: match accumulation {
                    Accumulation::Qr => Sums::Qr(
                        (0..outputs)
                            .map(|_| BlockQr::new(STAGE_BLOCK_SAMPLES + c, c))
                            .collect(),
                        vec![Mat::zeros(c, c); outputs],
                    ),
                    Accumulation::Gram => Sums::Gram(
                        vec![Mat::zeros(c, STAGE_BLOCK_SAMPLES); outputs],
                        vec![GramSum::new(c); outputs],
                    ),
                },
                y: vec![0.0; outputs * model.columns()],
                q: vec![0.0; 3 * dims],
                rows: vec![0; outputs],
                error: None,
            })
            .collect();
        Ok(Self {
            model,
            columns: base.independent().to_vec(),
            names: base.base_names(),
            works,
            samples: 0,
            accumulation,
        })
    }

    /// The accumulation in use.
    pub fn accumulation(&self) -> Accumulation {
        self.accumulation
    }

    /// Everything pushed so far as an accumulator over this stage's base
    /// parameters, one row group per joint (the lanes merged in order).
    /// With [`Accumulation::Gram`], check
    /// [`QrAccumulator::gram_check`] before trusting an ill-conditioned
    /// problem.
    pub fn accumulator(&self) -> QrAccumulator {
        let mut acc = QrAccumulator::new(&self.names, self.model.outputs())
            .expect("a base analysis has at least one parameter");
        for w in &self.works {
            for j in 0..w.rows.len() {
                if w.rows[j] == 0 {
                    continue;
                }
                match &w.sums {
                    Sums::Qr(_, r) => acc.merge_factor(j, r[j].as_ref(), w.rows[j]),
                    Sums::Gram(_, g) => acc.merge_gram(j, &g[j], w.rows[j]),
                }
            }
        }
        acc
    }

    /// Base parameter names (the accumulator's unknowns).
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Samples pushed so far (sample indices in errors count from the first
    /// push).
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Rows accumulated per output (samples minus the rows left out by
    /// [`Self::push_selected`]).
    pub fn rows(&self) -> Vec<usize> {
        let mut r = vec![0; self.model.outputs()];
        for w in &self.works {
            for (r, w) in r.iter_mut().zip(&w.rows) {
                *r += w;
            }
        }
        r
    }

    /// Accumulates `states` (the next samples). Fails on the first sample
    /// (in order) whose kinematics fail (outside the workspace, singular)
    /// or whose torque is not finite; nothing of a failing call is
    /// accumulated.
    pub fn push(&mut self, states: &States<'_>) -> Result<(), IdentError> {
        self.push_selected(states, None)
    }

    /// [`Self::push`] keeping only output `j`'s rows where `keep[j]` is
    /// true (e.g. away from velocity reversals); `None` keeps every row.
    /// Every sample's kinematics are still evaluated and checked, as in
    /// memory.
    pub fn push_selected(
        &mut self,
        states: &States<'_>,
        keep: Option<&[&[bool]]>,
    ) -> Result<(), IdentError> {
        let outputs = self.model.outputs();
        states.check(self.model.coordinates(), outputs)?;
        let n = states.len();
        if let Some(k) = keep {
            let bad = k.len() != outputs || k.iter().any(|m| m.len() != n);
            if bad {
                return Err(IdentError::InvalidData {
                    context: "streaming stage: row masks".into(),
                    reason: format!(
                        "{} masks of lengths {:?} for {outputs} outputs of {n} samples: give \
                         one keep flag per sample and output",
                        k.len(),
                        k.iter().map(|m| m.len()).collect::<Vec<_>>()
                    ),
                });
            }
        }
        let starts: Vec<usize> = (0..n).step_by(STAGE_BLOCK_SAMPLES).collect();
        let saved: Vec<(Saved, Vec<usize>)> = self
            .works
            .iter()
            .map(|w| (w.sums.save(), w.rows.clone()))
            .collect();
        let (model, columns) = (&self.model, &self.columns[..]);
        let offset = self.samples;
        for wave in starts.chunks(LANES) {
            self.works[..wave.len()]
                .par_iter_mut()
                .zip(wave.par_iter())
                .for_each(|(w, &s)| {
                    let rows = STAGE_BLOCK_SAMPLES.min(n - s);
                    let block = Block {
                        st: states,
                        keep,
                        start: s,
                        rows,
                        offset,
                    };
                    w.error = run_block(w, model, columns, &block).err();
                });
            if let Some(e) = self.works.iter_mut().find_map(|w| w.error.take()) {
                for (w, (sums, rows)) in self.works.iter_mut().zip(saved) {
                    w.sums.restore(sums);
                    w.rows = rows;
                    w.error = None;
                }
                return Err(e);
            }
        }
        self.samples += n;
        Ok(())
    }
}

/// The running sums of a lane (to undo a failing push).
enum Saved {
    Qr(Vec<Mat<f64>>),
    Gram(Vec<GramSum>),
}

impl Sums {
    fn save(&self) -> Saved {
        match self {
            Sums::Qr(_, r) => Saved::Qr(r.clone()),
            Sums::Gram(_, g) => Saved::Gram(g.clone()),
        }
    }

    fn restore(&mut self, saved: Saved) {
        match (self, saved) {
            (Sums::Qr(_, r), Saved::Qr(s)) => *r = s,
            (Sums::Gram(_, g), Saved::Gram(s)) => *g = s,
            _ => unreachable!("a lane keeps its accumulation"),
        }
    }

    fn is_finite(&self) -> bool {
        let finite =
            |m: &Mat<f64>| (0..m.ncols()).all(|j| (0..m.nrows()).all(|i| m[(i, j)].is_finite()));
        match self {
            Sums::Qr(_, r) => r.iter().all(finite),
            Sums::Gram(_, g) => g.iter().all(|g| g.is_finite()),
        }
    }
}

/// A block of samples of one push: `rows` samples from `start` (`offset`:
/// samples pushed before, for messages), with the optional row masks.
struct Block<'s, 'a> {
    st: &'s States<'a>,
    keep: Option<&'s [&'s [bool]]>,
    start: usize,
    rows: usize,
    offset: usize,
}

impl Block<'_, '_> {
    fn kept(&self, j: usize, k: usize) -> bool {
        self.keep.is_none_or(|m| m[j][k])
    }
}

/// Writes the block's rows into `a[j]` from row `top` (masked rows as
/// zeros, which add nothing to `AᵀA`); returns the rows kept per output.
fn fill_block<M: LinearModel>(
    a: &mut [MatMut<'_, f64>],
    top: usize,
    w: &mut Buffers<'_>,
    model: &M,
    columns: &[usize],
    bl: &Block<'_, '_>,
) -> Result<Vec<usize>, IdentError> {
    let b = columns.len();
    let m = a.len();
    let mut kept = vec![0; m];
    for i in 0..bl.rows {
        let k = bl.start + i;
        fill_sample(model, bl.st, k, bl.offset, w)?;
        for (j, a) in a.iter_mut().enumerate() {
            if bl.kept(j, k) {
                for (jb, &col) in columns.iter().enumerate() {
                    a[(top + i, jb)] = w.y[m * col + j];
                }
                a[(top + i, b)] = bl.st.tau[j][k];
                kept[j] += 1;
            } else {
                for jb in 0..=b {
                    a[(top + i, jb)] = 0.0;
                }
            }
        }
    }
    Ok(kept)
}

/// A lane's per-sample buffers: the regressor (`outputs × columns`) and
/// the state `[q, q̇, q̈]`.
struct Buffers<'w> {
    y: &'w mut [f64],
    q: &'w mut [f64],
}

/// [`fill_block`] into transposed blocks (`c × samples`, column `i` = row
/// of sample `i`), through plain slices: the per-sample copy of the hot
/// path.
fn fill_block_transposed<M: LinearModel>(
    a: &mut [Mat<f64>],
    w: &mut Buffers<'_>,
    model: &M,
    columns: &[usize],
    bl: &Block<'_, '_>,
) -> Result<Vec<usize>, IdentError> {
    let b = columns.len();
    let m = a.len();
    let mut kept = vec![0; m];
    for i in 0..bl.rows {
        let k = bl.start + i;
        fill_sample(model, bl.st, k, bl.offset, w)?;
        for (j, a) in a.iter_mut().enumerate() {
            let col = a
                .as_mut()
                .col_mut(i)
                .try_as_col_major_mut()
                .expect("a Mat's columns are contiguous")
                .as_slice_mut();
            let (row, tau) = col.split_at_mut(b);
            if bl.kept(j, k) {
                for (dst, &c) in row.iter_mut().zip(columns) {
                    *dst = w.y[m * c + j];
                }
                tau[0] = bl.st.tau[j][k];
                kept[j] += 1;
            } else {
                row.fill(0.0);
                tau[0] = 0.0;
            }
        }
    }
    Ok(kept)
}

/// Fills and accumulates one block.
fn run_block<M: LinearModel>(
    w: &mut Work,
    model: &M,
    columns: &[usize],
    bl: &Block<'_, '_>,
) -> Result<(), IdentError> {
    let b = columns.len();
    let c = b + 1;
    let rows = bl.rows;
    let m = w.rows.len();
    let mut buffers = Buffers {
        y: &mut w.y,
        q: &mut w.q,
    };
    let kept = match &mut w.sums {
        Sums::Gram(blocks, grams) => {
            let kept = fill_block_transposed(blocks, &mut buffers, model, columns, bl)?;
            for (g, a) in grams.iter_mut().zip(blocks.iter()) {
                g.add_transposed(a.as_ref().subcols(0, rows));
            }
            kept
        }
        Sums::Qr(qr, r) => {
            let kept = {
                let mut a: Vec<MatMut<'_, f64>> = qr.iter_mut().map(|q| q.block_mut()).collect();
                for (a, r) in a.iter_mut().zip(r.iter()) {
                    a.as_mut().subrows_mut(0, c).copy_from(r);
                }
                fill_block(&mut a, c, &mut buffers, model, columns, bl)?
            };
            for j in 0..m {
                let lane = &r[j];
                let refill = |mut a: MatMut<'_, f64>| {
                    // Rare path (the lane's first blocks, or data that do
                    // not excite every base parameter yet): recompute the
                    // rows.
                    a.as_mut().subrows_mut(0, c).copy_from(lane);
                    let mut y = vec![0.0; m * model.columns()];
                    let mut q = vec![0.0; 3 * model.coordinates()];
                    let mut buffers = Buffers {
                        y: &mut y,
                        q: &mut q,
                    };
                    for i in 0..rows {
                        let k = bl.start + i;
                        let ok = bl.kept(j, k)
                            && fill_sample(model, bl.st, k, bl.offset, &mut buffers).is_ok();
                        for (jb, &col) in columns.iter().enumerate() {
                            a[(c + i, jb)] = if ok { buffers.y[m * col + j] } else { 0.0 };
                        }
                        a[(c + i, b)] = if ok { bl.st.tau[j][k] } else { 0.0 };
                    }
                };
                let f = qr[j].factor_filled(c + rows, refill).to_owned();
                r[j].copy_from(&f);
            }
            kept
        }
    };
    for (r, k) in w.rows.iter_mut().zip(kept) {
        *r += k;
    }
    if !w.sums.is_finite() {
        return Err(IdentError::InvalidData {
            context: format!(
                "streaming regressor, block of samples {}..{}",
                bl.offset + bl.start,
                bl.offset + bl.start + rows
            ),
            reason: "the regressor or a torque overflowed to a non-finite value; \
                      check the states for extreme rates or accelerations"
                .into(),
        });
    }
    Ok(())
}

/// The model's regressor of sample `k` into `w.y` (`outputs × columns`,
/// column-major), through the state buffer `w.q`.
#[inline]
fn fill_sample<M: LinearModel>(
    model: &M,
    st: &States<'_>,
    k: usize,
    offset: usize,
    w: &mut Buffers<'_>,
) -> Result<(), IdentError> {
    for (j, tau) in st.tau.iter().enumerate() {
        if !tau[k].is_finite() {
            return Err(IdentError::InvalidData {
                context: format!("streaming regressor, sample {}", offset + k),
                reason: format!(
                    "torque tau{} = {} is not finite; repair or drop the sample",
                    j + 1,
                    tau[k]
                ),
            });
        }
    }
    let n = st.x.len();
    let (q, rest) = w.q.split_at_mut(n);
    let (q_dot, q_ddot) = rest.split_at_mut(n);
    for i in 0..n {
        q[i] = st.x[i][k];
        q_dot[i] = st.x_dot[i][k];
        q_ddot[i] = st.x_ddot[i][k];
    }
    model
        .fill(q, q_dot, q_ddot, w.y)
        .map_err(|e| IdentError::external(format!("streaming regressor, sample {}", offset + k), e))
}
