//! A planar serial chain of any number of links in a vertical plane, with
//! Coulomb + viscous friction at every joint: the proof that identification
//! (in memory, streaming and physically consistent) is not bound to two
//! joints.
//!
//! The regressor is written once for `n` links from the Newton–Euler
//! equations in their linear form: link `i`'s inertial wrench about its
//! joint is linear in its standard parameters `(I_O, h = m c, m)`, and the
//! torque at joint `j ≤ i` is that wrench carried to joint `j`. The torques
//! the identification fits come from another code path, [`Chain::torques`]:
//! a backward recursion over the links' centres of mass and central
//! inertias, which never forms `h` or `I_O`.
//!
//! The excitation is designed by `aras-excite` for the chain's joints (one
//! Fourier series per joint, per-joint box, rate and acceleration limits).
//! [`identify`] samples it exactly; [`identify_log`] takes the way of a
//! measured log: an `aras-log` CSV with one angle and one torque column per
//! joint, read by `aras-log`, processed by `aras-signal` in joint
//! coordinates of run-time dimension and streamed through the base
//! regressor; [`diagnose_logs`] names an effect the model lacks with
//! `aras-diagnose`'s engine (the pipeline's), one output group per joint.

#![allow(clippy::needless_range_loop)] // index loops mirror the equations

use std::convert::Infallible;

use aras_excite::{DesignSettings, Dual, FourierTrajectory, Limits, Regressor};
use aras_ident::streaming::{RegressorStage, States};
use aras_ident::{ConsistentLs, LinearModel, LinkLayout, ReducedLs};
use aras_log::ReadOptions;
use aras_signal::{Bandwidth, JointCoordinates, PeriodSource, ProcessOptions};
use nalgebra::{DVector, Dyn};
use num_dual::DualNum;

use crate::{G, Link, views};

/// Standard parameters per link: `Ixx, Ixy, Ixz, Iyy, Iyz, Izz` about the
/// joint, `hx, hy, hz`, `m`.
pub const LINK_COLUMNS: usize = 10;

/// Friction parameters per joint: `Fc`, `Fv`.
pub const JOINT_COLUMNS: usize = 2;

/// A planar chain: link `i` turns about joint `i` (angle `q_i` relative to
/// link `i − 1`) and carries joint `i + 1` at `length[i]` along its x axis.
#[derive(Debug, Clone)]
pub struct Chain {
    /// The links, base first.
    pub links: Vec<Link>,
    /// Joint-to-joint length of each link (m); the last is unused.
    pub length: Vec<f64>,
    /// Coulomb level per joint (N·m).
    pub coulomb: Vec<f64>,
    /// Viscous coefficient per joint (N·m·s/rad).
    pub viscous: Vec<f64>,
    /// Joint springs `τ_j += k_j q_j` (N·m/rad): not in the model's
    /// regressor, the effect the diagnosis test hides (zero by default).
    pub spring: Vec<f64>,
}

impl Chain {
    /// A 3-link chain of decreasing links, used by the example's test.
    pub fn three_links() -> Self {
        Self {
            links: vec![
                Link {
                    mass: 2.2,
                    com: [0.14, 0.012, 0.0],
                    central: [0.002, 0.017, 0.018],
                },
                Link {
                    mass: 1.4,
                    com: [0.11, -0.01, 0.0],
                    central: [0.0012, 0.009, 0.0095],
                },
                Link {
                    mass: 0.7,
                    com: [0.07, 0.008, 0.0],
                    central: [0.0006, 0.003, 0.0032],
                },
            ],
            length: vec![0.3, 0.25, 0.15],
            coulomb: vec![0.3, 0.2, 0.1],
            viscous: vec![0.12, 0.08, 0.05],
            spring: vec![0.0; 3],
        }
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.links.len()
    }

    /// The regressor of this chain's geometry (lengths only).
    pub fn model(&self) -> ChainModel {
        ChainModel {
            length: self.length.clone(),
        }
    }

    /// The standard parameter vector in [`ChainModel`]'s column order.
    pub fn standard(&self) -> Vec<f64> {
        let mut v = Vec::new();
        for l in &self.links {
            v.extend(l.standard());
            v.push(l.mass);
        }
        for j in 0..self.joints() {
            v.extend([self.coulomb[j], self.viscous[j]]);
        }
        v
    }

