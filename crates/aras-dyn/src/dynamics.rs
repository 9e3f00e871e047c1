//! Direct (non-regressor) dynamics: inverse dynamics by virtual work (33),
//! the mass matrix (80), Coriolis/centrifugal and gravity terms, energies,
//! and forward dynamics.
//!
//! Everything here is in the base frame {0} as written in (33) and (80)
//! (`I_k⁰ = R_k I_k R_kᵀ`, `h_k⁰ = R_k h_k`), on purpose a different
//! computation from the link-frame regressor, so that `Y β` against
//! [`Dynamics::inverse`] is a real check.

use aras_kin::{Geometry, KinematicSample, Motion};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

use crate::regressor::Sign;
use crate::{DynError, Model, Params};

/// Largest number of extra-effect columns (all extras, cogging order 16).
const MAX_EXTRA_COLUMNS: usize = 2 + 2 + 2 + 3 + 4 * crate::params::MAX_COGGING_ORDER + 2;

/// The robot's dynamics for one validated parameter set.
#[derive(Debug, Clone)]
pub struct Dynamics {
    params: Params,
    geometry: Geometry,
    inertia: [Matrix3<f64>; 4],
    h: [Vector3<f64>; 4],
    gravity: Vector3<f64>,
    extras: Model,
    extras_beta: Vec<f64>,
}

