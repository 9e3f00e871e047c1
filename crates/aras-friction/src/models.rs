//! Friction models of one joint: static maps of the velocity and dynamic
//! models with an internal state integrated along the log's own time steps.
//!
//! | model | equation |
//! |---|---|
//! | [`CoulombViscous`] | `τ = f₀ + F_c sgn(v) + F_v v` |
//! | [`Stribeck`] | `τ = f₀ + [F_c + (F_s − F_c) e^{−|v/v_s|^δ}] sgn(v) + F_v v` |
//! | [`Dahl`] | `dF/dt = σ₀ v (1 − F sgn(v)/F_c)`, `τ = f₀ + F + F_v v` |
//! | [`MaxwellSlip`] | `w_i` elastoplastic to `±h(v)` over `L_i`, `τ = f₀ + Σ F_i w_i + F_v v` |
//! | [`LuGre`] | `dz/dt = v − σ₀ |v| z / g(v)`, `g(v) = F_c + (F_s − F_c) e^{−|v/v_s|^δ}`, `τ = f₀ + σ₀ z + σ₁ dz/dt + σ₂ v` |
//!
//! `v` is the joint velocity `dq` (rad/s), `sgn(0) = 0`.
//!
//! # Separable structure
//! Every model is linear in some of its parameters once a few *structural*
//! parameters are fixed: `τ = Φ(θ; motion) β`. [`Separable`] exposes `θ`, the
//! columns `Φ` and the map back to the physical parameters; fitting uses it for
//! variable projection (inner linear least squares by QR, outer bounded
//! nonlinear search over `θ` only). For the LuGre model the trick is to write
//! the state equation with `κ = σ₀ / F_c` and `r = F_s / F_c`:
//! `dz/dt = v − κ |v| z / h(v)` with `h(v) = 1 + (r − 1) e^{−|v/v_s|^δ}`;
//! then `z` depends on `θ = (κ, r, v_s, δ)` only and `τ` is linear in
//! `β = (f₀, σ₀, σ₁, σ₂)`; `F_c = σ₀/κ`, `F_s = r F_c`.
//!
//! # State integration on irregular steps
//! Between two samples the position is the cubic Hermite interpolant of
//! `(q, dq)` at both ends. Each interval is split where that interpolant
//! reverses and, near the Stribeck region, into pieces over which `h` changes
//! by at most [`STATE_H_STEP`]. In terms of the displacement `x` the state
//! equation is linear, `dz/dx = (κ/h)(z_ss − z)` with the steady state
//! `z_ss = sgn(Δx) h / κ`; over each piece `h` is taken linear between its
//! values at the piece's ends and the equation is advanced by its exact
//! solution for that `h` (second order in the piece length). This is
//! unconditionally stable for any stiffness
//! `σ₀` and any step (no explicit-Euler limit `σ₀ |v| Δt / g < 2`), and exact
//! for the rate-independent parts (Dahl, and LuGre outside the Stribeck region)
//! whatever the step. The state starts at its steady state for the first
//! velocity (relaxed, `z = 0`, when the joint starts at rest).

use serde::{Deserialize, Serialize};

use crate::{FrictionError, Track, track::HermiteInterval};

mod maxwell;
pub use maxwell::{MAXWELL_ELEMENTS, MAXWELL_SPACING, MaxwellSlip};

/// Largest change of the normalised Stribeck function `h(v)` over one
/// integration piece. The state error grows in proportion to it where the
/// bristles are neither stiff nor soft over a step (`κ|Δx|/h ≈ 1`); 0.001
/// keeps the friction error at about 1e-5 of `F_c` (RMS) on 1–16 ms steps
/// (see the tests against a fine RK4 integration), enough to recover the
/// Stribeck parameters to 1e-3, while adding pieces only around reversals
/// and Stribeck-region crossings.
pub const STATE_H_STEP: f64 = 0.001;

/// Upper limit on the pieces of one interval, so that a corrupt sample cannot
/// make the integration arbitrarily slow.
const MAX_PIECES: usize = 256;

/// Name, unit and physical range of one parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ParamInfo {
    /// Short name used in files and reports (`Fc`, `sigma0`, …).
    pub name: &'static str,
    /// SI unit.
    pub unit: &'static str,
    /// Smallest physical value.
    pub lower: f64,
    /// Largest physical value.
    pub upper: f64,
}

const BIG: f64 = 1e6;