    /// Joint torques of the motion `q, q̇, q̈` by a backward recursion over
    /// the centres of mass (independent of the regressor), plus friction.
    pub fn torques(&self, q: &[f64], qd: &[f64], qdd: &[f64]) -> Vec<f64> {
        let n = self.joints();
        let k = kinematics(&self.length, q, qd, qdd);
        let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
        let (mut f, mut moment) = ([0.0; 2], 0.0);
        let mut tau = vec![0.0; n];
        for i in (0..n).rev() {
            let l = &self.links[i];
            let (u, v) = (k.u[i], k.v[i]);
            // Centre of mass relative to the joint, world frame.
            let r = [
                l.com[0] * u[0] + l.com[1] * v[0],
                l.com[0] * u[1] + l.com[1] * v[1],
            ];
            let (w, wd) = (k.omega[i], k.alpha[i]);
            let a_c = [
                k.accel[i][0] - wd * r[1] - w * w * r[0],
                k.accel[i][1] + wd * r[0] - w * w * r[1],
            ];
            let own = [l.mass * a_c[0], l.mass * a_c[1]];
            // The child's force acts at joint i + 1.
            let to_child = [k.pos[i + 1][0] - k.pos[i][0], k.pos[i + 1][1] - k.pos[i][1]];
            moment = l.central[2] * wd + cross(r, own) + moment + cross(to_child, f);
            f = [own[0] + f[0], own[1] + f[1]];
            tau[i] = moment
                + self.coulomb[i] * qd[i].signum()
                + self.viscous[i] * qd[i]
                + self.spring.get(i).map_or(0.0, |k| k * q[i]);
        }
        tau
    }
}

/// Positions, frames and accelerations of the joints of a planar chain, in
/// any number type (dual numbers for the excitation design's derivatives).
struct Kinematics<T> {
    /// Joint positions `p_i` (and the tip, `p_n`).
    pos: Vec<[T; 2]>,
    /// Link x axes `u_i` and y axes `v_i` (world).
    u: Vec<[T; 2]>,
    v: Vec<[T; 2]>,
    /// Absolute rates and accelerations of the links.
    omega: Vec<T>,
    alpha: Vec<T>,
    /// Acceleration of each joint's origin plus gravity's upward one.
    accel: Vec<[T; 2]>,
}

fn kinematics<T: DualNum<Primitive = f64> + Copy>(
    length: &[f64],
    q: &[T],
    qd: &[T],
    qdd: &[T],
) -> Kinematics<T> {
    let n = q.len();
    let zero = T::from(0.0);
    let mut k = Kinematics {
        pos: vec![[zero; 2]],
        u: Vec::with_capacity(n),
        v: Vec::with_capacity(n),
        omega: Vec::with_capacity(n),
        alpha: Vec::with_capacity(n),
        accel: vec![[zero, T::from(G)]],
    };
    let (mut theta, mut w, mut wd) = (zero, zero, zero);
    for i in 0..n {
        theta += q[i];
        w += qd[i];
        wd += qdd[i];
        let (s, c) = (theta.sin(), theta.cos());
        let (u, v) = ([c, s], [-s, c]);
        let (p, a) = (k.pos[i], k.accel[i]);
        let l = length[i];
        k.pos.push([p[0] + u[0] * l, p[1] + u[1] * l]);
        k.accel.push([
            a[0] + (wd * v[0] - w * w * u[0]) * l,
            a[1] + (wd * v[1] - w * w * u[1]) * l,
        ]);
        k.u.push(u);
        k.v.push(v);
        k.omega.push(w);
        k.alpha.push(wd);
    }
    k
}

/// The regressor `τ = Y(q, q̇, q̈) β` of a planar chain, as `aras-ident`'s
/// [`LinearModel`]: `n` coordinates, `n` outputs, [`LINK_COLUMNS`] per link
/// then [`JOINT_COLUMNS`] per joint.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainModel {
    length: Vec<f64>,
}

impl LinearModel for ChainModel {
    type Error = Infallible;

    fn coordinates(&self) -> usize {
        self.length.len()
    }

