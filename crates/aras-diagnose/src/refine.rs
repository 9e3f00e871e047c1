//! The one refinement of a continuous non-linear setting in the workspace:
//! the minimum of a scalar profile `u ↦ RSS(u)` (the residual of the
//! linear fit with the setting fixed at `u`) by zoomed grid passes and a
//! parabola vertex, its σ from the profile's curvature. The diagnosis
//! refines a candidate's setting with it (Stribeck `v_s`, cogging cycles,
//! a time delay), the identification the friction effect's Coulomb
//! transition widths.
//!
//! The profile is evaluated a pass at a time (`profile(&[u…]) → [RSS…]`),
//! so a caller that scores every trial value of a pass with one sweep over
//! its data (the diagnosis's bounded-memory accumulation) keeps doing so.

/// Trial values per zoom pass (and per search interval in the first pass).
pub const ZOOM_POINTS: usize = 16;

/// Zoom passes: each narrows the interval to two spacings of the previous
/// one, `2 / (ZOOM_POINTS − 1)`; two leave a spacing of `2 / 15² ≈ 8.9e-3`
/// of the first interval (2 % in a log-scaled `v_s`, 0.4 % in cogging
/// cycles), and a parabola through the best three points of a smooth
/// profile lands within 0.03 % of where a third pass ends (measured on the
/// diagnosis's refinement tests).
pub const ZOOM_PASSES: usize = 2;

/// Where a profile's minimum was found, and the last pass around it.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileMinimum {
    /// The search variable at the minimum: the vertex of the parabola
    /// through the best trial value and its neighbours (kept within one
    /// spacing of the best), else the best trial value.
    pub u: f64,
    /// The first pass's interval that holds the minimum.
    pub interval: (f64, f64),
    /// The last pass's trial values, increasing.
    pub points: Vec<f64>,
    /// The profile at `points`.
    pub rss: Vec<f64>,
    /// Index of the smallest of `rss` (the first of equals).
    pub best: usize,
    /// The last pass's spacing.
    pub step: f64,
    /// True when `u` lies within 1 % of the interval's width of one of its
    /// ends: the true minimum may lie beyond it, and σ is unknown.
    pub at_bound: bool,
}

impl ProfileMinimum {
    /// σ of `u` from the curvature of the profile `n_eff ln RSS(u)` (a rise
    /// of ½ per σ², the likelihood of Gaussian residuals with `n_eff`
    /// independent rows): its second difference over the last pass's three
    /// trial values around the minimum. `None` at a bound, on a profile
    /// that is flat or concave there, or with an RSS ≤ 0.
    pub fn std_dev(&self, n_eff: f64) -> Option<f64> {
        if self.at_bound || self.points.len() < 3 {
            return None;
        }
        let i0 = self.best.clamp(1, self.points.len() - 2);
        let (fm, f0, fp) = (self.rss[i0 - 1], self.rss[i0], self.rss[i0 + 1]);
        let positive = [fm, f0, fp].iter().all(|x| *x > 0.0);
        if !positive {
            return None;
        }
        let j2 = n_eff * (fp.ln() - 2.0 * f0.ln() + fm.ln()) / (self.step * self.step);
        (j2 > 0.0 && j2.is_finite()).then(|| (2.0 / j2).sqrt())
    }
}

/// `ZOOM_POINTS` values from `lo` to `hi`, evenly spaced.
fn spaced(lo: f64, hi: f64) -> Vec<f64> {
    (0..ZOOM_POINTS)
        .map(|i| lo + (hi - lo) * i as f64 / (ZOOM_POINTS - 1) as f64)
        .collect()
}

/// Index of the smallest value (the first of equals; a NaN is never the
/// smallest).
pub(crate) fn argmin(v: &[f64]) -> usize {
    v.iter()
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |(bi, bv), (i, x)| {
                if *x < bv { (i, *x) } else { (bi, bv) }
            },
        )
        .0
}

