//! Cholesky factorisation and triangular solves: the workspace's one implementation, with its
//! one pivot rule.
//!
//! # The pivot rule
//!
//! Factorising the symmetric `n × n` matrix `A = G Gᵀ` (lower `G`, lower triangle of `A` read),
//! pivot `j` is `s_j = A_jj − Σ_{k<j} G_jk² = G_jj²`. It is accepted when it is finite and
//!
//! ```text
//! s_j > max(0, rel_tol · n · A_jj),      rel_tol = PD_RELATIVE_TOLERANCE = 4 ε by default,
//! ```
//!
//! and every entry of the factor is finite: each pivot keeps more than the rounding error of its
//! own diagonal entry, i.e. `A` is positive definite to working precision (scale invariant under
//! `D A D`, see [`crate::spd`]). The functions without a suffix use [`PD_RELATIVE_TOLERANCE`];
//! the `*_with` variants take another `rel_tol` for a caller that needs one, and that caller says
//! why (`0` accepts every positive finite pivot). A failure reports the pivot ([`PivotFailure`]).
//!
//! # Storage
//!
//! Slice kernels read and write column-major storage (`G_ij` at `j·n + i`, as
//! `DMatrix::as_slice` gives it). A right-hand side `x` of the left solves is `n × k`
//! column-major (`k = x.len() / n`; a vector is `k = 1`). Only [`cholesky_checked`] allocates.

use nalgebra::DMatrix;

use crate::spd::{PD_RELATIVE_TOLERANCE, PivotFailure};

/// In-place lower Cholesky factor of the column-major `n × n` matrix in `a[..n·n]` at the
/// workspace's pivot rule (module documentation): the lower triangle is read and overwritten by
/// `G`, the strict upper triangle is untouched.
pub fn cholesky_slice(a: &mut [f64], n: usize) -> Result<(), PivotFailure> {
    cholesky_slice_with(a, n, PD_RELATIVE_TOLERANCE)
}

/// [`cholesky_slice`] with pivots accepted above `max(0, rel_tol · n · A_jj)`. On failure the
/// columns before the failing pivot hold the partial factor.
pub fn cholesky_slice_with(a: &mut [f64], n: usize, rel_tol: f64) -> Result<(), PivotFailure> {
    debug_assert!(a.len() >= n * n);
    let scale = rel_tol * n as f64;
    for j in 0..n {
        let diag = a[j * n + j];
        let threshold = scale * diag;
        let mut s = diag;
        for k in 0..j {
            s -= a[k * n + j] * a[k * n + j];
        }
        if !s.is_finite() || s <= threshold || s <= 0.0 {
            return Err(PivotFailure { pivot: j, value: s, threshold });
        }
        let d = s.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut v = a[j * n + i];
            for k in 0..j {
                v -= a[k * n + i] * a[k * n + j];
            }
            let v = v / d;
            if !v.is_finite() {
                return Err(PivotFailure { pivot: j, value: s, threshold });
            }
            a[j * n + i] = v;
        }
    }
    Ok(())
}

/// In-place lower Cholesky factor of a square matrix at the workspace's pivot rule (only the
/// lower triangle is read; on success the strict upper triangle is zeroed). A non-square `a`
/// fails at pivot 0.
pub fn cholesky_in_place(a: &mut DMatrix<f64>) -> Result<(), PivotFailure> {
    cholesky_in_place_with(a, PD_RELATIVE_TOLERANCE)
}

/// [`cholesky_in_place`] with pivots accepted above `max(0, rel_tol · n · A_jj)`.
pub fn cholesky_in_place_with(a: &mut DMatrix<f64>, rel_tol: f64) -> Result<(), PivotFailure> {
    let n = a.nrows();
    if a.ncols() != n {
        return Err(not_square(a, rel_tol));
    }
    let g = a.as_mut_slice();
    cholesky_slice_with(g, n, rel_tol)?;
    for j in 0..n {
        g[j * n..j * n + j].fill(0.0);
    }
    Ok(())
}

/// Lower Cholesky factor `G` with `a = G Gᵀ`, reading the lower triangle of the square `a`, with
/// pivots accepted above `max(0, rel_tol · n · a_jj)` (allocates the factor; pass
/// [`PD_RELATIVE_TOLERANCE`] for the workspace's rule). A non-square `a` fails at pivot 0.
pub fn cholesky_checked(a: &DMatrix<f64>, rel_tol: f64) -> Result<DMatrix<f64>, PivotFailure> {
    if !a.is_square() {
        return Err(not_square(a, rel_tol));
    }
    let mut g = a.clone();
    cholesky_in_place_with(&mut g, rel_tol)?;
    Ok(g)
}

