//! The classical fourth-order Runge–Kutta step of the simulators.

/// Classical RK4 on a flat state `x ∈ ℝⁿ` with `ẋ = f(x)`, its stage
/// buffers allocated once.
///
/// One step of length `h` evaluates `k₁ = f(x)`, `k₂ = f(x + k₁·(h/2))`,
/// `k₃ = f(x + k₂·(h/2))`, `k₄ = f(x + k₃·h)` and sets
/// `x ← x + (k₁ + (k₂ + k₃)·2 + k₄)·(h/6)`, in that order of floating-point
/// operations. Its local error is `O(h⁵)`: exact, to rounding, for a
/// solution polynomial of degree ≤ 4. A simulator holds the input (the
/// motor torque) in the closure over the step, a zero-order hold.
#[derive(Debug, Clone, PartialEq)]
pub struct Rk4 {
    k: [Vec<f64>; 4],
    stage: Vec<f64>,
}

impl Rk4 {
    /// An integrator for states of dimension `dim`.
    pub fn new(dim: usize) -> Self {
        Self {
            k: std::array::from_fn(|_| vec![0.0; dim]),
            stage: vec![0.0; dim],
        }
    }

    /// The state dimension.
    pub fn dim(&self) -> usize {
        self.stage.len()
    }

    /// One step of length `h` of `x`, with `f(x, ẋ)` writing the
    /// derivative at `x` into `ẋ` (every entry). An error of `f` is
    /// returned at once and leaves `x` as it was.
    ///
    /// # Panics
    ///
    /// If `x` is not of dimension [`Self::dim`].
    pub fn step<E>(
        &mut self,
        x: &mut [f64],
        h: f64,
        mut f: impl FnMut(&[f64], &mut [f64]) -> Result<(), E>,
    ) -> Result<(), E> {
        assert_eq!(x.len(), self.dim(), "state dimension");
        let [k1, k2, k3, k4] = &mut self.k;
        let stage = &mut self.stage;
        let at = |stage: &mut [f64], k: &[f64], s: f64| {
            for ((y, x), k) in stage.iter_mut().zip(x.iter()).zip(k) {
                *y = x + k * s;
            }
        };
        f(x, k1)?;
        at(stage, k1, 0.5 * h);
        f(stage, k2)?;
        at(stage, k2, 0.5 * h);
        f(stage, k3)?;
        at(stage, k3, h);
        f(stage, k4)?;
        let s = h / 6.0;
        for (i, x) in x.iter_mut().enumerate() {
            *x += (k1[i] + (k2[i] + k3[i]) * 2.0 + k4[i]) * s;
        }
        Ok(())
    }
}
