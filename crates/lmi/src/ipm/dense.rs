//! Small dense kernels on column-major `n × n` slices, and thin wrappers over faer.
//!
//! Every routine works on caller-provided buffers (allocated once by the workspace) and lends
//! faer the workspace's [`MemStack`] where faer needs scratch: nothing here allocates.

use faer::dyn_stack::{MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::matmul::matmul;
use faer::linalg::qr::no_pivoting::factor::{qr_in_place, qr_in_place_scratch, recommended_block_size};
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Accum, MatMut, MatRef, Par};

/// Read-only faer view of a column-major `n × n` slice.
#[inline]
pub(crate) fn view(s: &[f64], n: usize) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(&s[..n * n], n, n)
}

/// Mutable faer view of a column-major `n × n` slice.
#[inline]
pub(crate) fn view_mut(s: &mut [f64], n: usize) -> MatMut<'_, f64> {
    MatMut::from_column_major_slice_mut(&mut s[..n * n], n, n)
}

/// `dst ← a · b` (any of the operands may be a transposed view).
#[inline]
pub(crate) fn mul(dst: &mut [f64], n: usize, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    matmul(view_mut(dst, n), Accum::Replace, a, b, 1.0, Par::Seq);
}

/// `out ← Tᵀ E T` (when `left_transposed`) or `out ← T E Tᵀ`, symmetrised; `tmp` is scratch.
#[inline(always)]
pub(crate) fn congruence(out: &mut [f64], tmp: &mut [f64], t: &[f64], e: &[f64], n: usize, left_transposed: bool) {
    let tv = view(t, n);
    if left_transposed {
        mul(tmp, n, view(e, n), tv);
        mul(out, n, tv.transpose(), view(tmp, n));
    } else {
        mul(tmp, n, view(e, n), tv.transpose());
        mul(out, n, tv, view(tmp, n));
    }
    symmetrize(out, n);
}

/// Replaces a square matrix by its symmetric part.
#[inline(always)]
pub(crate) fn symmetrize(a: &mut [f64], n: usize) {
    for j in 0..n {
        for i in 0..j {
            let v = 0.5 * (a[i + j * n] + a[j + i * n]);
            a[i + j * n] = v;
            a[j + i * n] = v;
        }
    }
}

/// Sets the strictly upper triangle to zero (faer's Cholesky leaves it untouched).
#[inline(always)]
pub(crate) fn zero_upper(a: &mut [f64], n: usize) {
    for j in 1..n {
        a[j * n..j * n + j].fill(0.0);
    }
}

/// `Σ aᵢⱼ bᵢⱼ` over all entries.
#[inline(always)]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `out ← L⁻¹` for a lower triangular `L` with a nonzero diagonal (column-major `n × n`;
/// the strict upper triangle of `out` is zero).
#[inline(always)]
pub(crate) fn invert_lower(l: &[f64], out: &mut [f64], n: usize) {
    out[..n * n].fill(0.0);
    for j in 0..n {
        let z = &mut out[j * n..j * n + n];
        z[j] = 1.0;
        for k in j..n {
            let col = &l[k * n..k * n + n];
            let zk = z[k] / col[k];
            z[k] = zk;
            for (zi, a) in z[k + 1..].iter_mut().zip(&col[k + 1..]) {
                *zi -= zk * a;
            }
        }
    }
}

/// Frobenius norm squared.
#[inline(always)]
pub(crate) fn norm2(a: &[f64]) -> f64 {
    a.iter().map(|x| x * x).sum()
}

/// Scratch needed by [`cholesky`] for order `n`.
pub(crate) fn cholesky_scratch(n: usize) -> StackReq {
    cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default())
}

/// In-place Cholesky `A = L Lᵀ` of the lower triangle of a column-major `n × n` slice; the
/// strict upper triangle is zeroed. Returns `false` if `A` is not numerically positive definite.
#[inline(always)]
pub(crate) fn cholesky(a: &mut [f64], n: usize, stack: &mut MemStack) -> bool {
    // Below this order a plain left-looking loop beats faer's blocked implementation.
    const SMALL: usize = 48;
    let ok = if n <= SMALL {
        super::eig::cholesky_lower_ok(a, n)
    } else {
        cholesky_in_place(view_mut(a, n), Default::default(), Par::Seq, stack, Default::default()).is_ok()
    };
    if ok {
        zero_upper(a, n);
        ok && a[..n * n].iter().step_by(n + 1).all(|d| d.is_finite() && *d > 0.0)
    } else {
        false
    }
}

/// Solves `L Lᵀ v = rhs` in place, `L` the lower Cholesky factor (column-major `n × n`).
///
/// Up to order 128 by two plain loops (a column update, then contiguous dot products: both
/// vectorise), which at the Schur orders of the filter LMI (30–100) cost a fraction of faer's
/// general triangular solves; faer's above.
#[inline(always)]
pub(crate) fn cholesky_solve(l: &[f64], n: usize, v: &mut [f64]) {
    if n <= 128 {
        // L z = v: column by column.
        for j in 0..n {
            let col = &l[j * n..j * n + n];
            let zj = v[j] / col[j];
            v[j] = zj;
            for (x, a) in v[j + 1..n].iter_mut().zip(&col[j + 1..]) {
                *x -= zj * a;
            }
        }
        // Lᵀ x = z: row j of Lᵀ is column j of L.
        for j in (0..n).rev() {
            let col = &l[j * n..j * n + n];
            let s: f64 = col[j + 1..].iter().zip(&v[j + 1..n]).map(|(a, x)| a * x).sum();
            v[j] = (v[j] - s) / col[j];
        }
        return;
    }
    let lv = view(l, n);
    solve_lower_triangular_in_place(lv, MatMut::from_column_major_slice_mut(&mut v[..n], n, 1), Par::Seq);
    solve_upper_triangular_in_place(lv.transpose(), MatMut::from_column_major_slice_mut(&mut v[..n], n, 1), Par::Seq);
}

/// Householder block size used for an `rows × cols` QR factorisation.
pub(crate) fn qr_block_size(rows: usize, cols: usize) -> usize {
    recommended_block_size::<f64>(rows, cols).max(1)
}

/// Scratch needed by [`qr`].
pub(crate) fn qr_scratch(rows: usize, cols: usize, bs: usize) -> StackReq {
    qr_in_place_scratch::<f64>(rows, cols, bs, Par::Seq, Default::default())
}

/// In-place Householder QR of the column-major `rows × cols` matrix `a` (`R` ends up in its
/// upper triangle); `qcoef` holds `bs × cols` Householder coefficients.
pub(crate) fn qr(a: &mut [f64], rows: usize, cols: usize, qcoef: &mut [f64], bs: usize, stack: &mut MemStack) {
    let av = MatMut::from_column_major_slice_mut(&mut a[..rows * cols], rows, cols);
    let qv = MatMut::from_column_major_slice_mut(&mut qcoef[..bs * cols], bs, cols);
    qr_in_place(av, qv, Par::Seq, stack, Default::default());
}
