//! Forward kinematics, inverse dynamics (RNEA) and the joint-torque
//! regressor, written once over the number type ([`Scalar`]): `f64` for
//! identification, dual numbers for the excitation design's exact
//! derivatives.
//!
//! Frames and vectors follow Featherstone's spatial algebra in body
//! coordinates: a body's velocity is `(ω, v)` with `v` the velocity of the
//! point at its frame's origin, its spatial acceleration `(ω̇, v̇ − ω × v)`
//! likewise, and gravity enters as an upward acceleration `−g` of the base.

use std::cell::RefCell;

use aras_excite::{Dual, Regressor};
use aras_ident::LinearModel;

use crate::error::UrdfError;
use crate::model::{LINK_COLUMNS, UrdfModel};
use crate::spatial::{
    M3, Scalar, V3, add, cross, cross_c, dot_c, lift, mat_mul, mul, mul_t, scale, scale_c, zero,
    zero3,
};

/// The pose of a body frame in the world: `x_world = R x_body + p`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose<T> {
    /// Rotation, row-major (`rotation[r][c]`); its columns are the body's
    /// axes in the world.
    pub rotation: [[T; 3]; 3],
    /// Position of the body frame's origin (m).
    pub translation: [T; 3],
}

/// One body's motion in its own frame, and its frame in its parent's.
#[derive(Debug, Clone, Copy)]
struct State<T> {
    /// The body frame in the parent frame: rotation and origin.
    r: M3<T>,
    p: V3<T>,
    /// Spatial velocity `(ω, v)` and acceleration `(ω̇, a)`.
    w: V3<T>,
    v: V3<T>,
    dw: V3<T>,
    dv: V3<T>,
    /// Spatial force `(n, f)` about the origin (RNEA's backward pass).
    n: V3<T>,
    f: V3<T>,
}

/// Scratch space for one evaluation, reused from sample to sample so that
/// the hot path does not allocate. One per thread; [`LinearModel::fill`]
/// and [`Regressor::fill_dual`] keep their own per thread.
#[derive(Debug, Clone, Default)]
pub struct Workspace<T> {
    states: Vec<State<T>>,
}

impl<T: Scalar> Workspace<T> {
    /// A workspace for `model` (it grows for a larger model on first use).
    pub fn new(model: &UrdfModel) -> Self {
        let mut w = Self { states: Vec::new() };
        w.ensure(model.dof());
        w
    }

    fn ensure(&mut self, n: usize) {
        if self.states.len() < n {
            let (z, z3) = (zero::<T>(), zero3::<T>());
            self.states.resize(
                n,
                State {
                    r: [[z; 3]; 3],
                    p: z3,
                    w: z3,
                    v: z3,
                    dw: z3,
                    dv: z3,
                    n: z3,
                    f: z3,
                },
            );
        }
    }
}

thread_local! {
    static SCRATCH: RefCell<Workspace<f64>> = const { RefCell::new(Workspace { states: Vec::new() }) };
    static SCRATCH_DUAL: RefCell<Workspace<Dual>> = const { RefCell::new(Workspace { states: Vec::new() }) };
}

/// `I x` for the inertia entries `i` in Pinocchio's order.
#[inline(always)]
fn inertia_apply<T: Scalar>(i: &[f64], x: V3<T>) -> V3<T> {
    [
        x[0] * i[0] + x[1] * i[1] + x[2] * i[3],
        x[0] * i[1] + x[1] * i[2] + x[2] * i[4],
        x[0] * i[3] + x[1] * i[4] + x[2] * i[5],
    ]
}

/// Friction above the Coulomb level at low speed per unit level: the
/// Coulomb law times `exp(−(q̇/v_s)²)`, the model's Stribeck column and the
/// diagnosis's candidate alike.
#[inline(always)]
pub(crate) fn stribeck<T: Scalar>(qd: T, w: f64, v_s: f64) -> T {
    let x = qd * (1.0 / v_s);
    coulomb(qd, w) * (-(x * x)).exp()
}

