//! Identification (spec §4, §6): a processed log → stacked regressor →
//! base parameters → OLS (62)–(66) → physically consistent SDP (67)–(73).
//!
//! The mathematics lives in `aras-signal` (processing), `aras-dyn`
//! (regressor) and `aras-ident` (base parameters, least squares, SDP); this
//! module wires them and applies the filtering mode of the spec §6 NOTE:
//! with **parallel filtering** the same zero-phase low-pass that
//! `aras-signal` applied to the torques is applied to every column of the
//! regressor, so a Coulomb jump is smeared identically on both sides of
//! `T = W β`.

use anyhow::{Context, Result, bail};
use aras_dyn::{Model, Params};
use aras_ident::{
    BaseParameters, ConsistentLs, LinkLayout, NoiseVariances, OlsEstimate, ReducedLs, RowGroups,
    SdpSettings, SdpSolution,
};
use aras_kin::Geometry;
use aras_signal::{
    Butterworth, DerivativeMethod, FilterSpec, Log, PeriodSource, ProcessOptions, Processed,
    Samples,
};
use faer::MatRef;
use nalgebra::{DMatrix, Vector2};

use crate::config::{Config, DerivativeChoice, FilteringMode, Weighting};

/// Processing options from the configuration (`period` overrides the sidecar).
pub fn process_options(
    cfg: &Config,
    period: Option<f64>,
    logged_derivatives: bool,
) -> ProcessOptions {
    let s = &cfg.signal;
    ProcessOptions {
        filter: (s.cutoff_hz > 0.0).then_some(FilterSpec {
            order: s.filter_order,
            cutoff_hz: s.cutoff_hz,
        }),
        period: period.map_or(PeriodSource::FromSidecar, PeriodSource::Seconds),
        settling_s: s.settling_s,
        max_period_spread: s.max_period_spread,
        derivative: match s.derivative {
            DerivativeChoice::Auto => DerivativeMethod::Auto,
            DerivativeChoice::CentralDifference => DerivativeMethod::CentralDifference,
            DerivativeChoice::Spectral => DerivativeMethod::Spectral,
            DerivativeChoice::SavitzkyGolay => DerivativeMethod::SavitzkyGolay {
                half_window: s.sg_half_window,
                poly_order: s.sg_poly_order,
            },
        },
        use_logged_derivatives: logged_derivatives,
    }
}

/// Data ready for least squares: the processed samples, the stacked
/// regressor (`2N × n`, joint 1's rows first) and torques, both filtered
/// as the filtering mode says.
pub struct Prepared {
    /// What `aras-signal` produced.
    pub processed: Processed,
    /// Stacked regressor of the model.
    pub w: DMatrix<f64>,
    /// Stacked torques `[τ1; τ2]`.
    pub t: Vec<f64>,
}

impl Prepared {
    /// Samples per joint.
    pub fn n(&self) -> usize {
        self.processed.samples.len()
    }

    /// Row groups (joint 1's rows, then joint 2's).
    pub fn groups(&self) -> Result<RowGroups> {
        Ok(RowGroups::contiguous(&[self.n(), self.n()])?)
    }

    /// A faer view of the regressor.
    pub fn w_ref(&self) -> MatRef<'_, f64> {
        mat_ref(&self.w)
    }
}

/// A faer view of a nalgebra matrix (both column-major).
pub fn mat_ref(m: &DMatrix<f64>) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(m.as_slice(), m.nrows(), m.ncols())
}

