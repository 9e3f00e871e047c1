//! Synthetic problems with known answers, shared by the integration tests.
#![allow(clippy::needless_range_loop)]
#![allow(dead_code)]

use faer::Mat;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};

pub fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

pub fn normal(r: &mut StdRng) -> f64 {
    StandardNormal.sample(r)
}

/// Names of one rigid body's 9 standard parameters, prefixed.
pub fn body_names(prefix: &str) -> Vec<String> {
    ["Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz", "hx", "hy", "hz"]
        .iter()
        .map(|n| format!("{prefix}.{n}"))
        .collect()
}

/// Standard parameters (I about the pivot, tensor entries; h = m ρ) of a
/// body of mass `m`, centre of mass `rho` and diagonal central inertia `ig`.
pub fn body_params(m: f64, rho: [f64; 3], ig: [f64; 3]) -> Vec<f64> {
    let r2 = rho.iter().map(|v| v * v).sum::<f64>();
    let mut i = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            let delta = if a == b { 1.0 } else { 0.0 };
            i[a][b] = m * (r2 * delta - rho[a] * rho[b]) + if a == b { ig[a] } else { 0.0 };
        }
    }
    vec![
        i[0][0],
        i[0][1],
        i[0][2],
        i[1][1],
        i[1][2],
        i[2][2],
        m * rho[0],
        m * rho[1],
        m * rho[2],
    ]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The 3 × 9 regressor rows of a body turning about a fixed point (the
/// (45) without the Jacobians): `[L(Ω̇) + [Ω]× L(Ω), [g]×]`.
pub fn body_rows(omega: [f64; 3], omega_dot: [f64; 3], g: [f64; 3]) -> [[f64; 9]; 3] {
    let l = |w: [f64; 3]| -> [[f64; 6]; 3] {
        [
            [w[0], w[1], w[2], 0.0, 0.0, 0.0],
            [0.0, w[0], 0.0, w[1], w[2], 0.0],
            [0.0, 0.0, w[0], 0.0, w[1], w[2]],
        ]
    };
    let ld = l(omega_dot);
    let lo = l(omega);
    let mut out = [[0.0; 9]; 3];
    for c in 0..6 {
        let col = [lo[0][c], lo[1][c], lo[2][c]];
        let x = cross(omega, col);
        for r in 0..3 {
            out[r][c] = ld[r][c] + x[r];
        }
    }
    // −h × g = g × h = [g]× h
    for c in 0..3 {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        let x = cross(g, e);
        for r in 0..3 {
            out[r][6 + c] = x[r];
        }
    }
    out
}

/// Random direction scaled to 9.81.
pub fn random_gravity(r: &mut StdRng) -> [f64; 3] {
    let v = [normal(r), normal(r), normal(r)];
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.map(|x| 9.81 * x / n)
}

/// `bodies` bodies with independent random motion whose torques add up in
/// the same 3 rows (joint-major: all x rows, then y, then z), plus optional
/// friction-like columns `Fv` (random velocity) and `Fc` (its sign) per
/// row axis. Returns W (3N × 9·bodies + 6·friction) and names.
pub fn multi_body(
    r: &mut StdRng,
    samples: usize,
    bodies: usize,
    shared_motion: bool,
    friction: bool,
) -> (Mat<f64>, Vec<String>) {
    let nb = 9 * bodies;
    let nf = if friction { 6 } else { 0 };
    let mut w = Mat::zeros(3 * samples, nb + nf);
    for s in 0..samples {
        let g = random_gravity(r);
        let mut motion = None;
        for k in 0..bodies {
            let (om, od) = match (shared_motion, motion) {
                (true, Some(m)) => m,
                _ => {
                    let m = (
                        [normal(r), normal(r), normal(r)],
                        [normal(r), normal(r), normal(r)],
                    );
                    motion = Some(m);
                    m
                }
            };
            let rows = body_rows(om, od, g);
            for a in 0..3 {
                for c in 0..9 {
                    w[(a * samples + s, 9 * k + c)] = rows[a][c];
                }
            }
        }
        if friction {
            for a in 0..3 {
                let v: f64 = r.random_range(-2.0..2.0);
                w[(a * samples + s, nb + 2 * a)] = v;
                w[(a * samples + s, nb + 2 * a + 1)] = v.signum();
            }
        }
    }
    let mut names: Vec<String> = (0..bodies)
        .flat_map(|k| body_names(&format!("L{}", k + 1)))
        .collect();
    if friction {
        for a in 1..=3 {
            names.push(format!("Fv{a}"));
            names.push(format!("Fc{a}"));
        }
    }
    (w, names)
}

/// `W β + N(0, σ²)` noise.
pub fn torques(w: &Mat<f64>, beta: &[f64], sigma: f64, r: &mut StdRng) -> Vec<f64> {
    (0..w.nrows())
        .map(|i| (0..w.ncols()).map(|j| w[(i, j)] * beta[j]).sum::<f64>() + sigma * normal(r))
        .collect()
}
