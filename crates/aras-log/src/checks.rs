//! Checks that run row by row while a log streams in, in O(1) memory:
//! strictly increasing time, regular sampling, angle magnitudes (degree
//! detection) and torque saturation.

use std::fmt;

use serde::Serialize;

use crate::error::LogError;

/// How many steps the nominal step is the median of (see
/// [`ReadOptions::step_tolerance`](crate::ReadOptions::step_tolerance)).
pub const NOMINAL_WINDOW: usize = 4096;

/// Relative RMS step jitter above which [`Warning::Jitter`] is given
/// (0.1 % of the step: above the rounding of printed or epoch times).
pub const JITTER_WARN: f64 = 1e-3;

/// Sample rates below this (Hz) with whole-number steps make the reader ask
/// whether `t` is in seconds.
pub const MIN_PLAUSIBLE_RATE_HZ: f64 = 10.0;

/// Saturation spans kept per channel and extreme; more are only counted.
const MAX_SPANS: usize = 20;

/// A stretch of consecutive samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Span {
    /// Time of the first sample (s).
    pub t_start: f64,
    /// Time of the last sample (s).
    pub t_end: f64,
    /// Line of the first sample.
    pub line: u64,
    /// Number of samples.
    pub samples: usize,
}

/// Which extreme a saturated channel sits at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Extreme {
    /// The channel's largest value.
    Maximum,
    /// The channel's smallest value.
    Minimum,
}

