//! The toolkit's robot-agnostic crates picked into another robot project: a
//! 2-link planar arm in a vertical plane with Coulomb + viscous friction at
//! both joints, which none of the crates knows.
//!
//! The arm's regressor is written by hand here, once, generic over the
//! number type, and handed to
//!
//! * `aras-excite` (its [`Regressor`] trait: the same [`LinearModel`] plus its
//!   rows in dual numbers), which
//!   designs the excitation (74)–(77) in joint coordinates;
//! * `aras-signal`, which processes the arm's log (angles and torques only)
//!   into `q, q̇, q̈` with [`JointCoordinates`];
//! * `aras-ident` (its [`LinearModel`] trait, the one the design uses too):
//!   base parameters, OLS in memory
//!   and streaming, and the physically consistent SDP.
//!
//! [`chain`] does the identification part for a planar chain of any number
//! of links (the test runs three): the regressor written once for `n`
//! links, base parameters, OLS in memory and streamed through
//! `aras-ident`'s stage with one row group per joint, and the SDP with one
//! pseudo-inertia per link.
//!
//! The torques of the log come from an independent code path (recursive
//! Newton–Euler on the rigid bodies, [`Arm::torques`]), not from the
//! regressor. Noise-free, the base parameters are recovered to rounding
//! error. Neither `aras-kin` nor `aras-dyn` is in this package's dependency
//! tree (`cargo tree -p planar-arm -e normal`; a test checks it).
//!
//! ```text
//! cargo run --release -p planar-arm
//! ```

use std::convert::Infallible;

pub mod chain;

use aras_excite::{DesignSettings, Dual, Limits, Regressor};
use aras_ident::streaming::{RegressorStage, States};
use aras_ident::{BaseParameters, ConsistentLs, LinearModel, LinkLayout, ReducedLs};
use aras_log::ReadOptions;
use aras_signal::{Bandwidth, JointCoordinates, OutputRows, PeriodSource, ProcessOptions};
use faer::Mat;
use nalgebra::Vector2;

use num_dual::DualNum;

/// Gravity, m/s² (along −y).
pub const G: f64 = 9.81;
/// Length of link 1 (joint 1 to joint 2), m.
pub const L1: f64 = 0.3;

/// One rigid link: mass, centre of mass in the link frame, central inertia
/// (principal axes along the link frame).
#[derive(Debug, Clone, Copy)]
pub struct Link {
    /// kg.
    pub mass: f64,
    /// m.
    pub com: [f64; 3],
    /// kg·m², about the centre of mass.
    pub central: [f64; 3],
}

impl Link {
    /// `Ixx, Ixy, Ixz, Iyy, Iyz, Izz` about the joint (tensor entries), then
    /// `h = m c`.
    fn standard(&self) -> [f64; 9] {
        let (m, c) = (self.mass, self.com);
        let r2 = c.iter().map(|v| v * v).sum::<f64>();
        let i = |a: usize, b: usize| {
            let delta = if a == b { 1.0 } else { 0.0 };
            m * (r2 * delta - c[a] * c[b]) + if a == b { self.central[a] } else { 0.0 }
        };
        [
            i(0, 0),
            i(0, 1),
            i(0, 2),
            i(1, 1),
            i(1, 2),
            i(2, 2),
            m * c[0],
            m * c[1],
            m * c[2],
        ]
    }
}

/// The arm's true parameters.
#[derive(Debug, Clone, Copy)]
pub struct Arm {
    /// Link 1 (joint 1 at the origin).
    pub l1: Link,
    /// Link 2 (joint 2 at distance [`L1`] along link 1's x axis).
    pub l2: Link,
    /// Coulomb level per joint, N·m.
    pub coulomb: [f64; 2],
    /// Viscous coefficient per joint, N·m·s/rad.
    pub viscous: [f64; 2],
}

impl Arm {
    /// The arm used by the example and its test.
    pub fn example() -> Self {
        Self {
            l1: Link {
                mass: 2.0,
                com: [0.15, 0.01, 0.0],
                central: [0.002, 0.016, 0.017],
            },
            l2: Link {
                mass: 1.2,
                com: [0.12, -0.015, 0.0],
                central: [0.001, 0.008, 0.0085],
            },
            coulomb: [0.3, 0.2],
            viscous: [0.12, 0.08],
        }
    }

