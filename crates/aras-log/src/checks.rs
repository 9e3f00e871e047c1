//! Checks that run row by row while a log streams in, in O(1) memory:
//! strictly increasing time, regular sampling, angle magnitudes (degree
//! detection) and torque saturation.

use std::fmt;

use serde::Serialize;

use crate::error::LogError;

/// How many steps the nominal step is the median of (see
/// [`ReadOptions::step_tolerance`](crate::ReadOptions::step_tolerance)).
pub const NOMINAL_WINDOW: usize = 4096;

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
        /// Channel name (`tau1` or `tau2`).
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
    worst: Option<StepDeviation>,
    angles: [AngleStat; 2],
    tau_range: [[f64; 2]; 2],
    flat: [[FlatAtExtreme; 2]; 2],
    saturation_samples: usize,
}

/// Results of the finished checks.
pub(crate) struct CheckResult {
    pub nominal_step: f64,
    pub worst_step: Option<StepDeviation>,
    pub duration: f64,
    pub theta_range: [[f64; 2]; 2],
    pub tau_range: [[f64; 2]; 2],
    pub warnings: Vec<Warning>,
}

impl Checks {
    pub fn new(nominal: Option<f64>, saturation_samples: usize) -> Self {
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
            worst: None,
            angles: [angle; 2],
            tau_range: [[f64::INFINITY, f64::NEG_INFINITY]; 2],
            flat: [flat(), flat()],
            saturation_samples,
        }
    }

    fn judge_step(&mut self, step: f64, t: f64, line: u64, nominal: f64) {
        let ratio = step / nominal;
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
        theta: [f64; 2],
        tau: [f64; 2],
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
        for (a, &v) in self.angles.iter_mut().zip(&theta) {
            a.min = a.min.min(v);
            a.max = a.max.max(v);
            if v.abs() > a.max_abs {
                a.max_abs = v.abs();
                a.line_of_max_abs = line;
            }
        }
        for ((r, flat), &v) in self.tau_range.iter_mut().zip(&mut self.flat).zip(&tau) {
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
    ) -> Result<CheckResult, LogError> {
        if self.rows < min_rows {
            return Err(LogError::TooFewRows {
                file: file.into(),
                rows: self.rows,
                needed: min_rows,
            });
        }
        self.settle_nominal();
        let nominal = self.nominal.unwrap_or(f64::NAN);
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
                nominal,
                tolerance: step_tolerance,
            });
        }
        let mut warnings = Vec::new();
        let [f1, f2] = self.flat;
        for (c, pair) in [f1, f2].into_iter().enumerate() {
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
            duration: self.prev_t - self.first_t,
            theta_range: [
                [self.angles[0].min, self.angles[0].max],
                [self.angles[1].min, self.angles[1].max],
            ],
            tau_range: self.tau_range,
            warnings,
        })
    }
}
