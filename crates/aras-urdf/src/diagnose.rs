//! Where a URDF robot's model and its logs disagree: the toolkit's
//! diagnosis engine (`aras-diagnose`) with the effects a serial arm's
//! joints show beyond the model's columns (`docs/urdf.md`, "Diagnose").
//!
//! The starting model is the URDF model itself (rigid bodies, and per
//! joint its friction, offset and armature columns); the candidates are,
//! per joint, friction above the Coulomb level at low speed (Stribeck), a
//! torque offset (when the model has none) and a spring on the joint's
//! angle, and a shift of every torque against the angles. Every row is
//! fitted and scored: the model's Coulomb law is the smooth `tanh(q̇/w)`,
//! so the velocity reversals are modelled rather than left out.

use aras_diagnose::{
    Candidate, ConsistentRefit, ConsistentSolution, Dataset, Diagnosis, DiagnosisModel,
    EngineOptions, SearchScale,
};
use aras_ident::{BaseParameters, ConsistentLs, IdentError, ReducedLs};
use aras_log::Log;
use aras_signal::{OutputRows, Samples};
use faer::Mat;
use serde::Serialize;

use crate::identify::{
    IdentifyError, IdentifySettings, consistent_problem, process, quasi_random_samples,
    signed_parameters,
};
use crate::{CoulombWidth, UrdfModel};

/// One candidate effect of a URDF robot with its setting.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum UrdfCandidate {
    /// Friction above the Coulomb level at low speed on one joint: the
    /// column `s(q̇) exp(−(q̇/v_s)²)`, `s` the model's Coulomb sign law.
    StribeckFriction {
        /// Joint index, 0-based.
        joint: usize,
        /// The joint's name.
        name: String,
        /// Stribeck velocity, rad/s (m/s).
        v_s: f64,
    },
    /// A constant torque on one joint.
    TorqueOffset {
        /// Joint index, 0-based.
        joint: usize,
        /// The joint's name.
        name: String,
    },
    /// A torque proportional to one joint's position.
    JointSpring {
        /// Joint index, 0-based.
        joint: usize,
        /// The joint's name.
        name: String,
    },
    /// Every torque taken this many samples after the angles.
    TimeDelay {
        /// Samples (negative: before; fractions interpolate).
        samples: f64,
    },
}

impl Candidate for UrdfCandidate {
    fn id(&self) -> String {
        match self {
            UrdfCandidate::StribeckFriction { name, .. } => format!("stribeck_friction:{name}"),
            UrdfCandidate::TorqueOffset { name, .. } => format!("torque_offset:{name}"),
            UrdfCandidate::JointSpring { name, .. } => format!("joint_spring:{name}"),
            UrdfCandidate::TimeDelay { .. } => "time_delay".into(),
        }
    }
    fn label(&self) -> String {
        match self {
            UrdfCandidate::StribeckFriction { name, v_s, .. } => {
                format!("stribeck_friction:{name}(v_s = {v_s:.4} rad/s)")
            }
            UrdfCandidate::TimeDelay { samples } => format!("time_delay({samples:+.2} samples)"),
            _ => self.id(),
        }
    }
    fn explanation(&self) -> String {
        match self {
            UrdfCandidate::StribeckFriction { .. } => {
                "friction rises above the Coulomb level at low speed and decays with the \
                 Stribeck velocity v_s (boundary lubrication in gears and bearings); the \
                 residual peaks, with the sign of the velocity, just after each reversal"
            }
            UrdfCandidate::TorqueOffset { .. } => {
                "a constant torque on the joint (a torque sensor's or amplifier's offset, an \
                 unmodelled static load); the residual has a constant mean"
            }
            UrdfCandidate::JointSpring { .. } => {
                "a torque proportional to the joint's position (a cable, a hose, a gravity \
                 compensator spring); the residual grows linearly with the angle"
            }
            UrdfCandidate::TimeDelay { .. } => {
                "torque and angle samples are not simultaneous (current-loop or bus latency, \
                 a held command logged as sampled); the residual follows the torque's rate"
            }
        }
        .into()
    }
    fn parameter_names(&self) -> Vec<String> {
        match self {
            UrdfCandidate::StribeckFriction { name, .. } => vec![format!("{name}.Fs")],
            UrdfCandidate::TorqueOffset { name, .. } => vec![format!("{name}.offset")],
            UrdfCandidate::JointSpring { name, .. } => vec![format!("{name}.k")],
            UrdfCandidate::TimeDelay { .. } => Vec::new(),
        }
    }
    fn torque_shift(&self) -> Option<f64> {
        match self {
            UrdfCandidate::TimeDelay { samples } => Some(*samples),
            _ => None,
        }
    }
    fn setting(&self) -> Option<(&str, f64)> {
        match self {
            UrdfCandidate::StribeckFriction { v_s, .. } => Some(("v_s", *v_s)),
            UrdfCandidate::TimeDelay { samples } => Some(("samples", *samples)),
            _ => None,
        }
    }
    fn search_scale(&self) -> Option<SearchScale> {
        match self {
            UrdfCandidate::StribeckFriction { .. } => Some(SearchScale::Log { factor: 3.0 }),
            UrdfCandidate::TimeDelay { samples } => Some(SearchScale::Linear {
                half_width: (0.5 * samples.abs()).max(1.0),
            }),
            _ => None,
        }
    }
    fn joints(&self) -> Option<Vec<usize>> {
        match self {
            UrdfCandidate::StribeckFriction { joint, .. }
            | UrdfCandidate::TorqueOffset { joint, .. }
            | UrdfCandidate::JointSpring { joint, .. } => Some(vec![*joint]),
            UrdfCandidate::TimeDelay { .. } => None,
        }
    }
    fn with_setting(&self, value: f64) -> Self {
        let mut c = self.clone();
        match &mut c {
            UrdfCandidate::StribeckFriction { v_s, .. } => *v_s = value,
            UrdfCandidate::TimeDelay { samples } => *samples = value,
            _ => {}
        }
        c
    }
}

