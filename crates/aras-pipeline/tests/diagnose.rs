//! The diagnosis on simulated data with hidden effects (ground truth from
//! the simulator).
//!
//! TRAIN: the designed excitation `fixtures/trajectories/default-excitation.json`
//! (10 s period, [`TRAIN_PERIODS`] periods, period-averaged). VALIDATION:
//! the paper's trajectory (79) at 0.5 Hz and 1.0 Hz (10 periods each,
//! period-averaged). Default sensors (10 mA current noise, 4096-count
//! encoders). Every log is written as CSV + sidecar and read back, as a
//! user's data would arrive. Simulations run once per scenario.
//!
//! Hidden magnitudes (realistic for this robot: its Coulomb levels are
//! 0.076 / 0.289 N·m, viscous 0.034 / 0.009 N·m·s/rad, and the torques reach
//! ≈ 1 N·m):
//!
//! | effect | hidden |
//! |---|---|
//! | `torque_offset` | [0.02, −0.03] N·m |
//! | `coulomb_asymmetry` | [0.02, 0.04] N·m (Fc ± Fca) |
//! | `stribeck_friction` | v_s = 0.2 rad/s, levels [0.06, 0.12] N·m (the reliable limit) |
//! | `passive_joint_viscous` | [0.005, 0.005, 0.005] N·m·s/rad |
//! | `cogging` | 12 cycles/rev, harmonics 1–2: 0.01, 0.004 N·m |
//! | `quadratic_damping` | [0.005, 0.005] N·m·s²/rad² |
//! | `time_delay` | 5 samples (5 ms at 1 kHz) |

use std::path::PathBuf;
use std::sync::OnceLock;

use aras_dyn::sim::{LuGre, SimConfig, simulate, write_log};
use aras_dyn::{Cogging, Effect, Model, Params, Sinusoid, Stribeck, Trajectory};
use aras_excite::FourierTrajectory;
use aras_ident::{BaseParameters, OlsEstimate, ols};
use aras_kin::Workspace;
use aras_log::{ReadOptions, read_log};
use aras_pipeline::diagnose::{Dataset, DiagnoseOptions, Diagnosis, diagnose};
use aras_pipeline::robot::{
    FilterMode, base_parameters, filter, filter_reach, keep_rows, reversal_mask, stack,
};
use aras_signal::{Bandwidth, FilterSpec, PeriodSource, ProcessOptions, process};
use rayon::prelude::*;

/// Periods of the 10 s excitation in TRAIN.
const TRAIN_PERIODS: f64 = 4.0;

fn excitation() -> &'static FourierTrajectory {
    static E: OnceLock<FourierTrajectory> = OnceLock::new();
    E.get_or_init(|| {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/trajectories/default-excitation.json");
        FourierTrajectory::load(&path).unwrap()
    })
}

/// One simulated log with noise `seed`, written, read back and processed.
fn dataset(
    truth: &Params,
    traj: &dyn Trajectory,
    secs: f64,
    delay: usize,
    seed: u64,
    tag: &str,
) -> Dataset {
    dataset_with(&SimConfig::default(), truth, traj, secs, delay, seed, tag)
}

/// [`dataset`] with the other simulator settings of `base`.
fn dataset_with(
    base: &SimConfig,
    truth: &Params,
    traj: &dyn Trajectory,
    secs: f64,
    delay: usize,
    seed: u64,
    tag: &str,
) -> Dataset {
    let cfg = SimConfig {
        duration_s: secs,
        torque_delay_samples: delay,
        seed,
        ..base.clone()
    };
    let log = simulate(truth, traj, &cfg).unwrap();
    let dir = aras_testkit::Scratch::new(&format!("diag-{tag}"));
    let path: PathBuf = dir.join(format!("{tag}.csv"));
    write_log(&path, &log, true).unwrap();
    let raw = read_log(&path, &ReadOptions::default()).unwrap();
    // The engine's figures below are on the paper's processing, the fixed
    // 10 Hz low-pass with rows away from reversals (the tools' default,
    // every row with the data-chosen bandwidth, is diagnosed in
    // `aras-cli`'s tests, which refine the Coulomb widths first).
    let popts = ProcessOptions {
        period: PeriodSource::Seconds(traj.period().unwrap()),
        filter: Bandwidth::Fixed(FilterSpec::default()),
        ..ProcessOptions::default()
    };
    let p = process(
        &raw,
        &popts,
        &aras_kin::task_motion(&truth.geometry().unwrap()),
    )
    .unwrap();
    Dataset::from_processed(tag, &p).unwrap()
}

/// TRAIN (the excitation) and the two validation sets of one scenario.
struct Scenario {
    train: Dataset,
    vals: Vec<Dataset>,
}

fn scenario(truth: &Params, delay: usize, seed: u64, tag: &str) -> Scenario {
    scenario_with(&SimConfig::default(), truth, delay, seed, tag)
}

/// [`scenario`] with the other simulator settings of `base`.
fn scenario_with(base: &SimConfig, truth: &Params, delay: usize, seed: u64, tag: &str) -> Scenario {
    let period = excitation().period();
    let train = dataset_with(
        base,
        truth,
        excitation(),
        TRAIN_PERIODS * period,
        delay,
        seed,
        &format!("{tag}-train"),
    );
    let vals: Vec<Dataset> = [0.5, 1.0]
        .iter()
        .map(|&f| {
            dataset_with(
                base,
                truth,
                &Sinusoid::paper_79(f).unwrap(),
                10.0 / f,
                delay,
                seed,
                &format!("{tag}-val{f}"),
            )
        })
        .collect();
    Scenario { train, vals }
}

