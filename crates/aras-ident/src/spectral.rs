//! Covariance of a least-squares estimate fitted on one averaged period:
//! the sandwich in the frequency domain, harmonic by harmonic.
//!
//! When every group's rows are one whole period of a periodic record (an
//! averaged block, band-limited by a harmonic series or a circular filter),
//! the discrete Fourier transform turns the fit into one over harmonics, and
//! a stationary residual of any spectrum is uncorrelated from one harmonic
//! to the next. The score `Wᵀe = (1/n) Σ_k W_kᴴ E_k` is then a sum of
//! independent terms, one per harmonic `k` (the groups' rows at the same
//! harmonic summed, so the correlation between joints is counted), and
//!
//! `Cov β̂ = (WᵀW)⁻¹ S (WᵀW)⁻¹,  S = (1/n²) Σ_{k=0}^{n/2} c_k Re(U_k U_kᴴ),
//! U_k = Σ_g W_{g,k}ᴴ E_{g,k} / √(1 − h_{g,k})`
//!
//! with `c_k = 2` for the harmonics that have a conjugate twin (1 for the
//! mean and the Nyquist bin) and `h_{g,k} = W_{g,k}ᴴ (WᵀW)⁻¹ W_{g,k} / n`
//! the leverage of a real dimension of that harmonic (MacKinnon and White's
//! HC2 correction: unbiased for a residual of flat spectrum, and it restores
//! what the fit removed at the regressor's own harmonics).
//!
//! **Why not the time-domain HAC here.** After a harmonic series the
//! residual of a model that misses nothing but what the angles cannot show
//! (a closed loop's reaction to quantised angles, the top of the series) is
//! strongly coloured, and its power sits at harmonics far from the ones the
//! regressor occupies. A white-noise model of that residual, or a Bartlett
//! window as wide as the pass band, spreads that power onto the regressor's
//! harmonics and overstates σ; the harmonic sandwich weighs each harmonic's
//! residual power by the regressor's power at the same harmonic, which is
//! what the estimate's error is made of.
//!
//! The FFT is `rustfft` (any record length, planned once per length).

use faer::{Mat, MatRef};
use rustfft::{FftPlanner, num_complex::Complex};

use crate::covariance::{sandwich, sandwich_bread};
use crate::error::IdentError;
use crate::groups::RowGroups;
use crate::ls::OlsEstimate;

/// An eigenvalue of a harmonic's `I − H` below this share of its largest
/// is a direction the fit pins exactly.
const PINNED: f64 = 1e-9;

/// A harmonic whose columns hold less than this share of the largest
/// column power adds nothing to the sandwich (projected data: exactly
/// nothing past the series' last harmonic).
const LIVE: f64 = 1e-24;

/// Default half-width (harmonics each side) of the window that smooths the
/// residual's cross-spectrum: 9 harmonics, 18 real dimensions per group, so
/// a parameter that lives at one harmonic (a constant offset at the mean)
/// still has its noise level estimated from its neighbours.
pub const DEFAULT_HALF_WIDTH: usize = 4;

/// A harmonic-sandwich covariance and what it rests on.
#[derive(Debug, Clone)]
pub struct SpectralCovariance {
    /// `b × b` covariance of the estimate.
    pub covariance: Mat<f64>,
    /// Samples per period (the DFT length).
    pub period_samples: usize,
    /// The largest leverage of a real dimension of one group's harmonic:
    /// near 1, that harmonic alone fixes a combination of the parameters.
    pub max_leverage: f64,
}