/// Settings of [`diagnose`], defaults in [`DiagnoseSettings::default`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnoseSettings {
    /// The training log's period, s (`None`: its sidecar, else detected);
    /// the validation logs' periods come from their sidecars.
    pub period: Option<f64>,
    /// Quasi-random states the base parameters are computed from.
    pub base_states: usize,
    /// Mass bounds of the final model's physically consistent
    /// re-identification, a fraction of each body's URDF mass (as
    /// identification's).
    pub mass_tolerance: f64,
    /// Stribeck velocities scanned per joint, rad/s (m/s), refined
    /// between them once added.
    pub stribeck_v_s: Vec<f64>,
    /// Torque-against-angle shifts scanned, samples (refined once added).
    pub delays: Vec<f64>,
    /// Try a spring on every joint.
    pub springs: bool,
    /// Significance, minimum gain and steps of the engine. By default its
    /// row exclusion near reversals is off (`min_speed` 0: the model's
    /// Coulomb law is smooth) and the minimum gain is 0.01 points of (78)
    /// on the joint a candidate acts on: an arm's proximal joints carry
    /// gravity torques a hundred times their friction, so a friction
    /// effect that matters for control at low speed moves their (78) by
    /// hundredths of a point; the F-test and a gain on every validation
    /// log keep the false names out (`docs/urdf.md`, "Diagnose").
    pub engine: EngineOptions,
}

impl Default for DiagnoseSettings {
    /// 600 states; `v_s` 0.01, 0.02, 0.05, 0.1, 0.2 rad/s; shifts ±0.5,
    /// 1, 2, 3, 5 samples; springs on; the engine's defaults on every row
    /// with a 0.01-point minimum gain.
    fn default() -> Self {
        Self {
            period: None,
            base_states: 600,
            mass_tolerance: IdentifySettings::default().mass_tolerance,
            stribeck_v_s: vec![0.01, 0.02, 0.05, 0.1, 0.2],
            delays: [0.5, 1.0, 2.0, 3.0, 5.0]
                .iter()
                .flat_map(|&d| [d, -d])
                .collect(),
            springs: true,
            engine: EngineOptions {
                min_speed: 0.0,
                min_gain: 0.01,
                ..EngineOptions::default()
            },
        }
    }
}

/// The candidates [`diagnose`] scans for `model` with `settings`, in a
/// fixed order.
pub fn candidates(model: &UrdfModel, settings: &DiagnoseSettings) -> Vec<UrdfCandidate> {
    let names = model.joint_names();
    let mut out = Vec::new();
    for (joint, name) in names.iter().enumerate() {
        let name = name.clone();
        // A joint whose model has a Stribeck column already is not offered
        // another.
        let has_stribeck = model.stribeck_columns().iter().any(|(j, _)| *j == joint);
        out.extend(
            settings
                .stribeck_v_s
                .iter()
                .filter(|_| !has_stribeck)
                .map(|&v_s| UrdfCandidate::StribeckFriction {
                    joint,
                    name: name.clone(),
                    v_s,
                }),
        );
        if !model.joint_columns().offset {
            out.push(UrdfCandidate::TorqueOffset {
                joint,
                name: name.clone(),
            });
        }
        if settings.springs {
            out.push(UrdfCandidate::JointSpring { joint, name });
        }
    }
    out.extend(
        settings
            .delays
            .iter()
            .map(|&samples| UrdfCandidate::TimeDelay { samples }),
    );
    out
}

