//! Physically consistent least squares (67)–(73) as one convex SDP (clarabel).
//!
//! Each link's pseudo-inertia (`docs/model.md`, "Physical consistency")
//! `𝒥_k = [[½tr(I_k)·1 − I_k, h_k], [h_kᵀ, m_k]]` is linear in
//! `(I_k, h_k, m_k)`, and `𝒥_k ⪰ 0` is exactly (67)–(69). With the mass an
//! extra decision variable per link (for ARAS-Diamond it does not enter the
//! dynamics; for a robot whose standard vector holds the mass, such as a
//! serial arm's `m` per link, [`LinkLayout::with_mass_column`] ties the two
//! by an equality), mass
//! bounds, optional box bounds (73) and sign constraints (70), the problem
//!
//! ```text
//! minimise  ‖R K β − z‖² + λ (‖D(β − β_ref)‖² + Σ_k d_k² (m_k − m_ref,k)²)
//! subject to 𝒥_k(β, m_k) ⪰ ε_k I, bounds
//! ```
//!
//! is convex: one interior-point solve gives the global optimum, no random
//! restarts as with (72). `‖R K β − z‖² + ρ² = ‖W_b K β − T‖²` comes from the
//! thin QR of the (weighted) base regressor ([`ReducedLs`]), so the problem's
//! size does not grow with the number of samples. The objective is posed as
//! a second-order cone (epigraph `t ≥ ‖·‖`), which keeps the solver away
//! from the squared condition number of a quadratic form.
//!
//! **Regulariser.** Only combinations `K β` enter the data; the rest of `β`
//! (and the masses) is fixed by nothing but the constraints. The term
//! `λ‖D(β − β_ref)‖²` picks, among equally good standard sets, the one
//! closest to the reference (CAD). `D_jj = ‖R K e_j‖` is the torque a unit of
//! parameter `j` produces over the data, so every parameter's deviation is
//! priced in the same unit as the residual (a ridge on standardised
//! columns); parameters with no effect on the data get the smallest non-zero
//! weight, and a mass gets its link's first-moment weight times the link's
//! length scale (changing `m` by δ is like changing `h` by `δ·L`). With the
//! default `λ = 1e-6` the fit changes by about `λ·κ²` relative, with `κ` the
//! condition number of the column-scaled base regressor.
//!
//! **Scaling and margin.** `𝒥_k` mixes kg·m², kg·m and kg; the cone is
//! imposed on `T𝒥_kT`, `T = diag(1, 1, 1, L_k)`, whose entries are all
//! kg·m², with `L_k = sqrt(tr I_ref / (2 m_ref))` (the reference link's RMS
//! distance of mass from the pivot). The strictness margin is
//! `ε_k = psd_margin · m_ref L_k²`.

use std::fmt;
use std::time::Instant;

use aras_core::Inertia;
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use serde::Serialize;

use crate::base::BaseParameters;
use crate::dense::symmetric_eigenvalues;
use crate::error::IdentError;
use crate::ls::ReducedLs;

/// Which standard parameters are one link's inertia (about the pivot, link
/// frame) and first moment, and the link's mass range.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkLayout {
    /// Link name (for reports).
    pub name: String,
    /// Indices of `Ixx, Ixy, Ixz, Iyy, Iyz, Izz` (38) in the standard vector
    /// (tensor entries: `Ixy = I[0,1] = −Σ m x y`).
    pub inertia: [usize; 6],
    /// Indices of `hx, hy, hz` (`h = m ρ`).
    pub first_moment: [usize; 3],
    /// Reference (CAD) mass, kg.
    pub mass_reference: f64,
    /// Mass bounds, kg.
    pub mass_bounds: (f64, f64),
    /// Index of the link's mass in the standard vector, when the dynamics
    /// holds it (a serial arm's `m`): the pseudo-inertia's mass is then
    /// that parameter. `None` (ARAS-Diamond's links): the mass is a
    /// variable of its own that only the constraints and the regulariser
    /// fix.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass_column: Option<usize>,
}

impl LinkLayout {
    /// A link with mass bounds `±20 %` around the reference mass.
    pub fn new(
        name: impl Into<String>,
        inertia: [usize; 6],
        first_moment: [usize; 3],
        mass_reference: f64,
    ) -> Self {
        Self {
            name: name.into(),
            inertia,
            first_moment,
            mass_reference,
            mass_bounds: (0.8 * mass_reference, 1.2 * mass_reference),
            mass_column: None,
        }
    }

