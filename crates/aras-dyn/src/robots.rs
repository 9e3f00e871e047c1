//! Ready-made parameter sets: the real ARAS-Diamond from its CAD data
//! (`docs/model.md`, "Default robot"), and a builder for other spherical robots from simple geometry.

use nalgebra::{Matrix3, Vector3};

use crate::Inertia;
use crate::params::{DEFAULT_GRAVITY, Friction};
use crate::{ParamError, Params};

/// One row of the CAD table (`docs/model.md`, "Default robot").
struct CadRow {
    mass: f64,
    /// Principal inertia about the COM (the CAD's products are zero).
    ig: [f64; 3],
    /// COM = Ry(angle)·[0, 0, r].
    angle_deg: f64,
    r: f64,
}

/// The CAD table, from the robot authors' `Inertial_Parameters_Full.m`.
const CAD: [CadRow; 4] = [
    CadRow {
        mass: 0.1170118419,
        ig: [6.4413629155e-4, 6.3501139794e-4, 1.7161749378e-5],
        angle_deg: 22.9518,
        r: 0.252,
    },
    CadRow {
        mass: 0.1121923268,
        ig: [5.3590531389e-4, 5.2840271497e-4, 1.5074544696e-5],
        angle_deg: 22.6335,
        r: 0.228,
    },
    CadRow {
        mass: 0.1555782254,
        ig: [9.8499010048e-4, 9.3427520943e-4, 6.1016538598e-5],
        angle_deg: 22.8026,
        r: 0.276,
    },
    CadRow {
        mass: 0.1453301931,
        ig: [7.5779670437e-4, 7.4969800460e-4, 2.3482517406e-5],
        angle_deg: 22.5,
        r: 0.204,
    },
];

impl Params {
    /// The real ARAS-Diamond (the simulator's default truth): α = β = 45°,
    /// `g = [0, −9.81, 0]`, CAD inertia converted to the RCM by (28), and
    /// the friction and elasticity identified by the robot's authors
    /// (`docs/model.md`, "Default robot"). The same values as `fixtures/robots/aras-diamond.json`.
    pub fn aras_diamond() -> Self {
        let links = std::array::from_fn(|k| {
            let c = &CAD[k];
            let (s, co) = c.angle_deg.to_radians().sin_cos();
            // Ry(q)·[0, 0, r] = [r sin q, 0, r cos q].
            let rho = Vector3::new(c.r * s, 0.0, c.r * co);
            Inertia::from_com(c.mass, &Matrix3::from_diagonal(&Vector3::from(c.ig)), &rho)
        });
        Self {
            alpha_deg: 45.0,
            beta_deg: 45.0,
            gravity: Vector3::from(DEFAULT_GRAVITY),
            links,
            friction: Friction {
                viscous: [0.034321, 0.008779],
                coulomb: [0.076031, 0.28876],
                width: [0.0; 2],
            },
            elasticity: [0.001, 0.065757],
            extra: Default::default(),
        }
    }
}

/// A point mass on a link, in the link's arc plane (x–z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    /// Mass (kg, ≥ 0).
    pub mass: f64,
    /// Angle from the link's joint axis `z` towards `x` (rad).
    pub angle: f64,
    /// Distance from the RCM (m, ≥ 0).
    pub radius: f64,
}

/// A link modelled as a thin circular arc of uniform density centred on the
/// RCM, plus point masses (motors, hinges, instrument).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ArcLink {
    /// Mass of the arc (kg, ≥ 0).
    pub arc_mass: f64,
    /// Radius of the arc (m, ≥ 0).
    pub arc_radius: f64,
    /// Extra point masses.
    pub points: Vec<PointMass>,
}

impl ArcLink {
    /// Inertial parameters about the RCM in the link frame, for an arc that
    /// spans `span` rad from the joint axis `z` towards `x` (in the x–z
    /// plane, so `Ixy = Iyz = hy = 0`).
    ///
    /// For the arc, with `m` its mass, `r` its radius, `L` the span:
    /// `h = (m r/L)[1 − cos L, 0, sin L]`,
    /// `Ixx = m r²(1 − (L/2 − sin 2L/4)/L)`, `Iyy = m r²`,
    /// `Izz = m r²(1 − (L/2 + sin 2L/4)/L)`, `Ixz = −m r² sin²L/(2L)`;
    /// each point mass adds `m(|p|² 1 − p pᵀ)` and `m p`.
    pub fn link_params(&self, span: f64) -> Inertia {
        let (m, r, l) = (self.arc_mass, self.arc_radius, span);
        let mr2 = m * r * r;
        let s2 = l / 2.0 - (2.0 * l).sin() / 4.0;
        let c2 = l / 2.0 + (2.0 * l).sin() / 4.0;
        let sc = l.sin().powi(2) / 2.0;
        let mut i = Matrix3::new(
            mr2 * (1.0 - s2 / l),
            0.0,
            -mr2 * sc / l,
            0.0,
            mr2,
            0.0,
            -mr2 * sc / l,
            0.0,
            mr2 * (1.0 - c2 / l),
        );
        let mut h = Vector3::new(1.0 - l.cos(), 0.0, l.sin()) * (m * r / l);
        let mut mass = m;
        for p in &self.points {
            let (s, c) = p.angle.sin_cos();
            let pos = Vector3::new(p.radius * s, 0.0, p.radius * c);
            i += Inertia::point_mass(p.mass, &pos).inertia();
            h += pos * p.mass;
            mass += p.mass;
        }
        let mut out = Inertia {
            h,
            mass,
            ..Default::default()
        };
        out.set_inertia(&i);
        out
    }
}

/// Parameters of another coaxial spherical five-bar from simple geometry.
///
/// Assumptions: every link is a thin, uniform circular arc centred on the
/// RCM, lying in its link frame's x–z plane and spanning the link's arc
/// (α for links 1–2, β for links 3–4) from its joint axis; motors, hinges
/// and the instrument are point masses. A thin planar body has no extent
/// along `y`, so its pseudo-inertia is only positive *semi*definite; give
/// the point masses or a small offset if strict consistency is needed.
/// Friction and elasticity start at zero; gravity is `[0, −9.81, 0]`.
pub fn arc_robot(
    alpha_deg: f64,
    beta_deg: f64,
    links: &[ArcLink; 4],
) -> Result<Params, ParamError> {
    let mut p = Params::zero(alpha_deg, beta_deg);
    let geometry = p.geometry()?;
    for (k, l) in links.iter().enumerate() {
        let key = |f: &str| format!("arc_robot.links.{}.{f}", k + 1);
        for (name, v) in [("arc_mass", l.arc_mass), ("arc_radius", l.arc_radius)] {
            check_nonneg(v, &key(name))?;
        }
        for (j, pm) in l.points.iter().enumerate() {
            check_nonneg(pm.mass, &key(&format!("points[{j}].mass")))?;
            check_nonneg(pm.radius, &key(&format!("points[{j}].radius")))?;
            crate::json::finite(pm.angle, &key(&format!("points[{j}].angle")))?;
        }
        let span = if k < 2 {
            geometry.alpha()
        } else {
            geometry.beta()
        };
        p.links[k] = l.link_params(span);
    }
    p.validate()?;
    Ok(p)
}

fn check_nonneg(v: f64, key: &str) -> Result<(), ParamError> {
    crate::json::finite(v, key)?;
    if v < 0.0 {
        return Err(ParamError::Invalid {
            key: key.into(),
            value: v,
            reason: "masses and radii must not be negative",
        });
    }
    Ok(())
}