/// The diagnosis from the paper's model; `consistent`: with the final SDP
/// re-fit (CAD reference).
fn diagnose_on(s: &Scenario, consistent: bool) -> Diagnosis {
    let cad = Params::aras_diamond();
    let model = Model::paper(cad.gravity).unwrap();
    let opts = DiagnoseOptions {
        reference: consistent.then(|| cad.clone()),
        ..DiagnoseOptions::default()
    };
    diagnose(&model, &cad.geometry().unwrap(), &s.train, &s.vals, &opts).unwrap()
}

/// The acceptance setup: noise seed 1 (the simulator's default), with the
/// consistent re-fit.
fn run(truth: &Params, delay: usize, tag: &str) -> Diagnosis {
    let d = diagnose_on(&scenario(truth, delay, 1, tag), true);
    show(tag, &d);
    d
}

fn show(tag: &str, d: &Diagnosis) {
    eprintln!("== {tag}: {}", d.conclusion);
    for r in &d.fitness {
        eprintln!("  step {} {:?}  {}", r.step, r.fitness, r.model);
    }
    for (k, round) in d.rounds.iter().enumerate() {
        eprintln!(" round {k}");
        for c in round.iter().take(4) {
            eprintln!(
                "   {:40} k={} drop={:.3}% neff={:.0} F={:.2} p={:.2e} gain={:?} sets={:?} sig={}",
                c.label,
                c.added_parameters,
                c.rss_drop_percent,
                c.n_eff,
                c.f,
                c.p_value,
                c.gain,
                c.gain_per_set,
                c.significant
            );
        }
    }
    for s in &d.steps {
        eprintln!(
            "  added {} aliases {:?} {:?}",
            s.label, s.aliases, s.parameters
        );
        if let Some(r) = &s.refinement {
            eprintln!(
                "  refined {} = {:.4} ± {:.4} (grid {})",
                r.name, r.value, r.std_dev, r.grid_value
            );
        }
    }
    for a in d.after.iter() {
        for w in &a.whiteness {
            eprintln!(
                "  after {} white j{} p={:.3} rms={:.5}",
                a.dataset, w.joint, w.p_value, w.rms
            );
        }
        for f in a.findings.iter().filter(|f| f.systematic).take(3) {
            eprintln!("  {}", f.text);
        }
    }
    eprintln!("  {:.2} s", d.elapsed_s);
}

/// Total validation fitness gain of the first step (mean over joints and
/// sets, percentage points).
fn first_gain(d: &Diagnosis) -> f64 {
    let m = |k: usize| {
        let f = &d.fitness[k].fitness_filtered;
        f.iter().map(|x| 0.5 * (x[0] + x[1])).sum::<f64>() / f.len() as f64
    };
    m(1) - m(0)
}

fn hidden(id: &str) -> (Params, usize) {
    let mut p = Params::aras_diamond();
    let mut delay = 0;
    let x = &mut p.extra;
    match id {
        "torque_offset" => x.torque_offset = Some([0.02, -0.03]),
        "coulomb_asymmetry" => x.coulomb_asymmetry = Some([0.02, 0.04]),
        "stribeck_friction" => {
            x.stribeck_friction = Some(Stribeck {
                v_s: 0.2,
                level: [0.06, 0.12],
            })
        }
        "passive_joint_viscous" => x.passive_joint_viscous = Some([0.005; 3]),
        "cogging" => {
            x.cogging = Some(Cogging {
                cycles_per_rev: 12.0,
                sin: [vec![0.01, 0.004], vec![0.0, 0.0]],
                cos: [vec![0.0, 0.0], vec![0.01, 0.004]],
            })
        }
        "quadratic_damping" => x.quadratic_damping = Some([0.005, 0.005]),
        "time_delay" => delay = 5,
        _ => panic!("unknown effect {id}"),
    }
    (p, delay)
}

/// The hidden effect is named first (for `coulomb_asymmetry`, which equals
/// `torque_offset` on data that never rest, as the alias of the name
/// given) and the validation fitness improves by at least `gain` points.
fn named_first(id: &str, gain: f64) {
    let (p, delay) = hidden(id);
    check_named_first(id, gain, &run(&p, delay, id));
}

fn check_named_first(id: &str, gain: f64, d: &Diagnosis) {
    let s = d
        .steps
        .first()
        .unwrap_or_else(|| panic!("{id}: nothing found"));
    assert!(
        names(s, id),
        "{id}: first step is {} (aliases {:?})",
        s.label,
        s.aliases
    );
    let g = first_gain(d);
    assert!(g >= gain, "{id}: gain {g:.3} < {gain}");
}

/// True if step `s` names `id`, directly or as an alias (the same
/// hypothesis on these data).
fn names(s: &aras_pipeline::diagnose::Step, id: &str) -> bool {
    s.id == id || s.aliases.iter().any(|a| a == id)
}

/// The `torque_offset` scenario (seed 1) and its diagnosis, shared by the
/// acceptance test and the σ test.
fn offset_case() -> &'static (Scenario, Diagnosis) {
    static C: OnceLock<(Scenario, Diagnosis)> = OnceLock::new();
    C.get_or_init(|| {
        let (p, delay) = hidden("torque_offset");
        let s = scenario(&p, delay, 1, "torque_offset");
        let d = diagnose_on(&s, true);
        show("torque_offset", &d);
        (s, d)
    })
}

#[test]
fn finds_torque_offset() {
    check_named_first("torque_offset", 0.3, &offset_case().1);
}

#[test]
fn finds_coulomb_asymmetry() {
    named_first("coulomb_asymmetry", 0.5);
}

#[test]
fn finds_stribeck_friction() {
    named_first("stribeck_friction", 0.2);
}

#[test]
fn finds_passive_joint_viscous() {
    named_first("passive_joint_viscous", 10.0);
}

#[test]
fn finds_cogging() {
    named_first("cogging", 10.0);
}

