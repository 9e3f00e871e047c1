//! The Panda end to end through `aras-ident`: its regressor's base
//! parameters, and OLS on noise-free torques from RNEA (another code path)
//! recovers them.

mod common;

use aras_ident::{BaseParameters, LinearModel, ReducedLs};
use common::{ALL, panda, sequence};

#[test]
fn panda_base_parameters_are_recovered_by_ols() {
    let model = panda(ALL, [0.4, -0.3, -9.8]);
    assert_eq!(model.dof(), 7);
    let (n, cols) = (model.dof(), model.columns());
    assert_eq!(cols, 7 * 14);
    // The truth: the URDF's inertials, friction and armature of their
    // usual sizes.
    let mut truth = model.urdf_parameters();
    for j in 0..n {
        let b = 70 + 4 * j;
        truth[b..b + 4].copy_from_slice(&[
            0.3 + 0.05 * j as f64,
            0.8 - 0.1 * j as f64,
            0.02 * j as f64 - 0.05,
            0.1 + 0.02 * j as f64,
        ]);
    }
    let samples = 600;
    let mut next = sequence();
    let mut w = faer::Mat::<f64>::zeros(n * samples, cols);
    let mut tau = vec![0.0; n * samples];
    let mut y = vec![0.0; n * cols];
    for s in 0..samples {
        let q: Vec<f64> = (0..n).map(|_| 2.5 * next()).collect();
        let qd: Vec<f64> = (0..n).map(|_| 2.0 * next()).collect();
        let qdd: Vec<f64> = (0..n).map(|_| 8.0 * next()).collect();
        model.fill(&q, &qd, &qdd, &mut y).unwrap();
        let t = model.inverse_dynamics(&truth, &q, &qd, &qdd).unwrap();
        for j in 0..n {
            for c in 0..cols {
                w[(j * samples + s, c)] = y[n * c + j];
            }
            tau[j * samples + s] = t[j];
        }
    }
    let base = BaseParameters::from_regressor(w.as_ref(), &model.names(), 1e-8).unwrap();
    eprintln!("Panda: {} base parameters of {cols}", base.n_base());
    eprintln!("{:?}", base.unidentifiable());
    let wb = base.base_regressor(w.as_ref()).unwrap();
    let ls = ReducedLs::new(wb.as_ref(), &tau, &base.base_names()).unwrap();
    let est = ls.ols().unwrap().estimate;
    let want = base.to_base(&truth).unwrap();
    for (k, (e, t)) in est.iter().zip(&want).enumerate() {
        let scale = t.abs().max(1e-3);
        assert!(
            (e - t).abs() <= 1e-8 * scale,
            "{}: estimate {e} truth {t}",
            base.expression(k)
        );
    }
}
