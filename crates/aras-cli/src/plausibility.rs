//! Results no robotics engineer would believe, flagged loudly instead of
//! reported with confidence: in the terminal (stderr, also with
//! `--quiet`), in the report and in `summary.json` (`implausible`).
//!
//! Each check is a symptom of misread data rather than of a subtle model
//! error (torques in mN·m, angles or time in the wrong unit, filtering
//! switched off): the run still finishes and writes its outputs, since the
//! numbers may help to find the cause, but it does not pass for a result.

use serde::Serialize;

use crate::summary::Fitness;
use aras_pipeline::validate::PdSummary;

/// An SDP estimate more than this many fitness points (78) below OLS on
/// the identification log is implausible: on data its model explains the
/// two agree to tenths of a point (the default run: ≤ 0.1), so a large gap
/// says that no physical body reproduces the torques.
pub const SDP_GAP_POINTS: f64 = 5.0;

/// A link mass or mass-matrix eigenvalue more than this factor away from
/// the nominal robot's (the SDP's reference, e.g. from CAD) is implausible:
/// a CAD model is not wrong by an order of magnitude.
pub const SCALE_FACTOR: f64 = 10.0;

/// Measured torques beyond this multiple of the configured torque limit
/// (`simulation.torque_limit`) are implausible: no actuator delivers that;
/// the log's unit is the likely cause (mN·m is ×1000).
pub const TORQUE_LIMIT_FACTOR: f64 = 1.5;

/// What is implausible.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Check {
    /// The SDP fits far worse than OLS ([`SDP_GAP_POINTS`]).
    SdpFarBelowOls,
    /// The SDP solver did not reach its tolerance.
    SolverNotSolved,
    /// A link mass an order of magnitude from the nominal one.
    MassOutOfScale,
    /// The mass matrix an order of magnitude from the nominal one.
    MassMatrixOutOfScale,
    /// A friction level the actuator could not overcome.
    FrictionBeyondTorqueLimit,
    /// Logged torques beyond the configured torque limit.
    TorqueBeyondLimit,
}

/// One implausible finding.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Implausible {
    /// Which check.
    pub check: Check,
    /// What was found, with the figures, and what to look at.
    pub message: String,
}

/// What the checks look at.
pub struct Evidence<'a> {
    /// Fitness per dataset; the first is the identification log.
    pub fitness: &'a [Fitness],
    /// The SDP solver's status.
    pub status: aras_ident::SolverStatus,
    /// The physically consistent estimate.
    pub sdp: &'a aras_dyn::Params,
    /// The nominal robot (the SDP's reference).
    pub nominal: &'a aras_dyn::Params,
    /// The mass-matrix check of the SDP estimate and of the nominal robot.
    pub pd: (&'a PdSummary, &'a PdSummary),
    /// The configured torque limits (N·m).
    pub torque_limit: [f64; 2],
    /// The largest logged |τ| per joint (N·m).
    pub torque_peak: [f64; 2],
}

/// Every implausible finding of `e` (empty when the result is believable).
pub fn check(e: &Evidence) -> Vec<Implausible> {
    let mut out = Vec::new();
    let mut flag = |check, message: String| out.push(Implausible { check, message });
    if let Some(f) = e.fitness.first() {
        for j in 0..2 {
            let gap = f.ols[j] - f.sdp[j];
            if gap > SDP_GAP_POINTS || !f.sdp[j].is_finite() {
                flag(
                    Check::SdpFarBelowOls,
                    format!(
                        "τ{}: the physically consistent (SDP) fitness {:.1} % is {gap:.1} points \
                         below OLS ({:.1} %) on {}: no physical robot explains these torques. \
                         Check the torque unit (N·m), the angle and time units, and the \
                         filtering (signal.cutoff_hz)",
                        j + 1,
                        f.sdp[j],
                        f.ols[j],
                        f.dataset
                    ),
                );
            }
        }
    }
    if e.status != aras_ident::SolverStatus::Solved {
        flag(
            Check::SolverNotSolved,
            format!(
                "the SDP solver ended with status {:?}, not Solved: its estimate is not \
                 reliable; usually a symptom of data on the wrong scale",
                e.status
            ),
        );
    }
    for (k, (l, n)) in e.sdp.links.iter().zip(&e.nominal.links).enumerate() {
        if n.mass > 0.0 && out_of_scale(l.mass / n.mass) {
            flag(
                Check::MassOutOfScale,
                format!(
                    "link {}: mass {:.4} kg against the nominal {:.4} kg ({:.3}×)",
                    k + 1,
                    l.mass,
                    n.mass,
                    l.mass / n.mass
                ),
            );
        }
    }
    let (pd, nominal_pd) = e.pd;
    for (what, a, b) in [
        ("largest", pd.max_eigenvalue, nominal_pd.max_eigenvalue),
        ("smallest", pd.min_eigenvalue, nominal_pd.min_eigenvalue),
    ] {
        if b > 0.0 && (!a.is_finite() || out_of_scale(a / b)) {
            flag(
                Check::MassMatrixOutOfScale,
                format!(
                    "the mass matrix's {what} eigenvalue over the workspace is {a:.3e} kg·m² \
                     against the nominal robot's {b:.3e} ({:.3}×)",
                    a / b
                ),
            );
        }
    }
    for j in 0..2 {
        let limit = e.torque_limit[j];
        let fc = e.sdp.friction.coulomb[j];
        if limit > 0.0 && fc > limit {
            flag(
                Check::FrictionBeyondTorqueLimit,
                format!(
                    "Fc{} = {fc:.4} N·m exceeds the torque limit {limit} N·m \
                     (simulation.torque_limit): the motor could not move the joint",
                    j + 1
                ),
            );
        }
        let peak = e.torque_peak[j];
        if limit > 0.0 && peak > TORQUE_LIMIT_FACTOR * limit {
            flag(
                Check::TorqueBeyondLimit,
                format!(
                    "the log's τ{} reaches {peak:.4} (read as N·m), {:.1}× the torque limit \
                     {limit} N·m (simulation.torque_limit): is the torque logged in N·m? \
                     (mN·m would be 1000× too large); else set the robot's real limit",
                    j + 1,
                    peak / limit
                ),
            );
        }
    }
    out
}

fn out_of_scale(ratio: f64) -> bool {
    !(ratio.is_finite() && (1.0 / SCALE_FACTOR..=SCALE_FACTOR).contains(&ratio))
}

/// The largest |τ| per joint of a log's torques.
pub fn torque_peak(tau: &[Vec<f64>]) -> [f64; 2] {
    [0, 1].map(|j| tau[j].iter().fold(0.0_f64, |m, v| m.max(v.abs())))
}

/// Prints the findings on stderr, loudly (also with `--quiet`).
pub fn print(findings: &[Implausible]) {
    if findings.is_empty() {
        return;
    }
    eprintln!(
        "WARNING: IMPLAUSIBLE RESULT ({} finding{}); the outputs were written but should not \
         be used before the cause is found:",
        findings.len(),
        if findings.len() == 1 { "" } else { "s" }
    );
    for f in findings {
        eprintln!("  - {}", f.message);
    }
}
