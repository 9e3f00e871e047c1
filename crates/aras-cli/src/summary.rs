//! `summary.json`: the machine-readable result of a run, and `base.json`.
//!
//! Deterministic: the same seed and settings give the same bytes, except
//! the wall-clock stage timings, which live under the single key
//! `"timings_s"` and are left out with `--reproducible`.

use std::collections::BTreeMap;

use aras_ident::SdpSolution;
use serde::Serialize;

use crate::identify::Identification;

/// What `summary.json` records of the processing (`aras_signal::ProcessSummary`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProcessingRecord {
    /// How the bandwidth was chosen.
    pub bandwidth: aras_signal::BandwidthMethod,
    /// The choice in one sentence, with the torque timing's handling.
    pub reason: String,
    /// The log's torque timing: `sampled` or `held`.
    pub torque_timing: aras_log::TorqueTiming,
    /// How far after each row the motion was evaluated (sample steps).
    pub motion_shift_steps: f64,
}

impl ProcessingRecord {
    /// The record of `summary`.
    pub fn new(summary: &aras_signal::ProcessSummary) -> Self {
        Self {
            bandwidth: summary.bandwidth.method,
            reason: summary.bandwidth.reason.clone(),
            torque_timing: summary.torque_timing,
            motion_shift_steps: summary.motion_shift_steps,
        }
    }
}
use aras_pipeline::validate::{CrossValidation, ErrorSummary, PdSummary};

/// Format tag of `summary.json`.
pub const SUMMARY_FORMAT: &str = "aras-summary/1";
/// Format tag of `base.json`.
pub const BASE_FORMAT: &str = "aras-base/1";

/// Fitness (78) per joint of the two estimates on one dataset.
#[derive(Debug, Clone, Serialize)]
pub struct Fitness {
    /// Dataset: `"excitation"` or `"xv_<f>hz"`.
    pub dataset: String,
    /// Frequency of (79) (Hz), for cross-validation datasets.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_hz: Option<f64>,
    /// OLS, `[τ1, τ2]` (%).
    pub ols: [f64; 2],
    /// Physically consistent (SDP), `[τ1, τ2]` (%).
    pub sdp: [f64; 2],
    /// OLS on the rows away from velocity reversals (the rows the fit
    /// uses), `[τ1, τ2]` (%).
    pub ols_kept: [f64; 2],
    /// SDP on the rows away from velocity reversals (%).
    pub sdp_kept: [f64; 2],
    /// Where `ols`/`sdp` were scored: the simulated robot or a measured log.
    pub data: DataKind,
    /// Noise ceiling (%): the fitness of the true robot's noise-free torques
    /// against the same log (`aras_pipeline::validate::ceiling`); known for
    /// simulated data only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_ceiling: Option<[f64; 2]>,
    /// The noise ceiling on the rows away from velocity reversals (compare
    /// with `ols_kept`, `sdp_kept`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_ceiling_kept: Option<[f64; 2]>,
    /// The paper's value for this kind of dataset (%), measured on the
    /// **real** robot (§7, Table 2): another experiment, shown for
    /// orientation, not a score to beat.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_real_robot: Option<[f64; 2]>,
}

/// Where a fitness was measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DataKind {
    /// A log of the simulated robot (the truth is known).
    Simulated,
    /// A log whose truth is unknown (e.g. the real robot).
    Measured,
}

/// The SDP solver's report.
#[derive(Debug, Clone, Serialize)]
pub struct SdpReport {
    /// Solver status.
    pub status: aras_ident::SolverStatus,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Residual norm `‖W_b β_b − T‖` of the SDP estimate (N·m).
    pub residual_norm: f64,
    /// The same for OLS (the unconstrained optimum).
    pub ols_residual_norm: f64,
    /// Link masses of the solution (kg).
    pub masses: Vec<f64>,
    /// Constraints active at the solution.
    pub active: Vec<String>,
}

impl SdpReport {
    /// From a solution.
    pub fn new(s: &SdpSolution) -> Self {
        Self {
            status: s.status,
            iterations: s.iterations,
            residual_norm: s.residual_norm,
            ols_residual_norm: s.ols_residual_norm,
            masses: s.masses.clone(),
            active: s
                .active
                .iter()
                .map(|a| format!("{:?} {}", a.kind, a.name))
                .collect(),
        }
    }
}

/// Pseudo-inertia smallest eigenvalues per link (kg·m²).
#[derive(Debug, Clone, Serialize)]
pub struct PseudoInertia {
    /// OLS completed near the nominal robot.
    pub ols: [f64; 4],
    /// SDP.
    pub sdp: [f64; 4],
    /// The truth (simulated data only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<[f64; 4]>,
}

