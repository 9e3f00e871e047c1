//! The selection loop: fit every candidate with the current model, score,
//! add the best significant one, repeat; refine the added candidates'
//! settings; analyse the residuals before and after; then, where the robot
//! offers one, re-identify physically consistently.

use std::time::Instant;

use aras_signal::Samples;
use faer::{Mat, MatRef};
use serde::Serialize;

use crate::chunks::{Plan, WINDOW_TOL, in_lanes, in_order};
use crate::data::{Dataset, check_rows};
use crate::filtering::{
    DEFAULT_MIN_SPEED, DEFAULT_REVERSAL_REACH, DEFAULT_VALIDATION_REACH, filter_many_columns,
};
use crate::refine::minimise_profile;
use crate::residual::{ResidualAnalysis, ResidualSummary, Row};
use aras_ident::selection::{
    Accumulator, CandidateEvaluation, CandidateSpec, EvaluationStatus, Layout, ModelFit, Selection,
    SelectionOptions, SelectionStatus, SelectionStep, fit_model, select,
};
use aras_ident::streaming::QrAccumulator;
use aras_ident::validate::FitnessSums;
use aras_ident::{IdentError, ReducedLs, SolverStatus};

/// One candidate effect with one value of its non-linear setting: what the
/// diagnosis scans, names in its report and refines.
pub trait Candidate: Clone + PartialEq + std::fmt::Debug + Serialize + Send + Sync {
    /// Stable identifier of the candidate's family (every setting of it
    /// shares it; aliases and reports name it; a family is added at most
    /// once).
    fn id(&self) -> String;
    /// A short label including the setting, unique among the candidates
    /// of one diagnosis (e.g. `stribeck_friction(v_s = 0.1 rad/s)`).
    fn label(&self) -> String;
    /// Why such an effect exists physically, and how it shows in the data.
    fn explanation(&self) -> String;
    /// Names of the candidate's regressor columns, in order (empty for a
    /// torque shift).
    fn parameter_names(&self) -> Vec<String>;
    /// `Some(samples)` if the candidate is not a regressor column but a
    /// shift of the torques against the angles by this many samples
    /// (negative: lead; fractions interpolate): the same model is fitted to
    /// the shifted torques.
    fn torque_shift(&self) -> Option<f64> {
        None
    }
    /// The continuous setting refined between the grid points once the
    /// candidate is added, `(name, value)`; `None` for a linear candidate.
    fn setting(&self) -> Option<(&str, f64)> {
        None
    }
    /// How the setting is searched around its grid value (`None` where
    /// [`Self::setting`] is).
    fn search_scale(&self) -> Option<SearchScale> {
        None
    }
    /// The values around which the refinement searches, the grid value
    /// first (default: the grid value alone).
    fn search_centres(&self) -> Vec<f64> {
        self.setting().map(|(_, v)| vec![v]).unwrap_or_default()
    }
    /// The candidate with its setting replaced by `value` (unchanged if it
    /// has none).
    fn with_setting(&self, value: f64) -> Self;
    /// The joints (0-based) whose torques the candidate acts on, whose
    /// validation gains judge it (default `None`: every joint, e.g. an
    /// effect with a parameter per joint, or a torque shift).
    fn joints(&self) -> Option<Vec<usize>> {
        None
    }
}

/// The robot as the diagnosis sees it: the starting model's base regressor
/// and the candidates' columns on a window of processed samples, for any
/// number of joints (one row block per joint, joint-major: rows
/// `j n .. (j + 1) n` are joint `j + 1`'s equation on the window's `n`
/// samples). Columns are returned unfiltered: the engine applies the data
/// set's zero-phase low-pass to them as to the torques.
pub trait DiagnosisModel: Sync {
    /// The candidate effects this robot offers.
    type Candidate: Candidate;
    /// What a window's columns are computed from, evaluated once per window
    /// and shared by the base regressor and every candidate (e.g. the
    /// kinematics of each sample).
    type Window;
    /// A model's description in the report (starting and final model).
    type Terms: Clone + PartialEq + std::fmt::Debug + Serialize;
    /// The physically consistent re-identification it offers ([`NoRefit`]
    /// if none).
    type Refit: ConsistentRefit<Self::Window>;

    /// Joints (torque equations) of the robot.
    fn joints(&self) -> usize;
    /// Base parameters of the starting model (columns of
    /// [`Self::base_columns`]).
    fn n_base(&self) -> usize;
    /// A readable definition of base parameter `column` for the report.
    fn base_name(&self, column: usize) -> String;
    /// The window's shared evaluation of `samples`, whose first sample is
    /// sample `first` of the record (for messages).
    fn window(&self, samples: &Samples, first: usize) -> Result<Self::Window, IdentError>;
    /// The starting model's base regressor on the window, joint-major
    /// (`joints · n × n_base`), unfiltered.
    fn base_columns(&self, window: &Self::Window) -> Result<Mat<f64>, IdentError>;
    /// Columns of `candidate` (`joints · n × ` its parameter count),
    /// unfiltered. Not called for a torque shift.
    fn candidate_columns(
        &self,
        candidate: &Self::Candidate,
        window: &Self::Window,
    ) -> Result<Mat<f64>, IdentError>;
    /// Names of the starting model's terms, joined with the added
    /// candidates' labels into a model's name in the fitness table.
    fn term_names(&self) -> Vec<String>;
    /// The description of the starting model with `added` appended.
    fn terms(&self, added: &[Self::Candidate]) -> Result<Self::Terms, IdentError>;
    /// The physically consistent re-identification of the starting model
    /// with `added` (`None`: not offered, or not for this model).
    fn consistent_refit(
        &self,
        added: &[Self::Candidate],
    ) -> Result<Option<Self::Refit>, IdentError>;
}

/// A physically consistent re-identification of a model (e.g. an SDP on
/// the links' pseudo-inertias): its base regressor on a window, and the
/// constrained solution of its reduced least-squares problem.
pub trait ConsistentRefit<W>: Sync {
    /// Names of the base parameters (columns of [`Self::base_columns`]).
    fn base_names(&self) -> Vec<String>;
    /// The model's base regressor on a window, joint-major, unfiltered.
    fn base_columns(&self, window: &W) -> Result<Mat<f64>, IdentError>;
    /// The constrained solution of the accumulated problem.
    fn solve(&self, reduced: &ReducedLs) -> Result<ConsistentSolution, IdentError>;
}

/// What [`ConsistentRefit::solve`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct ConsistentSolution {
    /// Solver status.
    pub status: SolverStatus,
    /// The base parameters of the solution (to predict with the base
    /// regressor).
    pub base: Vec<f64>,
    /// The named (standard) parameters reported.
    pub parameters: Vec<NamedValue>,
}

impl ConsistentSolution {
    /// The solution of a constrained problem in the standard parameters:
    /// `standard` (named by `names`, σ unknown), its base parameters by
    /// `base`.
    ///
    /// # Errors
    /// [`IdentError::DimensionMismatch`] when `standard` is not one value
    /// per name and per standard parameter of `base`.
    pub fn from_standard<S: AsRef<str>>(
        status: SolverStatus,
        base: &aras_ident::BaseParameters,
        names: &[S],
        standard: &[f64],
    ) -> Result<Self, IdentError> {
        if names.len() != standard.len() {
            return Err(IdentError::DimensionMismatch {
                what: "named standard parameters",
                expected: names.len(),
                found: standard.len(),
                hint: "give one value per name",
            });
        }
        Ok(Self {
            status,
            base: base.to_base(standard)?,
            parameters: names
                .iter()
                .zip(standard)
                .map(|(name, value)| NamedValue {
                    name: name.as_ref().to_owned(),
                    value: *value,
                    std_dev: 0.0,
                })
                .collect(),
        })
    }
}

/// No physically consistent re-identification (a robot without one).
#[derive(Debug, Clone, Copy)]
pub enum NoRefit {}

impl<W> ConsistentRefit<W> for NoRefit {
    fn base_names(&self) -> Vec<String> {
        match *self {}
    }
    fn base_columns(&self, _: &W) -> Result<Mat<f64>, IdentError> {
        match *self {}
    }
    fn solve(&self, _: &ReducedLs) -> Result<ConsistentSolution, IdentError> {
        match *self {}
    }
}

/// How a candidate's setting is searched between grid points
/// ([`Candidate::search_scale`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum SearchScale {
    /// On its logarithm, over `factor` either side of the grid value (a
    /// positive scale such as a velocity or a count per revolution).
    Log {
        /// The factor either side.
        factor: f64,
    },
    /// On the value itself, over `half_width` either side (a signed shift).
    Linear {
        /// The half-width.
        half_width: f64,
    },
}