const fn p(name: &'static str, unit: &'static str, lower: f64, upper: f64) -> ParamInfo {
    ParamInfo {
        name,
        unit,
        lower,
        upper,
    }
}

const OFFSET: ParamInfo = p("offset", "N·m", -BIG, BIG);
const FC: ParamInfo = p("Fc", "N·m", 0.0, BIG);
const FS: ParamInfo = p("Fs", "N·m", 0.0, BIG);
const VS: ParamInfo = p("vs", "rad/s", 1e-5, 1e3);
pub(crate) const DELTA: ParamInfo = p("delta", "1", 0.25, 5.0);
const FV: ParamInfo = p("Fv", "N·m·s/rad", 0.0, BIG);
const SIGMA0: ParamInfo = p("sigma0", "N·m/rad", 1e-6, 1e12);
const SIGMA1: ParamInfo = p("sigma1", "N·m·s/rad", 0.0, BIG);
const SIGMA2: ParamInfo = p("sigma2", "N·m·s/rad", 0.0, BIG);

/// `sgn(v)` with `sgn(0) = 0`.
pub fn sgn(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// The Stribeck decay `e^{−|v/v_s|^δ}` ([`aras_core::stribeck_decay`], the
/// workspace's one home of the LuGre and Stribeck equations).
pub use aras_core::stribeck_decay;

/// What every friction model offers: its parameters and a prediction of the
/// friction torque along a motion.
pub trait FrictionModel {
    /// Short model name (`coulomb_viscous`, `stribeck`, `dahl`, `lugre`, …).
    fn name(&self) -> &'static str;
    /// Names, units and physical ranges of the parameters, in the order of
    /// [`FrictionModel::parameters`].
    fn parameter_info(&self) -> Vec<ParamInfo>;
    /// The parameter vector.
    fn parameters(&self) -> Vec<f64>;
    /// Friction torque (N·m) at every sample of the motion.
    fn predict(&self, motion: &Track) -> Vec<f64>;
}

/// A model that is linear in its coefficients `β` once its structural
/// parameters `θ` are fixed: `τ = Φ(θ; motion) β` (see the module docs).
pub trait Separable: FrictionModel + Sized {
    /// Names and ranges of the structural parameters `θ`.
    fn structure_info() -> Vec<ParamInfo>;
    /// Names and ranges of the linear coefficients `β`.
    fn coefficient_info() -> Vec<ParamInfo>;
    /// This model's `θ`.
    fn structure(&self) -> Vec<f64>;
    /// This model's `β`.
    fn coefficients(&self) -> Vec<f64>;
    /// The regressor columns `Φ(θ)` along the motion, one `Vec` per coefficient.
    fn columns(theta: &[f64], motion: &Track) -> Vec<Vec<f64>>;
    /// The physical model from `θ` and `β`.
    fn from_parts(theta: &[f64], beta: &[f64]) -> Self;
    /// The model from its parameter vector ([`FrictionModel::parameters`]
    /// order) without range checks, for derivatives by finite differences.
    fn from_vector(values: &[f64]) -> Self;
}

fn check_params(
    model: &'static str,
    info: &[ParamInfo],
    values: &[f64],
) -> Result<(), FrictionError> {
    if values.len() != info.len() {
        return Err(FrictionError::ParameterCount {
            model,
            expected: info.len(),
            found: values.len(),
            names: info.iter().map(|i| i.name).collect::<Vec<_>>().join(", "),
        });
    }
    for (i, &v) in info.iter().zip(values) {
        if !(v >= i.lower && v <= i.upper) {
            return Err(FrictionError::ParameterOutOfRange {
                model,
                name: i.name,
                value: v,
                lower: i.lower,
                upper: i.upper,
            });
        }
    }
    Ok(())
}

/// `Σ_j β_j · column_j`: a separable model's prediction from its columns
/// ([`Separable::columns`], at any structure) and coefficients, without
/// computing the columns again.
pub fn combine(columns: &[Vec<f64>], beta: &[f64]) -> Vec<f64> {
    let n = columns.first().map_or(0, Vec::len);
    let mut out = vec![0.0; n];
    for (c, &b) in columns.iter().zip(beta) {
        for (o, x) in out.iter_mut().zip(c) {
            *o += b * x;
        }
    }
    out
}

/// Integrates `dz/dt = v − κ |v| z / h(v)` along the motion (module docs) and
/// returns `z` and `dz/dt` at every sample.
pub(crate) fn integrate_state(
    motion: &Track,
    kappa: f64,
    h: impl Fn(f64) -> f64,
) -> (Vec<f64>, Vec<f64>) {
    let (t, q, dq) = (motion.t(), motion.q(), motion.dq());
    let n = t.len();
    let mut z = vec![0.0; n];
    let mut zd = vec![0.0; n];
    if n == 0 {
        return (z, zd);
    }
    // h at every sample and at rest, computed once.
    let hs: Vec<f64> = dq.iter().map(|&v| h(v)).collect();
    let h_rest = h(0.0);
    let mut zk = sgn(dq[0]) * hs[0] / kappa;
    z[0] = zk;
    zd[0] = dq[0] - kappa * dq[0].abs() * zk / hs[0];
    for k in 0..n - 1 {
        let dt = t[k + 1] - t[k];
        let hi = HermiteInterval::new(dt, q[k], q[k + 1], dq[k], dq[k + 1]);
        let (rev, nrev) = hi.reversals();
        // Segment ends in normalised time: reversals split the interval.
        let mut ends = [0.0; 4];
        ends[1..=nrev].copy_from_slice(&rev[..nrev]);
        ends[nrev + 1] = 1.0;
        let mut xa = q[k];
        for seg in 0..=nrev {
            let (sa, sb) = (ends[seg], ends[seg + 1]);
            let ha = if seg == 0 { hs[k] } else { h_rest };
            let hb = if seg == nrev { hs[k + 1] } else { h_rest };
            let xb = if seg == nrev {
                q[k + 1]
            } else {
                hi.position(sb)
            };
            // Pieces so that h changes by at most STATE_H_STEP over each.
            let pieces = (((ha - hb).abs() / STATE_H_STEP).ceil() as usize).clamp(1, MAX_PIECES);
            let mut x0 = xa;
            let mut h0 = ha;
            for i in 1..=pieces {
                let s1 = if i == pieces {
                    sb
                } else {
                    sa + (sb - sa) * i as f64 / pieces as f64
                };
                let (x1, h1) = if i == pieces {
                    (xb, hb)
                } else {
                    (hi.position(s1), h(hi.velocity(s1)))
                };
                if x1 != x0 {
                    zk = exact_piece(zk, x1 - x0, kappa, h0, h1);
                }
                x0 = x1;
                h0 = h1;
            }
            xa = xb;
        }
        z[k + 1] = zk;
        zd[k + 1] = dq[k + 1] - kappa * dq[k + 1].abs() * zk / hs[k + 1];
    }
    (z, zd)
}

/// Advances `z` over one monotone piece of displacement `dx` along which `h`
/// goes linearly (in the displacement) from `ha` to `hb`. With `s = sgn(dx)`,
/// `ζ = s z` and the travelled distance `ξ ∈ [0, Δ]`, `Δ = |dx|`, the state
/// equation is `dζ/dξ = 1 − κ ζ / h(ξ)`; its exact solution for linear `h` is
///
/// ```text
/// ζ(Δ) = ρ ζ(0) + (Δ h_b / h_ℓ) φ(D / h_ℓ),   ρ = e^{−κΔ/h_ℓ},
/// D = κΔ + h_b − h_a,   φ(y) = (1 − e^{−y}) / y,
/// ```
///
/// `h_ℓ = (h_b − h_a) / ln(h_b/h_a)` the logarithmic mean. Every term is
/// bounded for any stiffness: for `κΔ/h → ∞` it tends to the steady state
/// with its lag, `ζ → Δ h_b / (κΔ + h_b − h_a)`; for constant `h` it is the
/// exponential relaxation to `h/κ`.
fn exact_piece(z: f64, dx: f64, kappa: f64, ha: f64, hb: f64) -> f64 {
    let sign = sgn(dx);
    let delta = dx.abs();
    let d = (hb - ha) / ha;
    // d / ln(1 + d) by its series where pieces keep h nearly constant
    // (|d| ≤ STATE_H_STEP for most pieces): the first omitted term,
    // 3 d⁵ / 160, is below 2e-17 at |d| = 1e-3, so this equals the
    // logarithm's value to rounding, at a fraction of its cost.
    let h_log = if d.abs() < 1e-3 {
        ha * (1.0 + d * (0.5 + d * (-1.0 / 12.0 + d * (1.0 / 24.0 - d * (19.0 / 720.0)))))
    } else {
        ha * d / d.ln_1p()
    };
    let rho = (-kappa * delta / h_log).exp();
    let y = (kappa * delta + hb - ha) / h_log;
    // φ(y) = −expm1(−y)/y, accurate near y = 0.
    let phi = if y.abs() < 1e-12 {
        1.0
    } else {
        -(-y).exp_m1() / y
    };
    sign * (rho * sign * z + delta * hb / h_log * phi)
}

// ---------------------------------------------------------------- Coulomb + viscous

/// Offset, Coulomb and viscous friction: `τ = f₀ + F_c sgn(v) + F_v v`.
///
/// The offset `f₀` absorbs a constant torque (gravity not removed, sensor
/// bias); `F_c ≥ 0`, `F_v ≥ 0`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoulombViscous {
    /// Constant offset `f₀`, N·m.
    pub offset: f64,
    /// Coulomb level `F_c`, N·m.
    pub coulomb: f64,
    /// Viscous coefficient `F_v`, N·m·s/rad.
    pub viscous: f64,
}

