//! Symmetry and positive-definiteness checks with the workspace's tolerances.
//!
//! * Symmetric: `|M_ij − M_ji| ≤` [`SYMMETRY_TOLERANCE`]` · max_kl |M_kl|` (scale invariant).
//! * Positive definite: every Cholesky pivot `s_j` (the square of the `j`-th diagonal entry of
//!   the factor) is finite and `s_j >` [`PD_RELATIVE_TOLERANCE`]` · n · M_jj`: each pivot keeps
//!   more than the rounding error of its own diagonal entry, i.e. the matrix is positive definite
//!   to working precision. The test is invariant under diagonal scaling `D M D`, so a matrix such
//!   as `diag(1e-12, 1e4)` is accepted (a floor relative to `max_i M_ii` would reject it). Every
//!   factorisation of [`crate::cholesky`] applies this rule.

use nalgebra::DMatrix;

/// Relative symmetry tolerance: `|M_ij − M_ji| ≤ SYMMETRY_TOLERANCE · max_kl |M_kl|`.
pub const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// Relative positive-definiteness tolerance: every Cholesky pivot `s_j` must exceed
/// `PD_RELATIVE_TOLERANCE · n · M_jj` (the default of every factorisation in
/// [`crate::cholesky`]).
pub const PD_RELATIVE_TOLERANCE: f64 = 4.0 * f64::EPSILON;

/// A rejected Cholesky pivot: its index, value and the threshold it had to exceed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PivotFailure {
    /// Index `j` of the pivot.
    pub pivot: usize,
    /// The pivot `s_j` (NaN or ∞ if the factorisation overflowed).
    pub value: f64,
    /// The threshold `rel_tol · n · M_jj` it had to exceed (the pivot had to be positive too).
    pub threshold: f64,
}

/// The worst asymmetry of a square matrix beyond `tol · max_kl |m_kl|`: `Some((row, col,
/// |m_row,col − m_col,row|, tolerance))` for the worst pair (`row < col`), `None` if symmetric
/// within the tolerance.
pub fn max_asymmetry(m: &DMatrix<f64>, tol: f64) -> Option<(usize, usize, f64, f64)> {
    let tolerance = tol * m.amax();
    let n = m.nrows().min(m.ncols());
    let mut worst: Option<(usize, usize, f64, f64)> = None;
    for row in 0..n {
        for col in (row + 1)..n {
            let difference = (m[(row, col)] - m[(col, row)]).abs();
            if difference > tolerance && worst.is_none_or(|(_, _, d, _)| difference > d) {
                worst = Some((row, col, difference, tolerance));
            }
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cholesky_checked;

    #[test]
    fn factor_reproduces_the_matrix_and_failures_name_the_pivot() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0]);
        let l = cholesky_checked(&a, PD_RELATIVE_TOLERANCE).unwrap();
        assert!((&l * l.transpose() - &a).amax() < 1e-14);
        assert_eq!(l[(0, 1)], 0.0);
        // Indefinite: fails at the second pivot (5 − 4·4/4 … here 1 − 4 < 0).
        let b = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let f = cholesky_checked(&b, PD_RELATIVE_TOLERANCE).unwrap_err();
        assert_eq!(f.pivot, 1);
        assert!((f.value + 3.0).abs() < 1e-15);
        // Numerically singular: pivot below 4 ε n times its own diagonal entry.
        let c = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0 + 1e-17]);
        assert_eq!(cholesky_checked(&c, PD_RELATIVE_TOLERANCE).unwrap_err().pivot, 1);
        // NaN and non-square.
        let d = DMatrix::from_element(1, 1, f64::NAN);
        assert!(cholesky_checked(&d, PD_RELATIVE_TOLERANCE).is_err());
        assert!(cholesky_checked(&DMatrix::zeros(2, 3), PD_RELATIVE_TOLERANCE).is_err());
        // Badly scaled but positive definite to working precision: accepted (scale invariant).
        let d = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1e-12, 1e4]));
        assert!(cholesky_checked(&d, PD_RELATIVE_TOLERANCE).is_ok());
        let mut g = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.5, 1.0]);
        let scale = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1e-8, 1e8]));
        g = &scale * g * &scale;
        assert!(cholesky_checked(&g, PD_RELATIVE_TOLERANCE).is_ok());
        // Empty: the empty factor.
        assert_eq!(cholesky_checked(&DMatrix::zeros(0, 0), PD_RELATIVE_TOLERANCE).unwrap().nrows(), 0);
    }

    #[test]
    fn asymmetry_is_relative_and_reports_the_worst_pair() {
        let mut m = DMatrix::from_row_slice(3, 3, &[1e6, 1.0, 2.0, 1.0, 1.0, 3.0, 2.0, 3.0, 1.0]);
        assert_eq!(max_asymmetry(&m, SYMMETRY_TOLERANCE), None);
        m[(0, 1)] += 1e-5; // 1e-11 relative to 1e6: within tolerance
        assert_eq!(max_asymmetry(&m, SYMMETRY_TOLERANCE), None);
        m[(1, 2)] += 1.0;
        m[(0, 2)] += 0.5;
        let (row, col, diff, tol) = max_asymmetry(&m, SYMMETRY_TOLERANCE).unwrap();
        assert_eq!((row, col), (1, 2));
        assert_eq!(diff, 1.0);
        assert!((tol - 1e-4).abs() < 1e-12);
    }
}