impl SearchScale {
    /// The setting value of a search variable.
    pub fn setting_value(self, u: f64) -> f64 {
        match self {
            SearchScale::Log { .. } => u.exp(),
            SearchScale::Linear { .. } => u,
        }
    }

    /// The search interval around the grid value `v`, in the search
    /// variable.
    pub fn interval(self, v: f64) -> (f64, f64) {
        match self {
            SearchScale::Log { factor } => (v.ln() - factor.ln(), v.ln() + factor.ln()),
            SearchScale::Linear { half_width } => (v - half_width, v + half_width),
        }
    }

    /// The σ of the setting from the σ of the search variable at `u`.
    pub fn sigma(self, u: f64, sigma_u: f64) -> f64 {
        match self {
            SearchScale::Log { .. } => u.exp() * sigma_u,
            SearchScale::Linear { .. } => sigma_u,
        }
    }
}

/// Settings of the engine's [`diagnose`] that do not depend on the robot;
/// `Default` gives the documented values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EngineOptions {
    /// Family-wise significance level of one round (default 0.01), split
    /// over the candidate settings of the round.
    pub alpha: f64,
    /// Smallest validation fitness gain (percentage points of (78),
    /// averaged over the joints it acts on, [`Candidate::joints`]) a candidate must bring on **every**
    /// validation set to be added (default 0.1): a statistically real but
    /// practically invisible effect is not worth parameters, and a gain on
    /// one motion only is more likely an accident of that motion than a
    /// property of the robot.
    pub min_gain: f64,
    /// At most this many effects are added (default 7).
    pub max_steps: usize,
    /// Joint `j`'s rows where `|θ̇_j|` is below this (rad/s), widened by the
    /// filter's reach, are left out of fits and scores (default 0.2, the
    /// identification's threshold): at velocity reversals the exact `sign`
    /// of (49) misfits the real friction (sticking, creeping, a simulator's
    /// `tanh`) by far more than the noise. 0 keeps every row.
    pub min_speed: f64,
    /// TRAIN's exclusion is widened by the zero-phase filter's reach down
    /// to this fraction of its impulse-response peak (default 1e-3, as in
    /// identification: 253 samples at 10 Hz and 1 kHz).
    pub reach_tol: f64,
    /// The same for the validation sets (default 0.5: the filter's main
    /// lobe only, so that fast validation motions keep rows).
    pub validation_reach_tol: f64,
    /// One flag per joint: joint `j` is fitted and scored on every row,
    /// without the exclusion above (default empty: no joint). Set it where
    /// the starting model's Coulomb law describes the reversals.
    pub all_rows: Vec<bool>,
}

impl Default for EngineOptions {
    /// The selection's defaults (`aras_ident::selection::SelectionOptions`)
    /// and the reversal exclusion's ([`crate::filtering`]).
    fn default() -> Self {
        let s = SelectionOptions::default();
        Self {
            alpha: s.alpha,
            min_gain: s.min_gain,
            max_steps: s.max_steps,
            min_speed: DEFAULT_MIN_SPEED,
            reach_tol: DEFAULT_REVERSAL_REACH,
            validation_reach_tol: DEFAULT_VALIDATION_REACH,
            all_rows: Vec::new(),
        }
    }
}

/// A named number with its standard deviation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedValue {
    /// Parameter name.
    pub name: String,
    /// Value (SI).
    pub value: f64,
    /// Standard deviation: the OLS σ of (64)–(66) corrected for the
    /// zero-phase filter's noise gain (divided by `√g`, [`Dataset::noise_gain`]),
    /// since the filtered residual is correlated over `≈ 1/g` samples;
    /// 0 if unknown (never NaN).
    pub std_dev: f64,
}

/// The evidence for one candidate setting in one round.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateScore<C> {
    /// The candidate with its setting.
    pub candidate: C,
    /// Its label.
    pub label: String,
    /// Base parameters it adds (0: an alias of what the model has).
    pub added_parameters: usize,
    /// Relative drop of the TRAIN residual sum of squares (%).
    pub rss_drop_percent: f64,
    /// Effective independent samples (every joint) used by the F-test.
    pub n_eff: f64,
    /// F statistic of the nested-model test.
    pub f: f64,
    /// Its p-value.
    pub p_value: f64,
    /// Change of the Bayesian information criterion on TRAIN with the
    /// effective sample count, `N_eff ln(RSS₁/RSS₀) + k ln N_eff` (negative:
    /// better). Significant candidates are ranked by it, not by the raw
    /// validation gain, so that a flexible many-parameter candidate (e.g.
    /// slow cogging, 8 parameters) does not win over the 2-parameter effect
    /// it imitates.
    pub delta_bic: f64,
    /// Validation fitness gain per joint (percentage points, mean over the
    /// validation sets), of the filtered kept-row fitness
    /// ([`FitnessRow::fitness_filtered`]).
    pub gain: Vec<f64>,
    /// Mean of `gain`.
    pub mean_gain: f64,
    /// Gain per validation set (mean over the joints, percentage points).
    pub gain_per_set: Vec<f64>,
    /// Significant: p below the round's corrected level and a gain of at
    /// least `min_gain` on every validation set.
    pub significant: bool,
    /// Why the candidate could not be scored (e.g. not excited by the
    /// kept rows); empty if it was.
    pub note: String,
}

/// One effect added.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step<C> {
    /// Stable identifier.
    pub id: String,
    /// Label with setting.
    pub label: String,
    /// The candidate.
    pub candidate: C,
    /// Physical explanation.
    pub explanation: String,
    /// Other candidates that explain the data equally well (their TRAIN
    /// residual drop is within 0.1 % of this one's and they add as many
    /// parameters): on these data they are the same hypothesis. Typical:
    /// `coulomb_asymmetry` and `torque_offset` on data without rest
    /// periods, where `|sign θ̇| = 1` on every row kept.
    pub aliases: Vec<String>,
    /// Its fitted parameters (OLS on TRAIN, with the current model).
    pub parameters: Vec<NamedValue>,
    /// The evidence.
    pub evidence: CandidateScore<C>,
    /// The candidate's nonlinear setting refined between the grid points
    /// (`stribeck_friction`'s `v_s`); `None` for candidates without one
    /// refined.
    pub refinement: Option<Refinement>,
}

impl<C: Candidate> Step<C> {
    /// The step's candidate at its refined setting where it was refined:
    /// the effect the final model carries.
    pub fn refined_candidate(&self) -> C {
        match &self.refinement {
            Some(r) => self.candidate.with_setting(r.value),
            None => self.candidate.clone(),
        }
    }
}

/// Whether a refined setting lies inside its search interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RefinementStatus {
    /// A minimum inside the interval; `std_dev` from its curvature.
    Interior,
    /// The minimum is at an end of the interval (the true value may lie
    /// beyond it); `std_dev` is 0 (unknown).
    AtBound,
}

/// A nonlinear setting refined by a one-dimensional search after the grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refinement {
    /// The setting's name ([`Candidate::setting`]: `v_s` in rad/s,
    /// `cycles_per_rev` or `delay_samples`).
    pub name: String,
    /// The grid value the selection chose.
    pub grid_value: f64,
    /// The value minimising the TRAIN residual (zoomed grid search over
    /// [`Candidate::search_scale`]'s interval around each search centre,
    /// then a parabola).
    pub value: f64,
    /// Standard deviation from the curvature of the profile
    /// `N_eff ln RSS(u)` in the search variable `u` (`ln v`, or `v` for a
    /// delay; a rise of 1 is one σ; `N_eff` as in the F-test), its second
    /// difference over the last zoom pass's three trial values around the
    /// minimum; 0 if unknown.
    pub std_dev: f64,
    /// Interior minimum or at a bound.
    pub status: RefinementStatus,
    /// The effect's parameters refitted at the refined value (its columns
    /// interpolated by a cubic from the four nearest trial values').
    pub parameters: Vec<NamedValue>,
    /// Validation fitness (78) per set and joint at the refined value (%),
    /// on the filtered (and period-averaged) torques of the rows the fits
    /// keep, as the selection scores it: not the raw-torque figure.
    pub fitness_filtered: Vec<Vec<f64>>,
}

