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

pub mod ceiling;
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
