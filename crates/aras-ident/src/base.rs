//! Base parameters (58)–(61): which combinations of the standard parameters
//! the dynamics can see, found numerically from a stacked regressor.

use std::fmt;

use faer::{Mat, MatRef};
use serde::Serialize;

use crate::error::{IdentError, check_finite_mat};
use crate::rank::{analyse, combinations};

/// Default relative rank tolerance.
///
/// Columns are scaled to unit norm, so this is the sine of the angle between
/// a column and the span of the earlier ones (equivalently `|R_jj|` relative
/// to the largest, which is 1). Structural dependencies (trigonometric
/// identities, parameters that never enter the dynamics) leave a residual of
/// rounding size, about `√N · 1e-16` for `N` stacked rows, so below 1e-12 even
/// for millions of rows; any genuinely independent but weakly excited
/// parameter at 1e-8 would have its standard deviation amplified 10⁸ times
/// and could not be estimated anyway. 1e-8 sits safely between the two.
pub const DEFAULT_RANK_TOLERANCE: f64 = 1e-8;

/// Coefficients of a base parameter below this (relative, on unit-norm
/// columns) are rounding noise: they are set to exactly zero in `K` and not
/// printed.
pub const COEFFICIENT_CLEAN: f64 = 1e-9;

/// How far the decision on the rank was from the tolerance: a healthy
/// analysis has `smallest_kept ≫ tolerance ≫ largest_dropped`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RankMargin {
    /// Smallest sine (relative `|R_jj|`) among the kept columns.
    pub smallest_kept: f64,
    /// Largest sine among the dependent (grouped) columns; 0 if none.
    pub largest_dropped: f64,
    /// The tolerance used.
    pub tolerance: f64,
}

/// The map between `n` standard parameters and `b` base parameters.
///
/// `β_b = K β` with `K` (`b × n`) equal to the identity on the kept columns
/// `S`, so the base regressor is simply `W_b = W E` (`E` selects the columns
/// `S`) and `W β = W_b K β` for every `W` with the same dependencies.
#[derive(Debug, Clone)]
pub struct BaseParameters {
    names: Vec<String>,
    independent: Vec<usize>,
    grouped: Vec<usize>,
    unidentifiable: Vec<usize>,
    k: Mat<f64>,
    norms: Vec<f64>,
    margin: RankMargin,
}

impl BaseParameters {
    /// Finds the base parameters of the stacked regressor `w` (rows =
    /// samples, one column per standard parameter, named by `names`), with
    /// relative rank tolerance `tol` (see [`DEFAULT_RANK_TOLERANCE`]).
    ///
    /// Use many random, rich samples (as in (58)): a column dependency that
    /// only holds on poor data would be taken as structural. The earliest
    /// column of each dependent group names the base parameter.
    pub fn from_regressor<S: AsRef<str>>(
        w: MatRef<'_, f64>,
        names: &[S],
        tol: f64,
    ) -> Result<Self, IdentError> {
        let names: Vec<String> = names.iter().map(|s| s.as_ref().to_owned()).collect();
        if names.len() != w.ncols() {
            return Err(IdentError::DimensionMismatch {
                what: "parameter names for the regressor's columns",
                expected: w.ncols(),
                found: names.len(),
                hint: "give exactly one name per regressor column",
            });
        }
        if !(tol > 0.0 && tol < 1.0) {
            return Err(IdentError::InvalidSetting {
                name: "rank tolerance",
                value: tol,
                reason: "must lie in (0, 1); the default is 1e-8",
            });
        }
        check_finite_mat("regressor", w, &names)?;
        if w.nrows() == 0 || w.ncols() == 0 {
            return Err(IdentError::NoExcitation {
                what: "base parameters",
                rows: w.nrows(),
            });
        }
        let r = crate::dense::compress(w);
        let a = analyse(r.as_ref(), tol);
        if a.independent.is_empty() {
            return Err(IdentError::NoExcitation {
                what: "base parameters",
                rows: w.nrows(),
            });
        }
        let k = combinations(r.as_ref(), &a, COEFFICIENT_CLEAN);
        let margin = RankMargin {
            smallest_kept: a.smallest_kept(),
            largest_dropped: a.largest_dropped(),
            tolerance: tol,
        };
        Ok(Self {
            names,
            independent: a.independent,
            grouped: a.dependent,
            unidentifiable: a.zero,
            k,
            norms: a.norms,
            margin,
        })
    }