/// Processes a log and stacks the model's regressor on it.
pub fn prepare(
    log: &Log,
    opts: &ProcessOptions,
    mode: FilteringMode,
    model: &Model,
    geometry: &Geometry,
) -> Result<Prepared> {
    let processed = aras_signal::process(log, opts, geometry)
        .with_context(|| format!("processing {}", log.name))?;
    let s = &processed.samples;
    let n = s.len();
    if n < 2 * model.columns() {
        bail!(
            "{}: only {n} samples after processing, fewer than twice the {} parameters; \
             record a longer log",
            log.name,
            model.columns()
        );
    }
    let mut w =
        stacked(model, geometry, s).with_context(|| format!("regressor of {}", log.name))?;
    if mode == FilteringMode::Parallel
        && let Some(spec) = opts.filter
    {
        let periodic = processed.summary.periods.is_some();
        filter_columns(&mut w, n, spec, processed.summary.sample_rate_hz, periodic)?;
    }
    let mut t = s.tau[0].clone();
    t.extend_from_slice(&s.tau[1]);
    Ok(Prepared { processed, w, t })
}

/// The stacked regressor at the processed samples.
pub fn stacked(model: &Model, geometry: &Geometry, s: &Samples) -> Result<DMatrix<f64>> {
    let v = |a: &[Vec<f64>; 2]| -> Vec<Vector2<f64>> {
        a[0].iter()
            .zip(&a[1])
            .map(|(p, g)| Vector2::new(*p, *g))
            .collect()
    };
    Ok(model.stacked_from_states(geometry, &v(&s.x), &v(&s.x_dot), &v(&s.x_ddot))?)
}

/// Applies the processing's zero-phase low-pass to every joint block of
/// every column: the periodic form for an averaged record, otherwise
/// forward–backward with the same padding rule as `aras-signal`
/// (ten time constants of the slowest pole).
fn filter_columns(
    w: &mut DMatrix<f64>,
    n: usize,
    spec: FilterSpec,
    fs: f64,
    periodic: bool,
) -> Result<()> {
    let sos = Butterworth::lowpass(spec.order, spec.cutoff_hz, fs)?;
    let slowest = (std::f64::consts::PI / (2.0 * spec.order as f64)).sin();
    let tau = fs / (std::f64::consts::TAU * spec.cutoff_hz * slowest);
    let pad = ((10.0 * tau).ceil() as usize)
        .max(sos.padlen())
        .min(n.saturating_sub(1));
    let mut scratch = Vec::new();
    for block in w.as_mut_slice().chunks_mut(n) {
        if block.iter().all(|v| *v == 0.0) {
            continue;
        }
        if periodic {
            sos.filtfilt_periodic_in_place(block)?;
        } else {
            sos.filtfilt_in_place_padded(block, pad, &mut scratch)?;
        }
    }
    Ok(())
}

/// Points of a low-discrepancy (Halton) sequence, deterministic.
fn halton(i: usize, base: usize) -> f64 {
    let (mut f, mut r, mut k) = (1.0, 0.0, i);
    while k > 0 {
        f /= base as f64;
        r += f * (k % base) as f64;
        k /= base;
    }
    r
}

/// Base parameters (58)–(61) of `model` from `count` quasi-random samples
/// of `(X, Ẋ, Ẍ)` filling the workspace box and the rate and acceleration
/// limits (rich data, so only structural dependencies remain).
pub fn base_parameters(model: &Model, geometry: &Geometry, cfg: &Config) -> Result<BaseParameters> {
    let t = &cfg.trajectory;
    let d = f64::to_radians;
    let count = cfg.identification.base_samples;
    let primes = [2, 3, 5, 7, 11, 13];
    let mut x = Vec::with_capacity(count);
    let mut xd = Vec::with_capacity(count);
    let mut xdd = Vec::with_capacity(count);
    for i in 1..=count {
        let u: Vec<f64> = primes.iter().map(|&p| halton(i, p)).collect();
        x.push(Vector2::new(
            d(t.min_deg[0] + u[0] * (t.max_deg[0] - t.min_deg[0])),
            d(t.min_deg[1] + u[1] * (t.max_deg[1] - t.min_deg[1])),
        ));
        xd.push(Vector2::new(
            d(t.max_rate_deg_s[0] * (2.0 * u[2] - 1.0)),
            d(t.max_rate_deg_s[1] * (2.0 * u[3] - 1.0)),
        ));
        xdd.push(Vector2::new(
            d(t.max_accel_deg_s2[0] * (2.0 * u[4] - 1.0)),
            d(t.max_accel_deg_s2[1] * (2.0 * u[5] - 1.0)),
        ));
    }
    let w = model
        .stacked_from_states(geometry, &x, &xd, &xdd)
        .context("regressor on random workspace samples (is the box in trajectory.min_deg/max_deg reachable?)")?;
    Ok(BaseParameters::from_regressor(
        mat_ref(&w),
        &model.names(),
        cfg.identification.rank_tolerance,
    )?)
}