/// Validation fitness after a step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitnessRow {
    /// 0 = starting model, k = after the k-th added effect.
    pub step: usize,
    /// What the model is at this step.
    pub model: String,
    /// Fitness (78) per validation set, per joint (%): the prediction from
    /// the processed motion, unfiltered, against the log's raw torques on
    /// every row that has a sample (an averaged block's prediction repeated
    /// on every period), as every other command reports it. `None` for a
    /// set whose log rows are not known (spooled, [`Dataset::has_log_rows`]).
    pub fitness: Vec<Option<Vec<f64>>>,
    /// The selection's score (%): the fitness of the filtered (and
    /// period-averaged) torques on the rows the fits keep, away from
    /// velocity reversals. The gains of [`CandidateScore`] are differences
    /// of it.
    pub fitness_filtered: Vec<Vec<f64>>,
    /// The prediction behind [`Self::fitness`] per validation set: the
    /// log rows that have a sample and the predicted τ1, τ2 on them (not
    /// serialised; `aras diagnose` writes the starting and final models').
    #[serde(skip)]
    pub predicted: Vec<Option<LogPrediction>>,
}

/// A prediction on a log's rows.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LogPrediction {
    /// Row numbers of the log (0-based, data rows).
    pub rows: Vec<usize>,
    /// Predicted torque per joint on those rows (N·m).
    pub tau: Vec<Vec<f64>>,
}

/// The physically consistent re-identification of the final model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConsistentFit {
    /// Solver status.
    pub status: SolverStatus,
    /// Validation fitness (78) per set per joint (%) on the filtered (and
    /// period-averaged) torques of the kept rows, as
    /// [`FitnessRow::fitness_filtered`].
    pub fitness_filtered: Vec<Vec<f64>>,
    /// Standard parameters of the final model.
    pub parameters: Vec<NamedValue>,
}

/// The result of [`diagnose`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis<C, T> {
    /// Starting model.
    pub initial_model: T,
    /// Final model (starting model + effects added, in order, each at its
    /// refined setting).
    pub final_model: T,
    /// Torque-against-angle shift found (samples; 0 if none).
    pub delay_samples: f64,
    /// TRAIN's rows per joint that fits and scores use (away from velocity
    /// reversals, [`EngineOptions::min_speed`]).
    pub rows_fitted: Vec<usize>,
    /// Effects added, in order.
    pub steps: Vec<Step<C>>,
    /// Every candidate's score in every round.
    pub rounds: Vec<Vec<CandidateScore<C>>>,
    /// Validation fitness per step.
    pub fitness: Vec<FitnessRow>,
    /// Residual analysis of each validation set with the starting model.
    pub before: Vec<ResidualAnalysis>,
    /// The same with the final model (refined settings).
    pub after: Vec<ResidualAnalysis>,
    /// True if the final residual is white with no systematic bin.
    pub noise_like: bool,
    /// The conclusion in words.
    pub conclusion: String,
    /// Final model's OLS estimate at the refined settings: base parameters
    /// (readable definitions as names), then the added effects'.
    pub estimate: Vec<NamedValue>,
    /// Physically consistent re-identification, if the robot offered one
    /// ([`DiagnosisModel::consistent_refit`]), of the final model with
    /// every effect at its refined setting.
    pub consistent: Option<ConsistentFit>,
    /// Wall time (s).
    pub elapsed_s: f64,
}

/// Where the final model's misfit on the fitted rows lies: its largest
/// systematic bin (velocity, position, acceleration or time) and the
/// frequency band holding most of the residual's power, if one does.
fn locate(after: &[ResidualAnalysis]) -> String {
    let bin = after
        .iter()
        .flat_map(|a| a.findings.iter())
        .filter(|f| f.systematic)
        .max_by(|a, b| a.z.abs().total_cmp(&b.z.abs()));
    let band = after
        .iter()
        .flat_map(|a| a.spectra.iter())
        .filter_map(|s| s.finding.as_ref())
        .max_by(|a, b| a.z.total_cmp(&b.z));
    let parts: Vec<&str> = [bin, band]
        .into_iter()
        .flatten()
        .map(|f| f.text.as_str())
        .collect();
    if parts.is_empty() {
        String::new()
    } else {
        format!(" Where it lies: {}.", parts.join("; "))
    }
}

/// The conclusion's sentence on the rows left out near velocity reversals
/// (the final model's residual there, [`ResidualAnalysis::left_out`]).
fn left_out_sentence(after: &[ResidualAnalysis], min_speed: f64) -> String {
    let parts: Vec<&crate::residual::LeftOut> =
        after.iter().flat_map(|a| a.left_out.iter()).collect();
    if parts.iter().all(|l| l.rows == 0) {
        return String::new();
    }
    let mean = |f: fn(&crate::residual::LeftOut) -> f64| {
        parts.iter().map(|l| f(l)).sum::<f64>() / parts.len() as f64
    };
    let (all, fitted) = (
        mean(|l| l.fitness_filtered_all_rows),
        mean(|l| l.fitness_filtered_fitted_rows),
    );
    let worst = parts
        .iter()
        .flat_map(|l| l.findings.iter())
        .max_by(|a, b| a.z.abs().total_cmp(&b.z.abs()));
    match worst {
        Some(w) => format!(
            " Near velocity reversals, on the rows the fits leave out (|θ̇| < {min_speed} rad/s \
             and the filter's reach), the final model misses beyond noise ({}); filtered \
             validation fitness on all rows is {all:.1} % against {fitted:.1} % on the fitted rows: \
             friction at low speed (sticking, presliding, a Stribeck velocity below \
             {min_speed} rad/s) that the model's Coulomb law does not describe and that the \
             candidates, fitted on moving rows, do not see.",
            w.text
        ),
        None => format!(
            " On the rows left out near velocity reversals the residual is within noise \
             (filtered validation fitness on all rows {all:.1} %, on the fitted rows {fitted:.1} %)."
        ),
    }
}

/// Rows `rows` of column `j` of an owned matrix (an owned faer matrix
/// stores each column contiguously).
fn column(m: &Mat<f64>, j: usize, rows: std::ops::Range<usize>) -> &[f64] {
    m.col(j)
        .try_as_col_major()
        .map_or(&[][..], |c| &c.as_slice()[rows])
}

/// Column `j` of an owned matrix, to write.
fn column_mut(m: &mut Mat<f64>, j: usize) -> &mut [f64] {
    m.col_mut(j)
        .try_as_col_major_mut()
        .map_or(&mut [][..], |c| c.as_slice_mut())
}

/// Where a column of the selection's rows comes from.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// Base column `j` of the starting model.
    Base(usize),
    /// Column `jj` of candidate `k`'s own columns.
    Block(usize, usize),
    /// The filtered torque shifted by this many samples (0: the target).
    Torque(f64),
    /// Nothing (a candidate without columns of its own).
    Zero,
}

/// Candidates and their layout for one trial.
type TrialLayout<C> = (Vec<C>, Layout);

/// `cands` and their layout after `n_base` base columns for `joints`
/// joints, candidate `k` named `label(k, c)` (names must be unique): a
/// torque shift's column is the shifted torque, every other candidate
/// brings its parameters' columns.
fn candidate_layout<C: Candidate>(
    n_base: usize,
    joints: usize,
    cands: Vec<C>,
    label: impl Fn(usize, &C) -> String,
) -> Result<TrialLayout<C>, IdentError> {
    let specs = cands
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let spec = match c.torque_shift() {
                None => {
                    CandidateSpec::columns(label(k, c), c.parameter_names().len()).in_family(c.id())
                }
                Some(_) => CandidateSpec::target(label(k, c)).in_family(c.id()),
            };
            match c.joints() {
                Some(j) => spec.on_groups(j),
                None => spec,
            }
        })
        .collect();
    let layout = Layout::new(n_base, specs, joints)?;
    Ok((cands, layout))
}

/// Everything the passes over the data share.
struct Context<'a, M: DiagnosisModel> {
    model: &'a M,
    joints: usize,
    cands: Vec<M::Candidate>,
    layout: Layout,
    /// Largest torque shift of the delay candidates (rows lost at each end
    /// of a non-periodic record, for every model alike).
    max_shift: usize,
}

