//! Nested least-squares fits from the accumulated Gram blocks: estimate,
//! σ, residual sums of squares per group and validation fitness (78), for
//! any subset of the accumulated columns and any of the targets.

use faer::Mat;
use serde::Serialize;

use super::accumulate::Sums;
use crate::error::IdentError;
use crate::streaming::GramCheck;

/// How accurate a fit from the normal equations is ([`GramCheck`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Accuracy {
    /// `κ² ε` is within [`crate::streaming::GRAM_ERROR_LIMIT`]: the normal
    /// equations cost nothing that matters.
    Within,
    /// `κ² ε` is beyond the limit: the estimate may carry a relative error
    /// up to `κ² ε` from the normal equations (report it, or refit the
    /// selected model by QR on the rows).
    Beyond,
}

/// One fitted model: the estimate on the training sums and its validation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelFit {
    /// Row columns in the model, in order (numerically dependent columns
    /// left out, see `dependent`).
    pub columns: Vec<usize>,
    /// Requested columns left out because they lie (to the rank tolerance)
    /// in the span of the columns before them: aliases, not evidence.
    pub dependent: Vec<usize>,
    /// Row column used as target.
    pub target: usize,
    /// Estimate per entry of `columns`.
    pub estimate: Vec<f64>,
    /// Standard deviation per entry of `columns`: the OLS σ with the residual
    /// variance divided by the noise gain `g` (filtered, correlated noise);
    /// 0 if unknown (never NaN).
    pub std_dev: Vec<f64>,
    /// Training residual sum of squares per group.
    pub rss: Vec<f64>,
    /// Training rows per group.
    pub rows: Vec<usize>,
    /// Fitness (78) per validation set, per group (%).
    pub fitness: Vec<Vec<f64>>,
    /// Accuracy check of the normal equations of this fit.
    pub check: GramCheck,
    /// `check` as a status.
    pub accuracy: Accuracy,
}

impl ModelFit {
    /// Total training residual sum of squares.
    pub fn total_rss(&self) -> f64 {
        self.rss.iter().sum()
    }

    /// Fitness per group averaged over the validation sets (%).
    pub fn mean_fitness(&self) -> Vec<f64> {
        let k = self.fitness.len().max(1) as f64;
        let g = self.rss.len();
        (0..g)
            .map(|j| self.fitness.iter().map(|f| f[j]).sum::<f64>() / k)
            .collect()
    }
}

/// Symmetric entry of the summed Gram.
fn total_gram(s: &Sums) -> Mat<f64> {
    let w = s.grams[0].ncols();
    let mut g = Mat::zeros(w, w);
    for m in &s.grams {
        g += m;
    }
    g
}

