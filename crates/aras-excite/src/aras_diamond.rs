//! ARAS-Diamond through this crate's traits (feature `aras-diamond`):
//! `aras-dyn`'s [`TaskRegressor`] as a design [`Regressor`],
//! [`FourierTrajectory`] as the simulator's [`Trajectory`], and motor-space
//! samples of a trajectory.
//!
//! The rest of the crate knows no robot; this module is the only one that
//! names `aras-kin` and `aras-dyn`, so a project with its own robot leaves
//! the feature off and neither crate is built.

use aras_dyn::{RegressorError, TaskRegressor, Trajectory};
use aras_kin::{Geometry, Workspace, evaluate};
use nalgebra::Vector2;

use crate::error::{ExciteError, check_finite};
use crate::regressor::Dual;
use crate::{FourierTrajectory, Limits, Motion, Regressor};

/// The design differentiates `aras-dyn`'s [`TaskRegressor`] (the same
/// [`aras_ident::LinearModel`] identification uses) by its dual-number rows.
impl Regressor for TaskRegressor {
    fn fill_dual(
        &self,
        q: &[Dual],
        q_dot: &[Dual],
        q_ddot: &[Dual],
        rows: &mut [Dual],
    ) -> Result<(), RegressorError> {
        let v = |a: &[Dual]| Vector2::new(a[0], a[1]);
        self.fill_rows(&Motion::new(v(q), v(q_dot), v(q_ddot)), rows)
    }
}

impl Trajectory for FourierTrajectory {
    fn eval(&self, t: f64) -> Motion {
        FourierTrajectory::eval(self, t)
    }

    fn period(&self) -> Option<f64> {
        Some(FourierTrajectory::period(self))
    }
}

impl Limits {
    /// The limits of an `aras-kin` [`Workspace`] (box and rates, (77)) with
    /// the acceleration limit `max_accel` (rad/s²).
    pub fn from_workspace(workspace: &Workspace, max_accel: Vector2<f64>) -> Self {
        Self {
            min: workspace.min(),
            max: workspace.max(),
            max_rate: workspace.max_rate(),
            max_accel,
        }
    }
}

/// One sample mapped to motor space by the kinematics: `t, θ, θ̇, θ̈`, the
/// columns of the log format (`t, theta1, theta2`, and the optional
/// `dtheta*`, `ddtheta*`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorRow {
    /// Time (s).
    pub t: f64,
    /// Motor angles `θ` (rad), (1)–(2).
    pub theta: Vector2<f64>,
    /// Motor rates `θ̇ = J Ẋ` (rad/s).
    pub theta_dot: Vector2<f64>,
    /// Motor accelerations `θ̈ = J Ẍ + J̇ Ẋ` (rad/s²).
    pub theta_ddot: Vector2<f64>,
}

impl MotorRow {
    /// `[t, θ1, θ2, θ̇1, θ̇2, θ̈1, θ̈2]` (s, rad, rad/s, rad/s²).
    pub fn to_array(&self) -> [f64; 7] {
        [
            self.t,
            self.theta[0],
            self.theta[1],
            self.theta_dot[0],
            self.theta_dot[1],
            self.theta_ddot[0],
            self.theta_ddot[1],
        ]
    }
}

impl FourierTrajectory {
    /// Samples the trajectory at `times` (s) and maps every sample to motor
    /// space with the kinematics (θ, θ̇, θ̈), the quantities of the log format.
    ///
    /// Errors (naming the time) if a sample is unreachable or singular.
    pub fn motor_samples(
        &self,
        geometry: &Geometry,
        times: &[f64],
    ) -> Result<Vec<MotorRow>, ExciteError> {
        times
            .iter()
            .map(|&t| {
                check_finite(|| "t".into(), t)?;
                let s = self.eval(t);
                let k =
                    evaluate(geometry, &Motion::new(s.pos, s.vel, s.acc)).map_err(|source| {
                        ExciteError::Kinematics {
                            t,
                            source: Box::new(source),
                        }
                    })?;
                Ok(MotorRow {
                    t,
                    theta: k.joint.pos,
                    theta_dot: k.joint.vel,
                    theta_ddot: k.joint.acc,
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::fourier as traj;
    use aras_ident::LinearModel;

    /// The adapter gives exactly the model's own regressor, in values and
    /// in the real part of its dual rows.
    #[test]
    fn adapter_matches_model() {
        let r = TaskRegressor::aras_diamond().unwrap();
        assert_eq!(r.columns(), 42);
        let (x, xd, xdd) = (
            Vector2::new(1.4, 1.0),
            Vector2::new(0.3, -0.7),
            Vector2::new(2.0, 1.0),
        );
        let mut rows = vec![0.0; 84];
        r.fill(x.as_slice(), xd.as_slice(), xdd.as_slice(), &mut rows)
            .unwrap();
        let s = evaluate(r.geometry(), &Motion::new(x, xd, xdd)).unwrap();
        let y = r.model().regressor(&s);
        assert_eq!(y.as_slice(), &rows[..]);
        let lift = |v: Vector2<f64>| [Dual::from_re(v[0]), Dual::from_re(v[1])];
        let mut drows = vec![Dual::from_re(0.0); 84];
        r.fill_dual(&lift(x), &lift(xd), &lift(xdd), &mut drows)
            .unwrap();
        assert!(drows.iter().zip(&rows).all(|(d, v)| d.re == *v));
        let f = FourierTrajectory::at_rest(1.0, 2, x).unwrap();
        assert_eq!(Trajectory::period(&f), Some(std::f64::consts::TAU));
        assert_eq!(Trajectory::eval(&f, 0.3).pos, x);
    }

    /// The paper's limits are the kinematics' workspace (77) with the
    /// default acceleration limit: the two homes of the box agree.
    #[test]
    fn paper_limits_are_the_paper_workspace() {
        let p = Limits::paper();
        assert_eq!(Limits::from_workspace(&Workspace::paper(), p.max_accel), p);
    }

    #[test]
    fn motor_samples_follow_the_kinematics() {
        let g = Geometry::aras_diamond();
        let f = traj(&[
            0.1, -0.2, 0.1, 0.05, 0.2, -0.1, 0.1, 0.1, 0.05, 0.1, 0.1, 0.0,
        ]);
        let rows = f.motor_samples(&g, &[0.0, 1.3, 4.0]).unwrap();
        for r in &rows {
            let s = f.eval(r.t);
            let ik = aras_kin::inverse(&g, &s.pos).unwrap();
            assert!((ik.theta - r.theta).norm() < 1e-14);
            // θ1 + θ2 = 2φ, (7), so the rates add up the same way.
            assert!((r.theta_dot.sum() - 2.0 * s.vel[0]).abs() < 1e-12);
            assert!((r.theta_ddot.sum() - 2.0 * s.acc[0]).abs() < 1e-12);
        }
        let far = FourierTrajectory::at_rest(1.0, 1, Vector2::new(1.0, 2.0)).unwrap();
        let e = far.motor_samples(&g, &[0.5]).unwrap_err().to_string();
        assert!(e.contains("t = 0.5"), "{e}");
    }
}
