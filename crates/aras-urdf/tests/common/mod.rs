//! Random URDFs and physically consistent parameters for the property
//! tests.

#![allow(dead_code)]

use aras_excite::FourierTrajectory;
use aras_urdf::{CoulombWidth, JointColumns, ModelSettings, UrdfModel};
use nalgebra::Dyn;
use proptest::prelude::*;

/// The Panda fixture (its hand and fingers fixed to link 7).
pub const PANDA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../fixtures/urdf/panda_arm.urdf"
);

/// Every joint column: viscous, Coulomb, offset, armature.
pub const ALL: JointColumns = JointColumns {
    viscous: true,
    coulomb: true,
    offset: true,
    armature: true,
};

/// The Panda with joint `columns`, gravity `gravity` and a 0.02 rad/s
/// Coulomb width.
pub fn panda(columns: JointColumns, gravity: [f64; 3]) -> UrdfModel {
    let settings = ModelSettings {
        gravity,
        columns,
        coulomb_width: CoulombWidth::Uniform(0.02),
        ..ModelSettings::default()
    };
    UrdfModel::from_file(PANDA, settings).unwrap()
}

/// A fixed additive-recurrence sequence in [−1, 1).
pub fn sequence() -> impl FnMut() -> f64 {
    let mut u = 0.5f64;
    move || {
        u = (u + 0.618_033_988_749_895) % 1.0;
        2.0 * u - 1.0
    }
}

/// The 10 s excitation of the tests (five harmonics per joint of random
/// sizes about the middle of its limits; `skip` draws discarded first, for
/// another trajectory), and the offsets.
pub fn excitation(model: &UrdfModel, skip: usize) -> (Vec<f64>, FourierTrajectory<Dyn>) {
    let mut next = sequence();
    for _ in 0..skip {
        next();
    }
    let (mut offset, mut a, mut b) = (Vec::new(), Vec::new(), Vec::new());
    for j in model.joints() {
        let l = j.limits.unwrap();
        offset.push(0.5 * (l.lower.unwrap() + l.upper.unwrap()));
        a.push((0..5).map(|_| 0.25 * next()).collect::<Vec<_>>());
        b.push((0..5).map(|_| 0.25 * next()).collect::<Vec<_>>());
    }
    let omega = std::f64::consts::TAU / 10.0;
    let trajectory = FourierTrajectory::<Dyn>::new(omega, offset.clone(), a, b).unwrap();
    (offset, trajectory)
}

/// One link's inertial: mass, centre of mass, the inertial frame's rpy and
/// the second moments of its mass distribution along the frame's axes
/// (so the moments `d_y + d_z, …` always satisfy the triangle inequality).
#[derive(Debug, Clone)]
pub struct LinkSpec {
    pub mass: f64,
    pub com: [f64; 3],
    pub rpy: [f64; 3],
    pub spread: [f64; 3],
}

/// One joint: its type, the index of its parent link (its child is the
/// next link), origin and axis.
#[derive(Debug, Clone)]
pub struct JointSpec {
    pub kind: &'static str,
    pub parent: usize,
    pub xyz: [f64; 3],
    pub rpy: [f64; 3],
    pub axis: [f64; 3],
}

/// A robot: `links[0]` is the root; joint `k` moves `links[k + 1]`.
#[derive(Debug, Clone)]
pub struct RobotSpec {
    pub links: Vec<LinkSpec>,
    pub joints: Vec<JointSpec>,
}

impl LinkSpec {
    /// `ixx, ixy, ixz, iyy, iyz, izz` about the centre of mass, in the
    /// inertial frame.
    pub fn inertia(&self) -> [f64; 6] {
        let [a, b, c] = self.spread.map(|d| self.mass * d);
        [b + c, 0.0, 0.0, a + c, 0.0, a + b]
    }
}

