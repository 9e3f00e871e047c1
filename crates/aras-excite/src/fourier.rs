//! Finite Fourier-series trajectories in task space, (74)–(76).

use std::path::Path;

use aras_core::Motion;
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, Dim, OVector, U1, U2};
use serde::{Deserialize, Serialize};

use crate::error::{ExciteError, check_finite};

/// Format tag written into (and required in) every trajectory JSON document.
pub const FORMAT: &str = "aras-fourier/1";

/// Default number of harmonics L (`docs/excitation.md`).
pub const DEFAULT_HARMONICS: usize = 5;

/// Default base frequency ω_f = 2π/10 rad/s, a 10 s period (`docs/excitation.md`).
pub const DEFAULT_OMEGA_F: f64 = std::f64::consts::TAU / 10.0;

/// Names of ARAS-Diamond's task coordinates, for messages and key paths.
pub(crate) const COORDS: [&str; 2] = ["phi", "gamma"];

/// The name of coordinate `i` of `n` in messages: `phi`, `gamma` for two
/// (the task pose of ARAS-Diamond), `x1 … xn` otherwise.
pub(crate) fn coordinate_name(i: usize, n: usize) -> String {
    if n == 2 {
        COORDS[i].to_owned()
    } else {
        format!("x{}", i + 1)
    }
}

/// One sample of a trajectory: `t` and the state `X, Ẋ, Ẍ`.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskRow<D: Dim = U2>
where
    DefaultAllocator: Allocator<D>,
{
    /// Time (s).
    pub t: f64,
    /// The state at `t`.
    pub state: Motion<f64, D>,
}

impl Copy for TaskRow<U2> {}

impl TaskRow<U2> {
    /// `[t, φ, γ, φ̇, γ̇, φ̈, γ̈]` (s, rad, rad/s, rad/s²).
    pub fn to_array(&self) -> [f64; 7] {
        let s = &self.state;
        [
            self.t, s.pos[0], s.pos[1], s.vel[0], s.vel[1], s.acc[0], s.acc[1],
        ]
    }
}

/// A periodic trajectory, one finite Fourier series per coordinate `i`
/// (ARAS-Diamond's `φ, γ`, or a serial arm's joint angles), (74)–(76):
///
/// ```text
/// X_i(t) = X_i0 + Σ_l  a_l^i/(ω_f l) sin(ω_f l t) − b_l^i/(ω_f l) cos(ω_f l t)
/// Ẋ_i(t) =        Σ_l  a_l^i cos(ω_f l t) + b_l^i sin(ω_f l t)
/// Ẍ_i(t) =        Σ_l −a_l^i ω_f l sin(ω_f l t) + b_l^i ω_f l cos(ω_f l t)
/// ```
///
/// The coefficients `a`, `b` are velocity amplitudes (rad/s), `X_i0` is in
/// rad, `ω_f` in rad/s. `X_i0` is the mean of `X_i` over a period (every
/// sine and cosine averages to zero); it is not the *initial* position,
/// `X_i(0) = X_i0 − Σ_l b_l^i/(ω_f l)`.
///
/// The number of coordinates is the type `D`, as for [`Motion`]: two by
/// default, or [`nalgebra::Dyn`] for a robot whose joints are known at run
/// time. Always valid: finite numbers, `ω_f > 0`, `L ≥ 1`, equal lengths,
/// as many coordinates as `D` holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "FourierJson", into = "FourierJson", bound = "D: Dim")]
pub struct FourierTrajectory<D: Dim = U2> {
    omega_f: f64,
    offset: Vec<f64>,
    a: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
    #[serde(skip)]
    dim: D,
}

/// The JSON shape of a trajectory (see `docs/excitation.md`).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FourierJson {
    format: String,
    omega_f: f64,
    offset: Vec<f64>,
    a: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
}

impl<D: Dim> TryFrom<FourierJson> for FourierTrajectory<D> {
    type Error = ExciteError;

