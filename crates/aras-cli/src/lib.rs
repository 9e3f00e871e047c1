//! The ARAS-Diamond toolkit's command-line tools and reports.
//!
//! This crate orchestrates the workflow of `docs/model.md`: it parses the
//! command line and the config file, calls the library crates in the order of
//! the data flow (excitation → simulation → signal processing →
//! identification → validation → diagnosis) and writes reports. It holds no
//! mathematics of its own.
//!
//! Conventions: SI units and radians everywhere except config keys ending
//! in `_deg` and report labels; torques are motor (joint) torques; stacked
//! data put joint 1's rows first. Outputs are written atomically into a
//! staged directory that replaces the target only at the end; `--force`
//! replaces only files a previous run recorded in its manifest and that are
//! unchanged since; one run at a time writes an output ([`output`]).
//! See `docs/architecture.md` (data flow, module map) and `docs/config.md`.
//!
//! Dependencies beyond the workspace crates: `clap` (command line),
//! `toml`/`serde_json` (config files), `plotters` (SVG plots), `indicatif`
//! (progress bars), `anyhow` (error context across the many file and stage
//! boundaries of an application; the libraries use `thiserror`), `faer`
//! (views of the stacked regressor for `aras-ident`), `ctrlc` (the binary's
//! Ctrl-C / `SIGTERM` handler that removes an interrupted run's staging
//! directory: signal handling is per-OS code better not written by hand).

#![warn(missing_docs)]

pub mod cli;
pub mod cmd;
pub mod config;
pub mod excite;
pub mod friction;
pub mod identify;
pub mod output;
pub mod paper;
pub mod plausibility;
pub mod report;
pub mod robot;
pub mod simulate;
pub mod stages;
pub mod summary;
pub mod validate;

/// The README's and `docs/`'s Rust snippets, compiled and run as doctests
/// (`cargo test --doc -p aras-cli`), so that what the documentation shows
/// works.
#[cfg(doctest)]
mod documentation {
    #[doc = include_str!("../../../README.md")]
    struct Readme;
    #[doc = include_str!("../../../docs/architecture.md")]
    struct Architecture;
    #[doc = include_str!("../../../docs/blas.md")]
    struct Blas;
    #[doc = include_str!("../../../docs/config.md")]
    struct Config;
    #[doc = include_str!("../../../docs/diagnose.md")]
    struct Diagnose;
    #[doc = include_str!("../../../docs/excitation.md")]
    struct Excitation;
    #[doc = include_str!("../../../docs/friction.md")]
    struct Friction;
    #[doc = include_str!("../../../docs/kinematics.md")]
    struct Kinematics;
    #[doc = include_str!("../../../docs/log-format.md")]
    struct LogFormat;
    #[doc = include_str!("../../../docs/mjcf.md")]
    struct Mjcf;
    #[doc = include_str!("../../../docs/model.md")]
    struct Model;
    #[doc = include_str!("../../../docs/parameter-format.md")]
    struct ParameterFormat;
    #[doc = include_str!("../../../docs/performance.md")]
    struct Performance;
    #[doc = include_str!("../../../docs/processing.md")]
    struct Processing;
    #[doc = include_str!("../../../docs/robustness.md")]
    struct Robustness;
    #[doc = include_str!("../../../docs/scale.md")]
    struct Scale;
    #[doc = include_str!("../../../docs/simulator.md")]
    struct Simulator;
    #[doc = include_str!("../../../docs/tour.md")]
    struct Tour;
    #[doc = include_str!("../../../docs/urdf.md")]
    struct Urdf;
    #[doc = include_str!("../../../docs/validation.md")]
    struct Validation;
}

#[cfg(test)]
mod tests {
    /// Every page of `docs/` is in [`documentation`]'s doctests, so a Rust
    /// snippet added to any of them is compiled and run.
    #[test]
    fn every_doc_page_is_doctested() {
        let here = include_str!("lib.rs");
        let docs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs");
        for e in std::fs::read_dir(docs).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            if name.ends_with(".md") {
                let line = format!("include_str!(\"../../../docs/{name}\")");
                assert!(here.contains(&line), "docs/{name} is not doctested");
            }
        }
    }
}
