//! The regressor + accumulation stage: task-space states → base regressor
//! rows → running QR factors, in fixed-size blocks, in parallel, without
//! allocation per sample.

use aras_dyn::Model;
use aras_kin::Geometry;
use faer::{Mat, MatMut};
use nalgebra::Vector2;
use rayon::prelude::*;

use super::accumulator::{BlockQr, QrAccumulator};
use crate::base::BaseParameters;
use crate::error::IdentError;

/// Samples per block: two 2048 × (b+1) column-major blocks (one per joint,
/// 400 kB each for b = 23) stay in the L2 cache while they are filled and
/// factorised.
pub const STAGE_BLOCK_SAMPLES: usize = 2048;

/// A run of consecutive samples in task space with their torques,
/// structure-of-arrays (all slices of equal length), SI units: `X = [φ, γ]`
/// (rad), `Ẋ` (rad/s), `Ẍ` (rad/s²), `τ` (N·m).
#[derive(Debug, Clone, Copy)]
pub struct States<'a> {
    /// `φ`, `γ`.
    pub x: [&'a [f64]; 2],
    /// `φ̇`, `γ̇`.
    pub x_dot: [&'a [f64]; 2],
    /// `φ̈`, `γ̈`.
    pub x_ddot: [&'a [f64]; 2],
    /// `τ1`, `τ2`.
    pub tau: [&'a [f64]; 2],
}

impl States<'_> {
    /// Number of samples (of `x[0]`; [`RegressorStage::push`] checks the rest).
    pub fn len(&self) -> usize {
        self.x[0].len()
    }

    /// True if there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn check(&self) -> Result<(), IdentError> {
        let n = self.len();
        for (what, v) in [
            ("states: gamma", self.x[1]),
            ("states: phi_dot", self.x_dot[0]),
            ("states: gamma_dot", self.x_dot[1]),
            ("states: phi_ddot", self.x_ddot[0]),
            ("states: gamma_ddot", self.x_ddot[1]),
            ("states: tau1", self.tau[0]),
            ("states: tau2", self.tau[1]),
        ] {
            if v.len() != n {
                return Err(IdentError::DimensionMismatch {
                    what,
                    expected: n,
                    found: v.len(),
                    hint: "all state and torque slices must have one entry per sample",
                });
            }
        }
        Ok(())
    }
}

/// Independent accumulation lanes: block `i` of a push goes to lane
/// `i % LANES`. A constant (not the thread count) so results never depend
/// on the machine.
const LANES: usize = 4;

/// One lane's storage: a block per joint (its running factor in the top
/// `b+1` rows, the new samples below), the per-sample regressor buffer,
/// the lane's running factors and row count.
struct Work {
    qr: [BlockQr; 2],
    y: Vec<f64>,
    r: [Mat<f64>; 2],
    rows: usize,
    error: Option<IdentError>,
}

/// Turns task-space states into the base regressor of a [`Model`] and
/// accumulates `[W_b | T]` into a [`QrAccumulator`] (two row groups: joint 1,
/// joint 2), the per-sample work of streaming identification.
///
/// Each lane keeps its own running factor and factorises
/// `[R_lane; new rows]` in one blocked QR, so after the first block the
/// matrix has full rank and faer's fast QR never has to fall back.
///
/// Per sample: `aras_kin::evaluate` (kinematics (1)–(25)), `Model::fill`
/// (regressor (45)–(53), into a reused buffer), the base columns `W_b = W E`
/// (61) copied into the joint's block. Per block of
/// [`STAGE_BLOCK_SAMPLES`]: faer's blocked QR of each joint's block. Blocks
/// run in parallel (rayon) in waves of one block per lane; lanes are merged
/// in a fixed order by [`RegressorStage::accumulator`], so the result does
/// not depend on the number of threads (bit-identical).
///
/// Rows are the regressor *unfiltered*; streaming with the parallel filter
/// is done by [`super::identify_log`], which filters blocks with overlap
/// before they get here.
pub struct RegressorStage {
    model: Model,
    geometry: Geometry,
    columns: Vec<usize>,
    names: Vec<String>,
    works: Vec<Work>,
    samples: usize,
}

impl RegressorStage {
    /// A stage for `model` on `geometry`, keeping the base columns of `base`
    /// (which must have been found on the same model's columns).
    pub fn new(
        model: &Model,
        geometry: &Geometry,
        base: &BaseParameters,
    ) -> Result<Self, IdentError> {
        if base.standard_names() != model.names().as_slice() {
            return Err(IdentError::DimensionMismatch {
                what: "base analysis columns vs model columns",
                expected: model.columns(),
                found: base.n_standard(),
                hint: "find the base parameters on this model's regressor (same effects, same order)",
            });
        }
        let b = base.n_base();
        let works = (0..LANES)
            .map(|_| Work {
                qr: [
                    BlockQr::new(STAGE_BLOCK_SAMPLES + b + 1, b + 1),
                    BlockQr::new(STAGE_BLOCK_SAMPLES + b + 1, b + 1),
                ],
                y: vec![0.0; 2 * model.columns()],
                r: [Mat::zeros(b + 1, b + 1), Mat::zeros(b + 1, b + 1)],
                rows: 0,
                error: None,
            })
            .collect();
        Ok(Self {
            model: model.clone(),
            geometry: *geometry,
            columns: base.independent().to_vec(),
            names: base.base_names(),
            works,
            samples: 0,
        })
    }

    /// Everything pushed so far as an accumulator over this stage's base
    /// parameters, one row group per joint (the lanes merged in order).
    pub fn accumulator(&self) -> QrAccumulator {
        let mut acc =
            QrAccumulator::new(&self.names, 2).expect("a base analysis has at least one parameter");
        for w in &self.works {
            if w.rows > 0 {
                acc.merge_factor(0, w.r[0].as_ref(), w.rows);
                acc.merge_factor(1, w.r[1].as_ref(), w.rows);
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

    /// Accumulates `states` (the next samples). Fails on the first sample
    /// (in order) whose kinematics fail (outside the workspace, singular)
    /// or whose torque is not finite; nothing of a failing call is
    /// accumulated.
    pub fn push(&mut self, states: &States<'_>) -> Result<(), IdentError> {
        states.check()?;
        let n = states.len();
        let starts: Vec<usize> = (0..n).step_by(STAGE_BLOCK_SAMPLES).collect();
        let saved: Vec<([Mat<f64>; 2], usize)> =
            self.works.iter().map(|w| (w.r.clone(), w.rows)).collect();
        let (model, geometry, columns) = (&self.model, &self.geometry, &self.columns[..]);
        let offset = self.samples;
        for wave in starts.chunks(LANES) {
            self.works[..wave.len()]
                .par_iter_mut()
                .zip(wave.par_iter())
                .for_each(|(w, &s)| {
                    let rows = STAGE_BLOCK_SAMPLES.min(n - s);
                    w.error = run_block(w, model, geometry, columns, states, s, rows, offset).err();
                });
            if let Some(e) = self.works.iter_mut().find_map(|w| w.error.take()) {
                for (w, (r, rows)) in self.works.iter_mut().zip(saved) {
                    w.r = r;
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

/// Fills and factorises one block of `rows` samples starting at `start`
/// (`offset`: samples pushed before, for messages).
#[allow(clippy::too_many_arguments)]
fn run_block(
    w: &mut Work,
    model: &Model,
    geometry: &Geometry,
    columns: &[usize],
    st: &States<'_>,
    start: usize,
    rows: usize,
    offset: usize,
) -> Result<(), IdentError> {
    let b = columns.len();
    let c = b + 1;
    {
        let (q0, q1) = w.qr.split_at_mut(1);
        let mut a0 = q0[0].block_mut();
        let mut a1 = q1[0].block_mut();
        a0.as_mut().subrows_mut(0, c).copy_from(&w.r[0]);
        a1.as_mut().subrows_mut(0, c).copy_from(&w.r[1]);
        for i in 0..rows {
            let k = start + i;
            fill_sample(model, geometry, st, k, offset, &mut w.y)?;
            for (jb, &col) in columns.iter().enumerate() {
                a0[(c + i, jb)] = w.y[2 * col];
                a1[(c + i, jb)] = w.y[2 * col + 1];
            }
            a0[(c + i, b)] = st.tau[0][k];
            a1[(c + i, b)] = st.tau[1][k];
        }
    }
    for j in 0..2 {
        let lane = &w.r[j];
        let refill = |mut a: MatMut<'_, f64>| {
            // Rare path (the lane's first blocks, or data that do not
            // excite every base parameter yet): recompute the rows.
            a.as_mut().subrows_mut(0, c).copy_from(lane);
            let mut y = vec![0.0; 2 * model.columns()];
            for i in 0..rows {
                let k = start + i;
                if fill_sample(model, geometry, st, k, offset, &mut y).is_ok() {
                    for (jb, &col) in columns.iter().enumerate() {
                        a[(c + i, jb)] = y[2 * col + j];
                    }
                }
                a[(c + i, b)] = st.tau[j][k];
            }
        };
        let r = w.qr[j].factor_filled(c + rows, refill).to_owned();
        w.r[j].copy_from(&r);
    }
    w.rows += rows;
    for j in 0..2 {
        let r = &w.r[j];
        for c in 0..=b {
            for i in 0..=c {
                if !r[(i, c)].is_finite() {
                    return Err(IdentError::Adapter {
                        context: format!(
                            "streaming regressor, block of samples {}..{}",
                            offset + start,
                            offset + start + rows
                        ),
                        message: format!(
                            "the regressor or torque of joint {} overflowed to a non-finite value; \
                             check the states for extreme rates or accelerations",
                            j + 1
                        ),
                    });
                }
            }
        }
    }
    Ok(())
}

/// Kinematics and regressor of sample `k` into `y` (2 × n, column-major).
#[inline]
fn fill_sample(
    model: &Model,
    geometry: &Geometry,
    st: &States<'_>,
    k: usize,
    offset: usize,
    y: &mut [f64],
) -> Result<(), IdentError> {
    for (j, tau) in st.tau.iter().enumerate() {
        if !tau[k].is_finite() {
            return Err(IdentError::Adapter {
                context: format!("streaming regressor, sample {}", offset + k),
                message: format!(
                    "torque tau{} = {} is not finite; repair or drop the sample",
                    j + 1,
                    tau[k]
                ),
            });
        }
    }
    let s = aras_kin::evaluate(
        geometry,
        &Vector2::new(st.x[0][k], st.x[1][k]),
        &Vector2::new(st.x_dot[0][k], st.x_dot[1][k]),
        &Vector2::new(st.x_ddot[0][k], st.x_ddot[1][k]),
    )
    .map_err(|e| IdentError::Adapter {
        context: format!("streaming regressor, kinematics of sample {}", offset + k),
        message: e.to_string(),
    })?;
    model.fill(&s, y).map_err(|e| IdentError::Adapter {
        context: format!("streaming regressor, sample {}", offset + k),
        message: e.to_string(),
    })
}
