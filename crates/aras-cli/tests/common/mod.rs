//! Helpers shared by the command-line tests.
#![allow(dead_code)]

use std::collections::HashMap;
use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use aras_cli::output::OutDir;

/// A fresh, empty scratch directory `aras-{suite}-{name}-{pid}`, removed
/// when the test passes.
pub fn scratch(suite: &str, name: &str) -> aras_testkit::Scratch {
    aras_testkit::Scratch::new(&format!("{suite}-{name}"))
}

/// A file under the repository's `fixtures/`.
pub fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(rel)
}

/// Runs the `aras` binary with `args`.
pub fn aras(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aras"))
        .args(args)
        .output()
        .unwrap()
}

/// (relative path, content hash) of every file under `dir`, sorted.
pub fn snapshot(dir: &Path) -> Vec<(String, u64)> {
    let mut v = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let mut h = DefaultHasher::new();
                std::fs::read(&p).unwrap().hash(&mut h);
                v.push((
                    p.strip_prefix(dir).unwrap().display().to_string(),
                    h.finish(),
                ));
            }
        }
    }
    v.sort();
    v
}

/// A run directory as the tool leaves it: written through `OutDir`, so
/// with its manifest.
pub fn own_run(out: &Path, files: &[(&str, &str)]) {
    let o = OutDir::create(out, true, &[]).unwrap();
    for (name, text) in files {
        o.write(name, text).unwrap();
    }
    o.commit().unwrap();
}

/// A short `validate` configuration (one frequency of (79), two periods, a
/// coarse PD grid) written as `dir/short.toml`.
pub fn short_validate_config(dir: &Path) -> PathBuf {
    let cfg = dir.join("short.toml");
    std::fs::write(
        &cfg,
        "[validation]\nfrequencies_hz = [1.0]\nperiods = 2\npd_grid = 5\npd_random = 10\n",
    )
    .unwrap();
    cfg
}

/// Columns of a CSV by header name.
pub fn columns(path: &Path) -> HashMap<String, Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let names: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    for line in lines {
        for (c, v) in cols.iter_mut().zip(line.split(',')) {
            c.push(v.parse().unwrap());
        }
    }
    names.into_iter().zip(cols).collect()
}

/// Fitness (78), two-pass, in percent: an independent check of the
/// library's figure.
pub fn fitness(measured: &[f64], predicted: &[f64]) -> f64 {
    let mean = measured.iter().sum::<f64>() / measured.len() as f64;
    let err: f64 = measured
        .iter()
        .zip(predicted)
        .map(|(m, p)| (m - p).powi(2))
        .sum();
    let var: f64 = measured.iter().map(|m| (m - mean).powi(2)).sum();
    100.0 * (1.0 - (err / var).sqrt())
}