impl CoulombViscous {
    /// Builds the model from `[offset, Fc, Fv]`, checking the physical ranges.
    pub fn from_parameters(values: &[f64]) -> Result<Self, FrictionError> {
        check_params("coulomb_viscous", &Self::coefficient_info(), values)?;
        Ok(Self::from_parts(&[], values))
    }
}

impl FrictionModel for CoulombViscous {
    fn name(&self) -> &'static str {
        "coulomb_viscous"
    }
    fn parameter_info(&self) -> Vec<ParamInfo> {
        Self::coefficient_info()
    }
    fn parameters(&self) -> Vec<f64> {
        vec![self.offset, self.coulomb, self.viscous]
    }
    fn predict(&self, motion: &Track) -> Vec<f64> {
        motion
            .dq()
            .iter()
            .map(|&v| self.offset + self.coulomb * sgn(v) + self.viscous * v)
            .collect()
    }
}

impl Separable for CoulombViscous {
    fn structure_info() -> Vec<ParamInfo> {
        vec![]
    }
    fn coefficient_info() -> Vec<ParamInfo> {
        vec![OFFSET, FC, FV]
    }
    fn structure(&self) -> Vec<f64> {
        vec![]
    }
    fn coefficients(&self) -> Vec<f64> {
        self.parameters()
    }
    fn columns(_theta: &[f64], motion: &Track) -> Vec<Vec<f64>> {
        let dq = motion.dq();
        vec![
            vec![1.0; dq.len()],
            dq.iter().map(|&v| sgn(v)).collect(),
            dq.to_vec(),
        ]
    }
    fn from_parts(_theta: &[f64], beta: &[f64]) -> Self {
        Self {
            offset: beta[0],
            coulomb: beta[1],
            viscous: beta[2],
        }
    }
    fn from_vector(values: &[f64]) -> Self {
        Self::from_parts(&[], values)
    }
}

