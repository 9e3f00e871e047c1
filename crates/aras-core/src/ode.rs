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
///
/// The stages are stored in `S`: a `Vec<f64>` for a dimension known at run
/// time ([`Rk4::new`]), or an array `[f64; N]` for a fixed one
/// ([`Rk4::fixed`]), whose lengths the compiler sees through the step.
#[derive(Debug, Clone, PartialEq)]
pub struct Rk4<S = Vec<f64>> {
    k: [S; 4],
    stage: S,
}

impl Rk4 {
    /// An integrator for states of dimension `dim`.
    pub fn new(dim: usize) -> Self {
        Self {
            k: std::array::from_fn(|_| vec![0.0; dim]),
            stage: vec![0.0; dim],
        }
    }
}

impl<const N: usize> Rk4<[f64; N]> {
    /// An integrator for states of the fixed dimension `N`.
    pub fn fixed() -> Self {
        Self {
            k: [[0.0; N]; 4],
            stage: [0.0; N],
        }
    }
}

impl<S: AsRef<[f64]> + AsMut<[f64]>> Rk4<S> {
    /// The state dimension.
    pub fn dim(&self) -> usize {
        self.stage.as_ref().len()
    }

    /// One step of length `h` of `x`, with `f(x, ẋ)` writing the
    /// derivative at `x` into `ẋ` (every entry). An error of `f` is
    /// returned at once and leaves `x` as it was.
    ///
    /// # Panics
    ///
    /// If `x` is not of dimension [`Self::dim`].
    #[inline]
    pub fn step<E>(
        &mut self,
        x: &mut [f64],
        h: f64,
        mut f: impl FnMut(&[f64], &mut [f64]) -> Result<(), E>,
    ) -> Result<(), E> {
        assert_eq!(x.len(), self.dim(), "state dimension");
        let [k1, k2, k3, k4] = &mut self.k;
        let (k1, k2, k3, k4) = (k1.as_mut(), k2.as_mut(), k3.as_mut(), k4.as_mut());
        let stage = self.stage.as_mut();
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
        for ((((x, a), b), c), d) in x.iter_mut().zip(&*k1).zip(&*k2).zip(&*k3).zip(&*k4) {
            *x += (a + (b + c) * 2.0 + d) * s;
        }
        Ok(())
    }
}
