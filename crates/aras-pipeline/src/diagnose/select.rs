//! The ARAS-Diamond as a robot of the diagnosis engine
//! ([`aras_diagnose::DiagnosisModel`]): its starting model's base regressor
//! through the kinematics of every sample, its candidate effects as
//! single-effect models, and the SDP on its four links as the physically
//! consistent refit.

use crate::PipelineError;
use aras_diagnose::{ConsistentRefit, ConsistentSolution, DiagnosisModel, EngineOptions};
use aras_dyn::{Effect, Model, Params};
use aras_ident::{BaseParameters, ConsistentLs, IdentError, ReducedLs};
use aras_kin::{Geometry, KinematicSample, Workspace};
use aras_signal::Samples;
use faer::Mat;
use serde::Serialize;

use super::candidates::{Candidate, CandidateGrid};
use crate::prepare::{RegressorColumns, columns_on};
use crate::robot::consistent_problem;
use aras_diagnose::Dataset;

/// The result of [`diagnose`]: the engine's report with the ARAS-Diamond's
/// candidates and its models as lists of effects.
pub type Diagnosis = aras_diagnose::Diagnosis<Candidate, Vec<Effect>>;

/// One effect added ([`Diagnosis::steps`]).
pub type Step = aras_diagnose::Step<Candidate>;

/// The evidence for one candidate setting in one round.
pub type CandidateScore = aras_diagnose::CandidateScore<Candidate>;

/// Settings of [`diagnose`]; `Default` gives the documented values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnoseOptions {
    /// Candidates and their grids.
    pub grid: CandidateGrid,
    /// Family-wise significance level of one round (default
    /// [`EngineOptions`]' 0.01), split
    /// over the candidate settings of the round.
    pub alpha: f64,
    /// Smallest validation fitness gain (percentage points of (78),
    /// averaged over the joints) a candidate must bring on **every**
    /// validation set to be added (default 0.1): a statistically real but
    /// practically invisible effect is not worth parameters, and a gain on
    /// one motion only is more likely an accident of that motion than a
    /// property of the robot.
    pub min_gain: f64,
    /// At most this many effects are added (default 7).
    pub max_steps: usize,
    /// Quasi-random states for the structural base parameters (default
    /// [`crate::identify::DEFAULT_BASE_SAMPLES`], as identification).
    pub base_samples: usize,
    /// The box those states fill (default the paper's workspace (77));
    /// identification samples its configured excitation box.
    #[serde(skip)]
    pub workspace: Workspace,
    /// Joint `j`'s rows where `|θ̇_j|` is below this (rad/s), widened by the
    /// filter's reach, are left out of fits and scores (default 0.2, the
    /// identification's threshold, `robot::reversal_mask`): at velocity
    /// reversals the exact `sign` of (49) misfits the real friction
    /// (sticking, creeping, the simulator's `tanh`) by far more than the
    /// noise. Stribeck friction stays visible above this speed only for
    /// `v_s ≳ min_speed / 2` (`exp(−4) ≈ 2 %` of its level at `v_s =
    /// min_speed / 2`).
    pub min_speed: f64,
    /// TRAIN's exclusion is widened by the zero-phase filter's reach down
    /// to this fraction of its impulse-response peak (default 1e-3, as in
    /// identification: 253 samples at 10 Hz and 1 kHz).
    pub reach_tol: f64,
    /// The same for the validation sets (default 0.5: the filter's main
    /// lobe only, so that fast validation motions keep rows; the
    /// identification's cross-validation uses the same).
    pub validation_reach_tol: f64,
    /// Joint `j` is fitted and scored on every row, without the exclusion
    /// above (default: neither). Set it where the starting model's Coulomb
    /// law describes the reversals, i.e. its friction has a width refined
    /// on every row (`crate::friction_width`, `Fc tanh(θ̇/w)`), as
    /// identification's `rows = "all"` does; with the sign law (49) the
    /// reversal misfit would be offered to the candidates.
    pub all_rows: [bool; 2],
    /// Reference parameters (e.g. CAD) for the final physically consistent
    /// re-identification; `None` skips it.
    pub reference: Option<Params>,
}

