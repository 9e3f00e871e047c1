//! Benchmarks against the targets: OLS on 320 000 × 23 ≤ 50 ms,
//! the SDP ≤ 200 ms, the workspace PD scan on 1e5 points ≤ 100 ms.
#![allow(clippy::needless_range_loop)]

use aras_ident::validate::{PdRegion, check_positive_definite};
use aras_ident::{BaseParameters, ConsistentLs, LinkLayout, ReducedLs};
use criterion::{Criterion, criterion_group, criterion_main};
use faer::Mat;
use std::hint::black_box;

// The rigid-body rows (Newton–Euler in regressor form) the tests use too.
#[path = "../tests/common/mod.rs"]
mod common;

/// SplitMix64-based standard normals (Box–Muller), deterministic.
struct Gen(u64);
impl Gen {
    fn u(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn n(&mut self) -> f64 {
        let (a, b) = (self.u().max(1e-300), self.u());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

fn bench_ols(c: &mut Criterion) {
    let (m, b) = (320_000, 23);
    let mut g = Gen(1);
    let w = Mat::from_fn(m, b, |_, j| (1.0 + j as f64) * g.n());
    let t: Vec<f64> = (0..m).map(|i| w[(i, 0)] + 0.1 * g.n()).collect();
    let names: Vec<String> = (1..=b).map(|i| format!("b{i}")).collect();
    c.bench_function("ols_320000x23", |bch| {
        bch.iter(|| {
            ReducedLs::new(black_box(w.as_ref()), black_box(&t), &names)
                .unwrap()
                .ols()
                .unwrap()
        })
    });
}

/// Four rigid bodies (36 standard parameters) turning about a common pivot
/// with random motion and gravity, summed into three rows, plus 6 friction
/// columns: 42 standard parameters, the size of the ARAS model.
fn bench_sdp(c: &mut Criterion) {
    let n = 2000;
    let mut g = Gen(2);
    let mut w = Mat::zeros(3 * n, 42);
    for s in 0..n {
        let gr = [g.n(), g.n(), g.n()];
        let gn = (gr[0] * gr[0] + gr[1] * gr[1] + gr[2] * gr[2]).sqrt();
        let gv = gr.map(|v| 9.81 * v / gn);
        for k in 0..4 {
            let om = [g.n(), g.n(), g.n()];
            let od = [g.n(), g.n(), g.n()];
            let rows = common::body_rows(om, od, gv);
            for a in 0..3 {
                for col in 0..9 {
                    w[(a * n + s, 9 * k + col)] = rows[a][col];
                }
            }
        }
        for a in 0..3 {
            let v = 2.0 * g.u() - 1.0;
            w[(a * n + s, 36 + 2 * a)] = v;
            w[(a * n + s, 37 + 2 * a)] = v.signum();
        }
    }
    let names: Vec<String> = (0..42).map(|i| format!("p{i}")).collect();
    let base = BaseParameters::from_regressor(w.as_ref(), &names, 1e-8).unwrap();
    // Truth: slightly non-physical first body (so a PSD constraint binds).
    let body = |m: f64, r: [f64; 3], ig: [f64; 3]| -> Vec<f64> {
        let r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        let e = |a: usize, bb: usize| {
            m * ((if a == bb { r2 } else { 0.0 }) - r[a] * r[bb])
                + if a == bb { ig[a] } else { 0.0 }
        };
        vec![
            e(0, 0),
            e(0, 1),
            e(0, 2),
            e(1, 1),
            e(1, 2),
            e(2, 2),
            m * r[0],
            m * r[1],
            m * r[2],
        ]
    };
    let mut truth = Vec::new();
    for k in 0..4 {
        truth.extend(body(
            0.1 + 0.02 * k as f64,
            [0.1, 0.0, 0.25],
            [6e-4, 6e-4, 2e-5],
        ));
    }
    truth.extend([0.03, 0.08, 0.01, 0.3, 0.02, 0.1]);
    let reference = truth.clone();
    truth[0] += 2e-3;
    let t: Vec<f64> = (0..3 * n)
        .map(|i| (0..42).map(|j| w[(i, j)] * truth[j]).sum::<f64>() + 1e-3 * g.n())
        .collect();
    let wb = base.base_regressor(w.as_ref()).unwrap();
    let red = ReducedLs::new(wb.as_ref(), &t, &base.base_names()).unwrap();
    let mut p = ConsistentLs::new(&names, reference).unwrap();
    for k in 0..4 {
        let o = 9 * k;
        p.link(LinkLayout::new(
            format!("L{}", k + 1),
            [o, o + 1, o + 2, o + 3, o + 4, o + 5],
            [o + 6, o + 7, o + 8],
            0.1 + 0.02 * k as f64,
        ))
        .unwrap();
    }
    p.nonnegative(&["p36", "p37", "p38", "p39", "p40", "p41"])
        .unwrap();
    let sol = p.solve(&base, &red).unwrap();
    eprintln!(
        "SDP on 42 standard / {} base parameters: {sol}",
        base.n_base()
    );
    c.bench_function("sdp_4_links_42_params", |bch| {
        bch.iter(|| p.solve(black_box(&base), black_box(&red)).unwrap())
    });
}

/// A closed-form 2×2 mass matrix of a 2-DOF arm-like mechanism (stand-in
/// until aras-dyn provides (80)).
fn bench_pd(c: &mut Criterion) {
    let region = PdRegion::new(
        [30f64.to_radians(), 40f64.to_radians()],
        [140f64.to_radians(), 80f64.to_radians()],
    );
    let mut r = region.clone();
    r.grid_per_axis = 0;
    r.random = 100_000;
    let m = |x: &[f64; 2]| -> Result<[[f64; 2]; 2], String> {
        let (s, c) = x[1].sin_cos();
        let m11 = 0.02 + 0.01 * c + 0.004 * x[0].cos() * s;
        let m12 = 0.003 * c;
        Ok([[m11, m12], [m12, 0.008 + 0.002 * s * s]])
    };
    let rep = check_positive_definite(m, &r);
    eprintln!(
        "PD scan: {} points, λ ∈ [{:.4e}, {:.4e}], min at {:?}",
        rep.points, rep.min_eigenvalue, rep.max_eigenvalue, rep.argmin
    );
    c.bench_function("pd_scan_1e5", |bch| {
        bch.iter(|| check_positive_definite(m, black_box(&r)))
    });
}

criterion_group!(benches, bench_ols, bench_sdp, bench_pd);
criterion_main!(benches);
