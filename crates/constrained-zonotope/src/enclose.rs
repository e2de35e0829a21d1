//! A-priori bounds of rounding errors (docs/constrained-zonotopes.md, "Rounding").
//!
//! A dot product of length `k` evaluated in floating point (round to nearest) satisfies
//! `|fl(xᵀy) − xᵀy| ≤ γ_k |x|ᵀ|y| + k·η` (Higham, *Accuracy and Stability of Numerical
//! Algorithms*, §3.1; `γ_k = k u / (1 − k u)`, `u = 2⁻⁵³`, `η = 2⁻¹⁰⁷⁴` for underflow). The computed
//! `fl(|x|ᵀ|y|)` falls short of `|x|ᵀ|y|` by at most the factor `1 − γ_k`; [`dot_error`] covers
//! both with `γ_{k+2}` and rounds its own result up.

use intervals::up;
use nalgebra::DMatrix;

const U: f64 = f64::EPSILON / 2.0;

/// `γ_k = k u / (1 − k u)`.
#[must_use]
pub fn gamma(k: usize) -> f64 {
    let ku = k as f64 * U;
    ku / (1.0 - ku)
}

/// An upper bound of `|fl(Σ xᵢ yᵢ) − Σ xᵢ yᵢ|` for a sum of `len` products whose computed sum of
/// magnitudes is `abs_sum` (module documentation). `+∞` when `abs_sum` overflowed.
#[must_use]
#[inline]
pub fn dot_error(abs_sum: f64, len: usize) -> f64 {
    let tiny = len as f64 * f64::from_bits(1);
    up(up(gamma(len + 2) * abs_sum) + tiny)
}

/// `a + b` rounded up (for sums of non-negative error bounds).
#[must_use]
#[inline]
pub fn add_up(a: f64, b: f64) -> f64 {
    up(a + b)
}

/// An upper bound of `Σⱼ |mᵢⱼ|` (row `i`).
#[must_use]
pub fn abs_row_sum_up(m: &DMatrix<f64>, i: usize) -> f64 {
    let mut s = 0.0;
    for j in 0..m.ncols() {
        s = add_up(s, m[(i, j)].abs());
    }
    s
}

/// The product `M X` (`r × k` times `k × q`) and an upper bound of each entry's rounding error.
#[must_use]
pub fn product(m: &DMatrix<f64>, x: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
    let (r, k, q) = (m.nrows(), m.ncols(), x.ncols());
    let mut p = DMatrix::zeros(r, q);
    let mut e = DMatrix::zeros(r, q);
    for j in 0..q {
        for i in 0..r {
            let (mut s, mut a) = (0.0, 0.0);
            for l in 0..k {
                let t = m[(i, l)] * x[(l, j)];
                s += t;
                a += t.abs();
            }
            p[(i, j)] = s;
            e[(i, j)] = if k == 0 { 0.0 } else { dot_error(a, k) };
        }
    }
    (p, e)
}

/// Per row `i`, an upper bound of `Σⱼ eᵢⱼ` (the error of a row of a generator matrix times a
/// factor in the unit box).
#[must_use]
pub fn row_sums_up(e: &DMatrix<f64>) -> Vec<f64> {
    (0..e.nrows()).map(|i| abs_row_sum_up(e, i)).collect()
}