    /// The link's mass is the standard parameter at `index` (see
    /// [`LinkLayout::mass_column`]).
    pub fn with_mass_column(mut self, index: usize) -> Self {
        self.mass_column = Some(index);
        self
    }

    /// Replaces the mass bounds.
    pub fn with_mass_bounds(mut self, lower: f64, upper: f64) -> Self {
        self.mass_bounds = (lower, upper);
        self
    }
}

/// Settings of the physically consistent solve, with documented defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SdpSettings {
    /// Regulariser weight `λ` (default 1e-6; see the module docs).
    pub regularisation: f64,
    /// PSD margin relative to the link's scale `m_ref L²` (default 1e-6):
    /// `T𝒥T ⪰ ε I` makes (67)–(69) strict.
    pub psd_margin: f64,
    /// Solver feasibility and gap tolerance (default 1e-10, tighter than
    /// clarabel's 1e-8: the parameter combinations the data do not see are
    /// fixed only by the small regulariser, and need the extra digits).
    pub tolerance: f64,
    /// Iteration limit (default 200).
    pub max_iter: u32,
    /// Time limit in seconds (default 60).
    pub time_limit: f64,
    /// A constraint is reported active when its slack is below this
    /// fraction of its natural scale (default 1e-5).
    pub active_tolerance: f64,
}

impl Default for SdpSettings {
    fn default() -> Self {
        Self {
            regularisation: 1e-6,
            psd_margin: 1e-6,
            tolerance: 1e-10,
            max_iter: 200,
            time_limit: 60.0,
            active_tolerance: 1e-5,
        }
    }
}

/// Kinds of constraint that can be active at the solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ConstraintKind {
    /// Link mass at its lower bound.
    MassLower,
    /// Link mass at its upper bound.
    MassUpper,
    /// Parameter at its lower box bound (73).
    BoxLower,
    /// Parameter at its upper box bound (73).
    BoxUpper,
    /// Parameter at zero under a sign constraint (70).
    NonNegative,
    /// Pseudo-inertia at the PSD margin (a link at the edge of physical consistency).
    PseudoInertia,
}

/// An active constraint at the solution.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ActiveConstraint {
    /// Kind.
    pub kind: ConstraintKind,
    /// Parameter or link name.
    pub name: String,
    /// Slack (distance to the bound, in the constraint's units).
    pub slack: f64,
}

/// Per-link physical-consistency report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkReport {
    /// Link name.
    pub name: String,
    /// Identified mass, kg.
    pub mass: f64,
    /// Smallest eigenvalue of the pseudo-inertia `𝒥` as defined (mixed units, kg·m² and kg).
    pub min_eigenvalue: f64,
    /// Smallest eigenvalue of `T𝒥T`, kg·m².
    pub min_eigenvalue_scaled: f64,
    /// Largest eigenvalue of `T𝒥T`, kg·m².
    pub max_eigenvalue_scaled: f64,
    /// The margin `ε` imposed on `T𝒥T`, kg·m².
    pub margin: f64,
    /// Length scale `L`, m.
    pub length_scale: f64,
    /// `T𝒥T` at its margin (active PSD constraint).
    pub psd_near_singular: bool,
}

/// The physically consistent estimate and the solver's account of it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SdpSolution {
    /// Standard parameters `β`; those constrained `≥ 0` are exactly 0 where
    /// the solver left them negative within its feasibility tolerance.
    pub standard: Vec<f64>,
    /// Link masses, in the order the links were given.
    pub masses: Vec<f64>,
    /// Base parameters `K β`.
    pub base: Vec<f64>,
    /// Solver status ([`Solved`](crate::SolverStatus::Solved) or
    /// [`AlmostSolved`](crate::SolverStatus::AlmostSolved)).
    pub status: crate::SolverStatus,
    /// True for `AlmostSolved` (reduced accuracy).
    pub reduced_accuracy: bool,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Solver time, s.
    pub solve_time: f64,
    /// Set-up plus solve time, s.
    pub total_time: f64,
    /// `‖W_b K β − T‖` of the (weighted) data.
    pub residual_norm: f64,
    /// The unconstrained optimum's residual norm, for comparison.
    pub ols_residual_norm: f64,
    /// Per-link report.
    pub links: Vec<LinkReport>,
    /// Active constraints.
    pub active: Vec<ActiveConstraint>,
}

