//! Proves that clarabel's PSD cones link (OpenBLAS) and solve here, and pins
//! the packing convention the SDP module relies on.
#![cfg(feature = "sdp")]
#![allow(clippy::needless_range_loop)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// min tr X subject to X ⪰ C, with C = [[2, 1], [1, 2]] ≻ 0: the optimum is X = C.
/// Variables (X11, X12, X22); the cone slack is svec(X − C) =
/// (X11 − 2, √2 (X12 − 1), X22 − 2) = b − A x, i.e. A = −diag(1, √2, 1),
/// b = −svec(C) (upper triangle by columns, off-diagonals × √2).
#[test]
fn tiny_sdp_solves_with_the_documented_packing() {
    let r2 = std::f64::consts::SQRT_2;
    let p = CscMatrix::<f64>::zeros((3, 3));
    let q = [1.0, 0.0, 1.0];
    let a = CscMatrix::from(&[[-1.0, 0.0, 0.0], [0.0, -r2, 0.0], [0.0, 0.0, -1.0]]);
    let b = [-2.0, -r2, -2.0];
    let cones = [SupportedConeT::PSDTriangleConeT(2)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .unwrap();
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).unwrap();
    solver.solve();
    let s = &solver.solution;
    assert_eq!(s.status, SolverStatus::Solved);
    // Interior-point accuracy at the default 1e-8 gap tolerance: 1e-6 is
    // loose enough for the last iterate, tight enough to catch a wrong packing
    // (which would move X12 by a factor √2).
    assert!((s.x[0] - 2.0).abs() < 1e-6, "{:?}", s.x);
    assert!((s.x[1] - 1.0).abs() < 1e-6, "{:?}", s.x);
    assert!((s.x[2] - 2.0).abs() < 1e-6, "{:?}", s.x);
    assert!(s.iterations < 30);
}
