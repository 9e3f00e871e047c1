//! Diagnosis of the ARAS-Diamond: where model and measurement disagree,
//! which missing effect explains it, and how much the gap shrinks once it
//! is added, by the robot-agnostic engine of `aras-diagnose` (its module
//! documentation describes the residual analysis, the selection with the
//! effective number of samples, the refinement, memory and time).
//!
//! What is the ARAS-Diamond's here:
//! * **Candidates** ([`CANDIDATE_IDS`], [`Candidate`]): `torque_offset`, `coulomb_asymmetry`,
//!   `stribeck_friction` (v_s scanned), `passive_joint_viscous`, `cogging`
//!   (cycles per revolution scanned, order configurable),
//!   `quadratic_damping`, `time_delay` (torque shifted against the angles),
//!   over the grids of [`CandidateGrid`].
//! * **The robot** ([`diagnose`]): the starting model's base regressor
//!   through the kinematics of every sample (its structural base from a
//!   Halton set of the workspace, as in identification), each candidate's
//!   columns from its single-effect [`aras_dyn::Model`], and the final
//!   model's physically consistent re-identification (SDP on the links,
//!   friction-like levels `≥ 0`) when a reference is given.
//! * **Its Coulomb widths** ([`diagnose_with_widths`]): the starting
//!   model's `Fc tanh(θ̇/w)` widths refined on TRAIN together with the
//!   effects the diagnosis names, the recipe `aras diagnose` runs.
//! * **Long logs**: a data set's samples may be in a scratch file
//!   ([`crate::spool::SpooledSamples`], an [`aras_diagnose::SampleSource`]),
//!   written while a long training log is processed in overlapping blocks
//!   ([`crate::streaming::spool_log`]).

mod candidates;
mod select;
mod widths;

pub use aras_diagnose::residual;
pub use aras_diagnose::{
    ConsistentFit, Dataset, EngineOptions, Finding, FitnessRow, LeftOut, LogPrediction, NamedValue,
    Refinement, RefinementStatus, ResidualAnalysis, ResidualSpectrum, RowSample, SAMPLE_ROWS,
    SampledRow, SearchScale, SpectrumBand, TRACE_POINTS, Trace, Whiteness,
};
pub use aras_diagnose::{chi2_sf, f_sf, integrated_time, ljung_box};
pub use candidates::{CANDIDATE_IDS, Candidate, CandidateGrid, TIME_DELAY, explanation};
pub use select::{CandidateScore, DiagnoseOptions, Diagnosis, Step, diagnose};
pub use widths::{
    Additions, DiagnosisWithWidths, PassRows, PassStage, WIDTH_PASSES, WidthSource,
    diagnose_with_widths, widths_with,
};

impl aras_diagnose::SampleSource for crate::spool::SpooledSamples {
    fn len(&self) -> usize {
        crate::spool::SpooledSamples::len(self)
    }

    fn read(
        &self,
        rows: std::ops::Range<usize>,
        out: &mut aras_signal::Samples,
    ) -> Result<(), aras_ident::IdentError> {
        crate::spool::SpooledSamples::read(self, rows, out)
            .map_err(crate::PipelineError::into_ident)
    }
}