/// A pure 12-cycle cogging (first harmonic only, 0.01 N·m): 6 cycles of
/// order 2 hold the same 12-cycle harmonic and fit it equally well, but the
/// name is the fundamental present, 12 cycles of order 1 (half the
/// parameters), with the hidden amplitudes within 10 %.
#[test]
fn names_the_fundamental_of_a_pure_cogging() {
    let mut p = Params::aras_diamond();
    p.extra.cogging = Some(Cogging {
        cycles_per_rev: 12.0,
        sin: [vec![0.01], vec![0.0]],
        cos: [vec![0.0], vec![0.01]],
    });
    let d = run(&p, 0, "cogging_order_1");
    let s = d.steps.first().expect("nothing found");
    assert_eq!(
        s.label, "cogging(12 cycles/rev, order 1)",
        "{}",
        d.conclusion
    );
    for (name, want) in [("Cs1_1", 0.01), ("Cc2_1", 0.01)] {
        let q = s.parameters.iter().find(|q| q.name == name).expect(name);
        assert!((q.value - want).abs() <= 0.1 * want, "{name}: {}", q.value);
    }
}

#[test]
fn finds_quadratic_damping() {
    named_first("quadratic_damping", 2.0);
}

#[test]
fn finds_time_delay() {
    named_first("time_delay", 1.0);
}

/// A delay between the grid's samples, 3.4 samples (3 whole and 0.4
/// interpolated, `SimConfig::torque_delay_fraction`): named first with the
/// right sign on noise seeds 1–5, and refined (zoomed grid search over a
/// linearly interpolated torque shift) to within ±0.5 samples. What the
/// refinement measures is the lag between the logged torque and the
/// processed motion: the simulator holds each torque sample for one period
/// (zero-order hold) and its sidecar says so, so the processing already
/// evaluates the motion at the hold's midpoint and the lag left is the
/// delay itself, 3.4 samples; the refined value must hold it within 3σ of
/// its own uncertainty (or 0.1 samples).
#[test]
fn refines_a_fractional_time_delay() {
    let base = SimConfig {
        torque_delay_fraction: 0.4,
        ..SimConfig::default()
    };
    let ds: Vec<Diagnosis> = SEEDS
        .par_iter()
        .map(|&seed| {
            let tag = format!("delay34-{seed}");
            let d = diagnose_on(
                &scenario_with(&base, &Params::aras_diamond(), 3, seed, &tag),
                false,
            );
            show(&format!("delay 3.4, seed {seed}"), &d);
            d
        })
        .collect();
    for (d, seed) in ds.iter().zip(SEEDS) {
        let step = d.steps.first().expect("nothing found");
        assert_eq!(step.id, "time_delay", "{}", step.label);
        let r = step.refinement.as_ref().expect("no refinement");
        eprintln!(
            "seed {seed}: refined delay {:.3} ± {:.3} (grid {})",
            r.value, r.std_dev, r.grid_value
        );
        assert!(r.grid_value > 0.0, "{}", r.grid_value);
        assert!((r.value - 3.4).abs() <= 0.5, "{}", r.value);
        assert!(
            (r.value - 3.4).abs() <= (3.0 * r.std_dev).max(0.1),
            "{} ± {}",
            r.value,
            r.std_dev
        );
    }
}

/// Noise seeds of the multi-seed cases: five, so that a result is not one
/// noise draw's luck.
const SEEDS: [u64; 5] = [1, 2, 3, 4, 5];

/// The diagnosis of `truth` on every seed of [`SEEDS`] (in parallel), with
/// the consistent re-fit.
fn on_seeds(truth: &Params, tag: &str) -> Vec<Diagnosis> {
    SEEDS
        .par_iter()
        .map(|&seed| {
            let d = diagnose_on(&scenario(truth, 0, seed, &format!("{tag}-{seed}")), true);
            show(&format!("{tag}, seed {seed}"), &d);
            d
        })
        .collect()
}

#[test]
fn control_adds_nothing_and_says_noise_like_on_five_seeds() {
    for (d, seed) in on_seeds(&Params::aras_diamond(), "control")
        .iter()
        .zip(SEEDS)
    {
        assert!(d.steps.is_empty(), "seed {seed}: {}", d.conclusion);
        assert!(d.noise_like, "seed {seed}: {}", d.conclusion);
        assert!(
            d.conclusion.contains("noise-like"),
            "seed {seed}: {}",
            d.conclusion
        );
    }
}

#[test]
fn two_hidden_effects_are_both_found_and_nothing_else() {
    let (mut p, _) = hidden("cogging");
    p.extra.quadratic_damping = Some([0.005, 0.005]);
    let d = run(&p, 0, "two");
    let mut ids: Vec<&str> = d.steps.iter().map(|s| s.id.as_str()).collect();
    ids.sort();
    assert_eq!(ids, ["cogging", "quadratic_damping"], "{}", d.conclusion);
    assert!(d.noise_like, "{}", d.conclusion);
}

/// Both effects named, nothing else, on every seed; the verdict on the
/// remaining validation residual is printed (`docs/diagnose.md`,
/// "Acceptance": whiteness on the refitted model).
#[test]
fn two_hidden_effects_are_both_named_and_nothing_else_on_five_seeds() {
    let (mut p, _) = hidden("cogging");
    p.extra.quadratic_damping = Some([0.005, 0.005]);
    let ds = on_seeds(&p, "two");
    for (d, seed) in ds.iter().zip(SEEDS) {
        let mut ids: Vec<&str> = d.steps.iter().map(|s| s.id.as_str()).collect();
        ids.sort();
        assert_eq!(
            ids,
            ["cogging", "quadratic_damping"],
            "seed {seed}: {}",
            d.conclusion
        );
    }
    let white = ds.iter().filter(|d| d.noise_like).count();
    eprintln!(
        "validation residual noise-like on {white} of {} seeds",
        ds.len()
    );
}