    /// The standard parameter vector in [`PlanarArm`]'s column order.
    pub fn standard(&self) -> Vec<f64> {
        let mut v = Vec::with_capacity(COLUMNS);
        v.extend(self.l1.standard());
        v.extend(self.l2.standard());
        v.push(self.l2.mass);
        v.extend([
            self.coulomb[0],
            self.viscous[0],
            self.coulomb[1],
            self.viscous[1],
        ]);
        v
    }

    /// Joint torques by recursive Newton–Euler in the plane (independent
    /// of the regressor): gravity as an upward base acceleration, forces
    /// and moments about each joint, plus friction.
    pub fn torques(&self, q: [f64; 2], qd: [f64; 2], qdd: [f64; 2]) -> [f64; 2] {
        let rot = |a: f64, v: [f64; 2]| {
            let (s, c) = a.sin_cos();
            [c * v[0] - s * v[1], s * v[0] + c * v[1]]
        };
        let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
        // Acceleration of a point at `r` (world frame) from a frame whose
        // origin accelerates by `a0`, turning at ω, ω̇.
        let acc = |a0: [f64; 2], w: f64, wd: f64, r: [f64; 2]| {
            [
                a0[0] - wd * r[1] - w * w * r[0],
                a0[1] + wd * r[0] - w * w * r[1],
            ]
        };
        let a0 = [0.0, G];
        let (w1, wd1) = (qd[0], qdd[0]);
        let (w2, wd2) = (qd[0] + qd[1], qdd[0] + qdd[1]);
        let th2 = q[0] + q[1];
        let p2 = rot(q[0], [L1, 0.0]);
        let r1 = rot(q[0], [self.l1.com[0], self.l1.com[1]]);
        let r2 = rot(th2, [self.l2.com[0], self.l2.com[1]]);
        let a_p2 = acc(a0, w1, wd1, p2);
        let a_c1 = acc(a0, w1, wd1, r1);
        let a_c2 = acc(a_p2, w2, wd2, r2);
        let f2 = [self.l2.mass * a_c2[0], self.l2.mass * a_c2[1]];
        let n2 = self.l2.central[2] * wd2 + cross(r2, f2);
        let f1c = [self.l1.mass * a_c1[0], self.l1.mass * a_c1[1]];
        let n1 = self.l1.central[2] * wd1 + cross(r1, f1c) + n2 + cross(p2, f2);
        let friction = |j: usize| self.coulomb[j] * qd[j].signum() + self.viscous[j] * qd[j];
        [n1 + friction(0), n2 + friction(1)]
    }
}

/// Number of standard parameters: 9 per link, link 2's mass, 4 friction.
pub const COLUMNS: usize = 23;

/// The arm's regressor `τ = Y(q, q̇, q̈) β`, derived by hand from its
/// Lagrangian (joint angles `q1` absolute, `q2` relative).
#[derive(Debug, Clone, Copy)]
pub struct PlanarArm;

impl PlanarArm {
    /// The non-zero entries of `Y`, in any number type: `set(column, row 1,
    /// row 2)`. The Coulomb columns' sign has zero derivative.
    fn rows<T: DualNum<Primitive = f64> + Copy>(
        q: [T; 2],
        qd: [T; 2],
        qdd: [T; 2],
        mut set: impl FnMut(usize, T, T),
    ) {
        let zero = T::from(0.0);
        let (s1, c1) = (q[0].sin(), q[0].cos());
        let (s2, c2) = (q[1].sin(), q[1].cos());
        let (st, ct) = ((q[0] + q[1]).sin(), (q[0] + q[1]).cos());
        // Link 1: Izz, hx, hy.
        set(5, qdd[0], zero);
        set(6, c1 * G, zero);
        set(7, -s1 * G, zero);
        // Link 2: Izz, hx, hy.
        let a2 = qdd[0] + qdd[1];
        set(14, a2, a2);
        let coriolis = qd[0] * qd[1] * 2.0 + qd[1] * qd[1];
        let centripetal = qd[0] * qd[0];
        set(
            15,
            c2 * (qdd[0] * 2.0 + qdd[1]) * L1 - s2 * coriolis * L1 + ct * G,
            c2 * qdd[0] * L1 + s2 * centripetal * L1 + ct * G,
        );
        set(
            16,
            -s2 * (qdd[0] * 2.0 + qdd[1]) * L1 - c2 * coriolis * L1 - st * G,
            -s2 * qdd[0] * L1 + c2 * centripetal * L1 - st * G,
        );
        // Link 2's mass, carried at the end of link 1.
        set(18, qdd[0] * (L1 * L1) + c1 * (G * L1), zero);
        // Friction.
        let sign = |v: T| T::from(v.re().signum());
        set(19, sign(qd[0]), zero);
        set(20, qd[0], zero);
        set(21, zero, sign(qd[1]));
        set(22, zero, qd[1]);
    }

