//! The diagnosis of a model whose Coulomb law has refined transition
//! widths (`Fc tanh(θ̇/w)`, [`crate::friction_width`]): the widths are a
//! setting of the starting model's friction, so they are refined together
//! with the effects the diagnosis names. A width refined without a missing
//! effect absorbs part of it and leaves the rest to a wrong candidate.
//!
//! [`diagnose_with_widths`] is that recipe, the one `aras diagnose` runs:
//! widths refined on TRAIN as identification refines them, a diagnosis
//! ([`diagnose()`]), the widths refined again with the effects it named,
//! until it names the effects it was refined with (at most
//! [`WIDTH_PASSES`] passes).

use crate::PipelineError;
use std::path::Path;

use aras_dyn::{Effect, Model};
use aras_ident::IdentError;
use aras_kin::Geometry;
use aras_log::Log;
use aras_signal::ProcessOptions;

use super::{Candidate, Dataset, DiagnoseOptions, Diagnosis, Step, diagnose};
use crate::friction_width::{FitRows, WidthRefinement, WidthStatus, with_widths};
use crate::identify::{IdentifySettings, friction_widths};
use crate::prepare::{RegressorColumns, prepare};
use crate::robot::base_parameters;
use crate::streaming::{StreamingOptions, identify_log};

/// Most diagnosis passes with re-refined Coulomb widths.
pub const WIDTH_PASSES: usize = 3;

/// What a diagnosis named, as a model takes it: effects with their refined
/// settings, and a torque delay (`aras_signal::delay_torque`, samples)
/// removed from the logs before processing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Additions {
    /// Effects whose columns are appended to the starting model.
    pub effects: Vec<Effect>,
    /// The torque is taken this many samples after the angles (fractions
    /// interpolated).
    pub torque_delay: Option<f64>,
}

impl Additions {
    /// The effects and delay that `steps` added, each at its refined
    /// setting where it has one.
    pub fn named(steps: &[Step]) -> Self {
        let mut out = Self::default();
        for s in steps {
            match s.refined_candidate() {
                Candidate::Effect { effect } => out.effects.push(effect),
                Candidate::TimeDelay { samples } => out.torque_delay = Some(samples),
            }
        }
        out
    }

    /// `start` with the effects appended (their columns come last).
    ///
    /// # Errors
    /// An effect the model already has, or one it cannot take
    /// ([`IdentError::External`], naming the effect).
    pub fn model(&self, start: &Model) -> Result<Model, PipelineError> {
        let mut model = start.clone();
        for e in &self.effects {
            model = model.with_effect(*e).map_err(|err| {
                IdentError::external(format!("adding the effect `{}` to the model", e.id()), err)
            })?;
        }
        Ok(model)
    }
}

/// Where the Coulomb widths are refined: TRAIN, read as identification
/// reads it.
#[derive(Debug, Clone, Copy)]
pub enum WidthSource<'a> {
    /// None: the sign law (49), each joint fitted away from its reversals
    /// (as identification with [`FitRows::AwayFromReversals`]).
    SignLaw,
    /// The log in memory, processed with these options (identification's).
    Log {
        /// TRAIN.
        log: &'a Log,
        /// Its processing.
        process: &'a ProcessOptions,
    },
    /// The log's file, read in bounded memory by the streaming
    /// identification ([`identify_log`]), which refines the widths on the
    /// averaged period (a log without a period keeps the sign law).
    Streamed {
        /// TRAIN's file.
        path: &'a Path,
        /// Its reading, processing and width search; the torque delay is
        /// set by each pass.
        options: &'a StreamingOptions,
    },
}

/// The rows a diagnosis pass fits and scores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassRows {
    /// Every row of a joint whose width was refined, the rows away from
    /// reversals of the others.
    Fitted,
    /// Every row of every joint whose width was refined or whose reversals
    /// the Coulomb law does not describe: the reversals are where the
    /// missing effect lies.
    EveryRow,
    /// The rows identification fits, from its widths: nothing named made
    /// the reversals described.
    IdentifyRows,
}

/// A stage of [`diagnose_with_widths`] about to start (for a progress
/// display; the library draws nothing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassStage {
    /// The Coulomb widths refined on TRAIN with the additions so far.
    Widths {
        /// Pass number, from 1.
        pass: usize,
    },
    /// A diagnosis.
    Diagnose {
        /// Pass number, from 1.
        pass: usize,
        /// Its rows.
        rows: PassRows,
    },
}

/// The result of [`diagnose_with_widths`].
#[derive(Debug, Clone)]
pub struct DiagnosisWithWidths {
    /// The diagnosis kept.
    pub diagnosis: Diagnosis,
    /// The starting model's Coulomb widths it ran with.
    pub widths: WidthRefinement,
    /// Passes run.
    pub passes: usize,
}