/// The harmonic sandwich ([module docs](self)) of the least-squares fit
/// `min ‖W x − T‖` with residual `residual = T − W x̂`, whose groups each
/// hold one whole period in time order: group `g`'s rows are samples
/// `0..n` of the period, `n = groups.sample_count()` (joint-major or
/// interleaved stacking of complete periods). `w` and `residual` are those
/// of the fit itself (weighted rows for WLS).
///
/// # Errors
/// A group that is not one whole period ([`IdentError::InvalidData`]: a
/// reversal mask dropped rows, which the time-domain
/// [`crate::hac_covariance`] handles), columns the rows do not excite and
/// non-finite data. A direction the fit pins exactly at one harmonic (a
/// column held by that harmonic alone) carries no noise to measure: it is
/// left out of that harmonic's residual, and its neighbours measure it.
pub fn spectral_covariance(
    w: MatRef<'_, f64>,
    residual: &[f64],
    groups: &RowGroups,
    half_width: usize,
) -> Result<SpectralCovariance, IdentError> {
    let winv = sandwich_bread(w, residual, groups, "harmonic covariance")?;
    let n = groups.sample_count();
    let rows = period_rows(groups, n)?;
    let spectra = Spectra::new(w, residual, &rows);
    let corrected = Corrected::new(&spectra, &winv)?;
    let meat = spectra.meat(&corrected, half_width);
    Ok(SpectralCovariance {
        covariance: sandwich(&winv, &meat, 1.0),
        period_samples: n,
        max_leverage: corrected.max_leverage,
    })
}

/// Each group's regressor columns and residual as spectra over one period.
struct Spectra {
    /// Samples per period.
    n: usize,
    /// `cols[g][j][k]`: column `j` of group `g` at harmonic `k`.
    cols: Vec<Vec<Vec<Complex<f64>>>>,
    /// `res[g][k]`: the residual of group `g` at harmonic `k`.
    res: Vec<Vec<Complex<f64>>>,
    /// Whether any group's columns hold power at harmonic `k` (projected
    /// data hold none past the series' last harmonic).
    live: Vec<bool>,
}

impl Spectra {
    /// One FFT per column and group (planned once).
    fn new(w: MatRef<'_, f64>, residual: &[f64], rows: &[Vec<usize>]) -> Self {
        let n = rows[0].len();
        let fft = FftPlanner::<f64>::new().plan_fft_forward(n);
        let spectrum = |x: &mut dyn FnMut(usize) -> f64| {
            let mut v: Vec<Complex<f64>> = (0..n).map(|i| Complex::new(x(i), 0.0)).collect();
            fft.process(&mut v);
            v
        };
        let cols: Vec<Vec<Vec<Complex<f64>>>> = rows
            .iter()
            .map(|r| {
                (0..w.ncols())
                    .map(|j| spectrum(&mut |i| w[(r[i], j)]))
                    .collect()
            })
            .collect();
        let res = rows
            .iter()
            .map(|r| spectrum(&mut |i| residual[r[i]]))
            .collect();
        // The largest column power at each harmonic, once.
        let power: Vec<f64> = (0..=n / 2)
            .map(|k| {
                cols.iter()
                    .flat_map(|c| c.iter().map(move |v| v[k].norm_sqr()))
                    .fold(0.0f64, f64::max)
            })
            .collect();
        let top = power.iter().copied().fold(0.0f64, f64::max);
        let live = power.iter().map(|&p| p > LIVE * top).collect();
        Self { n, cols, res, live }
    }

    fn groups(&self) -> usize {
        self.cols.len()
    }

    fn columns(&self) -> usize {
        self.cols[0].len()
    }

    /// Real dimensions of harmonic `k`: one for the mean and the Nyquist
    /// bin, two (cosine, sine) for the others.
    fn dims(&self, k: usize) -> usize {
        if k == 0 || 2 * k == self.n { 1 } else { 2 }
    }

    /// Harmonic `k` as real rows (`dims(k)` per group, group-fastest),
    /// scaled so that sums over them are the time domain's (Parseval):
    /// `x = √(dims/n) (Re W, −Im W)`, and the residual likewise.
    fn real_rows(&self, k: usize) -> (Mat<f64>, Vec<f64>) {
        let (d, ng) = (self.dims(k), self.groups());
        let f = (d as f64 / self.n as f64).sqrt();
        let part = |v: Complex<f64>, r: usize| f * if r < ng { v.re } else { -v.im };
        let x = Mat::from_fn(d * ng, self.columns(), |r, j| {
            part(self.cols[r % ng][j][k], r)
        });
        let e = (0..d * ng).map(|r| part(self.res[r % ng][k], r)).collect();
        (x, e)
    }