    fn outputs(&self) -> usize {
        self.length.len()
    }

    fn columns(&self) -> usize {
        (LINK_COLUMNS + JOINT_COLUMNS) * self.length.len()
    }

    fn names(&self) -> Vec<String> {
        let body = [
            "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz", "hx", "hy", "hz", "m",
        ];
        let n = self.length.len();
        let mut names: Vec<String> = (1..=n)
            .flat_map(|i| body.iter().map(move |b| format!("L{i}.{b}")))
            .collect();
        names.extend((1..=n).flat_map(|j| [format!("Fc{j}"), format!("Fv{j}")]));
        names
    }

    fn fill(&self, q: &[f64], qd: &[f64], qdd: &[f64], y: &mut [f64]) -> Result<(), Infallible> {
        self.rows(q, qd, qdd, y);
        Ok(())
    }
}

/// For `aras-excite`: the same rows in dual numbers.
impl Regressor for ChainModel {
    fn fill_dual(
        &self,
        q: &[Dual],
        qd: &[Dual],
        qdd: &[Dual],
        y: &mut [Dual],
    ) -> Result<(), Infallible> {
        self.rows(q, qd, qdd, y);
        Ok(())
    }
}

impl ChainModel {
    /// Every entry of `Y` (column-major `n × columns`) in any number type;
    /// the Coulomb columns' sign has zero derivative.
    fn rows<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], qd: &[T], qdd: &[T], y: &mut [T]) {
        let n = self.length.len();
        let k = kinematics(&self.length, q, qd, qdd);
        let cross = |a: [T; 2], b: [T; 2]| a[0] * b[1] - a[1] * b[0];
        y.fill(T::from(0.0));
        let mut set = |col: usize, j: usize, v: T| y[n * col + j] = v;
        for i in 0..n {
            let (u, v, a) = (k.u[i], k.v[i], k.accel[i]);
            let (w, wd) = (k.omega[i], k.alpha[i]);
            // The force on link i per unit hx, hy and m.
            let fx = [wd * v[0] - w * w * u[0], wd * v[1] - w * w * u[1]];
            let fy = [-wd * u[0] - w * w * v[0], -wd * u[1] - w * w * v[1]];
            let base = i * LINK_COLUMNS;
            for j in 0..=i {
                let r = [k.pos[i][0] - k.pos[j][0], k.pos[i][1] - k.pos[j][1]];
                set(base + 5, j, wd);
                set(base + 6, j, cross(u, a) + cross(r, fx));
                set(base + 7, j, cross(v, a) + cross(r, fy));
                set(base + 9, j, cross(r, a));
            }
        }
        let friction = LINK_COLUMNS * n;
        for j in 0..n {
            set(friction + 2 * j, j, T::from(qd[j].re().signum()));
            set(friction + 2 * j + 1, j, qd[j]);
        }
    }
}

/// What [`identify`] found for a chain.
#[derive(Debug)]
pub struct ChainOutcome {
    /// Condition number of the designed excitation's scaled base regressor.
    pub condition_number: f64,
    /// The median of the same over random feasible trajectories.
    pub random_condition_median: f64,
    /// The base parameters' definitions.
    pub base_names: Vec<String>,
    /// True base parameters.
    pub truth: Vec<f64>,
    /// OLS on the stacked base regressor in memory.
    pub ols: Vec<f64>,
    /// OLS from the streaming accumulation of the same samples.
    pub streaming: Vec<f64>,
    /// Rows the streaming stage accumulated per joint.
    pub streaming_rows: Vec<usize>,
    /// The physically consistent estimate's base parameters.
    pub sdp: Vec<f64>,
    /// The SDP's solver status.
    pub sdp_status: aras_ident::SolverStatus,
    /// Smallest pseudo-inertia eigenvalue per link of the SDP estimate.
    pub min_eigenvalues: Vec<f64>,
    /// The designed excitation.
    pub trajectory: FourierTrajectory<Dyn>,
}

