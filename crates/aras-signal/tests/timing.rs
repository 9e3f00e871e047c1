//! Jittered and epoch time stamps through the processing: period averaging
//! uses every whole period, and an averaging that leaves much of the record
//! unused says so.

use aras_log::{ReadOptions, Warning, read_log_from};
use aras_signal::{JointCoordinates, PeriodSource, ProcessOptions, process};
use rand::{RngExt, SeedableRng};

/// 16 periods of 2 s at 1 kHz, times from `time(i)`.
fn periodic(time: impl Fn(usize) -> String) -> String {
    let mut csv = String::from("t,theta1,theta2,tau1,tau2\n");
    for i in 0..32_000 {
        let x = std::f64::consts::TAU * 0.5 * i as f64 * 1e-3;
        csv += &format!(
            "{},{},{},{},{}\n",
            time(i),
            2.0 + 0.2 * x.sin(),
            0.6 - 0.1 * (2.0 * x).cos(),
            0.3 * x.sin(),
            -0.2 * x.cos()
        );
    }
    csv
}

fn averaged_blocks(csv: &str) -> (usize, usize, Vec<Warning>) {
    let log = read_log_from(csv.as_bytes(), "lab.csv", &ReadOptions::default()).unwrap();
    let opts = ProcessOptions {
        period: PeriodSource::Seconds(2.0),
        ..Default::default()
    };
    let p = process(&log, &opts, &JointCoordinates).unwrap();
    let s = p.summary.periods.expect("averaged");
    (s.blocks_averaged, s.periods_per_block, p.warnings)
}

#[test]
fn jittered_and_epoch_stamps_average_every_period() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let jitter: Vec<f64> = (0..32_000)
        .map(|_| (rng.random::<f64>() - 0.5) * 4e-4)
        .collect();
    for csv in [
        periodic(|i| format!("{}", i as f64 * 1e-3 + jitter[i])),
        periodic(|i| format!("{:.6}", 1.7e9 + i as f64 * 1e-3)),
    ] {
        let (blocks, k, warnings) = averaged_blocks(&csv);
        assert_eq!((blocks, k), (16, 1), "{warnings:?}");
        assert!(
            !warnings
                .iter()
                .any(|w| matches!(w, Warning::AveragingUnused { .. })),
            "{warnings:?}"
        );
    }
}

#[test]
fn averaging_that_leaves_much_unused_is_a_warning() {
    // A period of 2.0001 s is 2000.1 samples: the first whole block is 10
    // periods, and 16 periods hold one block: 37.5 % of the record unused.
    let csv = periodic(|i| format!("{}", i as f64 * 1e-3));
    let log = read_log_from(csv.as_bytes(), "lab.csv", &ReadOptions::default()).unwrap();
    let opts = ProcessOptions {
        period: PeriodSource::Seconds(2.0001),
        max_period_spread: 0.5,
        ..Default::default()
    };
    let p = process(&log, &opts, &JointCoordinates).unwrap();
    let w = p
        .warnings
        .iter()
        .find(|w| matches!(w, Warning::AveragingUnused { .. }))
        .expect("a warning");
    let msg = w.to_string();
    assert!(
        msg.contains("1 block(s) of 10 period(s) and leaves 37.5 % of the record unused"),
        "{msg}"
    );
}
