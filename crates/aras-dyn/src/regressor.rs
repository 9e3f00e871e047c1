//! The regressor `Y(X, Ẋ, Ẍ)` with `τ = Y β`, (38)–(57): per sample
//! into a caller's buffer (no allocation, generic over the scalar so dual
//! numbers give exact derivatives), and stacked over many samples.
//!
//! Per-sample layout: a 2×n matrix stored column-major in a slice of length
//! `2n` (entry (joint `i`, column `j`) at `2j + i`), which is the storage of
//! a nalgebra `Matrix2xX`.
//!
//! Stacked layout: **joint-major**, `2N × n`, column-major: rows `0..N` are
//! joint 1 of every sample, rows `N..2N` joint 2, so each joint's block of a
//! column is one contiguous slice.

use aras_kin::{Geometry, KinematicSample, Motion, Scalar};
use nalgebra::{DMatrix, Matrix2xX, Vector2, Vector3};
use rayon::prelude::*;

use crate::{DynError, Effect, Model};

/// How `sign(θ̇)` is evaluated in friction-like columns.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Sign {
    /// The exact sign (`0` at rest), as in (49); its derivative is zero.
    #[default]
    Exact,
    /// `tanh(θ̇ / w)` with width `w` (rad/s, > 0): the simulator's smooth,
    /// chatter-free friction.
    Tanh(f64),
}

impl Sign {
    #[inline(always)]
    pub(crate) fn eval<T: Scalar>(self, v: T) -> T {
        match self {
            Sign::Exact => {
                let r = v.value();
                if r > 0.0 {
                    T::one()
                } else if r < 0.0 {
                    -T::one()
                } else {
                    T::zero()
                }
            }
            Sign::Tanh(w) => (v / T::lift(w)).tanh(),
        }
    }
}

impl Model {
    /// Fills the 2×n regressor of one sample into `out` (column-major,
    /// length `2 * columns()`), without allocating; exact `sign`.
    ///
    /// Generic over [`Scalar`] so the excitation design can differentiate
    /// it with dual numbers; non-smooth columns have zero derivative.
    pub fn fill<T: Scalar>(&self, s: &KinematicSample<T>, out: &mut [T]) -> Result<(), DynError> {
        self.fill_with(s, Sign::Exact, out)
    }

    /// [`Model::fill`] with a chosen [`Sign`] evaluation.
    ///
    /// # Errors
    /// [`DynError::StatefulEffect`] for a model with an effect that has a
    /// state ([`crate::Effect::is_stateful`]); [`DynError::Length`] for a
    /// buffer of the wrong length.
    pub fn fill_with<T: Scalar>(
        &self,
        s: &KinematicSample<T>,
        sign: Sign,
        out: &mut [T],
    ) -> Result<(), DynError> {
        self.check_per_sample()?;
        if out.len() != 2 * self.columns() {
            return Err(DynError::Length {
                what: "regressor buffer (2 × columns)",
                expected: 2 * self.columns(),
                found: out.len(),
            });
        }
        self.fill_unchecked(s, sign, out);
        Ok(())
    }

    #[inline]
    pub(crate) fn fill_unchecked<T: Scalar>(
        &self,
        s: &KinematicSample<T>,
        sign: Sign,
        out: &mut [T],
    ) {
        let gf = self.gravity();
        let g = Vector3::new(T::lift(gf.x), T::lift(gf.y), T::lift(gf.z));
        for (e, o) in self.layout() {
            e.fill(s, &g, sign, &mut out[2 * o..2 * (o + e.columns())]);
        }
    }

    /// The 2×n regressor of one sample (allocates the result). The columns
    /// of an effect with a state ([`crate::Effect::is_stateful`]) are zero
    /// here: one sample has no history; [`Model::stacked`] computes them.
    pub fn regressor(&self, s: &KinematicSample) -> Matrix2xX<f64> {
        let mut m = Matrix2xX::zeros(self.columns());
        self.fill_unchecked(s, Sign::Exact, m.as_mut_slice());
        m
    }

    /// `τ = Y β` for one sample.
    ///
    /// # Errors
    /// [`DynError::StatefulEffect`] for a model with an effect that has a
    /// state, [`DynError::Length`] for a `beta` of the wrong length.
    pub fn torque(&self, s: &KinematicSample, beta: &[f64]) -> Result<Vector2<f64>, DynError> {
        self.check_per_sample()?;
        if beta.len() != self.columns() {
            return Err(DynError::Length {
                what: "parameter vector",
                expected: self.columns(),
                found: beta.len(),
            });
        }
        Ok(self.regressor(s) * nalgebra::DVectorView::from_slice(beta, beta.len()))
    }

    /// Stacked joint-major regressor (`2N × n`) of many samples, in parallel
    /// (rayon) over blocks of samples. Allocates the result; see
    /// [`Model::stacked_into`] to reuse a buffer. Errors (rather than
    /// panicking) with [`Model::stacked_into`]'s shape check.
    pub fn stacked(&self, samples: &[KinematicSample]) -> Result<DMatrix<f64>, DynError> {
        let mut out = DMatrix::zeros(2 * samples.len(), self.columns());
        self.stacked_into(samples, &mut out)?;
        Ok(out)
    }

    /// [`Model::stacked`] into a caller's `2N × n` matrix (reusing its memory:
    /// first-touch page faults of a fresh 100 MB matrix can cost more than
    /// filling it).
    pub fn stacked_into(
        &self,
        samples: &[KinematicSample],
        out: &mut DMatrix<f64>,
    ) -> Result<(), DynError> {
        self.check_shape(samples.len(), out)?;
        self.stacked_blocks(samples.len(), out, |i, buf| {
            self.fill_unchecked(&samples[i], Sign::Exact, buf);
            Ok(())
        })?;
        self.fill_states(samples.len(), |i| samples[i].joint, out);
        Ok(())
    }