/// The excitation's limits for `joints` joints: every joint within
/// ±0.9 rad of its offset (the first from −0.6 to 1.2 rad), 3 rad/s,
/// 12 rad/s².
pub fn limits(joints: usize) -> Limits<Dyn> {
    let v = |f: &dyn Fn(usize) -> f64| DVector::from_fn(joints, |i, _| f(i));
    Limits {
        min: v(&|i| if i == 0 { -0.6 } else { -0.9 }),
        max: v(&|i| if i == 0 { 1.2 } else { 0.9 }),
        max_rate: v(&|_| 3.0),
        max_accel: v(&|_| 12.0),
    }
}

/// Designs the excitation of `chain` (3 harmonics, 5 s period, 6 starts) and
/// identifies the chain from `samples` samples of two periods of it
/// (noise-free torques from [`Chain::torques`]): base parameters, OLS in
/// memory and streamed, and the SDP with one pseudo-inertia per link.
pub fn identify(chain: &Chain, samples: usize) -> Result<ChainOutcome, Box<dyn std::error::Error>> {
    let model = chain.model();
    let n = chain.joints();
    let names = model.names();
    let beta = chain.standard();
    let base = crate::base_parameters_of(&model, 400)?;

    // 1. The excitation, and random feasible ones to compare it with.
    let projection = aras_excite::base_projection(&base);
    let settings = DesignSettings {
        harmonics: 3,
        omega_f: std::f64::consts::TAU / 5.0,
        starts: 6,
        ..DesignSettings::new(limits(n))
    };
    let design = aras_excite::design(&model, &projection, &settings)?;
    let traj = &design.trajectory;
    let mut random: Vec<f64> = aras_excite::random_feasible(&settings, 31, 7)?
        .iter()
        .map(|t| aras_excite::assess(&model, &projection, t, settings.criterion_points))
        .map(|a| a.map(|a| a.condition_number))
        .collect::<Result<_, _>>()?;
    random.sort_by(f64::total_cmp);
    let dt = 2.0 * traj.period() / samples as f64;

    // 2. Structure-of-arrays samples: per joint q, q̇, q̈, τ.
    let mut soa = vec![vec![vec![0.0; samples]; n]; 4];
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for s in 0..samples {
        traj.eval_into((s as f64 + 0.5) * dt, &mut q, &mut qd, &mut qdd);
        let tau = chain.torques(&q, &qd, &qdd);
        for j in 0..n {
            for (k, v) in [q[j], qd[j], qdd[j], tau[j]].into_iter().enumerate() {
                soa[k][j][s] = v;
            }
        }
    }
    let [x, xd, xdd, tau] = [0, 1, 2, 3].map(|k| views(&soa[k]));

    // 3. In memory: the stacked regressor, joint 1's rows, then joint 2's, ….
    let w = crate::stacked_regressor(&model, &x, &xd, &xdd);
    let t = soa[3].concat();
    let truth = base.to_base(&beta)?;
    let wb = base.base_regressor(w.as_ref())?;
    let reduced = ReducedLs::new(wb.as_ref(), &t, &base.base_names())?;
    let ols = reduced.ols()?.estimate;

    // 4. Streamed: the same samples through the stage, one row group per joint.
    let mut stage = RegressorStage::new(model, &base)?;
    stage.push(&States {
        x: &x,
        x_dot: &xd,
        x_ddot: &xdd,
        tau: &tau,
    })?;
    let streaming = stage.accumulator().ols()?.estimate;

    // 5. Physically consistent: each link's pseudo-inertia PSD (67)–(69), with
    // a reference 10 % off the truth, each mass column within ±50 %,
    // friction ≥ 0.
    let reference: Vec<f64> = beta.iter().map(|v| 1.1 * v).collect();
    let mut problem = ConsistentLs::new(&names, reference)?;
    for (i, link) in chain.links.iter().enumerate() {
        let c = i * LINK_COLUMNS;
        problem
            .link(LinkLayout::new(
                format!("L{}", i + 1),
                [c, c + 1, c + 2, c + 3, c + 4, c + 5],
                [c + 6, c + 7, c + 8],
                link.mass,
            ))?
            .bound(c + 9, 0.5 * link.mass, 1.5 * link.mass)?;
    }
    let friction: Vec<&str> = names[LINK_COLUMNS * n..]
        .iter()
        .map(String::as_str)
        .collect();
    problem.nonnegative(&friction)?;
    let sol = problem.solve(&base, &reduced)?;
    Ok(ChainOutcome {
        condition_number: design.assessment.condition_number,
        random_condition_median: random[random.len() / 2],
        base_names: base.expressions(),
        truth,
        ols,
        streaming,
        streaming_rows: stage.rows(),
        sdp: sol.base.clone(),
        sdp_status: sol.status,
        min_eigenvalues: sol.links.iter().map(|l| l.min_eigenvalue).collect(),
        trajectory: traj.clone(),
    })
}

