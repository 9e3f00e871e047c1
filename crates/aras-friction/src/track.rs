//! A joint's track: its motion along a (possibly irregular) time grid.

use crate::FrictionError;

/// Time stamps, positions and velocities of one joint, one value per sample.
///
/// The grid may be irregular (jitter, gaps): the dynamic models integrate their
/// internal state over each interval between two samples, so nothing assumes a
/// constant step. Construction checks lengths, finiteness and strictly
/// increasing time, so every model can rely on clean input.
#[derive(Debug, Clone, Copy)]
pub struct Track<'a> {
    t: &'a [f64],
    q: &'a [f64],
    dq: &'a [f64],
}

impl<'a> Track<'a> {
    /// Checks and wraps time `t` (s), position `q` (rad) and velocity `dq` (rad/s).
    pub fn new(t: &'a [f64], q: &'a [f64], dq: &'a [f64]) -> Result<Self, FrictionError> {
        let n = t.len();
        for (what, s) in [("position q", q), ("velocity dq", dq)] {
            if s.len() != n {
                return Err(FrictionError::LengthMismatch {
                    what,
                    expected: n,
                    found: s.len(),
                });
            }
        }
        for (what, s) in [("time t", t), ("position q", q), ("velocity dq", dq)] {
            if let Some((index, &value)) = s.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(FrictionError::NonFinite { what, index, value });
            }
        }
        if let Some(k) = (1..n).find(|&k| t[k] <= t[k - 1]) {
            return Err(FrictionError::TimeNotIncreasing {
                index: k,
                previous: t[k - 1],
                value: t[k],
            });
        }
        Ok(Self { t, q, dq })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Time stamps, s.
    pub fn t(&self) -> &'a [f64] {
        self.t
    }

    /// Positions, rad.
    pub fn q(&self) -> &'a [f64] {
        self.q
    }

    /// Velocities, rad/s.
    pub fn dq(&self) -> &'a [f64] {
        self.dq
    }
}

/// The cubic Hermite interpolant of one interval, built from the positions
/// and velocities at its two ends. Within the interval it gives positions
/// consistent with both samples, so state models can be driven by exact
/// displacements rather than by a velocity held constant.
#[derive(Debug, Clone, Copy)]
pub(crate) struct HermiteInterval {
    q0: f64,
    dt: f64,
    // q(s) = q0 + dt (c1 s + c2 s² + c3 s³), s ∈ [0, 1]
    c1: f64,
    c2: f64,
    c3: f64,
}

impl HermiteInterval {
    pub(crate) fn new(dt: f64, q0: f64, q1: f64, v0: f64, v1: f64) -> Self {
        let d = (q1 - q0) / dt;
        Self {
            q0,
            dt,
            c1: v0,
            c2: 3.0 * d - 2.0 * v0 - v1,
            c3: -2.0 * d + v0 + v1,
        }
    }

    /// Position at the normalised time `s ∈ [0, 1]`.
    pub(crate) fn position(&self, s: f64) -> f64 {
        self.q0 + self.dt * s * (self.c1 + s * (self.c2 + s * self.c3))
    }

    /// Velocity (rad/s) at the normalised time `s ∈ [0, 1]`.
    pub(crate) fn velocity(&self, s: f64) -> f64 {
        self.c1 + s * (2.0 * self.c2 + 3.0 * s * self.c3)
    }

    /// Normalised times in (0, 1) where the interpolated velocity changes sign,
    /// ascending (at most two).
    pub(crate) fn reversals(&self) -> ([f64; 2], usize) {
        // v(s)/dt-free form: c1 + 2 c2 s + 3 c3 s²
        let (a, b, c) = (3.0 * self.c3, 2.0 * self.c2, self.c1);
        let mut out = [0.0; 2];
        let mut n = 0;
        let mut push = |s: f64| {
            if s > 1e-9 && s < 1.0 - 1e-9 && s.is_finite() {
                out[n] = s;
                n += 1;
            }
        };
        let scale = a.abs().max(b.abs()).max(c.abs());
        if scale == 0.0 {
            return (out, 0);
        }
        if a.abs() <= 1e-12 * scale {
            if b != 0.0 {
                push(-c / b);
            }
        } else {
            let disc = b * b - 4.0 * a * c;
            if disc > 0.0 {
                // Numerically stable roots.
                let sq = disc.sqrt();
                let qv = -0.5 * (b + b.signum() * sq);
                let (r1, r2) = if qv != 0.0 {
                    (qv / a, c / qv)
                } else {
                    (-b / (2.0 * a), -b / (2.0 * a))
                };
                let (lo, hi) = if r1 <= r2 { (r1, r2) } else { (r2, r1) };
                push(lo);
                if hi != lo {
                    push(hi);
                }
            }
        }
        (out, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hermite_reproduces_ends_and_cubics() {
        // q(t) = 1 + 2t − t² + 0.5 t³ on [0.3, 0.7] is reproduced exactly.
        let q = |t: f64| 1.0 + 2.0 * t - t * t + 0.5 * t * t * t;
        let v = |t: f64| 2.0 - 2.0 * t + 1.5 * t * t;
        let (t0, t1) = (0.3, 0.7);
        let h = HermiteInterval::new(t1 - t0, q(t0), q(t1), v(t0), v(t1));
        for i in 0..=10 {
            let s = i as f64 / 10.0;
            let t = t0 + s * (t1 - t0);
            assert!((h.position(s) - q(t)).abs() < 1e-14);
        }
    }

    #[test]
    fn hermite_reversal_found() {
        // q = sin(t) around t = π/2: the velocity cos(t) changes sign once.
        let (t0, t1) = (1.4, 1.8);
        let h = HermiteInterval::new(t1 - t0, t0.sin(), t1.sin(), t0.cos(), t1.cos());
        let (r, n) = h.reversals();
        assert_eq!(n, 1);
        let t = t0 + r[0] * (t1 - t0);
        // Cubic interpolation error of the root is O(dt³) ≈ 1e-3 here.
        assert!((t - std::f64::consts::FRAC_PI_2).abs() < 2e-3, "{t}");
    }

    #[test]
    fn motion_rejects_bad_time() {
        let t = [0.0, 0.1, 0.1];
        let z = [0.0; 3];
        let e = Track::new(&t, &z, &z).unwrap_err();
        assert!(matches!(
            e,
            FrictionError::TimeNotIncreasing { index: 2, .. }
        ));
        let q = [0.0, f64::NAN, 0.0];
        let t = [0.0, 0.1, 0.2];
        let e = Track::new(&t, &q, &z).unwrap_err();
        assert!(matches!(e, FrictionError::NonFinite { index: 1, .. }));
    }
}
