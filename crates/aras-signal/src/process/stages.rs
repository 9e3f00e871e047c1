//! The stages of [`process_in`](super::process_in), one function each, in
//! the order the module docs give: (0) a uniform grid, (1) the period and
//! its average, (2–3) the bandwidth and the derivatives, then the output
//! rows.

use aras_log::{Log, Warning};

use super::{
    Bandwidth, MAX_UNUSED_SILENT, Pair, PeriodSource, PeriodSummary, ProcessOptions, RowMap,
    UNIFORM_TOLERANCE, channel_name, filter_all, padlen, periodic_slopes,
};
use crate::bandwidth::{
    HarmonicSelection, PeriodDetection, PeriodOrigin, SpectrumCutoff, detect_period, harmonic_fit,
    hermite_at, resample, spectrum_cutoff, uniform_derivatives,
};
use crate::derivative::{DerivativeMethod, derivatives, resolve, spectral_with};
use crate::error::ProcessError;
use crate::fourier::Fourier;
use crate::periods::{PeriodAverage, average_periods};
use crate::{Butterworth, FilterSpec, FilterSummary};

/// Step 0: every processed channel on the nominal uniform grid.
pub(super) struct Grid {
    /// The grid's times.
    pub t: Vec<f64>,
    /// The angles, the torques, then any logged derivatives
    /// ([`channel_name`]'s order).
    pub raw: Vec<Vec<f64>>,
    /// The log's steps were not uniform, so the channels were resampled.
    pub irregular: bool,
    /// What the resampling did, for the summary.
    pub resampling: Option<String>,
}

/// Step 0: the channels as logged on a uniform log, resampled by cubic
/// Hermite interpolation onto the nominal grid otherwise.
pub(super) fn uniform_grid(
    log: &Log,
    logged_vel: Option<&Vec<Vec<f64>>>,
    logged_acc: Option<&Vec<Vec<f64>>>,
) -> Grid {
    let dt = log.summary.nominal_step_s;
    let irregular = log
        .summary
        .worst_step
        .is_some_and(|w| (w.ratio - 1.0).abs() > UNIFORM_TOLERANCE);
    let chans = log
        .theta
        .iter()
        .chain(&log.tau)
        .chain(logged_vel.into_iter().flatten())
        .chain(logged_acc.into_iter().flatten());
    match log.summary.worst_step.filter(|_| irregular) {
        Some(w) => {
            let t0 = log.t[0];
            let span = log.t[log.len() - 1] - t0;
            let n = (span / dt + 1e-9).floor() as usize + 1;
            Grid {
                t: (0..n).map(|k| t0 + k as f64 * dt).collect(),
                raw: chans.map(|c| resample(&log.t, c, t0, dt, n)).collect(),
                irregular,
                resampling: Some(format!(
                    "time steps vary (worst {:.4} s = {:.3}× the nominal {:.4} s at t = {:.3} \
                     s): all columns resampled onto the nominal grid by cubic Hermite \
                     interpolation (three-point slopes of the non-uniform grid); the outputs are \
                     evaluated back at the logged times",
                    w.step_s, w.ratio, dt, w.t
                )),
            }
        }
        None => Grid {
            t: log.t.clone(),
            raw: chans.cloned().collect(),
            irregular,
            resampling: None,
        },
    }
}

/// Step 1's choice of a period.
pub(super) struct PeriodChoice {
    /// The period to average over, if any.
    pub period: Option<f64>,
    /// Where it came from.
    pub origin: Option<PeriodOrigin>,
    /// The detector's account, when it ran.
    pub detection: Option<PeriodDetection>,
}

impl PeriodChoice {
    /// The period came from the detector (so a failure to average is a
    /// note, not an error).
    fn detected(&self) -> bool {
        self.origin == Some(PeriodOrigin::Detected)
    }
}