    /// The sandwich's meat: the residual's co-spectrum (G × G) smoothed
    /// over `2·half_width + 1` harmonics, weighted by the dimensions each
    /// keeps, and each live harmonic's scores varying by it:
    /// `S = Σ_k Σ_rows xᵀ C_k x`.
    fn meat(&self, corrected: &Corrected, half_width: usize) -> Mat<f64> {
        let (ng, b, half) = (self.groups(), self.columns(), self.n / 2);
        let mut s = Mat::<f64>::zeros(b, b);
        let mut co = vec![0.0; ng * ng];
        for k in (0..=half).filter(|&k| self.live[k]) {
            co.iter_mut().for_each(|v| *v = 0.0);
            let mut count = vec![0.0; ng];
            for j in k.saturating_sub(half_width)..=(k + half_width).min(half) {
                let (e, w) = (&corrected.residual[j], &corrected.kept[j]);
                for d in 0..self.dims(j) {
                    for g in 0..ng {
                        for h in 0..ng {
                            co[g * ng + h] += e[d * ng + g] * e[d * ng + h];
                        }
                        count[g] += w[d * ng + g];
                    }
                }
            }
            for g in 0..ng {
                for h in 0..ng {
                    co[g * ng + h] /= (count[g] * count[h]).sqrt();
                }
            }
            let (x, _) = self.real_rows(k);
            for d in 0..self.dims(k) {
                for g in 0..ng {
                    for h in 0..ng {
                        let c = co[g * ng + h];
                        if c == 0.0 {
                            continue;
                        }
                        for j in 0..b {
                            let xj = c * x[(d * ng + h, j)];
                            for i in j..b {
                                s[(i, j)] += x[(d * ng + g, i)] * xj;
                            }
                        }
                    }
                }
            }
        }
        for j in 0..b {
            for i in j..b {
                s[(j, i)] = s[(i, j)];
            }
        }
        s
    }
}

/// Each harmonic's residual with the fit's leverage taken out,
/// `ẽ = (I − H)^(−1/2) e` with `H = X (WᵀW)⁻¹ Xᵀ` its block of the hat
/// matrix (CR2: unbiased for white noise, and it undoes the constraints the
/// normal equations put on the groups' residuals at the regressor's
/// harmonics).
struct Corrected {
    /// `residual[k]`: harmonic `k`'s corrected residual, as its real rows.
    residual: Vec<Vec<f64>>,
    /// `kept[k]`: the share of each real row that carries noise to measure
    /// (1, less where the fit pins a direction exactly).
    kept: Vec<Vec<f64>>,
    /// The largest leverage of a direction kept.
    max_leverage: f64,
}

impl Corrected {
    fn new(spectra: &Spectra, winv: &Mat<f64>) -> Result<Self, IdentError> {
        let half = spectra.n / 2;
        let mut out = Self {
            residual: Vec::with_capacity(half + 1),
            kept: Vec::with_capacity(half + 1),
            max_leverage: 0.0,
        };
        for k in 0..=half {
            let (x, e) = spectra.real_rows(k);
            if !spectra.live[k] {
                out.kept.push(vec![1.0; e.len()]);
                out.residual.push(e);
                continue;
            }
            let (residual, kept, leverage) = Self::harmonic(&x, &e, winv)?;
            out.max_leverage = out.max_leverage.max(leverage);
            out.residual.push(residual);
            out.kept.push(kept);
        }
        Ok(out)
    }