/// The physically consistent identification problem (builder).
#[derive(Debug, Clone)]
pub struct ConsistentLs {
    names: Vec<String>,
    reference: Vec<f64>,
    links: Vec<LinkLayout>,
    boxes: Vec<(usize, f64, f64)>,
    nonnegative: Vec<usize>,
    settings: SdpSettings,
}

impl ConsistentLs {
    /// A problem over the named standard parameters with a reference (CAD)
    /// set `reference`, towards which the regulariser pulls.
    pub fn new<S: AsRef<str>>(names: &[S], reference: Vec<f64>) -> Result<Self, IdentError> {
        if names.len() != reference.len() {
            return Err(IdentError::DimensionMismatch {
                what: "reference parameter vector",
                expected: names.len(),
                found: reference.len(),
                hint: "give one reference value per standard parameter",
            });
        }
        crate::error::check_finite_vec("reference parameter vector", &reference)?;
        Ok(Self {
            names: names.iter().map(|s| s.as_ref().to_owned()).collect(),
            reference,
            links: Vec::new(),
            boxes: Vec::new(),
            nonnegative: Vec::new(),
            settings: SdpSettings::default(),
        })
    }

    /// Index of a standard parameter by name.
    pub fn index_of(&self, name: &str) -> Result<usize, IdentError> {
        self.names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| IdentError::UnknownParameter {
                name: name.to_owned(),
                known: self.names.join(", "),
            })
    }

    fn check_index(&self, what: &str, i: usize) -> Result<(), IdentError> {
        if i >= self.names.len() {
            return Err(IdentError::IndexOutOfRange {
                what: what.to_owned(),
                index: i,
                count: self.names.len(),
            });
        }
        Ok(())
    }

    /// Adds a link. Its indices must be in range and belong to no other link.
    pub fn link(&mut self, layout: LinkLayout) -> Result<&mut Self, IdentError> {
        let bad = |reason: String| IdentError::InvalidLayout {
            link: layout.name.clone(),
            reason,
        };
        let idx: Vec<usize> = layout
            .inertia
            .iter()
            .chain(&layout.first_moment)
            .chain(&layout.mass_column)
            .copied()
            .collect();
        for &i in &idx {
            self.check_index(&format!("link `{}`", layout.name), i)?;
        }
        for (a, &i) in idx.iter().enumerate() {
            if idx[..a].contains(&i) {
                return Err(bad(format!(
                    "parameter `{}` is listed twice",
                    self.names[i]
                )));
            }
            if let Some(other) = self.links.iter().find(|l| {
                l.inertia.contains(&i) || l.first_moment.contains(&i) || l.mass_column == Some(i)
            }) {
                return Err(bad(format!(
                    "parameter `{}` already belongs to link `{}`",
                    self.names[i], other.name
                )));
            }
        }
        if !(layout.mass_reference.is_finite() && layout.mass_reference > 0.0) {
            return Err(bad(format!(
                "reference mass {} must be positive and finite",
                layout.mass_reference
            )));
        }
        let (lo, hi) = layout.mass_bounds;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(IdentError::InvalidBounds {
                name: format!("mass of {}", layout.name),
                lower: lo,
                upper: hi,
            });
        }
        if hi <= 0.0 {
            return Err(bad(format!("mass upper bound {hi} must be positive")));
        }
        self.links.push(layout);
        Ok(self)
    }

    /// Adds a link by parameter names (`[Ixx, Ixy, Ixz, Iyy, Iyz, Izz]`,
    /// `[hx, hy, hz]`) with `±20 %` mass bounds.
    pub fn link_by_names(
        &mut self,
        name: &str,
        inertia: [&str; 6],
        first_moment: [&str; 3],
        mass_reference: f64,
    ) -> Result<&mut Self, IdentError> {
        let mut ii = [0; 6];
        for (k, n) in inertia.iter().enumerate() {
            ii[k] = self.index_of(n)?;
        }
        let mut hh = [0; 3];
        for (k, n) in first_moment.iter().enumerate() {
            hh[k] = self.index_of(n)?;
        }
        self.link(LinkLayout::new(name, ii, hh, mass_reference))
    }

    /// Box bound `lower ≤ β_i ≤ upper`.
    pub fn bound(&mut self, index: usize, lower: f64, upper: f64) -> Result<&mut Self, IdentError> {
        self.check_index("box bound", index)?;
        if !(lower.is_finite() && upper.is_finite() && lower <= upper) {
            return Err(IdentError::InvalidBounds {
                name: self.names[index].clone(),
                lower,
                upper,
            });
        }
        self.boxes.push((index, lower, upper));
        Ok(self)
    }

    /// Box bounds (73) around the reference: `[lo·β_ref, hi·β_ref]` (ends
    /// swapped for a negative reference), e.g. `lo = 0.8, hi = 1.25`.
    /// Parameters whose reference is exactly zero are left free, since (73)
    /// would pin them to zero.
    pub fn box_around_reference(
        &mut self,
        indices: &[usize],
        lo: f64,
        hi: f64,
    ) -> Result<&mut Self, IdentError> {
        for &i in indices {
            self.check_index("box bound", i)?;
            let r = self.reference[i];
            if r == 0.0 {
                continue;
            }
            let (a, b) = (lo * r, hi * r);
            self.bound(i, a.min(b), a.max(b))?;
        }
        Ok(self)
    }

    /// Mass bounds `(1 ∓ fraction) ×` each added link's reference mass
    /// (replacing the `±20 %` of [`LinkLayout::new`]), e.g. from a
    /// configuration. `fraction` must lie in `[0, 1)`.
    pub fn mass_tolerance(&mut self, fraction: f64) -> Result<&mut Self, IdentError> {
        if !(fraction.is_finite() && (0.0..1.0).contains(&fraction)) {
            return Err(IdentError::InvalidSetting {
                name: "mass tolerance",
                value: fraction,
                reason: "give a fraction in [0, 1) of the reference mass (0.2 for ±20 %)",
            });
        }
        for l in &mut self.links {
            let m = l.mass_reference;
            l.mass_bounds = ((1.0 - fraction) * m, (1.0 + fraction) * m);
        }
        Ok(self)
    }

    /// Sign constraints (70) `β_i ≥ 0` on the named parameters (e.g. `Fv1`, `Fc1`, `Ke1`).
    pub fn nonnegative<S: AsRef<str>>(&mut self, names: &[S]) -> Result<&mut Self, IdentError> {
        for n in names {
            let i = self.index_of(n.as_ref())?;
            self.nonnegative.push(i);
        }
        Ok(self)
    }

    /// Replaces the settings.
    pub fn settings(&mut self, settings: SdpSettings) -> &mut Self {
        self.settings = settings;
        self
    }

    /// The links added so far.
    pub fn links(&self) -> &[LinkLayout] {
        &self.links
    }

    fn check_settings(&self) -> Result<(), IdentError> {
        let s = &self.settings;
        let pos = |name, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(IdentError::InvalidSetting {
                    name,
                    value: v,
                    reason: "must be positive and finite",
                })
            }
        };
        pos("regularisation", s.regularisation)?;
        pos("tolerance", s.tolerance)?;
        pos("time_limit", s.time_limit)?;
        pos("active_tolerance", s.active_tolerance)?;
        if !(s.psd_margin.is_finite() && s.psd_margin >= 0.0) {
            return Err(IdentError::InvalidSetting {
                name: "psd_margin",
                value: s.psd_margin,
                reason: "must be ≥ 0 and finite",
            });
        }
        Ok(())
    }

    /// Length scale `L_k` of a link from its reference values.
    fn length_scale(&self, l: &LinkLayout) -> f64 {
        let r = &self.reference;
        let tr = r[l.inertia[0]] + r[l.inertia[3]] + r[l.inertia[5]];
        let len = (tr / (2.0 * l.mass_reference)).sqrt();
        if len.is_finite() && len > 0.0 {
            len
        } else {
            1.0
        }
    }

    /// Solves the SDP for the base map `base` and the reduced (weighted)
    /// least-squares problem `ls` in base-parameter space.
    pub fn solve(&self, base: &BaseParameters, ls: &ReducedLs) -> Result<SdpSolution, IdentError> {
        let start = Instant::now();
        self.check_settings()?;
        self.check_dimensions(base, ls)?;
        let scales = self.scales(base, ls);
        let mut c = Conic::default();
        self.objective_cone(&mut c, &scales, ls);
        self.mass_ties(&mut c);
        let linear = self.linear_inequalities(&mut c);
        let margins = self.psd_cones(&mut c, &scales.lens);
        let solver = self.run(c)?;
        self.report(base, ls, &solver, (&linear, &margins, &scales.lens), start)
    }

    /// The base map and the reduced problem must be over this problem's
    /// standard parameters.
    fn check_dimensions(&self, base: &BaseParameters, ls: &ReducedLs) -> Result<(), IdentError> {
        let n = self.names.len();
        if base.n_standard() != n {
            return Err(IdentError::DimensionMismatch {
                what: "standard parameters of the base map",
                expected: n,
                found: base.n_standard(),
                hint: "build the base map and the SDP over the same standard parameters",
            });
        }
        if ls.names().len() != base.n_base() {
            return Err(IdentError::DimensionMismatch {
                what: "columns of the reduced least-squares problem",
                expected: base.n_base(),
                found: ls.names().len(),
                hint: "reduce the base regressor W_b = W E of the same base map",
            });
        }
        Ok(())
    }

    /// The objective's matrix `A = R K` in standard-parameter space and the
    /// regulariser's scales: each parameter's column norm of `A` (the
    /// smallest positive one where a column is zero), each link's mass
    /// scale from its first moments, and the links' length scales.
    fn scales(&self, base: &BaseParameters, ls: &ReducedLs) -> Scales {
        let (n, b) = (self.names.len(), base.n_base());
        let k = base.k();
        let r = ls.r();
        let a = faer::Mat::from_fn(b, n, |i, j| {
            (i..b).map(|l| r[(i, l)] * k[(l, j)]).sum::<f64>()
        });
        let mut d: Vec<f64> = (0..n)
            .map(|j| (0..b).map(|i| a[(i, j)] * a[(i, j)]).sum::<f64>().sqrt())
            .collect();
        let dmin = d
            .iter()
            .copied()
            .filter(|&v| v > 0.0)
            .fold(f64::INFINITY, f64::min);
        let dmin = if dmin.is_finite() { dmin } else { 1.0 };
        let lens: Vec<f64> = self.links.iter().map(|l| self.length_scale(l)).collect();
        let dm: Vec<f64> = self
            .links
            .iter()
            .zip(&lens)
            .map(|(l, len)| {
                let v = l.first_moment.iter().map(|&j| d[j]).sum::<f64>() / 3.0 * len;
                if v > 0.0 { v } else { dmin }
            })
            .collect();
        d.iter_mut().for_each(|v| {
            if *v == 0.0 {
                *v = dmin;
            }
        });
        Scales { a, d, dm, lens }
    }

    /// The first constraint block, the objective's second-order cone:
    /// `t ≥ ‖[A β − z; √λ D(β − β_ref); √λ d_m (m − m_ref)]‖`.
    fn objective_cone(&self, c: &mut Conic, scales: &Scales, ls: &ReducedLs) {
        let (n, nl, b) = (self.names.len(), self.links.len(), ls.names().len());
        let sl = self.settings.regularisation.sqrt();
        let Scales { a, d, dm, .. } = scales;
        c.entry(n + nl, -1.0);
        c.close(0.0);
        for i in 0..b {
            for j in 0..n {
                c.entry(j, -a[(i, j)]);
            }
            c.close(-ls.z()[i]);
        }
        for j in 0..n {
            c.entry(j, -sl * d[j]);
            c.close(-sl * d[j] * self.reference[j]);
        }
        for (kk, l) in self.links.iter().enumerate() {
            c.entry(n + kk, -sl * dm[kk]);
            c.close(-sl * dm[kk] * l.mass_reference);
        }
        c.cones
            .push(SupportedConeT::SecondOrderConeT(1 + b + n + nl));
    }

    /// The second block: a link's mass variable is its standard parameter
    /// where the dynamics holds it, `β_j − m_k = 0`.
    fn mass_ties(&self, c: &mut Conic) {
        let n = self.names.len();
        let tied = c.row;
        for (kk, l) in self.links.iter().enumerate() {
            if let Some(j) = l.mass_column {
                c.entry(j, 1.0);
                c.entry(n + kk, -1.0);
                c.close(0.0);
            }
        }
        if c.row > tied {
            c.cones.push(SupportedConeT::ZeroConeT(c.row - tied));
        }
    }

    /// The third block, linear inequalities `s = rhs − A x ≥ 0`: mass
    /// ranges, box bounds (73) and sign constraints (70). Returns their
    /// first row and, per row, its kind, name, variable and scale (for the
    /// active-constraint report).
    fn linear_inequalities(&self, c: &mut Conic) -> Linear {
        let n = self.names.len();
        let start = c.row;
        let mut rows = Vec::new();
        for (kk, l) in self.links.iter().enumerate() {
            c.entry(n + kk, -1.0);
            c.close(-l.mass_bounds.0);
            rows.push((
                ConstraintKind::MassLower,
                l.name.clone(),
                n + kk,
                l.mass_reference,
            ));
            c.entry(n + kk, 1.0);
            c.close(l.mass_bounds.1);
            rows.push((
                ConstraintKind::MassUpper,
                l.name.clone(),
                n + kk,
                l.mass_reference,
            ));
        }
        for &(j, lo, hi) in &self.boxes {
            let scale = (hi - lo)
                .abs()
                .max(self.reference[j].abs())
                .max(f64::MIN_POSITIVE);
            c.entry(j, -1.0);
            c.close(-lo);
            rows.push((ConstraintKind::BoxLower, self.names[j].clone(), j, scale));
            c.entry(j, 1.0);
            c.close(hi);
            rows.push((ConstraintKind::BoxUpper, self.names[j].clone(), j, scale));
        }
        for &j in &self.nonnegative {
            c.entry(j, -1.0);
            c.close(0.0);
            rows.push((
                ConstraintKind::NonNegative,
                self.names[j].clone(),
                j,
                self.reference[j].abs(),
            ));
        }
        if c.row > start {
            c.cones
                .push(SupportedConeT::NonnegativeConeT(c.row - start));
        }
        Linear { start, rows }
    }

    /// The fourth block, `svec(T𝒥T − εI) ∈ S⁴₊` per link (upper triangle by columns,
    /// off-diagonals × √2, as clarabel packs them). Returns each link's
    /// margin `ε`.
    fn psd_cones(&self, c: &mut Conic, lens: &[f64]) -> Vec<f64> {
        let n = self.names.len();
        let r2 = std::f64::consts::SQRT_2;
        let basis = pseudo_inertia_basis();
        let mut margins = Vec::with_capacity(self.links.len());
        for (kk, l) in self.links.iter().enumerate() {
            let len = lens[kk];
            let eps = self.settings.psd_margin * l.mass_reference * len * len;
            margins.push(eps);
            // The variable multiplying input `p` of `𝒥` (nine standard
            // parameters, then the mass).
            let var = |p: usize| match p {
                0..6 => l.inertia[p],
                6..9 => l.first_moment[p - 6],
                _ => n + kk,
            };
            for (r, col) in SVEC4 {
                let scale = if r == 3 { len } else { 1.0 } * if col == 3 { len } else { 1.0 };
                let packing = if r == col { 1.0 } else { r2 };
                for (p, unit) in basis.iter().enumerate() {
                    let coefficient = unit[col][r] * scale;
                    if coefficient != 0.0 {
                        c.entry(var(p), -(coefficient * packing));
                    }
                }
                c.close(if r == col { -eps } else { 0.0 });
            }
            c.cones.push(SupportedConeT::PSDTriangleConeT(4));
        }
        margins
    }

    /// Clarabel on the cones built, minimising the epigraph variable `t`;
    /// an infeasible or failed solve is an error.
    fn run(&self, c: Conic) -> Result<DefaultSolver<f64>, IdentError> {
        let s = self.settings;
        let nx = self.names.len() + self.links.len() + 1;
        let amat = CscMatrix::new_from_triplets(c.row, nx, c.ri, c.ci, c.vv);
        let p = CscMatrix::zeros((nx, nx));
        let mut q = vec![0.0; nx];
        q[nx - 1] = 1.0;
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(s.max_iter)
            .time_limit(s.time_limit)
            .tol_gap_abs(s.tolerance)
            .tol_gap_rel(s.tolerance)
            .tol_feas(s.tolerance)
            .build()
            .map_err(|e| IdentError::SolverSetup {
                stage: "settings",
                source: Box::new(e),
            })?;
        let mut solver =
            DefaultSolver::new(&p, &q, &amat, &c.rhs, &c.cones, settings).map_err(|e| {
                IdentError::SolverSetup {
                    stage: "problem data",
                    source: Box::new(e),
                }
            })?;
        solver.solve();
        let sol = &solver.solution;
        let status = solver_status(sol.status);
        match sol.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => Ok(solver),
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                Err(IdentError::Infeasible { status })
            }
            _ => Err(IdentError::SolverFailed {
                status,
                iterations: sol.iterations,
            }),
        }
    }

    /// The solution: standard parameters (sign-constrained ones within the
    /// feasibility tolerance set to exactly 0), masses, base parameters,
    /// the residual, each link's pseudo-inertia eigenvalues, and the active
    /// constraints.
    fn report(
        &self,
        base: &BaseParameters,
        ls: &ReducedLs,
        solver: &DefaultSolver<f64>,
        (linear, margins, lens): (&Linear, &[f64], &[f64]),
        start: Instant,
    ) -> Result<SdpSolution, IdentError> {
        let s = self.settings;
        let (n, nl) = (self.names.len(), self.links.len());
        let sol = &solver.solution;
        let status = solver_status(sol.status);
        let x = &sol.x;
        let mut standard = x[..n].to_vec();
        // An interior-point solution meets `β_j ≥ 0` only to its feasibility
        // tolerance (−7e-12 has been seen at an active bound); a consumer
        // that requires the sign (MuJoCo's frictionloss) would refuse it.
        let feasible = s.tolerance * (1.0 + x.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        for &j in &self.nonnegative {
            if standard[j] < 0.0 && standard[j] >= -feasible {
                standard[j] = 0.0;
            }
        }
        let masses = x[n..n + nl].to_vec();
        let base_values = base.to_base(&standard)?;
        let residual_norm = ls.rss(&base_values)?.sqrt();
        let tol = s.active_tolerance;
        let mut active = Vec::new();
        for (kk, (kind, name, var, scale)) in linear.rows.iter().enumerate() {
            let slack = sol.s[linear.start + kk];
            let scale = scale.max(x[*var].abs());
            if slack <= tol * scale || (scale == 0.0 && slack <= 0.0) {
                active.push(ActiveConstraint {
                    kind: *kind,
                    name: name.clone(),
                    slack,
                });
            }
        }
        let mut links = Vec::with_capacity(nl);
        for (kk, l) in self.links.iter().enumerate() {
            let (j, js) = pseudo_inertia(&standard, l, masses[kk], lens[kk]);
            let ev = symmetric_eigenvalues(&j);
            let evs = symmetric_eigenvalues(&js);
            let near = evs[0] - margins[kk] <= tol * evs[3].abs();
            if near {
                active.push(ActiveConstraint {
                    kind: ConstraintKind::PseudoInertia,
                    name: l.name.clone(),
                    slack: evs[0] - margins[kk],
                });
            }
            links.push(LinkReport {
                name: l.name.clone(),
                mass: masses[kk],
                min_eigenvalue: ev[0],
                min_eigenvalue_scaled: evs[0],
                max_eigenvalue_scaled: evs[3],
                margin: margins[kk],
                length_scale: lens[kk],
                psd_near_singular: near,
            });
        }
        Ok(SdpSolution {
            standard,
            masses,
            base: base_values,
            reduced_accuracy: sol.status == SolverStatus::AlmostSolved,
            status,
            iterations: sol.iterations,
            solve_time: sol.solve_time,
            total_time: start.elapsed().as_secs_f64(),
            residual_norm,
            ols_residual_norm: ls.min_rss().sqrt(),
            links,
            active,
        })
    }
}