/// Step 1: the period given, from the sidecar, or detected in the angles
/// (only for an automatic bandwidth without logged derivatives).
pub(super) fn choose_period(
    log: &Log,
    opts: &ProcessOptions,
    angles: &[Vec<f64>],
    logged: bool,
) -> PeriodChoice {
    let dt = log.summary.nominal_step_s;
    let mut detection = None;
    let (period, origin) = match opts.period {
        PeriodSource::Seconds(p) => (Some(p), Some(PeriodOrigin::Given)),
        PeriodSource::Off => (None, None),
        PeriodSource::FromSidecar => match log.sidecar.excitation.period_s {
            Some(p) => (Some(p), Some(PeriodOrigin::Sidecar)),
            None if !logged && opts.filter == Bandwidth::Auto => {
                let views: Vec<&[f64]> = angles.iter().map(Vec::as_slice).collect();
                let d = detect_period(&views, dt);
                let p = d.period_s;
                detection = Some(d);
                (p, p.map(|_| PeriodOrigin::Detected))
            }
            None => (None, None),
        },
    };
    PeriodChoice {
        period,
        origin,
        detection,
    }
}

/// Step 1: the period average of the grid's channels, when a period was
/// chosen and the angles' periods agree. Periods that disagree are an
/// error for a given period and a note for a detected one.
pub(super) fn average(
    grid: &Grid,
    choice: &PeriodChoice,
    opts: &ProcessOptions,
    joints: usize,
    dt: f64,
    notes: &mut Vec<String>,
) -> Result<Option<PeriodAverage>, ProcessError> {
    let Some(p) = choice.period else {
        return Ok(None);
    };
    let views: Vec<&[f64]> = grid.raw.iter().map(|c| c.as_slice()).collect();
    let avg = match average_periods(&views, dt, p, opts.settling_s) {
        Ok(avg) => avg,
        Err(e) if choice.detected() => {
            notes.push(format!("detected period {p:.6} s not used: {e}"));
            return Ok(None);
        }
        Err(e) => return Err(e),
    };
    match (0..joints).find(|&c| avg.spread_relative[c] > opts.max_period_spread) {
        Some(c) if !choice.detected() => {
            let k = avg.worst_block[c];
            let i0 = avg.start + k * avg.samples_per_block;
            Err(ProcessError::PeriodsDisagree {
                channel: channel_name(c, joints),
                index: k,
                t_start: grid.t[i0],
                t_end: grid.t[i0 + avg.samples_per_block - 1],
                relative: avg.spread_relative[c],
                limit: opts.max_period_spread,
                period_s: p,
            })
        }
        Some(c) => {
            notes.push(format!(
                "detected period {p:.6} s not used: {} spreads {:.1} % between periods (limit \
                 {:.1} %)",
                channel_name(c, joints),
                100.0 * avg.spread_relative[c],
                100.0 * opts.max_period_spread
            ));
            Ok(None)
        }
        None => Ok(Some(avg)),
    }
}

/// The record steps 2–3 work on: the averaged period block, or the whole
/// uniform grid.
pub(super) struct Record {
    /// Its channels ([`channel_name`]'s order).
    pub data: Vec<Vec<f64>>,
    /// Its times.
    pub t: Vec<f64>,
    /// The averaging, when the record is one period block.
    pub periods: Option<PeriodSummary>,
    /// Grid samples the record does not hold (settling and tail).
    pub dropped: usize,
    /// How the record's rows map back onto the log's.
    pub map: RowMap,
}