/// Something suspicious that does not stop processing.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Warning {
    /// A torque sits flat at its extreme (actuator or sensor saturation).
    Saturation {
        /// Channel name (`tau1`, `tau2`, …).
        channel: String,
        /// Which extreme.
        extreme: Extreme,
        /// The flat value (N·m).
        value: f64,
        /// Where (at most 20 listed).
        spans: Vec<Span>,
        /// Spans beyond those listed.
        more_spans: usize,
    },
    /// Time stamps far from zero (a clock epoch): times are counted from
    /// the first row, and the logged values carry the rounding of f64 at
    /// their magnitude.
    TimeOffset {
        /// The first time stamp (s), subtracted from every row.
        offset_s: f64,
        /// Spacing of f64 values at that magnitude (s): the logged times
        /// are known to ± half of it.
        resolution_s: f64,
    },
    /// The time steps scatter around the nominal step by more than
    /// [`JITTER_WARN`] of it.
    Jitter {
        /// Nominal step (s).
        nominal_s: f64,
        /// RMS deviation of a step from the nominal (or a whole multiple of
        /// it) (s).
        rms_s: f64,
        /// Largest such deviation (s).
        max_s: f64,
    },
    /// Resampling interpolated across gaps in the time stamps (each no
    /// longer than the stated limit).
    GapsBridged {
        /// Gaps bridged.
        count: usize,
        /// The longest (s).
        longest_s: f64,
        /// The first few, one per line of the message.
        list: Vec<String>,
    },
    /// Period averaging leaves a large part of the record unused.
    AveragingUnused {
        /// Periods per averaged block.
        periods_per_block: usize,
        /// Whole blocks averaged.
        blocks: usize,
        /// Fraction of the samples not averaged (settling and tail).
        unused: f64,
    },
    /// Isolated samples far off their neighbours, kept, dropped or
    /// repaired as the options say.
    Glitches {
        /// What was done with them.
        action: String,
        /// How many were found.
        count: usize,
        /// The first few, one per line of the message.
        list: Vec<String>,
    },
    /// A periodic record's torque periods differ notably (only reported).
    PeriodSpread {
        /// Channel name.
        channel: String,
        /// Largest RMS deviation of a period from the average, relative to
        /// the average period's standard deviation.
        relative: f64,
    },
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Warning::Saturation {
                channel,
                extreme,
                value,
                spans,
                more_spans,
            } => {
                let which = match extreme {
                    Extreme::Maximum => "maximum",
                    Extreme::Minimum => "minimum",
                };
                write!(
                    f,
                    "{channel} sits flat at its {which} {value} N·m (saturation?) at t ="
                )?;
                for (i, s) in spans.iter().enumerate() {
                    let sep = if i == 0 { " " } else { ", " };
                    write!(
                        f,
                        "{sep}{:.4}–{:.4} s ({} samples from line {})",
                        s.t_start, s.t_end, s.samples, s.line
                    )?;
                }
                if *more_spans > 0 {
                    write!(f, " and {more_spans} more spans")?;
                }
                write!(
                    f,
                    "; samples there understate the true torque: exclude them or lower the excitation"
                )
            }
            Warning::TimeOffset {
                offset_s,
                resolution_s,
            } => write!(
                f,
                "time stamps start at t = {offset_s} s (a clock epoch?): times are counted from \
                 the first row; at that magnitude f64 resolves only {:.3} µs, so every logged \
                 time carries up to ±{:.3} µs of rounding (log times relative to the start for \
                 full precision)",
                resolution_s * 1e6,
                resolution_s * 0.5e6
            ),
            Warning::Jitter {
                nominal_s,
                rms_s,
                max_s,
            } => write!(
                f,
                "time stamps jitter: steps deviate from the nominal {} s by {:.3} ms RMS (up to \
                 {:.3} ms); the processing interpolates onto a uniform grid (or use --resample to \
                 do it explicitly, with gaps reported)",
                crate::error::sig(*nominal_s),
                rms_s * 1e3,
                max_s * 1e3
            ),
            Warning::AveragingUnused {
                periods_per_block,
                blocks,
                unused,
            } => write!(
                f,
                "period averaging uses {blocks} block(s) of {periods_per_block} period(s) and \
                 leaves {:.1} % of the record unused: the period is not a whole number of \
                 samples; check the period (--period) and the time unit and rate of the log",
                unused * 100.0
            ),
            Warning::GapsBridged {
                count,
                longest_s,
                list,
            } => {
                write!(
                    f,
                    "{count} gap(s) in the time stamps interpolated by the resampling (longest \
                     {} s):",
                    crate::error::sig(*longest_s)
                )?;
                for l in list {
                    write!(f, "\n  {l}")?;
                }
                Ok(())
            }
            Warning::Glitches {
                action,
                count,
                list,
            } => {
                write!(f, "{count} isolated glitch(es) {action}:")?;
                for l in list {
                    write!(f, "\n  {l}")?;
                }
                Ok(())
            }
            Warning::PeriodSpread { channel, relative } => write!(
                f,
                "{channel}: periods differ from their average by up to {:.1}% RMS (noise or \
                 non-periodic disturbance)",
                relative * 100.0
            ),
        }
    }
}

/// Tracks runs of samples flat at the running maximum of `sign·value`.
#[derive(Debug, Clone)]
struct FlatAtExtreme {
    sign: f64,
    value: f64,
    current: Option<Span>,
    last_index: usize,
    runs: Vec<Span>,
    more: usize,
}

impl FlatAtExtreme {
    fn new(sign: f64) -> Self {
        Self {
            sign,
            value: f64::NEG_INFINITY,
            current: None,
            last_index: 0,
            runs: Vec::new(),
            more: 0,
        }
    }

    fn close(&mut self, min_len: usize) {
        if let Some(s) = self.current.take()
            && s.samples >= min_len
        {
            if self.runs.len() < MAX_SPANS {
                self.runs.push(s);
            } else {
                self.more += 1;
            }
        }
    }

    #[inline]
    fn push(&mut self, raw: f64, index: usize, t: f64, line: u64, min_len: usize) {
        let v = self.sign * raw;
        // "Flat" means equal up to rounding of the value itself.
        let tol = 1e-12 * self.value.abs().max(1.0);
        if self.value == f64::NEG_INFINITY || v > self.value + tol {
            self.value = v;
            self.runs.clear();
            self.more = 0;
            self.current = Some(Span {
                t_start: t,
                t_end: t,
                line,
                samples: 1,
            });
        } else if v >= self.value - tol {
            match &mut self.current {
                Some(s) if self.last_index + 1 == index => {
                    s.t_end = t;
                    s.samples += 1;
                }
                _ => {
                    self.close(min_len);
                    self.current = Some(Span {
                        t_start: t,
                        t_end: t,
                        line,
                        samples: 1,
                    });
                }
            }
        } else {
            self.close(min_len);
        }
        self.last_index = index;
    }