impl<M: DiagnosisModel> Context<'_, M> {
    fn range(&self, d: &Dataset) -> (usize, usize) {
        if d.periodic {
            (0, d.len())
        } else {
            (self.max_shift, d.len().saturating_sub(self.max_shift))
        }
    }

    /// The robot's evaluation of a window's samples.
    fn window(&self, w: &crate::chunks::Window) -> Result<M::Window, IdentError> {
        self.model.window(&w.samples, w.lo)
    }

    /// `d`'s low-pass on the joint-major columns of a window of `n`
    /// samples, all matrices at once ([`filter_many_columns`]).
    fn filter(&self, d: &Dataset, n: usize, all: &mut [Mat<f64>]) -> Result<(), IdentError> {
        if let Some(sos) = &d.filter {
            let mut refs: Vec<&mut Mat<f64>> = all.iter_mut().collect();
            filter_many_columns(&mut refs, n, sos, d.periodic)?;
        }
        Ok(())
    }

    /// The starting model's base columns and each of `cands`' columns on
    /// the window `win` of `n` samples of `d`, filtered together.
    fn window_columns<'c>(
        &self,
        d: &Dataset,
        n: usize,
        win: &M::Window,
        cands: impl IntoIterator<Item = &'c M::Candidate>,
    ) -> Result<(Mat<f64>, Vec<Mat<f64>>), IdentError>
    where
        M::Candidate: 'c,
    {
        let mut all = vec![self.model.base_columns(win)?];
        for c in cands {
            all.push(self.model.candidate_columns(c, win)?);
        }
        self.filter(d, n, &mut all)?;
        let mut all = all.into_iter();
        let wb = all.next().ok_or(IdentError::InvalidSetting {
            name: "window columns",
            value: 0.0,
            reason: "internal: the base model's columns are missing",
        })?;
        Ok((wb, all.collect()))
    }

    /// The selection rows of `d` chunk by chunk into one [`Accumulator`]:
    /// `[start base regressor | every candidate's columns | τ]`, a delay
    /// candidate's column being the shifted torque.
    fn accumulate(&self, d: &Dataset, p: &Plan) -> Result<Accumulator, IdentError> {
        self.accumulate_with(d, p, &self.cands, &self.layout)
    }

    /// [`Self::accumulate`] for another candidate list and its layout.
    fn accumulate_with(
        &self,
        d: &Dataset,
        p: &Plan,
        cands: &[M::Candidate],
        layout: &Layout,
    ) -> Result<Accumulator, IdentError> {
        let (lo, hi) = self.range(d);
        let width = layout.width();
        let target = layout.target_column();
        let pb = layout.base_columns();
        // Where each layout column comes from, so the rows are gathered
        // column by column.
        let source: Vec<Source> = (0..width)
            .map(|j| {
                if j < pb {
                    return Source::Base(j);
                }
                if j == target {
                    // A shift of 0 reads the sample itself.
                    return Source::Torque(0.0);
                }
                (0..cands.len())
                    .find_map(|k| {
                        let cols = layout.candidate_columns(k);
                        let jj = j.checked_sub(cols.start).filter(|_| cols.contains(&j))?;
                        Some(match cands[k].torque_shift() {
                            None => Source::Block(k, jj),
                            Some(samples) => Source::Torque(samples),
                        })
                    })
                    .unwrap_or(Source::Zero)
            })
            .collect();
        let with_columns: Vec<bool> = cands.iter().map(|c| c.torque_shift().is_none()).collect();
        let lanes = in_lanes(
            d,
            p,
            (lo, hi),
            || Accumulator::new(layout),
            |acc, w, a, b| {
                let (wl, nw) = (w.lo, w.len());
                let win = self.window(w)?;
                let (wb, filtered) = self.window_columns(
                    d,
                    nw,
                    &win,
                    cands.iter().filter(|c| c.torque_shift().is_none()),
                )?;
                let mut filtered = filtered.into_iter();
                let blocks: Vec<Option<Mat<f64>>> = with_columns
                    .iter()
                    .map(|has| if *has { filtered.next() } else { None })
                    .collect();
                // The columns hold what the chunk needs from the window's
                // evaluation: free it before the rows are gathered.
                drop(win);
                for g in 0..self.joints {
                    let idx = w.rows(g, a, b);
                    // Joint g's rows of the window's columns; only the
                    // columns not zero on them are gathered (a per-joint
                    // effect's columns are zero in the other joints' rows:
                    // most candidates' columns).
                    let rows = g * nw..(g + 1) * nw;
                    let from = |src: Source| -> Option<&[f64]> {
                        match src {
                            Source::Base(c) => Some(column(&wb, c, rows.clone())),
                            Source::Block(k, c) => {
                                blocks[k].as_ref().map(|bk| column(bk, c, rows.clone()))
                            }
                            Source::Torque(_) | Source::Zero => None,
                        }
                    };
                    let cols: Vec<usize> = (0..width)
                        .filter(|&j| match source[j] {
                            Source::Torque(_) => true,
                            Source::Zero => false,
                            src => from(src).is_some_and(|v| v.iter().any(|x| *x != 0.0)),
                        })
                        .collect();
                    let mut m = Mat::<f64>::zeros(idx.len(), cols.len());
                    for (q, &j) in cols.iter().enumerate() {
                        let out = column_mut(&mut m, q);
                        match (source[j], from(source[j])) {
                            (Source::Torque(d), _) => {
                                for (o, &i) in out.iter_mut().zip(&idx) {
                                    *o = w.shifted(g, i, d);
                                }
                            }
                            (_, Some(v)) => {
                                for (o, &i) in out.iter_mut().zip(&idx) {
                                    *o = v[i - wl];
                                }
                            }
                            (_, None) => {}
                        }
                    }
                    acc.push_columns(g, m.as_ref(), &cols)?;
                }
                Ok(())
            },
        )?;
        let mut it = lanes.into_iter();
        let mut acc = it.next().unwrap_or_else(|| Accumulator::new(layout));
        for l in it {
            acc.merge(&l)?;
        }
        Ok(acc)
    }

    /// The torque shift (samples) of the model `fit`: its delay
    /// candidate's, or 0.
    fn fit_delay(&self, fit: &ModelFit) -> f64 {
        if fit.target == self.layout.target_column() {
            return 0.0;
        }
        (0..self.cands.len())
            .find(|&k| self.layout.candidate_columns(k).start == fit.target)
            .and_then(|k| self.cands[k].torque_shift())
            .unwrap_or(0.0)
    }

    /// The coefficient of every layout column of `fit` (0 for a column
    /// not in the model) and the candidates with a nonzero one that bring
    /// columns of their own.
    fn coefficients(&self, fit: &ModelFit) -> (Vec<f64>, Vec<usize>) {
        let mut beta = vec![0.0; self.layout.width()];
        for (c, v) in fit.columns.iter().zip(&fit.estimate) {
            beta[*c] = *v;
        }
        let used = (0..self.cands.len())
            .filter(|&k| {
                self.cands[k].torque_shift().is_none()
                    && self.layout.candidate_columns(k).any(|c| beta[c] != 0.0)
            })
            .collect();
        (beta, used)
    }

    /// The prediction of the selected model `fit` (coefficients `beta`,
    /// candidates `used`) on joint `g`'s rows `a..b` of a window starting
    /// at record sample `wl` with `nw` samples.
    fn predict_rows(
        &self,
        (beta, used): (&[f64], &[usize]),
        (wb, blocks): (&Mat<f64>, &[Mat<f64>]),
        (wl, nw): (usize, usize),
        g: usize,
        i: usize,
    ) -> f64 {
        let pb = self.layout.base_columns();
        let row = g * nw + (i - wl);
        let mut v = 0.0;
        for j in 0..pb {
            v += beta[j] * wb[(row, j)];
        }
        for (k, bk) in used.iter().zip(blocks) {
            for (jj, j) in self.layout.candidate_columns(*k).enumerate() {
                v += beta[j] * bk[(row, jj)];
            }
        }
        v
    }

    /// The residual analysis of the selected model `fit` on every row of
    /// `d` in its range, fitted or left out near a reversal, summarised in
    /// record order as the rows are computed: only the model's columns
    /// are built, and nothing proportional to the data set is held.
    fn residual_analysis(
        &self,
        d: &Dataset,
        p: &Plan,
        fit: &ModelFit,
    ) -> Result<ResidualAnalysis, IdentError> {
        let (lo, hi) = self.range(d);
        let (beta, used) = self.coefficients(fit);
        let delay = self.fit_delay(fit);
        let mut summary = ResidualSummary::new(
            &d.name,
            self.joints,
            hi - lo,
            d.sample_rate_hz,
            d.periodic,
            d.filter_dof() / d.len() as f64,
            d.pass_band_end(),
        )?;
        in_order(
            d,
            p,
            (lo, hi),
            |w, a, b| {
                let (wl, nw) = (w.lo, w.len());
                let win = self.window(w)?;
                let (wb, blocks) =
                    self.window_columns(d, nw, &win, used.iter().map(|&k| &self.cands[k]))?;
                let s = &w.samples;
                let rows: Vec<Vec<Row>> = (0..self.joints)
                    .map(|g| {
                        (a..b)
                            .map(|i| {
                                let pred = self.predict_rows(
                                    (&beta, &used),
                                    (&wb, &blocks),
                                    (wl, nw),
                                    g,
                                    i,
                                );
                                let t = w.shifted(g, i, delay);
                                let at = i - wl;
                                Row {
                                    residual: t - pred,
                                    measured: t,
                                    fitted: w.kept(g, i),
                                    motion: [
                                        s.theta[g][at],
                                        s.theta_dot[g][at],
                                        s.theta_ddot[g][at],
                                        s.t[at],
                                    ],
                                }
                            })
                            .collect()
                    })
                    .collect();
                Ok(rows)
            },
            |rows| {
                for (g, rows) in rows.iter().enumerate() {
                    for row in rows {
                        summary.push(g, row)?;
                    }
                }
                Ok(())
            },
        )?;
        summary.finish()
    }

    /// Fitness (78) per joint of the selected model `fit` on `d` against
    /// its log's raw torques on every row that has a sample (`None` if `d`
    /// does not know its log's rows): the prediction from the processed
    /// motion with the columns unfiltered, a torque-against-angle shift
    /// of the model applied to the prediction (shifted back by the delay),
    /// an averaged block's prediction repeated on every period.
    fn raw_fitness(
        &self,
        d: &Dataset,
        p: &Plan,
        fit: &ModelFit,
    ) -> Result<Option<(Vec<f64>, LogPrediction)>, IdentError> {
        let Some(rows) = d.log_rows() else {
            return Ok(None);
        };
        let mut u = d.clone();
        u.filter = None;
        let plan = Plan::new(&u, p.min_speed, WINDOW_TOL, 0)?;
        let n = u.len();
        let (beta, used) = self.coefficients(fit);
        let delay = self.fit_delay(fit);
        let mut pred: Vec<Vec<f64>> = (0..self.joints).map(|_| Vec::with_capacity(n)).collect();
        in_order(
            &u,
            &plan,
            (0, n),
            |w, a, b| {
                let (wl, nw) = (w.lo, w.len());
                let win = self.window(w)?;
                let (wb, cols) =
                    self.window_columns(&u, nw, &win, used.iter().map(|&k| &self.cands[k]))?;
                let out: Vec<Vec<f64>> = (0..self.joints)
                    .map(|g| {
                        (a..b)
                            .map(|i| {
                                self.predict_rows((&beta, &used), (&wb, &cols), (wl, nw), g, i)
                            })
                            .collect()
                    })
                    .collect();
                Ok(out)
            },
            |out| {
                for (g, v) in out.into_iter().enumerate() {
                    pred[g].extend(v);
                }
                Ok(())
            },
        )?;
        let on: Vec<(usize, usize)> = rows
            .sample
            .iter()
            .enumerate()
            .filter_map(|(r, i)| Some((r, (*i).filter(|i| *i < n)?)))
            .collect();
        let mut f = vec![0.0; self.joints];
        let mut out = LogPrediction {
            rows: on.iter().map(|(r, _)| *r).collect(),
            tau: vec![Vec::new(); self.joints],
        };
        for (g, fg) in f.iter_mut().enumerate() {
            let q: Vec<f64> = on
                .iter()
                .map(|&(_, i)| {
                    if delay == 0.0 {
                        pred[g][i]
                    } else {
                        aras_signal::delayed_at(&pred[g], i, -delay)
                    }
                })
                .collect();
            let m: Vec<f64> = on.iter().map(|&(r, _)| rows.tau[g][r]).collect();
            *fg = aras_ident::validate::fitness(&m, &q)?;
            out.tau[g] = q;
        }
        Ok(Some((f, out)))
    }

    /// The model of `refit` on `d`: calls `f(state, g, W_b rows, torques)`
    /// chunk by chunk (torques shifted by `delay`).
    fn model_pass<T: Send>(
        &self,
        (d, p): (&Dataset, &Plan),
        refit: &M::Refit,
        delay: f64,
        init: impl Fn() -> T + Sync,
        f: impl Fn(&mut T, usize, MatRef<'_, f64>, &[f64]) -> Result<(), IdentError> + Sync,
    ) -> Result<Vec<T>, IdentError> {
        let (lo, hi) = self.range(d);
        in_lanes(d, p, (lo, hi), init, |st, w, a, b| {
            let (wl, nw) = (w.lo, w.len());
            let win = self.window(w)?;
            let mut wb = [refit.base_columns(&win)?];
            drop(win);
            self.filter(d, nw, &mut wb)?;
            let [wb] = wb;
            for g in 0..self.joints {
                let idx = w.rows(g, a, b);
                let m = Mat::from_fn(idx.len(), wb.ncols(), |r, j| wb[(g * nw + idx[r] - wl, j)]);
                let t: Vec<f64> = idx.iter().map(|&i| w.shifted(g, i, delay)).collect();
                f(st, g, m.as_ref(), &t)?;
            }
            Ok(())
        })
    }
}

