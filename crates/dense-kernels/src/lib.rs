//! Small dense kernels shared by the workspace: one home for the Cholesky factorisation and the
//! triangular solves, symmetric-positive-definite checks, symmetrisation and their tolerances,
//! and the allocation-free products of the filters' hot paths.
//!
//! * Hot-path kernels (`mul_nn`, `mul_nt`, `gemv`, `symmetrize`, `i_minus_lc`, …) work on
//!   column-major [`DMatrix`] storage and write into a preallocated output whose dimensions the
//!   caller guarantees (checked by `debug_assert!`). Sizes are those of the filters (a few
//!   states), so plain loops beat blocked BLAS here.
//! * [`cholesky`]: in-place factorisations of matrices and column-major slices, left and right
//!   triangular solves, solves and inverses from a factor; none of them allocates except
//!   [`cholesky_checked`].
//! * [`small`]: the same kernels with their sizes as const generic parameters, for a caller
//!   that knows its sizes once (a filter of `n` states and `m` outputs) and dispatches to them;
//!   same operations in the same order, so the same numbers; [`fixed`]: their twins that also
//!   skip a zero multiplier as the general kernels do, so the same bits on any data.
//! * Validation ([`spd`]): symmetry and positive definiteness with the workspace's tolerances,
//!   reporting the offending entry or pivot.
//! * [`test_data`]: deterministic pseudo-random matrices for the workspace's tests.
//!
//! **The pivot rule.** Positive definite to working precision means that every Cholesky pivot
//! `G_jj²` is finite and above `4 ε n` times its own diagonal entry ([`PD_RELATIVE_TOLERANCE`]
//! `= 4 ε`): every factorisation here applies it, and a caller that needs another threshold passes
//! it to a `*_with` variant and says why at the call site.
//!
//! The interior-point SDP backend (`lmi`) keeps its own faer/SIMD kernels because its whole
//! iteration runs inside one SIMD dispatch, into which those kernels must be inlined to be
//! compiled for the machine's instruction set; called from here they would run at the baseline
//! target's.

pub mod cholesky;
pub mod fixed;
pub mod small;
pub mod spd;
pub mod test_data;

use nalgebra::{DMatrix, DVector};

pub use cholesky::{
    cholesky_checked, cholesky_in_place, cholesky_in_place_with, cholesky_inverse, cholesky_slice, cholesky_slice_with,
    cholesky_solve, solve_lower, solve_lower_t, solve_right_lower, solve_right_lower_t, spd_inverse,
};
pub use spd::{PD_RELATIVE_TOLERANCE, PivotFailure, SYMMETRY_TOLERANCE, max_asymmetry};

/// `out = alpha · a · b + beta · out`.
pub fn mul_nn(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>) {
    debug_assert_eq!(b.nrows(), a.ncols());
    // b[l, j] is at j·k + l (column-major b, k × c).
    mul_strided(alpha, a, b.as_slice(), b.ncols(), (a.ncols(), 1), beta, out);
}

/// `out = alpha · a · bᵀ + beta · out`.
pub fn mul_nt(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>) {
    debug_assert_eq!(b.ncols(), a.ncols());
    // bᵀ[l, j] = b[j, l] is at l·c + j (column-major b, c × k).
    mul_strided(alpha, a, b.as_slice(), b.nrows(), (1, b.nrows()), beta, out);
}

/// `out = alpha · a · B + beta · out` where `B[l, j] = b[j·stride.0 + l·stride.1]` has `c` columns.
///
/// Up to [`small::MAX_ROWS`] rows the output column is accumulated in registers by a kernel with
/// the row count fixed (one dispatch per call, same operations in the same order).
fn mul_strided(
    alpha: f64,
    a: &DMatrix<f64>,
    b: &[f64],
    c: usize,
    stride: (usize, usize),
    beta: f64,
    out: &mut DMatrix<f64>,
) {
    let (r, k) = a.shape();
    debug_assert_eq!(out.shape(), (r, c));
    let (a, o) = (a.as_slice(), out.as_mut_slice());
    macro_rules! rows {
        ($($r:literal)*) => {
            match r {
                $($r => small::mul_rows::<$r>(alpha, a, b, (k, c), stride, beta, o),)*
                _ => mul_any(alpha, a, b, (r, k, c), stride, beta, o),
            }
        };
    }
    rows!(1 2 3 4 5 6 7 8)
}

/// [`mul_strided`] for any row count.
fn mul_any(
    alpha: f64,
    a: &[f64],
    b: &[f64],
    (r, k, c): (usize, usize, usize),
    stride: (usize, usize),
    beta: f64,
    o: &mut [f64],
) {
    for j in 0..c {
        let oc = &mut o[j * r..(j + 1) * r];
        scale_col(oc, beta);
        for l in 0..k {
            let s = alpha * b[j * stride.0 + l * stride.1];
            if s != 0.0 {
                let ac = &a[l * r..(l + 1) * r];
                for i in 0..r {
                    oc[i] += s * ac[i];
                }
            }
        }
    }
}

/// `out = alpha · a · x + beta · out` (matrix–vector).
pub fn gemv(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
    let (r, k) = a.shape();
    debug_assert_eq!(x.len(), k);
    debug_assert_eq!(out.len(), r);
    let (a, x, o) = (a.as_slice(), x.as_slice(), out.as_mut_slice());
    // A vector is a one-column matrix: x[l] is at l.
    macro_rules! rows {
        ($($r:literal)*) => {
            match r {
                $($r => small::mul_rows::<$r>(alpha, a, x, (k, 1), (0, 1), beta, o),)*
                _ => mul_any(alpha, a, x, (r, k, 1), (0, 1), beta, o),
            }
        };
    }
    rows!(1 2 3 4 5 6 7 8)
}