    fn fill_rows<T: DualNum<Primitive = f64> + Copy>(
        q: [T; 2],
        qd: [T; 2],
        qdd: [T; 2],
        y: &mut [T],
    ) {
        y.fill(T::from(0.0));
        Self::rows(q, qd, qdd, |col, t1, t2| {
            y[2 * col] = t1;
            y[2 * col + 1] = t2;
        });
    }
}

/// For `aras-ident`: rows of a sample, column names.
impl LinearModel for PlanarArm {
    type Error = Infallible;

    fn coordinates(&self) -> usize {
        2
    }

    fn outputs(&self) -> usize {
        2
    }

    fn columns(&self) -> usize {
        COLUMNS
    }

    fn names(&self) -> Vec<String> {
        let body = ["Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz", "hx", "hy", "hz"];
        let mut n: Vec<String> = ["L1", "L2"]
            .iter()
            .flat_map(|l| body.iter().map(move |b| format!("{l}.{b}")))
            .collect();
        n.extend(["L2.m", "Fc1", "Fv1", "Fc2", "Fv2"].map(String::from));
        n
    }

    fn fill(&self, q: &[f64], qd: &[f64], qdd: &[f64], y: &mut [f64]) -> Result<(), Infallible> {
        Self::fill_rows([q[0], q[1]], [qd[0], qd[1]], [qdd[0], qdd[1]], y);
        Ok(())
    }
}

/// For `aras-excite`: the same rows in dual numbers (the `f64` rows are the
/// [`LinearModel`]'s).
impl Regressor for PlanarArm {
    fn fill_dual(
        &self,
        q: &[Dual],
        q_dot: &[Dual],
        q_ddot: &[Dual],
        rows: &mut [Dual],
    ) -> Result<(), Infallible> {
        let a = |v: &[Dual]| [v[0], v[1]];
        Self::fill_rows(a(q), a(q_dot), a(q_ddot), rows);
        Ok(())
    }
}

/// How the example runs: the excitation's period and design effort, the
/// log's rate and length.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Excitation period (s).
    pub period_s: f64,
    /// Harmonics of the excitation.
    pub harmonics: usize,
    /// Random feasible starts of the design.
    pub starts: usize,
    /// Log rate (Hz).
    pub rate_hz: f64,
    /// Periods logged.
    pub periods: usize,
}

impl Default for Settings {
    /// 5 s period, 3 harmonics, 2 starts, 200 Hz, 2 periods.
    fn default() -> Self {
        Self {
            period_s: 5.0,
            harmonics: 3,
            starts: 2,
            rate_hz: 200.0,
            periods: 2,
        }
    }
}

/// What the example found.
#[derive(Debug)]
pub struct Outcome {
    /// Condition number of the designed excitation's scaled base regressor.
    pub condition_number: f64,
    /// The processing's account of the bandwidth it chose.
    pub bandwidth: String,
    /// Largest error of the processed `q̈` against the trajectory's exact
    /// one (rad/s²).
    pub max_accel_error: f64,
    /// The base parameters' definitions.
    pub base_names: Vec<String>,
    /// True base parameters.
    pub truth: Vec<f64>,
    /// OLS on the stacked base regressor in memory.
    pub ols: Vec<f64>,
    /// OLS from the streaming accumulation of the same samples.
    pub streaming: Vec<f64>,
    /// The physically consistent estimate's base parameters.
    pub sdp: Vec<f64>,
    /// The SDP's solver status.
    pub sdp_status: aras_ident::SolverStatus,
    /// Smallest pseudo-inertia eigenvalue per link of the SDP estimate.
    pub min_eigenvalues: Vec<f64>,
}

