//! The generalized Maxwell-slip model (Lampaert, Al-Bender and Swevers
//! 2003): several elastoplastic elements in parallel, each of which sticks
//! with its own stiffness until its force reaches its share of the Stribeck
//! curve, then slips.
//!
//! ```text
//! stick:  dw_i/dq = 1 / L_i          slip:  |w_i| = h(v)
//! h(v) = 1 + (r − 1) e^{−|v/v_s|^δ}
//! τ = f₀ + Σ F_i w_i + F_v v,        F_i ≥ 0,  L_i = L ρ^{i−1}
//! ```
//!
//! `w_i` is element `i`'s force over its level `F_i`; `L_i = F_i / k_i` its
//! presliding length (travel from relaxed to slipping), on a geometric grid
//! of [`MAXWELL_ELEMENTS`] lengths spaced by [`MAXWELL_SPACING`] below the
//! longest, `L`. In steady sliding every element slips and `τ = f₀ +
//! (Σ F_i) h(v) sgn(v) + F_v v`: the [`crate::Stribeck`] curve with
//! `F_c = Σ F_i`, `F_s = r F_c`. Near rest the elements yield one after the
//! other, so the presliding curve is piecewise linear with as many knees as
//! elements: hysteresis with several lengths, which LuGre's single
//! exponential state cannot hold. The structure `θ = (L, r, v_s, δ)` is
//! LuGre's with the presliding length in place of the stiffness, and `τ` is
//! linear in `β = (f₀, F_1 … F_n, F_v)` with every level held ≥ 0, so the
//! model is passive by construction.
//!
//! Between two samples an element moves with the Hermite interpolant's
//! displacement, split at its reversals; each piece is one clamp of
//! `w + Δx/L_i` to `±h` at the piece's end (exact for the elastoplastic
//! element when `h` is constant over the piece).

use serde::{Deserialize, Serialize};

use super::{DELTA, FV, FrictionModel, OFFSET, ParamInfo, RATIO, Separable, VS, check_params, p};
use crate::{FrictionError, Track, track::HermiteInterval};

/// Elements of the model.
pub const MAXWELL_ELEMENTS: usize = 6;

/// Ratio of neighbouring presliding lengths, `L_{i+1} / L_i`: six elements
/// span three decades, from the longest length to a thousandth of it, a
/// factor 4 apart (a factor 10 left 25 % more held-out RMS on a joint with
/// two slip elements beside LuGre).
pub const MAXWELL_SPACING: f64 = 0.25;

/// The generalized Maxwell-slip model (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MaxwellSlip {
    /// Constant offset `f₀`, N·m.
    pub offset: f64,
    /// Each element's level `F_i`, N·m (≥ 0), longest length first.
    pub levels: [f64; MAXWELL_ELEMENTS],
    /// Presliding length of the first element `L`, rad; element `i` has
    /// `L ρ^{i−1}`.
    pub length: f64,
    /// Static over Coulomb level `r = F_s / F_c` of the Stribeck curve.
    pub static_ratio: f64,
    /// Stribeck velocity `v_s`, rad/s.
    pub stribeck_velocity: f64,
    /// Shape exponent `δ`.
    pub shape: f64,
    /// Viscous coefficient `F_v`, N·m·s/rad.
    pub viscous: f64,
}

const LEVEL_NAMES: [&str; MAXWELL_ELEMENTS] = ["F1", "F2", "F3", "F4", "F5", "F6"];
const LENGTH: ParamInfo = p("L1", "rad", 1e-9, 1e3);

/// `[offset, F1 … F6, L1, Fs_over_Fc, vs, delta, Fv]`.
fn info() -> Vec<ParamInfo> {
    let mut v = vec![OFFSET];
    v.extend(level_info());
    v.extend([LENGTH, RATIO, VS, DELTA, FV]);
    v
}

fn level_info() -> impl Iterator<Item = ParamInfo> {
    LEVEL_NAMES
        .iter()
        .map(|&name| p(name, "N·m", 0.0, super::BIG))
}

impl MaxwellSlip {
    /// Builds the model from `[offset, F1 … F6, L1, Fs_over_Fc, vs, delta,
    /// Fv]`, checking the physical ranges.
    pub fn from_parameters(values: &[f64]) -> Result<Self, FrictionError> {
        check_params("maxwell_slip", &info(), values)?;
        Ok(Self::from_vector(values))
    }