    fn finish(mut self, min_len: usize) -> Option<(f64, Vec<Span>, usize)> {
        self.close(min_len);
        (!self.runs.is_empty()).then_some((self.sign * self.value, self.runs, self.more))
    }
}

/// Range of an angle channel and where its largest magnitude is.
#[derive(Debug, Clone, Copy)]
struct AngleStat {
    min: f64,
    max: f64,
    max_abs: f64,
    line_of_max_abs: u64,
}

/// Largest deviation from the nominal step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepDeviation {
    /// Line of the sample ending the step.
    pub line: u64,
    /// Time of that sample (s).
    pub t: f64,
    /// The step (s).
    pub step_s: f64,
    /// `step / nominal`.
    pub ratio: f64,
}

/// Running checks over all rows of one log.
#[derive(Debug, Clone)]
pub(crate) struct Checks {
    pub rows: usize,
    first_t: f64,
    prev_t: f64,
    nominal: Option<f64>,
    pending: Vec<(f64, f64, u64)>,
    median: Option<f64>,
    intervals: f64,
    /// Least-squares line of `t − t₀` against the whole-interval index `k`
    /// (Welford's running means and co-moments; the first row is `(0, 0)`).
    fit: StepFit,
    jitter_ss: f64,
    jitter_n: usize,
    jitter_max: f64,
    worst: Option<StepDeviation>,
    angles: Vec<AngleStat>,
    tau_range: Vec<[f64; 2]>,
    flat: Vec<[FlatAtExtreme; 2]>,
    saturation_samples: usize,
}

/// Results of the finished checks.
pub(crate) struct CheckResult {
    pub nominal_step: f64,
    pub worst_step: Option<StepDeviation>,
    pub duration: f64,
    pub jitter_rms: f64,
    pub jitter_max: f64,
    pub theta_range: Vec<[f64; 2]>,
    pub tau_range: Vec<[f64; 2]>,
    pub warnings: Vec<Warning>,
}

impl Checks {
    pub fn new(nominal: Option<f64>, saturation_samples: usize, joints: usize) -> Self {
        let angle = AngleStat {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            max_abs: 0.0,
            line_of_max_abs: 0,
        };
        let flat = || [FlatAtExtreme::new(1.0), FlatAtExtreme::new(-1.0)];
        Self {
            rows: 0,
            first_t: 0.0,
            prev_t: f64::NEG_INFINITY,
            nominal,
            pending: Vec::new(),
            median: nominal,
            intervals: 0.0,
            fit: StepFit::default(),
            jitter_ss: 0.0,
            jitter_n: 0,
            jitter_max: 0.0,
            worst: None,
            angles: vec![angle; joints],
            tau_range: vec![[f64::INFINITY, f64::NEG_INFINITY]; joints],
            flat: (0..joints).map(|_| flat()).collect(),
            saturation_samples,
        }
    }

    fn judge_step(&mut self, step: f64, t: f64, line: u64, nominal: f64) {
        let ratio = step / nominal;
        // Whole nominal intervals this step spans (1, or more across a gap
        // when the tolerance lets gaps through), and its deviation from them.
        let whole = ratio.round().max(1.0);
        self.intervals += whole;
        self.fit.push(self.intervals, t - self.first_t);
        let dev_s = (step - whole * nominal).abs();
        self.jitter_ss += dev_s * dev_s;
        self.jitter_n += 1;
        self.jitter_max = self.jitter_max.max(dev_s);
        let dev = (ratio - 1.0).abs();
        if self.worst.is_none_or(|w| dev > (w.ratio - 1.0).abs()) {
            self.worst = Some(StepDeviation {
                line,
                t,
                step_s: step,
                ratio,
            });
        }
    }

