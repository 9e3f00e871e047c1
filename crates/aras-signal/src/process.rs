//! Raw log → clean, aligned samples θ, θ̇, θ̈, X, Ẋ, Ẍ, τ (spec §6).
//!
//! Order of operations, and why:
//! 1. **Period averaging** (if a period is known) on the raw data: averaging
//!    is linear, so doing it first cuts the work by the number of periods
//!    and yields one periodic record, which step 2–3 can treat exactly.
//! 2. **Zero-phase low-pass** of θ and τ (and logged θ̇, θ̈) with the same
//!    Butterworth filter: circular (`|H|²` in the frequency domain) for a
//!    periodic record, scipy-style `filtfilt` otherwise.
//! 3. **Derivatives** of the filtered θ ([`DerivativeMethod`]).
//! 4. **Kinematics**: `X = forward(θ)` (assembly mode `+`, spec (6)–(7)),
//!    `Ẋ = J⁻¹θ̇`, `Ẍ = J⁻¹(θ̈ − J̇Ẋ)` (spec (8)–(11)). Going through the
//!    Jacobian rather than differentiating X keeps `θ̇ = J Ẋ` exact sample by
//!    sample, so joint-space terms (friction on θ̇) and task-space terms agree,
//!    and logged θ̇ columns are used as they are.

use nalgebra::Vector2;
use serde::Serialize;

use crate::derivative::{DerivativeMethod, derivatives, resolve, spectral_with};
use crate::error::ProcessError;
use crate::fourier::Fourier;
use crate::log::{Log, Warning};
use crate::periods::average_periods;
use crate::{Butterworth, Sos};

/// Low-pass filter settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FilterSpec {
    /// Butterworth order (1–32; forward–backward doubles the attenuation).
    pub order: usize,
    /// −3 dB cut-off of one pass (Hz); the zero-phase pair is −6 dB there.
    pub cutoff_hz: f64,
}

impl Default for FilterSpec {
    /// Order 4 at 10 Hz: 20× the highest excitation harmonic (5 × 0.1 Hz,
    /// spec (74)) and 4× the fastest validation trajectory (2.5 Hz, Table 2),
    /// so the dynamics pass untouched while sensor noise is cut.
    fn default() -> Self {
        Self {
            order: 4,
            cutoff_hz: 10.0,
        }
    }
}

/// Where the excitation period comes from.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub enum PeriodSource {
    /// `excitation.period_s` of the sidecar if present, else no averaging.
    #[default]
    FromSidecar,
    /// This period (s).
    Seconds(f64),
    /// No period averaging.
    Off,
}

/// Options of [`process`]. `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProcessOptions {
    /// Low-pass filter; `None` for no filtering (default [`FilterSpec::default`]).
    pub filter: Option<FilterSpec>,
    /// Period for averaging (default: from the sidecar).
    pub period: PeriodSource,
    /// Seconds dropped at the start before averaging (default 0).
    pub settling_s: f64,
    /// Largest accepted RMS deviation of one period of θ from the average,
    /// relative to the average period's standard deviation (default 0.1).
    /// Torque periods are only reported (noise makes them spread more).
    pub max_period_spread: f64,
    /// Derivative method (default [`DerivativeMethod::Auto`]).
    pub derivative: DerivativeMethod,
    /// Use the log's `dtheta`/`ddtheta` columns when present instead of
    /// differentiating θ (default false: the paper differentiates encoder
    /// angles).
    pub use_logged_derivatives: bool,
}

impl Default for ProcessOptions {
    fn default() -> Self {
        Self {
            filter: Some(FilterSpec::default()),
            period: PeriodSource::FromSidecar,
            settling_s: 0.0,
            max_period_spread: 0.1,
            derivative: DerivativeMethod::Auto,
            use_logged_derivatives: false,
        }
    }
}

/// Processed samples, structure-of-arrays, SI units (rad, rad/s, rad/s², N·m).
/// All vectors have the same length.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Samples {
    /// Time (s).
    pub t: Vec<f64>,
    /// Joint angles θ1, θ2.
    pub theta: [Vec<f64>; 2],
    /// Joint rates θ̇.
    pub theta_dot: [Vec<f64>; 2],
    /// Joint accelerations θ̈.
    pub theta_ddot: [Vec<f64>; 2],
    /// Task pose X = [φ, γ].
    pub x: [Vec<f64>; 2],
    /// Task rates Ẋ.
    pub x_dot: [Vec<f64>; 2],
    /// Task accelerations Ẍ.
    pub x_ddot: [Vec<f64>; 2],
    /// Joint torques τ1, τ2.
    pub tau: [Vec<f64>; 2],
}