    fn try_from(j: FourierJson) -> Result<Self, ExciteError> {
        if j.format != FORMAT {
            return Err(ExciteError::Json {
                origin: "key `format`".into(),
                line: 0,
                column: 0,
                message: format!(
                    "{:?} is not a trajectory format this reader knows; expected {FORMAT:?} \
                     (write the file with `aras excite`)",
                    j.format
                ),
            });
        }
        Self::new(j.omega_f, j.offset, j.a, j.b)
    }
}

impl<D: Dim> From<FourierTrajectory<D>> for FourierJson {
    fn from(f: FourierTrajectory<D>) -> Self {
        Self {
            format: FORMAT.into(),
            omega_f: f.omega_f,
            offset: f.offset,
            a: f.a,
            b: f.b,
        }
    }
}

impl<D: Dim> FourierTrajectory<D> {
    /// A trajectory from its coefficients: base frequency `omega_f` (rad/s,
    /// positive), offsets `X_i0` (rad), and per coordinate the `a` and `b`
    /// coefficients of harmonics 1..L (rad/s). Errors name the bad value,
    /// or the number of coordinates when `D` fixes another.
    pub fn new(
        omega_f: f64,
        offset: impl Into<Vec<f64>>,
        a: impl Into<Vec<Vec<f64>>>,
        b: impl Into<Vec<Vec<f64>>>,
    ) -> Result<Self, ExciteError> {
        let (offset, a, b) = (offset.into(), a.into(), b.into());
        check_omega(omega_f)?;
        let n = offset.len();
        let want = D::try_to_usize().unwrap_or(n);
        if n == 0 || n != want {
            return Err(ExciteError::CoefficientLength {
                name: "offset".into(),
                found: n,
                expected: want.max(1),
            });
        }
        for (name, list) in [("a", &a), ("b", &b)] {
            if list.len() != n {
                return Err(ExciteError::CoefficientLength {
                    name: name.into(),
                    found: list.len(),
                    expected: n,
                });
            }
        }
        let l = a[0].len();
        if l == 0 {
            return Err(ExciteError::InvalidSetting {
                name: "harmonics",
                value: 0.0,
                reason: "a Fourier trajectory needs at least one harmonic (L ≥ 1)".into(),
            });
        }
        for i in 0..n {
            check_finite(|| format!("offset[{i}]"), offset[i])?;
            for (name, list) in [("a", &a[i]), ("b", &b[i])] {
                if list.len() != l {
                    return Err(ExciteError::CoefficientLength {
                        name: format!("{name}[{i}]"),
                        found: list.len(),
                        expected: l,
                    });
                }
                for (k, &v) in list.iter().enumerate() {
                    check_finite(|| format!("{name}[{i}][{k}]"), v)?;
                }
            }
        }
        Ok(Self {
            omega_f,
            offset,
            a,
            b,
            dim: D::from_usize(n),
        })
    }

    /// Number of coordinates.
    pub fn coordinates(&self) -> usize {
        self.offset.len()
    }

    /// Number of harmonics L.
    pub fn harmonics(&self) -> usize {
        self.a[0].len()
    }

    /// Base frequency ω_f (rad/s).
    pub fn omega_f(&self) -> f64 {
        self.omega_f
    }

    /// Period `2π/ω_f` (s).
    pub fn period(&self) -> f64 {
        std::f64::consts::TAU / self.omega_f
    }

    /// The `a` coefficients of coordinate `i` (for ARAS-Diamond 0 = φ,
    /// 1 = γ), harmonics 1..L (rad/s).
    ///
    /// # Panics
    /// If `i` is not a coordinate.
    pub fn a(&self, i: usize) -> &[f64] {
        &self.a[i]
    }

    /// The `b` coefficients of coordinate `i`, harmonics 1..L (rad/s).
    ///
    /// # Panics
    /// If `i` is not a coordinate.
    pub fn b(&self, i: usize) -> &[f64] {
        &self.b[i]
    }

    /// Exact position, velocity and acceleration of every coordinate at
    /// time `t` (s), (74)–(76), into `pos`, `vel`, `acc` (one entry per
    /// coordinate). No allocation.
    pub fn eval_into(&self, t: f64, pos: &mut [f64], vel: &mut [f64], acc: &mut [f64]) {
        pos.copy_from_slice(&self.offset);
        vel.fill(0.0);
        acc.fill(0.0);
        for l in 0..self.harmonics() {
            let w = self.omega_f * (l + 1) as f64;
            let (s, c) = (w * t).sin_cos();
            for i in 0..self.offset.len() {
                let (a, b) = (self.a[i][l], self.b[i][l]);
                pos[i] += (a * s - b * c) / w;
                vel[i] += a * c + b * s;
                acc[i] += w * (b * c - a * s);
            }
        }
    }
}

