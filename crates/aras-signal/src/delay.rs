//! Torque samples that are not simultaneous with the angle samples: a
//! current loop, a bus or a drive's filter logs the torque some samples
//! after the motion it belongs to. A fraction of a sample is interpolated
//! linearly between samples, the rule the diagnosis's `time_delay`
//! candidate uses, so a delay it reports can be removed here exactly.

use aras_log::Log;

use crate::ProcessError;

/// The value of `x` `delay` samples after sample `i`, interpolated linearly
/// between samples for a fraction; indices wrap around the record (exact
/// for one period of a periodic signal; a record that is not periodic keeps
/// `i + delay` inside `[0, len − 1]`). A whole-sample delay reads the
/// sample itself.
///
/// # Panics
/// When `x` is empty.
pub fn delayed_at(x: &[f64], i: usize, delay: f64) -> f64 {
    let n = x.len() as i64;
    let whole = delay.floor();
    let frac = delay - whole;
    let k = i as i64 + whole as i64;
    let at = |k: i64| x[k.rem_euclid(n) as usize];
    if frac == 0.0 {
        at(k)
    } else {
        (1.0 - frac) * at(k) + frac * at(k + 1)
    }
}

/// One period `x` of a periodic signal shifted by `delay` samples
/// circularly, `y_i = x(i + delay)`, by its discrete Fourier series: every
/// harmonic's phase moves by `2π k delay / n` (the Nyquist bin of an even
/// `n` keeps its real part), so a fraction of a sample is an exact all-pass
/// shift. [`delayed_at`]'s linear interpolation halfway between two samples
/// averages them and halves the variance of white noise; on torques that
/// are not low-passed a half-sample shift of either sign would then fit
/// better by the noise it removes. A whole number of samples rotates `x`
/// (to rounding).
pub fn delayed_periodic(x: &[f64], delay: f64) -> Vec<f64> {
    let mut y = x.to_vec();
    let n = x.len();
    if n == 0 || delay == 0.0 {
        return y;
    }
    let mut f = crate::fourier::Fourier::new(n);
    let w = std::f64::consts::TAU * delay / n as f64;
    f.apply(&mut y, |k| {
        if 2 * k == n as i64 {
            rustfft::num_complex::Complex64::new((w * k as f64).cos(), 0.0)
        } else {
            rustfft::num_complex::Complex64::from_polar(1.0, w * k as f64)
        }
    });
    y
}

