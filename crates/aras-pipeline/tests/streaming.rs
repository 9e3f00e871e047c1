//! Streaming least squares against the in-memory path ("Scale").
#![allow(clippy::needless_range_loop)]

mod common;

use aras_dyn::{Model, Params};
use aras_ident::streaming::{Accumulation, QrAccumulator, RegressorStage, States};
use aras_ident::{BaseParameters, NoiseVariances, ReducedLs, RowGroups, wls};
use aras_kin::Geometry;
use aras_log::{ReadOptions, read_log};
use aras_pipeline::TaskRegressor;
use aras_pipeline::robot::{filter, filter_reach, keep_rows, noise_gain, reversal_mask, stack};
use aras_pipeline::streaming::{StreamingOptions, StreamingRoute, identify_log, synthetic};
use aras_signal::{Bandwidth, Butterworth, FilterSpec, PeriodSource, process};
use aras_testkit::assert_source_not_repeated;
use faer::Mat;
use proptest::prelude::*;

/// Largest relative difference, scaled by the largest magnitude of `b`.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let s = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs() / s))
}

/// A random well-conditioned problem: `rows` rows per group, 2 groups.
fn problem(rows: usize, cols: usize, seed: u64) -> (Mat<f64>, Vec<f64>) {
    let mut r = common::rng(seed);
    let w = Mat::from_fn(2 * rows, cols, |i, j| {
        common::normal(&mut r) * (1.0 + j as f64) + if i < rows { 0.0 } else { 0.3 }
    });
    let t: Vec<f64> = (0..2 * rows)
        .map(|i| {
            (0..cols).map(|j| w[(i, j)] * (j as f64 - 3.0)).sum::<f64>()
                + common::normal(&mut r) * if i < rows { 0.1 } else { 0.5 }
        })
        .collect();
    (w, t)
}

fn names(n: usize) -> Vec<String> {
    (0..n).map(|j| format!("p{j}")).collect()
}

fn accumulate(w: &Mat<f64>, t: &[f64], rows: usize, chunk: usize) -> QrAccumulator {
    let mut acc = QrAccumulator::new(&names(w.ncols()), 2).unwrap();
    for g in 0..2 {
        let mut s = 0;
        while s < rows {
            let k = chunk.min(rows - s);
            acc.push_rows(
                g,
                w.as_ref().subrows(g * rows + s, k),
                &t[g * rows + s..g * rows + s + k],
            )
            .unwrap();
            s += k;
        }
    }
    acc
}

#[test]
fn chunked_accumulation_matches_in_memory_ols_and_wls() {
    let (rows, cols) = (20_000, 23);
    let (w, t) = problem(rows, cols, 1);
    let mem = ReducedLs::new(w.as_ref(), &t, &names(cols)).unwrap();
    let mem_ols = mem.ols().unwrap();
    let groups = RowGroups::contiguous(&[rows, rows]).unwrap();
    let mem_wls = wls(
        w.as_ref(),
        &t,
        &names(cols),
        &groups,
        NoiseVariances::FromResiduals,
    )
    .unwrap();
    for chunk in [1, 97, 4096, 20_000] {
        let acc = accumulate(&w, &t, rows, chunk);
        assert_eq!(acc.rows(), 2 * rows);
        let ols = acc.ols().unwrap();
        // Orthogonal transformations in a different order: the estimates
        // differ by rounding, κ·ε with κ ≈ 30 here, far below 1e-10.
        assert!(
            rel(&ols.estimate, &mem_ols.estimate) < 1e-10,
            "chunk {chunk}"
        );
        assert!(rel(&ols.std_dev, &mem_ols.std_dev) < 1e-10);
        assert!((ols.residual_norm / mem_ols.residual_norm - 1.0).abs() < 1e-10);
        let e = acc.wls(NoiseVariances::FromResiduals).unwrap();
        assert!(rel(&e.estimate.estimate, &mem_wls.estimate.estimate) < 1e-10);
        assert!(rel(&e.variances, &mem_wls.variances) < 1e-10);
    }
}