/// Sign of the rate with `sign(0) = 0`, or its smooth `tanh(q̇ / w)`.
#[inline(always)]
fn coulomb<T: Scalar>(qd: T, w: f64) -> T {
    if w > 0.0 {
        (qd * (1.0 / w)).tanh()
    } else {
        let r = qd.re();
        T::from(if r > 0.0 {
            1.0
        } else if r < 0.0 {
            -1.0
        } else {
            0.0
        })
    }
}

impl UrdfModel {
    fn check_state<T: Scalar>(
        &self,
        q: &[T],
        qd: &[T],
        qdd: &[T],
        out: (&'static str, usize, usize),
    ) -> Result<(), UrdfError> {
        let n = self.dof();
        for (what, v) in [("q", q), ("q_dot", qd), ("q_ddot", qdd)] {
            if v.len() != n {
                return Err(UrdfError::Dimension {
                    what,
                    expected: n,
                    found: v.len(),
                });
            }
            if let Some((index, x)) = v.iter().enumerate().find(|(_, x)| !x.re().is_finite()) {
                return Err(UrdfError::NonFinite {
                    what,
                    index,
                    value: x.re(),
                });
            }
        }
        let (what, expected, found) = out;
        if expected != found {
            return Err(UrdfError::Dimension {
                what,
                expected,
                found,
            });
        }
        Ok(())
    }

    /// Joint frames in their parents, velocities and accelerations of every
    /// body (with gravity as the base's upward acceleration if `gravity`).
    fn kinematics<T: Scalar>(
        &self,
        ws: &mut Workspace<T>,
        q: &[T],
        qd: &[T],
        qdd: &[T],
        gravity: bool,
    ) {
        ws.ensure(self.dof());
        let g = if gravity { self.gravity_root } else { [0.0; 3] };
        let base_dv: V3<T> = lift([-g[0], -g[1], -g[2]]);
        for (i, b) in self.bodies.iter().enumerate() {
            let (r, p) = if b.rotates {
                let (s, c) = q[i].sin_cos();
                let c1 = T::from(1.0) - c;
                let mut r = [[zero::<T>(); 3]; 3];
                for (k, row) in r.iter_mut().enumerate() {
                    for (l, e) in row.iter_mut().enumerate() {
                        *e = c * b.a[k][l] + s * b.b[k][l] + c1 * b.c[k][l];
                    }
                }
                (r, lift(b.p0))
            } else {
                let mut r = [[zero::<T>(); 3]; 3];
                for (k, row) in r.iter_mut().enumerate() {
                    for (l, e) in row.iter_mut().enumerate() {
                        *e = T::from(b.a[k][l]);
                    }
                }
                (r, add(lift(b.p0), scale_c(b.aa, q[i])))
            };
            let (w0, v0, dw0, dv0) = match b.parent {
                Some(k) => {
                    let s = &ws.states[k];
                    (s.w, s.v, s.dw, s.dv)
                }
                None => (zero3(), zero3(), zero3(), base_dv),
            };
            let mut w = mul_t(&r, w0);
            let mut v = mul_t(&r, add(v0, cross(w0, p)));
            let mut dw = mul_t(&r, dw0);
            let mut dv = mul_t(&r, add(dv0, cross(dw0, p)));
            let a = b.axis;
            if b.rotates {
                w = add(w, scale_c(a, qd[i]));
                let sq = scale_c(a, qd[i]);
                dw = add(add(dw, scale_c(a, qdd[i])), cross(w, sq));
                dv = add(dv, cross(v, sq));
            } else {
                v = add(v, scale_c(a, qd[i]));
                let sq = scale_c(a, qd[i]);
                dv = add(add(dv, scale_c(a, qdd[i])), cross(w, sq));
            }
            let s = &mut ws.states[i];
            s.r = r;
            s.p = p;
            s.w = w;
            s.v = v;
            s.dw = dw;
            s.dv = dv;
        }
    }

    /// The joint-torque regressor `Y(q, q̇, q̈)` (column-major
    /// `dof × parameter_count`: `y[dof · c + j]` is joint `j`'s entry of
    /// column `c`), in any number type, with the caller's workspace.
    pub fn regressor_with<T: Scalar>(
        &self,
        ws: &mut Workspace<T>,
        q: &[T],
        qd: &[T],
        qdd: &[T],
        y: &mut [T],
    ) -> Result<(), UrdfError> {
        self.check_state(
            q,
            qd,
            qdd,
            ("regressor", self.dof() * self.parameter_count(), y.len()),
        )?;
        self.regressor_unchecked(ws, q, qd, qdd, y);
        Ok(())
    }

    fn regressor_unchecked<T: Scalar>(
        &self,
        ws: &mut Workspace<T>,
        q: &[T],
        qd: &[T],
        qdd: &[T],
        y: &mut [T],
    ) {
        let n = self.dof();
        self.kinematics(ws, q, qd, qdd, true);
        y.fill(zero());
        const E: [V3<f64>; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        for i in 0..n {
            let s = &ws.states[i];
            let (w, v, dw, dv) = (s.w, s.v, s.dw, s.dv);
            // Body i's wrench (n, f) per unit of each standard parameter.
            let mut cols = [[zero3::<T>(); 2]; LINK_COLUMNS];
            cols[0] = [zero3(), add(dv, cross(w, v))];
            for (k, e) in E.iter().enumerate() {
                let ang = add(
                    add(cross_c(*e, dv), cross(w, cross_c(*e, v))),
                    cross(v, cross(w, lift(*e))),
                );
                let lin = add(cross(dw, lift(*e)), cross(w, cross(w, lift(*e))));
                cols[1 + k] = [ang, lin];
            }
            for k in 0..6 {
                let mut unit = [0.0; 6];
                unit[k] = 1.0;
                let ang = add(inertia_apply(&unit, dw), cross(w, inertia_apply(&unit, w)));
                cols[4 + k] = [ang, zero3()];
            }
            // Carried to every joint from i up to the root.
            let mut k = i;
            loop {
                let b = &self.bodies[k];
                for (c, col) in cols.iter().enumerate() {
                    let part = if b.rotates { col[0] } else { col[1] };
                    y[n * (LINK_COLUMNS * i + c) + k] = dot_c(b.axis, part);
                }
                let Some(parent) = b.parent else { break };
                let st = &ws.states[k];
                for col in cols.iter_mut() {
                    let f = mul(&st.r, col[1]);
                    col[0] = add(mul(&st.r, col[0]), cross(st.p, f));
                    col[1] = f;
                }
                k = parent;
            }
        }
        self.joint_columns_into(qd, qdd, |c, j, v| y[n * c + j] = v);
    }

    /// Writes the enabled per-joint columns' entries through `set(column,
    /// joint, value)`.
    fn joint_columns_into<T: Scalar>(
        &self,
        qd: &[T],
        qdd: &[T],
        mut set: impl FnMut(usize, usize, T),
    ) {
        let c = self.columns;
        for j in 0..self.dof() {
            let mut col = self.joint_base(j);
            let entries = [
                (c.viscous, qd[j]),
                (c.coulomb, coulomb(qd[j], self.widths[j])),
                (c.offset, T::from(1.0)),
                (c.armature, qdd[j]),
            ];
            for (on, v) in entries {
                if on {
                    set(col, j, v);
                    col += 1;
                }
            }
        }
        let first = self.dof() * (LINK_COLUMNS + c.count());
        for (k, &(j, v_s)) in self.stribeck.iter().enumerate() {
            set(first + k, j, stribeck(qd[j], self.widths[j], v_s));
        }
    }

    /// Joint torques by the recursive Newton–Euler algorithm for the
    /// standard parameters `params` (column order of
    /// [`parameter_names`](Self::parameter_names)), with the caller's
    /// workspace: the spatial inertias carry the motion out from the base,
    /// the wrenches back in. Independent of the regressor's columns.
    pub fn inverse_dynamics_with<T: Scalar>(
        &self,
        ws: &mut Workspace<T>,
        params: &[f64],
        q: &[T],
        qd: &[T],
        qdd: &[T],
        tau: &mut [T],
    ) -> Result<(), UrdfError> {
        self.check_state(q, qd, qdd, ("torques", self.dof(), tau.len()))?;
        self.check_parameters(params)?;
        self.rnea_unchecked(ws, params, q, qd, qdd, tau, true);
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn rnea_unchecked<T: Scalar>(
        &self,
        ws: &mut Workspace<T>,
        params: &[f64],
        q: &[T],
        qd: &[T],
        qdd: &[T],
        tau: &mut [T],
        gravity: bool,
    ) {
        let n = self.dof();
        self.kinematics(ws, q, qd, qdd, gravity);
        for i in 0..n {
            let pi = &params[LINK_COLUMNS * i..LINK_COLUMNS * (i + 1)];
            let (m, h, inertia) = (pi[0], [pi[1], pi[2], pi[3]], &pi[4..]);
            let s = &mut ws.states[i];
            let (w, v, dw, dv) = (s.w, s.v, s.dw, s.dv);
            // Momentum about the origin: k = I ω + h × v, l = m v + ω × h.
            let k = add(inertia_apply(inertia, w), cross_c(h, v));
            let l = add(scale(v, m), cross(w, lift(h)));
            s.n = add(
                add(inertia_apply(inertia, dw), cross_c(h, dv)),
                add(cross(w, k), cross(v, l)),
            );
            s.f = add(add(scale(dv, m), cross(dw, lift(h))), cross(w, l));
        }
        for i in (0..n).rev() {
            let b = &self.bodies[i];
            let (nn, ff, r, p) = {
                let s = &ws.states[i];
                (s.n, s.f, s.r, s.p)
            };
            tau[i] = dot_c(b.axis, if b.rotates { nn } else { ff });
            if let Some(parent) = b.parent {
                let f = mul(&r, ff);
                let nn = add(mul(&r, nn), cross(p, f));
                let s = &mut ws.states[parent];
                s.n = add(s.n, nn);
                s.f = add(s.f, f);
            }
        }
        self.joint_columns_into(qd, qdd, |c, j, v| tau[j] += v * params[c]);
    }

    /// A standard parameter vector of this model's length, every entry
    /// finite.
    pub(crate) fn check_parameters(&self, params: &[f64]) -> Result<(), UrdfError> {
        let np = self.parameter_count();
        if params.len() != np {
            return Err(UrdfError::Dimension {
                what: "parameters",
                expected: np,
                found: params.len(),
            });
        }
        if let Some((index, x)) = params.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(UrdfError::NonFinite {
                what: "parameters",
                index,
                value: *x,
            });
        }
        Ok(())
    }

    /// The joint-space mass matrix `M(q)` (row-major, `dof × dof`, armature
    /// included) and the bias `b(q, q̇) = τ(q, q̇, 0)` (gravity, Coriolis and
    /// centrifugal torques, friction) of `params`, so that the torques are
    /// `τ = M q̈ + b`: column `j` of `M` by RNEA without gravity at `q̇ = 0`,
    /// `q̈ = e_j`, less the same at `q̈ = 0` (the offset column).
    pub fn mass_matrix_and_bias(
        &self,
        ws: &mut Workspace<f64>,
        params: &[f64],
        q: &[f64],
        qd: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), UrdfError> {
        let n = self.dof();
        let mut bias = vec![0.0; n];
        let zero = vec![0.0; n];
        self.inverse_dynamics_with(ws, params, q, qd, &zero, &mut bias)?;
        let mut rest = vec![0.0; n];
        self.rnea_unchecked(ws, params, q, &zero, &zero, &mut rest, false);
        let mut m = vec![0.0; n * n];
        let mut e = zero.clone();
        let mut col = vec![0.0; n];
        for j in 0..n {
            e[j] = 1.0;
            self.rnea_unchecked(ws, params, q, &zero, &e, &mut col, false);
            e[j] = 0.0;
            for i in 0..n {
                m[i * n + j] = col[i] - rest[i];
            }
        }
        Ok((m, bias))
    }

    /// Joint accelerations `q̈ = M⁻¹ (τ − b)` under the torques `tau`
    /// (forward dynamics from the mass matrix,
    /// [`mass_matrix_and_bias`](Self::mass_matrix_and_bias), by Cholesky).
    /// A mass matrix that is not positive definite (parameters that are
    /// not physical) is an error.
    pub fn forward_dynamics(
        &self,
        ws: &mut Workspace<f64>,
        params: &[f64],
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
    ) -> Result<Vec<f64>, UrdfError> {
        let n = self.dof();
        if tau.len() != n {
            return Err(UrdfError::Dimension {
                what: "torques",
                expected: n,
                found: tau.len(),
            });
        }
        let (m, b) = self.mass_matrix_and_bias(ws, params, q, qd)?;
        let m = nalgebra::DMatrix::from_row_slice(n, n, &m);
        let rhs = nalgebra::DVector::from_iterator(n, tau.iter().zip(&b).map(|(t, b)| t - b));
        let chol = m.cholesky().ok_or_else(|| UrdfError::Setting {
            name: "parameters".into(),
            problem: "the mass matrix is not positive definite at this state: the \
                      parameters are not those of a physical robot"
                .into(),
        })?;
        Ok(chol.solve(&rhs).iter().copied().collect())
    }

    /// Joint torques by RNEA (see
    /// [`inverse_dynamics_with`](Self::inverse_dynamics_with)) for the
    /// standard parameters `params`, e.g. [`urdf_parameters`](Self::urdf_parameters).
    pub fn inverse_dynamics(
        &self,
        params: &[f64],
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
    ) -> Result<Vec<f64>, UrdfError> {
        let mut tau = vec![0.0; self.dof()];
        SCRATCH.with(|ws| {
            self.inverse_dynamics_with(&mut ws.borrow_mut(), params, q, qd, qdd, &mut tau)
        })?;
        Ok(tau)
    }

    /// The regressor in `f64` as a new column-major `dof × parameter_count`
    /// vector (see [`regressor_with`](Self::regressor_with)).
    pub fn regressor(&self, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<Vec<f64>, UrdfError> {
        let mut y = vec![0.0; self.dof() * self.parameter_count()];
        SCRATCH.with(|ws| self.regressor_with(&mut ws.borrow_mut(), q, qd, qdd, &mut y))?;
        Ok(y)
    }

    /// Poses in the world of every body frame (the joint frames, in joint
    /// order) at the positions `q`, in any number type, with the base
    /// placement of the settings.
    pub fn body_poses<T: Scalar>(&self, q: &[T]) -> Result<Vec<Pose<T>>, UrdfError> {
        self.check_state(q, q, q, ("poses", 0, 0))?;
        let mut ws = Workspace::<T>::new(self);
        let z = vec![zero::<T>(); self.dof()];
        self.kinematics(&mut ws, q, &z, &z, false);
        let base = Pose {
            rotation: self.base_rotation.map(|r| r.map(T::from)),
            translation: lift(self.base_translation),
        };
        let mut poses: Vec<Pose<T>> = Vec::with_capacity(self.dof());
        for (i, b) in self.bodies.iter().enumerate() {
            let parent = b.parent.map_or(base, |k| poses[k]);
            let s = &ws.states[i];
            poses.push(Pose {
                rotation: mat_mul(&parent.rotation, &s.r),
                translation: add(parent.translation, mul(&parent.rotation, s.p)),
            });
        }
        Ok(poses)
    }

    /// Gravity in the root link's frame (m/s²): the settings' world gravity
    /// turned by the base orientation.
    pub fn gravity_in_root(&self) -> [f64; 3] {
        self.gravity_root
    }
}

impl LinearModel for UrdfModel {
    type Error = UrdfError;

    fn coordinates(&self) -> usize {
        self.dof()
    }

    fn outputs(&self) -> usize {
        self.dof()
    }

    fn names(&self) -> Vec<String> {
        self.parameter_names()
    }

    fn columns(&self) -> usize {
        self.parameter_count()
    }

    fn fill(&self, q: &[f64], qd: &[f64], qdd: &[f64], rows: &mut [f64]) -> Result<(), UrdfError> {
        SCRATCH.with(|ws| self.regressor_with(&mut ws.borrow_mut(), q, qd, qdd, rows))
    }
}

impl Regressor for UrdfModel {
    fn fill_dual(
        &self,
        q: &[Dual],
        qd: &[Dual],
        qdd: &[Dual],
        rows: &mut [Dual],
    ) -> Result<(), UrdfError> {
        SCRATCH_DUAL.with(|ws| self.regressor_with(&mut ws.borrow_mut(), q, qd, qdd, rows))
    }
}
