//! The one thing identification needs from a robot: a dynamic model that is
//! linear in its parameters.

/// A dynamic model linear in its parameters, `τ = Y(q, q̇, q̈) β`: for one
/// sample of the coordinates `q` and their first and second time
/// derivatives, [`outputs`](Self::outputs) rows (one per actuator, the row
/// groups of a stacked regressor) of [`columns`](Self::columns) entries (one
/// per standard parameter, named by [`names`](Self::names)).
///
/// Implement it for any robot to use the streaming accumulation
/// ([`crate::streaming::RegressorStage`]) on it; the stacked matrices of the
/// in-memory path ([`crate::BaseParameters`], [`crate::ols`]) need only the
/// rows it produces. SI units: `q` in rad or m, rates per second.
pub trait LinearModel: Sync {
    /// Why an evaluation failed (e.g. a pose outside the workspace).
    type Error: std::error::Error + Send + Sync + 'static;

    /// Number of coordinates of a sample (length of `q`, `q̇`, `q̈`).
    fn coordinates(&self) -> usize;

    /// Rows per sample: one per actuator.
    fn outputs(&self) -> usize;

    /// The standard parameters' names, in column order.
    fn names(&self) -> Vec<String>;

    /// Number of columns (standard parameters).
    fn columns(&self) -> usize {
        self.names().len()
    }

    /// Writes every entry of `Y(q, q̇, q̈)` into `rows`, column-major `outputs × columns`
    /// (`rows[outputs · j + i]` is output `i`'s entry of column `j`, as
    /// nalgebra's column-major matrices). Called once per sample in the hot
    /// path of streaming identification: should not allocate.
    fn fill(
        &self,
        q: &[f64],
        q_dot: &[f64],
        q_ddot: &[f64],
        rows: &mut [f64],
    ) -> Result<(), Self::Error>;
}

impl<M: LinearModel> LinearModel for &M {
    type Error = M::Error;

    fn coordinates(&self) -> usize {
        (**self).coordinates()
    }

    fn outputs(&self) -> usize {
        (**self).outputs()
    }

    fn names(&self) -> Vec<String> {
        (**self).names()
    }

    fn columns(&self) -> usize {
        (**self).columns()
    }

    fn fill(
        &self,
        q: &[f64],
        q_dot: &[f64],
        q_ddot: &[f64],
        rows: &mut [f64],
    ) -> Result<(), Self::Error> {
        (**self).fill(q, q_dot, q_ddot, rows)
    }
}