/// Stands in for an error taken out of a lane's state (never reported).
const LANE_STOPPED: IdentError = IdentError::InvalidSetting {
    name: "accumulation lanes",
    value: 0.0,
    reason: "internal: the lane stopped at an earlier error",
};

fn score_of<C: Candidate>(c: &C, e: &CandidateEvaluation) -> CandidateScore<C> {
    CandidateScore {
        candidate: c.clone(),
        label: c.label(),
        added_parameters: e.added_parameters,
        rss_drop_percent: e.rss_drop_percent,
        n_eff: e.n_eff,
        f: e.f,
        p_value: e.p_value,
        delta_bic: e.delta_bic,
        gain: e.gain.clone(),
        mean_gain: e.mean_gain,
        gain_per_set: e.gain_per_set.clone(),
        significant: e.status == EvaluationStatus::Significant,
        note: match e.status {
            EvaluationStatus::NoNewParameters => {
                "its columns lie in the span of the model's on these rows".into()
            }
            _ => e.note.clone(),
        },
    }
}

fn describe<M: DiagnosisModel>(model: &M, steps: &[Step<M::Candidate>]) -> String {
    let mut s: Vec<String> = model.term_names();
    s.extend(steps.iter().map(|st| st.label.clone()));
    s.join(" + ")
}

/// The diagnosis's inputs checked: at least one validation set, the
/// settings in range, every data set of the model's joint count. Returns
/// the joint count.
fn check_inputs<M: DiagnosisModel>(
    model: &M,
    train: &Dataset,
    validation: &[Dataset],
    opts: &EngineOptions,
) -> Result<usize, IdentError> {
    if validation.is_empty() {
        return Err(IdentError::InvalidSetting {
            name: "validation data sets",
            value: 0.0,
            reason: "give at least one validation log (e.g. --validate VAL.csv)",
        });
    }
    if !(opts.alpha > 0.0 && opts.alpha < 1.0) {
        return Err(IdentError::InvalidSetting {
            name: "alpha",
            value: opts.alpha,
            reason: "the significance level must lie in (0, 1), e.g. 0.01",
        });
    }
    if !(opts.min_gain.is_finite() && opts.min_gain >= 0.0) {
        return Err(IdentError::InvalidSetting {
            name: "min_gain",
            value: opts.min_gain,
            reason: "the minimum fitness gain must be a finite number of percentage points ≥ 0",
        });
    }
    let joints = model.joints();
    if !opts.all_rows.is_empty() && opts.all_rows.len() != joints {
        return Err(IdentError::DimensionMismatch {
            what: "joints fitted on every row (all_rows)",
            expected: joints,
            found: opts.all_rows.len(),
            hint: "give one flag per joint, or none",
        });
    }
    train.check()?;
    for v in validation {
        v.check()?;
    }
    for d in std::iter::once(train).chain(validation) {
        let found = d.joints()?;
        if found != joints {
            return Err(IdentError::DimensionMismatch {
                what: "joints of a diagnosis data set",
                expected: joints,
                found,
                hint: "give data sets of the robot the model describes",
            });
        }
    }
    Ok(joints)
}

/// What the residual after the last step says, for the conclusion.
#[derive(Debug, Clone, Copy)]
struct Verdict {
    /// The selection stopped because no candidate was significant (not at
    /// the step limit).
    stopped_clean: bool,
    /// Every validation residual is white by Ljung–Box.
    white: bool,
    /// A residual bin lies beyond the systematic threshold.
    systematic: bool,
}