/// Sensor noise of a simulated log: Gaussian, independent per sample and
/// channel, from a seeded generator (the same seed, the same log).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Standard deviation of the angles (rad).
    pub angle: f64,
    /// Standard deviation of the torques (N·m).
    pub torque: f64,
    /// Seed of the generator.
    pub seed: u64,
}

/// The `aras-log` CSV of `periods` periods of `trajectory` run by `chain`
/// and logged at `rate_hz`: `t, theta1 … thetaN, tau1 … tauN`, the torques
/// from [`Chain::torques`], with `noise` added if given. Samples lie half
/// a step off the period boundary, where the design puts `q̇ = 0`, so none
/// sits on a Coulomb reversal.
pub fn log_csv(
    chain: &Chain,
    trajectory: &FourierTrajectory<Dyn>,
    rate_hz: f64,
    periods: usize,
    noise: Option<Noise>,
) -> String {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = rand::rngs::StdRng::seed_from_u64(noise.map_or(0, |n| n.seed));
    let mut draw = |sd: f64| -> f64 {
        if sd > 0.0 {
            let z: f64 = StandardNormal.sample(&mut rng);
            sd * z
        } else {
            0.0
        }
    };
    let n = chain.joints();
    let mut csv = String::from("t");
    for name in ["theta", "tau"] {
        for j in 1..=n {
            csv += &format!(",{name}{j}");
        }
    }
    csv.push('\n');
    let rows = (periods as f64 * trajectory.period() * rate_hz).round() as usize;
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for i in 0..rows {
        let t = (i as f64 + 0.5) / rate_hz;
        trajectory.eval_into(t, &mut q, &mut qd, &mut qdd);
        let tau = chain.torques(&q, &qd, &qdd);
        csv += &t.to_string();
        let (sa, st) = noise.map_or((0.0, 0.0), |n| (n.angle, n.torque));
        for v in &q {
            csv += &format!(",{}", v + draw(sa));
        }
        for v in &tau {
            csv += &format!(",{}", v + draw(st));
        }
        csv.push('\n');
    }
    csv
}

/// What [`identify_log`] found.
#[derive(Debug)]
pub struct LogOutcome {
    /// Joints the log reader found in the header.
    pub joints: usize,
    /// Processed samples (one averaged block of the period).
    pub samples: usize,
    /// How the processing limited the band, in its own words.
    pub bandwidth: String,
    /// True base parameters.
    pub truth: Vec<f64>,
    /// OLS from the streaming accumulation of the processed samples.
    pub streaming: Vec<f64>,
}

/// Identifies `chain` from the log `csv` of a periodic excitation of
/// period `period_s`: read by `aras-log` (as many joints as the header
/// names), processed by `aras-signal` in the chain's joint coordinates
/// (period averaging, the data-chosen bandwidth), and streamed through
/// the base regressor to OLS.
pub fn identify_log(
    chain: &Chain,
    csv: &str,
    period_s: f64,
) -> Result<LogOutcome, Box<dyn std::error::Error>> {
    let model = chain.model();
    let base = crate::base_parameters_of(&model, 400)?;
    let (joints, processed) = read_and_process(csv, period_s)?;
    let s = &processed.samples;
    let mut stage = RegressorStage::new(model, &base)?;
    stage.push(&States {
        x: &views(&s.x),
        x_dot: &views(&s.x_dot),
        x_ddot: &views(&s.x_ddot),
        tau: &views(&s.tau),
    })?;
    Ok(LogOutcome {
        joints,
        samples: s.len(),
        bandwidth: processed.summary.bandwidth.reason.clone(),
        truth: base.to_base(&chain.standard())?,
        streaming: stage.accumulator().ols()?.estimate,
    })
}