    /// Number of standard parameters `n`.
    pub fn n_standard(&self) -> usize {
        self.names.len()
    }

    /// Number of base parameters `b` (the numerical rank).
    pub fn n_base(&self) -> usize {
        self.independent.len()
    }

    /// Names of the standard parameters, in column order.
    pub fn standard_names(&self) -> &[String] {
        &self.names
    }

    /// Short names of the base parameters: `b1 … bb`.
    pub fn base_names(&self) -> Vec<String> {
        (1..=self.n_base()).map(|i| format!("b{i}")).collect()
    }

    /// Standard-parameter indices kept as base columns (`S`), increasing.
    pub fn independent(&self) -> &[usize] {
        &self.independent
    }

    /// Standard parameters that do not enter the data at all (zero columns):
    /// they cannot be identified and appear in no base parameter.
    pub fn unidentifiable(&self) -> Vec<&str> {
        self.unidentifiable
            .iter()
            .map(|&j| self.names[j].as_str())
            .collect()
    }

    /// Standard parameters identifiable only in combination: folded into
    /// base parameters named after an earlier column.
    pub fn grouped(&self) -> Vec<&str> {
        self.grouped
            .iter()
            .map(|&j| self.names[j].as_str())
            .collect()
    }

    /// The `b × n` map `K` of `β_b = K β`.
    pub fn k(&self) -> MatRef<'_, f64> {
        self.k.as_ref()
    }

    /// Column norms of the regressor the analysis was made on (the torque
    /// each standard parameter produces per unit value); zero for
    /// unidentifiable parameters.
    pub fn column_norms(&self) -> &[f64] {
        &self.norms
    }

    /// How close the rank decision was.
    pub fn rank_margin(&self) -> RankMargin {
        self.margin
    }

    fn check_len(&self, what: &'static str, v: &[f64], n: usize) -> Result<(), IdentError> {
        if v.len() != n {
            return Err(IdentError::DimensionMismatch {
                what,
                expected: n,
                found: v.len(),
                hint: "vectors must follow the parameter order of the base analysis",
            });
        }
        crate::error::check_finite_vec(what, v)
    }

    /// Standard → base: `β_b = K β`.
    pub fn to_base(&self, beta: &[f64]) -> Result<Vec<f64>, IdentError> {
        self.check_len("standard parameter vector", beta, self.n_standard())?;
        Ok((0..self.n_base())
            .map(|i| {
                (0..self.n_standard())
                    .map(|j| self.k[(i, j)] * beta[j])
                    .sum()
            })
            .collect())
    }

    /// Base → the standard representative with every grouped and
    /// unidentifiable parameter zero (`β = E β_b`; `K E = I`).
    pub fn to_standard(&self, beta_b: &[f64]) -> Result<Vec<f64>, IdentError> {
        self.check_len("base parameter vector", beta_b, self.n_base())?;
        let mut beta = vec![0.0; self.n_standard()];
        for (i, &j) in self.independent.iter().enumerate() {
            beta[j] = beta_b[i];
        }
        Ok(beta)
    }

    /// Base → the standard set closest to `reference` (e.g. CAD) with
    /// `K β = β_b`: `β = β_ref + C⁻¹ K̃⁺ (β_b − K β_ref)`, the smallest change
    /// measured in torque units (`K̃ = K C⁻¹`, `C` = column norms), so that
    /// parameters of different units are compared fairly. Unidentifiable
    /// parameters keep their reference values. With `reference = 0` this is
    /// the (torque-weighted) minimum-norm completion.
    pub fn to_standard_near(
        &self,
        beta_b: &[f64],
        reference: &[f64],
    ) -> Result<Vec<f64>, IdentError> {
        self.check_len("base parameter vector", beta_b, self.n_base())?;
        self.check_len(
            "reference standard parameters",
            reference,
            self.n_standard(),
        )?;
        let kref = self.to_base(reference)?;
        let rhs: Vec<f64> = beta_b.iter().zip(&kref).map(|(a, b)| a - b).collect();
        // Minimum-norm solution of K̃ δ̃ = rhs via the QR of K̃ᵀ (n × b, full
        // column rank because K̃ contains a scaled identity on S).
        let (n, b) = (self.n_standard(), self.n_base());
        let mut data = Vec::with_capacity(n * b);
        for i in 0..b {
            for j in 0..n {
                let c = self.norms[j];
                data.push(if c > 0.0 { self.k[(i, j)] / c } else { 0.0 });
            }
        }
        let qr = crate::dense::HouseholderQr::new(data, n, b);
        let r = qr.r();
        // Rᵀ y = rhs (forward substitution), then δ̃ = Q [y; 0].
        let mut y = rhs;
        for i in 0..b {
            let mut s = y[i];
            for j in 0..i {
                s -= r[(j, i)] * y[j];
            }
            y[i] = s / r[(i, i)];
        }
        let mut delta = vec![0.0; n];
        delta[..b].copy_from_slice(&y);
        qr.apply_q(&mut delta);
        Ok((0..n)
            .map(|j| {
                let c = self.norms[j];
                reference[j] + if c > 0.0 { delta[j] / c } else { 0.0 }
            })
            .collect())
    }

    /// The base regressor `W_b = W E` (the kept columns) of any regressor
    /// with the same columns as the analysis.
    pub fn base_regressor(&self, w: MatRef<'_, f64>) -> Result<Mat<f64>, IdentError> {
        if w.ncols() != self.n_standard() {
            return Err(IdentError::DimensionMismatch {
                what: "regressor columns",
                expected: self.n_standard(),
                found: w.ncols(),
                hint: "the regressor must have one column per standard parameter, in the order of the base analysis",
            });
        }
        Ok(Mat::from_fn(w.nrows(), self.n_base(), |i, j| {
            w[(i, self.independent[j])]
        }))
    }

    /// The readable definition of base parameter `i` (0-based), e.g.
    /// `b7 = L1.Izz + L2.Izz + 0.5·L3.Ixx`. Coefficients are printed with six
    /// significant digits; those within 1e-9 (relative) of an integer as
    /// that integer.
    pub fn expression(&self, i: usize) -> String {
        let mut s = format!("b{} =", i + 1);
        let mut first = true;
        for j in 0..self.n_standard() {
            let c = self.k[(i, j)];
            if c == 0.0 {
                continue;
            }
            let sign = if c < 0.0 { "-" } else { "+" };
            let mag = c.abs();
            let term = if (mag - 1.0).abs() <= 1e-9 {
                self.names[j].clone()
            } else {
                format!("{}·{}", format_coefficient(mag), self.names[j])
            };
            if first {
                s.push_str(&format!(" {}{}", if c < 0.0 { "-" } else { "" }, term));
                first = false;
            } else {
                s.push_str(&format!(" {sign} {term}"));
            }
        }
        s
    }

    /// All base-parameter definitions, one per line.
    pub fn expressions(&self) -> Vec<String> {
        (0..self.n_base()).map(|i| self.expression(i)).collect()
    }
}