impl Samples {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True if there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// The filter that was applied.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FilterSummary {
    /// Butterworth order.
    pub order: usize,
    /// Cut-off (Hz).
    pub cutoff_hz: f64,
    /// `"zero-phase forward-backward (scipy sosfiltfilt)"` or the periodic form.
    pub kind: String,
}

/// The period averaging that was done.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodSummary {
    /// Period (s).
    pub period_s: f64,
    /// Periods per averaged block: the smallest `k` with `k·P·fs` a whole
    /// number of samples (1 when a period is; 7 for 0.7 Hz at 1 kHz). The
    /// output is one block, i.e. `k` periods.
    pub periods_per_block: usize,
    /// Samples per block (the output's length before derivative edge loss).
    pub samples_per_block: usize,
    /// Blocks averaged.
    pub blocks_averaged: usize,
    /// Whole periods averaged (`blocks_averaged · periods_per_block`).
    pub periods_averaged: usize,
    /// Samples dropped for settling.
    pub settling_samples: usize,
    /// Samples after the last whole period.
    pub tail_samples: usize,
    /// Relative RMS spread of θ1, θ2, τ1, τ2 (see [`crate::PeriodAverage`]).
    pub spread_relative: [f64; 4],
    /// Absolute RMS spread of θ1, θ2 (rad), τ1, τ2 (N·m).
    pub spread_rms: [f64; 4],
}

/// What [`process`] did, for the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProcessSummary {
    /// Rows in the log.
    pub input_samples: usize,
    /// Samples out.
    pub output_samples: usize,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Filter, if any.
    pub filter: Option<FilterSummary>,
    /// Period averaging, if any.
    pub periods: Option<PeriodSummary>,
    /// Input samples not represented in the output: settling, tail, and the
    /// derivative's edge loss.
    pub samples_dropped: usize,
    /// Derivative method actually used.
    pub derivative: DerivativeMethod,
    /// `"differentiated θ"` or `"logged dtheta/ddtheta columns"`.
    pub derivative_source: String,
    /// Where angles and torques came from (from the log reader).
    pub angle_source: String,
    /// Where torques came from.
    pub torque_source: String,
}

/// The result of [`process`].
#[derive(Debug, Clone, PartialEq)]
pub struct Processed {
    /// The samples.
    pub samples: Samples,
    /// What was done.
    pub summary: ProcessSummary,
    /// Notes (the log's and processing's).
    pub notes: Vec<String>,
    /// Warnings (the log's and processing's).
    pub warnings: Vec<Warning>,
}

const CHANNELS: [&str; 4] = ["theta1", "theta2", "tau1", "tau2"];

