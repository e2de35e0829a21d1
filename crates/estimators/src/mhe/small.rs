//! Cholesky factorisation and inverse of small column-major matrices held in slices
//! (allocation-free helpers of the moving-horizon estimators).

/// Lower Cholesky factor of the `n × n` column-major `a` in place (lower triangle read and
/// written); false if a pivot is not positive to working precision (relative `1e−14`).
pub(crate) fn cholesky(a: &mut [f64], n: usize) -> bool {
    dense_kernels::cholesky_slice(a, n, 1e-14)
}

/// `out ← (L Lᵀ)⁻¹` (full symmetric) from the lower factor `l`.
pub(crate) fn chol_inverse(l: &[f64], n: usize, out: &mut [f64]) {
    // Column by column: solve L Lᵀ x = e_c.
    for c in 0..n {
        let col = &mut out[c * n..(c + 1) * n];
        col.fill(0.0);
        col[c] = 1.0;
        for i in 0..n {
            let mut s = col[i];
            for k in 0..i {
                s -= l[k * n + i] * col[k];
            }
            col[i] = s / l[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = col[i];
            for k in i + 1..n {
                s -= l[i * n + k] * col[k];
            }
            col[i] = s / l[i * n + i];
        }
    }
    for c in 0..n {
        for r in c + 1..n {
            let v = 0.5 * (out[c * n + r] + out[r * n + c]);
            out[c * n + r] = v;
            out[r * n + c] = v;
        }
    }
}