/// The joint box and limits of the excitation: `q1 ∈ [−0.6, 1.4]`,
/// `q2 ∈ [−1.8, 0.6]` rad, 3 rad/s, 12 rad/s².
pub fn limits() -> Limits {
    Limits {
        min: Vector2::new(-0.6, -1.8),
        max: Vector2::new(1.4, 0.6),
        max_rate: Vector2::new(3.0, 3.0),
        max_accel: Vector2::new(12.0, 12.0),
    }
}

/// Base parameters of the arm from 300 pseudo-random states (the
/// dependencies are structural, so any rich set of states finds them).
pub fn base_parameters() -> Result<BaseParameters, aras_ident::IdentError> {
    base_parameters_of(&PlanarArm, 300)
}

/// The stacked regressor of `model` on per-coordinate columns `x, ẋ, ẍ`
/// (one slice per coordinate, all of one length): output 1's rows, then
/// output 2's, … (`aras-ident`'s output-major layout).
pub fn stacked_regressor<M: LinearModel<Error = Infallible>>(
    model: &M,
    x: &[&[f64]],
    x_dot: &[&[f64]],
    x_ddot: &[&[f64]],
) -> Mat<f64> {
    let (m, cols) = (model.outputs(), model.columns());
    let samples = x.first().map_or(0, |c| c.len());
    let mut w = Mat::<f64>::zeros(m * samples, cols);
    let mut y = vec![0.0; m * cols];
    let at = |v: &[&[f64]], i: usize| -> Vec<f64> { v.iter().map(|c| c[i]).collect() };
    for i in 0..samples {
        let Ok(()) = model.fill(&at(x, i), &at(x_dot, i), &at(x_ddot, i), &mut y);
        for j in 0..m {
            for c in 0..cols {
                w[(j * samples + i, c)] = y[m * c + j];
            }
        }
    }
    w
}

/// Slices of per-coordinate columns, as [`stacked_regressor`] and
/// `aras-ident`'s streaming stage take them.
pub fn views(columns: &[Vec<f64>]) -> Vec<&[f64]> {
    columns.iter().map(Vec::as_slice).collect()
}

/// Base parameters of any of this example's models from `samples`
/// pseudo-random states: `q` within ±1.5 rad, `q̇` ±3 rad/s, `q̈` ±10 rad/s².
pub fn base_parameters_of<M: LinearModel<Error = Infallible>>(
    model: &M,
    samples: usize,
) -> Result<BaseParameters, aras_ident::IdentError> {
    let dims = model.coordinates();
    let mut u = 0.5f64;
    let mut next = || {
        // A fixed additive-recurrence sequence: deterministic, no seed.
        u = (u + 0.618_033_988_749_895) % 1.0;
        2.0 * u - 1.0
    };
    // Per sample: q, then q̇, then q̈, each over the coordinates.
    let mut states = vec![vec![Vec::with_capacity(samples); dims]; 3];
    for _ in 0..samples {
        for (state, scale) in states.iter_mut().zip([1.5, 3.0, 10.0]) {
            for column in state.iter_mut() {
                column.push(scale * next());
            }
        }
    }
    let [x, xd, xdd] = [0, 1, 2].map(|k| views(&states[k]));
    let w = stacked_regressor(model, &x, &xd, &xdd);
    BaseParameters::from_regressor(w.as_ref(), &model.names(), 1e-8)
}