/// The objective's matrix and the regulariser's scales ([`ConsistentLs::scales`]).
struct Scales {
    /// `A = R K` (b × n).
    a: faer::Mat<f64>,
    /// Each standard parameter's scale.
    d: Vec<f64>,
    /// Each link's mass scale.
    dm: Vec<f64>,
    /// Each link's length scale.
    lens: Vec<f64>,
}

/// The linear inequalities' first row and, per row, its kind, name,
/// variable and scale.
struct Linear {
    start: usize,
    rows: Vec<(ConstraintKind, String, usize, f64)>,
}

/// The conic constraints `A x + s = rhs`, `s` in `cones`, built row by row
/// as clarabel takes them (triplets of `A`).
#[derive(Default)]
struct Conic {
    ri: Vec<usize>,
    ci: Vec<usize>,
    vv: Vec<f64>,
    rhs: Vec<f64>,
    row: usize,
    cones: Vec<SupportedConeT<f64>>,
}

impl Conic {
    /// Coefficient `v` of variable `col` in the current row (zeros are
    /// not stored).
    fn entry(&mut self, col: usize, v: f64) {
        if v != 0.0 {
            self.ri.push(self.row);
            self.ci.push(col);
            self.vv.push(v);
        }
    }

    /// Ends the current row with its right-hand side.
    fn close(&mut self, rhs: f64) {
        self.rhs.push(rhs);
        self.row += 1;
    }
}