/// An effect the library cannot describe: quadratic damping hidden, every
/// other candidate offered. Whatever is added, the verdict on what is left
/// is "not noise-like" on every seed: whiteness is judged on the final model
/// refitted on each validation set (which absorbs the TRAIN estimate's
/// error), the bins beyond 4 standard errors on the TRAIN fit (which a
/// refit would absorb too).
#[test]
fn an_effect_outside_the_library_is_not_called_noise_like_on_five_seeds() {
    let (p, _) = hidden("quadratic_damping");
    let cad = Params::aras_diamond();
    let model = Model::paper(cad.gravity).unwrap();
    let mut opts = DiagnoseOptions {
        reference: Some(cad.clone()),
        ..DiagnoseOptions::default()
    };
    opts.grid.ids.retain(|id| id != "quadratic_damping");
    let ds: Vec<Diagnosis> = SEEDS
        .par_iter()
        .map(|&seed| {
            let s = scenario(&p, 0, seed, &format!("outside-{seed}"));
            let d = diagnose(&model, &cad.geometry().unwrap(), &s.train, &s.vals, &opts).unwrap();
            show(&format!("outside, seed {seed}"), &d);
            d
        })
        .collect();
    for (d, seed) in ds.iter().zip(SEEDS) {
        assert!(!d.noise_like, "seed {seed}: {}", d.conclusion);
        assert!(
            d.conclusion.contains("outside the candidate library"),
            "seed {seed}: {}",
            d.conclusion
        );
        // Located in frequency: quadratic damping τ = Fq θ̇|θ̇| lives at the
        // motion's low harmonics, so a band there holds most of the
        // residual's power, far above the filtered noise's flat density.
        let (spectrum, band) = d
            .after
            .iter()
            .flat_map(|a| a.spectra.iter())
            .filter_map(|s| Some((s, s.finding.as_ref()?)))
            .max_by(|a, b| a.1.z.total_cmp(&b.1.z))
            .unwrap_or_else(|| panic!("seed {seed}: no frequency band located"));
        assert!(
            d.conclusion.contains(&band.text),
            "seed {seed}: {}",
            d.conclusion
        );
        assert!(
            band.text.contains("follows the motion"),
            "seed {seed}: {}",
            band.text
        );
        let top = spectrum
            .bands
            .iter()
            .max_by(|a, b| a.residual_share.total_cmp(&b.residual_share))
            .unwrap();
        assert!(top.hi_hz <= 2.0, "seed {seed}: {top:?}");
    }
}

/// The in-memory identification of `model` on TRAIN, as `identify` does
/// it: stacked regressor, parallel filter, reversal exclusion (0.2 rad/s,
/// reach 1e-3), base-parameter OLS, σ corrected for the filter's noise gain.
fn identify_in_memory(model: &Model, train: &Dataset) -> (BaseParameters, OlsEstimate) {
    let geometry = Params::aras_diamond().geometry().unwrap();
    let sos = train.filter.as_ref().unwrap();
    let mut st = stack(model, &geometry, train.samples().unwrap()).unwrap();
    filter(&mut st, sos, FilterMode::Parallel, train.periodic).unwrap();
    let guard = filter_reach(sos, train.len(), train.periodic, 1e-3).unwrap();
    let keep = reversal_mask(
        &train.samples().unwrap().theta_dot,
        0.2,
        guard,
        train.periodic,
    )
    .unwrap();
    let st = keep_rows(&st, &keep).unwrap();
    let base = base_parameters(model, &geometry, &Workspace::paper(), 600).unwrap();
    let wb = base.base_regressor(st.w.as_ref()).unwrap();
    let est = ols(wb.as_ref(), &st.t, &base.base_names())
        .unwrap()
        .with_filtered_noise(train.noise_gain().unwrap())
        .unwrap();
    (base, est)
}

/// The σ `diagnose` reports for an added effect's parameters is the
/// in-memory identification's filter-corrected σ of the same model on the
/// same data (and not the white-noise σ, √(1/g) ≈ 7.4× smaller).
#[test]
fn added_effect_sigma_equals_in_memory_corrected_sigma() {
    let (s, d) = offset_case();
    let step = &d.steps[0];
    assert_eq!(step.id, "torque_offset");
    let cad = Params::aras_diamond();
    let model = Model::paper(cad.gravity)
        .unwrap()
        .with_effect(Effect::TorqueOffset)
        .unwrap();
    let (base, est) = identify_in_memory(&model, &s.train);
    let g = s.train.noise_gain().unwrap();
    // g = Σh² of the 10 Hz 4th-order zero-phase filter at 1 kHz ≈ 1/55;
    // the F-test's `filter_dof / N` is the same quantity by Parseval,
    // integrated in frequency (4000 midpoints: 1e-3 relative is ample).
    let dof = s.train.filter_dof() / s.train.len() as f64;
    assert!((dof - g).abs() <= 1e-3 * g, "filter_dof/N {dof} vs Σh² {g}");
    assert!(g > 0.01 && g < 0.03, "{g}");
    assert_eq!(step.parameters.len(), 2);
    for p in &step.parameters {
        let k = (0..base.n_base())
            .find(|&k| base.expression(k).ends_with(&format!("= {}", p.name)))
            .unwrap_or_else(|| panic!("{} not in the in-memory base", p.name));
        eprintln!(
            "{}: {:.6} ± {:.2e} (in memory {:.6} ± {:.2e})",
            p.name, p.value, p.std_dev, est.estimate[k], est.std_dev[k]
        );
        // Same rows and columns up to column order: the QR's round-off
        // (κ ≈ 1e4, ε ≈ 1e-16) stays far below 1e-8 relative.
        assert!(
            (p.std_dev - est.std_dev[k]).abs() <= 1e-8 * est.std_dev[k],
            "{}: σ {} vs {}",
            p.name,
            p.std_dev,
            est.std_dev[k]
        );
        assert!((p.value - est.estimate[k]).abs() <= 1e-8 * est.std_dev[k]);
    }
}