/// Fits `target` on `columns` (row indices) from the training sums and
/// evaluates on each validation set. `rank_tolerance`: a column whose part
/// outside the span of the columns before it is below this fraction of its
/// norm is left out (`dependent`). `noise_gain` in (0, 1] corrects σ for
/// filtered noise.
pub(crate) fn fit(
    train: &Sums,
    validation: &[Sums],
    columns: &[usize],
    target: usize,
    rank_tolerance: f64,
    noise_gain: f64,
) -> Result<ModelFit, IdentError> {
    let g = total_gram(train);
    let dt = g[(target, target)].max(0.0).sqrt();
    if dt == 0.0 {
        return Err(IdentError::ConstantSignal {
            group: 0,
            len: train.rows.iter().sum(),
        });
    }
    // Cholesky of the column-equilibrated Gram, in the given order, leaving
    // out dependent columns: `r` holds the kept columns' factor (upper,
    // column by column), `z` the projected target.
    let mut kept: Vec<usize> = Vec::with_capacity(columns.len());
    let mut dep = Vec::new();
    let mut d: Vec<f64> = Vec::with_capacity(columns.len());
    let mut r: Vec<Vec<f64>> = Vec::with_capacity(columns.len()); // r[j][k], k ≤ j
    let tol2 = rank_tolerance * rank_tolerance;
    for &c in columns {
        let dc = g[(c, c)].max(0.0).sqrt();
        if dc == 0.0 || kept.contains(&c) {
            dep.push(c);
            continue;
        }
        let mut col = Vec::with_capacity(kept.len() + 1);
        let mut norm2 = 0.0;
        for (k, &ck) in kept.iter().enumerate() {
            let mut v = g[(ck, c)] / (d[k] * dc);
            for l in 0..k {
                v -= r[k][l] * col[l];
            }
            v /= r[k][k];
            norm2 += v * v;
            col.push(v);
        }
        let rr = 1.0 - norm2;
        if rr <= tol2 {
            dep.push(c);
            continue;
        }
        col.push(rr.sqrt());
        r.push(col);
        kept.push(c);
        d.push(dc);
    }
    let p = kept.len();
    // Forward substitution for z = R⁻ᵀ (D⁻¹ Xᵀy / |y|), back substitution
    // for the scaled estimate.
    let mut z = vec![0.0; p];
    for k in 0..p {
        let mut v = g[(kept[k], target)] / (d[k] * dt);
        for l in 0..k {
            v -= r[k][l] * z[l];
        }
        z[k] = v / r[k][k];
    }
    let mut b = vec![0.0; p];
    for k in (0..p).rev() {
        let mut v = z[k];
        for j in k + 1..p {
            v -= r[j][k] * b[j];
        }
        b[k] = v / r[k][k];
    }
    let estimate: Vec<f64> = (0..p).map(|k| b[k] * dt / d[k]).collect();
    let rss_of = |s: &Sums, grp: usize| -> f64 {
        let m = &s.grams[grp];
        let mut q = m[(target, target)];
        for k in 0..p {
            q -= 2.0 * estimate[k] * m[(kept[k], target)];
            for l in 0..p {
                q += estimate[k] * estimate[l] * m[(kept[k], kept[l])];
            }
        }
        q.max(0.0)
    };
    let groups = train.grams.len();
    let rss: Vec<f64> = (0..groups).map(|grp| rss_of(train, grp)).collect();
    let n: usize = train.rows.iter().sum();
    // σ: s² (XᵀX)⁻¹ with (XᵀX)⁻¹ = D⁻¹ R⁻¹ R⁻ᵀ D⁻¹; R⁻¹ column by column.
    let dof = n as f64 - p as f64;
    let s2 = if dof > 0.0 {
        rss.iter().sum::<f64>() / dof / noise_gain
    } else {
        f64::NAN
    };
    let mut rinv = vec![vec![0.0; p]; p]; // rinv[col][row]
    for j in 0..p {
        rinv[j][j] = 1.0 / r[j][j];
        for i in (0..j).rev() {
            let mut v = 0.0;
            for k in i + 1..=j {
                v += r[k][i] * rinv[j][k];
            }
            rinv[j][i] = -v / r[i][i];
        }
    }
    let std_dev: Vec<f64> = (0..p)
        .map(|k| {
            let row2: f64 = (k..p).map(|j| rinv[j][k] * rinv[j][k]).sum();
            let v = (s2 * row2).sqrt() / d[k];
            if v.is_finite() { v } else { 0.0 }
        })
        .collect();
    let fac = Mat::from_fn(p, p, |i, j| if i <= j { r[j][i] } else { 0.0 });
    let check = GramCheck::of_factor(fac.as_ref());
    let fitness = validation
        .iter()
        .map(|s| {
            (0..groups)
                .map(|grp| {
                    crate::validate::fitness_from_sums(
                        rss_of(s, grp),
                        s.sums[grp][target],
                        s.grams[grp][(target, target)],
                        s.rows[grp],
                        grp,
                    )
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(ModelFit {
        columns: kept,
        dependent: dep,
        target,
        estimate,
        std_dev,
        rss,
        rows: train.rows.clone(),
        fitness,
        accuracy: if check.passed {
            Accuracy::Within
        } else {
            Accuracy::Beyond
        },
        check,
    })
}
