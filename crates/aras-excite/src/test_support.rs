//! Test-only helpers, shared by the unit tests, the integration tests and
//! the benchmark (included by path there). NOT part of the public API.
//!
//! * [`StandIn`]: a smooth, nonlinear stand-in regressor with robot-like
//!   columns built on the real kinematics, one exactly dependent column and
//!   one zero column (so the base projection has work to do).
//! * [`fourier`]: a trajectory from a flat list of coefficients.
//! * [`base_projection`]: a base projection `E` by faer's column-pivoted QR
//!   on a stacked regressor of random samples. The real pipeline takes `E`
//!   from `aras-ident`; this helper exists only for tests and benches.

#![allow(dead_code)]

use aras_excite::{Dual, Regressor};
use aras_ident::LinearModel;
use aras_kin::{Geometry, KinError, Motion, Scalar, Workspace, evaluate};
use nalgebra::{DMatrix, Vector2};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// Smooth stand-in for a robot regressor: 12 columns, 10 base parameters.
pub struct StandIn {
    /// Geometry for the kinematics.
    pub geometry: Geometry,
}

impl Default for StandIn {
    fn default() -> Self {
        Self {
            geometry: Geometry::aras_diamond(),
        }
    }
}

impl LinearModel for StandIn {
    type Error = KinError;

    fn coordinates(&self) -> usize {
        2
    }

    fn outputs(&self) -> usize {
        2
    }

    fn names(&self) -> Vec<String> {
        (0..12).map(|c| format!("c{c}")).collect()
    }

    fn columns(&self) -> usize {
        12
    }

    fn fill(
        &self,
        q: &[f64],
        q_dot: &[f64],
        q_ddot: &[f64],
        rows: &mut [f64],
    ) -> Result<(), KinError> {
        let v = |a: &[f64]| Vector2::new(a[0], a[1]);
        self.rows(&Motion::new(v(q), v(q_dot), v(q_ddot)), rows)
    }
}

impl Regressor for StandIn {
    fn fill_dual(
        &self,
        q: &[Dual],
        q_dot: &[Dual],
        q_ddot: &[Dual],
        rows: &mut [Dual],
    ) -> Result<(), KinError> {
        let v = |a: &[Dual]| Vector2::new(a[0], a[1]);
        self.rows(&Motion::new(v(q), v(q_dot), v(q_ddot)), rows)
    }
}

impl StandIn {
    /// The rows at the task motion `(X, Ẋ, Ẍ)`, in any number type.
    fn rows<T: Scalar>(&self, task: &Motion<T>, rows: &mut [T]) -> Result<(), KinError> {
        let k = evaluate(&self.geometry, task)?;
        let (th, thd, thdd) = (k.joint.pos, k.joint.vel, k.joint.acc);
        let cd = (th[0] - th[1]).cos();
        // Column-major 2 × 12: entry (joint j, column c) at 2c + j.
        let cols: [[T; 2]; 11] = [
            [thdd[0], T::zero()],
            [T::zero(), thdd[1]],
            [thd[0], T::zero()],
            [T::zero(), thd[1]],
            [th[0].cos(), th[1].cos()],
            [th[0].sin(), -th[1].sin()],
            [thd[0] * thd[1], thd[1] * thd[1]],
            [cd * thdd[1], cd * thdd[0]],
            [
                k.omega_dot[2][2],
                k.omega_dot[3][2] + k.omega[3][0] * k.omega[3][1],
            ],
            [th[0], T::zero()],
            // Exactly column 0 + column 2: not a base column.
            [thdd[0] + thd[0], T::zero()],
        ];
        for (c, col) in cols.iter().enumerate() {
            rows[2 * c] = col[0];
            rows[2 * c + 1] = col[1];
        }
        // Column 11 stays zero.
        Ok(())
    }
}

/// Base projection `E` (n × b) selecting the independent columns found by
/// column-pivoted QR on `samples` random samples in the workspace (relative
/// rank tolerance 1e-9 of the largest |R_ii|: the stand-in's dependent
/// columns are exact, so their |R_ii| sit at rounding level, ~1e-15).
pub fn base_projection<R: Regressor>(reg: &R, samples: usize, seed: u64) -> DMatrix<f64> {
    let ws = Workspace::paper();
    let n = reg.columns();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut w = faer::Mat::<f64>::zeros(2 * samples, n);
    let mut rows = vec![0.0; 2 * n];
    for s in 0..samples {
        let mut r = |lo: f64, hi: f64| rng.random_range(lo..hi);
        let x = Vector2::new(r(ws.min()[0], ws.max()[0]), r(ws.min()[1], ws.max()[1]));
        let xd = Vector2::new(r(-3.0, 3.0), r(-3.0, 3.0));
        let xdd = Vector2::new(r(-10.0, 10.0), r(-10.0, 10.0));
        rows.iter_mut().for_each(|v| *v = 0.0);
        reg.fill(x.as_slice(), xd.as_slice(), xdd.as_slice(), &mut rows)
            .unwrap_or_else(|e| panic!("regressor failed: {e}"));
        for j in 0..2 {
            for c in 0..n {
                w[(j * samples + s, c)] = rows[2 * c + j];
            }
        }
    }
    let qr = w.col_piv_qr();
    let r = qr.R();
    let perm = qr.P();
    let fwd = perm.arrays().0;
    let r00 = r[(0, 0)].abs();
    let rank = (0..n.min(2 * samples))
        .take_while(|&i| r[(i, i)].abs() > 1e-9 * r00)
        .count();
    let mut e = DMatrix::zeros(n, rank);
    for (k, &col) in fwd.iter().take(rank).enumerate() {
        e[(col, k)] = 1.0;
    }
    e
}

/// A trajectory with `ω_f = 0.7`, offsets `[1.2, 1.0]` rad and the
/// coefficients `seed` (`a` of both coordinates, then `b`; four equal parts).
pub fn fourier(seed: &[f64]) -> aras_excite::FourierTrajectory {
    let l = seed.len() / 4;
    aras_excite::FourierTrajectory::new(
        0.7,
        [1.2, 1.0],
        [seed[..l].to_vec(), seed[l..2 * l].to_vec()],
        [seed[2 * l..3 * l].to_vec(), seed[3 * l..4 * l].to_vec()],
    )
    .unwrap()
}