impl<D: Dim> FourierTrajectory<D>
where
    DefaultAllocator: Allocator<D>,
{
    /// The motionless trajectory at `x0` with `harmonics` zero coefficients.
    pub fn at_rest(
        omega_f: f64,
        harmonics: usize,
        x0: OVector<f64, D>,
    ) -> Result<Self, ExciteError> {
        let z = vec![vec![0.0; harmonics]; x0.len()];
        Self::new(omega_f, x0.as_slice().to_vec(), z.clone(), z)
    }

    /// Offsets `X_i0` (rad): the mean position over a period.
    pub fn offset(&self) -> OVector<f64, D> {
        OVector::from_column_slice_generic(self.dim, U1, &self.offset)
    }

    /// Exact position, velocity and acceleration at time `t` (s),
    /// (74)–(76). Allocates only for a run-time dimension.
    pub fn eval(&self, t: f64) -> Motion<f64, D> {
        let mut m = Motion::zeros_generic(self.dim);
        self.eval_into(
            t,
            m.pos.as_mut_slice(),
            m.vel.as_mut_slice(),
            m.acc.as_mut_slice(),
        );
        m
    }

    /// Samples `points_per_period` equally spaced instants per period, for
    /// `periods` periods, starting at `t = 0` (the grid excludes the end).
    pub fn sample(&self, points_per_period: usize, periods: usize) -> Vec<TaskRow<D>> {
        let h = self.period() / points_per_period.max(1) as f64;
        (0..points_per_period * periods)
            .map(|j| {
                let t = j as f64 * h;
                TaskRow {
                    t,
                    state: self.eval(t),
                }
            })
            .collect()
    }
}

impl<D: Dim> FourierTrajectory<D> {
    /// Parses the JSON format documented in `docs/excitation.md`.
    pub fn from_json(text: &str) -> Result<Self, ExciteError> {
        parse_json(text, "<string>")
    }