/// The diagnosis's conclusion in words: what was added (at the refined
/// settings), why the selection stopped, whether the residual is
/// noise-like, and where a misfit lies when it is not.
fn conclusion<C: Candidate>(
    refined: &[C],
    verdict: Verdict,
    after: &[ResidualAnalysis],
    opts: &EngineOptions,
) -> String {
    let added = if refined.is_empty() {
        "No effect was added".to_owned()
    } else {
        format!(
            "Added, in order (at the refined settings): {}",
            refined
                .iter()
                .map(Candidate::label)
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let Verdict {
        stopped_clean,
        white,
        systematic,
    } = verdict;
    let noise_like = stopped_clean && white && !systematic;
    let conclusion = if !stopped_clean {
        format!(
            "{added}; stopped at the step limit ({}) or with every candidate used.",
            opts.max_steps
        )
    } else if noise_like {
        format!(
            "{added}. No remaining candidate is significant and the validation residual is \
             noise-like (white by Ljung–Box at 1 %, no bin beyond {:.0} standard errors).",
            crate::residual::Z_SYSTEMATIC
        )
    } else {
        format!(
            "{added}. No remaining candidate is significant, but the validation residual is \
             not noise-like ({}{}): the rest is an effect outside the candidate library or a \
             processing artefact.",
            if white { "white" } else { "not white" },
            if systematic {
                ", systematic bins remain"
            } else {
                ""
            }
        )
    };

    let located = if noise_like {
        String::new()
    } else {
        locate(after)
    };
    conclusion + &located + &left_out_sentence(after, opts.min_speed)
}

impl<'a, M: DiagnosisModel> Context<'a, M> {
    /// The candidates laid out after the model's base columns, and the
    /// largest torque shift among them (with its refinement interval).
    fn new(model: &'a M, joints: usize, candidates: Vec<M::Candidate>) -> Result<Self, IdentError> {
        let (cands, layout) =
            candidate_layout(model.n_base(), joints, candidates, |_, c| c.label())?;
        let max_shift = cands
            .iter()
            .map(|c| match c.torque_shift() {
                // The refinement's search interval around the grid value, and
                // one more sample for the interpolation of a fraction.
                Some(samples) => {
                    let (lo, hi) = c
                        .search_scale()
                        .map_or((samples, samples), |s| s.interval(samples));
                    lo.abs().max(hi.abs()).ceil() as usize + 1
                }
                None => 0,
            })
            .max()
            .unwrap_or(0);
        Ok(Self {
            model,
            joints,
            cands,
            layout,
            max_shift,
        })
    }

    /// The report of one selection step: its candidate, evidence and fitted
    /// parameters, and the torque delay it names, if it is one.
    fn step_of(&self, st: &SelectionStep) -> (Step<M::Candidate>, Option<f64>) {
        let mut delay = None;
        let c = &self.cands[st.candidate];
        let parameters = match c.torque_shift() {
            None => {
                let names = c.parameter_names();
                self.layout
                    .candidate_columns(st.candidate)
                    .zip(&names)
                    .filter_map(|(col, name)| {
                        let k = st.fit.columns.iter().position(|c| *c == col)?;
                        Some(NamedValue {
                            name: name.clone(),
                            value: st.fit.estimate[k],
                            std_dev: st.fit.std_dev[k],
                        })
                    })
                    .collect()
            }
            Some(samples) => {
                delay = Some(samples);
                vec![NamedValue {
                    name: "delay_samples".into(),
                    value: samples,
                    std_dev: 0.0,
                }]
            }
        };
        let step = Step {
            id: c.id(),
            label: c.label(),
            candidate: c.clone(),
            explanation: c.explanation(),
            aliases: st.aliases.clone(),
            parameters,
            evidence: score_of(c, &st.evaluation),
            refinement: None,
        };
        (step, delay)
    }

    /// The names of a fit's columns (the model's base parameters, then each
    /// added candidate's parameters) with their values and σ.
    fn named_estimate(&self, final_fit: &ModelFit) -> Vec<NamedValue> {
        let mut estimate: Vec<NamedValue> = Vec::new();
        for (k, col) in final_fit.columns.iter().enumerate() {
            let name = if *col < self.layout.base_columns() {
                self.model.base_name(*col)
            } else {
                (0..self.cands.len())
                    .find_map(|c| {
                        let r = self.layout.candidate_columns(c);
                        let off = col.checked_sub(r.start)?;
                        if !r.contains(col) || self.cands[c].torque_shift().is_some() {
                            return None;
                        }
                        self.cands[c].parameter_names().get(off).cloned()
                    })
                    .unwrap_or_default()
            };
            estimate.push(NamedValue {
                name,
                value: final_fit.estimate[k],
                std_dev: final_fit.std_dev[k],
            });
        }
        estimate
    }
}

/// Runs the diagnosis: `model`'s starting model identified on `train`,
/// scored on `validation` (at least one set), `candidates` tried (each
/// label unique) until none is significant.
pub fn diagnose<M: DiagnosisModel>(
    model: &M,
    candidates: Vec<M::Candidate>,
    train: &Dataset,
    validation: &[Dataset],
    opts: &EngineOptions,
) -> Result<Diagnosis<M::Candidate, M::Terms>, IdentError> {
    let clock = Instant::now();
    let joints = check_inputs(model, train, validation, opts)?;
    let ctx = Context::new(model, joints, candidates)?;
    let sets = Sets::new(train, validation, opts, ctx.max_shift)?;
    let (train_acc, val_accs) = ctx.accumulate_sets(&sets)?;
    let sel_opts = selection_options(train, opts)?;
    let sel = select(&train_acc, &val_accs, &sel_opts)?;
    let (mut steps, fitness, delay_samples) = ctx.history(&sets, &sel)?;
    ctx.refine_settings(&sets, &sel, &mut steps, &sel_opts)?;
    let rounds = ctx.rounds(&sel);
    // The final model takes each effect at its refined setting: that is
    // the model a user carries on with, and the one whose residual the
    // verdict below is about.
    let refined: Vec<M::Candidate> = steps.iter().map(Step::refined_candidate).collect();
    let refitted = ctx.refitted(&sets, &refined, &steps, &sel_opts)?;
    let (fctx, final_accs, final_fit, final_added): (_, &[Accumulator], _, Vec<usize>) =
        match &refitted {
            Some(r) => (&r.ctx, &r.val_accs, &r.fit, (0..refined.len()).collect()),
            None => (
                &ctx,
                &val_accs,
                sel.final_fit(),
                sel.steps.iter().map(|st| st.candidate).collect(),
            ),
        };
    let before = ctx.analyses(&sets, &val_accs, &sel.initial, &[], &sel_opts)?;
    let after = fctx.analyses(&sets, final_accs, final_fit, &final_added, &sel_opts)?;
    let verdict = Verdict::of(sel.status == SelectionStatus::NothingSignificant, &after);
    let noise_like = verdict.noise_like();
    let conclusion = conclusion(&refined, verdict, &after, opts);

    let final_model = model.terms(&refined)?;
    let estimate = fctx.named_estimate(final_fit);
    let consistent = match model.consistent_refit(&refined)? {
        Some(refit) => {
            let delay = refined
                .iter()
                .find_map(|c| c.torque_shift())
                .unwrap_or(delay_samples);
            let fit = consistent_fit(&ctx, sets.train(), sets.validation(), &refit, delay)?;
            Some(fit)
        }
        None => None,
    };
    Ok(Diagnosis {
        initial_model: model.terms(&[])?,
        final_model,
        delay_samples,
        rows_fitted: train_acc.rows().to_vec(),
        steps,
        rounds,
        fitness,
        before,
        after,
        noise_like,
        conclusion,
        estimate,
        consistent,
        elapsed_s: clock.elapsed().as_secs_f64(),
    })
}

/// TRAIN and the validation sets, each with its row plan: the rows away
/// from velocity reversals (TRAIN's exclusion widened by `reach_tol`, the
/// validation sets' by `validation_reach_tol`) and the chunks read.
struct Sets<'d> {
    train: &'d Dataset,
    train_plan: Plan,
    validation: &'d [Dataset],
    plans: Vec<Plan>,
}

impl<'d> Sets<'d> {
    fn new(
        train: &'d Dataset,
        validation: &'d [Dataset],
        opts: &EngineOptions,
        max_shift: usize,
    ) -> Result<Self, IdentError> {
        let train_plan = Plan::new(train, opts.min_speed, opts.reach_tol, max_shift)?
            .with_all_rows(opts.all_rows.clone());
        let plans = validation
            .iter()
            .map(|v| {
                Plan::new(v, opts.min_speed, opts.validation_reach_tol, max_shift)
                    .map(|p| p.with_all_rows(opts.all_rows.clone()))
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            train,
            train_plan,
            validation,
            plans,
        })
    }

    fn train(&self) -> (&Dataset, &Plan) {
        (self.train, &self.train_plan)
    }

    fn validation(&self) -> (&[Dataset], &[Plan]) {
        (self.validation, &self.plans)
    }

    /// Each validation set with its plan.
    fn pairs(&self) -> impl Iterator<Item = (&Dataset, &Plan)> {
        self.validation.iter().zip(&self.plans)
    }
}

/// The selection's settings: the engine's α, minimum gain and step limit,
/// with the filter's independent fraction of samples for the F-test and
/// its noise gain for σ (the same number by Parseval, applied once each).
fn selection_options(
    train: &Dataset,
    opts: &EngineOptions,
) -> Result<SelectionOptions, IdentError> {
    let dof_ratio = (train.filter_dof() / train.len() as f64).clamp(1e-9, 1.0);
    Ok(SelectionOptions {
        alpha: opts.alpha,
        min_gain: opts.min_gain,
        max_steps: opts.max_steps,
        effective_fraction: dof_ratio,
        noise_gain: train.noise_gain()?.clamp(1e-12, 1.0),
        ..SelectionOptions::default()
    })
}

impl Verdict {
    /// The verdict on the final residuals `after` of a selection that
    /// stopped clean or not.
    fn of(stopped_clean: bool, after: &[ResidualAnalysis]) -> Self {
        Self {
            stopped_clean,
            white: after
                .iter()
                .all(|a| a.whiteness.iter().all(|w| w.is_white())),
            systematic: after
                .iter()
                .any(|a| a.findings.iter().any(|f| f.systematic)),
        }
    }

    /// Nothing significant is left, the residuals are white and no bin is
    /// systematic.
    fn noise_like(&self) -> bool {
        self.stopped_clean && self.white && !self.systematic
    }
}

/// The final model with a setting moved off its grid value by a
/// refinement: its own columns and validation sums (one more pass over
/// each set), and its fit on TRAIN.
struct Refitted<'a, M: DiagnosisModel> {
    ctx: Context<'a, M>,
    val_accs: Vec<Accumulator>,
    fit: ModelFit,
}