// ---------------------------------------------------------------- Stribeck

/// Static Stribeck friction with a continuous Stribeck velocity and shape:
/// `τ = f₀ + [F_c + (F_s − F_c) e^{−|v/v_s|^δ}] sgn(v) + F_v v`.
///
/// `δ = 2` is the Gaussian shape of the classical LuGre papers, `δ = 1`
/// Tustin's exponential; `δ` is fitted unless fixed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stribeck {
    /// Constant offset `f₀`, N·m.
    pub offset: f64,
    /// Coulomb level `F_c`, N·m.
    pub coulomb: f64,
    /// Static (breakaway) level `F_s`, N·m.
    pub static_friction: f64,
    /// Stribeck velocity `v_s`, rad/s.
    pub stribeck_velocity: f64,
    /// Shape exponent `δ`.
    pub shape: f64,
    /// Viscous coefficient `F_v`, N·m·s/rad.
    pub viscous: f64,
}

impl Stribeck {
    /// Builds the model from `[offset, Fc, Fs, vs, delta, Fv]`, checking the
    /// physical ranges.
    pub fn from_parameters(values: &[f64]) -> Result<Self, FrictionError> {
        check_params("stribeck", &STRIBECK_INFO, values)?;
        Ok(Self {
            offset: values[0],
            coulomb: values[1],
            static_friction: values[2],
            stribeck_velocity: values[3],
            shape: values[4],
            viscous: values[5],
        })
    }