impl RobotSpec {
    pub fn urdf(&self) -> String {
        let mut s = String::from("<?xml version=\"1.0\"?>\n<robot name=\"random\">\n");
        for (i, l) in self.links.iter().enumerate() {
            let [xx, xy, xz, yy, yz, zz] = l.inertia();
            s += &format!(
                "  <link name=\"l{i}\">\n    <inertial>\n      <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\n      <mass value=\"{}\"/>\n      <inertia ixx=\"{xx}\" ixy=\"{xy}\" ixz=\"{xz}\" iyy=\"{yy}\" iyz=\"{yz}\" izz=\"{zz}\"/>\n    </inertial>\n  </link>\n",
                l.com[0], l.com[1], l.com[2], l.rpy[0], l.rpy[1], l.rpy[2], l.mass
            );
        }
        for (k, j) in self.joints.iter().enumerate() {
            s += &format!(
                "  <joint name=\"j{k}\" type=\"{}\">\n    <parent link=\"l{}\"/>\n    <child link=\"l{}\"/>\n    <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\n    <axis xyz=\"{} {} {}\"/>\n    <limit lower=\"-3\" upper=\"3\" effort=\"100\" velocity=\"5\"/>\n  </joint>\n",
                j.kind,
                j.parent,
                k + 1,
                j.xyz[0],
                j.xyz[1],
                j.xyz[2],
                j.rpy[0],
                j.rpy[1],
                j.rpy[2],
                j.axis[0],
                j.axis[1],
                j.axis[2]
            );
        }
        s + "</robot>\n"
    }

    /// Movable joints.
    pub fn dof(&self) -> usize {
        self.joints.iter().filter(|j| j.kind != "fixed").count()
    }
}

fn v3(r: f64) -> impl Strategy<Value = [f64; 3]> {
    [-r..r, -r..r, -r..r]
}

fn axis() -> impl Strategy<Value = [f64; 3]> {
    v3(1.0).prop_filter("non-zero axis", |a| {
        a.iter().map(|x| x * x).sum::<f64>() > 0.05
    })
}

pub fn link() -> impl Strategy<Value = LinkSpec> {
    (
        0.2..5.0f64,
        v3(0.2),
        v3(3.2),
        [0.001..0.05f64, 0.001..0.05, 0.001..0.05],
    )
        .prop_map(|(mass, com, rpy, spread)| LinkSpec {
            mass,
            com,
            rpy,
            spread,
        })
}

/// A robot of `2..=max` links; `fixed` allows fixed joints, `tree`
/// branches. The first joint always moves.
pub fn robot(max: usize, fixed: bool, tree: bool) -> impl Strategy<Value = RobotSpec> {
    (2..=max)
        .prop_flat_map(move |n| {
            let joints = proptest::collection::vec(
                (
                    0..if fixed { 4usize } else { 3 },
                    0.0..1.0f64,
                    v3(0.4),
                    v3(3.2),
                    axis(),
                ),
                n - 1,
            );
            (proptest::collection::vec(link(), n), joints)
        })
        .prop_map(move |(links, joints)| RobotSpec {
            links,
            joints: joints
                .into_iter()
                .enumerate()
                .map(|(k, (kind, at, xyz, rpy, axis))| JointSpec {
                    kind: if k == 0 {
                        "revolute"
                    } else {
                        ["revolute", "prismatic", "continuous", "fixed"][kind]
                    },
                    parent: if tree {
                        ((k + 1) as f64 * at) as usize
                    } else {
                        k
                    },
                    xyz,
                    rpy,
                    axis,
                })
                .collect(),
        })
}

/// A physically consistent set of body parameters `m, m c, I_O` (Pinocchio
/// order) from a mass, a centre of mass and a rotated central inertia.
pub fn body_parameters(l: &LinkSpec) -> [f64; 10] {
    let (m, c) = (l.mass, l.com);
    let r = rpy(l.rpy);
    let [xx, _, _, yy, _, zz] = l.inertia();
    let d = [xx, yy, zz];
    // R diag(d) Rᵀ + m (|c|² 1 − c cᵀ).
    let c2 = c.iter().map(|x| x * x).sum::<f64>();
    let i = |a: usize, b: usize| {
        let rot: f64 = (0..3).map(|k| r[a][k] * d[k] * r[b][k]).sum();
        rot + m * (if a == b { c2 } else { 0.0 } - c[a] * c[b])
    };
    [
        m,
        m * c[0],
        m * c[1],
        m * c[2],
        i(0, 0),
        i(0, 1),
        i(1, 1),
        i(0, 2),
        i(1, 2),
        i(2, 2),
    ]
}

pub fn rpy(a: [f64; 3]) -> [[f64; 3]; 3] {
    let (sr, cr) = a[0].sin_cos();
    let (sp, cp) = a[1].sin_cos();
    let (sy, cy) = a[2].sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// A state of `n` joints.
pub fn state(n: usize) -> impl Strategy<Value = (Vec<f64>, Vec<f64>, Vec<f64>)> {
    (
        proptest::collection::vec(-3.0..3.0f64, n),
        proptest::collection::vec(-3.0..3.0f64, n),
        proptest::collection::vec(-10.0..10.0f64, n),
    )
}

/// Largest absolute entry.
pub fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a, x| a.max(x.abs()))
}