/// The record of an average (with its torque-spread and unused-record
/// warnings), or of the grid itself.
pub(super) fn record(
    averaged: Option<PeriodAverage>,
    grid: Grid,
    period: Option<f64>,
    opts: &ProcessOptions,
    joints: usize,
    warnings: &mut Vec<Warning>,
) -> Record {
    let Some(avg) = averaged else {
        return Record {
            data: grid.raw,
            t: grid.t,
            periods: None,
            dropped: 0,
            map: RowMap::Direct { edge: 0 },
        };
    };
    let nu = grid.t.len();
    for c in joints..2 * joints {
        if avg.spread_relative[c] > opts.max_period_spread {
            warnings.push(Warning::PeriodSpread {
                channel: channel_name(c, joints),
                relative: avg.spread_relative[c],
            });
        }
    }
    // A large unused remainder means the block is many periods long (the
    // period is not a whole number of samples at this step): say so rather
    // than average silently less of the record.
    let unused = (nu - avg.samples_per_block * avg.blocks) as f64 / nu as f64;
    if unused > MAX_UNUSED_SILENT {
        warnings.push(Warning::AveragingUnused {
            periods_per_block: avg.periods_per_block,
            blocks: avg.blocks,
            unused,
        });
    }
    let summary = PeriodSummary {
        period_s: period.expect("an average has a period"),
        periods_per_block: avg.periods_per_block,
        samples_per_block: avg.samples_per_block,
        blocks_averaged: avg.blocks,
        periods_averaged: avg.periods(),
        settling_samples: avg.start,
        tail_samples: avg.tail,
        spread_relative: avg.spread_relative[..2 * joints].to_vec(),
        spread_rms: avg.spread_rms[..2 * joints].to_vec(),
    };
    Record {
        t: grid.t[avg.start..avg.start + avg.samples_per_block].to_vec(),
        dropped: nu - avg.samples_per_block * avg.blocks,
        map: RowMap::Periodic {
            start: avg.start,
            per: avg.samples_per_block,
        },
        periods: Some(summary),
        data: avg.channels,
    }
}

/// Step 2's choice of a bandwidth, with the derivatives when the choice
/// yields them (a harmonic series, logged rates).
#[derive(Default)]
pub(super) struct BandChoice {
    /// The harmonic series per joint (automatic bandwidth, periodic record).
    pub harmonics: Option<Vec<HarmonicSelection>>,
    /// The spectrum's cut-off (automatic bandwidth, aperiodic record).
    pub spectrum: Option<SpectrumCutoff>,
    /// The low-pass to apply to θ and τ.
    pub filter: Option<FilterSpec>,
    /// θ̇, θ̈ and the rows lost at each end, when already known.
    pub derivatives: Option<(Pair, Pair, usize)>,
}

/// Step 2: the bandwidth. Logged rates are used as they are (θ̈ from θ̇
/// when it is not logged); an automatic bandwidth fits each joint's
/// harmonic series on a periodic record (in place) or finds the spectrum's
/// cut-off otherwise; a fixed one is the given low-pass.
pub(super) fn choose_band(
    record: &mut Record,
    fourier: Option<&mut Fourier>,
    opts: &ProcessOptions,
    logged: Option<bool>,
    joints: usize,
    dt: f64,
) -> BandChoice {
    let (data, n) = (&mut record.data, record.t.len());
    if let Some(acc_logged) = logged {
        let vel: Pair = data[2 * joints..3 * joints].to_vec();
        let acc: Pair = if acc_logged {
            data[3 * joints..4 * joints].to_vec()
        } else {
            vel.iter().map(|v| uniform_derivatives(v, dt).0).collect()
        };
        return BandChoice {
            derivatives: Some((vel, acc, 0)),
            ..BandChoice::default()
        };
    }
    match (opts.filter, fourier) {
        (Bandwidth::Auto, Some(f)) => {
            let kp = record.periods.as_ref().map_or(1, |p| p.periods_per_block);
            let mut vel = vec![vec![0.0; n]; joints];
            let mut acc = vec![vec![0.0; n]; joints];
            let harmonics = (0..joints)
                .map(|j| harmonic_fit(f, &mut data[j], &mut vel[j], &mut acc[j], kp, dt))
                .collect();
            let spectral = matches!(
                opts.derivative,
                DerivativeMethod::Auto | DerivativeMethod::Spectral
            );
            BandChoice {
                harmonics: Some(harmonics),
                derivatives: spectral.then_some((vel, acc, 0)),
                ..BandChoice::default()
            }
        }
        (Bandwidth::Auto, None) => {
            let angles: Vec<&[f64]> = data[..joints].iter().map(Vec::as_slice).collect();
            let c = spectrum_cutoff(&angles, dt);
            BandChoice {
                filter: Some(FilterSpec {
                    order: FilterSpec::default().order,
                    cutoff_hz: c.cutoff_hz,
                }),
                spectrum: Some(c),
                ..BandChoice::default()
            }
        }
        (Bandwidth::Fixed(spec), _) => BandChoice {
            filter: Some(spec),
            ..BandChoice::default()
        },
        (Bandwidth::Off, _) => BandChoice::default(),
    }
}