/// The model as the engine sees it.
struct Engine<'a> {
    model: &'a UrdfModel,
    base: BaseParameters,
    base_states: usize,
    mass_tolerance: f64,
    widths: Vec<f64>,
}

/// A window: the model's standard regressor on its samples (joint-major)
/// and their joint positions and rates.
struct Window {
    w: Mat<f64>,
    q: Vec<Vec<f64>>,
    v: Vec<Vec<f64>>,
}

impl DiagnosisModel for Engine<'_> {
    type Candidate = UrdfCandidate;
    type Window = Window;
    type Terms = Vec<String>;
    type Refit = Refit;

    fn joints(&self) -> usize {
        self.model.dof()
    }
    fn n_base(&self) -> usize {
        self.base.n_base()
    }
    fn base_name(&self, column: usize) -> String {
        self.base.expression(column)
    }
    fn window(&self, s: &Samples, first: usize) -> Result<Window, IdentError> {
        let w = self
            .model
            .regressor_on(s)
            .map_err(|e| IdentError::External {
                context: format!("the regressor on the samples from {first}"),
                source: Box::new(e),
            })?;
        Ok(Window {
            w,
            q: s.x.clone(),
            v: s.x_dot.clone(),
        })
    }
    fn base_columns(&self, w: &Window) -> Result<Mat<f64>, IdentError> {
        self.base.base_regressor(w.w.as_ref())
    }
    fn candidate_columns(&self, c: &UrdfCandidate, w: &Window) -> Result<Mat<f64>, IdentError> {
        Ok(candidate_columns(&self.widths, c, w))
    }
    fn term_names(&self) -> Vec<String> {
        let c = self.model.joint_columns();
        let mut t = vec!["rigid_bodies".to_owned()];
        for (on, name) in [
            (c.viscous, "viscous"),
            (c.coulomb, "coulomb"),
            (c.offset, "offset"),
            (c.armature, "armature"),
        ] {
            if on {
                t.push(name.into());
            }
        }
        let names = self.model.joint_names();
        for (j, v_s) in self.model.stribeck_columns() {
            t.push(format!("stribeck:{}(v_s = {v_s:.4} rad/s)", names[*j]));
        }
        t
    }
    fn terms(&self, added: &[UrdfCandidate]) -> Result<Vec<String>, IdentError> {
        let mut t = self.term_names();
        t.extend(added.iter().map(Candidate::label));
        Ok(t)
    }
    fn consistent_refit(&self, added: &[UrdfCandidate]) -> Result<Option<Refit>, IdentError> {
        Refit::new(self, added).map(Some)
    }
}

/// The columns of candidate `c` on window `w` (joint-major, one per
/// parameter), with the model's Coulomb widths per joint; none for a
/// torque shift, which the engine applies itself.
fn candidate_columns(widths: &[f64], c: &UrdfCandidate, w: &Window) -> Mat<f64> {
    let n = w.q.len();
    let m = w.q.first().map_or(0, Vec::len);
    let column = |joint: usize, f: &dyn Fn(usize) -> f64| {
        Mat::from_fn(
            n * m,
            1,
            |r, _| if r / m.max(1) == joint { f(r % m) } else { 0.0 },
        )
    };
    match c {
        UrdfCandidate::StribeckFriction { joint, v_s, .. } => {
            let j = *joint;
            column(j, &|r| {
                crate::dynamics::stribeck(w.v[j][r], widths[j], *v_s)
            })
        }
        UrdfCandidate::TorqueOffset { joint, .. } => column(*joint, &|_| 1.0),
        UrdfCandidate::JointSpring { joint, .. } => column(*joint, &|r| w.q[*joint][r]),
        UrdfCandidate::TimeDelay { .. } => Mat::zeros(n * m, 0),
    }
}