/// The base projection `E` (`n × b`, `W_b = W E`) for the design.
pub fn projection(base: &BaseParameters) -> DMatrix<f64> {
    let mut e = DMatrix::zeros(base.n_standard(), base.n_base());
    for (j, &i) in base.independent().iter().enumerate() {
        e[(i, j)] = 1.0;
    }
    e
}

/// Everything identification produced.
pub struct Identification {
    /// Rows used in the fit per joint (the rest were near rest).
    pub rows_fitted: [usize; 2],
    /// The identified model's parameter names (standard).
    pub names: Vec<String>,
    /// Base parameters.
    pub base: BaseParameters,
    /// OLS (or WLS) estimate of the base parameters.
    pub ols: OlsEstimate,
    /// The SDP solution.
    pub sdp: SdpSolution,
    /// OLS completed to standard parameters closest to the nominal robot.
    pub ols_params: Params,
    /// The physically consistent standard parameters.
    pub sdp_params: Params,
    /// Excitation data: predictions `W_b β_b` (OLS, SDP), stacked.
    pub predicted_ols: Vec<f64>,
    /// SDP predictions.
    pub predicted_sdp: Vec<f64>,
    /// Fitness (78) per joint, OLS.
    pub fitness_ols: [f64; 2],
    /// Fitness (78) per joint, SDP.
    pub fitness_sdp: [f64; 2],
}

/// Fitness (78) per joint of stacked torques (joint 1 first).
pub fn fitness_per_joint(measured: &[f64], predicted: &[f64]) -> Result<[f64; 2]> {
    let n = measured.len() / 2;
    Ok([
        aras_ident::validate::fitness(&measured[..n], &predicted[..n])?,
        aras_ident::validate::fitness(&measured[n..], &predicted[n..])?,
    ])
}

/// Parameters `p` with the standard vector `beta` of `model` and `masses`.
pub fn with_standard(
    p: &Params,
    model: &Model,
    beta: &[f64],
    masses: Option<&[f64]>,
) -> Result<Params> {
    let mut q = p.clone();
    q.extra = Default::default();
    q.set_standard_vector(model, beta)?;
    if let Some(m) = masses {
        for (l, &m) in q.links.iter_mut().zip(m) {
            l.mass = m;
        }
    }
    Ok(q)
}

