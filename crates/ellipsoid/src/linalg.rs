//! Input validation, and allocating conveniences over the kernels of `dense-kernels` (the
//! Cholesky factorisation with its pivot rule, triangular solves, symmetrisation), whose failures
//! carry the failing pivot and which cannot panic on the (already validated) inputs.

use nalgebra::{DMatrix, DVector};

use crate::error::{EllipsoidError, Result};
use crate::{PD_RELATIVE_TOLERANCE, SYMMETRY_TOLERANCE};

/// Solves `L x = b` for the lower-triangular `L` (non-zero diagonal).
pub(crate) fn forward_sub(l: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let mut x = b.clone();
    dense_kernels::solve_lower(l.as_slice(), l.nrows(), x.as_mut_slice());
    x
}

/// Solves `L X = B` column by column.
pub(crate) fn forward_sub_mat(l: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    let mut x = b.clone();
    dense_kernels::solve_lower(l.as_slice(), l.nrows(), x.as_mut_slice());
    x
}

/// Solves `Lᵀ x = b` for the lower-triangular `L` (non-zero diagonal).
pub(crate) fn back_sub_transpose(l: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let mut x = b.clone();
    dense_kernels::solve_lower_t(l.as_slice(), l.nrows(), x.as_mut_slice());
    x
}

/// `(a + aᵀ) / 2`.
pub(crate) fn symmetrize(a: &DMatrix<f64>) -> DMatrix<f64> {
    let mut s = a.clone();
    dense_kernels::symmetrize(&mut s);
    s
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
    let l = dense_kernels::cholesky_checked(&sym, PD_RELATIVE_TOLERANCE).map_err(|f| {
        EllipsoidError::NotPositiveDefinite { what, pivot: f.pivot, value: f.value, threshold: f.threshold }
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
        let l = dense_kernels::cholesky_checked(&a, PD_RELATIVE_TOLERANCE).expect("SPD");
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
    fn validation_reports_failing_pivot() {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        match validate_spd(&a, 2, "A") {
            Err(EllipsoidError::NotPositiveDefinite { pivot, value, .. }) => {
                assert_eq!(pivot, 1);
                assert!((value + 3.0).abs() < 1e-15);
            }
            other => panic!("{other:?}"),
        }
    }
}
