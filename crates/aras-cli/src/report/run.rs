//! The identification report: what a reader wants to see after a run, in
//! the order of the data flow, with the noise ceiling next to simulated
//! fitness and the paper's real-robot numbers labelled as such.

use std::collections::BTreeMap;

use anyhow::Result;
use aras_excite::Design;
use aras_signal::ProcessSummary;

use super::Report;
use super::plots::{Series, bars, heatmap, lines};
use crate::identify::Identification;
use crate::paper;
use crate::summary::{Fitness, PseudoInertia, SigmaMethod};
use aras_pipeline::validate::{CrossValidation, ErrorSummary, PdSummary};

/// Everything the report shows; absent parts are skipped.
pub struct RunData<'a> {
    /// Report title.
    pub title: String,
    /// One paragraph on what was run (data source, noise, seed).
    pub intro: String,
    /// Stage timings (s).
    pub timings: &'a [(String, f64)],
    /// The excitation design, when one was made.
    pub design: Option<&'a Design>,
    /// What the signal processing did.
    pub processing: &'a ProcessSummary,
    /// Time of the fitted samples (s).
    pub t: &'a [f64],
    /// Measured (processed) stacked torques.
    pub measured: &'a [f64],
    /// The identification.
    pub id: &'a Identification,
    /// Fitness per dataset.
    pub fitness: &'a [Fitness],
    /// Cross-validation runs.
    pub xv: &'a [CrossValidation],
    /// PD checks per estimate.
    pub pd: &'a BTreeMap<String, PdSummary>,
    /// Heat map of the SDP mass matrix's smallest eigenvalue.
    pub heat: Option<&'a aras_pipeline::validate::EigenGrid>,
    /// Pseudo-inertia eigenvalues.
    pub pseudo: &'a PseudoInertia,
    /// Parameter errors, when the truth is known.
    pub errors: Option<&'a BTreeMap<String, ErrorSummary>>,
    /// True base parameters, when known.
    pub truth_base: Option<&'a [f64]>,
    /// What makes the result implausible (`crate::plausibility`).
    pub implausible: &'a [crate::plausibility::Implausible],
}

fn f(v: f64, digits: usize) -> String {
    format!("{v:.digits$}")
}

fn g(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e-3 && v.abs() < 1e4 {
        format!("{v:.5}")
    } else {
        format!("{v:.4e}")
    }
}

/// What the summary table means for a simulated log: the noise ceiling
/// and the paper's values next to ours.
pub const SIMULATED_FITNESS: &str = "Fitness (78) in %, `100 (1 − ‖τ − τ̂‖/‖τ − mean τ‖)`, on \
     the processed (period-averaged, zero-phase filtered) torques: OLS and SDP columns on \
     **every** sample; the \"kept\" columns only on the rows away from velocity reversals (the \
     rows the fit uses; `identification.min_speed`, widened by the filter's reach), where \
     (49)'s Coulomb model holds. **Ceiling**: the fitness of a perfect prediction against the \
     same noisy log: the torque the simulated motors really produced, before the sensor noise \
     (no model, no parameters, no processing; on the kept rows it is processed exactly like \
     the measured torques). What separates it from 100 % is the sensor noise alone; what \
     separates ours from it is everything else: the identification, the processing \
     (derivatives from quantised angles) and, on every row, the paper's sign-Coulomb friction \
     (49) against the simulated robot's smooth friction at velocity reversals. It is known \
     only for logs simulated in the same run. **Paper**: the published values measured on the \
     *real* robot (§7: about 75 % OLS / 78 % constrained on the excitation; Table 2 on (79)), \
     a different experiment with the real robot's unmodelled effects and sensors: shown for \
     orientation, not comparable with a simulation.";

/// What the summary table means for a log scored without a noise ceiling
/// (a measured log, or a simulated one whose noise-free torques this run
/// does not have); [`measured_fitness`] adds what the sidecar tells.
const MEASURED_FITNESS: &str = "Fitness (78) in %, `100 (1 − ‖τ − τ̂‖/‖τ − mean τ‖)`, of \
     the identified model against this log's processed (period-averaged, zero-phase \
     filtered) measured torques: OLS and SDP columns on **every** sample; the \"kept\" columns \
     only on the rows away from velocity reversals (the rows the fit uses; \
     `identification.min_speed`, widened by the filter's reach), where (49)'s Coulomb model \
     holds.";