/// Turns a validated log into samples ready for identification.
pub fn process(
    log: &Log,
    opts: &ProcessOptions,
    geometry: &aras_kin::Geometry,
) -> Result<Processed, ProcessError> {
    let dt = log.summary.nominal_step_s;
    let fs = 1.0 / dt;
    let mut notes = log.notes.clone();
    let mut warnings = log.warnings.clone();
    if !(opts.max_period_spread.is_finite() && opts.max_period_spread > 0.0) {
        return Err(ProcessError::InvalidOption {
            name: "max_period_spread",
            value: opts.max_period_spread.to_string(),
            reason: "give a positive relative RMS such as 0.1".into(),
        });
    }

    // Channels: θ1, θ2, τ1, τ2, then logged θ̇, θ̈ if used.
    let logged_vel = opts
        .use_logged_derivatives
        .then_some(log.theta_dot.as_ref())
        .flatten();
    let logged_acc = logged_vel.and(log.theta_ddot.as_ref());
    if !opts.use_logged_derivatives && (log.theta_dot.is_some() || log.theta_ddot.is_some()) {
        notes.push(
            "logged derivative columns ignored; θ̇, θ̈ differentiated from θ \
             (ProcessOptions::use_logged_derivatives)"
                .into(),
        );
    }
    let mut raw: Vec<&[f64]> = vec![&log.theta[0], &log.theta[1], &log.tau[0], &log.tau[1]];
    if let Some(v) = logged_vel {
        raw.extend([v[0].as_slice(), v[1].as_slice()]);
    }
    if let Some(a) = logged_acc {
        raw.extend([a[0].as_slice(), a[1].as_slice()]);
    }

    // 1. Period averaging.
    let period = match opts.period {
        PeriodSource::FromSidecar => log.sidecar.excitation.period_s,
        PeriodSource::Seconds(p) => Some(p),
        PeriodSource::Off => None,
    };
    let (mut data, t, period_summary, mut dropped) = match period {
        Some(p) => {
            let avg = average_periods(&raw, dt, p, opts.settling_s)?;
            for (c, channel) in CHANNELS.iter().enumerate().take(2) {
                if avg.spread_relative[c] > opts.max_period_spread {
                    let k = avg.worst_block[c];
                    let i0 = avg.start + k * avg.samples_per_block;
                    return Err(ProcessError::PeriodsDisagree {
                        channel,
                        index: k,
                        t_start: log.t[i0],
                        t_end: log.t[i0 + avg.samples_per_block - 1],
                        relative: avg.spread_relative[c],
                        limit: opts.max_period_spread,
                        period_s: p,
                    });
                }
            }
            for (c, channel) in CHANNELS.iter().enumerate().skip(2) {
                if avg.spread_relative[c] > opts.max_period_spread {
                    warnings.push(Warning::PeriodSpread {
                        channel: (*channel).into(),
                        relative: avg.spread_relative[c],
                    });
                }
            }
            let t = log.t[avg.start..avg.start + avg.samples_per_block].to_vec();
            let summary = PeriodSummary {
                period_s: p,
                periods_per_block: avg.periods_per_block,
                samples_per_block: avg.samples_per_block,
                blocks_averaged: avg.blocks,
                periods_averaged: avg.periods(),
                settling_samples: avg.start,
                tail_samples: avg.tail,
                spread_relative: std::array::from_fn(|c| avg.spread_relative[c]),
                spread_rms: std::array::from_fn(|c| avg.spread_rms[c]),
            };
            let dropped = log.len() - avg.samples_per_block * avg.blocks;
            (avg.channels, t, Some(summary), dropped)
        }
        None => (
            raw.iter().map(|c| c.to_vec()).collect::<Vec<_>>(),
            log.t.clone(),
            None,
            0,
        ),
    };
    let periodic = period_summary.is_some();
    let n = t.len();
    let mut fourier = periodic.then(|| Fourier::new(n));

    // 2. Zero-phase low-pass, the same filter on every channel.
    let filter_summary = match opts.filter {
        None => None,
        Some(spec) => {
            let sos = Butterworth::lowpass(spec.order, spec.cutoff_hz, fs).map_err(|source| {
                ProcessError::Filter {
                    context: format!("designing the low-pass for {}", log.name),
                    source,
                }
            })?;
            filter_all(&sos, spec, fs, &mut data, fourier.as_mut(), &log.name)?;
            Some(FilterSummary {
                order: spec.order,
                cutoff_hz: spec.cutoff_hz,
                kind: if periodic {
                    "zero-phase, periodic (|H|² applied to the averaged period's spectrum)".into()
                } else {
                    format!(
                        "zero-phase forward-backward (scipy sosfiltfilt, odd padding of {} samples)",
                        padlen(&sos, spec, fs, n)
                    )
                },
            })
        }
    };

    // 3. Derivatives.
    let method = resolve(opts.derivative, periodic);
    let (theta_dot, theta_ddot, edge, source) = match logged_vel {
        Some(_) => {
            let vel = [data[4].clone(), data[5].clone()];
            let acc = if logged_acc.is_some() {
                (data[6].clone(), data[7].clone(), 0)
            } else {
                let d0 = derivatives(&vel[0], dt, method, periodic)?;
                let d1 = derivatives(&vel[1], dt, method, periodic)?;
                (d0.first, d1.first, d0.edge)
            };
            let e = acc.2;
            let vel = vel.map(|v| v[e..n - e].to_vec());
            (vel, [acc.0, acc.1], e, "logged dtheta/ddtheta columns")
        }
        None => {
            let d = match (&mut fourier, method) {
                (Some(f), DerivativeMethod::Spectral) => {
                    let mut out = Vec::new();
                    for ch in &data[..2] {
                        let (mut a, mut b) = (ch.clone(), ch.clone());
                        spectral_with(f, &mut a, &mut b, dt);
                        out.push((a, b, 0));
                    }
                    out
                }
                _ => {
                    let mut out = Vec::new();
                    for ch in &data[..2] {
                        let d = derivatives(ch, dt, method, periodic)?;
                        out.push((d.first, d.second, d.edge));
                    }
                    out
                }
            };
            let e = d[0].2;
            let mut it = d.into_iter();
            let (a0, b0, _) = it.next().expect("two channels");
            let (a1, b1, _) = it.next().expect("two channels");
            ([a0, a1], [b0, b1], e, "differentiated θ")
        }
    };
    dropped += 2 * edge;
    let keep = edge..n - edge;

    // 4. Kinematics.
    let m = keep.len();
    let mut s = Samples {
        t: t[keep.clone()].to_vec(),
        theta: [
            data[0][keep.clone()].to_vec(),
            data[1][keep.clone()].to_vec(),
        ],
        theta_dot,
        theta_ddot,
        x: [vec![0.0; m], vec![0.0; m]],
        x_dot: [vec![0.0; m], vec![0.0; m]],
        x_ddot: [vec![0.0; m], vec![0.0; m]],
        tau: [data[2][keep.clone()].to_vec(), data[3][keep].to_vec()],
    };
    task_space(&mut s, geometry)?;

    Ok(Processed {
        summary: ProcessSummary {
            input_samples: log.len(),
            output_samples: s.len(),
            sample_rate_hz: fs,
            filter: filter_summary,
            periods: period_summary,
            samples_dropped: dropped,
            derivative: method,
            derivative_source: source.into(),
            angle_source: log.summary.angle_source.clone(),
            torque_source: log.summary.torque_source.clone(),
        },
        samples: s,
        notes,
        warnings,
    })
}

