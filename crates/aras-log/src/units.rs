//! Units of logged angles and of their logged derivatives, judged from the
//! values: the log reader's degrees check, and the consistency of a logged
//! derivative column with the column it is the derivative of. Other readers
//! of joint logs (e.g. `aras friction`'s) call the same functions.

use crate::error::LogError;

/// Largest magnitude and span (rad) of a robot joint's angle in radians:
/// a joint stays within a turn and a half either way, in degrees the same
/// motion exceeds it.
pub const ANGLE_LIMIT_RAD: f64 = 3.0 * std::f64::consts::PI;

/// Largest magnitude of an angle column read as degrees (two turns).
pub const ANGLE_LIMIT_DEG: f64 = 720.0;

/// What an angle column's range says about its unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AngleUnits {
    /// Within [`ANGLE_LIMIT_RAD`]: radians.
    Radians,
    /// Beyond radians but within [`ANGLE_LIMIT_DEG`]: degrees.
    Degrees,
    /// Beyond both: neither (e.g. encoder counts).
    Implausible,
}

/// The unit an angle column's values suggest, from its smallest, largest
/// and largest absolute value.
pub fn angle_units(min: f64, max: f64, max_abs: f64) -> AngleUnits {
    if max_abs <= ANGLE_LIMIT_RAD && max - min <= ANGLE_LIMIT_RAD {
        AngleUnits::Radians
    } else if max_abs <= ANGLE_LIMIT_DEG {
        AngleUnits::Degrees
    } else {
        AngleUnits::Implausible
    }
}

/// Refuses an angle column `name` of `file` whose values are not radians
/// ([`angle_units`]); `line` is the line of its largest absolute value.
pub fn check_angle_column(
    file: &str,
    name: &str,
    [min, max, max_abs]: [f64; 3],
    line: u64,
) -> Result<(), LogError> {
    match angle_units(min, max, max_abs) {
        AngleUnits::Radians => Ok(()),
        AngleUnits::Degrees => Err(LogError::Degrees {
            file: file.into(),
            name: name.into(),
            max: max_abs,
            line,
        }),
        AngleUnits::Implausible => Err(LogError::ImplausibleAngle {
            file: file.into(),
            name: name.into(),
            max: max_abs,
            line,
        }),
    }
}

/// Shortest time span (s) over which a logged derivative is integrated and
/// compared with the change of its column ([`derivative_ratio`]): long
/// enough that sample noise in the column does not bias the ratio, short
/// against any robot motion.
pub const RATIO_SPAN_S: f64 = 0.01;

/// Relative tolerance of [`check_derivative_column`]: a logged derivative
/// whose ratio to the column's own derivative is outside `1 ± 0.1` is
/// refused.
pub const RATIO_TOLERANCE: f64 = 0.1;

/// Least-squares ratio of a logged derivative `dx` to the derivative of `x`
/// (samples at the increasing times `t`, any spacing): on consecutive spans
/// of at least [`RATIO_SPAN_S`], the trapezoidal integral `I` of `dx` is
/// compared with the change `Δx`, and the ratio is `Σ I Δx / Σ Δx²` — 1 for
/// a consistent column, 180/π for a rate in degrees per second beside angles
/// in radians. Integrating rather than differentiating keeps the noise of
/// `x` from biasing the ratio. `None` when `x` does not change (nothing to
/// compare) or the lengths differ. A gap in the stamps (a step longer
/// than [`RATIO_GAP_STEPS`] times the median step) ends a span and is not
/// integrated: one trapezoid over a gap says nothing about the column's
/// units.
pub fn derivative_ratio(t: &[f64], x: &[f64], dx: &[f64]) -> Option<f64> {
    let n = t.len();
    if n < 2 || x.len() != n || dx.len() != n {
        return None;
    }
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = steps.len() / 2;
    let gap = RATIO_GAP_STEPS * *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    let mut i = 0;
    while i + 1 < n {
        if t[i + 1] - t[i] > gap {
            i += 1;
            continue;
        }
        let mut j = i;
        let mut integral = 0.0;
        while j + 1 < n && (j == i || t[j] - t[i] < RATIO_SPAN_S) && t[j + 1] - t[j] <= gap {
            integral += 0.5 * (dx[j] + dx[j + 1]) * (t[j + 1] - t[j]);
            j += 1;
        }
        let change = x[j] - x[i];
        sxy += integral * change;
        sxx += change * change;
        i = j;
    }
    (sxx > 0.0 && sxy.is_finite() && sxx.is_finite()).then(|| sxy / sxx)
}

/// A step longer than this many median steps is a gap in the stamps
/// ([`derivative_ratio`]).
pub const RATIO_GAP_STEPS: f64 = 4.0;

