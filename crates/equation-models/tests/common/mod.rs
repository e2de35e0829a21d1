//! Helpers shared by the integration tests.

use nalgebra::DVector;

/// A small deterministic generator of uniform numbers in `[lo, hi)`.
#[allow(dead_code)]
pub struct Lcg(pub u64);

impl Lcg {
    /// A uniform number in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }

    /// A vector of `n` uniform numbers in `[lo, hi)`.
    #[allow(dead_code)]
    pub fn vector(&mut self, n: usize, lo: f64, hi: f64) -> DVector<f64> {
        DVector::from_fn(n, |_, _| self.uniform(lo, hi))
    }
}
