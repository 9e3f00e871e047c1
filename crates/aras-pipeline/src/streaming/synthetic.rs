//! A fast synthetic robot run for scale tests and benchmarks: a periodic
//! multi-sine task-space trajectory (period 10 s, harmonics of 0.1 Hz, as
//! the excitation (74)) with exact model torques `τ = Y β` plus
//! deterministic pseudo-random noise. Much faster than the simulator, so
//! hour-long logs can be generated at test time.

use crate::PipelineError;
use std::io::Write;
use std::path::Path;

use aras_dyn::Model;
use aras_kin::{Geometry, Motion};
use rayon::prelude::*;

use aras_ident::IdentError;

/// Period of the synthetic trajectory (s).
pub const PERIOD_S: f64 = 10.0;

/// `(amplitude rad, harmonic of 0.1 Hz, phase)` per axis, about a centre
/// well inside the paper's workspace (77).
const COMPONENTS: [[(f64, f64, f64); 3]; 2] = [
    [(0.45, 1.0, 0.0), (0.15, 3.0, 1.0), (0.06, 7.0, 2.0)],
    [(0.20, 2.0, 0.5), (0.08, 5.0, 0.2), (0.04, 11.0, 1.7)],
];
const CENTRE: [f64; 2] = [1.48, 1.05];

/// `X, Ẋ, Ẍ` of the trajectory at time `t` (s).
pub fn state(t: f64) -> Motion {
    let mut out = Motion::default();
    for a in 0..2 {
        let (mut x, mut xd, mut xdd) = (CENTRE[a], 0.0, 0.0);
        for &(amp, h, ph) in &COMPONENTS[a] {
            let w = std::f64::consts::TAU * h / PERIOD_S;
            let (s, c) = (w * t + ph).sin_cos();
            x += amp * s;
            xd += amp * w * c;
            xdd -= amp * w * w * s;
        }
        out.pos[a] = x;
        out.vel[a] = xd;
        out.acc[a] = xdd;
    }
    out
}

/// Deterministic standard-normal-ish noise (sum of 4 uniforms, scaled to
/// unit variance) from a counter: reproducible, no state, no dependency.
fn noise(i: u64, channel: u64) -> f64 {
    let mut s = 0.0;
    for k in 0..4u64 {
        let mut z = i
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add((channel * 4 + k).wrapping_mul(0xBF58_476D_1CE4_E5B9));
        z ^= z >> 31;
        z = z.wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 29;
        s += (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
    }
    s * 3.0f64.sqrt()
}

/// Task-space states and torques of `n` samples at `fs` Hz, structure of
/// arrays `[x, x_dot, x_ddot, tau]`, each `[axis 0, axis 1]`.
pub type StateArrays = [[Vec<f64>; 2]; 4];

/// `n` samples at `fs` Hz of the trajectory with torques `Y β` plus noise
/// of standard deviation `noise_std` (N·m).
pub fn states(
    model: &Model,
    geometry: &Geometry,
    beta: &[f64],
    n: usize,
    fs: f64,
    noise_std: f64,
) -> Result<StateArrays, PipelineError> {
    let rows: Vec<[f64; 8]> = (0..n)
        .into_par_iter()
        .map(|i| row(model, geometry, beta, i, fs, noise_std))
        .collect::<Result<_, _>>()?;
    let mut out: StateArrays = Default::default();
    for r in &rows {
        for q in 0..4 {
            for a in 0..2 {
                out[q][a].push(r[2 * q + a]);
            }
        }
    }
    Ok(out)
}

/// One sample: `[φ, γ, φ̇, γ̇, φ̈, γ̈, τ1, τ2]`.
fn row(
    model: &Model,
    geometry: &Geometry,
    beta: &[f64],
    i: usize,
    fs: f64,
    noise_std: f64,
) -> Result<[f64; 8], PipelineError> {
    let (s, tau) = sample(model, geometry, beta, i, fs, noise_std)?;
    Ok([
        s.task.pos[0],
        s.task.pos[1],
        s.task.vel[0],
        s.task.vel[1],
        s.task.acc[0],
        s.task.acc[1],
        tau[0],
        tau[1],
    ])
}

fn sample(
    model: &Model,
    geometry: &Geometry,
    beta: &[f64],
    i: usize,
    fs: f64,
    noise_std: f64,
) -> Result<(aras_kin::KinematicSample, [f64; 2]), PipelineError> {
    let s = aras_kin::evaluate(geometry, &state(i as f64 / fs))
        .map_err(|e| IdentError::external("synthetic trajectory", e))?;
    let tau = model
        .torque(&s, beta)
        .map_err(|e| IdentError::external("synthetic torques", e))?;
    let i = i as u64;
    Ok((
        s,
        [
            tau[0] + noise_std * noise(i, 0),
            tau[1] + noise_std * noise(i, 1),
        ],
    ))
}

/// Writes `n` samples at `fs` Hz as an `aras-log/1` CSV with logged
/// derivatives (`t, theta1, theta2, dtheta1, dtheta2, ddtheta1, ddtheta2,
/// tau1, tau2`), in blocks (bounded memory), formatted in parallel.
pub fn write_log(
    path: &Path,
    model: &Model,
    geometry: &Geometry,
    beta: &[f64],
    n: usize,
    fs: f64,
    noise_std: f64,
) -> Result<(), PipelineError> {
    let io = |e: std::io::Error| IdentError::external(format!("writing {}", path.display()), e);
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    writeln!(
        f,
        "t,theta1,theta2,dtheta1,dtheta2,ddtheta1,ddtheta2,tau1,tau2"
    )
    .map_err(io)?;
    const BLOCK: usize = 16_384;
    let starts: Vec<usize> = (0..n).step_by(BLOCK).collect();
    for wave in starts.chunks(8) {
        let texts: Vec<String> = wave
            .par_iter()
            .map(|&s0| -> Result<String, IdentError> {
                let mut out = String::with_capacity(BLOCK * 160);
                for i in s0..(s0 + BLOCK).min(n) {
                    let (s, tau) = sample(model, geometry, beta, i, fs, noise_std)
                        .map_err(PipelineError::into_ident)?;
                    use std::fmt::Write as _;
                    let _ = writeln!(
                        out,
                        "{:.6},{:.12},{:.12},{:.12},{:.12},{:.12},{:.12},{:.12},{:.12}",
                        i as f64 / fs,
                        s.joint.pos[0],
                        s.joint.pos[1],
                        s.joint.vel[0],
                        s.joint.vel[1],
                        s.joint.acc[0],
                        s.joint.acc[1],
                        tau[0],
                        tau[1]
                    );
                }
                Ok(out)
            })
            .collect::<Result<_, _>>()?;
        for t in texts {
            f.write_all(t.as_bytes()).map_err(io)?;
        }
    }
    f.flush().map_err(io).map_err(PipelineError::from)
}
