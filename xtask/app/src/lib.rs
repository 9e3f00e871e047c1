//! The ARAS-Diamond toolkit's command-line tools and reports.
//!
//! This crate is the orchestrator of `spec/ARAS-DIAMOND.md`: it parses the
//! command line and the config file, calls the library crates in the order of
//! the data flow (excitation → simulation → signal processing →
//! identification → validation → diagnosis) and writes reports. It holds no
//! mathematics of its own.
//!
//! Dependencies beyond the workspace crates: `clap` (command line),
//! `toml`/`serde_json` (config files), `plotters` (SVG plots), `indicatif`
//! (progress bars), `anyhow` (error context across the many file and stage
//! boundaries of an application; the libraries use `thiserror`).

pub mod output;
pub mod report;
