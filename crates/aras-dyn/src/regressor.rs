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

use aras_kin::{Geometry, KinematicSample, Scalar};
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
    fn eval<T: Scalar>(self, v: T) -> T {
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

/// `J⁻ᵀ v` for `J = [[1, K], [1, −K]]`: `½ [v0 + v1/K, v0 − v1/K]`.
#[inline(always)]
fn inv_t<T: Scalar>(k: T, v0: T, v1: T) -> (T, T) {
    let half = T::lift(0.5);
    let q = v1 / k;
    (half * (v0 + q), half * (v0 - q))
}

/// Rigid-link columns (2×36) of (45): per link `J⁻ᵀ J_ωkᵀ R_k [Λ_k, [g^k]×]`
/// with `Λ_k = L(Ω̇^k) + [Ω^k]× L(Ω^k)` (40).
#[inline(always)]
fn rigid_links<T: Scalar>(s: &KinematicSample<T>, g: &Vector3<T>, out: &mut [T]) {
    let k_inv = T::one() / s.jacobian.k();
    let half = T::lift(0.5);
    for k in 0..4 {
        let r = &s.rotations[k];
        let w = r.tr_mul(&s.omega[k]);
        let wd = r.tr_mul(&s.omega_dot[k]);
        let gk = r.tr_mul(g);
        // Link-frame Jacobian B = Rᵀ J_ω; rows of A = J⁻ᵀ Bᵀ are u0ᵀ, u1ᵀ.
        let b = r.tr_mul(&s.link_jacobians[k]);
        let c0 = b.column(0);
        let c1 = b.column(1) * k_inv;
        let u0 = (c0 + c1) * half;
        let u1 = (c0 - c1) * half;
        let (wx, wy, wz) = (w.x, w.y, w.z);
        let (ax, ay, az) = (wd.x, wd.y, wd.z);
        let (gx, gy, gz) = (gk.x, gk.y, gk.z);
        let z = T::zero();
        let cols: [[T; 3]; 9] = [
            [ax, wx * wz, -(wx * wy)],
            [ay - wx * wz, ax + wy * wz, wx * wx - wy * wy],
            [az + wx * wy, wz * wz - wx * wx, ax - wy * wz],
            [-(wy * wz), ay, wx * wy],
            [wy * wy - wz * wz, az - wx * wy, ay + wx * wz],
            [wy * wz, -(wx * wz), az],
            [z, gz, -gy],
            [-gz, z, gx],
            [gy, -gx, z],
        ];
        let base = 18 * k;
        for (j, c) in cols.iter().enumerate() {
            out[base + 2 * j] = u0.x * c[0] + u0.y * c[1] + u0.z * c[2];
            out[base + 2 * j + 1] = u1.x * c[0] + u1.y * c[1] + u1.z * c[2];
        }
    }
}

/// Column of a passive hinge between links `i` and `j` (kin indices).
#[inline(always)]
fn hinge<T: Scalar>(s: &KinematicSample<T>, i: usize, j: usize) -> (T, T) {
    let jr = s.link_jacobians[i] - s.link_jacobians[j];
    let w = s.omega[i] - s.omega[j];
    let v = jr.tr_mul(&w);
    inv_t(s.jacobian.k(), v[0], v[1])
}

impl Effect {
    /// Writes this effect's 2×`columns()` block (column-major) for one
    /// sample. `out.len()` must be `2 * self.columns()`.
    #[inline]
    pub(crate) fn fill<T: Scalar>(
        &self,
        s: &KinematicSample<T>,
        g: &Vector3<T>,
        sign: Sign,
        out: &mut [T],
    ) {
        let z = T::zero();
        let (td, th) = (s.theta_dot, s.theta);
        let diag = |a: T, b: T, out: &mut [T]| {
            out[0] = a;
            out[1] = z;
            out[2] = z;
            out[3] = b;
        };
        match *self {
            Effect::RigidLinks => rigid_links(s, g, out),
            Effect::Friction => {
                out.copy_from_slice(&[
                    td[0],
                    z,
                    sign.eval(td[0]),
                    z,
                    z,
                    td[1],
                    z,
                    sign.eval(td[1]),
                ]);
            }
            Effect::Elasticity => diag(th[0], th[1], out),
            Effect::TorqueOffset => diag(T::one(), T::one(), out),
            Effect::CoulombAsymmetry => diag(sign.eval(td[0]).abs(), sign.eval(td[1]).abs(), out),
            Effect::StribeckFriction { v_s } => {
                let f = |v: T| {
                    let q = v / T::lift(v_s);
                    sign.eval(v) * (-(q * q)).exp()
                };
                diag(f(td[0]), f(td[1]), out)
            }
            Effect::PassiveJointViscous => {
                for (c, (i, j)) in [(2, 0), (3, 1), (2, 3)].into_iter().enumerate() {
                    let (a, b) = hinge(s, i, j);
                    out[2 * c] = a;
                    out[2 * c + 1] = b;
                }
            }
            Effect::Cogging {
                cycles_per_rev,
                order,
            } => {
                let mut c = 0;
                for j in 0..2 {
                    for h in 1..=order {
                        let (sn, cs) = (th[j] * T::lift(h as f64 * cycles_per_rev)).sin_cos();
                        out[2 * c + j] = sn;
                        out[2 * c + 1 - j] = z;
                        out[2 * c + 2 + j] = cs;
                        out[2 * c + 3 - j] = z;
                        c += 2;
                    }
                }
            }
            Effect::QuadraticDamping => diag(td[0] * td[0].abs(), td[1] * td[1].abs(), out),
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
    pub fn fill_with<T: Scalar>(
        &self,
        s: &KinematicSample<T>,
        sign: Sign,
        out: &mut [T],
    ) -> Result<(), DynError> {
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

    /// The 2×n regressor of one sample (allocates the result).
    pub fn regressor(&self, s: &KinematicSample) -> Matrix2xX<f64> {
        let mut m = Matrix2xX::zeros(self.columns());
        self.fill_unchecked(s, Sign::Exact, m.as_mut_slice());
        m
    }

    /// `τ = Y β` for one sample.
    pub fn torque(&self, s: &KinematicSample, beta: &[f64]) -> Result<Vector2<f64>, DynError> {
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
        })
    }

    /// Stacked joint-major regressor of the samples `(X_i, Ẋ_i, Ẍ_i)`,
    /// evaluating the kinematics on the fly (no per-sample storage). Errors
    /// with the first failing sample's kinematic error.
    pub fn stacked_from_states(
        &self,
        geometry: &Geometry,
        x: &[Vector2<f64>],
        x_dot: &[Vector2<f64>],
        x_ddot: &[Vector2<f64>],
    ) -> Result<DMatrix<f64>, DynError> {
        let mut out = DMatrix::zeros(2 * x.len(), self.columns());
        self.stacked_from_states_into(geometry, x, x_dot, x_ddot, &mut out)?;
        Ok(out)
    }

    /// [`Model::stacked_from_states`] into a caller's `2N × n` matrix.
    pub fn stacked_from_states_into(
        &self,
        geometry: &Geometry,
        x: &[Vector2<f64>],
        x_dot: &[Vector2<f64>],
        x_ddot: &[Vector2<f64>],
        out: &mut DMatrix<f64>,
    ) -> Result<(), DynError> {
        for (what, len) in [("x_dot", x_dot.len()), ("x_ddot", x_ddot.len())] {
            if len != x.len() {
                return Err(DynError::Length {
                    what,
                    expected: x.len(),
                    found: len,
                });
            }
        }
        self.check_shape(x.len(), out)?;
        self.stacked_blocks(x.len(), out, |i, buf| {
            let s = aras_kin::evaluate(geometry, &x[i], &x_dot[i], &x_ddot[i])?;
            self.fill_unchecked(&s, Sign::Exact, buf);
            Ok(())
        })
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