/// Pad length for a non-periodic record: ten time constants of the
/// filter's slowest pole, `fs/(2π·fc·sin(π/2N))` samples each, so start-up
/// transients decay to e⁻¹⁰ inside the odd extension; never less than
/// scipy's default, and capped below the record length.
fn padlen(sos: &Sos, spec: FilterSpec, fs: f64, n: usize) -> usize {
    let slowest = (std::f64::consts::PI / (2.0 * spec.order as f64)).sin();
    let tau = fs / (std::f64::consts::TAU * spec.cutoff_hz * slowest);
    ((10.0 * tau).ceil() as usize)
        .max(sos.padlen())
        .min(n.saturating_sub(1))
}

fn filter_all(
    sos: &Sos,
    spec: FilterSpec,
    fs: f64,
    data: &mut [Vec<f64>],
    fourier: Option<&mut Fourier>,
    name: &str,
) -> Result<(), ProcessError> {
    match fourier {
        Some(f) => {
            for ch in data.iter_mut() {
                sos.periodic_with(f, ch);
            }
        }
        None => {
            let mut scratch = Vec::new();
            let pad = padlen(sos, spec, fs, data[0].len());
            for (c, ch) in data.iter_mut().enumerate() {
                sos.filtfilt_in_place_padded(ch, pad, &mut scratch)
                    .map_err(|source| ProcessError::Filter {
                        context: format!(
                            "filtering {} of {name}",
                            CHANNELS.get(c).copied().unwrap_or("a logged derivative")
                        ),
                        source,
                    })?;
            }
        }
    }
    Ok(())
}

/// Fills X, Ẋ, Ẍ from θ, θ̇, θ̈ through `aras_kin::forward_motion`,
/// spec (6)–(11): `X = forward(θ)` (which rejects unreachable and
/// near-singular poses), `Ẋ = J⁻¹θ̇`, `Ẍ = J⁻¹(θ̈ − J̇Ẋ)`, so θ̇ = JẊ holds
/// exactly at every sample.
fn task_space(s: &mut Samples, g: &aras_kin::Geometry) -> Result<(), ProcessError> {
    for i in 0..s.len() {
        let col = |c: &[Vec<f64>; 2]| Vector2::new(c[0][i], c[1][i]);
        let [x, xd, xdd] = aras_kin::forward_motion(
            g,
            &col(&s.theta),
            &col(&s.theta_dot),
            &col(&s.theta_ddot),
            aras_kin::AssemblyMode::Plus,
        )
        .map_err(|source| ProcessError::Kinematics {
            index: i,
            t: s.t[i],
            source,
        })?;
        for j in 0..2 {
            s.x[j][i] = x[j];
            s.x_dot[j][i] = xd[j];
            s.x_ddot[j][i] = xdd[j];
        }
    }
    Ok(())
}
