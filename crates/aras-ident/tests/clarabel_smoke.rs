use clarabel::algebra::*;
use clarabel::solver::*;
#[test]
fn tiny_sdp() {
    let p = CscMatrix::<f64>::zeros((3, 3));
    let c = [1.0, 0.0, 1.0];
    let a = CscMatrix::from(&[[-1.0, 0.0, 0.0], [0.0, -2f64.sqrt(), 0.0], [0.0, 0.0, -1.0]]);
    let b = [0.0, 0.0, 0.0];
    let cones = [PSDTriangleConeT(2)];
    let s = DefaultSettingsBuilder::default().verbose(false).build().unwrap();
    let mut solver = DefaultSolver::new(&p, &c, &a, &b, &cones, s).unwrap();
    solver.solve();
    println!("{:?}", solver.solution.status);
}