/// The fitness on every validation row and on the fitted rows that the
/// diagnosis reports with the rows left out near reversals
/// (`ResidualAnalysis::left_out`) equals the in-memory prediction of the
/// final model (paper + `torque_offset`, identified on TRAIN) on the same
/// validation set: its stacked, parallel-filtered regressor times the
/// in-memory estimate, all rows, and the rows of the validation reversal
/// mask (0.2 rad/s, reach 0.5).
#[test]
fn all_row_fitness_equals_the_in_memory_prediction() {
    let (s, d) = offset_case();
    let cad = Params::aras_diamond();
    let model = Model::paper(cad.gravity)
        .unwrap()
        .with_effect(Effect::TorqueOffset)
        .unwrap();
    let (base, est) = identify_in_memory(&model, &s.train);
    let geometry = cad.geometry().unwrap();
    for (v, a) in s.vals.iter().zip(&d.after) {
        let sos = v.filter.as_ref().unwrap();
        let mut st = stack(&model, &geometry, v.samples().unwrap()).unwrap();
        filter(&mut st, sos, FilterMode::Parallel, v.periodic).unwrap();
        let wb = base.base_regressor(st.w.as_ref()).unwrap();
        let pred: Vec<f64> = (0..wb.nrows())
            .map(|r| (0..wb.ncols()).map(|c| wb[(r, c)] * est.estimate[c]).sum())
            .collect();
        let guard = filter_reach(sos, v.len(), v.periodic, 0.5).unwrap();
        let keep = reversal_mask(&v.samples().unwrap().theta_dot, 0.2, guard, v.periodic).unwrap();
        let n = v.len();
        assert_eq!(a.left_out.len(), 2);
        for (g, l) in a.left_out.iter().enumerate() {
            let rows = g * n..(g + 1) * n;
            let all =
                aras_ident::validate::fitness(&st.t[rows.clone()], &pred[rows.clone()]).unwrap();
            let pick = |x: &[f64]| -> Vec<f64> {
                rows.clone().filter(|&r| keep[r]).map(|r| x[r]).collect()
            };
            let fitted = aras_ident::validate::fitness(&pick(&st.t), &pick(&pred)).unwrap();
            let left = rows.clone().filter(|&r| !keep[r]).count();
            eprintln!(
                "{} joint {}: all rows {:.4} % (in memory {all:.4}), fitted {:.4} % \
                 (in memory {fitted:.4}), left out {} rows ({left})",
                v.name,
                l.joint,
                l.fitness_filtered_all_rows,
                l.fitness_filtered_fitted_rows,
                l.rows
            );
            assert_eq!(l.rows, left, "{} joint {}", v.name, l.joint);
            // Same model, rows and filter; the estimates agree to 1e-8
            // relative (`added_effect_sigma_equals_in_memory_corrected_sigma`),
            // so the fitness in percent agrees far below 1e-5 points.
            assert!(
                (l.fitness_filtered_all_rows - all).abs() < 1e-5,
                "{} vs {all}",
                l.fitness_filtered_all_rows
            );
            assert!(
                (l.fitness_filtered_fitted_rows - fitted).abs() < 1e-5,
                "{} vs {fitted}",
                l.fitness_filtered_fitted_rows
            );
            assert!(l.fitness_filtered_all_rows < l.fitness_filtered_fitted_rows);
        }
    }
}

/// Hidden LuGre friction (`Fs = 1.3 Fc`, `v_s = 0.03 rad/s`, presliding
/// length `Fc/σ0` = 5e-4 rad), simulated as a bristle state and not as a
/// column: every deviation from the sign law lives below the exclusion's
/// 0.2 rad/s. No candidate may be named for it, and the conclusion must
/// locate the misfit on the rows left out near reversals, at low speed,
/// with the all-row fitness below the fitted rows'.
#[test]
fn lugre_friction_is_located_at_reversals_and_nothing_is_named() {
    let fc = Params::aras_diamond().friction.coulomb;
    let base = SimConfig {
        substeps: 4,
        lugre: Some(LuGre {
            static_level: [1.3 * fc[0], 1.3 * fc[1]],
            stribeck_velocity: [0.03; 2],
            stiffness: [fc[0] / 5e-4, fc[1] / 5e-4],
            damping: [0.2, 0.4],
        }),
        ..SimConfig::default()
    };
    let s = scenario_with(&base, &Params::aras_diamond(), 0, 1, "lugre");
    let d = diagnose_on(&s, false);
    show("lugre", &d);
    assert!(d.steps.is_empty(), "{}", d.conclusion);
    assert!(
        d.conclusion.contains("Near velocity reversals"),
        "{}",
        d.conclusion
    );
    let worst = d
        .after
        .iter()
        .flat_map(|a| a.left_out.iter())
        .flat_map(|l| l.findings.iter())
        .max_by(|a, b| a.z.abs().total_cmp(&b.z.abs()))
        .expect("no finding on the rows left out");
    eprintln!("worst: {}", worst.text);
    let bin = d
        .after
        .iter()
        .flat_map(|a| a.left_out.iter())
        .flat_map(|l| l.profile.bins.iter())
        .find(|b| b.z() == worst.z)
        .unwrap();
    assert!(bin.lo.abs().min(bin.hi.abs()) < 0.2, "{bin:?}");
    let parts: Vec<_> = d.after.iter().flat_map(|a| a.left_out.iter()).collect();
    let gap: f64 = parts
        .iter()
        .map(|l| l.fitness_filtered_fitted_rows - l.fitness_filtered_all_rows)
        .sum::<f64>()
        / parts.len() as f64;
    eprintln!("fitted − all-row fitness: {gap:.2} points");
    assert!(gap > 1.0, "{gap}");
}