    /// Presliding length of every element, rad.
    pub fn lengths(&self) -> [f64; MAXWELL_ELEMENTS] {
        lengths(self.length)
    }

    /// The Coulomb level `F_c = Σ F_i`, N·m.
    pub fn coulomb(&self) -> f64 {
        self.levels.iter().sum()
    }

    /// The steady-state (Stribeck) curve of this model.
    pub fn steady_state(&self) -> super::Stribeck {
        let fc = self.coulomb();
        super::Stribeck {
            offset: self.offset,
            coulomb: fc,
            static_friction: self.static_ratio * fc,
            stribeck_velocity: self.stribeck_velocity,
            shape: self.shape,
            viscous: self.viscous,
        }
    }

    /// Each element's normalised force `w_i` at every sample for the
    /// structure `[L, r, v_s, δ]`.
    fn states(theta: &[f64], motion: &Track) -> Vec<Vec<f64>> {
        let law = aras_core::LuGreLaw {
            coulomb: 1.0,
            static_level: theta[1],
            stribeck_velocity: theta[2],
            shape: theta[3],
            stiffness: 1.0,
        };
        let h = |v: f64| law.level(v);
        let inv: Vec<f64> = lengths(theta[0]).iter().map(|l| 1.0 / l).collect();
        let (t, q, dq) = (motion.t(), motion.q(), motion.dq());
        let n = t.len();
        let mut out: Vec<Vec<f64>> = (0..MAXWELL_ELEMENTS)
            .map(|_| Vec::with_capacity(n))
            .collect();
        if n == 0 {
            return out;
        }
        // Relaxed at rest, slipping in the direction of a first motion.
        let mut w = [super::sgn(dq[0]) * h(dq[0]); MAXWELL_ELEMENTS];
        let h_rest = h(0.0);
        for (o, x) in out.iter_mut().zip(&w) {
            o.push(*x);
        }
        for k in 0..n - 1 {
            let hi = HermiteInterval::new(t[k + 1] - t[k], q[k], q[k + 1], dq[k], dq[k + 1]);
            let (rev, nrev) = hi.reversals();
            let mut xa = q[k];
            for seg in 0..=nrev {
                let (xb, hb) = if seg == nrev {
                    (q[k + 1], h(dq[k + 1]))
                } else {
                    (hi.position(rev[seg]), h_rest)
                };
                let dx = xb - xa;
                for (w, inv) in w.iter_mut().zip(&inv) {
                    *w = (*w + dx * inv).clamp(-hb, hb);
                }
                xa = xb;
            }
            for (o, x) in out.iter_mut().zip(&w) {
                o.push(*x);
            }
        }
        out
    }
}

/// `L ρ^{i−1}` for every element.
fn lengths(longest: f64) -> [f64; MAXWELL_ELEMENTS] {
    let mut l = [longest; MAXWELL_ELEMENTS];
    for i in 1..MAXWELL_ELEMENTS {
        l[i] = l[i - 1] * MAXWELL_SPACING;
    }
    l
}

impl FrictionModel for MaxwellSlip {
    fn name(&self) -> &'static str {
        "maxwell_slip"
    }
    fn parameter_info(&self) -> Vec<ParamInfo> {
        info()
    }
    fn parameters(&self) -> Vec<f64> {
        let mut v = vec![self.offset];
        v.extend(self.levels);
        v.extend([
            self.length,
            self.static_ratio,
            self.stribeck_velocity,
            self.shape,
            self.viscous,
        ]);
        v
    }
    fn predict(&self, motion: &Track) -> Vec<f64> {
        super::predict_parts::<Self>(&self.structure(), &self.coefficients(), motion)
    }
}

