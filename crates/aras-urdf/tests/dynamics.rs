//! Property tests of the dynamics: the regressor against RNEA, RNEA
#![allow(clippy::needless_range_loop)] // index loops mirror the equations
//! against the Lagrangian built from the forward kinematics alone, fixed
//! joints merged against the same joints free but at rest, the energy
//! balance, and the dual-number rows against finite differences.

mod common;

use aras_excite::{Dual, Regressor};
use aras_ident::LinearModel;
use aras_urdf::{CoulombWidth, JointColumns, ModelSettings, Scalar, StribeckColumn, UrdfModel};
use common::*;
use num_dual::{Dual64, HyperDual64};
use proptest::prelude::*;

fn settings(gravity: [f64; 3], base_rpy: [f64; 3], columns: JointColumns) -> ModelSettings {
    ModelSettings {
        gravity,
        base_rpy,
        base_xyz: [0.1, -0.2, 0.3],
        columns,
        coulomb_width: CoulombWidth::Uniform(0.05),
        stribeck: Vec::new(),
    }
}

/// The model of `spec` with `settings` and a Stribeck column on its first
/// joint (`v_s` 0.07), so that every kind of column is in the checks.
fn with_stribeck(spec: &RobotSpec, settings: ModelSettings) -> UrdfModel {
    let plain = UrdfModel::from_urdf_str(&spec.urdf(), "random.urdf", settings.clone()).unwrap();
    let joint = plain.joint_names()[0].clone();
    UrdfModel::from_urdf_str(
        &spec.urdf(),
        "random.urdf",
        ModelSettings {
            stribeck: vec![StribeckColumn { joint, v_s: 0.07 }],
            ..settings
        },
    )
    .unwrap()
}

fn all_columns() -> JointColumns {
    JointColumns {
        viscous: true,
        coulomb: true,
        offset: true,
        armature: true,
    }
}

/// Random physically consistent body parameters and friction values for
/// a model.
fn parameters(model: &UrdfModel, bodies: &[LinkSpec], friction: &[f64]) -> Vec<f64> {
    let mut p: Vec<f64> = bodies.iter().flat_map(body_parameters).collect();
    let extra = model.parameter_count() - p.len();
    p.extend(friction.iter().cycle().take(extra));
    p
}

type Case = (
    RobotSpec,
    Vec<LinkSpec>,
    (Vec<f64>, Vec<f64>, Vec<f64>),
    [f64; 3],
    [f64; 3],
    Vec<f64>,
);

fn case(max: usize, fixed: bool, tree: bool) -> impl Strategy<Value = Case> {
    robot(max, fixed, tree).prop_flat_map(|r| {
        let n = r.dof();
        (
            Just(r),
            proptest::collection::vec(link(), n),
            state(n),
            [-10.0..10.0f64, -10.0..10.0, -10.0..10.0],
            [-3.2..3.2f64, -3.2..3.2, -3.2..3.2],
            proptest::collection::vec(0.0..2.0f64, 4 * n),
        )
    })
}