impl Dynamics {
    /// Validates the parameters and prepares the per-link tensors.
    pub fn new(params: &Params) -> Result<Self, DynError> {
        params.validate()?;
        let geometry = params.geometry()?;
        let full = params.model()?;
        // Per-sample extras only: an effect with a state needs the motion's
        // history, which one sample does not have.
        let extra_effects: Vec<_> = full
            .effects()
            .iter()
            .filter(|e| !e.is_paper() && !e.is_stateful())
            .copied()
            .collect();
        let extras = Model::new(extra_effects, params.gravity)?;
        let extras_beta = params.standard_vector(&extras)?.as_slice().to_vec();
        Ok(Self {
            params: params.clone(),
            geometry,
            inertia: std::array::from_fn(|k| params.links[k].inertia()),
            h: std::array::from_fn(|k| params.links[k].h),
            gravity: params.gravity,
            extras,
            extras_beta,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The geometry.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// Kinematics at `(X, Ẋ, Ẍ)` for this robot's geometry.
    pub fn sample(&self, task: &Motion) -> Result<KinematicSample, DynError> {
        Ok(aras_kin::evaluate(&self.geometry, task)?)
    }

    /// `I_k⁰ = R_k I_k R_kᵀ` (30) and `h_k⁰ = R_k h_k`.
    #[inline(always)]
    fn base_frame(&self, s: &KinematicSample, k: usize) -> (Matrix3<f64>, Vector3<f64>) {
        let r = &s.rotations[k];
        (r * self.inertia[k] * r.transpose(), r * self.h[k])
    }

    /// Motor torques the links need, by virtual work (33):
    /// `J⁻ᵀ Σ_k J_ωkᵀ (I_k⁰ Ω̇_k + Ω_k × I_k⁰ Ω_k − h_k⁰ × g)` (N·m).
    pub fn link_torque(&self, s: &KinematicSample) -> Vector2<f64> {
        let mut acc = Vector2::zeros();
        for k in 0..4 {
            let (i0, h0) = self.base_frame(s, k);
            let w = &s.omega[k];
            let f = i0 * s.omega_dot[k] + w.cross(&(i0 * w)) - h0.cross(&self.gravity);
            acc += s.link_jacobians[k].tr_mul(&f);
        }
        s.jacobian.inverse().transpose() * acc
    }

    /// Friction `Fv θ̇ + Fc tanh(θ̇ / w)` with the parameters' widths; a joint
    /// whose width is 0 takes the given sign model (the exact sign of (49),
    /// or the simulator's smoothing) (N·m).
    pub fn friction_torque(&self, theta_dot: &Vector2<f64>, sign: Sign) -> Vector2<f64> {
        let f = &self.params.friction;
        let law = |j: usize| {
            let v = theta_dot[j];
            let w = f.width[j];
            if w > 0.0 {
                (v / w).tanh()
            } else {
                sign.eval(v)
            }
        };
        Vector2::new(
            f.viscous[0] * theta_dot[0] + f.coulomb[0] * law(0),
            f.viscous[1] * theta_dot[1] + f.coulomb[1] * law(1),
        )
    }

    /// Capstan elasticity `K_e θ` (50) (N·m).
    pub fn elastic_torque(&self, theta: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(
            self.params.elasticity[0] * theta[0],
            self.params.elasticity[1] * theta[1],
        )
    }

    /// Torque of the extra effects present in the parameters (N·m); zero
    /// if there are none. No allocation. An effect with a state
    /// ([`crate::Effect::is_stateful`]) is not included: one sample has no
    /// history ([`crate::Model::stacked`] evaluates it along a sequence).
    pub fn extra_torque(&self, s: &KinematicSample, sign: Sign) -> Vector2<f64> {
        let n = self.extras.columns();
        if n == 0 {
            return Vector2::zeros();
        }
        let mut buf = [0.0; 2 * MAX_EXTRA_COLUMNS];
        self.extras.fill_unchecked(s, sign, &mut buf[..2 * n]);
        let mut t = Vector2::zeros();
        for (j, b) in self.extras_beta.iter().enumerate() {
            t[0] += buf[2 * j] * b;
            t[1] += buf[2 * j + 1] * b;
        }
        t
    }

    /// Full inverse dynamics: links (33) + friction (the parameters' widths,
    /// the exact sign where a width is 0) +
    /// elasticity + extra effects, the direct counterpart of `Y β` (48).
    pub fn inverse(&self, s: &KinematicSample) -> Vector2<f64> {
        self.link_torque(s)
            + self.friction_torque(&s.joint.vel, Sign::Exact)
            + self.elastic_torque(&s.joint.pos)
            + self.extra_torque(s, Sign::Exact)
    }

    /// Task-space mass matrix `M(X) = Σ J_ωkᵀ I_k⁰ J_ωk` (80).
    pub fn mass_matrix(&self, s: &KinematicSample) -> Matrix2<f64> {
        let mut m = Matrix2::zeros();
        for k in 0..4 {
            let (i0, _) = self.base_frame(s, k);
            let jw = &s.link_jacobians[k];
            m += jw.tr_mul(&(i0 * jw));
        }
        m
    }

    /// Motor-space mass matrix `J⁻ᵀ M J⁻¹` (80).
    pub fn mass_matrix_motor(&self, s: &KinematicSample) -> Matrix2<f64> {
        let ji = s.jacobian.inverse();
        ji.transpose() * self.mass_matrix(s) * ji
    }

    /// Task-space Coriolis/centrifugal term
    /// `c(X, Ẋ) = Σ J_ωkᵀ (I_k⁰ J̇_ωk Ẋ + Ω_k × I_k⁰ Ω_k)` (ignores `s.task.acc`).
    pub fn coriolis(&self, s: &KinematicSample) -> Vector2<f64> {
        let mut c = Vector2::zeros();
        for k in 0..4 {
            let (i0, _) = self.base_frame(s, k);
            let w = &s.omega[k];
            let f = i0 * (s.link_jacobian_dots[k] * s.task.vel) + w.cross(&(i0 * w));
            c += s.link_jacobians[k].tr_mul(&f);
        }
        c
    }

    /// Task-space gravity term `Σ J_ωkᵀ (−h_k⁰ × g)`.
    pub fn gravity_torque(&self, s: &KinematicSample) -> Vector2<f64> {
        let mut g = Vector2::zeros();
        for k in 0..4 {
            let h0 = s.rotations[k] * self.h[k];
            g += s.link_jacobians[k].tr_mul(&(-h0.cross(&self.gravity)));
        }
        g
    }

    /// Kinetic energy `½ Σ Ω_kᵀ I_k⁰ Ω_k` (J).
    pub fn kinetic_energy(&self, s: &KinematicSample) -> f64 {
        (0..4)
            .map(|k| {
                let w = s.rotations[k].tr_mul(&s.omega[k]);
                0.5 * w.dot(&(self.inertia[k] * w))
            })
            .sum()
    }

    /// Potential energy of gravity `−Σ gᵀ R_k h_k` (J, zero at the RCM level).
    pub fn potential_energy(&self, s: &KinematicSample) -> f64 {
        -(0..4)
            .map(|k| self.gravity.dot(&(s.rotations[k] * self.h[k])))
            .sum::<f64>()
    }

    /// Forward dynamics with the paper's model: `Ẍ = M⁻¹(Jᵀ(τ − τ_f − τ_e
    /// − τ_extra) − c − g)`, friction with the exact sign.
    pub fn forward(
        &self,
        x: &Vector2<f64>,
        x_dot: &Vector2<f64>,
        tau: &Vector2<f64>,
    ) -> Result<Vector2<f64>, DynError> {
        let s = self.sample(&Motion::new(*x, *x_dot, Vector2::zeros()))?;
        let other = self.friction_torque(&s.joint.vel, Sign::Exact)
            + self.elastic_torque(&s.joint.pos)
            + self.extra_torque(&s, Sign::Exact);
        self.forward_links(&s, &(tau - other))
    }

    /// Rigid-body forward dynamics: the task acceleration produced by motor
    /// torques `tau_links` acting on the links alone, at the pose and rate
    /// of `s` (its `task.acc` is ignored). Errors if `M` is not positive
    /// definite.
    pub fn forward_links(
        &self,
        s: &KinematicSample,
        tau_links: &Vector2<f64>,
    ) -> Result<Vector2<f64>, DynError> {
        let (m, bias) = self.task_terms(s);
        let rhs = s.jacobian.matrix().transpose() * tau_links - bias;
        solve_spd(&m, &rhs).ok_or(DynError::NotPositiveDefinite {
            phi_deg: s.task.pos[0].to_degrees(),
            gamma_deg: s.task.pos[1].to_degrees(),
            det: m.determinant(),
            m11: m[(0, 0)],
        })
    }

    /// `M` and `c + g` in one pass (each `I_k⁰` computed once): the hot
    /// path of the simulator.
    #[inline]
    fn task_terms(&self, s: &KinematicSample) -> (Matrix2<f64>, Vector2<f64>) {
        let mut m = Matrix2::zeros();
        let mut bias = Vector2::zeros();
        for k in 0..4 {
            let (i0, h0) = self.base_frame(s, k);
            let jw = &s.link_jacobians[k];
            let w = &s.omega[k];
            m += jw.tr_mul(&(i0 * jw));
            let f = i0 * (s.link_jacobian_dots[k] * s.task.vel) + w.cross(&(i0 * w))
                - h0.cross(&self.gravity);
            bias += jw.tr_mul(&f);
        }
        (m, bias)
    }
}

/// Solves `M a = b` for a symmetric 2×2 `M`; `None` unless positive definite.
fn solve_spd(m: &Matrix2<f64>, b: &Vector2<f64>) -> Option<Vector2<f64>> {
    let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
    if !(m[(0, 0)] > 0.0 && det > 0.0 && det.is_finite()) {
        return None;
    }
    let a = Vector2::new(
        (m[(1, 1)] * b[0] - m[(0, 1)] * b[1]) / det,
        (m[(0, 0)] * b[1] - m[(1, 0)] * b[0]) / det,
    );
    a.iter().all(|v| v.is_finite()).then_some(a)
}