/// The model's standard regressor on `w` with the columns of `added` after
/// it, joint-major.
fn extended(widths: &[f64], added: &[UrdfCandidate], w: &Window) -> Mat<f64> {
    let extra: Vec<Mat<f64>> = added
        .iter()
        .map(|c| candidate_columns(widths, c, w))
        .collect();
    let cols = w.w.ncols() + extra.iter().map(Mat::ncols).sum::<usize>();
    let mut out = Mat::<f64>::zeros(w.w.nrows(), cols);
    out.as_mut()
        .subcols_mut(0, w.w.ncols())
        .copy_from(w.w.as_ref());
    let mut at = w.w.ncols();
    for e in &extra {
        out.as_mut()
            .subcols_mut(at, e.ncols())
            .copy_from(e.as_ref());
        at += e.ncols();
    }
    out
}

/// The physically consistent re-identification of the final model: the
/// URDF model's standard parameters and the added effects' (a Stribeck
/// level, an offset, a spring), its own base parameters from the
/// quasi-random states of [`UrdfModel::base_parameters`] with the added
/// columns on them, and identification's SDP (one pseudo-inertia per body,
/// masses within the tolerance, friction, armature and every Stribeck
/// level ≥ 0: friction above the Coulomb level at low speed).
struct Refit {
    widths: Vec<f64>,
    added: Vec<UrdfCandidate>,
    names: Vec<String>,
    base: BaseParameters,
    problem: ConsistentLs,
}

impl Refit {
    fn new(engine: &Engine<'_>, added: &[UrdfCandidate]) -> Result<Self, IdentError> {
        let model = engine.model;
        let added: Vec<UrdfCandidate> = added
            .iter()
            .filter(|c| c.torque_shift().is_none())
            .cloned()
            .collect();
        let mut names = model.parameter_names();
        let mut reference = model.urdf_parameters();
        let mut signed = signed_parameters(model);
        for c in &added {
            let p = c.parameter_names();
            if matches!(c, UrdfCandidate::StribeckFriction { .. }) {
                signed.extend(p.iter().cloned());
            }
            reference.extend(std::iter::repeat_n(0.0, p.len()));
            names.extend(p);
        }
        let window = engine.window(&quasi_random_samples(model, engine.base_states), 0)?;
        let w = extended(&engine.widths, &added, &window);
        let base =
            BaseParameters::from_regressor(w.as_ref(), &names, aras_ident::DEFAULT_RANK_TOLERANCE)?;
        let problem = consistent_problem(model, &names, reference, engine.mass_tolerance, &signed)?;
        Ok(Self {
            widths: engine.widths.clone(),
            added,
            names,
            base,
            problem,
        })
    }
}

impl ConsistentRefit<Window> for Refit {
    fn base_names(&self) -> Vec<String> {
        self.base.base_names()
    }

    fn base_columns(&self, window: &Window) -> Result<Mat<f64>, IdentError> {
        self.base
            .base_regressor(extended(&self.widths, &self.added, window).as_ref())
    }

    fn solve(&self, reduced: &ReducedLs) -> Result<ConsistentSolution, IdentError> {
        let sol = self.problem.solve(&self.base, reduced)?;
        ConsistentSolution::from_standard(sol.status, &self.base, &self.names, &sol.standard)
    }
}

/// Finds which effects `model` misses on `train`, judged on the
/// `validation` logs (other motions of the same robot): each log processed
/// as identification processes it (the validation logs with their
/// sidecars' periods), the engine of `aras-diagnose` over
/// [`candidates`], every row fitted and scored.
///
/// # Errors
/// [`IdentifyError`] when a log's joints are not the model's, a log cannot
/// be processed, or the engine refuses a setting.
pub fn diagnose(
    model: &UrdfModel,
    train: &Log,
    validation: &[Log],
    settings: &DiagnoseSettings,
) -> Result<Diagnosis<UrdfCandidate, Vec<String>>, IdentifyError> {
    let n = model.dof();
    let widths = match &model.settings().coulomb_width {
        CoulombWidth::Uniform(w) => vec![*w; n],
        CoulombWidth::PerJoint(w) => w.clone(),
    };
    let engine = Engine {
        model,
        base: model.base_parameters(settings.base_states)?,
        base_states: settings.base_states,
        mass_tolerance: settings.mass_tolerance,
        widths,
    };
    let set = |name: &str, log: &Log, period: Option<f64>| -> Result<Dataset, IdentifyError> {
        let processed = process(model, log, period, OutputRows::Averaged, false)?;
        Ok(Dataset::from_processed_owned(name, processed)?)
    };
    let train_set = set("train", train, settings.period)?;
    let validation_sets = validation
        .iter()
        .map(|l| set(&l.name, l, None))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(aras_diagnose::diagnose(
        &engine,
        candidates(model, settings),
        &train_set,
        &validation_sets,
        &settings.engine,
    )?)
}