    /// Serialises to pretty JSON (shortest round-trip floats, so reading it
    /// back gives the identical trajectory).
    pub fn to_json(&self) -> String {
        // Serialising plain finite numbers and strings cannot fail.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Reads a trajectory JSON file.
    pub fn load(path: &Path) -> Result<Self, ExciteError> {
        let text = std::fs::read_to_string(path).map_err(|source| ExciteError::Io {
            path: path.to_owned(),
            source,
        })?;
        parse_json(&text, &path.display().to_string())
    }

    /// Writes the trajectory as JSON.
    pub fn save(&self, path: &Path) -> Result<(), ExciteError> {
        std::fs::write(path, self.to_json() + "\n").map_err(|source| ExciteError::Io {
            path: path.to_owned(),
            source,
        })
    }
}

fn parse_json<D: Dim>(text: &str, origin: &str) -> Result<FourierTrajectory<D>, ExciteError> {
    if text.trim().is_empty() {
        return Err(ExciteError::Json {
            origin: origin.into(),
            line: 1,
            column: 1,
            message:
                "the file is empty; expected a trajectory object (write one with `aras excite`)"
                    .into(),
        });
    }
    serde_json::from_str(text).map_err(|e| ExciteError::Json {
        origin: origin.into(),
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })
}

/// Checks a base frequency: finite and positive.
pub(crate) fn check_omega(omega_f: f64) -> Result<(), ExciteError> {
    check_finite(|| "omega_f".into(), omega_f)?;
    if omega_f <= 0.0 {
        return Err(ExciteError::InvalidSetting {
            name: "omega_f",
            value: omega_f,
            reason: "the base frequency must be positive (rad/s); the paper uses 2π/10".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::fourier as traj;
    use proptest::prelude::*;

    proptest! {
        // Velocity and acceleration are the exact derivatives of (74): a
        // central difference with h = 1e-5 has truncation error ~h²·|X⃛| ≈ 1e-9
        // and rounding ~1e-16/h ≈ 1e-11, so 1e-7 is a safe, tight bound.
        #[test]
        fn derivatives_match_finite_differences(
            c in proptest::collection::vec(-1.0..1.0f64, 12),
            t in 0.0..20.0f64,
        ) {
            let f = traj(&c);
            let h = 1e-5;
            let (p, m, s) = (f.eval(t + h), f.eval(t - h), f.eval(t));
            let v = (p.pos - m.pos) / (2.0 * h);
            let a = (p.vel - m.vel) / (2.0 * h);
            prop_assert!((v - s.vel).norm() < 1e-7);
            prop_assert!((a - s.acc).norm() < 1e-7);
        }

        // Periodic with 2π/ω_f, and the offset is the mean over a period
        // (the mean of 64 equally spaced samples of a degree-3 trig polynomial
        // is exact up to rounding).
        #[test]
        fn periodic_and_offset_is_mean(c in proptest::collection::vec(-1.0..1.0f64, 12), t in 0.0..10.0f64) {
            let f = traj(&c);
            let (x0, x1) = (f.eval(t), f.eval(t + f.period()));
            prop_assert!((x0.pos - x1.pos).norm() < 1e-12);
            let rows = f.sample(64, 1);
            let mean = rows.iter().map(|r| r.state.pos).sum::<nalgebra::Vector2<f64>>() / 64.0;
            prop_assert!((mean - f.offset()).norm() < 1e-12);
        }
    }

    #[test]
    fn json_round_trip_is_exact() {
        let f = traj(&[
            0.1,
            -0.2,
            0.3,
            0.4,
            0.5,
            -0.6,
            0.7,
            0.8,
            1.0 / 3.0,
            0.2,
            0.1,
            0.0,
        ]);
        let back = <FourierTrajectory>::from_json(&f.to_json()).unwrap();
        assert_eq!(back, f);
    }

    #[test]
    fn json_errors_name_the_problem() {
        let f = traj(&[0.1; 12]);
        let bad = f.to_json().replace("\"omega_f\"", "\"omega\"");
        let e = <FourierTrajectory>::from_json(&bad)
            .unwrap_err()
            .to_string();
        assert!(e.contains("omega") && e.contains("line"), "{e}");
        let short = r#"{"format":"aras-fourier/1","omega_f":1.0,"offset":[1,1],"a":[[1,2],[1]],"b":[[1,2],[1,2]]}"#;
        let e = <FourierTrajectory>::from_json(short)
            .unwrap_err()
            .to_string();
        assert!(e.contains("a[1]") && e.contains("1 entries"), "{e}");
        let neg = r#"{"format":"aras-fourier/1","omega_f":-1.0,"offset":[1,1],"a":[[1],[1]],"b":[[1],[1]]}"#;
        let e = <FourierTrajectory>::from_json(neg).unwrap_err().to_string();
        assert!(e.contains("omega_f = -1"), "{e}");
        let fmt = r#"{"format":"x","omega_f":1.0,"offset":[1,1],"a":[[1],[1]],"b":[[1],[1]]}"#;
        assert!(<FourierTrajectory>::from_json(fmt).is_err());
    }

    #[test]
    fn constructor_rejects_bad_values() {
        let one = || [vec![0.1], vec![0.1]];
        assert!(<FourierTrajectory>::new(0.0, [1.0, 1.0], one(), one()).is_err());
        assert!(<FourierTrajectory>::new(f64::NAN, [1.0, 1.0], one(), one()).is_err());
        assert!(<FourierTrajectory>::new(1.0, [f64::INFINITY, 1.0], one(), one()).is_err());
        assert!(
            <FourierTrajectory>::new(1.0, [1.0, 1.0], [vec![], vec![]], [vec![], vec![]]).is_err()
        );
        let e = <FourierTrajectory>::new(1.0, [1.0, 1.0], [vec![0.1], vec![f64::NAN]], one())
            .unwrap_err()
            .to_string();
        assert!(e.contains("a[1][0]"), "{e}");
    }
}