impl<'a, M: DiagnosisModel> Context<'a, M> {
    /// TRAIN's and each validation set's sums, each checked to have rows.
    fn accumulate_sets(&self, sets: &Sets) -> Result<(Accumulator, Vec<Accumulator>), IdentError> {
        let (train, plan) = sets.train();
        let train_acc = self.accumulate(train, plan)?;
        check_rows(train_acc.rows())?;
        let val_accs = sets
            .pairs()
            .map(|(v, p)| {
                let acc = self.accumulate(v, p)?;
                check_rows(acc.rows())?;
                Ok(acc)
            })
            .collect::<Result<_, IdentError>>()?;
        Ok((train_acc, val_accs))
    }

    /// The fitness row of `fit` after `steps`: (78) against each
    /// validation set's raw torques where it keeps its log's rows, and on
    /// the filtered sums.
    fn fitness_row(
        &self,
        sets: &Sets,
        steps: &[Step<M::Candidate>],
        fit: &ModelFit,
    ) -> Result<FitnessRow, IdentError> {
        let all = sets
            .pairs()
            .map(|(v, p)| self.raw_fitness(v, p, fit))
            .collect::<Result<Vec<_>, IdentError>>()?;
        let (fitness, predicted) = all
            .into_iter()
            .map(|x| x.map_or((None, None), |(f, p)| (Some(f), Some(p))))
            .unzip();
        Ok(FitnessRow {
            step: steps.len(),
            model: describe(self.model, steps),
            fitness,
            fitness_filtered: fit.fitness.clone(),
            predicted,
        })
    }

    /// The selected steps in order, the fitness of the starting model and
    /// after each step, and the delay (samples) the last delay step named.
    #[allow(clippy::type_complexity)]
    fn history(
        &self,
        sets: &Sets,
        sel: &Selection,
    ) -> Result<(Vec<Step<M::Candidate>>, Vec<FitnessRow>, f64), IdentError> {
        let mut rows = vec![self.fitness_row(sets, &[], &sel.initial)?];
        let mut steps: Vec<Step<M::Candidate>> = Vec::new();
        let mut delay_samples = 0.0;
        for st in &sel.steps {
            let (step, delay) = self.step_of(st);
            delay_samples = delay.unwrap_or(delay_samples);
            steps.push(step);
            rows.push(self.fitness_row(sets, &steps, &st.fit)?);
        }
        Ok((steps, rows, delay_samples))
    }

    /// Nonlinear settings between the grid points: one pass over TRAIN per
    /// trial value (bounded memory), the other selected candidates kept.
    fn refine_settings(
        &self,
        sets: &Sets,
        sel: &Selection,
        steps: &mut [Step<M::Candidate>],
        sel_opts: &SelectionOptions,
    ) -> Result<(), IdentError> {
        for k in 0..steps.len() {
            let candidate = steps[k].candidate.clone();
            if candidate.setting().is_some() {
                let others: Vec<M::Candidate> = sel
                    .steps
                    .iter()
                    .map(|st| self.cands[st.candidate].clone())
                    .filter(|c| *c != candidate)
                    .collect();
                steps[k].refinement = Some(refine_setting(
                    self,
                    sets.train(),
                    sets.validation(),
                    &others,
                    candidate,
                    sel_opts,
                )?);
            }
        }
        Ok(())
    }

    /// Every round's candidates with their scores, best mean gain first.
    fn rounds(&self, sel: &Selection) -> Vec<Vec<CandidateScore<M::Candidate>>> {
        let mut rounds: Vec<Vec<CandidateScore<M::Candidate>>> = sel
            .rounds
            .iter()
            .map(|r| {
                r.iter()
                    .map(|e| score_of(&self.cands[e.candidate], e))
                    .collect()
            })
            .collect();
        for r in &mut rounds {
            r.sort_by(|a, b| b.mean_gain.total_cmp(&a.mean_gain));
        }
        rounds
    }

    /// The final model `refined` refitted when a refinement moved a setting
    /// off its grid value; `None` when the selection's fit is the final one.
    fn refitted(
        &self,
        sets: &Sets,
        refined: &[M::Candidate],
        steps: &[Step<M::Candidate>],
        sel_opts: &SelectionOptions,
    ) -> Result<Option<Refitted<'a, M>>, IdentError> {
        let moved = steps.iter().any(|s| {
            s.refinement
                .as_ref()
                .is_some_and(|r| r.value != r.grid_value)
        });
        if !moved {
            return Ok(None);
        }
        let (cands, layout) = candidate_layout(
            self.model.n_base(),
            self.joints,
            refined.to_vec(),
            |_, c| c.label(),
        )?;
        let ctx = Context {
            model: self.model,
            joints: self.joints,
            cands,
            layout,
            max_shift: self.max_shift,
        };
        // Kept apart from the selection's sums, which the residuals before
        // still need.
        let val_accs = sets
            .pairs()
            .map(|(v, p)| ctx.accumulate(v, p))
            .collect::<Result<Vec<_>, _>>()?;
        let (train, plan) = sets.train();
        let train_acc = ctx.accumulate(train, plan)?;
        let added: Vec<usize> = (0..refined.len()).collect();
        let fit = fit_model(&train_acc, &val_accs, &added, sel_opts)?;
        Ok(Some(Refitted { ctx, val_accs, fit }))
    }

    /// Residual analyses of `fit` on each validation set (its sums `accs`):
    /// the fitted rows, and apart the rows left out near velocity
    /// reversals. Whiteness is judged on what the model's columns (`added`
    /// to the base) cannot express on each set: the residual of the model
    /// refitted there (its least squares on the set's own sums), so that
    /// the TRAIN estimate's own error, which follows the motion, does not
    /// read as a missing term. The profiles, spectra and left-out rows stay
    /// those of the TRAIN estimate: a refit on one sinusoid would absorb
    /// much of a missing law.
    fn analyses(
        &self,
        sets: &Sets,
        accs: &[Accumulator],
        fit: &ModelFit,
        added: &[usize],
        sel_opts: &SelectionOptions,
    ) -> Result<Vec<ResidualAnalysis>, IdentError> {
        let mut out = sets
            .pairs()
            .map(|(v, p)| self.residual_analysis(v, p, fit))
            .collect::<Result<Vec<_>, _>>()?;
        for ((a, (v, p)), acc) in out.iter_mut().zip(sets.pairs()).zip(accs) {
            let refit = fit_model(acc, std::slice::from_ref(acc), added, sel_opts)?;
            a.whiteness = self.residual_analysis(v, p, &refit)?.whiteness;
        }
        Ok(out)
    }
}