/// `MEASURED_FITNESS` and what the log's origin allows: with the
/// simulation's truth (`truth`) parameter errors but no ceiling; without
/// it, neither.
pub fn measured_fitness(truth: bool) -> String {
    let origin = if truth {
        "The sidecar holds the simulation's truth (parameter errors below) but this run does \
         not have the noise-free torques, so there is no noise ceiling"
    } else {
        "The log is measured (its sidecar holds no simulation truth), so there is no noise \
         ceiling and no parameter error"
    };
    format!(
        "{MEASURED_FITNESS} {origin}: what separates the fitness from 100 % is sensor noise and \
         model error together; `aras diagnose` shows which effects the model misses. \
         **Paper**: the published values measured on the real robot (§7), another experiment: \
         shown for orientation."
    )
}

/// Builds the report.
pub fn build(d: &RunData) -> Result<Report> {
    let mut r = Report::new(&d.title);
    r.paragraph(&d.intro);
    if !d.implausible.is_empty() {
        r.heading(1, "WARNING: implausible result");
        r.paragraph(
            "The checks below failed (`summary.json`, key `implausible`): the figures that \
             follow were computed, but should not be used before the cause is found.",
        );
        r.list(d.implausible.iter().map(|i| i.message.clone()).collect());
    }

    let simulated = d
        .fitness
        .iter()
        .any(|x| x.data == crate::summary::DataKind::Simulated);
    r.heading(
        1,
        if simulated {
            "Summary: fitness on the simulated robot, next to the noise ceiling"
        } else {
            "Summary: fitness on the log"
        },
    );
    // The ceiling columns and their explanation only where a ceiling is
    // known: a measured log has none.
    let mut rows = Vec::new();
    for x in d.fitness {
        let pair = |v: Option<[f64; 2]>, digits: usize| {
            v.map_or(["–".to_string(), "–".to_string()], |p| {
                [f(p[0], digits), f(p[1], digits)]
            })
        };
        let c = pair(x.noise_ceiling, 2);
        let ck = pair(x.noise_ceiling_kept, 2);
        let p = pair(x.paper_real_robot, 1);
        rows.push(if simulated {
            vec![
                x.dataset.clone(),
                f(x.ols[0], 2),
                f(x.sdp[0], 2),
                c[0].clone(),
                f(x.ols[1], 2),
                f(x.sdp[1], 2),
                c[1].clone(),
                f(x.ols_kept[0], 2),
                ck[0].clone(),
                f(x.ols_kept[1], 2),
                ck[1].clone(),
                p[0].clone(),
                p[1].clone(),
            ]
        } else {
            vec![
                x.dataset.clone(),
                f(x.ols[0], 2),
                f(x.sdp[0], 2),
                f(x.ols[1], 2),
                f(x.sdp[1], 2),
                f(x.ols_kept[0], 2),
                f(x.ols_kept[1], 2),
                p[0].clone(),
                p[1].clone(),
            ]
        });
    }
    let header: &[&str] = if simulated {
        &[
            "dataset",
            "OLS τ1",
            "SDP τ1",
            "ceiling τ1",
            "OLS τ2",
            "SDP τ2",
            "ceiling τ2",
            "kept OLS τ1",
            "kept ceiling τ1",
            "kept OLS τ2",
            "kept ceiling τ2",
            "paper τ1 (real robot)",
            "paper τ2 (real robot)",
        ]
    } else {
        &[
            "dataset",
            "OLS τ1",
            "SDP τ1",
            "OLS τ2",
            "SDP τ2",
            "kept OLS τ1",
            "kept OLS τ2",
            "paper τ1 (real robot)",
            "paper τ2 (real robot)",
        ]
    };
    r.table(header, rows);
    r.paragraph(if simulated {
        SIMULATED_FITNESS.to_string()
    } else {
        measured_fitness(d.errors.is_some())
    });

    if let Some(des) = d.design {
        r.heading(1, "Excitation trajectory (74)–(77)");
        let tr = &des.trajectory;
        let n = 500;
        let ts: Vec<f64> = (0..=n).map(|i| tr.period() * i as f64 / n as f64).collect();
        let st: Vec<_> = ts.iter().map(|&t| tr.eval(t)).collect();
        let phi: Vec<f64> = st.iter().map(|s| s.pos[0].to_degrees()).collect();
        let gam: Vec<f64> = st.iter().map(|s| s.pos[1].to_degrees()).collect();
        let svg = lines(
            "Excitation trajectory (one period)",
            "t (s)",
            "angle (deg)",
            &[
                Series {
                    name: "φ".into(),
                    x: &ts,
                    y: &phi,
                },
                Series {
                    name: "γ".into(),
                    x: &ts,
                    y: &gam,
                },
            ],
            500,
        )?;
        r.figure(
            "excitation.svg",
            "Task coordinates φ, γ of the designed excitation",
            svg,
        );
        r.list(vec![
            format!(
                "{} harmonics, period {:.3} s, criterion {:?}: condition number of the column-scaled base regressor **{:.3}**",
                tr.harmonics(),
                tr.period(),
                des.criterion,
                des.condition_number
            ),
            format!(
                "best of {} starts (start {}); worst relative limit margin {:.4} on {} points",
                des.starts.len(),
                des.best_start,
                des.margins.worst_relative,
                des.margins.points
            ),
        ]);
    }

    r.heading(1, "Signal processing (§6)");
    let p = d.processing;
    let mut items = vec![
        format!(
            "{} input samples at {:.1} Hz → {} samples fitted",
            p.input_samples, p.sample_rate_hz, p.output_samples
        ),
        format!(
            "angles from {}, torques from {}",
            p.angle_source, p.torque_source
        ),
        format!("derivatives: {:?} ({})", p.derivative, p.derivative_source),
    ];
    if let Some(per) = &p.periods {
        items.push(format!(
            "period averaging: {} periods of {:.3} s in {} blocks of {} periods ({} samples each), relative spread θ {:.2e}/{:.2e}, τ {:.2e}/{:.2e}",
            per.periods_averaged,
            per.period_s,
            per.blocks_averaged,
            per.periods_per_block,
            per.samples_per_block,
            per.spread_relative[0],
            per.spread_relative[1],
            per.spread_relative[2],
            per.spread_relative[3]
        ));
    }
    if let Some(fl) = &p.filter {
        items.push(format!(
            "low-pass: Butterworth order {} at {} Hz, {}",
            fl.order, fl.cutoff_hz, fl.kind
        ));
    }
    r.list(items);

    torque_figures(&mut r, d)?;
    base_table(&mut r, d);
    cross_validation(&mut r, d)?;
    mass_matrix(&mut r, d)?;
    pseudo_inertia(&mut r, d);
    if let Some(errs) = d.errors {
        r.heading(1, "Parameter errors against the simulation's truth");
        let mut rows = Vec::new();
        for (k, e) in errs {
            rows.push(vec![
                k.clone(),
                f(e.max_relative_percent, 3),
                f(e.rms_in_sigma, 2),
            ]);
        }
        r.table(
            &["estimate", "max |error|/|truth| (%)", "RMS error/σ"],
            rows,
        );
        r.paragraph(
            "Over the base parameters (the only identifiable quantities). RMS error/σ near 1 means \
             the OLS standard deviations (64) are honest; the SDP is pulled towards the nominal robot \
             by its regulariser and constraints, so its errors are not Gaussian.",
        );
    }
    let s = &d.id.sdp;
    r.heading(1, "Physically consistent solve (67)–(73)");
    r.list(vec![
        format!("status {} after {} iterations", s.status, s.iterations),
        format!(
            "residual ‖W_b β − T‖ = {:.6} N·m (OLS optimum {:.6} N·m)",
            s.residual_norm, s.ols_residual_norm
        ),
        format!(
            "masses (kg): {}",
            s.masses
                .iter()
                .map(|m| f(*m, 4))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        format!(
            "active constraints: {}",
            if s.active.is_empty() {
                "none".to_string()
            } else {
                s.active
                    .iter()
                    .map(|a| format!("{:?} {}", a.kind, a.name))
                    .collect::<Vec<_>>()
                    .join("; ")
            }
        ),
    ]);

    r.heading(1, "Timings");
    let total: f64 = d.timings.iter().map(|t| t.1).sum();
    let mut rows: Vec<Vec<String>> = d
        .timings
        .iter()
        .map(|(n, s)| vec![n.clone(), f(*s, 2)])
        .collect();
    rows.push(vec!["**total**".into(), f(total, 2)]);
    r.table(&["stage", "wall-clock (s)"], rows);
    Ok(r)
}

fn torque_figures(r: &mut Report, d: &RunData) -> Result<()> {
    r.heading(1, "Measured vs predicted torque on the identification data");
    let n = d.t.len();
    for j in 0..2 {
        let rng = j * n..(j + 1) * n;
        let m = &d.measured[rng.clone()];
        let o = &d.id.predicted_ols[rng.clone()];
        let s = &d.id.predicted_sdp[rng];
        let svg = lines(
            &format!("Joint {} torque", j + 1),
            "t (s)",
            "τ (N·m)",
            &[
                Series {
                    name: "measured".into(),
                    x: d.t,
                    y: m,
                },
                Series {
                    name: "OLS".into(),
                    x: d.t,
                    y: o,
                },
                Series {
                    name: "SDP".into(),
                    x: d.t,
                    y: s,
                },
            ],
            800,
        )?;
        r.figure(
            format!("torque{}.svg", j + 1),
            format!("Joint {}: measured and predicted torque", j + 1),
            svg,
        );
        let ro: Vec<f64> = m.iter().zip(o).map(|(a, b)| a - b).collect();
        let rs: Vec<f64> = m.iter().zip(s).map(|(a, b)| a - b).collect();
        let svg = lines(
            &format!("Joint {} residual", j + 1),
            "t (s)",
            "τ − τ̂ (N·m)",
            &[
                Series {
                    name: "OLS".into(),
                    x: d.t,
                    y: &ro,
                },
                Series {
                    name: "SDP".into(),
                    x: d.t,
                    y: &rs,
                },
            ],
            800,
        )?;
        r.figure(
            format!("residual{}.svg", j + 1),
            format!("Joint {}: residuals", j + 1),
            svg,
        );
    }
    Ok(())
}

fn base_table(r: &mut Report, d: &RunData) {
    let id = d.id;
    r.heading(1, "Base parameters (58)–(66), Table 1 style");
    r.paragraph(format!(
        "{} standard parameters → **{} base parameters** (numerical rank; rank margin: smallest kept {:.2e}, largest dropped {:.2e}, tolerance {:.0e}). \
         The paper reports 21 for its model; the count depends on gravity and the model (docs/model.md, section Base parameters), and its \
         21 combinations are not published, so its values are listed by index only as a Table 1 style reference, \
         **not comparable one-to-one** with ours.",
        id.base.n_standard(),
        id.base.n_base(),
        id.base.rank_margin().smallest_kept,
        id.base.rank_margin().largest_dropped,
        id.base.rank_margin().tolerance,
    ));
    let mut rows = Vec::new();
    for i in 0..id.base.n_base() {
        let def = id.base.expression(i);
        let def = def
            .split_once(" = ")
            .map_or(def.clone(), |(_, rhs)| rhs.to_string());
        let truth = d.truth_base.map_or("–".into(), |t| g(t[i]));
        let (pv, ps) = paper::TABLE1
            .get(i)
            .map_or(("–".into(), "–".into()), |(v, s)| (g(*v), f(*s, 2)));
        rows.push(vec![
            format!("b{}", i + 1),
            format!("`{def}`"),
            g(id.ols.estimate[i]),
            f(id.ols.rel_std_percent[i], 2),
            g(id.sdp.base[i]),
            truth,
            pv,
            ps,
        ]);
    }
    r.table(
        &[
            "#",
            "definition",
            "OLS",
            "σ%",
            "SDP",
            "truth",
            "paper #",
            "paper σ%",
        ],
        rows,
    );
    let un = id.base.unidentifiable();
    if !un.is_empty() {
        r.paragraph(format!(
            "Unidentifiable (no effect on the torques): {}.",
            un.join(", ")
        ));
    }
    let rows = d.measured.len() / 2;
    let which = match id.rows_fitted.map(|n| n == rows) {
        [true, true] => "every row, with the Coulomb transition widths refined",
        [false, false] => "away from velocity reversals",
        _ => {
            "every row for a joint whose Coulomb transition width was refined, away from \
               velocity reversals for the other"
        }
    };
    let sigma = match id.sigma_method {
        SigmaMethod::HarmonicSandwich => {
            "the harmonic sandwich (`aras_ident::spectral`): every row of the averaged period \
             was fitted, so the residual's spectrum is measured harmonic by harmonic and \
             weighed by the regressor's own harmonics"
        }
        SigmaMethod::LargerOfHacAndWhiteFiltered => {
            "the larger of the HAC sandwich covariance (`aras_ident::covariance`, which counts \
             the filtered residual's correlation with a bandwidth from its own autocorrelation \
             time) and the white-noise model of the filter, per parameter"
        }
        SigmaMethod::WhiteFiltered => "the white-noise model of the filtered torques",
    };
    r.paragraph(format!(
        "Residual standard deviation σ_ρ = {:.3e} N·m (66); condition number of the base regressor {:.1}; largest σ% {:.2}. \
         Fitted on {} (joint 1) and {} (joint 2) of {rows} rows each, {which}; \
         σ and σ% come from {sigma}.",
        id.ols.residual_variance.sqrt(),
        id.ols.condition_number,
        id.ols.rel_std_percent.iter().cloned().fold(0.0, f64::max),
        id.rows_fitted[0],
        id.rows_fitted[1],
    ));
}

fn cross_validation(r: &mut Report, d: &RunData) -> Result<()> {
    if d.xv.is_empty() {
        return Ok(());
    }
    r.heading(1, "Cross-validation on (79) (simulated robot)");
    let mut rows = Vec::new();
    for x in d.xv {
        let p = paper::table2(x.frequency_hz);
        let ps = |j: usize| p.map_or("–".to_string(), |p| f(p[j], 1));
        rows.push(vec![
            format!("{} Hz", x.frequency_hz),
            f(x.fitness[0][0], 2),
            f(x.fitness[1][0], 2),
            x.ceiling.map_or("–".to_string(), |c| f(c.all[0], 2)),
            f(x.fitness[0][1], 2),
            f(x.fitness[1][1], 2),
            x.ceiling.map_or("–".to_string(), |c| f(c.all[1], 2)),
            ps(0),
            ps(1),
        ]);
    }
    r.table(
        &[
            "f",
            "OLS τ1",
            "SDP τ1",
            "ceiling τ1",
            "OLS τ2",
            "SDP τ2",
            "ceiling τ2",
            "paper τ1 (real robot)",
            "paper τ2 (real robot)",
        ],
        rows,
    );
    r.paragraph(
        "Ours and the ceiling on simulated logs of (79); the paper's Table 2 was measured on \
         the real robot (another experiment, for orientation only).",
    );
    let cats: Vec<String> =
        d.xv.iter()
            .map(|x| format!("{} Hz", x.frequency_hz))
            .collect();
    // The ceiling's bars when every log has one (the simulated logs of (79)).
    let ceilings: Option<Vec<[f64; 2]>> = d.xv.iter().map(|x| x.ceiling.map(|c| c.all)).collect();
    let mut series = Vec::new();
    for j in 0..2 {
        series.push((
            format!("SDP τ{} (simulated)", j + 1),
            d.xv.iter().map(|x| x.fitness[1][j]).collect(),
        ));
        if let Some(c) = &ceilings {
            series.push((
                format!("ceiling τ{} (simulated)", j + 1),
                c.iter().map(|c| c[j]).collect(),
            ));
        }
    }
    let svg = bars("Cross-validation fitness", "fitness (%)", &cats, &series)?;
    r.figure(
        "cross_validation.svg",
        "Fitness (78) per frequency on the simulated robot: SDP next to the noise ceiling",
        svg,
    );
    if let Some(x) = d.xv.last() {
        let n = x.traces.t.len();
        let mut ys = Vec::new();
        for j in 0..2 {
            ys.push((
                format!("measured τ{}", j + 1),
                &x.traces.measured[j * n..(j + 1) * n],
            ));
            ys.push((
                format!("SDP τ{}", j + 1),
                &x.traces.predicted[1][j * n..(j + 1) * n],
            ));
        }
        let series: Vec<Series> = ys
            .iter()
            .map(|(name, y)| Series {
                name: name.clone(),
                x: &x.traces.t,
                y,
            })
            .collect();
        let svg = lines(
            &format!(
                "Cross-validation at {} Hz (one averaged period)",
                x.frequency_hz
            ),
            "t (s)",
            "τ (N·m)",
            &series,
            600,
        )?;
        r.figure(
            "cross_validation_fastest.svg",
            "Measured vs SDP-predicted torque on the fastest cross-validation trajectory",
            svg,
        );
    }
    Ok(())
}

fn mass_matrix(r: &mut Report, d: &RunData) -> Result<()> {
    r.heading(1, "Mass matrix (80) over the workspace");
    let mut rows = Vec::new();
    for (k, p) in d.pd {
        rows.push(vec![
            k.clone(),
            p.points.to_string(),
            format!("{:.4e}", p.min_eigenvalue),
            format!("({:.1}°, {:.1}°)", p.argmin_deg[0], p.argmin_deg[1]),
            format!("{:.4e}", p.max_eigenvalue),
            format!("({:.1}°, {:.1}°)", p.argmax_deg[0], p.argmax_deg[1]),
            if p.positive_definite {
                "yes".into()
            } else {
                format!("**no** ({} points)", p.non_positive + p.failures)
            },
        ]);
    }
    r.table(
        &[
            "estimate",
            "points",
            "min eig (kg·m²)",
            "at (φ, γ)",
            "max eig (kg·m²)",
            "at (φ, γ)",
            "PD everywhere",
        ],
        rows,
    );
    r.paragraph("Motor-space mass matrix `J⁻ᵀ M J⁻¹` at rest, on a grid plus random points of the box (77).");
    if let Some((xs, ys, v)) = d.heat {
        let svg = heatmap(
            "Smallest mass-matrix eigenvalue (SDP), kg·m²",
            "φ (deg)",
            "γ (deg)",
            xs,
            ys,
            v,
        )?;
        r.figure("mass_eigen.svg", "Smallest eigenvalue of the motor-space mass matrix of the SDP estimate over the workspace", svg);
    }
    Ok(())
}

fn pseudo_inertia(r: &mut Report, d: &RunData) {
    r.heading(
        1,
        "Pseudo-inertia minimum eigenvalues (physical consistency)",
    );
    let p = d.pseudo;
    let rows = (0..4)
        .map(|k| {
            vec![
                format!("link {}", k + 1),
                format!("{:.3e}", p.ols[k]),
                format!("{:.3e}", p.sdp[k]),
                p.truth.map_or("–".into(), |t| format!("{:.3e}", t[k])),
            ]
        })
        .collect();
    r.table(
        &["link", "OLS (completed near nominal)", "SDP", "truth"],
        rows,
    );
    r.paragraph(
        "Smallest eigenvalue of `𝒥_k = [[½tr(I)·1 − I, h], [hᵀ, m]]` (kg·m² and kg mixed, as in docs/model.md, section Physical consistency); \
         positive ⇔ (67)–(69) hold. OLS only fixes the base combinations; its standard set is the one closest to \
         the nominal robot, with the nominal masses.",
    );
}