/// Designs the excitation, logs the arm along it (angles and Newton–Euler
/// torques as CSV text, no derivative columns), processes the log and
/// identifies the arm.
pub fn run(settings: &Settings) -> Result<Outcome, Box<dyn std::error::Error>> {
    let arm = Arm::example();
    let model = PlanarArm;
    let names = LinearModel::names(&model);
    let beta = arm.standard();

    // 1. Base parameters and the excitation designed on them.
    let base = base_parameters()?;
    let design = aras_excite::design(
        &model,
        &aras_excite::base_projection(&base),
        &DesignSettings {
            harmonics: settings.harmonics,
            omega_f: std::f64::consts::TAU / settings.period_s,
            limits: limits(),
            starts: settings.starts,
            ..DesignSettings::default()
        },
    )?;
    let traj = &design.trajectory;

    // 2. The log: samples half a step off the period boundary, where the
    // design puts q̇ = 0 (so no sample sits on a Coulomb reversal).
    let dt = 1.0 / settings.rate_hz;
    let n = (settings.periods as f64 * settings.period_s * settings.rate_hz).round() as usize;
    let mut csv = String::from("t,theta1,theta2,tau1,tau2\n");
    let mut exact_accel = Vec::with_capacity(n);
    for i in 0..n {
        let t = (i as f64 + 0.5) * dt;
        let s = traj.eval(t);
        let tau = arm.torques(s.pos.into(), s.vel.into(), s.acc.into());
        csv += &format!("{t},{},{},{},{}\n", s.pos[0], s.pos[1], tau[0], tau[1]);
        exact_accel.push(s.acc);
    }

    // 3. Processing: the known period gives a harmonic series up to the
    // noise floor; every row is kept.
    let log = aras_log::read_log_from(csv.as_bytes(), "planar-arm.csv", &ReadOptions::default())?;
    let processed = aras_signal::process(
        &log,
        &ProcessOptions {
            filter: Bandwidth::Auto,
            period: PeriodSource::Seconds(settings.period_s),
            rows: OutputRows::EveryRow,
            ..ProcessOptions::default()
        },
        &JointCoordinates,
    )?;
    let s = &processed.samples;
    let rows = s.len();
    let max_accel_error = (0..rows)
        .flat_map(|i| (0..2).map(move |j| (i, j)))
        .map(|(i, j)| (s.x_ddot[j][i] - exact_accel[i][j]).abs())
        .fold(0.0, f64::max);

    // 4. Stacked regressor from the processed samples: joint 1's rows, then
    // joint 2's; the torques are the log's.
    let w = stacked_regressor(&model, &views(&s.x), &views(&s.x_dot), &views(&s.x_ddot));
    let t = s.tau.concat();
    let truth = base.to_base(&beta)?;
    let wb = base.base_regressor(w.as_ref())?;
    let reduced = ReducedLs::new(wb.as_ref(), &t, &base.base_names())?;
    let ols = reduced.ols()?.estimate;

    let mut stage = RegressorStage::new(model, &base)?;
    stage.push(&States {
        x: &[&s.x[0], &s.x[1]],
        x_dot: &[&s.x_dot[0], &s.x_dot[1]],
        x_ddot: &[&s.x_ddot[0], &s.x_ddot[1]],
        tau: &[&s.tau[0], &s.tau[1]],
    })?;
    let streaming = stage.accumulator().ols()?.estimate;

    // 5. The SDP: each link's pseudo-inertia PSD (67)–(69) with a reference
    // 10 % off the truth, link 2's mass column within ±50 %, friction ≥ 0.
    let reference: Vec<f64> = beta.iter().map(|v| 1.1 * v).collect();
    let mut problem = ConsistentLs::new(&names, reference)?;
    problem
        .link(LinkLayout::new(
            "L1",
            [0, 1, 2, 3, 4, 5],
            [6, 7, 8],
            arm.l1.mass,
        ))?
        .link(LinkLayout::new(
            "L2",
            [9, 10, 11, 12, 13, 14],
            [15, 16, 17],
            arm.l2.mass,
        ))?
        .bound(18, 0.5 * arm.l2.mass, 1.5 * arm.l2.mass)?
        .nonnegative(&["Fc1", "Fv1", "Fc2", "Fv2"])?;
    let sol = problem.solve(&base, &reduced)?;
    Ok(Outcome {
        condition_number: design.assessment.condition_number,
        bandwidth: processed.summary.bandwidth.reason.clone(),
        max_accel_error,
        base_names: base.expressions(),
        truth,
        ols,
        streaming,
        sdp: sol.base.clone(),
        sdp_status: sol.status,
        min_eigenvalues: sol.links.iter().map(|l| l.min_eigenvalue).collect(),
    })
}