fn solver_status(s: SolverStatus) -> crate::SolverStatus {
    use crate::SolverStatus as S;
    match s {
        SolverStatus::Unsolved => S::Unsolved,
        SolverStatus::Solved => S::Solved,
        SolverStatus::AlmostSolved => S::AlmostSolved,
        SolverStatus::PrimalInfeasible => S::PrimalInfeasible,
        SolverStatus::DualInfeasible => S::DualInfeasible,
        SolverStatus::AlmostPrimalInfeasible => S::AlmostPrimalInfeasible,
        SolverStatus::AlmostDualInfeasible => S::AlmostDualInfeasible,
        SolverStatus::MaxIterations => S::MaxIterations,
        SolverStatus::MaxTime => S::MaxTime,
        SolverStatus::NumericalError => S::NumericalError,
        SolverStatus::InsufficientProgress => S::InsufficientProgress,
        SolverStatus::CallbackTerminated => S::CallbackTerminated,
    }
}

/// Upper-triangle entries `(row, column)` of a symmetric 4×4 matrix, by
/// columns: the order clarabel packs a PSD cone's `svec` in.
const SVEC4: [(usize, usize); 10] = [
    (0, 0),
    (0, 1),
    (1, 1),
    (0, 2),
    (1, 2),
    (2, 2),
    (0, 3),
    (1, 3),
    (2, 3),
    (3, 3),
];

