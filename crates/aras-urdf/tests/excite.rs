//! An excitation for the Panda designed by aras-excite within the URDF's
//! joint and velocity limits: feasible, and far better conditioned than
//! random feasible trajectories.

mod common;

use aras_excite::{DesignSettings, assess, base_projection, design, random_feasible};
use aras_ident::BaseParameters;
use aras_urdf::{ModelSettings, UrdfModel};
use common::{ALL, PANDA, panda};

/// The Panda (every joint column) and its base parameters.
fn panda_and_base() -> (UrdfModel, BaseParameters) {
    let model = panda(ALL, [0.0, 0.0, -9.81]);
    let base = model.base_parameters(600).unwrap();
    (model, base)
}

/// Two starts of the default design (5 harmonics, 10 s period) within the
/// URDF's limits shrunk by 10 %, 10 rad/s²: κ 6.9 against a median of 24.4
/// over 100 random feasible trajectories (the test asserts ≥ 2.5× lower),
/// and every joint inside its limits on a grid ten times finer than the
/// design's.
#[test]
fn the_panda_excitation_is_feasible_and_well_conditioned() {
    let (model, base) = panda_and_base();
    let projection = base_projection(&base);
    let limits = model.excitation_limits(0.1, 10.0).unwrap();
    let settings = DesignSettings {
        starts: 2,
        ..DesignSettings::new(limits.clone())
    };
    let mut random: Vec<f64> = random_feasible(&settings, 100, 7)
        .unwrap()
        .iter()
        .map(|t| {
            assess(&model, &projection, t, settings.criterion_points)
                .unwrap()
                .condition_number
        })
        .collect();
    random.sort_by(f64::total_cmp);
    let median = random[50];
    let d = design(&model, &projection, &settings).unwrap();
    let kappa = d.assessment.condition_number;
    assert!(kappa * 2.5 <= median, "κ {kappa} vs random median {median}");
    let n = model.dof();
    let traj = &d.trajectory;
    let (mut q, mut v, mut a) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let steps = 10 * settings.constraint_points;
    for k in 0..steps {
        traj.eval_into(
            traj.period() * k as f64 / steps as f64,
            &mut q,
            &mut v,
            &mut a,
        );
        for j in 0..n {
            assert!(
                q[j] >= limits.min[j] - 1e-9 && q[j] <= limits.max[j] + 1e-9,
                "joint {j}: {}",
                q[j]
            );
            assert!(
                v[j].abs() <= limits.max_rate[j] + 1e-9,
                "joint {j}: rate {}",
                v[j]
            );
            assert!(
                a[j].abs() <= limits.max_accel[j] + 1e-9,
                "joint {j}: accel {}",
                a[j]
            );
        }
    }
    // A joint without limits cannot be excited within them.
    let text = std::fs::read_to_string(PANDA).unwrap().replacen(
        "type=\"revolute\"",
        "type=\"continuous\"",
        1,
    );
    let open = UrdfModel::from_urdf_str(&text, "open.urdf", ModelSettings::default()).unwrap();
    let e = open.excitation_limits(0.1, 10.0).unwrap_err().to_string();
    assert!(e.contains("limits of joint `panda_joint1`"), "{e}");
}