    /// The steady-state friction `g(v) sgn(v) + F_v v + f₀` at one velocity.
    pub fn at(&self, v: f64) -> f64 {
        let g = stribeck_decay(v, self.stribeck_velocity, self.shape);
        self.offset
            + (self.coulomb + (self.static_friction - self.coulomb) * g) * sgn(v)
            + self.viscous * v
    }
}

const STRIBECK_INFO: [ParamInfo; 6] = [OFFSET, FC, FS, VS, DELTA, FV];

impl FrictionModel for Stribeck {
    fn name(&self) -> &'static str {
        "stribeck"
    }
    fn parameter_info(&self) -> Vec<ParamInfo> {
        STRIBECK_INFO.to_vec()
    }
    fn parameters(&self) -> Vec<f64> {
        vec![
            self.offset,
            self.coulomb,
            self.static_friction,
            self.stribeck_velocity,
            self.shape,
            self.viscous,
        ]
    }
    fn predict(&self, motion: &Track) -> Vec<f64> {
        motion.dq().iter().map(|&v| self.at(v)).collect()
    }
}

impl Separable for Stribeck {
    fn structure_info() -> Vec<ParamInfo> {
        vec![VS, DELTA]
    }
    fn coefficient_info() -> Vec<ParamInfo> {
        vec![OFFSET, FC, FS, FV]
    }
    fn structure(&self) -> Vec<f64> {
        vec![self.stribeck_velocity, self.shape]
    }
    fn coefficients(&self) -> Vec<f64> {
        vec![
            self.offset,
            self.coulomb,
            self.static_friction,
            self.viscous,
        ]
    }
    fn columns(theta: &[f64], motion: &Track) -> Vec<Vec<f64>> {
        let dq = motion.dq();
        let n = dq.len();
        let mut c = vec![vec![1.0; n], vec![0.0; n], vec![0.0; n], dq.to_vec()];
        for (i, &v) in dq.iter().enumerate() {
            let g = stribeck_decay(v, theta[0], theta[1]);
            c[1][i] = sgn(v) * (1.0 - g);
            c[2][i] = sgn(v) * g;
        }
        c
    }
    fn from_parts(theta: &[f64], beta: &[f64]) -> Self {
        Self {
            offset: beta[0],
            coulomb: beta[1],
            static_friction: beta[2],
            stribeck_velocity: theta[0],
            shape: theta[1],
            viscous: beta[3],
        }
    }
    fn from_vector(v: &[f64]) -> Self {
        Self {
            offset: v[0],
            coulomb: v[1],
            static_friction: v[2],
            stribeck_velocity: v[3],
            shape: v[4],
            viscous: v[5],
        }
    }
}

// ---------------------------------------------------------------- Dahl

/// Dahl's model (exponent 1) plus offset and viscous friction:
/// `dF/dt = σ₀ v (1 − F sgn(v) / F_c)`, `τ = f₀ + F + F_v v`.
///
/// `F` rises with stiffness `σ₀` after a reversal and saturates at `±F_c`
/// over the presliding displacement `x_d = F_c / σ₀`. The model is rate
/// independent: `F` depends on the path `q`, not on how fast it is travelled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Dahl {
    /// Constant offset `f₀`, N·m.
    pub offset: f64,
    /// Coulomb level `F_c`, N·m.
    pub coulomb: f64,
    /// Rest stiffness `σ₀`, N·m/rad.
    pub stiffness: f64,
    /// Viscous coefficient `F_v`, N·m·s/rad.
    pub viscous: f64,
}

const DAHL_INFO: [ParamInfo; 4] = [OFFSET, FC, SIGMA0, FV];
const PRESLIDE: ParamInfo = p("x_presliding", "rad", 1e-9, 1e3);

impl Dahl {
    /// Builds the model from `[offset, Fc, sigma0, Fv]`, checking the physical
    /// ranges.
    pub fn from_parameters(values: &[f64]) -> Result<Self, FrictionError> {
        check_params("dahl", &DAHL_INFO, values)?;
        Ok(Self {
            offset: values[0],
            coulomb: values[1],
            stiffness: values[2],
            viscous: values[3],
        })
    }

    /// The normalised state `w = F / F_c ∈ [−1, 1]` for a presliding
    /// displacement `x_d`.
    pub(crate) fn normalised_state(x_d: f64, motion: &Track) -> Vec<f64> {
        let (mut z, _) = integrate_state(motion, 1.0 / x_d, |_| 1.0);
        // z is in rad with steady state ±x_d; w = z / x_d.
        for v in &mut z {
            *v /= x_d;
        }
        z
    }
}

