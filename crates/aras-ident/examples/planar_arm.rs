//! `aras-ident` on a robot it knows nothing about: a 2-link planar arm in a
//! vertical plane with Coulomb + viscous friction at both joints.
//!
//! The arm's regressor is written by hand here and handed to `aras-ident`
//! through its [`LinearModel`] trait; the torques come from an independent
//! code path (recursive Newton–Euler on the rigid bodies, not the
//! regressor). Base parameters, OLS (in memory and streaming) and the
//! physically consistent SDP are `aras-ident`'s. Noise-free, the base
//! parameters are recovered to rounding error.
//!
//! ```text
//! cargo run --release -p aras-ident --example planar_arm
//! ```
//!
//! `aras-ident`'s test `tests/planar_arm.rs` runs the same code in CI.

use std::convert::Infallible;
use std::f64::consts::TAU;

use aras_ident::streaming::{RegressorStage, States};
use aras_ident::{BaseParameters, ConsistentLs, LinearModel, LinkLayout, ReducedLs};
use faer::Mat;

/// Gravity, m/s² (along −y).
const G: f64 = 9.81;
/// Length of link 1 (joint 1 to joint 2), m.
const L1: f64 = 0.3;

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

impl LinearModel for PlanarArm {
    type Error = Infallible;

    fn coordinates(&self) -> usize {
        2
    }

    fn outputs(&self) -> usize {
        2
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
        y.fill(0.0);
        let (s1, c1) = q[0].sin_cos();
        let (s2, c2) = q[1].sin_cos();
        let (st, ct) = (q[0] + q[1]).sin_cos();
        let mut set = |col: usize, t1: f64, t2: f64| {
            y[2 * col] = t1;
            y[2 * col + 1] = t2;
        };
        // Link 1: Izz, hx, hy.
        set(5, qdd[0], 0.0);
        set(6, G * c1, 0.0);
        set(7, -G * s1, 0.0);
        // Link 2: Izz, hx, hy.
        let a2 = qdd[0] + qdd[1];
        set(14, a2, a2);
        let coriolis = 2.0 * qd[0] * qd[1] + qd[1] * qd[1];
        let centripetal = qd[0] * qd[0];
        set(
            15,
            L1 * c2 * (2.0 * qdd[0] + qdd[1]) - L1 * s2 * coriolis + G * ct,
            L1 * c2 * qdd[0] + L1 * s2 * centripetal + G * ct,
        );
        set(
            16,
            -L1 * s2 * (2.0 * qdd[0] + qdd[1]) - L1 * c2 * coriolis - G * st,
            -L1 * s2 * qdd[0] + L1 * c2 * centripetal - G * st,
        );
        // Link 2's mass, carried at the end of link 1.
        set(18, L1 * L1 * qdd[0] + G * L1 * c1, 0.0);
        // Friction.
        set(19, qd[0].signum(), 0.0);
        set(20, qd[0], 0.0);
        set(21, 0.0, qd[1].signum());
        set(22, 0.0, qd[1]);
        Ok(())
    }
}

/// A periodic excitation: three harmonics per joint of a 5 s period,
/// exact rates.
pub fn excitation(t: f64) -> [[f64; 2]; 3] {
    let w = TAU / 5.0;
    let coef = [
        [(0.8, 0.3), (0.3, -0.2), (0.15, 0.1)],
        [(0.6, -0.4), (-0.35, 0.25), (0.2, 0.12)],
    ];
    let offset = [0.4, -0.6];
    let mut out = [[0.0; 2]; 3];
    for j in 0..2 {
        out[0][j] = offset[j];
        for (k, &(a, b)) in coef[j].iter().enumerate() {
            let kw = (k + 1) as f64 * w;
            let (s, c) = (kw * t).sin_cos();
            out[0][j] += a * s + b * c;
            out[1][j] += kw * (a * c - b * s);
            out[2][j] += -kw * kw * (a * s + b * c);
        }
    }
    out
}

/// What the example found.
#[derive(Debug)]
pub struct Outcome {
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

/// Simulates `samples` samples at 200 Hz and identifies the arm.
pub fn run(samples: usize) -> Result<Outcome, Box<dyn std::error::Error>> {
    let arm = Arm::example();
    let model = PlanarArm;
    let names = model.names();
    let beta = arm.standard();
    // States and torques (the "log"), one row group per joint.
    let mut st = [(); 4].map(|_| [Vec::new(), Vec::new()]);
    for i in 0..samples {
        let [q, qd, qdd] = excitation(i as f64 / 200.0);
        let tau = arm.torques(q, qd, qdd);
        for j in 0..2 {
            st[0][j].push(q[j]);
            st[1][j].push(qd[j]);
            st[2][j].push(qdd[j]);
            st[3][j].push(tau[j]);
        }
    }
    // Stacked regressor: joint 1's rows, then joint 2's.
    let mut w = Mat::<f64>::zeros(2 * samples, COLUMNS);
    let mut t = vec![0.0; 2 * samples];
    let mut y = vec![0.0; 2 * COLUMNS];
    for i in 0..samples {
        let q = [st[0][0][i], st[0][1][i]];
        let qd = [st[1][0][i], st[1][1][i]];
        let qdd = [st[2][0][i], st[2][1][i]];
        model.fill(&q, &qd, &qdd, &mut y)?;
        for j in 0..2 {
            for c in 0..COLUMNS {
                w[(j * samples + i, c)] = y[2 * c + j];
            }
            t[j * samples + i] = st[3][j][i];
        }
    }
    let base = BaseParameters::from_regressor(w.as_ref(), &names, 1e-8)?;
    let truth = base.to_base(&beta)?;
    let wb = base.base_regressor(w.as_ref())?;
    let reduced = ReducedLs::new(wb.as_ref(), &t, &base.base_names())?;
    let ols = reduced.ols()?.estimate;

    let mut stage = RegressorStage::new(model, &base)?;
    let states = States {
        x: [&st[0][0], &st[0][1]],
        x_dot: [&st[1][0], &st[1][1]],
        x_ddot: [&st[2][0], &st[2][1]],
        tau: [&st[3][0], &st[3][1]],
    };
    stage.push(&states)?;
    let streaming = stage.accumulator().ols()?.estimate;

    // The SDP: each link's pseudo-inertia PSD (67)–(69) with a reference
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
        base_names: base.expressions(),
        truth,
        ols,
        streaming,
        sdp: sol.base.clone(),
        sdp_status: sol.status,
        min_eigenvalues: sol.links.iter().map(|l| l.min_eigenvalue).collect(),
    })
}

#[allow(dead_code)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let o = run(2000)?;
    println!(
        "{:<40} {:>12} {:>12} {:>12}",
        "base parameter", "truth", "OLS", "SDP"
    );
    for i in 0..o.truth.len() {
        println!(
            "{:<40} {:>12.6} {:>12.6} {:>12.6}",
            o.base_names[i], o.truth[i], o.ols[i], o.sdp[i]
        );
    }
    println!(
        "SDP status {}, pseudo-inertia min eigenvalues {:?}",
        o.sdp_status, o.min_eigenvalues
    );
    Ok(())
}