    fn settle_nominal(&mut self) {
        if self.nominal.is_some() || self.pending.is_empty() {
            return;
        }
        let mut steps: Vec<f64> = self.pending.iter().map(|p| p.0).collect();
        let mid = steps.len() / 2;
        let (_, m, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
        let nominal = *m;
        self.nominal = Some(nominal);
        self.median = Some(nominal);
        for (step, t, line) in std::mem::take(&mut self.pending) {
            self.judge_step(step, t, line, nominal);
        }
    }

    /// Checks one row. `t_column` is for messages.
    #[inline]
    pub fn row(
        &mut self,
        file: &str,
        line: u64,
        t_column: usize,
        t: f64,
        theta: &[f64],
        tau: &[f64],
    ) -> Result<(), LogError> {
        if self.rows == 0 {
            self.first_t = t;
        } else {
            if t <= self.prev_t {
                return Err(LogError::TimeNotIncreasing {
                    file: file.into(),
                    line,
                    column: t_column,
                    previous: self.prev_t,
                    t,
                });
            }
            let step = t - self.prev_t;
            match self.nominal {
                Some(n) => self.judge_step(step, t, line, n),
                None => {
                    self.pending.push((step, t, line));
                    if self.pending.len() >= NOMINAL_WINDOW {
                        self.settle_nominal();
                    }
                }
            }
        }
        self.prev_t = t;
        for (a, &v) in self.angles.iter_mut().zip(theta) {
            a.min = a.min.min(v);
            a.max = a.max.max(v);
            if v.abs() > a.max_abs {
                a.max_abs = v.abs();
                a.line_of_max_abs = line;
            }
        }
        for ((r, flat), &v) in self.tau_range.iter_mut().zip(&mut self.flat).zip(tau) {
            r[0] = r[0].min(v);
            r[1] = r[1].max(v);
            for f in flat {
                f.push(v, self.rows, t, line, self.saturation_samples);
            }
        }
        self.rows += 1;
        Ok(())
    }

    /// End-of-log checks. `check_degrees` is off for encoder-derived angles.
    pub fn finish(
        mut self,
        file: &str,
        min_rows: usize,
        step_tolerance: f64,
        check_degrees: bool,
        unit_given: bool,
        given_step: bool,
    ) -> Result<CheckResult, LogError> {
        if self.rows < min_rows {
            return Err(LogError::TooFewRows {
                file: file.into(),
                rows: self.rows,
                needed: min_rows,
            });
        }
        self.settle_nominal();
        let median = self.median.unwrap_or(f64::NAN);
        // The nominal step: the slope of the least-squares line of the time
        // stamps against their whole-interval index. Every stamp's jitter
        // enters with weight ~1/n (the span over the intervals would carry
        // the last stamp's jitter whole), and the rounding of the median
        // does not enter, unlike the median of the steps alone.
        let span = self.prev_t - self.first_t;
        let nominal = match self.fit.slope() {
            Some(s) if !given_step && self.intervals > 0.0 => s,
            _ => median,
        };
        if !unit_given
            && nominal.is_finite()
            && 1.0 / nominal < MIN_PLAUSIBLE_RATE_HZ
            && median >= 1.0
            && (median - median.round()).abs() <= 1e-6 * median
        {
            let (unit, flag) = if median < 1e3 {
                ("milliseconds", "ms")
            } else if median < 1e6 {
                ("microseconds", "us")
            } else {
                ("nanoseconds", "ns")
            };
            return Err(LogError::TimeUnit {
                file: file.into(),
                step: median,
                unit,
                flag,
            });
        }
        if check_degrees {
            for (c, a) in self.angles.iter().enumerate() {
                crate::units::check_angle_column(
                    file,
                    &format!("theta{}", c + 1),
                    [a.min, a.max, a.max_abs],
                    a.line_of_max_abs,
                )?;
            }
        }
        if let Some(w) = self.worst
            && (w.ratio - 1.0).abs() > step_tolerance
        {
            return Err(LogError::IrregularSampling {
                file: file.into(),
                line: w.line,
                t: w.t,
                step: w.step_s,
                ratio: w.ratio,
                nominal: median,
                tolerance: step_tolerance,
            });
        }
        let mut warnings = Vec::new();
        let jitter_rms = if self.jitter_n > 0 {
            (self.jitter_ss / self.jitter_n as f64).sqrt()
        } else {
            0.0
        };
        if jitter_rms > JITTER_WARN * nominal {
            warnings.push(Warning::Jitter {
                nominal_s: nominal,
                rms_s: jitter_rms,
                max_s: self.jitter_max,
            });
        }
        let flat = std::mem::take(&mut self.flat);
        for (c, pair) in flat.into_iter().enumerate() {
            let [hi, lo] = pair;
            // A constant channel is flat at both extremes: report it once.
            let constant = self.tau_range[c][0] == self.tau_range[c][1];
            for (tracker, extreme) in [(hi, Extreme::Maximum), (lo, Extreme::Minimum)] {
                if constant && extreme == Extreme::Minimum {
                    continue;
                }
                if let Some((value, spans, more)) = tracker.finish(self.saturation_samples) {
                    warnings.push(Warning::Saturation {
                        channel: format!("tau{}", c + 1),
                        extreme,
                        value,
                        spans,
                        more_spans: more,
                    });
                }
            }
        }
        Ok(CheckResult {
            nominal_step: nominal,
            worst_step: self.worst,
            duration: span,
            jitter_rms,
            jitter_max: self.jitter_max,
            theta_range: self.angles.iter().map(|a| [a.min, a.max]).collect(),
            tau_range: self.tau_range,
            warnings,
        })
    }
}

/// A running least-squares line `t = a + h k` (Welford's updates of the
/// means and co-moments: no cancellation however long the log).
#[derive(Debug, Clone, Copy)]
struct StepFit {
    n: f64,
    mean_k: f64,
    mean_t: f64,
    c_kt: f64,
    m_kk: f64,
}

impl Default for StepFit {
    /// The first row: `k = 0` at `t − t₀ = 0`.
    fn default() -> Self {
        Self {
            n: 1.0,
            mean_k: 0.0,
            mean_t: 0.0,
            c_kt: 0.0,
            m_kk: 0.0,
        }
    }
}

impl StepFit {
    fn push(&mut self, k: f64, t: f64) {
        self.n += 1.0;
        let dk = k - self.mean_k;
        self.mean_k += dk / self.n;
        let dt = t - self.mean_t;
        self.mean_t += dt / self.n;
        self.c_kt += dk * (t - self.mean_t);
        self.m_kk += dk * (k - self.mean_k);
    }

    /// The slope `h`, once two distinct indices were seen.
    fn slope(&self) -> Option<f64> {
        (self.m_kk > 0.0).then(|| self.c_kt / self.m_kk)
    }
}

#[cfg(test)]
mod step_fit_tests {
    use super::StepFit;

    /// The slope of an exact line, and of a line with alternating jitter
    /// (where the span over the intervals is off by the last stamp's
    /// jitter over n): least squares is within 1e-9 of the step.
    #[test]
    fn slope_of_lines_with_and_without_jitter() {
        let mut exact = StepFit::default();
        let mut jittered = StepFit::default();
        let h = 1e-3;
        let n = 3000;
        for i in 1..n {
            let k = i as f64;
            exact.push(k, k * h);
            jittered.push(k, k * h + if i % 2 == 1 { 2e-4 } else { 0.0 });
        }
        assert!((exact.slope().unwrap() - h).abs() < 1e-15);
        let span_over_intervals = ((n - 1) as f64 * h + 2e-4) / (n - 1) as f64;
        assert!((span_over_intervals - h).abs() > 6e-8);
        assert!((jittered.slope().unwrap() - h).abs() < 1e-9);
        assert_eq!(StepFit::default().slope(), None);
    }
}