/// `𝒥` of each unit input (nine standard parameters, then the mass),
/// column-major: `𝒥` is linear in them, so these are the coefficients of
/// the constraint, taken from [`Inertia::pseudo_inertia`] rather than
/// written out a second time.
fn pseudo_inertia_basis() -> [[[f64; 4]; 4]; 10] {
    std::array::from_fn(|p| {
        let mut standard = [0.0; 9];
        let mass = if p < 9 {
            standard[p] = 1.0;
            0.0
        } else {
            1.0
        };
        Inertia::from_standard(&standard, mass)
            .pseudo_inertia()
            .into()
    })
}

/// The pseudo-inertia `𝒥` of a link and its scaled form `T𝒥T`.
fn pseudo_inertia(
    beta: &[f64],
    l: &LinkLayout,
    m: f64,
    len: f64,
) -> ([[f64; 4]; 4], [[f64; 4]; 4]) {
    let [ixx, ixy, ixz, iyy, iyz, izz] = l.inertia.map(|i| beta[i]);
    let [hx, hy, hz] = l.first_moment.map(|i| beta[i]);
    let j: [[f64; 4]; 4] = Inertia::from_standard(&[ixx, ixy, ixz, iyy, iyz, izz, hx, hy, hz], m)
        .pseudo_inertia()
        .into();
    let mut js = j;
    for i in 0..3 {
        js[i][3] *= len;
        js[3][i] *= len;
    }
    js[3][3] *= len * len;
    (j, js)
}