impl FrictionModel for Dahl {
    fn name(&self) -> &'static str {
        "dahl"
    }
    fn parameter_info(&self) -> Vec<ParamInfo> {
        DAHL_INFO.to_vec()
    }
    fn parameters(&self) -> Vec<f64> {
        vec![self.offset, self.coulomb, self.stiffness, self.viscous]
    }
    fn predict(&self, motion: &Track) -> Vec<f64> {
        if self.coulomb == 0.0 {
            return CoulombViscous::from_parts(&[], &[self.offset, 0.0, self.viscous])
                .predict(motion);
        }
        let x_d = self.coulomb / self.stiffness;
        let w = Self::normalised_state(x_d, motion);
        w.iter()
            .zip(motion.dq())
            .map(|(w, v)| self.offset + self.coulomb * w + self.viscous * v)
            .collect()
    }
}

impl Separable for Dahl {
    fn structure_info() -> Vec<ParamInfo> {
        vec![PRESLIDE]
    }
    fn coefficient_info() -> Vec<ParamInfo> {
        vec![OFFSET, FC, FV]
    }
    fn structure(&self) -> Vec<f64> {
        vec![self.coulomb / self.stiffness]
    }
    fn coefficients(&self) -> Vec<f64> {
        vec![self.offset, self.coulomb, self.viscous]
    }
    fn columns(theta: &[f64], motion: &Track) -> Vec<Vec<f64>> {
        vec![
            vec![1.0; motion.len()],
            Self::normalised_state(theta[0], motion),
            motion.dq().to_vec(),
        ]
    }
    fn from_parts(theta: &[f64], beta: &[f64]) -> Self {
        Self {
            offset: beta[0],
            coulomb: beta[1],
            stiffness: beta[1] / theta[0],
            viscous: beta[2],
        }
    }
    fn from_vector(v: &[f64]) -> Self {
        Self {
            offset: v[0],
            coulomb: v[1],
            stiffness: v[2],
            viscous: v[3],
        }
    }
}

// ---------------------------------------------------------------- LuGre

/// The LuGre model (Canudas de Wit et al. 1995) with a Stribeck shape
/// exponent and an offset:
///
/// ```text
/// dz/dt = v − σ₀ |v| z / g(v),   g(v) = F_c + (F_s − F_c) e^{−|v/v_s|^δ}
/// τ     = f₀ + σ₀ z + σ₁ dz/dt + σ₂ v
/// ```
///
/// In steady sliding `dz/dt = 0` and `τ = f₀ + g(v) sgn(v) + σ₂ v`: the
/// [`Stribeck`] curve with `F_v = σ₂`. Near rest `τ ≈ σ₀ x` for a small
/// displacement `x` from a relaxed state (presliding stiffness). The state is
/// integrated as described in the module docs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LuGre {
    /// Constant offset `f₀`, N·m.
    pub offset: f64,
    /// Coulomb level `F_c`, N·m (> 0).
    pub coulomb: f64,
    /// Static level `F_s`, N·m (> 0).
    pub static_friction: f64,
    /// Stribeck velocity `v_s`, rad/s.
    pub stribeck_velocity: f64,
    /// Shape exponent `δ` (2 in the original model).
    pub shape: f64,
    /// Bristle stiffness `σ₀`, N·m/rad.
    pub sigma0: f64,
    /// Bristle damping `σ₁`, N·m·s/rad.
    pub sigma1: f64,
    /// Viscous coefficient `σ₂`, N·m·s/rad.
    pub sigma2: f64,
}

const LUGRE_INFO: [ParamInfo; 8] = [OFFSET, FC, FS, VS, DELTA, SIGMA0, SIGMA1, SIGMA2];
const KAPPA: ParamInfo = p("kappa", "1/rad", 1e-6, 1e12);
const RATIO: ParamInfo = p("Fs_over_Fc", "1", 0.05, 20.0);

impl LuGre {
    /// Builds the model from `[offset, Fc, Fs, vs, delta, sigma0, sigma1,
    /// sigma2]`, checking the physical ranges (`F_c`, `F_s` must be positive).
    pub fn from_parameters(values: &[f64]) -> Result<Self, FrictionError> {
        check_params("lugre", &LUGRE_INFO, values)?;
        let m = Self {
            offset: values[0],
            coulomb: values[1],
            static_friction: values[2],
            stribeck_velocity: values[3],
            shape: values[4],
            sigma0: values[5],
            sigma1: values[6],
            sigma2: values[7],
        };
        let theta = m.structure();
        check_params("lugre", &[KAPPA, RATIO], &theta[..2])?;
        Ok(m)
    }

