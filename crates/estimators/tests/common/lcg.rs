//! The moving-horizon tests' random systems and data, drawn from a small linear congruential
//! generator.

use nalgebra::{DMatrix, DVector};

/// Inputs and measurements of a run.
pub type Data = (Vec<DVector<f64>>, Vec<DVector<f64>>);

/// A linear congruential generator.
pub struct Lcg(pub u64);

impl Lcg {
    /// A uniform number in `[-1, 1)`.
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    /// `1` or `-1`, by the sign of the next uniform number.
    pub fn sign(&mut self) -> f64 {
        if self.uniform() >= 0.0 { 1.0 } else { -1.0 }
    }
}

/// A random stable-ish system `(A, B, C)` with `n` states, one input and `m` outputs.
pub fn system(n: usize, m: usize, seed: u64) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let mut g = Lcg(seed);
    let a = DMatrix::from_fn(n, n, |i, j| if i == j { 0.9 } else { 0.0 } + 0.2 * g.uniform());
    let b = DMatrix::from_fn(n, 1, |_, _| g.uniform());
    let c = DMatrix::from_fn(m, n, |_, _| g.uniform());
    (a, b, c)
}

/// `steps` inputs `u_k = sin(0.3 k)` and measurements of `(A, B, C)` from `x0_scale · g.uniform()`
/// in each component of `x₀`, with each process noise component `w · draw(g)` and each
/// measurement noise component `v · draw(g)`.
pub fn simulate(
    (a, b, c): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    steps: usize,
    g: &mut Lcg,
    x0_scale: f64,
    (w, v): (f64, f64),
    draw: fn(&mut Lcg) -> f64,
) -> Data {
    let mut x = DVector::from_fn(a.nrows(), |_, _| x0_scale * g.uniform());
    let (mut us, mut ys) = (Vec::new(), Vec::new());
    for k in 0..steps {
        let u = DVector::from_element(1, (0.3 * k as f64).sin());
        x = a * &x + b * &u + DVector::from_fn(a.nrows(), |_, _| w * draw(g));
        ys.push(c * &x + DVector::from_fn(c.nrows(), |_, _| v * draw(g)));
        us.push(u);
    }
    (us, ys)
}