/// The minimum of `profile` over the search `intervals` (each `lo < hi`,
/// e.g. one per search centre): a first pass of [`ZOOM_POINTS`] trial
/// values over every interval, then [`ZOOM_PASSES`]` − 1` passes of as many
/// over two spacings around the best value (inside its interval), then the
/// parabola vertex. `profile` is called once per pass with that pass's
/// trial values and returns their RSS, one each; its errors are passed on.
pub fn minimise_profile<E>(
    intervals: &[(f64, f64)],
    mut profile: impl FnMut(&[f64]) -> Result<Vec<f64>, E>,
) -> Result<ProfileMinimum, E> {
    let us: Vec<f64> = intervals
        .iter()
        .flat_map(|&(lo, hi)| spaced(lo, hi))
        .collect();
    let mut rss = profile(&us)?;
    let mut best = argmin(&rss);
    let (lo, hi) = intervals[best / ZOOM_POINTS];
    let mut points = us;
    let mut step = (hi - lo) / (ZOOM_POINTS - 1) as f64;
    for _ in 1..ZOOM_PASSES {
        let u = points[best];
        let (a, b) = ((u - step).max(lo), (u + step).min(hi));
        points = spaced(a, b);
        rss = profile(&points)?;
        best = argmin(&rss);
        step = (b - a) / (ZOOM_POINTS - 1) as f64;
    }
    let mut u = points[best];
    if best > 0 && best + 1 < points.len() {
        let (fm, f0, fp) = (rss[best - 1], rss[best], rss[best + 1]);
        let curv = fp - 2.0 * f0 + fm;
        if curv > 0.0 {
            u = (u - 0.5 * step * (fp - fm) / curv).clamp(u - step, u + step);
        }
    }
    let edge = 0.01 * (hi - lo);
    let at_bound = u - lo < edge || hi - u < edge;
    Ok(ProfileMinimum {
        u,
        interval: (lo, hi),
        points,
        rss,
        best,
        step,
        at_bound,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Gaussian log-likelihood profile `RSS(u) = exp((u − m)² / (n σ²))`
    /// (`n ln RSS` a parabola with curvature `2/σ²`): the minimum and σ
    /// are recovered, a minimum beyond the interval is reported at its
    /// bound without σ, and a pass's errors are passed on.
    #[test]
    fn recovers_a_known_profile() {
        let (m, sigma, n) = (0.3137, 0.021, 500.0);
        let f = |us: &[f64]| -> Result<Vec<f64>, ()> {
            Ok(us
                .iter()
                .map(|u| ((u - m) * (u - m) / (n * sigma * sigma)).exp())
                .collect())
        };
        // The vertex of the parabola through three RSS values (not ln RSS)
        // of the last pass (spacing 8.9e-3) lands within 2e-6 of the
        // minimum here; 1e-5 is 0.1 % of the spacing.
        let r = minimise_profile(&[(-1.0, 1.0)], f).unwrap();
        assert!((r.u - m).abs() < 1e-5, "{}", r.u);
        assert!(!r.at_bound);
        let s = r.std_dev(n).unwrap();
        assert!((s / sigma - 1.0).abs() < 1e-9, "{s}");
        let r = minimise_profile(&[(-1.0, 0.2)], f).unwrap();
        assert!(r.at_bound && r.std_dev(n).is_none());
        let mut calls = 0;
        let e = minimise_profile(&[(0.0, 1.0)], |_| {
            calls += 1;
            Err::<Vec<f64>, _>("pass failed")
        });
        assert_eq!((e, calls), (Err("pass failed"), 1));
        // Two intervals: the first pass spans both, the zoom stays in the
        // one that holds the minimum.
        let r = minimise_profile(&[(-3.0, -2.0), (0.0, 1.0)], f).unwrap();
        assert_eq!(r.interval, (0.0, 1.0));
        assert!((r.u - m).abs() < 1e-5, "{}", r.u);
    }
}