/// Step 2: the low-pass of θ and τ alike, periodic on a periodic record.
pub(super) fn low_pass(
    spec: FilterSpec,
    data: &mut [Vec<f64>],
    fourier: Option<&mut Fourier>,
    log: &Log,
    joints: usize,
) -> Result<FilterSummary, ProcessError> {
    let fs = 1.0 / log.summary.nominal_step_s;
    let sos = Butterworth::lowpass(spec.order, spec.cutoff_hz, fs).map_err(|source| {
        ProcessError::Filter {
            context: format!("designing the low-pass for {}", log.name),
            source,
        }
    })?;
    let periodic = fourier.is_some();
    let n = data[0].len();
    filter_all(
        &sos,
        spec,
        fs,
        &mut data[..2 * joints],
        fourier,
        &log.name,
        joints,
    )?;
    Ok(FilterSummary {
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

/// Step 3: the derivative method used and θ̇, θ̈ with the rows lost at
/// each end, unless step 2 already gave them.
pub(super) fn differentiate(
    known: Option<(Pair, Pair, usize)>,
    angles: &[Vec<f64>],
    mut fourier: Option<&mut Fourier>,
    asked: DerivativeMethod,
    dt: f64,
) -> Result<(DerivativeMethod, Pair, Pair, usize), ProcessError> {
    let periodic = fourier.is_some();
    let method = match (&known, asked) {
        (Some(_), _) => asked,
        (None, DerivativeMethod::Auto) if !periodic => DerivativeMethod::Auto,
        (None, m) => resolve(m, periodic),
    };
    let (v, a, edge) = match known {
        Some(d) => d,
        None if method == DerivativeMethod::Auto => {
            // Non-periodic, automatic: central differences, one-sided at
            // the ends, so no row is lost.
            let (v, a) = angles.iter().map(|x| uniform_derivatives(x, dt)).unzip();
            (v, a, 0)
        }
        None => {
            let mut out = Vec::new();
            for ch in angles {
                match (fourier.as_deref_mut(), method) {
                    (Some(f), DerivativeMethod::Spectral) => {
                        let (mut a, mut b) = (ch.clone(), ch.clone());
                        spectral_with(f, &mut a, &mut b, dt);
                        out.push((a, b, 0));
                    }
                    _ => {
                        let d = derivatives(ch, dt, method, periodic)?;
                        out.push((d.first, d.second, d.edge));
                    }
                }
            }
            let e = out.first().map_or(0, |o| o.2);
            let (first, second) = out.into_iter().map(|(a, b, _)| (a, b)).unzip();
            (first, second, e)
        }
    };
    Ok((method, v, a, edge))
}

/// The motion of a uniform record (times `t`, `edge` rows lost at its
/// start) at the log's own times: exact indices on a uniform log (wrapping
/// for a periodic record), cubic Hermite with the derivatives as slopes
/// between grid points of a resampled one (shifted by `shift` steps).
pub(super) fn at_log_times(
    log_t: &[f64],
    t0: f64,
    motion: [&Pair; 3],
    dt: f64,
    shift: f64,
    irregular: bool,
    periodic: bool,
) -> [Pair; 3] {
    let [theta, theta_dot, theta_ddot] = motion;
    let nj = theta.len();
    let rows = log_t.len();
    let mut out: [Pair; 3] = std::array::from_fn(|_| vec![Vec::new(); nj]);
    for j in 0..nj {
        let (x, v, a) = (&theta[j], &theta_dot[j], &theta_ddot[j]);
        let jerk = periodic_slopes(a, dt, periodic);
        for o in out.iter_mut() {
            o[j] = Vec::with_capacity(rows);
        }
        let m = x.len();
        for &ti in log_t {
            let pos = (ti - t0) / dt + if irregular { shift } else { 0.0 };
            let (k, u) = if irregular {
                let k = pos.floor();
                (k as i64, pos - k)
            } else {
                (pos.round() as i64, 0.0)
            };
            let idx = |k: i64| -> usize {
                if periodic {
                    k.rem_euclid(m as i64) as usize
                } else {
                    k.clamp(0, m as i64 - 1) as usize
                }
            };
            let (i0, i1) = (idx(k), idx(k + 1));
            let h = |y: &[f64], dy: &[f64], sc: f64| -> f64 {
                if u == 0.0 {
                    return y[i0];
                }
                let (u2, u3) = (u * u, u * u * u);
                y[i0] * (2.0 * u3 - 3.0 * u2 + 1.0)
                    + dy[i0] * sc * (u3 - 2.0 * u2 + u)
                    + y[i1] * (-2.0 * u3 + 3.0 * u2)
                    + dy[i1] * sc * (u3 - u2)
            };
            out[0][j].push(h(x, v, dt));
            out[1][j].push(h(v, a, dt));
            out[2][j].push(h(a, &jerk, dt));
        }
    }
    out
}

/// Adds to the series motion `[x, v, a]` at the log's rows the aperiodic
/// remainder of the logged angles `theta` (θ − series, e.g. a start-up
/// transient), low-passed where its own spectrum meets the noise (at most
/// the series' band) and differentiated; returns that cut-off.
pub(super) fn add_aperiodic_remainder(
    theta: &[Vec<f64>],
    motion: &mut [Pair; 3],
    harmonics: Option<&[HarmonicSelection]>,
    log: &Log,
) -> Result<SpectrumCutoff, ProcessError> {
    let dt = log.summary.nominal_step_s;
    let fs = 1.0 / dt;
    let nj = theta.len();
    let [x, v, a] = motion;
    let mut r: Vec<Vec<f64>> = (0..nj)
        .map(|j| theta[j].iter().zip(&x[j]).map(|(a, b)| a - b).collect())
        .collect();
    let views: Vec<&[f64]> = r.iter().map(Vec::as_slice).collect();
    let mut c = spectrum_cutoff(&views, dt);
    // Above the band of the series (the smallest highest harmonic of the
    // joints that move, `band_of`) the angles hold noise for the torque.
    if let Some(h) = harmonics {
        let top = h
            .iter()
            .map(|s| s.highest_hz)
            .filter(|f| *f > 0.0)
            .fold(f64::INFINITY, f64::min);
        if top.is_finite() {
            c.cutoff_hz = c.cutoff_hz.min(top);
        }
    }
    let spec = FilterSpec {
        cutoff_hz: c.cutoff_hz,
        ..FilterSpec::default()
    };
    let sos = Butterworth::lowpass(spec.order, spec.cutoff_hz, fs).map_err(|source| {
        ProcessError::Filter {
            context: format!("designing the remainder's low-pass for {}", log.name),
            source,
        }
    })?;
    filter_all(&sos, spec, fs, &mut r, None, &log.name, nj)?;
    for j in 0..nj {
        let (dv, da) = uniform_derivatives(&r[j], dt);
        for i in 0..x[j].len() {
            x[j][i] += r[j][i];
            v[j][i] += dv[i];
            a[j][i] += da[i];
        }
    }
    Ok(c)
}

/// The motion of a resampled, aperiodic record back at the log's times
/// (shifted by `shift` steps), by cubic Hermite interpolation.
pub(super) fn resampled_at_log_times(
    t: &[f64],
    motion: [&Pair; 3],
    log_t: &[f64],
    shift: f64,
    dt: f64,
) -> [Pair; 3] {
    let [theta, theta_dot, theta_ddot] = motion;
    let at: Vec<f64> = log_t.iter().map(|ti| ti + shift * dt).collect();
    let mut out: [Pair; 3] = std::array::from_fn(|_| vec![Vec::new(); theta.len()]);
    for j in 0..theta.len() {
        let jerk = periodic_slopes(&theta_ddot[j], dt, false);
        out[0][j] = hermite_at(t, &theta[j], &theta_dot[j], &at);
        out[1][j] = hermite_at(t, &theta_dot[j], &theta_ddot[j], &at);
        out[2][j] = hermite_at(t, &theta_ddot[j], &jerk, &at);
    }
    out
}