/// The Coulomb widths of `start` refined on `source` with `additions`, as
/// identification refines them (`identification`: rows, filtering,
/// reversal threshold, width search); the base parameters on
/// `opts.workspace` with `opts.base_samples` states, as the diagnosis's.
/// Returns `start` with the widths, and the refinement.
///
/// # Errors
/// Processing, stacking or estimation failures of TRAIN.
pub fn widths_with(
    start: &Model,
    geometry: &Geometry,
    source: &WidthSource,
    identification: &IdentifySettings,
    opts: &DiagnoseOptions,
    additions: &Additions,
) -> Result<(Model, WidthRefinement), PipelineError> {
    if !refines(source, identification) {
        return Ok((start.clone(), WidthRefinement::not_refined()));
    }
    let with = additions.model(start)?;
    let base = base_parameters(&with, geometry, &opts.workspace, opts.base_samples)?;
    let refinement = match *source {
        WidthSource::SignLaw => WidthRefinement::not_refined(),
        WidthSource::Log { log, process } => {
            let delayed;
            let log = match additions.torque_delay {
                Some(d) => {
                    delayed = aras_signal::delay_torque(log, d).map_err(|e| {
                        IdentError::external(format!("delaying TRAIN's torques by {d} samples"), e)
                    })?;
                    &delayed
                }
                None => log,
            };
            let mut prepared = prepare(
                log,
                process,
                &with,
                geometry,
                identification.filtering,
                RegressorColumns::Standard,
                true,
            )?;
            friction_widths(&mut prepared, &base, &with, identification)?.1
        }
        WidthSource::Streamed { path, options } => {
            let options = StreamingOptions {
                torque_delay: additions.torque_delay,
                ..options.clone()
            };
            identify_log(path, &with, &base, &options)?.widths
        }
    };
    Ok((with_widths(start, refinement.widths())?, refinement))
}

/// Whether the widths are refined: a source to refine them on, and
/// identification fitting every row.
fn refines(source: &WidthSource, identification: &IdentifySettings) -> bool {
    identification.rows == FitRows::All && !matches!(source, WidthSource::SignLaw)
}

/// The diagnosis of `start` ([`diagnose()`] with `opts`) with its Coulomb
/// widths refined on `source` together with the effects it names.
///
/// Each pass refines the widths with the additions named so far
/// ([`widths_with`]) and diagnoses on the rows they describe
/// ([`PassRows::Fitted`]); when a pass names what it was refined with, or
/// after [`WIDTH_PASSES`] passes, it is kept.
///
/// A joint whose Coulomb law does not describe its reversals
/// ([`WidthStatus::ReversalsNotDescribed`]: identification fits it away
/// from them) is diagnosed on every row ([`PassRows::EveryRow`]), since the
/// reversals are where the missing effect lies; its start there is poor,
/// so only the first effect named (the clearest) refines the next pass's
/// widths. If nothing is named, or the named effects do not make the
/// reversals described, the diagnosis runs on the rows identification
/// fits, from its widths ([`PassRows::IdentifyRows`]). A pass whose widths
/// describe every reversal is kept when the effects it named would make a
/// joint fall back again.
///
/// With [`WidthSource::SignLaw`] or `identification.rows` =
/// [`FitRows::AwayFromReversals`] the sign law (49) is kept and one diagnosis runs on the rows away from
/// reversals. `stage` is called as each stage starts.
///
/// # Errors
/// Those of [`widths_with`] and [`diagnose()`].
#[allow(clippy::too_many_arguments)]
pub fn diagnose_with_widths(
    start: &Model,
    geometry: &Geometry,
    train: &Dataset,
    validation: &[Dataset],
    opts: &DiagnoseOptions,
    source: &WidthSource,
    identification: &IdentifySettings,
    stage: &mut dyn FnMut(PassStage),
) -> Result<DiagnosisWithWidths, PipelineError> {
    let refined = refines(source, identification);
    let mut additions = Additions::default();
    let mut consistent = None;
    let mut identify_widths = None;
    let mut pass = 0;
    loop {
        pass += 1;
        stage(PassStage::Widths { pass });
        let (model, widths) =
            widths_with(start, geometry, source, identification, opts, &additions)?;
        let not_described = widths
            .joints
            .map(|j| j.status == WidthStatus::ReversalsNotDescribed);
        if pass == 1 {
            identify_widths = Some((model.clone(), widths.clone()));
        }
        let mut run = |model: &Model, all_rows: [bool; 2], rows: PassRows| {
            stage(PassStage::Diagnose { pass, rows });
            let opts = DiagnoseOptions {
                all_rows,
                ..opts.clone()
            };
            diagnose(model, geometry, train, validation, &opts)
        };
        let kept = |diagnosis: Diagnosis, widths: WidthRefinement| DiagnosisWithWidths {
            diagnosis,
            widths,
            passes: pass,
        };
        let fitted = widths.joints.map(|j| j.all_rows);
        if !not_described.contains(&true) {
            let d = run(&model, fitted, PassRows::Fitted)?;
            let named = Additions::named(&d.steps);
            if !refined || named == additions || pass >= WIDTH_PASSES {
                return Ok(kept(d, widths));
            }
            consistent = Some((d, widths));
            additions = named;
            continue;
        }
        if let Some((d, widths)) = consistent.take() {
            return Ok(DiagnosisWithWidths {
                passes: pass - 1,
                ..kept(d, widths)
            });
        }
        let every = [0, 1].map(|j| fitted[j] || not_described[j]);
        let d = (pass < WIDTH_PASSES)
            .then(|| run(&model, every, PassRows::EveryRow))
            .transpose()?;
        match d {
            Some(d) if !d.steps.is_empty() => additions = Additions::named(&d.steps[..1]),
            _ => {
                let (model, widths) = identify_widths.take().unwrap_or((model, widths));
                let fitted = widths.joints.map(|j| j.all_rows);
                let d = run(&model, fitted, PassRows::IdentifyRows)?;
                return Ok(kept(d, widths));
            }
        }
    }
}