    /// Internal state `z` (rad) and its rate `dz/dt` at every sample.
    pub fn state(&self, motion: &Track) -> (Vec<f64>, Vec<f64>) {
        Self::state_for(&self.structure(), motion)
    }

    /// The state along `motion` for the structure `[κ, Fs/Fc, v_s, δ]`: the
    /// law ([`aras_core::LuGreLaw`]) normalised by `Fc` (level `g/Fc`,
    /// stiffness `κ = σ0/Fc`), whose bristle rate is the same.
    fn state_for(theta: &[f64], motion: &Track) -> (Vec<f64>, Vec<f64>) {
        let law = aras_core::LuGreLaw {
            coulomb: 1.0,
            static_level: theta[1],
            stribeck_velocity: theta[2],
            shape: theta[3],
            stiffness: theta[0],
        };
        integrate_state(motion, law.stiffness, |v| law.level(v))
    }

    /// The steady-state (Stribeck) curve of this model.
    pub fn steady_state(&self) -> Stribeck {
        Stribeck {
            offset: self.offset,
            coulomb: self.coulomb,
            static_friction: self.static_friction,
            stribeck_velocity: self.stribeck_velocity,
            shape: self.shape,
            viscous: self.sigma2,
        }
    }
}

impl FrictionModel for LuGre {
    fn name(&self) -> &'static str {
        "lugre"
    }
    fn parameter_info(&self) -> Vec<ParamInfo> {
        LUGRE_INFO.to_vec()
    }
    fn parameters(&self) -> Vec<f64> {
        vec![
            self.offset,
            self.coulomb,
            self.static_friction,
            self.stribeck_velocity,
            self.shape,
            self.sigma0,
            self.sigma1,
            self.sigma2,
        ]
    }
    fn predict(&self, motion: &Track) -> Vec<f64> {
        let (z, zd) = self.state(motion);
        z.iter()
            .zip(&zd)
            .zip(motion.dq())
            .map(|((z, zd), v)| self.offset + self.sigma0 * z + self.sigma1 * zd + self.sigma2 * v)
            .collect()
    }
}

impl Separable for LuGre {
    fn structure_info() -> Vec<ParamInfo> {
        vec![KAPPA, RATIO, VS, DELTA]
    }
    fn coefficient_info() -> Vec<ParamInfo> {
        vec![OFFSET, SIGMA0, SIGMA1, SIGMA2]
    }
    fn structure(&self) -> Vec<f64> {
        vec![
            self.sigma0 / self.coulomb,
            self.static_friction / self.coulomb,
            self.stribeck_velocity,
            self.shape,
        ]
    }
    fn coefficients(&self) -> Vec<f64> {
        vec![self.offset, self.sigma0, self.sigma1, self.sigma2]
    }
    fn columns(theta: &[f64], motion: &Track) -> Vec<Vec<f64>> {
        let (z, zd) = Self::state_for(theta, motion);
        vec![vec![1.0; motion.len()], z, zd, motion.dq().to_vec()]
    }
    fn from_parts(theta: &[f64], beta: &[f64]) -> Self {
        let coulomb = beta[1] / theta[0];
        Self {
            offset: beta[0],
            coulomb,
            static_friction: theta[1] * coulomb,
            stribeck_velocity: theta[2],
            shape: theta[3],
            sigma0: beta[1],
            sigma1: beta[2],
            sigma2: beta[3],
        }
    }
    fn from_vector(v: &[f64]) -> Self {
        Self {
            offset: v[0],
            coulomb: v[1],
            static_friction: v[2],
            stribeck_velocity: v[3],
            shape: v[4],
            sigma0: v[5],
            sigma1: v[6],
            sigma2: v[7],
        }
    }
}

/// Prediction `Φ(θ) β` of a separable model from its parts (the same as
/// [`FrictionModel::predict`] of [`Separable::from_parts`]).
pub fn predict_parts<M: Separable>(theta: &[f64], beta: &[f64], motion: &Track) -> Vec<f64> {
    combine(&M::columns(theta, motion), beta)
}