/// Smallest eigenvalue of a link's pseudo-inertia `𝒥` (`docs/model.md`) for a
/// standard parameter vector and mass: ≥ 0 iff (67)–(69) hold.
pub fn pseudo_inertia_min_eigenvalue(
    beta: &[f64],
    layout: &LinkLayout,
    mass: f64,
) -> Result<f64, IdentError> {
    if let Some(&i) = layout
        .inertia
        .iter()
        .chain(&layout.first_moment)
        .find(|&&i| i >= beta.len())
    {
        return Err(IdentError::IndexOutOfRange {
            what: format!("link `{}`", layout.name),
            index: i,
            count: beta.len(),
        });
    }
    Ok(symmetric_eigenvalues(&pseudo_inertia(beta, layout, mass, 1.0).0)[0])
}

impl fmt::Display for SdpSolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "SDP {} in {} iterations, {:.1} ms (total {:.1} ms); residual {:.6e} (unconstrained {:.6e})",
            self.status,
            self.iterations,
            1e3 * self.solve_time,
            1e3 * self.total_time,
            self.residual_norm,
            self.ols_residual_norm
        )?;
        for l in &self.links {
            writeln!(
                f,
                "  {}: m = {:.6} kg, λ_min(𝒥) = {:.3e}, λ_min(T𝒥T) = {:.3e} kg·m² (margin {:.1e}){}",
                l.name,
                l.mass,
                l.min_eigenvalue,
                l.min_eigenvalue_scaled,
                l.margin,
                if l.psd_near_singular {
                    " [PSD active]"
                } else {
                    ""
                }
            )?;
        }
        if self.active.is_empty() {
            writeln!(f, "  no active constraints")?;
        } else {
            for a in &self.active {
                writeln!(
                    f,
                    "  active: {:?} `{}` (slack {:.2e})",
                    a.kind, a.name, a.slack
                )?;
            }
        }
        Ok(())
    }
}