/// OLS and SDP on prepared data, with `nominal` as the SDP's reference.
pub fn identify(
    prepared: &Prepared,
    base: &BaseParameters,
    model: &Model,
    nominal: &Params,
    cfg: &Config,
) -> Result<Identification> {
    let names = model.names();
    let bnames = base.base_names();
    let w_b = base.base_regressor(prepared.w_ref())?;
    // Rows of joints moving at least `min_speed` (see the config docs).
    let s = &prepared.processed.samples;
    let n = prepared.n();
    let v = cfg.identification.min_speed;
    let rows: Vec<usize> = (0..2 * n)
        .filter(|&r| s.theta_dot[r / n][r % n].abs() >= v)
        .collect();
    let n1 = rows.iter().filter(|&&r| r < n).count();
    let n2 = rows.len() - n1;
    if n1 < w_b.ncols() || n2 < w_b.ncols() {
        bail!(
            "only {n1} (joint 1) and {n2} (joint 2) samples move faster than              identification.min_speed = {v} rad/s; lower it or excite the joints more"
        );
    }
    let w_fit = faer::Mat::from_fn(rows.len(), w_b.ncols(), |i, j| w_b[(rows[i], j)]);
    let t_fit: Vec<f64> = rows.iter().map(|&r| prepared.t[r]).collect();
    let (ols, reduced) = match cfg.identification.weighting {
        Weighting::Ols => {
            let r = ReducedLs::new(w_fit.as_ref(), &t_fit, &bnames)?;
            (r.ols()?, r)
        }
        Weighting::Wls => {
            let e = aras_ident::wls(
                w_fit.as_ref(),
                &t_fit,
                &bnames,
                &RowGroups::contiguous(&[n1, n2])?,
                NoiseVariances::FromResiduals,
            )?;
            (e.estimate, e.reduced)
        }
    };
    let reference: Vec<f64> = nominal
        .standard_vector(model)
        .context("the nominal robot's standard parameters")?
        .iter()
        .copied()
        .collect();
    let sc = &cfg.identification.sdp;
    let mut problem = ConsistentLs::new(&names, reference.clone())?;
    for k in 0..4 {
        let n = |s: &str| format!("L{}.{s}", k + 1);
        let idx = |s: &str| problem.index_of(&n(s));
        let inertia = [
            idx("Ixx")?,
            idx("Ixy")?,
            idx("Ixz")?,
            idx("Iyy")?,
            idx("Iyz")?,
            idx("Izz")?,
        ];
        let first = [idx("hx")?, idx("hy")?, idx("hz")?];
        let m = nominal.links[k].mass;
        if !(m.is_finite() && m > 0.0) {
            bail!(
                "link {} of the nominal robot has mass {m}: the physically consistent fit needs \
                 each link's approximate mass (`links.{}.mass` in the parameter file)",
                k + 1,
                k + 1
            );
        }
        let layout = LinkLayout::new(format!("link {}", k + 1), inertia, first, m)
            .with_mass_bounds(m * (1.0 - sc.mass_tolerance), m * (1.0 + sc.mass_tolerance));
        problem.link(layout)?;
        if let Some([lo, hi]) = sc.box_bounds {
            let all: Vec<usize> = inertia.iter().chain(&first).copied().collect();
            problem.box_around_reference(&all, lo, hi)?;
        }
    }
    if sc.nonnegative_friction {
        problem.nonnegative(&["Fv1", "Fc1", "Fv2", "Fc2", "Ke1", "Ke2"])?;
    }
    problem.settings(SdpSettings {
        regularisation: sc.regularisation,
        psd_margin: sc.epsilon,
        tolerance: sc.tolerance,
        max_iter: sc.max_iter,
        ..SdpSettings::default()
    });
    let sdp = problem
        .solve(base, &reduced)
        .context("physically consistent fit (SDP)")?;
    let ols_std = base.to_standard_near(&ols.estimate, &reference)?;
    let ols_params = with_standard(nominal, model, &ols_std, None)?;
    let sdp_params = with_standard(nominal, model, &sdp.standard, Some(&sdp.masses))?;
    let predicted_ols = aras_ident::validate::predict(w_b.as_ref(), &ols.estimate)?;
    let predicted_sdp = aras_ident::validate::predict(w_b.as_ref(), &sdp.base)?;
    let fitness_ols = fitness_per_joint(&prepared.t, &predicted_ols)?;
    let fitness_sdp = fitness_per_joint(&prepared.t, &predicted_sdp)?;
    Ok(Identification {
        rows_fitted: [n1, n2],
        names,
        base: base.clone(),
        ols,
        sdp,
        ols_params,
        sdp_params,
        predicted_ols,
        predicted_sdp,
        fitness_ols,
        fitness_sdp,
    })
}