impl Default for DiagnoseOptions {
    /// The engine's defaults ([`EngineOptions::default`]) with the paper's
    /// workspace, the default candidate grid and no reference.
    fn default() -> Self {
        let e = EngineOptions::default();
        Self {
            grid: CandidateGrid::default(),
            alpha: e.alpha,
            min_gain: e.min_gain,
            max_steps: e.max_steps,
            base_samples: crate::identify::DEFAULT_BASE_SAMPLES,
            workspace: Workspace::paper(),
            min_speed: e.min_speed,
            reach_tol: e.reach_tol,
            validation_reach_tol: e.validation_reach_tol,
            all_rows: [false; 2],
            reference: None,
        }
    }
}

impl DiagnoseOptions {
    /// The robot-independent part, as the engine takes it.
    pub fn engine(&self) -> EngineOptions {
        EngineOptions {
            alpha: self.alpha,
            min_gain: self.min_gain,
            max_steps: self.max_steps,
            min_speed: self.min_speed,
            reach_tol: self.reach_tol,
            validation_reach_tol: self.validation_reach_tol,
            all_rows: self.all_rows.to_vec(),
        }
    }
}

/// The ARAS-Diamond's starting model as the engine sees it.
struct Aras<'a> {
    start: &'a Model,
    geometry: &'a Geometry,
    /// Structural base of the starting model: its base regressor is the
    /// selection's base block.
    base: BaseParameters,
    /// Reference of the physically consistent refit, the box and count of
    /// the states its structural base is analysed on.
    reference: Option<&'a Params>,
    workspace: &'a Workspace,
    base_samples: usize,
}

/// A candidate effect alone, as a model whose regressor is its columns.
fn effect_model(effect: Effect, start: &Model) -> Result<Model, IdentError> {
    Model::new(vec![effect], start.gravity())
        .map_err(|e| IdentError::external(format!("candidate {}", effect.id()), e))
}

impl DiagnosisModel for Aras<'_> {
    type Candidate = Candidate;
    type Window = Vec<KinematicSample>;
    type Terms = Vec<Effect>;
    type Refit = Refit;

    fn joints(&self) -> usize {
        2
    }

    fn n_base(&self) -> usize {
        self.base.n_base()
    }

    fn base_name(&self, column: usize) -> String {
        self.base.expression(column)
    }

    fn window(&self, samples: &Samples, first: usize) -> Result<Self::Window, IdentError> {
        (0..samples.len())
            .map(|i| {
                aras_kin::evaluate(self.geometry, &samples.task(i)).map_err(|e| {
                    IdentError::external(format!("kinematics of sample {}", first + i), e)
                })
            })
            .collect()
    }

    fn base_columns(&self, window: &Self::Window) -> Result<Mat<f64>, IdentError> {
        columns_on(self.start, RegressorColumns::Base(&self.base), window, None)
            .map_err(PipelineError::into_ident)
    }

    fn candidate_columns(
        &self,
        candidate: &Candidate,
        window: &Self::Window,
    ) -> Result<Mat<f64>, IdentError> {
        match candidate {
            Candidate::Effect { effect } => columns_on(
                &effect_model(*effect, self.start)?,
                RegressorColumns::Standard,
                window,
                None,
            )
            .map_err(PipelineError::into_ident),
            Candidate::TimeDelay { .. } => Err(PipelineError::Internal(
                "columns asked of the time-delay candidate, which shifts the torques instead",
            )
            .into_ident()),
        }
    }

    fn term_names(&self) -> Vec<String> {
        self.start
            .effects()
            .iter()
            .map(|e| e.id().to_owned())
            .collect()
    }

    fn terms(&self, added: &[Candidate]) -> Result<Vec<Effect>, IdentError> {
        Ok(self.extended(added)?.effects().to_vec())
    }

    fn consistent_refit(&self, added: &[Candidate]) -> Result<Option<Refit>, IdentError> {
        let model = self.extended(added)?;
        let Some(reference) = self.reference else {
            return Ok(None);
        };
        if !model.effects().contains(&Effect::RigidLinks) {
            return Ok(None);
        }
        let base = crate::robot::base_parameters(
            &model,
            self.geometry,
            self.workspace,
            self.base_samples.max(50),
        )
        .map_err(PipelineError::into_ident)?;
        // The effects' own sign constraints (70) come with the problem.
        let problem = consistent_problem(&model, reference).map_err(PipelineError::into_ident)?;
        Ok(Some(Refit {
            model,
            base,
            problem,
        }))
    }
}

