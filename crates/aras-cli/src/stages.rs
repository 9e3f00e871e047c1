//! Stage timing and progress display.
//!
//! Each stage is timed; its wall-clock seconds go to the report and (unless
//! `--reproducible`) to `summary.json`. A spinner runs while a stage works
//! when stderr is a terminal and `--quiet` is not given; otherwise nothing
//! animated is drawn (logs stay clean). Stage lines (`✓ simulate  1.02 s`)
//! go to stderr unless `--quiet`. A stage that knows its total (a streamed
//! log's rows, estimated from the file size) turns its spinner into a bar
//! with the fraction done and the time left ([`determinate`],
//! [`progress_text`]); libraries only report counts through a callback.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Timings of a run and the display policy.
pub struct Stages {
    quiet: bool,
    animate: bool,
    timings: Vec<(String, f64)>,
    /// The stage [`Stages::begin`] started, its start and spinner.
    running: Option<(String, Instant, ProgressBar)>,
}

impl Stages {
    /// A run; `quiet` silences everything on stderr.
    pub fn new(quiet: bool) -> Self {
        Self {
            quiet,
            animate: !quiet && std::io::stderr().is_terminal(),
            timings: Vec::new(),
            running: None,
        }
    }

    /// True when progress bars may be drawn.
    pub fn animate(&self) -> bool {
        self.animate
    }

    /// Runs one stage with a spinner, records its time.
    pub fn run<T>(&mut self, name: &str, f: impl FnOnce(&ProgressBar) -> T) -> T {
        self.begin(name);
        let bar = self.running.as_ref().map(|r| r.2.clone());
        let out = f(bar.as_ref().unwrap_or(&ProgressBar::hidden()));
        self.end();
        out
    }

    /// Starts a stage (a spinner), ending the one running: for a library
    /// recipe that reports its stages as they start through a callback.
    pub fn begin(&mut self, name: &str) {
        self.end();
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
        self.running = Some((name.to_string(), Instant::now(), bar));
    }

    /// Ends the stage [`Stages::begin`] started (if any): its line and
    /// time.
    pub fn end(&mut self) {
        let Some((name, start, bar)) = self.running.take() else {
            return;
        };
        let secs = start.elapsed().as_secs_f64();
        bar.finish_and_clear();
        if !self.quiet {
            eprintln!("✓ {name:<28} {secs:>7.2} s");
        }
        self.timings.push((name, secs));
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

/// Turns a stage's spinner into a bar over `total` units (the caller sets
/// the position and, with [`progress_text`], the message).
pub fn determinate(bar: &ProgressBar, total: u64) {
    bar.set_length(total.max(1));
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{bar:30}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
}

/// How far a long stage is: `done` of `total` `unit`s (≈, the total being
/// an estimate), the percentage and the time left at the rate so far
/// (`elapsed` since the stage started); only the count when the total is
/// unknown, and no time left before the first unit or once the estimate
/// is reached.
pub fn progress_text(done: u64, total: Option<u64>, unit: &str, elapsed: Duration) -> String {
    let Some(total) = total.filter(|&t| t > 0) else {
        return format!("{done} {unit}");
    };
    let fraction = (done as f64 / total as f64).min(1.0);
    let mut s = format!(
        "{done} / ≈ {total} {unit} ({:.0} %)",
        (100.0 * fraction).floor()
    );
    if done > 0 && done < total {
        let left = elapsed.as_secs_f64() * (total - done) as f64 / done as f64;
        let d = duration_text(left);
        let about = if d.starts_with('<') { "" } else { "≈ " };
        s.push_str(&format!(", {about}{d} left"));
    }
    s
}

/// A duration in words for people: `< 1 s`, `42 s`, `3 min 05 s`,
/// `1 h 02 min`.
pub fn duration_text(secs: f64) -> String {
    if !secs.is_finite() || secs < 1.0 {
        return "< 1 s".into();
    }
    let s = secs.round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {:02} s", s / 60, s % 60),
        _ => format!("{} h {:02} min", s / 3600, (s % 3600) / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_has_a_fraction_and_the_time_left() {
        let t = |s| Duration::from_secs(s);
        assert_eq!(
            progress_text(250_000, Some(1_000_000), "rows", t(10)),
            "250000 / ≈ 1000000 rows (25 %), ≈ 30 s left"
        );
        assert_eq!(
            progress_text(100, Some(1_000), "rows", t(20)),
            "100 / ≈ 1000 rows (10 %), ≈ 3 min 00 s left"
        );
        // The estimate exceeded: no time left, never past 100 %.
        assert_eq!(
            progress_text(1_200, Some(1_000), "rows", t(5)),
            "1200 / ≈ 1000 rows (100 %)"
        );
        assert_eq!(
            progress_text(0, Some(1_000), "rows", t(0)),
            "0 / ≈ 1000 rows (0 %)"
        );
        assert_eq!(progress_text(42, None, "rows", t(3)), "42 rows");
        assert_eq!(duration_text(0.2), "< 1 s");
        assert_eq!(duration_text(3725.0), "1 h 02 min");
    }

    #[test]
    fn a_stage_bar_becomes_determinate() {
        let bar = ProgressBar::hidden();
        determinate(&bar, 5_000);
        bar.set_position(1_000);
        assert_eq!(bar.length(), Some(5_000));
        assert_eq!(bar.position(), 1_000);
    }
}