impl Separable for MaxwellSlip {
    fn structure_info() -> Vec<ParamInfo> {
        vec![LENGTH, RATIO, VS, DELTA]
    }
    fn coefficient_info() -> Vec<ParamInfo> {
        let mut v = vec![OFFSET];
        v.extend(level_info());
        v.push(FV);
        v
    }
    fn structure(&self) -> Vec<f64> {
        vec![
            self.length,
            self.static_ratio,
            self.stribeck_velocity,
            self.shape,
        ]
    }
    fn coefficients(&self) -> Vec<f64> {
        let mut v = vec![self.offset];
        v.extend(self.levels);
        v.push(self.viscous);
        v
    }
    fn columns(theta: &[f64], motion: &Track) -> Vec<Vec<f64>> {
        let mut cols = vec![vec![1.0; motion.len()]];
        cols.extend(Self::states(theta, motion));
        cols.push(motion.dq().to_vec());
        cols
    }
    fn from_parts(theta: &[f64], beta: &[f64]) -> Self {
        let mut levels = [0.0; MAXWELL_ELEMENTS];
        levels.copy_from_slice(&beta[1..=MAXWELL_ELEMENTS]);
        Self {
            offset: beta[0],
            levels,
            length: theta[0],
            static_ratio: theta[1],
            stribeck_velocity: theta[2],
            shape: theta[3],
            viscous: beta[MAXWELL_ELEMENTS + 1],
        }
    }
    fn from_vector(v: &[f64]) -> Self {
        let mut levels = [0.0; MAXWELL_ELEMENTS];
        levels.copy_from_slice(&v[1..=MAXWELL_ELEMENTS]);
        let s = MAXWELL_ELEMENTS + 1;
        Self {
            offset: v[0],
            levels,
            length: v[s],
            static_ratio: v[s + 1],
            stribeck_velocity: v[s + 2],
            shape: v[s + 3],
            viscous: v[s + 4],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(levels: [f64; MAXWELL_ELEMENTS], ratio: f64) -> MaxwellSlip {
        MaxwellSlip {
            offset: 0.01,
            levels,
            length: 4e-3,
            static_ratio: ratio,
            stribeck_velocity: 0.05,
            shape: 2.0,
            viscous: 0.1,
        }
    }

    /// In steady sliding every element slips: the prediction is the
    /// Stribeck curve with `F_c = Σ F_i`, at any speed and either way.
    #[test]
    fn steady_sliding_is_the_stribeck_curve() {
        let m = model([0.05, 0.1, 0.02, 0.0, 0.03, 0.01], 1.4);
        for v in [-0.3, -0.04, 0.01, 0.08, 1.5] {
            let t: Vec<f64> = (0..200).map(|i| i as f64 * 1e-3).collect();
            let q: Vec<f64> = t.iter().map(|t| v * t).collect();
            let dq = vec![v; t.len()];
            let p = m.predict(&Track::new(&t, &q, &dq).unwrap());
            let want = m.steady_state().at(v);
            assert!((p[199] - want).abs() < 1e-12, "v {v}: {} vs {want}", p[199]);
        }
    }

    /// With a flat Stribeck curve each element is the elastoplastic spring
    /// `F clamp(x + Δq, ±L) / L`: the model on a coarse grid (4 ms, its
    /// reversals inside the steps) equals that spring integrated by the
    /// test on a grid 200 times finer.
    #[test]
    fn each_element_is_an_elastoplastic_spring() {
        let levels = [0.05, 0.1, 0.02, 0.0, 0.03, 0.01];
        let m = model(levels, 1.0);
        let path = |t: f64| {
            (
                0.01 * (7.0 * t).sin() + 0.003 * (31.0 * t).sin(),
                0.07 * (7.0 * t).cos() + 0.093 * (31.0 * t).cos(),
            )
        };
        let n = 500;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 4e-3).collect();
        let (q, dq): (Vec<f64>, Vec<f64>) = t.iter().map(|&t| path(t)).unzip();
        let p = m.predict(&Track::new(&t, &q, &dq).unwrap());
        let lengths = m.lengths();
        let mut x: Vec<f64> = lengths
            .iter()
            .map(|l| super::super::sgn(dq[0]) * l)
            .collect();
        let mut q_prev = q[0];
        let fine = 200;
        let mut worst = 0.0f64;
        for k in 1..n {
            for j in 1..=fine {
                let tj = t[k - 1] + (t[k] - t[k - 1]) * j as f64 / fine as f64;
                let qj = path(tj).0;
                for (x, l) in x.iter_mut().zip(&lengths) {
                    *x = (*x + qj - q_prev).clamp(-l, *l);
                }
                q_prev = qj;
            }
            let spring: f64 = x
                .iter()
                .zip(&lengths)
                .zip(&levels)
                .map(|((x, l), f)| f * x / l)
                .sum();
            let want = m.offset + spring + m.viscous * dq[k];
            worst = worst.max((p[k] - want).abs());
        }
        // The Hermite interpolant is not the path: its position error over
        // a 4 ms step, h⁴ q⁗ / 384 ≈ 2e-9 rad, times the stiffest element's
        // F/L = 0.01 / 3.9e-6 N·m/rad is 5e-6 N·m (8e-6 measured).
        assert!(worst < 2e-5, "worst {worst}");
    }
}