/// Hidden torque offset and quadratic damping, TRAIN only: per noise seed
/// and effect parameter (`tau0_1`, `tau0_2`, `Fq1`, `Fq2`), its name, the
/// error, the reported (filter-corrected) σ and the white-noise σ.
fn added_effect_errors(seeds: u64) -> Vec<(String, f64, f64, f64)> {
    let mut truth = Params::aras_diamond();
    truth.extra.torque_offset = Some([0.02, -0.03]);
    truth.extra.quadratic_damping = Some([0.005, 0.005]);
    let model = truth.model().unwrap();
    let beta = truth.standard_vector(&model).unwrap();
    let period = excitation().period();
    (1..=seeds)
        .into_par_iter()
        .flat_map_iter(|seed| {
            let train = dataset(
                &truth,
                excitation(),
                TRAIN_PERIODS * period,
                0,
                seed,
                &format!("honest-{seed}"),
            );
            let (base, est) = identify_in_memory(&model, &train);
            let truth_b = base.to_base(beta.as_slice()).unwrap();
            let std_names = base.standard_names();
            let g = train.noise_gain().unwrap();
            base.independent()
                .iter()
                .enumerate()
                .filter(|(_, c)| {
                    ["tau0_1", "tau0_2", "Fq1", "Fq2"].contains(&std_names[**c].as_str())
                })
                .map(|(k, c)| {
                    let e = est.estimate[k] - truth_b[k];
                    let s = est.std_dev[k];
                    eprintln!(
                        "seed {seed} {}: error {e:.2e}, σ {s:.2e}, z {:.2}",
                        std_names[*c],
                        e / s
                    );
                    (std_names[*c].clone(), e, s, s * g.sqrt())
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let x: Vec<f64> = v.collect();
    (x.iter().map(|a| a * a).sum::<f64>() / x.len() as f64).sqrt()
}

/// Honest σ of the added effects' parameters over 32 noise seeds of
/// [`added_effect_errors`] (≈ 10 s on 2 cores): per parameter the spread of
/// the errors over the mean σ and the mean error in σ. Measured: spread
/// 0.92–1.25 σ, mean error −0.90…+0.49 σ (a deterministic bias: the base
/// model's misfit near reversals), RMS of all ratios 1.34; the white-noise
/// σ would give ≈ 12. Asserted: every spread within [0.7, 1.4] (the
/// standard error of a 32-sample spread is 13 %: three of them), the RMS
/// below 1.6, the white-noise RMS above four times it.
#[test]
fn added_effect_sigma_over_32_noise_seeds() {
    let z = added_effect_errors(32);
    for name in ["tau0_1", "tau0_2", "Fq1", "Fq2"] {
        let v: Vec<&(String, f64, f64, f64)> = z.iter().filter(|x| x.0 == name).collect();
        let m = v.len() as f64;
        let mean = v.iter().map(|x| x.1).sum::<f64>() / m;
        let sd = (v.iter().map(|x| (x.1 - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt();
        let sigma = v.iter().map(|x| x.2).sum::<f64>() / m;
        eprintln!(
            "{name}: spread {:.2} σ, mean error {:+.2} σ",
            sd / sigma,
            mean / sigma
        );
        assert!(
            (0.7..=1.4).contains(&(sd / sigma)),
            "{name}: {}",
            sd / sigma
        );
    }
    let all = rms(z.iter().map(|x| x.1 / x.2));
    let white = rms(z.iter().map(|x| x.1 / x.3));
    eprintln!("RMS error/σ over all: {all:.2} (white-noise σ: {white:.2})");
    assert!(all < 1.6, "{all}");
    assert!(white > 4.0 * all, "{white}");
}

/// Timing: a 160 s TRAIN log (16 periods of the excitation) and
/// two validation logs, all 7 candidates, with one hidden effect so that
/// two rounds run. Ignored: the simulation itself takes a few seconds.
#[test]
#[ignore]
fn timing_160_s() {
    let (p, _) = hidden("quadratic_damping");
    let period = excitation().period();
    let train = dataset(&p, excitation(), 16.0 * period, 0, 1, "timing-train");
    let vals: Vec<Dataset> = [0.5, 1.0]
        .iter()
        .map(|&f| {
            let t = Sinusoid::paper_79(f).unwrap();
            dataset(&p, &t, 10.0 / f, 0, 1, &format!("timing-val{f}"))
        })
        .collect();
    let cad = Params::aras_diamond();
    let model = Model::paper(cad.gravity).unwrap();
    let opts = DiagnoseOptions {
        reference: Some(cad.clone()),
        ..DiagnoseOptions::default()
    };
    let t0 = std::time::Instant::now();
    let d = diagnose(&model, &cad.geometry().unwrap(), &train, &vals, &opts).unwrap();
    let s = t0.elapsed().as_secs_f64();
    eprintln!(
        "160 s log: {s:.2} s, {} rounds, {} candidate settings per round",
        d.rounds.len(),
        d.rounds[0].len()
    );
    assert_eq!(d.steps[0].id, "quadratic_damping");
    assert!(s <= 10.0, "{s:.2} s");
}

/// Noise seeds of the robustness study (seed 1 is the acceptance tests').
const ROBUST_SEEDS: [u64; 5] = [1, 2, 3, 4, 5];

/// Magnitude grid per effect: fractions of the acceptance magnitude
/// ([`hidden`]), for `time_delay` the delay in samples. Chosen to bracket
/// each detection limit (a first scan of one seed: offset and Stribeck
/// between 50 % and 100 %, quadratic damping between 35 % and 50 %;
/// passive viscous and cogging gained ≈ 24 points at 100 %; with three
/// seeds Stribeck needed 2×, hence 2.8).
fn robust_grid(id: &str) -> &'static [f64] {
    match id {
        "torque_offset" | "coulomb_asymmetry" => &[0.25, 0.5, 0.7, 1.0, 1.4, 2.0],
        // Half the other scales: the acceptance level is twice the
        // original [0.03, 0.06] N·m, the grid stays in the same N·m.
        "stribeck_friction" => &[0.125, 0.25, 0.35, 0.5, 0.7, 1.0, 1.4],
        "quadratic_damping" => &[0.2, 0.35, 0.5, 0.7, 1.0],
        "passive_joint_viscous" | "cogging" => &[0.01, 0.02, 0.05, 0.1, 0.2, 0.5],
        "time_delay" => &[1.0, 2.0, 3.0, 5.0],
        _ => panic!("unknown effect {id}"),
    }
}

/// The truth with effect `id` at `scale` × its acceptance magnitude (for
/// `time_delay`: `scale` samples).
fn hidden_scaled(id: &str, scale: f64) -> (Params, usize) {
    if id == "time_delay" {
        return (Params::aras_diamond(), scale as usize);
    }
    let (mut p, delay) = hidden(id);
    let x = &mut p.extra;
    let mul = |v: &mut [f64]| v.iter_mut().for_each(|a| *a *= scale);
    if let Some(v) = &mut x.torque_offset {
        mul(v);
    }
    if let Some(v) = &mut x.coulomb_asymmetry {
        mul(v);
    }
    if let Some(s) = &mut x.stribeck_friction {
        mul(&mut s.level);
    }
    if let Some(v) = &mut x.passive_joint_viscous {
        mul(v);
    }
    if let Some(c) = &mut x.cogging {
        c.sin
            .iter_mut()
            .chain(c.cos.iter_mut())
            .for_each(|v| mul(v));
    }
    if let Some(v) = &mut x.quadratic_damping {
        mul(v);
    }
    (p, delay)
}

/// Robustness: every effect at a grid of magnitudes around its
/// detection limit, 5 noise seeds each, plus the control per seed; the
/// paper's model as start, the acceptance setup otherwise (no SDP re-fit:
/// it does not change what is named). Prints one `ROBUST {json}` line per
/// case and a `ROBUST_SUMMARY {json}` with, per effect, the smallest
/// magnitude of the grid from which on the effect is named first for every
/// seed, and the false discoveries (a step naming another effect).
/// `coulomb_asymmetry` counts as named when it is the name or an alias of
/// the first step (it is `torque_offset` on rows where the joint moves).
/// Ignored (≈ 8 min on 2 cores, 210 cases); results in docs/diagnose.md.
#[test]
#[ignore]
fn robustness_magnitudes() {
    let mut cases: Vec<(&str, f64, u64)> = Vec::new();
    for seed in ROBUST_SEEDS {
        cases.push(("control", 0.0, seed));
        for id in aras_pipeline::diagnose::CANDIDATE_IDS {
            for &scale in robust_grid(id) {
                cases.push((id, scale, seed));
            }
        }
    }
    let t0 = std::time::Instant::now();
    let records: Vec<serde_json::Value> = cases
        .par_iter()
        .map(|&(id, scale, seed)| {
            let (p, delay) = if id == "control" {
                (Params::aras_diamond(), 0)
            } else {
                hidden_scaled(id, scale)
            };
            let tag = format!("robust-{id}-{scale}-{seed}");
            let d = diagnose_on(&scenario(&p, delay, seed, &tag), false);
            let first = d.steps.first();
            let detected = id != "control" && first.is_some_and(|s| names(s, id));
            let wrong: Vec<String> = d
                .steps
                .iter()
                .filter(|s| !names(s, id))
                .map(|s| s.label.clone())
                .collect();
            // Round 0's evidence for the hidden effect: its best setting
            // (lowest p; the true delay for `time_delay`).
            let round0 = &d.rounds[0];
            let level = 0.01 / round0.len() as f64;
            let own = round0
                .iter()
                .filter(|c| {
                    c.candidate.id() == id
                        && (id != "time_delay"
                            || c.label == format!("time_delay({:+} samples)", scale as i64))
                })
                .min_by(|a, b| a.p_value.total_cmp(&b.p_value));
            let z_max = first
                .filter(|_| detected)
                .map(|s| {
                    s.parameters
                        .iter()
                        .filter(|p| p.std_dev > 0.0)
                        .map(|p| (p.value / p.std_dev).abs())
                        .fold(0.0, f64::max)
                })
                .unwrap_or(0.0);
            let rec = serde_json::json!({
                "effect": id,
                "scale": scale,
                "seed": seed,
                "first": first.map_or("none".to_owned(), |s| s.label.clone()),
                "detected": detected,
                "false_discoveries": wrong,
                "p": own.map(|c| c.p_value),
                "p_ok": own.map(|c| c.p_value < level),
                "f": own.map(|c| c.f),
                "gain_per_set": own.map(|c| c.gain_per_set.clone()),
                "rss_drop_percent": own.map(|c| c.rss_drop_percent),
                "max_abs_z_added": z_max,
                "fitness_gain": if d.steps.is_empty() { 0.0 } else { first_gain(&d) },
            });
            eprintln!("ROBUST {rec}");
            rec
        })
        .collect();
    let mut summary = Vec::new();
    for id in aras_pipeline::diagnose::CANDIDATE_IDS
        .iter()
        .copied()
        .chain(["control"])
    {
        let of: Vec<&serde_json::Value> = records.iter().filter(|r| r["effect"] == id).collect();
        let grid: Vec<f64> = if id == "control" {
            vec![0.0]
        } else {
            robust_grid(id).to_vec()
        };
        let all_seeds = |s: f64| {
            of.iter()
                .filter(|r| r["scale"].as_f64() == Some(s))
                .all(|r| r["detected"] == true)
        };
        // Smallest grid magnitude from which on every larger one is named
        // first for every seed.
        let mut reliable = None;
        for &s in grid.iter().rev() {
            if all_seeds(s) {
                reliable = Some(s);
            } else {
                break;
            }
        }
        let detected_per_scale: Vec<serde_json::Value> = grid
            .iter()
            .map(|&s| {
                let n = of
                    .iter()
                    .filter(|r| r["scale"].as_f64() == Some(s) && r["detected"] == true)
                    .count();
                serde_json::json!([s, n])
            })
            .collect();
        let false_disc: Vec<serde_json::Value> = of
            .iter()
            .filter(|r| {
                r["false_discoveries"]
                    .as_array()
                    .is_some_and(|a| !a.is_empty())
            })
            .map(|r| {
                serde_json::json!({"scale": r["scale"], "seed": r["seed"],
                    "named": r["false_discoveries"]})
            })
            .collect();
        summary.push(serde_json::json!({
            "effect": id,
            "seeds": ROBUST_SEEDS.len(),
            "smallest_reliable_scale": reliable,
            "detected_seeds_per_scale": detected_per_scale,
            "false_discoveries": false_disc,
        }));
    }
    eprintln!(
        "ROBUST_SUMMARY {}",
        serde_json::Value::Array(summary.clone())
    );
    eprintln!(
        "{} cases in {:.0} s",
        records.len(),
        t0.elapsed().as_secs_f64()
    );
    // The grid brackets every detection limit (the largest magnitude is
    // named for every seed, the smallest missed by at least one), and no
    // case names a wrong effect.
    for e in &summary {
        let per: Vec<(f64, u64)> = e["detected_seeds_per_scale"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| (x[0].as_f64().unwrap(), x[1].as_u64().unwrap()))
            .collect();
        let n = ROBUST_SEEDS.len() as u64;
        if e["effect"] != "control" {
            assert_eq!(per.last().unwrap().1, n, "{e}: top of the grid missed");
            assert!(per[0].1 < n, "{e}: the grid does not reach below the limit");
        }
        assert!(
            e["false_discoveries"].as_array().unwrap().is_empty(),
            "{e}: false discovery"
        );
    }
}

/// Cogging hidden off the grid (14 cycles per revolution, between the
/// grid's 12 and 16), with the amplitudes of the on-grid case: named first,
/// and the refinement of `cycles_per_rev` — the same search as for `v_s` —
/// moves it from the grid value to the truth within 3 of its reported σ and
/// within 2 % (a fifth of the grid's relative step there). The refitted
/// first-harmonic amplitudes are within 10 % of the hidden 0.01 N·m.
#[test]
fn refines_cogging_cycles_off_the_grid() {
    let mut p = Params::aras_diamond();
    p.extra.cogging = Some(Cogging {
        cycles_per_rev: 14.0,
        sin: [vec![0.01, 0.004], vec![0.0, 0.0]],
        cos: [vec![0.0, 0.0], vec![0.01, 0.004]],
    });
    for (d, seed) in on_seeds(&p, "cogging_off_grid").iter().zip(SEEDS) {
        let s = d.steps.first().expect("nothing found");
        assert_eq!(s.id, "cogging", "seed {seed}: {}", s.label);
        let r = s.refinement.as_ref().expect("no refinement");
        eprintln!("seed {seed}: refinement {r:?}");
        assert_eq!(r.name, "cycles_per_rev");
        assert_ne!(r.grid_value, 14.0, "the truth is not on the grid");
        assert!(r.std_dev > 0.0 && r.std_dev.is_finite(), "σ {}", r.std_dev);
        let err = (r.value - 14.0).abs();
        assert!(
            err <= 3.0 * r.std_dev && err <= 0.02 * 14.0,
            "seed {seed}: cycles {} ± {}",
            r.value,
            r.std_dev
        );
        for (name, want) in [("Cs1_1", 0.01), ("Cc2_1", 0.01)] {
            let q = r.parameters.iter().find(|q| q.name == name).expect(name);
            assert!(
                (q.value - want).abs() <= 0.1 * want,
                "seed {seed}: {name}: {}",
                q.value
            );
        }
    }
}

/// Stribeck friction hidden off the grid (v_s = 0.28 rad/s, between the
/// grid's 0.2 and 0.4): named first, and the refinement moves v_s from the
/// grid value to within ±30 % of the truth (the tolerance for the
/// low-speed study), with the refitted levels within 30 % of the hidden
/// [0.06, 0.12] N·m and a positive, finite σ. The simulator evaluates the
/// same Stribeck law as the candidate column (aras-dyn's effect), so this
/// tests the search, not an independent friction model.
#[test]
fn refines_stribeck_velocity_off_the_grid() {
    let mut p = Params::aras_diamond();
    p.extra.stribeck_friction = Some(Stribeck {
        v_s: 0.28,
        level: [0.06, 0.12],
    });
    for (d, seed) in on_seeds(&p, "stribeck_off_grid").iter().zip(SEEDS) {
        let s = d.steps.first().expect("nothing found");
        assert_eq!(s.id, "stribeck_friction", "seed {seed}: {}", s.label);
        let r = s.refinement.as_ref().expect("no refinement");
        eprintln!("seed {seed}: refinement {r:?}");
        assert!(
            (r.value - 0.28).abs() <= 0.3 * 0.28,
            "seed {seed}: v_s {}",
            r.value
        );
        assert!(r.std_dev > 0.0 && r.std_dev.is_finite(), "σ {}", r.std_dev);
        for (q, want) in r.parameters.iter().zip([0.06, 0.12]) {
            assert!(
                (q.value - want).abs() <= 0.3 * want,
                "seed {seed}: {}: {}",
                q.name,
                q.value
            );
        }
    }
}