#[test]
fn merging_accumulators_equals_one_accumulator() {
    let (rows, cols) = (5000, 8);
    let (w, t) = problem(rows, cols, 2);
    let whole = accumulate(&w, &t, rows, 1000).ols().unwrap();
    let mut a = QrAccumulator::new(&names(cols), 2).unwrap();
    let mut b = QrAccumulator::new(&names(cols), 2).unwrap();
    for g in 0..2 {
        let o = g * rows;
        a.push_rows(g, w.as_ref().subrows(o, 2000), &t[o..o + 2000])
            .unwrap();
        b.push_rows(
            g,
            w.as_ref().subrows(o + 2000, 3000),
            &t[o + 2000..o + 5000],
        )
        .unwrap();
    }
    a.merge(&b).unwrap();
    assert!(rel(&a.ols().unwrap().estimate, &whole.estimate) < 1e-12);
}

#[test]
fn rank_deficient_blocks_and_bad_input_are_handled() {
    let (rows, cols) = (3000, 6);
    let (mut w, t) = problem(rows, cols, 3);
    // The first 1000 rows of each group do not excite column 2 (a robot at
    // rest for a while): faer skips the column there, the fallback QR must not.
    for g in 0..2 {
        for i in 0..1000 {
            w[(g * rows + i, 2)] = 0.0;
        }
    }
    let mem = ReducedLs::new(w.as_ref(), &t, &names(cols))
        .unwrap()
        .ols()
        .unwrap();
    let acc = accumulate(&w, &t, rows, 1000);
    assert!(rel(&acc.ols().unwrap().estimate, &mem.estimate) < 1e-10);

    let mut acc = QrAccumulator::new(&names(cols), 2).unwrap();
    let mut bad = w.clone();
    bad[(5, 1)] = f64::NAN;
    let e = acc
        .push_rows(0, bad.as_ref().subrows(0, 10), &t[..10])
        .unwrap_err();
    assert!(e.to_string().contains("row 5, column 1 (`p1`)"), "{e}");
    let e = acc
        .push_rows(2, w.as_ref().subrows(0, 10), &t[..10])
        .unwrap_err();
    assert!(e.to_string().contains("row group"), "{e}");
    let e = acc.ols().unwrap_err();
    assert!(e.to_string().contains("rows"), "{e}");
    assert!(QrAccumulator::new(&names(3), 0).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    /// Any split of the rows into blocks gives the same estimate.
    #[test]
    fn any_chunking_gives_the_in_memory_estimate(chunk in 1usize..700, seed in 0u64..1000) {
        let (rows, cols) = (1500, 5);
        let (w, t) = problem(rows, cols, seed);
        let mem = ReducedLs::new(w.as_ref(), &t, &names(cols)).unwrap().ols().unwrap();
        let acc = accumulate(&w, &t, rows, chunk);
        prop_assert!(rel(&acc.ols().unwrap().estimate, &mem.estimate) < 1e-10);
    }
}

struct Robot {
    model: Model,
    geo: Geometry,
    base: BaseParameters,
    beta: Vec<f64>,
}

impl Robot {
    fn regressor(&self) -> TaskRegressor {
        TaskRegressor::new(self.model.clone(), self.geo)
    }
}

fn robot() -> Robot {
    let p = Params::aras_diamond();
    let model = p.model().unwrap();
    let geo = p.geometry().unwrap();
    let beta = p.standard_vector(&model).unwrap().as_slice().to_vec();
    // Base parameters from rich data: the synthetic trajectory sampled
    // sparsely over its period.
    let s = synthetic::states(&model, &geo, &beta, 2000, 200.0, 0.0).unwrap();
    let samples = aras_signal::Samples {
        t: (0..2000).map(|i| i as f64 / 200.0).collect(),
        x: s[0].to_vec(),
        x_dot: s[1].to_vec(),
        x_ddot: s[2].to_vec(),
        tau: s[3].to_vec(),
        ..Default::default()
    };
    let st = stack(&model, &geo, &samples).unwrap();
    let base = BaseParameters::from_regressor(st.w.as_ref(), &st.names, 1e-8).unwrap();
    Robot {
        model,
        geo,
        base,
        beta,
    }
}

#[test]
fn regressor_stage_matches_in_memory_stacking_and_is_deterministic() {
    let r = robot();
    let n = 30_000;
    let s = synthetic::states(&r.model, &r.geo, &r.beta, n, 1000.0, 0.01).unwrap();
    let samples = aras_signal::Samples {
        t: (0..n).map(|i| i as f64 / 1000.0).collect(),
        x: s[0].to_vec(),
        x_dot: s[1].to_vec(),
        x_ddot: s[2].to_vec(),
        tau: s[3].to_vec(),
        ..Default::default()
    };
    let st = stack(&r.model, &r.geo, &samples).unwrap();
    let wb = r.base.base_regressor(st.w.as_ref()).unwrap();
    let mem = ReducedLs::new(wb.as_ref(), &st.t, &r.base.base_names())
        .unwrap()
        .ols()
        .unwrap();
    let run = |chunk: usize| {
        let mut stage =
            RegressorStage::with_accumulation(r.regressor(), &r.base, Accumulation::Qr).unwrap();
        for c0 in (0..n).step_by(chunk) {
            let c1 = (c0 + chunk).min(n);
            let states = States {
                x: &[&s[0][0][c0..c1], &s[0][1][c0..c1]],
                x_dot: &[&s[1][0][c0..c1], &s[1][1][c0..c1]],
                x_ddot: &[&s[2][0][c0..c1], &s[2][1][c0..c1]],
                tau: &[&s[3][0][c0..c1], &s[3][1][c0..c1]],
            };
            stage.push(&states).unwrap();
        }
        assert_eq!(stage.samples(), n);
        stage.accumulator().ols().unwrap()
    };
    let a = run(7000);
    // Different row order and blocking than in memory: rounding only. The
    // base regressor's condition number is ~1e3, so 1e-10 is ~1e3 ε with
    // room for the accumulation over 60 000 rows.
    assert!(
        rel(&a.estimate, &mem.estimate) < 1e-10,
        "{:?}",
        rel(&a.estimate, &mem.estimate)
    );
    let b = run(7000);
    assert_eq!(
        a.estimate, b.estimate,
        "same chunks must give bit-identical results"
    );
    let c = run(n);
    assert!(rel(&c.estimate, &mem.estimate) < 1e-10);
    // Normal equations (the default): error of order κ² ε of the
    // column-scaled regressor at worst, still bit-identical for the same
    // chunks.
    let gram = |chunk: usize| {
        let mut stage = RegressorStage::new(r.regressor(), &r.base).unwrap();
        for c0 in (0..n).step_by(chunk) {
            let c1 = (c0 + chunk).min(n);
            let states = States {
                x: &[&s[0][0][c0..c1], &s[0][1][c0..c1]],
                x_dot: &[&s[1][0][c0..c1], &s[1][1][c0..c1]],
                x_ddot: &[&s[2][0][c0..c1], &s[2][1][c0..c1]],
                tau: &[&s[3][0][c0..c1], &s[3][1][c0..c1]],
            };
            stage.push(&states).unwrap();
        }
        let acc = stage.accumulator();
        (acc.ols().unwrap(), acc.gram_check().unwrap())
    };
    let (g1, check) = gram(7000);
    assert!(check.passed && check.condition > 10.0, "{check:?}");
    let e = rel(&g1.estimate, &mem.estimate);
    assert!(e < check.error_bound, "{e:e} vs κ²ε = {check:?}");
    assert_eq!(g1.estimate, gram(7000).0.estimate);
    // The model fits to the noise: unit-variance noise × 0.01 N·m.
    assert!(
        (a.residual_variance / 1e-4 - 1.0).abs() < 0.05,
        "{}",
        a.residual_variance
    );
}

#[test]
fn regressor_stage_names_the_failing_sample() {
    let r = robot();
    let mut stage = RegressorStage::new(r.regressor(), &r.base).unwrap();
    let s = synthetic::states(&r.model, &r.geo, &r.beta, 3000, 1000.0, 0.0).unwrap();
    let mut gamma = s[0][1].clone();
    gamma[2500] = 0.0; // γ = 0 is a singularity
    let states = States {
        x: &[&s[0][0], &gamma],
        x_dot: &[&s[1][0], &s[1][1]],
        x_ddot: &[&s[2][0], &s[2][1]],
        tau: &[&s[3][0], &s[3][1]],
    };
    let err = stage.push(&states).unwrap_err();
    let e = err.to_string();
    assert!(e.contains("sample 2500"), "{e}");
    // The model's error is the source, kept as itself and not repeated.
    assert_eq!(e, "streaming regressor, sample 2500");
    let cause = std::error::Error::source(&err).expect("the model's error is the source");
    let kin = cause
        .downcast_ref::<aras_pipeline::RegressorError>()
        .expect("the source is the regressor's own error");
    assert!(
        matches!(kin, aras_pipeline::RegressorError::Kinematics(_)),
        "{kin:?}"
    );
    // The regressor's error keeps the kinematics' error as its own source.
    let inner = std::error::Error::source(kin).expect("the kinematics' error is the source");
    assert!(
        inner.downcast_ref::<aras_kin::KinError>().is_some(),
        "{inner:?}"
    );
    assert_source_not_repeated(&err);
    assert_source_not_repeated(kin);
    assert_eq!(
        stage.accumulator().rows(),
        0,
        "nothing of a failing push is accumulated"
    );
    let short = States {
        tau: &[&s[3][0][..10], &s[3][1]],
        ..states
    };
    assert!(stage.push(&short).unwrap_err().to_string().contains("tau1"));
}

fn write(dir: &std::path::Path, name: &str, r: &Robot, n: usize, fs: f64) -> std::path::PathBuf {
    let p = dir.join(name);
    synthetic::write_log(&p, &r.model, &r.geo, &r.beta, n, fs, 0.002).unwrap();
    p
}

/// A fresh scratch directory, removed when the test passes.
fn tempdir(tag: &str) -> aras_testkit::Scratch {
    aras_testkit::Scratch::new(&format!("streaming-{tag}"))
}

/// What the in-memory identification gives: estimate, rows fitted per
/// joint, σ² corrected for the filter.
struct Reference {
    estimate: Vec<f64>,
    rows: [usize; 2],
    variance: f64,
    fitness: [f64; 2],
}

/// The in-memory pipeline, as `aras identify` runs it: read → process →
/// stack → filter → reversal exclusion (`reversal_mask` widened by
/// `filter_reach`) → OLS → σ corrected by `noise_gain`.
fn in_memory(path: &std::path::Path, r: &Robot, o: &StreamingOptions) -> Reference {
    let mut log = read_log(path, &o.read).unwrap();
    if let Some(d) = o.torque_delay {
        log = aras_signal::delay_torque(&log, d).unwrap();
    }
    let pr = process(&log, &o.process, &aras_kin::task_motion(&r.geo)).unwrap();
    let mut st = stack(&r.model, &r.geo, &pr.samples).unwrap();
    let periodic = pr.summary.periods.is_some();
    let n = pr.samples.len();
    let (mut guard, mut gain) = (0, 1.0);
    if let Some(f) = &pr.summary.filter {
        let sos = Butterworth::lowpass(f.order, f.cutoff_hz, pr.summary.sample_rate_hz).unwrap();
        filter(&mut st, &sos, o.filter_mode, periodic).unwrap();
        guard = filter_reach(&sos, n, periodic, o.reversal_reach).unwrap();
        gain = noise_gain(&sos, n, periodic).unwrap();
    }
    let keep = reversal_mask(&pr.samples.theta_dot, o.min_speed, guard, periodic).unwrap();
    let fit = keep_rows(&st, &keep).unwrap();
    let wb = r.base.base_regressor(fit.w.as_ref()).unwrap();
    let ols = ReducedLs::new(wb.as_ref(), &fit.t, &r.base.base_names())
        .unwrap()
        .ols()
        .unwrap()
        .with_filtered_noise(gain)
        .unwrap();
    let pred = aras_ident::validate::predict(wb.as_ref(), &ols.estimate).unwrap();
    let f = aras_ident::validate::fitness_per_group(&fit.t, &pred, &fit.groups).unwrap();
    Reference {
        fitness: [f[0], f[1]],
        estimate: ols.estimate,
        rows: [fit.groups.counts()[0], fit.groups.counts()[1]],
        variance: ols.residual_variance,
    }
}

/// Streaming with `o` (QR, then normal equations) against the in-memory
/// identification: the same rows, the same estimate and σ.
fn check_route(path: &std::path::Path, r: &Robot, o: &StreamingOptions, route: StreamingRoute) {
    let mem = in_memory(path, r, o);
    let mut q = o.clone();
    q.accumulation = Accumulation::Qr;
    let s = identify_log(path, &r.model, &r.base, &q).unwrap();
    assert_eq!(s.route, route);
    assert!(s.gram_check.is_none());
    assert_eq!(s.rows_fitted, mem.rows, "{route:?}: the same rows");
    if o.min_speed > 0.0 {
        assert!(
            s.rows_fitted[0] < s.samples_used && s.rows_fitted[1] < s.samples_used,
            "{route:?}: reversals were excluded ({:?} of {})",
            s.rows_fitted,
            s.samples_used
        );
    }
    // QR on the same rows in another order and blocking: rounding only
    // (κ ≈ 1e3, so ≈ 1e3 ε), plus filter edge transients below 1e-12 on the
    // overlapping-block route.
    let e = rel(&s.ols.estimate, &mem.estimate);
    assert!(e < 1e-9, "{route:?}: QR estimate differs by {e:e}");
    let v = (s.ols.residual_variance / mem.variance - 1.0).abs();
    assert!(v < 1e-9, "{route:?}: σ² differs by {v:e}");
    // Fitness (78) from the factors and torque sums, vs from the rows.
    let f = s.fitness(&s.ols.estimate).unwrap();
    for j in 0..2 {
        assert!(
            (f[j] - mem.fitness[j]).abs() < 1e-6,
            "{route:?}: {f:?} vs {:?}",
            mem.fitness
        );
    }

    let mut g = o.clone();
    g.accumulation = Accumulation::Gram;
    let s = identify_log(path, &r.model, &r.base, &g).unwrap();
    let check = s.gram_check.expect("normal equations are checked");
    assert!(check.passed, "{check:?}");
    assert_eq!(s.rows_fitted, mem.rows);
    // Normal equations: the error is of order κ² ε at worst (the Gram's
    // rounding amplified by the squared condition number; measured 20–700×
    // below it here), plus the route's own 1e-9.
    let e = rel(&s.ols.estimate, &mem.estimate);
    assert!(
        e < check.error_bound + 1e-9,
        "{route:?}: Gram estimate differs by {e:e}, κ²ε = {:e}",
        check.error_bound
    );
    let v = (s.ols.residual_variance / mem.variance - 1.0).abs();
    assert!(v < 1e-6, "{route:?}: Gram σ² differs by {v:e}");
}

/// `base` set up for each route of `identify_log`: logged derivatives with
/// no filter (the fast path); a non-periodic log filtered at 20 Hz with θ
/// differentiated (overlapping blocks); the period average on the fly.
fn route_options(base: &StreamingOptions) -> [(StreamingOptions, StreamingRoute); 3] {
    let mut logged = base.clone();
    logged.process.use_logged_derivatives = true;
    logged.process.filter = Bandwidth::Off;
    logged.process.period = PeriodSource::Off;
    let mut blocks = base.clone();
    blocks.process.period = PeriodSource::Off;
    blocks.process.filter = Bandwidth::Fixed(FilterSpec {
        order: 4,
        cutoff_hz: 20.0,
    });
    // The period average compared on the fixed low-pass; the data-chosen
    // bandwidth's streamed period is compared in `aras-cli`'s streaming test.
    let mut periodic = base.clone();
    periodic.process.period = PeriodSource::Seconds(synthetic::PERIOD_S);
    periodic.process.filter = Bandwidth::Fixed(FilterSpec::default());
    [
        (logged, StreamingRoute::LoggedDerivatives),
        (blocks, StreamingRoute::OverlappingBlocks),
        (periodic, StreamingRoute::PeriodAverage),
    ]
}

#[test]
fn identify_log_matches_the_in_memory_identification_on_every_route() {
    let r = robot();
    let dir = tempdir("routes");
    let fs = 500.0;
    let n = 40_000; // 80 s: 8 periods
    let path = write(&dir, "run.csv", &r, n, fs);
    for min_speed in [0.0, 0.2] {
        let base_opts = StreamingOptions {
            chunk_samples: 4096,
            min_speed,
            widths: None,
            ..Default::default()
        };
        for (o, route) in route_options(&base_opts) {
            check_route(&path, &r, &o, route);
            let s = identify_log(&path, &r.model, &r.base, &o).unwrap();
            match route {
                StreamingRoute::LoggedDerivatives => {
                    assert_eq!((s.samples_read, s.samples_used), (n, n));
                    assert_eq!(s.noise_gain, 1.0);
                }
                StreamingRoute::OverlappingBlocks => {
                    assert!(s.blocks > 5 && s.overlap > 0, "{} blocks", s.blocks);
                    assert!(s.noise_gain > 0.0 && s.noise_gain < 0.2, "{}", s.noise_gain);
                }
                StreamingRoute::PeriodAverage => assert_eq!(s.periods, 8),
            }
        }
    }
}

/// A period that is not a whole number of samples (10 s at a step of 3 ms
/// is 3333.33 samples) is averaged while reading in whole blocks of 3
/// periods (10 000 samples), as in memory: the same rows, estimate and σ.
#[test]
fn identify_log_averages_a_period_of_a_fractional_number_of_samples() {
    let r = robot();
    let dir = tempdir("fractional-period");
    let fs = 1000.0 / 3.0;
    let n = 21_000; // 63 s: 2 blocks of 3 periods, and a tail
    let path = write(&dir, "run.csv", &r, n, fs);
    let o = StreamingOptions {
        chunk_samples: 4096,
        min_speed: 0.2,
        widths: None,
        ..Default::default()
    };
    let [_, _, (periodic, route)] = route_options(&o);
    check_route(&path, &r, &periodic, route);
    let s = identify_log(&path, &r.model, &r.base, &periodic).unwrap();
    assert_eq!(s.periods, 6);
}

/// Where five overlaps exceed `chunk_samples` (a low cut-off, or a high
/// rate), a block is five overlaps long: no block re-reads more than 40 %
/// of itself, and the result is still the in-memory identification's.
#[test]
fn blocks_are_at_least_five_overlaps_long() {
    let r = robot();
    let dir = tempdir("long-blocks");
    let fs = 500.0;
    let n = 40_000;
    let path = write(&dir, "run.csv", &r, n, fs);
    let mut o = StreamingOptions {
        chunk_samples: 1024,
        min_speed: 0.2,
        widths: None,
        ..Default::default()
    };
    o.process.period = PeriodSource::Off;
    o.process.filter = Bandwidth::Fixed(FilterSpec {
        order: 4,
        cutoff_hz: 10.0,
    });
    check_route(&path, &r, &o, StreamingRoute::OverlappingBlocks);
    let s = identify_log(&path, &r.model, &r.base, &o).unwrap();
    let block = 5 * s.overlap;
    assert!(block > 1024, "the overlap ({}) must rule here", s.overlap);
    // Every block but the last holds `block` new samples.
    assert_eq!(
        s.blocks,
        n.div_ceil(block),
        "{} blocks of {block}",
        s.blocks
    );
}

/// A torque delay removed while streaming gives what removing it from the
/// whole log in memory gives (`aras_signal::delay_torque`), on every route,
/// for a positive and a negative fraction of samples.
#[test]
fn a_torque_delay_is_removed_on_every_route_as_in_memory() {
    let r = robot();
    let dir = tempdir("delay");
    let fs = 500.0;
    let n = 40_000;
    let path = write(&dir, "run.csv", &r, n, fs);
    for delay in [2.4, -1.5] {
        let base_opts = StreamingOptions {
            chunk_samples: 4096,
            min_speed: 0.2,
            torque_delay: Some(delay),
            widths: None,
            ..Default::default()
        };
        for (o, route) in route_options(&base_opts) {
            check_route(&path, &r, &o, route);
            if route == StreamingRoute::LoggedDerivatives {
                let s = identify_log(&path, &r.model, &r.base, &o).unwrap();
                assert_eq!(s.samples_read, n - (delay.abs().ceil() as usize));
            }
        }
    }
    let o = StreamingOptions {
        torque_delay: Some(f64::NAN),
        ..Default::default()
    };
    let e = identify_log(&path, &r.model, &r.base, &o).unwrap_err();
    assert!(e.to_string().contains("torque_delay"), "{e}");
}

#[test]
fn identify_log_reports_bad_options_and_bad_logs() {
    let r = robot();
    let dir = tempdir("bad");
    let o = StreamingOptions {
        chunk_samples: 10,
        ..Default::default()
    };
    let e = identify_log(&dir.join("none.csv"), &r.model, &r.base, &o).unwrap_err();
    assert!(e.to_string().contains("chunk_samples"), "{e}");
    let o = StreamingOptions::default();
    let e = identify_log(&dir.join("none.csv"), &r.model, &r.base, &o).unwrap_err();
    assert!(e.to_string().contains("none.csv"), "{e}");
    let p = dir.join("deg.csv");
    let mut text = String::from("t,theta1,theta2,tau1,tau2\n");
    for i in 0..3000 {
        text += &format!("{},{},{},0.1,0.2\n", i as f64 * 1e-3, 120.0, 60.0);
    }
    std::fs::write(&p, text).unwrap();
    let o = StreamingOptions {
        read: ReadOptions::default(),
        ..Default::default()
    };
    // Angles of 120 rad look like degrees: the reader's end-of-log check
    // fails even though the data was consumed in chunks (or the
    // kinematics fail first); either way an error naming the log.
    let e = identify_log(&p, &r.model, &r.base, &o).unwrap_err();
    assert!(
        e.to_string().contains("deg.csv") || e.to_string().contains("degrees"),
        "{e}"
    );
}

#[test]
fn gram_accumulation_matches_qr_and_its_guard_trips_on_ill_conditioned_data() {
    // Well conditioned: normal equations agree with in-memory QR to κ² ε.
    let (rows, cols) = (5_000, 23);
    let (w, t) = problem(rows, cols, 5);
    let mem = ReducedLs::new(w.as_ref(), &t, &names(cols))
        .unwrap()
        .ols()
        .unwrap();
    let mut acc = QrAccumulator::new(&names(cols), 2).unwrap();
    for g in 0..2 {
        acc.push_rows_gram(
            g,
            w.as_ref().subrows(g * rows, rows),
            &t[g * rows..(g + 1) * rows],
        )
        .unwrap();
    }
    assert_eq!(acc.gram_rows(), 2 * rows);
    let check = acc.gram_check().unwrap();
    assert!(check.passed && check.error().is_none(), "{check:?}");
    // κ ≈ 1 here, so the bound is ≈ ε; 1e-12 covers the rounding of sums
    // over thousands of rows that any method has.
    let e = rel(&acc.ols().unwrap().estimate, &mem.estimate);
    assert!(e < check.error_bound + 1e-12, "{e:e} vs {check:?}");
    // WLS from residuals goes through the same factors.
    let groups = RowGroups::contiguous(&[rows, rows]).unwrap();
    let mem_wls = wls(
        w.as_ref(),
        &t,
        &names(cols),
        &groups,
        NoiseVariances::FromResiduals,
    )
    .unwrap();
    let acc_wls = acc.wls(NoiseVariances::FromResiduals).unwrap();
    assert!(
        rel(&acc_wls.estimate.estimate, &mem_wls.estimate.estimate) < check.error_bound + 1e-12
    );

    // Ill conditioned: column 1 = column 0 + 1e-6 noise, κ ≈ 1e6, κ² ε ≈
    // 1e-4 > 1e-6: the check fails and says to use the QR accumulation,
    // which stays accurate (κ ε ≈ 1e-10).
    let mut r = common::rng(9);
    let n = 4_000;
    let w = Mat::from_fn(n, 3, |i, j| {
        let x = ((i * 37) % 101) as f64 / 101.0 - 0.5;
        match j {
            0 => x,
            1 => x + 1e-6 * common::normal(&mut r),
            _ => ((i * 13) % 7) as f64,
        }
    });
    let t: Vec<f64> = (0..n)
        .map(|i| w[(i, 0)] - 2.0 * w[(i, 1)] + 0.5 * w[(i, 2)])
        .collect();
    let mut gram = QrAccumulator::new(&names(3), 1).unwrap();
    gram.push_rows_gram(0, w.as_ref(), &t).unwrap();
    let check = gram.gram_check().unwrap();
    assert!(!check.passed && check.condition > 1e5, "{check:?}");
    let msg = check.error().unwrap().to_string();
    assert!(
        msg.contains("Accumulation::Qr") && msg.contains("--accumulation qr"),
        "{msg}"
    );
    let mut qr = QrAccumulator::new(&names(3), 1).unwrap();
    qr.push_rows(0, w.as_ref(), &t).unwrap();
    assert!(qr.gram_check().is_none());
    let x = qr.ols().unwrap().estimate;
    // Exact data: QR recovers the parameters to κ ε ≈ 1e-10 (× 10).
    assert!(rel(&x, &[1.0, -2.0, 0.5]) < 1e-9, "{x:?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    /// Any chunking of the normal equations gives the in-memory estimate to
    /// within their κ² ε bound (the compensated sum makes the blocking
    /// irrelevant to first order).
    #[test]
    fn gram_any_chunking_stays_within_its_bound(chunk in 1usize..3000, seed in 0u64..1000) {
        let (rows, cols) = (3_000, 8);
        let (w, t) = problem(rows, cols, seed);
        let mem = ReducedLs::new(w.as_ref(), &t, &names(cols)).unwrap().ols().unwrap();
        let mut acc = QrAccumulator::new(&names(cols), 2).unwrap();
        for g in 0..2 {
            let mut s0 = 0;
            while s0 < rows {
                let k = chunk.min(rows - s0);
                let (a, b) = (g * rows + s0, g * rows + s0 + k);
                acc.push_rows_gram(g, w.as_ref().subrows(a, k), &t[a..b]).unwrap();
                s0 += k;
            }
        }
        let check = acc.gram_check().unwrap();
        prop_assert!(check.passed);
        let e = rel(&acc.ols().unwrap().estimate, &mem.estimate);
        // + 1e-12: the rounding of sums over thousands of rows (κ ≈ 1).
        prop_assert!(e < check.error_bound + 1e-12, "{} vs {:?}", e, check);
    }
}