    /// One harmonic: its corrected residual, the kept share of each row and
    /// the largest leverage kept.
    fn harmonic(
        x: &Mat<f64>,
        e: &[f64],
        winv: &Mat<f64>,
    ) -> Result<(Vec<f64>, Vec<f64>, f64), IdentError> {
        let (m, b) = (x.nrows(), x.ncols());
        let xa = crate::linalg::product(x.as_ref(), winv.as_ref());
        let ih = Mat::from_fn(m, m, |i, j| {
            let hat = (0..b).map(|c| xa[(i, c)] * x[(j, c)]).sum::<f64>();
            if i == j { 1.0 - hat } else { -hat }
        });
        let (u, l) = crate::linalg::symmetric_eigen(ih.as_ref())
            .map_err(|e| IdentError::external("harmonic covariance", e))?;
        // A direction the fit pins exactly (l = 0: the groups' residuals at
        // a harmonic that one column holds alone sum to zero) carries no
        // noise to measure; it is dropped and its share counted in `kept`.
        let lmax = (0..m).map(|i| l[i]).fold(0.0f64, f64::max);
        let keep: Vec<bool> = (0..m).map(|i| l[i] > PINNED * lmax).collect();
        let lmin = (0..m)
            .filter(|&i| keep[i])
            .map(|i| l[i])
            .fold(f64::INFINITY, f64::min);
        let ue: Vec<f64> = (0..m)
            .map(|i| {
                if keep[i] {
                    (0..m).map(|r| u[(r, i)] * e[r]).sum::<f64>() / l[i].sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        let residual = (0..m)
            .map(|r| (0..m).map(|i| u[(r, i)] * ue[i]).sum())
            .collect();
        let kept = (0..m)
            .map(|r| {
                (0..m)
                    .filter(|&i| keep[i])
                    .map(|i| u[(r, i)] * u[(r, i)])
                    .sum()
            })
            .collect();
        Ok((residual, kept, 1.0 - lmin))
    }
}

/// Each group's rows in sample order, checked to be one whole period.
fn period_rows(groups: &RowGroups, n: usize) -> Result<Vec<Vec<usize>>, IdentError> {
    let mut rows: Vec<Vec<usize>> = vec![Vec::with_capacity(n); groups.n_groups()];
    for (r, (&g, &smp)) in groups.labels().iter().zip(groups.samples()).enumerate() {
        if smp != rows[g].len() {
            return Err(not_whole(g, n));
        }
        rows[g].push(r);
    }
    if let Some(g) = rows.iter().position(|r| r.len() != n) {
        return Err(not_whole(g, n));
    }
    Ok(rows)
}

fn not_whole(group: usize, n: usize) -> IdentError {
    IdentError::InvalidData {
        context: "harmonic covariance".into(),
        reason: format!(
            "group {group} does not hold every sample of the {n}-sample period once, in order; \
             the harmonic sandwich needs whole periods (use the HAC covariance for masked rows)"
        ),
    }
}

impl OlsEstimate {
    /// The estimate with the harmonic-sandwich covariance
    /// ([`spectral_covariance`]) of the fit `w x ≈ t` on whole periods:
    /// σ (64), σ% (65) and the covariance hold for a residual of any
    /// spectrum. `w` and `t` are the rows the estimate was fitted on
    /// (weighted rows for WLS); `residual_variance` stays (66).
    pub fn with_spectral_sandwich(
        self,
        w: MatRef<'_, f64>,
        t: &[f64],
        groups: &RowGroups,
    ) -> Result<(Self, SpectralCovariance), IdentError> {
        let e = self.residual_of(w, t)?;
        let cov = spectral_covariance(w, &e, groups, DEFAULT_HALF_WIDTH)?;
        Ok((self.with_covariance(cov.covariance.clone()), cov))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::covariance::gram_inverse;
    use crate::ls::ols;
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, Normal};

    /// A periodic regressor over `n` samples of two groups (joint-major):
    /// an offset per group (held at the mean alone) and two smooth columns
    /// shared by the groups.
    fn regressor(n: usize) -> Mat<f64> {
        Mat::from_fn(2 * n, 4, |r, j| {
            let (g, i) = (r / n, r % n);
            let x = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            match j {
                0 | 1 => f64::from(u8::from(g == j)),
                2 => (x + g as f64).sin(),
                _ => (2.0 * x).cos() * (1.0 + g as f64),
            }
        })
    }

    const NAMES: [&str; 4] = ["a", "b", "c", "d"];

    #[test]
    fn white_noise_gives_the_classical_covariance() {
        // For white noise the sandwich is (WᵀW)⁻¹ σ² (HC2 is unbiased
        // there): compare the average over many residuals with it.
        let n = 256;
        let w = regressor(n);
        let groups = RowGroups::contiguous(&[n, n]).unwrap();
        let mut rng = StdRng::seed_from_u64(7);
        let noise = Normal::new(0.0, 0.1).unwrap();
        let trials = 1000;
        let mut mean = [0.0; 4];
        for _ in 0..trials {
            let t: Vec<f64> = (0..2 * n).map(|_| noise.sample(&mut rng)).collect();
            let e = ols(w.as_ref(), &t, &NAMES).unwrap();
            let (e, _) = e.with_spectral_sandwich(w.as_ref(), &t, &groups).unwrap();
            for (m, s) in mean.iter_mut().zip(&e.std_dev) {
                *m += s * s / trials as f64;
            }
        }
        let names: Vec<String> = NAMES.iter().map(|s| s.to_string()).collect();
        let winv = gram_inverse(w.as_ref(), &names).unwrap();
        for (i, m) in mean.iter().enumerate() {
            let want = 0.01 * winv[(i, i)];
            // The offsets' σ² comes from a 9-harmonic window (≈ 8.5 real
            // dimensions): relative spread √(2/8.5) = 0.49 per trial, 0.015
            // over 1000 trials. A column the groups share at its only
            // harmonic pins a direction that mixes them; the smoothed
            // co-spectrum then runs 4–6 % low (measured 0.96 and 0.945 for
            // the two shared columns, 0.99 and 1.01 for the offsets): 7 %
            // holds that bias plus 1.5 standard errors, and no worse one.
            assert!((m / want - 1.0).abs() < 0.07, "{i}: {m} vs {want}");
        }
    }

    #[test]
    fn coloured_residual_far_from_the_regressor_costs_nothing() {
        // A residual made only of high harmonics, which no column holds,
        // gives a covariance of zero: the estimate's error is made of the
        // residual at the regressor's harmonics only.
        let n = 128;
        let w = regressor(n);
        let groups = RowGroups::contiguous(&[n, n]).unwrap();
        let e: Vec<f64> = (0..2 * n)
            .map(|r| (2.0 * std::f64::consts::PI * 40.0 * (r % n) as f64 / n as f64).sin())
            .collect();
        let c = spectral_covariance(w.as_ref(), &e, &groups, DEFAULT_HALF_WIDTH).unwrap();
        let worst = (0..4).map(|i| c.covariance[(i, i)]).fold(0.0, f64::max);
        assert!(worst < 1e-28, "{worst}");
    }

    #[test]
    fn matches_the_monte_carlo_spread_of_a_coloured_residual() {
        // Residual = white noise through a periodic 3-tap smoother: σ from
        // one record against the spread of the estimates over many.
        let n = 512;
        let w = regressor(n);
        let groups = RowGroups::contiguous(&[n, n]).unwrap();
        let mut rng = StdRng::seed_from_u64(11);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let trials = 400;
        let mut est = Vec::new();
        let mut var = [0.0; 4];
        for _ in 0..trials {
            let raw: Vec<f64> = (0..2 * n).map(|_| noise.sample(&mut rng)).collect();
            let t: Vec<f64> = (0..2 * n)
                .map(|r| {
                    let (g, i) = (r / n, r % n);
                    let at = |d: usize| raw[g * n + (i + d) % n];
                    at(0) + at(1) + at(2) + at(3)
                })
                .collect();
            let e = ols(w.as_ref(), &t, &NAMES).unwrap();
            let (e, _) = e.with_spectral_sandwich(w.as_ref(), &t, &groups).unwrap();
            for (v, s) in var.iter_mut().zip(&e.std_dev) {
                *v += s * s / trials as f64;
            }
            est.push(e.estimate.clone());
        }
        for i in 0..4 {
            let spread = est.iter().map(|e| e[i] * e[i]).sum::<f64>() / trials as f64;
            // 400 trials: the spread's variance is known to ≈ 7 %.
            assert!(
                (var[i] / spread - 1.0).abs() < 0.2,
                "{i}: σ² {} vs spread {spread}",
                var[i]
            );
        }
    }

    #[test]
    fn masked_rows_are_refused_by_name() {
        let n = 64;
        let w = regressor(n);
        let groups = RowGroups::contiguous(&[n, n - 1])
            .and_then(|g| {
                let samples: Vec<usize> = (0..n).chain(1..n).collect();
                g.with_samples(samples, n)
            })
            .unwrap();
        let w = w.subrows(0, 2 * n - 1);
        let e = vec![0.0; 2 * n - 1];
        let err = spectral_covariance(w, &e, &groups, DEFAULT_HALF_WIDTH)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("group 1") && err.contains("whole periods"),
            "{err}"
        );
    }
}