    /// Stacked joint-major regressor of the task motion samples
    /// `(X_i, Ẋ_i, Ẍ_i)`, evaluating the kinematics on the fly (no
    /// per-sample storage). Errors with the first failing sample's
    /// kinematic error.
    pub fn stacked_from_states(
        &self,
        geometry: &Geometry,
        task: &[Motion],
    ) -> Result<DMatrix<f64>, DynError> {
        let mut out = DMatrix::zeros(2 * task.len(), self.columns());
        self.stacked_from_states_into(geometry, task, &mut out)?;
        Ok(out)
    }

    /// [`Model::stacked_from_states`] into a caller's `2N × n` matrix.
    pub fn stacked_from_states_into(
        &self,
        geometry: &Geometry,
        task: &[Motion],
        out: &mut DMatrix<f64>,
    ) -> Result<(), DynError> {
        self.check_shape(task.len(), out)?;
        self.stacked_blocks(task.len(), out, |i, buf| {
            let s = aras_kin::evaluate(geometry, &task[i])?;
            self.fill_unchecked(&s, Sign::Exact, buf);
            Ok(())
        })?;
        if self.has_state() {
            // The joint motion again, only for a model with a state (the
            // blocks above did not keep it).
            let joints = task
                .iter()
                .map(|m| aras_kin::evaluate(geometry, m).map(|s| s.joint))
                .collect::<Result<Vec<_>, _>>()?;
            self.fill_states(task.len(), |i| joints[i], out);
        }
        Ok(())
    }

    /// True if an effect of the model has a state
    /// ([`crate::Effect::is_stateful`]): its columns need the sequence.
    pub fn has_state(&self) -> bool {
        self.effects().iter().any(|e| e.is_stateful())
    }

    fn check_per_sample(&self) -> Result<(), DynError> {
        match self.effects().iter().find(|e| e.is_stateful()) {
            Some(e) => Err(DynError::StatefulEffect { id: e.id() }),
            None => Ok(()),
        }
    }

    /// Writes the columns of the stateful effects along the `n` samples
    /// (joint motion of sample `i` from `joint(i)`), in record order.
    fn fill_states(&self, n: usize, joint: impl Fn(usize) -> Motion, out: &mut DMatrix<f64>) {
        if !self.has_state() || n == 0 {
            return;
        }
        let motion: Vec<Motion> = (0..n).map(joint).collect();
        for (e, o) in self.layout() {
            let Effect::PreslidingFriction { displacement } = *e else {
                continue;
            };
            let mut level = vec![0.0; n];
            let mut rate = vec![0.0; n];
            for j in 0..2 {
                let theta: Vec<f64> = motion.iter().map(|m| m.pos[j]).collect();
                let vel: Vec<f64> = motion.iter().map(|m| m.vel[j]).collect();
                crate::effects::presliding_states(
                    displacement,
                    &theta,
                    &vel,
                    &mut level,
                    &mut rate,
                );
                // Columns o + j (level) and o + 2 + j (damping) hold joint
                // j's values on joint j's rows.
                for (col, v) in [(o + j, &level), (o + 2 + j, &rate)] {
                    let start = col * 2 * n + j * n;
                    out.as_mut_slice()[start..start + n].copy_from_slice(v);
                }
            }
        }
    }

    fn check_shape(&self, n: usize, out: &DMatrix<f64>) -> Result<(), DynError> {
        if out.ncols() != self.columns() {
            return Err(DynError::Length {
                what: "stacked matrix columns",
                expected: self.columns(),
                found: out.ncols(),
            });
        }
        if out.nrows() != 2 * n {
            return Err(DynError::Length {
                what: "stacked matrix rows (2 × samples)",
                expected: 2 * n,
                found: out.nrows(),
            });
        }
        Ok(())
    }

    /// Drives a per-sample filler over blocks of samples in parallel, writing
    /// each joint block of each column as disjoint slices (no unsafe).
    fn stacked_blocks<F>(&self, n: usize, out: &mut DMatrix<f64>, fill: F) -> Result<(), DynError>
    where
        F: Fn(usize, &mut [f64]) -> Result<(), DynError> + Sync,
    {
        const BLOCK: usize = 2048;
        let cols = self.columns();
        if n == 0 || cols == 0 {
            return Ok(());
        }
        let blocks = n.div_ceil(BLOCK);
        // pieces[b][q]: block b of the contiguous run q = 2·column + joint.
        let mut pieces: Vec<Vec<&mut [f64]>> =
            (0..blocks).map(|_| Vec::with_capacity(2 * cols)).collect();
        for run in out.as_mut_slice().chunks_mut(n) {
            for (b, p) in run.chunks_mut(BLOCK).enumerate() {
                pieces[b].push(p);
            }
        }
        pieces
            .into_par_iter()
            .enumerate()
            .try_for_each(|(b, mut runs)| {
                // Fill a sub-block of samples into a small sample-major
                // buffer, then copy each run contiguously: writing 2n
                // streams one value at a time thrashes the TLB.
                const SUB: usize = 64;
                let w = 2 * cols;
                let mut tmp = vec![0.0; SUB * w];
                let len = runs[0].len();
                let mut start = 0;
                while start < len {
                    let m = SUB.min(len - start);
                    for i in 0..m {
                        fill(b * BLOCK + start + i, &mut tmp[i * w..(i + 1) * w])?;
                    }
                    for (q, run) in runs.iter_mut().enumerate() {
                        for (i, dst) in run[start..start + m].iter_mut().enumerate() {
                            *dst = tmp[i * w + q];
                        }
                    }
                    start += m;
                }
                Ok(())
            })
    }
}