/// The kinetic energy of the bodies with standard parameters `p`, from the
/// body poses alone: `T = ½ m v·v + v·(ω × h) + ½ ωᵀ I_O ω` with `ω, v`
/// in the body frame from `Rᵀ Ṙ` and `Rᵀ ṗ`, the rates by one more dual
/// number.
fn kinetic<T: Scalar>(model: &UrdfModel, p: &[f64], q: &[T], qd: &[T]) -> T {
    let x: Vec<num_dual::Dual<T>> = q
        .iter()
        .zip(qd)
        .map(|(&a, &b)| num_dual::Dual::new(a, b))
        .collect();
    let poses = model.body_poses(&x).unwrap();
    let mut t = T::from(0.0);
    for (i, pose) in poses.iter().enumerate() {
        let r = pose.rotation.map(|row| row.map(|e| e.re));
        let rd = pose.rotation.map(|row| row.map(|e| e.eps));
        let pd = pose.translation.map(|e| e.eps);
        // Rᵀ Ṙ = [ω]× and Rᵀ ṗ, body frame.
        let rt = |a: usize, b: usize, m: &[[T; 3]; 3]| {
            r[0][a] * m[0][b] + r[1][a] * m[1][b] + r[2][a] * m[2][b]
        };
        let w = [rt(2, 1, &rd), rt(0, 2, &rd), rt(1, 0, &rd)];
        let v: Vec<T> = (0..3)
            .map(|a| r[0][a] * pd[0] + r[1][a] * pd[1] + r[2][a] * pd[2])
            .collect();
        let b = &p[10 * i..10 * i + 10];
        let (m, h) = (b[0], [b[1], b[2], b[3]]);
        let ii = [[b[4], b[5], b[7]], [b[5], b[6], b[8]], [b[7], b[8], b[9]]];
        let wxh = [
            w[1] * h[2] - w[2] * h[1],
            w[2] * h[0] - w[0] * h[2],
            w[0] * h[1] - w[1] * h[0],
        ];
        let mut iw = T::from(0.0);
        for a in 0..3 {
            for c in 0..3 {
                iw += w[a] * w[c] * ii[a][c];
            }
        }
        t += (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * (0.5 * m)
            + v[0] * wxh[0]
            + v[1] * wxh[1]
            + v[2] * wxh[2]
            + iw * 0.5;
    }
    t
}

/// The potential energy `V = −Σ g · (m p + R h)` in the world.
fn potential<T: Scalar>(model: &UrdfModel, p: &[f64], q: &[T]) -> T {
    let g = model.settings().gravity;
    let poses = model.body_poses(q).unwrap();
    let mut v = T::from(0.0);
    for (i, pose) in poses.iter().enumerate() {
        let b = &p[10 * i..10 * i + 10];
        for a in 0..3 {
            let mut c = pose.translation[a] * b[0];
            for k in 0..3 {
                c += pose.rotation[a][k] * b[1 + k];
            }
            v -= c * g[a];
        }
    }
    v
}

/// `τ = d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q` by dual numbers, on the poses only.
fn lagrangian(model: &UrdfModel, p: &[f64], q: &[f64], qd: &[f64], qdd: &[f64]) -> Vec<f64> {
    let n = q.len();
    (0..n)
        .map(|k| {
            // d/dt ∂T/∂q̇_k: ε₁ on q̇_k, ε₂ along the motion in time.
            let qh: Vec<HyperDual64> = (0..n)
                .map(|i| HyperDual64::new(q[i], 0.0, qd[i], 0.0))
                .collect();
            let qdh: Vec<HyperDual64> = (0..n)
                .map(|i| HyperDual64::new(qd[i], if i == k { 1.0 } else { 0.0 }, qdd[i], 0.0))
                .collect();
            let ddt = kinetic(model, p, &qh, &qdh).eps1eps2;
            let seed = |i: usize| Dual64::new(q[i], if i == k { 1.0 } else { 0.0 });
            let qk: Vec<Dual64> = (0..n).map(seed).collect();
            let qdk: Vec<Dual64> = qd.iter().map(|&x| Dual64::from_re(x)).collect();
            let dtdq = kinetic(model, p, &qk, &qdk).eps;
            let dvdq = potential(model, p, &qk).eps;
            ddt - dtdq + dvdq
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// `Y(q, q̇, q̈) π` equals the torques of RNEA for random robots (chains
    /// and trees with fixed joints), parameters, friction, base
    /// orientations and gravity.
    #[test]
    fn regressor_times_parameters_is_rnea(
        (spec, bodies, (q, qd, qdd), g, base, friction) in case(7, true, true)
    ) {
        let model = with_stribeck(&spec, settings(g, base, all_columns()));
        let p = parameters(&model, &bodies, &friction);
        let y = model.regressor(&q, &qd, &qdd).unwrap();
        let tau = model.inverse_dynamics(&p, &q, &qd, &qdd).unwrap();
        let n = model.dof();
        let scale = 1.0 + max_abs(&tau);
        for j in 0..n {
            let yp: f64 = (0..p.len()).map(|c| y[n * c + j] * p[c]).sum();
            prop_assert!((yp - tau[j]).abs() <= 1e-12 * scale * 100.0, "joint {j}: Yπ {yp} RNEA {}", tau[j]);
        }
    }

    /// RNEA equals the Lagrangian `d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q` built from
    /// the forward kinematics alone.
    #[test]
    fn rnea_is_the_lagrangian(
        (spec, bodies, (q, qd, qdd), g, base, _f) in case(6, true, true)
    ) {
        let model = UrdfModel::from_urdf_str(&spec.urdf(), "random.urdf", settings(g, base, JointColumns::none())).unwrap();
        let p = parameters(&model, &bodies, &[]);
        let tau = model.inverse_dynamics(&p, &q, &qd, &qdd).unwrap();
        let lag = lagrangian(&model, &p, &q, &qd, &qdd);
        let scale = 1.0 + max_abs(&tau);
        for j in 0..model.dof() {
            prop_assert!((lag[j] - tau[j]).abs() <= 1e-10 * scale, "joint {j}: Lagrangian {} RNEA {}", lag[j], tau[j]);
        }
    }

    /// The power balance `dT/dt = q̇ᵀ (τ − g(q))` of the rigid bodies along
    /// random motions (`g = τ(q, 0, 0)`).
    #[test]
    fn energy_balance(
        (spec, bodies, (q, qd, qdd), g, base, _f) in case(7, true, true)
    ) {
        let model = UrdfModel::from_urdf_str(&spec.urdf(), "random.urdf", settings(g, base, JointColumns::none())).unwrap();
        let p = parameters(&model, &bodies, &[]);
        let n = model.dof();
        let tau = model.inverse_dynamics(&p, &q, &qd, &qdd).unwrap();
        let zero = vec![0.0; n];
        let grav = model.inverse_dynamics(&p, &q, &zero, &zero).unwrap();
        let x: Vec<Dual64> = (0..n).map(|i| Dual64::new(q[i], qd[i])).collect();
        let xd: Vec<Dual64> = (0..n).map(|i| Dual64::new(qd[i], qdd[i])).collect();
        let dtdt = kinetic(&model, &p, &x, &xd).eps;
        let power: f64 = (0..n).map(|i| qd[i] * (tau[i] - grav[i])).sum();
        let scale = 1.0 + max_abs(&tau) * max_abs(&qd) * n as f64;
        prop_assert!((dtdt - power).abs() <= 1e-11 * scale, "dT/dt {dtdt} power {power}");
    }

    /// A fixed joint merged into its parent gives the torques of the same
    /// joint made revolute and held at zero, with the joints in the same
    /// order otherwise.
    #[test]
    fn merged_fixed_joints_are_the_free_joints_at_rest(
        (spec, _b, _s, g, base, _f) in case(6, true, true),
        states in proptest::collection::vec((-3.0..3.0f64, -3.0..3.0f64, -10.0..10.0f64), 8),
    ) {
        let fixed = spec.joints.iter().position(|j| j.kind == "fixed");
        prop_assume!(fixed.is_some());
        let merged = UrdfModel::from_urdf_str(&spec.urdf(), "merged.urdf", settings(g, base, JointColumns::none())).unwrap();
        let mut free_spec = spec.clone();
        for j in free_spec.joints.iter_mut().filter(|j| j.kind == "fixed") {
            j.kind = "revolute";
        }
        let free = UrdfModel::from_urdf_str(&free_spec.urdf(), "free.urdf", settings(g, base, JointColumns::none())).unwrap();
        let names = merged.joint_names();
        let at: Vec<usize> = names
            .iter()
            .map(|n| free.joint_names().iter().position(|f| f == n).unwrap())
            .collect();
        let (n, nf) = (merged.dof(), free.dof());
        let (mut q, mut qd, mut qdd) = (vec![0.0; nf], vec![0.0; nf], vec![0.0; nf]);
        for (k, &i) in at.iter().enumerate() {
            let s = states[k % states.len()];
            (q[i], qd[i], qdd[i]) = s;
        }
        let pick = |v: &[f64]| at.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        let tm = merged.inverse_dynamics(&merged.urdf_parameters(), &pick(&q), &pick(&qd), &pick(&qdd)).unwrap();
        let tf = free.inverse_dynamics(&free.urdf_parameters(), &q, &qd, &qdd).unwrap();
        let scale = 1.0 + max_abs(&tf);
        for k in 0..n {
            prop_assert!((tm[k] - tf[at[k]]).abs() <= 1e-12 * scale * 100.0, "joint {}: merged {} free {}", names[k], tm[k], tf[at[k]]);
        }
    }

    /// The rows in dual numbers have the `f64` rows as real parts and
    /// their derivatives agree with central differences.
    #[test]
    fn dual_rows_are_the_rows_and_their_derivatives(
        (spec, _b, (q, qd, qdd), g, base, _f) in case(5, true, true),
        direction in 0usize..18,
    ) {
        let model = with_stribeck(&spec, settings(g, base, all_columns()));
        let n = model.dof();
        let k = direction % (3 * n);
        prop_assume!(k < 6);
        let seed = |v: &[f64], off: usize| -> Vec<Dual> {
            v.iter().enumerate().map(|(i, &x)| {
                let d = Dual::from_re(x);
                if off + i == k { d.derivative(k) } else { d }
            }).collect()
        };
        let (x, xd, xdd) = (seed(&q, 0), seed(&qd, n), seed(&qdd, 2 * n));
        let cols = model.columns();
        let mut rows = vec![Dual::from_re(0.0); n * cols];
        model.fill_dual(&x, &xd, &xdd, &mut rows).unwrap();
        let mut plain = vec![0.0; n * cols];
        model.fill(&q, &qd, &qdd, &mut plain).unwrap();
        let h = 1e-6;
        let shifted = |s: f64| {
            let mut st = [q.clone(), qd.clone(), qdd.clone()];
            st[k / n][k % n] += s;
            model.regressor(&st[0], &st[1], &st[2]).unwrap()
        };
        let (up, down) = (shifted(h), shifted(-h));
        for e in 0..n * cols {
            prop_assert!((rows[e].re - plain[e]).abs() <= 1e-12 * (1.0 + plain[e].abs()));
            let fd = (up[e] - down[e]) / (2.0 * h);
            let d = rows[e].eps.0.as_ref().map_or(0.0, |g| g[k]);
            prop_assert!((d - fd).abs() <= 1e-5 * (1.0 + fd.abs()), "entry {e}: dual {d} differences {fd}");
        }
    }
}

/// The parameters the URDF gives reproduce the torques of the same URDF
/// with the inertial origins rotated and the tensors turned to match: the
/// rotation of an `<inertial>` frame is applied.
#[test]
fn inertial_rotation_is_applied() {
    let urdf = |rpy: &str, i: [f64; 6]| {
        format!(
            r#"<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="0.1 0.02 -0.03" rpy="{rpy}"/><mass value="2"/>
    <inertia ixx="{}" ixy="{}" ixz="{}" iyy="{}" iyz="{}" izz="{}"/></inertial></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/></joint>
</robot>"#,
            i[0], i[1], i[2], i[3], i[4], i[5]
        )
    };
    // diag(0.01, 0.02, 0.03) turned by 90° about z is diag(0.02, 0.01, 0.03).
    let a = UrdfModel::from_urdf_str(
        &urdf("0 0 1.5707963267948966", [0.01, 0.0, 0.0, 0.02, 0.0, 0.03]),
        "a",
        ModelSettings::default(),
    )
    .unwrap();
    let b = UrdfModel::from_urdf_str(
        &urdf("0 0 0", [0.02, 0.0, 0.0, 0.01, 0.0, 0.03]),
        "b",
        ModelSettings::default(),
    )
    .unwrap();
    let (pa, pb) = (a.urdf_parameters(), b.urdf_parameters());
    for (x, y) in pa.iter().zip(&pb) {
        assert!((x - y).abs() < 1e-15, "{pa:?} vs {pb:?}");
    }
    // m c = (0.2, 0.04, −0.06); Iyy about the origin = 0.01 + 2 (0.1² + 0.03²).
    assert!((pa[1] - 0.2).abs() < 1e-15 && (pa[3] + 0.06).abs() < 1e-15);
    assert!((pa[6] - (0.01 + 2.0 * (0.01 + 0.0009))).abs() < 1e-15);
}