fn not_square(a: &DMatrix<f64>, rel_tol: f64) -> PivotFailure {
    let max_diag = (0..a.nrows().min(a.ncols())).map(|i| a[(i, i)]).fold(0.0, f64::max);
    PivotFailure { pivot: 0, value: f64::NAN, threshold: rel_tol * a.nrows() as f64 * max_diag }
}

/// `x ← G⁻¹ x` (forward substitution) for the lower-triangular column-major `n × n` factor `g`,
/// each of the `x.len() / n` columns of `x` in turn.
pub fn solve_lower(g: &[f64], n: usize, x: &mut [f64]) {
    debug_assert!(g.len() >= n * n && (n == 0 || x.len() % n == 0));
    for col in x.chunks_exact_mut(n.max(1)) {
        for i in 0..n {
            let mut s = col[i];
            for k in 0..i {
                s -= g[k * n + i] * col[k];
            }
            col[i] = s / g[i * n + i];
        }
    }
}

/// `x ← G⁻ᵀ x` (back substitution with the transpose) for the lower-triangular column-major
/// `n × n` factor `g`, each column of `x` in turn.
pub fn solve_lower_t(g: &[f64], n: usize, x: &mut [f64]) {
    debug_assert!(g.len() >= n * n && (n == 0 || x.len() % n == 0));
    for col in x.chunks_exact_mut(n.max(1)) {
        for i in (0..n).rev() {
            let mut s = col[i];
            for k in i + 1..n {
                s -= g[i * n + k] * col[k];
            }
            col[i] = s / g[i * n + i];
        }
    }
}

/// `x ← (G Gᵀ)⁻¹ x` for the lower Cholesky factor `g` (column-major `n × n`), each column of `x`
/// in turn.
pub fn cholesky_solve(g: &[f64], n: usize, x: &mut [f64]) {
    solve_lower(g, n, x);
    solve_lower_t(g, n, x);
}

/// `out ← (G Gᵀ)⁻¹` (column-major `n × n`, symmetrised: `(X + Xᵀ)/2`) from the lower Cholesky
/// factor `g`, by solving against each unit vector.
pub fn cholesky_inverse(g: &[f64], n: usize, out: &mut [f64]) {
    debug_assert!(out.len() >= n * n);
    let out = &mut out[..n * n];
    out.fill(0.0);
    for c in 0..n {
        out[c * n + c] = 1.0;
    }
    cholesky_solve(g, n, out);
    for c in 0..n {
        for r in c + 1..n {
            let v = 0.5 * (out[c * n + r] + out[r * n + c]);
            out[c * n + r] = v;
            out[r * n + c] = v;
        }
    }
}

/// `out ← a⁻¹` for a symmetric positive definite `a` (lower triangle read) at the workspace's
/// pivot rule, factorising in `work` (same order; it holds the factor `G` afterwards). On failure
/// `out` is unchanged.
pub fn spd_inverse(a: &DMatrix<f64>, work: &mut DMatrix<f64>, out: &mut DMatrix<f64>) -> Result<(), PivotFailure> {
    debug_assert!(work.shape() == a.shape() && out.shape() == a.shape());
    work.copy_from(a);
    cholesky_in_place(work)?;
    cholesky_inverse(work.as_slice(), a.nrows(), out.as_mut_slice());
    Ok(())
}

/// `x ← x · G⁻ᵀ` for a lower-triangular `G` (solves `Y Gᵀ = X` column by column).
pub fn solve_right_lower_t(x: &mut DMatrix<f64>, g: &DMatrix<f64>) {
    let (r, m) = x.shape();
    debug_assert_eq!(g.shape(), (m, m));
    let g = g.as_slice();
    let x = x.as_mut_slice();
    for j in 0..m {
        for k in 0..j {
            let s = g[k * m + j];
            if s != 0.0 {
                let (done, rest) = x.split_at_mut(j * r);
                let yk = &done[k * r..(k + 1) * r];
                let xj = &mut rest[..r];
                for i in 0..r {
                    xj[i] -= s * yk[i];
                }
            }
        }
        let d = 1.0 / g[j * m + j];
        x[j * r..(j + 1) * r].iter_mut().for_each(|v| *v *= d);
    }
}