/// Refuses a logged derivative column `name` of `file` that is not the
/// derivative of the column `of` ([`derivative_ratio`] outside
/// `1 ± RATIO_TOLERANCE`), with the ratio and what it suggests (degrees per
/// second, the sign, another column). A column `of` that never changes
/// gives nothing to compare and passes.
pub fn check_derivative_column(
    file: &str,
    (name, dx): (&str, &[f64]),
    (of, x): (&str, &[f64]),
    t: &[f64],
) -> Result<(), LogError> {
    let Some(ratio) = derivative_ratio(t, x, dx) else {
        return Ok(());
    };
    if (ratio - 1.0).abs() <= RATIO_TOLERANCE {
        return Ok(());
    }
    let deg = 180.0 / std::f64::consts::PI;
    let hint = if (ratio / deg - 1.0).abs() <= RATIO_TOLERANCE {
        format!("it looks like degrees per second (180/π = {deg:.1}): convert `{name}` to radians")
    } else if (ratio * deg - 1.0).abs() <= RATIO_TOLERANCE {
        format!(
            "`{of}` and `{name}` look like different units (1/ratio ≈ 180/π): log both in radians"
        )
    } else if (ratio + 1.0).abs() <= RATIO_TOLERANCE {
        format!("its sign is reversed: negate `{name}`")
    } else {
        format!(
            "check that `{name}` is the derivative of `{of}` in SI units (radians), or drop the \
             column so it is differentiated from `{of}`"
        )
    };
    Err(LogError::InconsistentDerivative {
        file: file.into(),
        name: name.into(),
        of: of.into(),
        ratio,
        hint,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(n: usize, dt: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let x = t.iter().map(|t| 0.5 * (3.0 * t).sin()).collect();
        let dx = t.iter().map(|t| 1.5 * (3.0 * t).cos()).collect();
        (t, x, dx)
    }

    #[test]
    fn ratio_of_a_consistent_derivative_is_one() {
        let (t, x, dx) = sine(4000, 1e-3);
        let r = derivative_ratio(&t, &x, &dx).unwrap();
        // Trapezoid over 10 ms of a 3 rad/s sine: error ≈ (3·0.01)²/12.
        assert!((r - 1.0).abs() < 1e-4, "{r}");
    }

    #[test]
    fn gaps_in_the_stamps_do_not_bias_the_ratio() {
        // 1–16 ms irregular steps with 0.1–0.3 s gaps on a 3 rad/s sine:
        // one trapezoid over a gap would be off by tens of percent.
        let mut t = vec![0.0];
        let mut k = 0u64;
        while *t.last().unwrap() < 20.0 {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (k >> 11) as f64 / (1u64 << 53) as f64;
            let step = if k.is_multiple_of(50) {
                0.1 + 0.2 * u
            } else {
                0.001 + 0.015 * u
            };
            t.push(t.last().unwrap() + step);
        }
        let x: Vec<f64> = t.iter().map(|t| 0.5 * (6.0 * t).sin()).collect();
        let dx: Vec<f64> = t.iter().map(|t| 3.0 * (6.0 * t).cos()).collect();
        let r = derivative_ratio(&t, &x, &dx).unwrap();
        // Trapezoid over ≤ 16 ms of a 6 rad/s sine: error ≤ (6·0.016)²/12.
        assert!((r - 1.0).abs() < 1e-3, "{r}");
    }

    #[test]
    fn noise_in_the_angle_does_not_bias_the_ratio() {
        let (t, mut x, dx) = sine(4000, 1e-3);
        // ±1e-3 rad scattered jitter, 10× a fine encoder's quantum.
        for (i, v) in x.iter_mut().enumerate() {
            *v += 2e-3 * (((i * 7919) % 13) as f64 / 12.0 - 0.5);
        }
        let r = derivative_ratio(&t, &x, &dx).unwrap();
        assert!((r - 1.0).abs() < 0.02, "{r}");
    }

    #[test]
    fn degrees_per_second_are_named() {
        let (t, x, dx) = sine(4000, 1e-3);
        let deg: Vec<f64> = dx.iter().map(|v| v.to_degrees()).collect();
        let e = check_derivative_column("a.csv", ("dtheta1", &deg), ("theta1", &x), &t)
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.csv: `dtheta1`"), "{e}");
        assert!(e.contains("57.3"), "{e}");
        assert!(e.contains("degrees per second"), "{e}");
        assert!(check_derivative_column("a.csv", ("dtheta1", &dx), ("theta1", &x), &t).is_ok());
        let neg: Vec<f64> = dx.iter().map(|v| -v).collect();
        let e = check_derivative_column("a.csv", ("dq", &neg), ("q", &x), &t)
            .unwrap_err()
            .to_string();
        assert!(e.contains("sign is reversed"), "{e}");
    }

    #[test]
    fn a_still_column_gives_no_ratio() {
        let t = [0.0, 0.1, 0.2];
        assert_eq!(derivative_ratio(&t, &[1.0; 3], &[0.3; 3]), None);
    }

    #[test]
    fn angle_units_from_the_range() {
        assert_eq!(angle_units(-1.0, 2.0, 2.0), AngleUnits::Radians);
        assert_eq!(angle_units(10.0, 120.0, 120.0), AngleUnits::Degrees);
        assert_eq!(angle_units(0.0, 4096.0, 4096.0), AngleUnits::Implausible);
    }
}