impl Aras<'_> {
    /// The starting model with the added effects (a time delay is not an
    /// effect of the model).
    fn extended(&self, added: &[Candidate]) -> Result<Model, IdentError> {
        let effects = added
            .iter()
            .filter_map(|c| match c {
                Candidate::Effect { effect } => Some(*effect),
                Candidate::TimeDelay { .. } => None,
            })
            .collect();
        super::Additions {
            effects,
            torque_delay: None,
        }
        .model(self.start)
        .map_err(PipelineError::into_ident)
    }
}

/// The physically consistent re-identification of the final model: the
/// SDP on the four links' pseudo-inertias (67)–(73) with the effects' sign
/// constraints (70), on the model's own structural base.
struct Refit {
    model: Model,
    base: BaseParameters,
    problem: ConsistentLs,
}

impl ConsistentRefit<Vec<KinematicSample>> for Refit {
    fn base_names(&self) -> Vec<String> {
        self.base.base_names()
    }

    fn base_columns(&self, window: &Vec<KinematicSample>) -> Result<Mat<f64>, IdentError> {
        columns_on(
            &self.model,
            RegressorColumns::Base(&self.base),
            window,
            None,
        )
        .map_err(PipelineError::into_ident)
    }

    fn solve(&self, reduced: &ReducedLs) -> Result<ConsistentSolution, IdentError> {
        let sol = self.problem.solve(&self.base, reduced)?;
        ConsistentSolution::from_standard(
            sol.status,
            &self.base,
            &self.model.names(),
            &sol.standard,
        )
    }
}

/// Runs the diagnosis: `start` (usually the paper's model) identified on
/// `train`, scored on `validation` (at least one set), candidates from
/// `opts.grid` (those of the effects `start` lacks), until no candidate is
/// significant ([`aras_diagnose::diagnose`]). Where a joint is fitted away
/// from its reversals (`opts.all_rows`), the candidates those rows cannot
/// see are not offered: an effect with a state (`presliding_friction`),
/// whose columns are the Coulomb law's there, and Stribeck friction with
/// `v_s < min_speed / 2` (below `exp(−4)` of its level there); a fit on
/// those rows would extrapolate wildly to the reversals.
pub fn diagnose(
    start: &Model,
    geometry: &Geometry,
    train: &Dataset,
    validation: &[Dataset],
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, PipelineError> {
    let engine = opts.engine();
    let every_row = opts.all_rows.iter().all(|&a| a);
    let cands: Vec<Candidate> = opts
        .grid
        .expand()
        .into_iter()
        .filter(|c| match c {
            Candidate::Effect { effect } => {
                let seen_away = match effect {
                    Effect::StribeckFriction { v_s } => *v_s >= 0.5 * opts.min_speed,
                    e => !e.is_stateful(),
                };
                !start.effects().iter().any(|e| e.id() == effect.id()) && (every_row || seen_away)
            }
            Candidate::TimeDelay { .. } => true,
        })
        .collect();
    for c in &cands {
        if let Candidate::Effect { effect } = c {
            effect_model(*effect, start)?;
        }
    }
    let base =
        crate::robot::base_parameters(start, geometry, &opts.workspace, opts.base_samples.max(50))?;
    let robot = Aras {
        start,
        geometry,
        base,
        reference: opts.reference.as_ref(),
        workspace: &opts.workspace,
        base_samples: opts.base_samples,
    };
    Ok(aras_diagnose::diagnose(
        &robot, cands, train, validation, &engine,
    )?)
}
