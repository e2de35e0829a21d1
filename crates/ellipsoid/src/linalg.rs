//! Small dense kernels (Cholesky, triangular solves) and input validation.
//!
//! The kernels are written out so that failures carry the failing pivot and so that no
//! library call can panic on the (already validated) inputs.

use nalgebra::{DMatrix, DVector};

use crate::error::{EllipsoidError, Result};
use crate::{PD_RELATIVE_TOLERANCE, SYMMETRY_TOLERANCE};

pub(crate) use dense_kernels::PivotFailure;

/// Lower Cholesky factor `L` with `a = L Lᵀ` at relative pivot tolerance `rel_tol`
/// ([`dense_kernels::cholesky_checked`]).
pub(crate) fn cholesky_with(a: &DMatrix<f64>, rel_tol: f64) -> std::result::Result<DMatrix<f64>, PivotFailure> {
    dense_kernels::cholesky_checked(a, rel_tol)
}

/// [`cholesky_with`] at the crate's positive-definiteness tolerance.
pub(crate) fn cholesky(a: &DMatrix<f64>) -> std::result::Result<DMatrix<f64>, PivotFailure> {
    cholesky_with(a, PD_RELATIVE_TOLERANCE)
}

/// Solves `L x = b` for lower-triangular `L` with non-zero diagonal.
pub(crate) fn forward_sub(l: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let n = l.nrows();
    let mut x = b.clone();
    for i in 0..n {
        let mut s = x[i];
        for k in 0..i {
            s -= l[(i, k)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
    x
}

/// Solves `L X = B` column by column.
pub(crate) fn forward_sub_mat(l: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    let n = l.nrows();
    let mut x = b.clone();
    for c in 0..b.ncols() {
        for i in 0..n {
            let mut s = x[(i, c)];
            for k in 0..i {
                s -= l[(i, k)] * x[(k, c)];
            }
            x[(i, c)] = s / l[(i, i)];
        }
    }
    x
}

/// Solves `Lᵀ x = b` for lower-triangular `L` with non-zero diagonal.
pub(crate) fn back_sub_transpose(l: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let n = l.nrows();
    let mut x = b.clone();
    for i in (0..n).rev() {
        let mut s = x[i];
        for k in (i + 1)..n {
            s -= l[(k, i)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
    x
}

/// `(a + aᵀ) / 2`.
pub(crate) fn symmetrize(a: &DMatrix<f64>) -> DMatrix<f64> {
    (a + a.transpose()) * 0.5
}

/// Rejects NaN and infinities in a vector.
pub(crate) fn check_vector_finite(v: &DVector<f64>, what: &'static str) -> Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(EllipsoidError::NonFiniteVectorEntry { what, index, value: v[index] }),
        None => Ok(()),
    }
}

/// Rejects NaN and infinities in a matrix (first offender in row-major order).
pub(crate) fn check_matrix_finite(m: &DMatrix<f64>, what: &'static str) -> Result<()> {
    for row in 0..m.nrows() {
        for col in 0..m.ncols() {
            let value = m[(row, col)];
            if !value.is_finite() {
                return Err(EllipsoidError::NonFiniteMatrixEntry { what, row, col, value });
            }
        }
    }
    Ok(())
}

/// Requires a square matrix.
pub(crate) fn check_square(m: &DMatrix<f64>, what: &'static str) -> Result<()> {
    if m.nrows() == m.ncols() {
        Ok(())
    } else {
        Err(EllipsoidError::NotSquare { what, rows: m.nrows(), cols: m.ncols() })
    }
}

/// Requires `|m_ij − m_ji| ≤ SYMMETRY_TOLERANCE · max_kl |m_kl|`; reports the worst pair.
pub(crate) fn check_symmetric(m: &DMatrix<f64>, what: &'static str) -> Result<()> {
    match dense_kernels::max_asymmetry(m, SYMMETRY_TOLERANCE) {
        Some((row, col, difference, tolerance)) => Err(EllipsoidError::NotSymmetric {
            what,
            row,
            col,
            upper: m[(row, col)],
            lower: m[(col, row)],
            difference,
            tolerance,
        }),
        None => Ok(()),
    }
}

/// Validates a user-supplied symmetric positive definite matrix of size `n`; returns the
/// symmetrised matrix and its lower Cholesky factor.
pub(crate) fn validate_spd(m: &DMatrix<f64>, n: usize, what: &'static str) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    check_square(m, what)?;
    if m.nrows() != n {
        return Err(EllipsoidError::DimensionMismatch { what, expected: n, found: m.nrows() });
    }
    check_matrix_finite(m, what)?;
    check_symmetric(m, what)?;
    let sym = symmetrize(m);
    let l = cholesky(&sym).map_err(|f| EllipsoidError::NotPositiveDefinite {
        what,
        pivot: f.pivot,
        value: f.value,
        threshold: f.threshold,
    })?;
    Ok((sym, l))
}

/// Requires a vector of length `n`.
pub(crate) fn check_len(v: &DVector<f64>, n: usize, what: &'static str) -> Result<()> {
    if v.len() == n { Ok(()) } else { Err(EllipsoidError::DimensionMismatch { what, expected: n, found: v.len() }) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_and_solves_round_trip() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0]);
        let l = cholesky(&a).expect("SPD");
        assert!((&l * l.transpose() - &a).amax() < 1e-14);
        let b = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let y = forward_sub(&l, &b);
        assert!((&l * &y - &b).amax() < 1e-14);
        let x = back_sub_transpose(&l, &b);
        assert!((l.transpose() * &x - &b).amax() < 1e-14);
        let bm = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 2.0, 1.0, -1.0, 3.0]);
        let xm = forward_sub_mat(&l, &bm);
        assert!((&l * xm - bm).amax() < 1e-14);
    }

    #[test]
    fn cholesky_reports_failing_pivot() {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let f = cholesky(&a).expect_err("indefinite");
        assert_eq!(f.pivot, 1);
        assert!((f.value + 3.0).abs() < 1e-15);
    }
}
