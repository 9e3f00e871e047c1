//! Stage timing and progress display.
//!
//! Each stage is timed; its wall-clock seconds go to the report and (unless
//! `--reproducible`) to `summary.json`. A spinner runs while a stage works
//! when stderr is a terminal and `--quiet` is not given; otherwise nothing
//! animated is drawn (logs stay clean). Stage lines (`✓ simulate  1.02 s`)
//! go to stderr unless `--quiet`.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Timings of a run and the display policy.
pub struct Stages {
    quiet: bool,
    animate: bool,
    timings: Vec<(String, f64)>,
}

impl Stages {
    /// A run; `quiet` silences everything on stderr.
    pub fn new(quiet: bool) -> Self {
        Self {
            quiet,
            animate: !quiet && std::io::stderr().is_terminal(),
            timings: Vec::new(),
        }
    }

    /// True when progress bars may be drawn.
    pub fn animate(&self) -> bool {
        self.animate
    }

    /// Runs one stage with a spinner, records its time.
    pub fn run<T>(&mut self, name: &str, f: impl FnOnce(&ProgressBar) -> T) -> T {
        let bar = if self.animate {
            let b = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            b.set_style(
                ProgressStyle::with_template("{spinner} {msg} {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            b.set_message(name.to_string());
            b.enable_steady_tick(Duration::from_millis(120));
            b
        } else {
            ProgressBar::hidden()
        };
        let start = Instant::now();
        let out = f(&bar);
        let secs = start.elapsed().as_secs_f64();
        bar.finish_and_clear();
        if !self.quiet {
            eprintln!("✓ {name:<28} {secs:>7.2} s");
        }
        self.timings.push((name.to_string(), secs));
        out
    }

    /// A determinate bar for `len` steps inside a stage (hidden when not animating).
    pub fn bar(&self, len: u64, what: &str) -> ProgressBar {
        if !self.animate {
            return ProgressBar::hidden();
        }
        let b = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
        b.set_style(
            ProgressStyle::with_template("  {msg} {bar:30} {pos}/{len}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b.set_message(what.to_string());
        b
    }

    /// Stage name and seconds, in order.
    pub fn timings(&self) -> &[(String, f64)] {
        &self.timings
    }

    /// Whether stderr output is suppressed.
    pub fn quiet(&self) -> bool {
        self.quiet
    }
}