/// Six significant digits, trailing zeros trimmed, integers without a dot.
fn format_coefficient(x: f64) -> String {
    let r = x.round();
    if r != 0.0 && (x - r).abs() <= 1e-9 * x.abs() {
        return format!("{r:.0}");
    }
    let s = format!("{:.5e}", x);
    let (mant, exp) = s.split_once('e').unwrap_or((&s, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    if (-4..6).contains(&exp) {
        let decimals = (5 - exp).max(0) as usize;
        let t = format!("{x:.decimals$}");
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            t
        }
    } else {
        let m = mant.trim_end_matches('0').trim_end_matches('.');
        format!("{m}e{exp}")
    }
}

impl fmt::Display for BaseParameters {
    /// One definition per line, then the grouped and unidentifiable lists.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} base parameters from {} standard parameters (rank tolerance {:e}, smallest kept {:.3e}, largest dropped {:.3e})",
            self.n_base(),
            self.n_standard(),
            self.margin.tolerance,
            self.margin.smallest_kept,
            self.margin.largest_dropped
        )?;
        for e in self.expressions() {
            writeln!(f, "  {e}")?;
        }
        if !self.grouped.is_empty() {
            writeln!(f, "  grouped into the above: {}", self.grouped().join(", "))?;
        }
        if !self.unidentifiable.is_empty() {
            writeln!(
                f,
                "  unidentifiable (no effect on the data): {}",
                self.unidentifiable().join(", ")
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::format_coefficient;

    #[test]
    fn coefficients_print_readably() {
        assert_eq!(format_coefficient(0.5), "0.5");
        assert_eq!(format_coefficient(2.0000000001), "2");
        assert_eq!(format_coefficient(0.0635040), "0.063504");
        assert_eq!(format_coefficient(123.456789), "123.457");
        assert_eq!(format_coefficient(1.5e-7), "1.5e-7");
    }
}
