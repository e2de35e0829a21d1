//! How the input enters the filter: in the predictor (13), or as a bounded disturbance (the
//! Yang–Li reconstruction (a)), with the rigorous effective-noise bound.

use nalgebra::{DMatrix, DVector};

use super::certify::{U, gamma};
use crate::error::EstimatorError;

/// How the input enters the filter.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum InputModel {
    /// `B u_k` in the predictor, as in (13).
    Predictor,
    /// The input is not used: `B u` over the box `[lower, upper]` is a bounded disturbance
    /// with centre `B u_mid` and outer ellipsoid `B 𝓔(0, W) Bᵀ`, `W = p · diag(h²)` (`h` the
    /// half-widths), added to the process noise by a trace-optimal outer Minkowski sum
    /// (the Yang–Li reconstruction (a), see [`crate::yang_li`]).
    ///
    /// Each step checks that `u` lies in the box and refuses it otherwise
    /// ([`EstimatorError::InputOutsideBounds`]). The centre and `W` are computed from the box
    /// with their rounding covered (`W` is enlarged by `8u` relative).
    BoundedDisturbance {
        /// Lower corner of the box.
        lower: DVector<f64>,
        /// Upper corner of the box.
        upper: DVector<f64>,
        /// Box centre `u_mid`.
        mid: DVector<f64>,
        /// Diagonal of `W`.
        w_diag: DVector<f64>,
    },
}

/// Refuses an input outside the declared box (allocation-free).
pub(crate) fn check_in_box(u: &DVector<f64>, lower: &DVector<f64>, upper: &DVector<f64>) -> Result<(), EstimatorError> {
    for i in 0..u.len() {
        let (value, lo, hi) = (u[i], lower[i], upper[i]);
        if !(lo <= value && value <= hi) {
            return Err(EstimatorError::InputOutsideBounds { index: i, value, lower: lo, upper: hi });
        }
    }
    Ok(())
}

/// `Q_eff = (1 + 1/s) Q + (1 + s) B W Bᵀ`, `s = √(tr Q / tr BWBᵀ)` (trace-optimal outer bound of
/// `𝓔(0, Q) ⊕ B 𝓔(0, W)`, valid even when `B W Bᵀ` is singular since `Q` is positive
/// definite), with a bound on its rounding error added to the diagonal so that the stored
/// `Q_eff` dominates the exact one (for the computed `s`; any `s > 0` gives a valid bound).
///
/// Rounding (`u = 2⁻⁵³`): entrywise, `|fl(Q_eff) − Q_eff| ≤ γ_{p+6} (1+s) |B|W|B|ᵀ +
/// γ₆ (1+1/s) |Q|` (for `BWBᵀ`: `B·W` one rounding, the `p`-term products `γ_{p+1}`, the
/// coefficient `1 + s` and its product two, the sum and the symmetrisation two; for `Q`: the
/// coefficient `1 + 1/s` two, its product, the sum and the symmetrisation three, plus one of
/// slack). Its spectral norm is at most `γ_{p+6}(1+s) ‖|B|W|B|ᵀ‖₂ + γ₆(1+1/s) ‖Q‖_F`, and
/// `‖|B|W|B|ᵀ‖₂ ≤ tr(|B|W|B|ᵀ) = Σⱼ wⱼ‖bⱼ‖² = tr(BWBᵀ)` (positive semidefinite), computed
/// directly from the columns of `B` and enlarged by `1 + γ_{n+p+1}` for its own rounding
/// (`‖Q‖_F` by `1 + γ_{n²+2}`). Adding `ε` to a diagonal entry `d` rounds too; `ε` is enlarged
/// by `16u` relative and by `4u max|dᵢ|`, which covers it.
pub(crate) fn effective_noise(
    q: &DMatrix<f64>,
    b: &DMatrix<f64>,
    w_diag: &DVector<f64>,
    bw: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) {
    let (n, p) = b.shape();
    let mut tb = 0.0;
    for j in 0..p {
        let col = &b.as_slice()[j * n..(j + 1) * n];
        tb += w_diag[j] * dense_kernels::dot(col, col);
        for i in 0..n {
            bw[(i, j)] = b[(i, j)] * w_diag[j];
        }
    }
    if tb.is_nan() || tb <= 0.0 {
        // B W Bᵀ = 0 (exactly: every term of the trace is a square times wⱼ ≥ 0).
        out.copy_from(q);
        return;
    }
    dense_kernels::mul_nt(1.0, bw, b, 0.0, out);
    let s = (q.trace() / tb).sqrt();
    out.iter_mut().for_each(|v| *v *= 1.0 + s);
    dense_kernels::add_scaled(out.as_mut_slice(), 1.0 + 1.0 / s, q.as_slice());
    dense_kernels::symmetrize(out);
    let tb_up = tb * (1.0 + gamma(n + p + 1));
    let nq_up = dense_kernels::fro(q.as_slice()) * (1.0 + gamma(n * n + 2));
    let err = gamma(p + 6) * (1.0 + s) * tb_up + gamma(6) * (1.0 + 1.0 / s) * nq_up;
    let max_d = (0..n).map(|i| out[(i, i)].abs()).fold(0.0, f64::max);
    let eps = err * (1.0 + 16.0 * U) + 4.0 * U * max_d;
    for i in 0..n {
        out[(i, i)] += eps;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random number in [−1, 1).
    fn lcg(state: &mut u64) -> f64 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    #[test]
    fn effective_noise_dominates_the_exact_sum() {
        // Q_eff − [(1 + 1/s) Q + (1 + s) B W Bᵀ] ⪰ 0 against nalgebra's evaluation, and the
        // inflation stays at the rounding level.
        let mut state = 42;
        for (n, p) in [(1, 1), (2, 3), (4, 8), (8, 8), (8, 2), (3, 1)] {
            for scale in [1e-6, 1.0, 1e6] {
                let g = DMatrix::from_fn(n, n, |_, _| lcg(&mut state));
                let q = &g * g.transpose() + DMatrix::identity(n, n) * 0.1;
                let b = DMatrix::from_fn(n, p, |_, _| lcg(&mut state) * scale);
                let w = DVector::from_fn(p, |_, _| 1.0 + lcg(&mut state));
                let mut bw = DMatrix::zeros(n, p);
                let mut out = DMatrix::zeros(n, n);
                effective_noise(&q, &b, &w, &mut bw, &mut out);
                let bwb = &b * DMatrix::from_diagonal(&w) * b.transpose();
                let s = (q.trace() / bwb.trace()).sqrt();
                let exact = &q * (1.0 + 1.0 / s) + &bwb * (1.0 + s);
                let diff = &out - &exact;
                let lmin = diff.clone().symmetric_eigenvalues().min();
                let scale_ref = exact.trace();
                assert!(lmin >= 0.0, "n = {n}, p = {p}: λmin = {lmin:e} (trace {scale_ref:e})");
                assert!(diff.norm() <= 1e-12 * scale_ref, "n = {n}, p = {p}: {:e}", diff.norm() / scale_ref);
            }
        }
    }
}