/// `x ← x · G⁻¹` for a lower-triangular `G` (solves `Y G = X`, last column first).
pub fn solve_right_lower(x: &mut DMatrix<f64>, g: &DMatrix<f64>) {
    let (r, m) = x.shape();
    debug_assert_eq!(g.shape(), (m, m));
    let g = g.as_slice();
    let x = x.as_mut_slice();
    for j in (0..m).rev() {
        for k in j + 1..m {
            let s = g[j * m + k];
            if s != 0.0 {
                let (head, tail) = x.split_at_mut(k * r);
                let yk = &tail[..r];
                let xj = &mut head[j * r..(j + 1) * r];
                for i in 0..r {
                    xj[i] -= s * yk[i];
                }
            }
        }
        let d = 1.0 / g[j * m + j];
        x[j * r..(j + 1) * r].iter_mut().for_each(|v| *v *= d);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;

    use crate::test_data::{centred_matrix as rand, spd_matrix};

    /// A random symmetric positive definite matrix with badly scaled coordinates.
    fn spd(n: usize, seed: u64) -> DMatrix<f64> {
        let d = DMatrix::from_diagonal(&DVector::from_fn(n, |i, _| 10f64.powi(i as i32 % 4 - 2)));
        &d * spd_matrix(n, seed, 0.1) * &d
    }

    fn close(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64) -> bool {
        (a - b).amax() <= tol * b.amax().max(1.0)
    }

    /// Pivot 1 is `≈ 10⁻¹⁵`: positive, but below `4 ε n ≈ 1.8·10⁻¹⁵` times its diagonal entry.
    fn barely_singular() -> DMatrix<f64> {
        DMatrix::from_row_slice(2, 2, &[1.0, 1.0 - 1e-15, 1.0 - 1e-15, 1.0 - 1e-15])
    }

    #[test]
    fn factors_match_nalgebra_and_reconstruct_the_matrix() {
        for n in 1..9 {
            let a = spd(n, n as u64);
            let reference = a.clone().cholesky().unwrap().l();
            // In place on a matrix: the factor, strict upper triangle zeroed.
            let mut g = a.clone();
            cholesky_in_place(&mut g).unwrap();
            assert!(close(&g, &reference, 1e-12), "n = {n}");
            assert!(close(&(&g * g.transpose()), &a, 1e-13), "n = {n}");
            assert!((0..n).all(|j| (0..j).all(|i| g[(i, j)] == 0.0)));
            // On a slice: the same numbers, the strict upper triangle untouched.
            let mut s = a.clone();
            if n > 1 {
                s[(0, n - 1)] = 7.0;
            }
            cholesky_slice(s.as_mut_slice(), n).unwrap();
            assert_eq!(s.lower_triangle(), g);
            if n > 1 {
                assert_eq!(s[(0, n - 1)], 7.0);
            }
            // Allocating: the same numbers again; only the lower triangle is read.
            let mut upper_garbage = a.clone();
            if n > 1 {
                upper_garbage[(0, 1)] = f64::NAN;
            }
            assert_eq!(cholesky_checked(&upper_garbage, PD_RELATIVE_TOLERANCE).unwrap(), g);
        }
        let mut empty = DMatrix::<f64>::zeros(0, 0);
        assert!(cholesky_in_place(&mut empty).is_ok());
    }

    #[test]
    fn the_pivot_rule_is_relative_to_the_own_diagonal_and_can_be_relaxed() {
        // Below 4 ε n times its diagonal entry: rejected by default, with the numbers.
        let a = barely_singular();
        let f = cholesky_checked(&a, PD_RELATIVE_TOLERANCE).unwrap_err();
        assert_eq!(f.pivot, 1);
        assert!(f.value > 0.0 && f.value <= f.threshold);
        assert_eq!(f.threshold, PD_RELATIVE_TOLERANCE * 2.0 * a[(1, 1)]);
        let mut s = a.clone();
        assert_eq!(cholesky_slice(s.as_mut_slice(), 2).unwrap_err(), f);
        assert_eq!(cholesky_in_place(&mut a.clone()).unwrap_err(), f);
        // Accepted when the caller asks only for positive pivots, and nalgebra agrees.
        let g = cholesky_checked(&a, 0.0).unwrap();
        assert!(close(&g, &a.clone().cholesky().unwrap().l(), 1e-12));
        let mut s = a.clone();
        assert!(cholesky_slice_with(s.as_mut_slice(), 2, 0.0).is_ok());
        assert!(cholesky_in_place_with(&mut a.clone(), 0.0).is_ok());
        // A stricter caller rejects a matrix the default accepts.
        let b = DMatrix::from_row_slice(2, 2, &[1.0, 0.999_999, 0.999_999, 1.0]);
        assert!(cholesky_checked(&b, PD_RELATIVE_TOLERANCE).is_ok());
        assert_eq!(cholesky_checked(&b, 1e-3).unwrap_err().pivot, 1);
        // Scale invariant: D A D with D = diag(1e-8, 1e8) is accepted like A.
        let d = DMatrix::from_diagonal(&DVector::from_vec(vec![1e-8, 1e8]));
        assert!(cholesky_checked(&(&d * &b * &d), PD_RELATIVE_TOLERANCE).is_ok());
        // Indefinite, NaN, infinite, overflowing, non-square.
        let c = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert_eq!(cholesky_in_place(&mut c.clone()).unwrap_err().pivot, 1);
        for bad in [f64::NAN, f64::INFINITY] {
            let mut m = DMatrix::<f64>::identity(3, 3);
            m[(2, 2)] = bad;
            assert_eq!(cholesky_in_place(&mut m).unwrap_err().pivot, 2);
        }
        let mut m = DMatrix::from_row_slice(2, 2, &[1e-300, 1e300, 1e300, 1.0]);
        assert_eq!(cholesky_in_place(&mut m).unwrap_err().pivot, 0);
        assert!(cholesky_in_place(&mut DMatrix::zeros(2, 3)).is_err());
        assert_eq!(cholesky_checked(&DMatrix::zeros(3, 2), PD_RELATIVE_TOLERANCE).unwrap_err().pivot, 0);
    }

    #[test]
    fn triangular_solves_match_nalgebra() {
        for n in 1..8 {
            let a = spd(n, 10 + n as u64);
            let chol = a.clone().cholesky().unwrap();
            let l = chol.l();
            for k in [1, 3] {
                let b = rand(n, k, 20 + n as u64);
                let mut x = b.clone();
                solve_lower(l.as_slice(), n, x.as_mut_slice());
                assert!(close(&x, &l.solve_lower_triangular(&b).unwrap(), 1e-10), "n = {n}");
                let mut x = b.clone();
                solve_lower_t(l.as_slice(), n, x.as_mut_slice());
                assert!(close(&x, &l.transpose().solve_upper_triangular(&b).unwrap(), 1e-10), "n = {n}");
                let mut x = b.clone();
                cholesky_solve(l.as_slice(), n, x.as_mut_slice());
                assert!(close(&x, &chol.solve(&b), 1e-10), "n = {n}");
                assert!(close(&(&a * &x), &b, 1e-10), "n = {n}");
            }
            // A vector is a one-column right-hand side.
            let v = DVector::from_fn(n, |i, _| i as f64 - 1.5);
            let mut x = v.clone();
            cholesky_solve(l.as_slice(), n, x.as_mut_slice());
            assert!((&x - chol.solve(&v)).amax() <= 1e-10 * x.amax().max(1.0));
            // Right solves.
            let b = rand(4, n, 30 + n as u64);
            let mut y = b.clone();
            solve_right_lower_t(&mut y, &l);
            assert!(close(&(&y * l.transpose()), &b, 1e-12));
            let mut y = b.clone();
            solve_right_lower(&mut y, &l);
            assert!(close(&(&y * &l), &b, 1e-12));
        }
        // Empty systems are no-ops.
        solve_lower(&[], 0, &mut []);
        cholesky_solve(&[], 0, &mut []);
    }

    #[test]
    fn inverses_match_nalgebra_and_are_symmetric() {
        for n in 1..8 {
            let a = spd(n, 40 + n as u64);
            let reference = a.clone().cholesky().unwrap().inverse();
            let mut g = a.clone();
            cholesky_in_place(&mut g).unwrap();
            let mut inv = DMatrix::from_element(n, n, f64::NAN);
            cholesky_inverse(g.as_slice(), n, inv.as_mut_slice());
            assert!(close(&inv, &reference, 1e-10), "n = {n}");
            assert_eq!(inv, inv.transpose());
            assert!(close(&(&a * &inv), &DMatrix::identity(n, n), 1e-10));
            let (mut work, mut out) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
            spd_inverse(&a, &mut work, &mut out).unwrap();
            assert_eq!(out, inv);
            assert_eq!(work, g);
        }
        // Failure leaves `out` unchanged and names the pivot.
        let (mut work, mut out) = (DMatrix::zeros(2, 2), DMatrix::from_element(2, 2, 3.0));
        assert_eq!(spd_inverse(&barely_singular(), &mut work, &mut out).unwrap_err().pivot, 1);
        assert_eq!(out, DMatrix::from_element(2, 2, 3.0));
    }
}
