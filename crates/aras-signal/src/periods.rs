//! Period averaging (spec §6: 160 s = 16 periods of the excitation are
//! averaged to cut noise). For white noise of standard deviation σ the
//! average of N periods has σ/√N.

use serde::Serialize;

use crate::error::ProcessError;

/// The average period of several channels.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodAverage {
    /// Samples per period.
    pub samples_per_period: usize,
    /// Whole periods averaged.
    pub periods: usize,
    /// Index of the first sample used (after the settling time).
    pub start: usize,
    /// Samples after the last whole period, not used.
    pub tail: usize,
    /// The averaged period, per channel.
    pub channels: Vec<Vec<f64>>,
    /// Per channel: largest RMS difference between one period and the
    /// average (channel units).
    pub spread_rms: Vec<f64>,
    /// Per channel: `spread_rms` relative to the standard deviation of the
    /// averaged period (0 for a constant channel that matches exactly).
    pub spread_relative: Vec<f64>,
    /// Per channel: index of the period with the largest spread.
    pub worst_period: Vec<usize>,
}

/// Averages whole periods of `channels` (all of equal length, uniform step
/// `dt`), after dropping `settling_s` seconds.
///
/// The period must be a whole number of samples up to a drift of half a
/// sample over the record; at least one whole period must remain.
pub fn average_periods(
    channels: &[&[f64]],
    dt: f64,
    period_s: f64,
    settling_s: f64,
) -> Result<PeriodAverage, ProcessError> {
    let bad = |name, value: f64, reason: &str| ProcessError::InvalidOption {
        name,
        value: value.to_string(),
        reason: reason.into(),
    };
    if !(period_s.is_finite() && period_s > 0.0) {
        return Err(bad(
            "period",
            period_s,
            "the period must be a positive number of seconds",
        ));
    }
    if !(settling_s.is_finite() && settling_s >= 0.0) {
        return Err(bad(
            "settling_s",
            settling_s,
            "the settling time must be ≥ 0 s",
        ));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(bad(
            "sample step",
            dt,
            "the step must be a positive number of seconds",
        ));
    }
    let n = channels.first().map_or(0, |c| c.len());
    let exact = period_s / dt;
    let per = exact.round() as usize;
    if per < 3 {
        return Err(ProcessError::TooShort {
            what: "period averaging".into(),
            have: per,
            need: 3,
            hint: "a period must span at least 3 samples".into(),
        });
    }
    let start = (settling_s / dt).round() as usize;
    let periods = n.saturating_sub(start) / per;
    if periods == 0 {
        return Err(ProcessError::TooShort {
            what: format!("period averaging (period {period_s} s after {settling_s} s settling)"),
            have: n,
            need: start + per,
            hint: "record at least one whole period after the settling time".into(),
        });
    }
    let drift = (exact - per as f64).abs() * periods as f64;
    if drift > 0.5 {
        return Err(ProcessError::PeriodNotWhole {
            period_s,
            samples: exact,
            step_s: dt,
            drift,
        });
    }
    let mut out = PeriodAverage {
        samples_per_period: per,
        periods,
        start,
        tail: n - start - periods * per,
        channels: Vec::with_capacity(channels.len()),
        spread_rms: Vec::new(),
        spread_relative: Vec::new(),
        worst_period: Vec::new(),
    };
    let inv = 1.0 / periods as f64;
    for ch in channels {
        let data = &ch[start..start + periods * per];
        let mut mean = vec![0.0; per];
        for p in data.chunks_exact(per) {
            for (m, v) in mean.iter_mut().zip(p) {
                *m += v;
            }
        }
        mean.iter_mut().for_each(|m| *m *= inv);
        let (mut worst, mut worst_k) = (0.0f64, 0);
        for (k, p) in data.chunks_exact(per).enumerate() {
            let ss: f64 = p.iter().zip(&mean).map(|(v, m)| (v - m).powi(2)).sum();
            let rms = (ss / per as f64).sqrt();
            if rms > worst {
                (worst, worst_k) = (rms, k);
            }
        }
        let mu = mean.iter().sum::<f64>() / per as f64;
        let sd = (mean.iter().map(|m| (m - mu).powi(2)).sum::<f64>() / per as f64).sqrt();
        let rel = if worst == 0.0 {
            0.0
        } else if sd > 0.0 {
            worst / sd
        } else {
            f64::INFINITY
        };
        out.channels.push(mean);
        out.spread_rms.push(worst);
        out.spread_relative.push(rel);
        out.worst_period.push(worst_k);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    #[test]
    fn averaging_reduces_white_noise_by_sqrt_n() {
        let (per, periods, sigma) = (4000, 16, 0.1);
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let clean: Vec<f64> = (0..per)
            .map(|i| (std::f64::consts::TAU * i as f64 / per as f64).sin())
            .collect();
        let noisy: Vec<f64> = (0..per * periods)
            .map(|i| {
                let e: f64 = StandardNormal.sample(&mut rng);
                clean[i % per] + sigma * e
            })
            .collect();
        let avg = average_periods(&[&noisy], 0.001, per as f64 * 0.001, 0.0).unwrap();
        assert_eq!((avg.periods, avg.tail), (periods, 0));
        let resid: f64 = avg.channels[0]
            .iter()
            .zip(&clean)
            .map(|(a, c)| (a - c).powi(2))
            .sum::<f64>()
            / per as f64;
        let expected = sigma / (periods as f64).sqrt();
        // The RMS of 4000 Gaussian samples estimates σ/√N with a relative
        // standard error of 1/√(2·4000) ≈ 1.1 %; 6 % is more than 5 standard
        // errors, yet a reduction by √(N/2) or √(2N) would be caught.
        assert!(
            (resid.sqrt() / expected - 1.0).abs() < 0.06,
            "{} vs {expected}",
            resid.sqrt()
        );
        // Each period's deviation from the average is the noise itself.
        assert!((avg.spread_rms[0] / sigma - 1.0).abs() < 0.1);
    }

    #[test]
    fn settling_tail_and_drift() {
        let x: Vec<f64> = (0..1050).map(|i| (i % 100) as f64).collect();
        let a = average_periods(&[&x], 0.01, 1.0, 0.2).unwrap();
        assert_eq!((a.start, a.periods, a.tail), (20, 10, 30));
        // Starting at sample 20, every period is 20..99, 0..19: identical.
        assert_eq!(a.spread_rms[0], 0.0);
        assert_eq!(a.channels[0][0], 20.0);
        assert!(matches!(
            average_periods(&[&x], 0.01, 1.003, 0.0),
            Err(ProcessError::PeriodNotWhole { .. })
        ));
        assert!(matches!(
            average_periods(&[&x], 0.01, 20.0, 0.0),
            Err(ProcessError::TooShort { .. })
        ));
    }
}