/// Reads a chain log (as many joints as its header names) and processes it
/// in joint coordinates of run-time dimension: period averaging, the
/// data-chosen bandwidth. Returns the joint count and the processing.
fn read_and_process(
    csv: &str,
    period_s: f64,
) -> Result<(usize, aras_signal::Processed), Box<dyn std::error::Error>> {
    let log = aras_log::read_log_from(csv.as_bytes(), "chain.csv", &ReadOptions::default())?;
    let processed = aras_signal::process_in::<Dyn>(
        &log,
        &ProcessOptions {
            filter: Bandwidth::Auto,
            period: PeriodSource::Seconds(period_s),
            ..ProcessOptions::default()
        },
        &JointCoordinates,
    )?;
    Ok((log.joints(), processed))
}

/// The effects [`diagnose_logs`] tries, per joint `j`: a torque offset
/// (`offset_j`) and a spring `k q_j` (`spring_j`), each on its own joint's
/// torque only.
pub fn candidate_names(joints: usize) -> Vec<String> {
    chain_candidates(joints)
        .iter()
        .map(aras_diagnose::Candidate::label)
        .collect()
}

/// A candidate effect of the chain: one column on one joint's torque.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(tag = "kind", content = "joint", rename_all = "snake_case")]
pub enum ChainCandidate {
    /// A constant torque on joint `j` (0-based): a torque sensor's or
    /// amplifier's offset.
    Offset(usize),
    /// A torque `k q_j` on joint `j` (0-based): a spring, a cable or a
    /// gravity compensator.
    Spring(usize),
}

/// The candidates per joint, in [`candidate_names`]' order.
fn chain_candidates(joints: usize) -> Vec<ChainCandidate> {
    (0..joints)
        .flat_map(|j| [ChainCandidate::Offset(j), ChainCandidate::Spring(j)])
        .collect()
}

impl aras_diagnose::Candidate for ChainCandidate {
    fn id(&self) -> String {
        // Each candidate is its own family (an offset on every joint may be
        // added): the label names it.
        aras_diagnose::Candidate::label(self)
    }
    fn label(&self) -> String {
        match self {
            ChainCandidate::Offset(j) => format!("offset_{}", j + 1),
            ChainCandidate::Spring(j) => format!("spring_{}", j + 1),
        }
    }
    fn explanation(&self) -> String {
        match self {
            ChainCandidate::Offset(_) => {
                "a constant torque on one joint (a torque sensor's or amplifier's offset); \
                 the residual has a constant mean"
            }
            ChainCandidate::Spring(_) => {
                "a torque proportional to one joint's angle (a spring, a cable, a gravity \
                 compensator); the residual grows linearly with the angle"
            }
        }
        .to_owned()
    }
    fn parameter_names(&self) -> Vec<String> {
        vec![self.label()]
    }
    fn with_setting(&self, _: f64) -> Self {
        *self
    }
}

/// The chain's model as the diagnosis engine sees it.
struct ChainRobot {
    model: ChainModel,
    base: aras_ident::BaseParameters,
    joints: usize,
}

/// A window of processed samples: the chain's standard regressor on them
/// (joint-major) and its joint angles.
struct ChainWindow {
    w: faer::Mat<f64>,
    q: Vec<Vec<f64>>,
}

impl aras_diagnose::DiagnosisModel for ChainRobot {
    type Candidate = ChainCandidate;
    type Window = ChainWindow;
    type Terms = Vec<String>;
    type Refit = aras_diagnose::NoRefit;