fn scale_col(c: &mut [f64], beta: f64) {
    if beta == 0.0 {
        c.iter_mut().for_each(|v| *v = 0.0);
    } else if beta != 1.0 {
        c.iter_mut().for_each(|v| *v *= beta);
    }
}

/// `out = A B` on column-major slices: `A` is `rows × inner`, `B` is `inner × cols`, `out` is
/// `rows × cols`. Each entry is summed over the inner index in order from 0, so the numbers are
/// those of the plain triple loop bit for bit. For a row-major `P = X Y`, pass `Y` as `a` and `X`
/// as `b` (`Pᵀ = Yᵀ Xᵀ`).
///
/// # Panics
/// If a slice is shorter than its matrix (the caller's sizes are an invariant of its buffers).
#[inline]
pub fn mul_slices(rows: usize, inner: usize, cols: usize, a: &[f64], b: &[f64], out: &mut [f64]) {
    debug_assert!(a.len() >= rows * inner && b.len() >= inner * cols && out.len() >= rows * cols);
    for col in 0..cols {
        let b_col = &b[col * inner..(col + 1) * inner];
        for r in 0..rows {
            let mut s = 0.0;
            for (k, &bk) in b_col.iter().enumerate() {
                s += a[k * rows + r] * bk;
            }
            out[col * rows + r] = s;
        }
    }
}

/// `Σ aᵢ bᵢ`; for matrices of equal shape, the Frobenius inner product `⟨A, B⟩ = tr(Aᵀ B)`.
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut s = 0.0;
    for i in 0..a.len() {
        s += a[i] * b[i];
    }
    s
}

/// Frobenius norm.
pub fn fro(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// `out = x · a + y · b` entrywise (same shapes).
#[inline]
pub fn lin2(out: &mut [f64], x: f64, a: &[f64], y: f64, b: &[f64]) {
    for i in 0..out.len() {
        out[i] = x * a[i] + y * b[i];
    }
}

/// `out += alpha · a` entrywise.
#[inline]
pub fn add_scaled(out: &mut [f64], alpha: f64, a: &[f64]) {
    for i in 0..out.len() {
        out[i] += alpha * a[i];
    }
}

/// `a ← (a + aᵀ)/2`.
#[inline]
pub fn symmetrize(a: &mut DMatrix<f64>) {
    let n = a.nrows();
    for j in 0..n {
        for i in j + 1..n {
            let v = 0.5 * (a[(i, j)] + a[(j, i)]);
            a[(i, j)] = v;
            a[(j, i)] = v;
        }
    }
}

/// `out = I − L C` (`L` is `n × m`, `C` is `m × n`).
pub fn i_minus_lc(l: &DMatrix<f64>, c: &DMatrix<f64>, out: &mut DMatrix<f64>) {
    mul_nn(-1.0, l, c, 0.0, out);
    let n = out.nrows();
    for i in 0..n {
        out[(i, i)] += 1.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_data::centred_matrix as m;

    #[test]
    fn slice_products_match_nalgebra_and_the_row_major_reading() {
        let (a, b) = (m(3, 4, 11), m(4, 2, 12));
        let mut out = vec![0.0; 6];
        mul_slices(3, 4, 2, a.as_slice(), b.as_slice(), &mut out);
        assert!((DMatrix::from_column_slice(3, 2, &out) - &a * &b).amax() < 1e-15);
        // Row-major X (2 × 3) and Y (3 × 2): P = X Y from the column-major reading of the same arrays.
        let (x, y) = ([1.0, 2.0, 3.0, 4.0, 5.0, 6.0], [7.0, 8.0, 9.0, 10.0, 11.0, 12.0]);
        let mut p = [0.0; 4];
        mul_slices(2, 3, 2, &y, &x, &mut p);
        assert_eq!(p, [58.0, 64.0, 139.0, 154.0]);
    }

    #[test]
    fn kernels_match_nalgebra() {
        let a = m(3, 4, 1);
        let b = m(4, 2, 2);
        let bt = b.transpose();
        let mut o = DMatrix::from_element(3, 2, 1.0);
        mul_nn(2.0, &a, &b, 0.5, &mut o);
        assert!((&o - (&a * &b * 2.0 + DMatrix::from_element(3, 2, 0.5))).amax() < 1e-14);
        mul_nt(1.0, &a, &bt, 0.0, &mut o);
        assert!((&o - &a * &b).amax() < 1e-14);
        let x = DVector::from_column_slice(&[1.0, -2.0, 0.5, 3.0]);
        let mut y = DVector::zeros(3);
        gemv(1.0, &a, &x, 0.0, &mut y);
        assert!((&y - &a * &x).amax() < 1e-14);

        let h = m(3, 3, 3);
        let s = &h * h.transpose() + DMatrix::identity(3, 3);
        let mut g = s.clone();
        assert!(cholesky_in_place(&mut g).is_ok());
        assert!((&g * g.transpose() - &s).amax() < 1e-13);
        let rhs = m(5, 3, 4);
        let mut y = rhs.clone();
        solve_right_lower_t(&mut y, &g);
        assert!((&y * g.transpose() - &rhs).amax() < 1e-12);
        let mut y = rhs.clone();
        solve_right_lower(&mut y, &g);
        assert!((&y * &g - &rhs).amax() < 1e-12);
        let mut bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(cholesky_in_place(&mut bad).is_err());
    }
}
