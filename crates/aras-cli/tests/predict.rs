//! `aras predict` prints the fitness (78) of exactly the file it writes
//! against the log's raw torques: recomputed here from the written file and
//! the log's own columns, on every processing route.

mod common;

use std::collections::HashMap;
use std::path::Path;

use common::{aras, columns, fitness, fixture, scratch};

/// The two percentages `predict` printed.
fn printed(stdout: &str) -> [f64; 2] {
    let after = |tag: &str| -> f64 {
        stdout
            .split(tag)
            .nth(1)
            .unwrap_or_else(|| panic!("no `{tag}` in {stdout}"))
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    [after("τ1 "), after("τ2 ")]
}

/// Writes `log`'s columns `cols` as a new log with `log`'s sidecar, its
/// time stamps moved by `shift(row)` seconds.
fn write_subset(log: &Path, out: &Path, cols: &[&str], shift: impl Fn(usize) -> f64) {
    let c = columns(log);
    let mut text = cols.join(",") + "\n";
    for (i, t) in c["t"].iter().enumerate() {
        let row: Vec<String> = cols
            .iter()
            .map(|k| match *k {
                "t" => format!("{}", t + shift(i)),
                _ => format!("{}", c[*k][i]),
            })
            .collect();
        text += &(row.join(",") + "\n");
    }
    std::fs::write(out, text).unwrap();
    std::fs::copy(aras_log::sidecar_path(log), aras_log::sidecar_path(out)).unwrap();
}

/// A route: its name, the log's columns, the time shift per row, options.
type Case<'a> = (
    &'a str,
    Vec<&'a str>,
    Box<dyn Fn(usize) -> f64>,
    Vec<String>,
);

#[test]
fn printed_fitness_is_the_written_files() {
    let dir = scratch("predict", "fitness");
    let cfg = dir.join("short.toml");
    std::fs::write(&cfg, "[simulation]\nperiods = 3\n").unwrap();
    let sim = dir.join("sim.csv");
    let r = aras(&[
        "simulate",
        "--frequency",
        "1",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        sim.to_str().unwrap(),
        "-q",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let base = ["t", "theta1", "theta2", "tau1", "tau2"];
    let logged = [
        "t", "theta1", "theta2", "tau1", "tau2", "dtheta1", "dtheta2", "ddtheta1", "ddtheta2",
    ];
    // Routes: logged derivatives as given; the fixed filter; the
    // data-chosen bandwidth (config); period averaging (--period); an
    // irregular time base (every other step 0.2 ms longer, the next shorter).
    let auto = dir.join("auto.toml");
    std::fs::write(&auto, "[signal]\nbandwidth = \"auto\"\n").unwrap();
    let cases: Vec<Case> = vec![
        ("logged", logged.to_vec(), Box::new(|_| 0.0), vec![]),
        ("fixed", base.to_vec(), Box::new(|_| 0.0), vec![]),
        (
            "auto",
            base.to_vec(),
            Box::new(|_| 0.0),
            vec!["--config".into(), auto.display().to_string()],
        ),
        (
            "periodic",
            base.to_vec(),
            Box::new(|_| 0.0),
            vec!["--period".into(), "1".into()],
        ),
        (
            "irregular",
            base.to_vec(),
            Box::new(|i| if i % 2 == 1 { 2e-4 } else { 0.0 }),
            vec![],
        ),
    ];
    for (name, cols, shift, extra) in cases {
        let log = dir.join(format!("{name}.csv"));
        write_subset(&sim, &log, &cols, shift);
        let out = dir.join(format!("{name}_pred.csv"));
        let mut args = vec![
            "predict".to_string(),
            "--params".into(),
            fixture("robots/aras-diamond.json").display().to_string(),
            "--data".into(),
            log.display().to_string(),
            "--out".into(),
            out.display().to_string(),
        ];
        args.extend(extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let r = aras(&args);
        assert!(
            r.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let said = printed(&String::from_utf8_lossy(&r.stdout));
        // The written file, joined with the log's raw torques by time.
        let raw = columns(&log);
        let pred = columns(&out);
        let row_of: HashMap<u64, usize> = raw["t"]
            .iter()
            .enumerate()
            .map(|(i, t)| (t.to_bits(), i))
            .collect();
        let rows: Vec<usize> = pred["t"]
            .iter()
            .map(|t| *row_of.get(&t.to_bits()).expect("a row of the log"))
            .collect();
        for (j, said) in said.iter().enumerate() {
            let m: Vec<f64> = rows
                .iter()
                .map(|&i| raw[&format!("tau{}", j + 1)][i])
                .collect();
            let f = fitness(&m, &pred[&format!("tau{}", j + 1)]);
            // Printed with three decimals.
            assert!(
                (f - said).abs() <= 5.1e-4,
                "{name}, τ{}: printed {said} %, the written file scores {f} %",
                j + 1
            );
        }
    }
}