/// `log` with each torque sample replaced by the one logged `delay`
/// samples later (`τ_i ← τ(i + delay)`, [`delayed_at`]), and the rows that
/// have no such torque dropped: the last `⌈delay⌉` for a positive delay,
/// the first `⌈−delay⌉` for a negative one. Every other column keeps its
/// rows; the summary's row count, duration and torque ranges follow, and a
/// note records the shift.
///
/// A positive delay is a torque that lags the motion (what the diagnosis's
/// `time_delay(+d)` finds). The value the diagnosis refines includes the
/// half sample a zero-order hold adds (`docs/diagnose.md`); give it as
/// reported.
pub fn delay_torque(log: &Log, delay: f64) -> Result<Log, ProcessError> {
    let n = log.len();
    let invalid = |reason: String| ProcessError::InvalidOption {
        name: "torque delay (samples)",
        value: delay.to_string(),
        reason,
    };
    if !delay.is_finite() {
        return Err(invalid("give a finite number of samples, e.g. 2.5".into()));
    }
    let whole = delay.floor() as i64;
    let reach_after = whole + i64::from(delay != delay.floor());
    // Rows i with i + whole ≥ 0 and i + reach_after ≤ n − 1.
    let lo = (-whole).max(0);
    let hi = n as i64 - reach_after.max(0);
    if hi - lo < 2 || (hi - lo) * 2 < n as i64 {
        return Err(invalid(format!(
            "a shift of {delay} samples would leave {} of the log's {n} rows; the delay must \
             be under half the log",
            (hi - lo).max(0)
        )));
    }
    let (lo, hi) = (lo as usize, hi as usize);
    let keep = |v: &[f64]| v[lo..hi].to_vec();
    let tau: Vec<Vec<f64>> = log
        .tau
        .iter()
        .map(|c| (lo..hi).map(|i| delayed_at(c, i, delay)).collect())
        .collect();
    let keep_all = |v: &[Vec<f64>]| v.iter().map(|c| keep(c)).collect::<Vec<_>>();
    let mut out = Log {
        name: log.name.clone(),
        t: keep(&log.t),
        theta: keep_all(&log.theta),
        tau,
        theta_dot: log.theta_dot.as_deref().map(keep_all),
        theta_ddot: log.theta_ddot.as_deref().map(keep_all),
        sidecar: log.sidecar.clone(),
        summary: log.summary.clone(),
        notes: log.notes.clone(),
        warnings: log.warnings.clone(),
    };
    out.summary.rows = out.t.len();
    out.summary.duration_s = out.t[out.t.len() - 1] - out.t[0];
    out.summary.tau_range = out
        .tau
        .iter()
        .map(|c| {
            c.iter()
                .fold([f64::INFINITY, f64::NEG_INFINITY], |[a, b], &x| {
                    [a.min(x), b.max(x)]
                })
        })
        .collect();
    out.notes.push(format!(
        "torque taken {delay} samples after the angles (time delay); {} row(s) without such a \
         torque dropped",
        n - out.t.len()
    ));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use aras_log::{ReadOptions, read_log_from};

    fn log(n: usize) -> Log {
        let mut csv = String::from("t,theta1,theta2,tau1,tau2\n");
        for i in 0..n {
            let t = i as f64 * 1e-3;
            let s = (std::f64::consts::TAU * 2.0 * t).sin();
            csv += &format!(
                "{t},{},{},{},{}\n",
                2.0 + 0.1 * s,
                0.6 - 0.1 * s,
                i as f64,
                s
            );
        }
        read_log_from(csv.as_bytes(), "d.csv", &ReadOptions::default()).unwrap()
    }

    /// A whole-sample delay moves every torque by exactly that many rows and
    /// drops as many rows at the end (positive) or start (negative); the
    /// angles keep their own rows.
    #[test]
    fn whole_samples_shift_exactly() {
        let l = log(1000);
        let d = delay_torque(&l, 3.0).unwrap();
        assert_eq!(d.len(), 997);
        assert_eq!(d.summary.rows, 997);
        assert_eq!(d.tau[0][0], 3.0);
        assert_eq!(d.tau[0][996], 999.0);
        assert_eq!(d.t[0], l.t[0]);
        assert_eq!(d.theta[1][996], l.theta[1][996]);
        let d = delay_torque(&l, -2.0).unwrap();
        assert_eq!(d.len(), 998);
        assert_eq!((d.t[0], d.tau[0][0]), (l.t[2], 0.0));
        assert_eq!(d.tau[0][d.len() - 1], 997.0);
    }

    /// A fraction interpolates linearly: τ = i gives i + d exactly, and a
    /// 2 Hz sine at 1 kHz shifted by 2.4 samples is the sine 2.4 ms later
    /// to the interpolation error `ω² h² / 8 = 2e-5`.
    #[test]
    fn fractions_interpolate_linearly() {
        let l = log(1000);
        let d = delay_torque(&l, 2.4).unwrap();
        assert_eq!(d.len(), 997);
        for (i, v) in d.tau[0].iter().enumerate() {
            assert!((v - (i as f64 + 2.4)).abs() < 1e-12, "{i}: {v}");
        }
        let w = std::f64::consts::TAU * 2.0;
        for (i, v) in d.tau[1].iter().enumerate() {
            let want = (w * (d.t[i] + 2.4e-3)).sin();
            assert!((v - want).abs() < 2.1e-5, "{i}: {v} vs {want}");
        }
        assert!(d.notes.last().unwrap().contains("2.4 samples"));
        let d = delay_torque(&l, -0.5).unwrap();
        assert_eq!(d.len(), 999);
        assert!((d.tau[0][0] - 0.5).abs() < 1e-12);
    }

    /// Wrapping indices are exact for a period: delaying one period of a
    /// sampled sine by whole samples rotates it.
    #[test]
    fn delayed_at_wraps_around_a_period() {
        let x: Vec<f64> = (0..8).map(|i| i as f64).collect();
        assert_eq!(delayed_at(&x, 7, 1.0), 0.0);
        assert_eq!(delayed_at(&x, 0, -1.0), 7.0);
        assert_eq!(delayed_at(&x, 7, 0.5), 3.5);
    }

    /// The Fourier shift of one period: a whole delay rotates the record, a
    /// fraction moves a sampled harmonic exactly and keeps white noise's
    /// variance (where linear interpolation halves it at half a sample).
    #[test]
    fn periodic_shift_is_an_exact_all_pass() {
        let n = 1000;
        let x: Vec<f64> = (0..n)
            .map(|i| (std::f64::consts::TAU * 7.0 * i as f64 / n as f64).sin())
            .collect();
        let y = delayed_periodic(&x, 3.0);
        for i in 0..n {
            assert!((y[i] - x[(i + 3) % n]).abs() < 1e-12);
        }
        let y = delayed_periodic(&x, -0.5);
        for (i, v) in y.iter().enumerate() {
            let want = (std::f64::consts::TAU * 7.0 * (i as f64 - 0.5) / n as f64).sin();
            assert!((v - want).abs() < 1e-12, "{i}: {v} vs {want}");
        }
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let noise: Vec<f64> = (0..4096).map(|_| StandardNormal.sample(&mut rng)).collect();
        let var = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64;
        let exact = delayed_periodic(&noise, 0.5);
        let linear: Vec<f64> = (0..noise.len())
            .map(|i| delayed_at(&noise, i, 0.5))
            .collect();
        let (v0, ve, vl) = (var(&noise), var(&exact), var(&linear));
        assert!((ve / v0 - 1.0).abs() < 0.01, "{ve} vs {v0}");
        assert!((vl / v0 - 0.5).abs() < 0.05, "{vl} vs {v0}");
    }

    #[test]
    fn bad_delays_are_errors() {
        let l = log(100);
        for d in [f64::NAN, f64::INFINITY, 60.0, -51.0] {
            let e = delay_torque(&l, d).unwrap_err().to_string();
            assert!(e.contains("torque delay"), "{d}: {e}");
        }
    }
}