/// The whole summary.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Always [`SUMMARY_FORMAT`].
    pub format: &'static str,
    /// The command that produced it.
    pub command: String,
    /// Seeds used (design, simulation), when simulated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Standard parameters of the identified model.
    pub standard_parameters: usize,
    /// Base parameters (numerical rank).
    pub base_parameters: usize,
    /// Condition number of the column-scaled excitation base regressor.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub excitation_condition_number: Option<f64>,
    /// Samples used in the fit (per joint).
    pub samples: usize,
    /// How the log was processed: the bandwidth's choice and why, the
    /// torque timing and the motion's shift; absent on the streaming route,
    /// whose blocks each have their own.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub processing: Option<ProcessingRecord>,
    /// What became of the log's logged derivative columns (`dtheta*`,
    /// `ddtheta*`) and why; absent when the log has none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub logged_derivatives: Option<String>,
    /// Sensor noise of the simulated logs (N·m, per joint), if simulated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub torque_noise_std_nm: Option<[f64; 2]>,
    /// Fitness per dataset.
    pub fitness: Vec<Fitness>,
    /// Workspace PD check of the mass matrix (80), per estimate.
    pub pd_check: BTreeMap<String, PdSummary>,
    /// Pseudo-inertia eigenvalues.
    pub pseudo_inertia_min_eigenvalue: PseudoInertia,
    /// Base-parameter errors against the truth, per estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameter_errors: Option<BTreeMap<String, ErrorSummary>>,
    /// The SDP solve.
    pub sdp: SdpReport,
    /// Findings that make the result implausible (`crate::plausibility`);
    /// empty when it is believable.
    pub implausible: Vec<crate::plausibility::Implausible>,
    /// The friction's Coulomb transition widths with σ, which rows each
    /// joint was fitted on, and why a joint fell back to the rows away from
    /// its reversals (`identification.rows`); absent on the streaming route,
    /// which fits the rows away from reversals with the sign law.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_width: Option<aras_pipeline::friction_width::WidthRefinement>,
    /// Wall-clock seconds per stage (absent with `--reproducible`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings_s: Option<BTreeMap<String, f64>>,
}

/// Builds the fitness list from the excitation fit and cross-validation.
/// `excitation_ceiling` is the noise ceiling of the identification log
/// (simulated logs only); cross-validation logs are always simulated.
pub fn fitness_list(
    id: &Identification,
    xv: &[CrossValidation],
    excitation_paper: bool,
    excitation_ceiling: Option<aras_pipeline::validate::ceiling::Ceiling>,
) -> Vec<Fitness> {
    let mut v = vec![Fitness {
        dataset: "excitation".into(),
        frequency_hz: None,
        ols: id.fitness_ols,
        sdp: id.fitness_sdp,
        ols_kept: id.fitness_ols_kept,
        sdp_kept: id.fitness_sdp_kept,
        data: if excitation_ceiling.is_some() {
            DataKind::Simulated
        } else {
            DataKind::Measured
        },
        noise_ceiling: excitation_ceiling.map(|c| c.all),
        noise_ceiling_kept: excitation_ceiling.map(|c| c.kept),
        paper_real_robot: excitation_paper.then_some(crate::paper::EXCITATION_FITNESS),
    }];
    for x in xv {
        v.push(Fitness {
            dataset: format!("xv_{}hz", x.frequency_hz),
            frequency_hz: Some(x.frequency_hz),
            ols: x.fitness[0],
            sdp: x.fitness[1],
            ols_kept: x.fitness_kept[0],
            sdp_kept: x.fitness_kept[1],
            data: DataKind::Simulated,
            noise_ceiling: x.ceiling.map(|c| c.all),
            noise_ceiling_kept: x.ceiling.map(|c| c.kept),
            paper_real_robot: crate::paper::table2(x.frequency_hz),
        });
    }
    v
}

/// One base parameter in `base.json`.
#[derive(Debug, Clone, Serialize)]
pub struct BaseEntry {
    /// `b1`, `b2`, …
    pub name: String,
    /// Its definition as a linear combination of standard parameters.
    pub definition: String,
    /// OLS value.
    pub ols: f64,
    /// OLS standard deviation (64), by the file's `sigma_method`.
    pub sigma: f64,
    /// σ% (65).
    pub sigma_percent: f64,
    /// The standard deviation assuming white noise before the filter
    /// (`OlsEstimate::with_filtered_noise`): the same on every route, so
    /// routes can be compared; optimistic when the residual is correlated.
    pub sigma_white: f64,
    /// The HAC sandwich's standard deviation alone (`null` on the streaming
    /// route, which keeps no residuals).
    pub sigma_hac: Option<f64>,
    /// SDP value.
    pub sdp: f64,
    /// The truth, when known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<f64>,
}

/// `base.json`.
#[derive(Debug, Clone, Serialize)]
pub struct BaseFile {
    /// Always [`BASE_FORMAT`].
    pub format: &'static str,
    /// Standard parameter names, in the order of the model.
    pub standard: Vec<String>,
    /// Standard parameters that never affect the torques.
    pub unidentifiable: Vec<String>,
    /// Residual variance σ²_ρ (66) (N²·m²).
    pub residual_variance: f64,
    /// Condition number of the fit's base regressor.
    pub condition_number: f64,
    /// Where `sigma` comes from.
    pub sigma_method: SigmaMethod,
    /// Rows per joint the fit used (away from velocity reversals).
    pub rows_fitted: [usize; 2],
    /// The base parameters.
    pub parameters: Vec<BaseEntry>,
}

/// How the σ of `base.json` was computed (the library's enum).
pub use aras_pipeline::identify::SigmaMethod;

/// Builds `base.json`'s content.
pub fn base_file(id: &Identification, truth_base: Option<&[f64]>) -> BaseFile {
    let o = &id.ols;
    BaseFile {
        format: BASE_FORMAT,
        standard: id.names.clone(),
        unidentifiable: id
            .base
            .unidentifiable()
            .iter()
            .map(|s| s.to_string())
            .collect(),
        residual_variance: o.residual_variance,
        condition_number: o.condition_number,
        sigma_method: id.sigma_method,
        rows_fitted: id.rows_fitted,
        parameters: (0..id.base.n_base())
            .map(|i| BaseEntry {
                name: format!("b{}", i + 1),
                definition: id.base.expression(i),
                ols: o.estimate[i],
                sigma: o.std_dev[i],
                sigma_percent: o.rel_std_percent[i],
                sigma_white: id.sigma_white[i],
                sigma_hac: Some(id.sigma_hac[i]),
                sdp: id.sdp.base[i],
                truth: truth_base.map(|t| t[i]),
            })
            .collect(),
    }
}