/// Refinement of `candidate`'s continuous setting
/// ([`Candidate::setting`]) over [`Candidate::search_scale`]'s interval
/// around each search centre, the `others` added effects kept; σ from the
/// profile's curvature. Every trial value of a zoom pass is a candidate of
/// one layout, so one bounded pass over TRAIN scores them all (the
/// selection's own scheme): [`ZOOM_PASSES`](crate::refine::ZOOM_PASSES) passes, whatever the log's
/// length. The fit at the refined value needs no pass of its own: its
/// columns are the cubic interpolation of the four nearest trial values'
/// columns, whose sums the last pass holds ([`Accumulator::combined`]).
fn refine_setting<M: DiagnosisModel>(
    ctx: &Context<'_, M>,
    train: (&Dataset, &Plan),
    validation: (&[Dataset], &[Plan]),
    others: &[M::Candidate],
    candidate: M::Candidate,
    opts: &SelectionOptions,
) -> Result<Refinement, IdentError> {
    let (Some((name, v0)), Some(scale)) = (candidate.setting(), candidate.search_scale()) else {
        return Err(IdentError::InvalidSetting {
            name: "refined candidate",
            value: 0.0,
            reason: "internal: only a candidate with a continuous setting is refined",
        });
    };
    let k0 = others.len();
    // The layout of `others` followed by the candidate at every trial value
    // of the search variable `us` (trials named by their index: two values
    // may print alike).
    let setup = |us: &[f64]| -> Result<TrialLayout<M::Candidate>, IdentError> {
        let mut cands = others.to_vec();
        cands.extend(
            us.iter()
                .map(|u| candidate.with_setting(scale.setting_value(*u))),
        );
        candidate_layout(ctx.model.n_base(), ctx.joints, cands, |k, c| {
            if k < k0 {
                c.label()
            } else {
                format!("{} (trial {})", c.id(), k - k0)
            }
        })
    };
    let with_trial = |k: usize| -> Vec<usize> { (0..k0).chain([k0 + k]).collect() };
    // One pass over TRAIN per zoom pass: the TRAIN RSS of the model at
    // every trial value (TRAIN's own sums stand in for a validation set,
    // whose figures are not used); the last pass's sums and layout are kept
    // for the fit at the refined value.
    let intervals: Vec<(f64, f64)> = candidate
        .search_centres()
        .into_iter()
        .map(|c| scale.interval(c))
        .collect();
    let mut last_pass: Option<(Accumulator, TrialLayout<M::Candidate>)> = None;
    let min = minimise_profile(&intervals, |us: &[f64]| -> Result<Vec<f64>, IdentError> {
        let (c, l) = setup(us)?;
        let acc = ctx.accumulate_with(train.0, train.1, &c, &l)?;
        let rss = (0..us.len())
            .map(|k| {
                fit_model(&acc, std::slice::from_ref(&acc), &with_trial(k), opts)
                    .map(|f| f.total_rss())
            })
            .collect::<Result<Vec<_>, _>>()?;
        last_pass = Some((acc, (c, l)));
        Ok(rss)
    })?;
    let Some((acc, trials)) = last_pass else {
        return Err(IdentError::InvalidSetting {
            name: "refined candidate",
            value: 0.0,
            reason: "internal: the refinement evaluated no pass",
        });
    };
    let (u, points, best) = (min.u, &min.points, min.best);
    let status = if min.at_bound {
        RefinementStatus::AtBound
    } else {
        RefinementStatus::Interior
    };
    // σ from the curvature of the profile at the three trial values around
    // its minimum.
    let ne = opts.effective_fraction * acc.rows().iter().sum::<usize>() as f64;
    let std_dev = min.std_dev(ne).map_or(0.0, |su| scale.sigma(u, su));
    let v = scale.setting_value(u);
    // The candidate's columns at u: the cubic through the four trial values
    // around it (u between the middle two where the grid allows).
    let below = if u >= points[best] {
        best
    } else {
        best.saturating_sub(1)
    };
    let first = below
        .saturating_sub(1)
        .min(points.len().saturating_sub(INTERPOLATION_NODES));
    let nodes: [usize; INTERPOLATION_NODES] = std::array::from_fn(|i| first + i);
    let weights = lagrange(nodes.map(|i| points[i]), u);
    let (c, l) = trials;
    let (_, last) = setup(&[u])?;
    let start = last.candidate_columns(k0).start;
    let combination: Vec<Vec<(usize, f64)>> = (0..last.width())
        .map(|j| {
            if j < start {
                vec![(j, 1.0)]
            } else if j == last.target_column() {
                vec![(l.target_column(), 1.0)]
            } else {
                nodes
                    .iter()
                    .zip(weights)
                    .map(|(&i, w)| (l.candidate_columns(k0 + i).start + j - start, w))
                    .collect()
            }
        })
        .collect();
    let tacc = acc.combined(&last, &combination)?;
    let vaccs = validation
        .0
        .iter()
        .zip(validation.1)
        .map(|(d, p)| {
            ctx.accumulate_with(d, p, &c, &l)?
                .combined(&last, &combination)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let f = fit_model(&tacc, &vaccs, &with_trial(0), opts)?;
    let names = candidate.with_setting(v).parameter_names();
    let parameters = last
        .candidate_columns(k0)
        .zip(&names)
        .filter_map(|(col, name)| {
            let k = f.columns.iter().position(|x| *x == col)?;
            Some(NamedValue {
                name: name.clone(),
                value: f.estimate[k],
                std_dev: f.std_dev[k],
            })
        })
        .collect();
    Ok(Refinement {
        name: name.into(),
        grid_value: v0,
        value: v,
        std_dev,
        status,
        parameters,
        fitness_filtered: f.fitness.clone(),
    })
}

/// Trial values a refined setting's columns are interpolated from: a
/// cubic, whose error is fourth order in the last zoom pass's spacing.
const INTERPOLATION_NODES: usize = 4;

/// Lagrange weights at `u` of the nodes `x` (distinct): a smooth function's
/// value at `u` is `Σ w_i f(x_i)` up to a term of order `N` in the
/// spacing.
fn lagrange<const N: usize>(x: [f64; N], u: f64) -> [f64; N] {
    std::array::from_fn(|i| {
        (0..N)
            .filter(|&k| k != i)
            .map(|k| (u - x[k]) / (x[i] - x[k]))
            .product()
    })
}

/// The physically consistent re-identification of the final model: its
/// reduced least-squares problem accumulated chunk by chunk (incremental
/// QR), its validation fitness from a second pass per set.
fn consistent_fit<M: DiagnosisModel>(
    ctx: &Context<'_, M>,
    train: (&Dataset, &Plan),
    (validation, vals_p): (&[Dataset], &[Plan]),
    refit: &M::Refit,
    delay: f64,
) -> Result<ConsistentFit, IdentError> {
    let joints = ctx.joints;
    let bn = refit.base_names();
    let lanes = ctx.model_pass(
        train,
        refit,
        delay,
        || QrAccumulator::new(&bn, joints),
        |acc, g, w, t| match acc {
            Ok(a) => a.push_rows(g, w, t),
            // The lane stops at this error; its state is not used again.
            Err(_) => Err(std::mem::replace(acc, Err(LANE_STOPPED)).unwrap_err()),
        },
    )?;
    let mut it = lanes.into_iter();
    let mut acc = it.next().ok_or(IdentError::InvalidSetting {
        name: "accumulation lanes",
        value: 0.0,
        reason: "internal: no lane",
    })??;
    for l in it {
        acc.merge(&l?)?;
    }
    let red = acc.reduced()?;
    let sol = refit.solve(&red)?;
    let beta_b = &sol.base;
    let fitness = validation
        .iter()
        .zip(vals_p)
        .map(|(v, p)| -> Result<Vec<f64>, IdentError> {
            // Per joint: the sums of (78), merged over the lanes.
            let lanes = ctx.model_pass(
                (v, p),
                refit,
                delay,
                || vec![FitnessSums::default(); joints],
                |s, g, w, t| {
                    for (r, y) in t.iter().enumerate() {
                        let pred: f64 = (0..w.ncols()).map(|j| w[(r, j)] * beta_b[j]).sum();
                        s[g].push(*y, pred);
                    }
                    Ok(())
                },
            )?;
            let mut tot = vec![FitnessSums::default(); joints];
            for l in &lanes {
                for (t, s) in tot.iter_mut().zip(l) {
                    t.merge(s);
                }
            }
            tot.iter().enumerate().map(|(g, s)| s.fitness(g)).collect()
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(ConsistentFit {
        status: sol.status,
        fitness_filtered: fitness,
        parameters: sol.parameters,
    })
}
