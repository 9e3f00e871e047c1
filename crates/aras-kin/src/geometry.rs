//! Arc geometry α, β of the five-bar, validated once.

use crate::KinError;

/// Arc lengths of the spherical five-bar (rad).
///
/// `α` is the arc of the proximal links (from `a` to the elbow axes `b`, `c`),
/// `β` the arc of the distal links (from the elbows to the end-effector axis
/// `d`). Sines and cosines are cached because every kinematic evaluation needs
/// them. The singularity tolerance is the smallest admissible value of each
/// singularity distance (`sin A`, `sin γ`, `sin B`, `|K|`); closer poses are
/// rejected rather than evaluated into huge or NaN numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    alpha: f64,
    beta: f64,
    pub(crate) sa: f64,
    pub(crate) ca: f64,
    pub(crate) sb: f64,
    pub(crate) cb: f64,
    tol: f64,
}

/// Default singularity tolerance: sin(0.057°). Well outside the workspace
/// (77) every distance is above 0.2, so this only rejects truly degenerate poses.
pub const DEFAULT_SINGULARITY_TOLERANCE: f64 = 1e-3;

impl Geometry {
    /// Geometry from arc angles in radians; both must lie in (0, π).
    pub fn new(alpha: f64, beta: f64) -> Result<Self, KinError> {
        for (name, value) in [("alpha", alpha), ("beta", beta)] {
            if !value.is_finite() {
                return Err(KinError::NonFinite { name, value });
            }
            if value <= 0.0 || value >= std::f64::consts::PI {
                return Err(KinError::InvalidGeometry { name, value });
            }
        }
        Ok(Self {
            alpha,
            beta,
            sa: alpha.sin(),
            ca: alpha.cos(),
            sb: beta.sin(),
            cb: beta.cos(),
            tol: DEFAULT_SINGULARITY_TOLERANCE,
        })
    }

    /// Geometry from arc angles in degrees.
    pub fn from_degrees(alpha_deg: f64, beta_deg: f64) -> Result<Self, KinError> {
        Self::new(alpha_deg.to_radians(), beta_deg.to_radians())
    }

    /// The built ARAS-Diamond: α = β = 45°.
    pub fn aras_diamond() -> Self {
        Self::new(std::f64::consts::FRAC_PI_4, std::f64::consts::FRAC_PI_4)
            .expect("45° arcs are valid")
    }

    /// The same geometry with another singularity tolerance, in (0, 1).
    pub fn with_singularity_tolerance(mut self, tol: f64) -> Result<Self, KinError> {
        if !(tol > 0.0 && tol < 1.0) {
            return Err(KinError::InvalidTolerance { value: tol });
        }
        self.tol = tol;
        Ok(self)
    }

    /// Proximal arc α (rad).
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Distal arc β (rad).
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// Singularity tolerance (dimensionless).
    pub fn singularity_tolerance(&self) -> f64 {
        self.tol
    }

    /// Range of polar angles γ the arcs can reach: (|α − β|, α + β), open.
    pub fn reachable_gamma(&self) -> (f64, f64) {
        (
            (self.alpha - self.beta).abs(),
            (self.alpha + self.beta).min(std::f64::consts::PI),
        )
    }
}

impl Default for Geometry {
    fn default() -> Self {
        Self::aras_diamond()
    }
}