    fn joints(&self) -> usize {
        self.joints
    }
    fn n_base(&self) -> usize {
        self.base.n_base()
    }
    fn base_name(&self, column: usize) -> String {
        self.base.expression(column)
    }
    fn window(
        &self,
        s: &aras_signal::Samples,
        _first: usize,
    ) -> Result<ChainWindow, aras_ident::IdentError> {
        Ok(ChainWindow {
            w: crate::stacked_regressor(
                &self.model,
                &views(&s.x),
                &views(&s.x_dot),
                &views(&s.x_ddot),
            ),
            q: s.x.clone(),
        })
    }
    fn base_columns(&self, w: &ChainWindow) -> Result<faer::Mat<f64>, aras_ident::IdentError> {
        self.base.base_regressor(w.w.as_ref())
    }
    fn candidate_columns(
        &self,
        c: &ChainCandidate,
        w: &ChainWindow,
    ) -> Result<faer::Mat<f64>, aras_ident::IdentError> {
        let m = w.q.first().map_or(0, Vec::len);
        let (j, spring) = match *c {
            ChainCandidate::Offset(j) => (j, false),
            ChainCandidate::Spring(j) => (j, true),
        };
        Ok(faer::Mat::from_fn(self.joints * m, 1, |r, _| {
            match (r / m.max(1) == j, spring) {
                (false, _) => 0.0,
                (true, false) => 1.0,
                (true, true) => w.q[j][r % m],
            }
        }))
    }
    fn term_names(&self) -> Vec<String> {
        vec!["links".into(), "coulomb_viscous".into()]
    }
    fn terms(&self, added: &[ChainCandidate]) -> Result<Vec<String>, aras_ident::IdentError> {
        use aras_diagnose::Candidate as _;
        let mut t = self.term_names();
        t.extend(added.iter().map(|c| c.label()));
        Ok(t)
    }
    fn consistent_refit(
        &self,
        _: &[ChainCandidate],
    ) -> Result<Option<aras_diagnose::NoRefit>, aras_ident::IdentError> {
        Ok(None)
    }
}

/// What [`diagnose_logs`] named.
#[derive(Debug)]
pub struct ChainDiagnosis {
    /// The candidates added, in order ([`candidate_names`]).
    pub added: Vec<String>,
    /// Their fitted values (N·m or N·m/rad).
    pub values: Vec<f64>,
    /// Mean validation fitness (78) per joint of the chain's model (%).
    pub fitness_before: Vec<f64>,
    /// The same with the added effects (%).
    pub fitness_after: Vec<f64>,
    /// True if the final validation residual is white with no systematic
    /// bin ([`aras_diagnose::Diagnosis::noise_like`]).
    pub noise_like: bool,
    /// The engine's conclusion in words.
    pub conclusion: String,
}

/// Finds which effect the chain's model misses with the diagnosis engine
/// of `aras-diagnose` (the pipeline's): the base regressor of the
/// processed `train` log and the [`candidate_names`] per joint, one output
/// group per joint, judged on the processed `validation` log of another
/// motion (both periodic with `period_s`). Every row is used: the chain's
/// Coulomb law is exact at its velocity reversals.
pub fn diagnose_logs(
    chain: &Chain,
    train: &str,
    validation: &str,
    period_s: f64,
) -> Result<ChainDiagnosis, Box<dyn std::error::Error>> {
    let model = chain.model();
    let joints = chain.joints();
    let base = crate::base_parameters_of(&model, 400)?;
    let robot = ChainRobot {
        model,
        base,
        joints,
    };
    let mut sets = Vec::new();
    for (name, csv) in [("train", train), ("validation", validation)] {
        let (_, processed) = read_and_process(csv, period_s)?;
        sets.push(aras_diagnose::Dataset::from_processed_owned(
            name, processed,
        )?);
    }
    let opts = aras_diagnose::EngineOptions {
        min_speed: 0.0,
        ..aras_diagnose::EngineOptions::default()
    };
    let d = aras_diagnose::diagnose(
        &robot,
        chain_candidates(joints),
        &sets[0],
        &sets[1..],
        &opts,
    )?;
    let mean = |row: Option<&aras_diagnose::FitnessRow>| -> Vec<f64> {
        let Some(row) = row else { return Vec::new() };
        let sets = row.fitness_filtered.len().max(1) as f64;
        (0..joints)
            .map(|j| row.fitness_filtered.iter().map(|f| f[j]).sum::<f64>() / sets)
            .collect()
    };
    let added: Vec<String> = d.steps.iter().map(|s| s.label.clone()).collect();
    let values = added
        .iter()
        .map(|name| {
            d.estimate
                .iter()
                .find(|v| &v.name == name)
                .map_or(f64::NAN, |v| v.value)
        })
        .collect();
    Ok(ChainDiagnosis {
        added,
        values,
        fitness_before: mean(d.fitness.first()),
        fitness_after: mean(d.fitness.last()),
        noise_like: d.noise_like,
        conclusion: d.conclusion,
    })
}
