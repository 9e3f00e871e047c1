//! Torques and regressors of a URDF model for states read from JSON: the
//! Rust side of `scripts/check_urdf.py`, which compares them with
//! Pinocchio's.
//!
//! ```text
//! cargo run --release -p aras-urdf --example urdf_torques -- IN.json OUT.json
//! ```
//!
//! `IN.json`: `{"urdf": "robot.urdf", "settings": {…ModelSettings…},
//! "q": [[…], …], "q_dot": […], "q_ddot": […]}` (one row per state, the
//! model's joint order, which `OUT.json` names). `OUT.json`:
//! `joint_names`, `parameter_names`, `parameters` (the URDF's), per state
//! `tau` (RNEA) and `regressor` (row-major `dof × parameters`), and
//! `base_parameters` (their count on the stacked regressor of all states)
//! and `positions` (every body frame's origin in the world, per state).
//! Optional in `IN.json`: `joint_values`, the values of the joint columns
//! (viscous, Coulomb, offset, armature as the settings enable them, in the
//! parameter order) used with the URDF's inertials, and `mjcf`, a new path
//! to write the model's MJCF with those parameters to (`to_mjcf`).

use std::error::Error;
use std::path::Path;

use aras_ident::BaseParameters;
use aras_urdf::{ModelSettings, UrdfModel};
use serde::{Deserialize, Serialize};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Input {
    urdf: String,
    #[serde(default)]
    settings: ModelSettings,
    q: Vec<Vec<f64>>,
    q_dot: Vec<Vec<f64>>,
    q_ddot: Vec<Vec<f64>>,
    #[serde(default)]
    joint_values: Vec<f64>,
    #[serde(default)]
    mjcf: Option<String>,
}

#[derive(Serialize)]
struct Output {
    joint_names: Vec<String>,
    parameter_names: Vec<String>,
    parameters: Vec<f64>,
    tau: Vec<Vec<f64>>,
    regressor: Vec<Vec<f64>>,
    base_parameters: usize,
    /// Every body frame's origin in the world, per state (joint order).
    positions: Vec<Vec<[f64; 3]>>,
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, output] = args.as_slice() else {
        return Err("usage: urdf_torques IN.json OUT.json".into());
    };
    let out = Path::new(output);
    if out.exists() {
        return Err(format!("{output} exists; give a new output path").into());
    }
    let input: Input = serde_json::from_str(&std::fs::read_to_string(input)?)?;
    let model = UrdfModel::from_file(&input.urdf, input.settings)?;
    let mut params = model.urdf_parameters();
    let (n, cols) = (model.dof(), model.parameter_count());
    let links = 10 * n;
    if !input.joint_values.is_empty() {
        if input.joint_values.len() != cols - links {
            return Err(format!(
                "joint_values: {} values for {} joint columns",
                input.joint_values.len(),
                cols - links
            )
            .into());
        }
        params[links..].copy_from_slice(&input.joint_values);
    }
    if let Some(path) = &input.mjcf {
        if Path::new(path).exists() {
            return Err(format!("{path} exists; give a new MJCF path").into());
        }
        std::fs::write(path, model.to_mjcf(&params)?)?;
    }
    let states = input.q.len();
    if input.q_dot.len() != states || input.q_ddot.len() != states {
        return Err("q, q_dot and q_ddot need the same number of states".into());
    }
    let mut tau = Vec::with_capacity(states);
    let mut positions = Vec::with_capacity(states);
    let mut regressor = Vec::with_capacity(states);
    let mut stacked = faer::Mat::<f64>::zeros(n * states, cols);
    for s in 0..states {
        let (q, qd, qdd) = (&input.q[s], &input.q_dot[s], &input.q_ddot[s]);
        tau.push(model.inverse_dynamics(&params, q, qd, qdd)?);
        positions.push(model.body_poses(q)?.iter().map(|p| p.translation).collect());
        let y = model.regressor(q, qd, qdd)?;
        let mut rows = vec![0.0; n * cols];
        for j in 0..n {
            for c in 0..cols {
                rows[j * cols + c] = y[n * c + j];
                stacked[(j * states + s, c)] = y[n * c + j];
            }
        }
        regressor.push(rows);
    }
    let base = BaseParameters::from_regressor(
        stacked.as_ref(),
        &model.parameter_names(),
        aras_ident::DEFAULT_RANK_TOLERANCE,
    )?;
    let result = Output {
        joint_names: model.joint_names(),
        parameter_names: model.parameter_names(),
        parameters: params,
        tau,
        regressor,
        base_parameters: base.n_base(),
        positions,
    };
    // Atomically: a temporary file beside the output, then a rename.
    let tmp = out.with_extension("json.partial");
    std::fs::write(&tmp, serde_json::to_vec(&result)?)?;
    std::fs::rename(&tmp, out)?;
    Ok(())
}
