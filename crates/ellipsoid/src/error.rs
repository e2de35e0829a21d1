//! The error type of the crate.

use thiserror::Error;

/// Everything that can go wrong when building or operating on ellipsoids.
///
/// Every message names the offending object (`what`, e.g. "shape matrix P") and, where it
/// applies, the entry or the dimensions involved.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum EllipsoidError {
    /// A vector or matrix that must have at least one entry is empty.
    #[error("{what} is empty: the dimension must be at least 1")]
    Empty {
        /// The object concerned.
        what: &'static str,
    },
    /// A matrix that must be square is not.
    #[error("{what} must be square, got {rows}×{cols}")]
    NotSquare {
        /// The object concerned.
        what: &'static str,
        /// Number of rows.
        rows: usize,
        /// Number of columns.
        cols: usize,
    },
    /// Two operands have incompatible dimensions.
    #[error("dimension mismatch: {what} has dimension {found}, expected {expected}")]
    DimensionMismatch {
        /// The object (and which of its dimensions) that does not fit.
        what: &'static str,
        /// The dimension required by the other operands.
        expected: usize,
        /// The dimension found.
        found: usize,
    },
    /// A vector holds NaN or an infinity.
    #[error("{what} has a non-finite entry {value} at index {index}")]
    NonFiniteVectorEntry {
        /// The object concerned.
        what: &'static str,
        /// Index of the first non-finite entry.
        index: usize,
        /// The entry.
        value: f64,
    },
    /// A matrix holds NaN or an infinity.
    #[error("{what} has a non-finite entry {value} at ({row}, {col})")]
    NonFiniteMatrixEntry {
        /// The object concerned.
        what: &'static str,
        /// Row of the first non-finite entry (row-major scan).
        row: usize,
        /// Column of that entry.
        col: usize,
        /// The entry.
        value: f64,
    },
    /// A matrix is not symmetric within [`crate::SYMMETRY_TOLERANCE`].
    #[error(
        "{what} is not symmetric: entries ({row}, {col}) = {upper} and ({col}, {row}) = {lower} \
         differ by {difference:e}, more than the tolerance {tolerance:e}"
    )]
    NotSymmetric {
        /// The object concerned.
        what: &'static str,
        /// Row of the worst pair (row < col).
        row: usize,
        /// Column of the worst pair.
        col: usize,
        /// Entry (row, col).
        upper: f64,
        /// Entry (col, row).
        lower: f64,
        /// |upper − lower|.
        difference: f64,
        /// The tolerance that was exceeded (absolute, scaled by the largest entry).
        tolerance: f64,
    },
    /// The Cholesky factorisation of a matrix that must be positive definite failed.
    #[error(
        "{what} is not positive definite: Cholesky pivot {pivot} is {value:e} \
         (must exceed the relative threshold {threshold:e})"
    )]
    NotPositiveDefinite {
        /// The object concerned.
        what: &'static str,
        /// Index of the failing pivot (0-based).
        pivot: usize,
        /// Value of the pivot (the would-be square of the diagonal of the factor).
        value: f64,
        /// The threshold it had to exceed.
        threshold: f64,
    },
    /// An affine map would produce a degenerate (flat) ellipsoid.
    #[error(
        "degenerate affine image: A P Aᵀ is not positive definite (Cholesky pivot {pivot} is \
         {value:e}); the map matrix A ({rows}×{cols}) must have full row rank, a flat image is \
         not representable as 𝓔(c, P) with P ≻ 0"
    )]
    DegenerateImage {
        /// Rows of A.
        rows: usize,
        /// Columns of A.
        cols: usize,
        /// Index of the failing pivot.
        pivot: usize,
        /// Value of the failing pivot.
        value: f64,
    },
    /// The parameterised set of an intersection bound is unbounded (or numerically so).
    #[error(
        "intersection bound for λ = {lambda} is unbounded: (1 − λ) I + λ Wᵀ W (W = R^(-1/2) C \
         P^(1/2)) has Cholesky pivot {pivot} = {value:e}; at λ = 1 the measurement matrix C \
         ({rows}×{cols}) must have full column rank, otherwise use λ < 1"
    )]
    UnboundedIntersection {
        /// The parameter used.
        lambda: f64,
        /// Rows of C.
        rows: usize,
        /// Columns of C.
        cols: usize,
        /// Index of the failing pivot.
        pivot: usize,
        /// Value of the failing pivot.
        value: f64,
    },
    /// The intersection bound collapses to at most one point (1 − δ = 0).
    #[error(
        "intersection bound for λ = {lambda} degenerates to at most a single point \
         (δ = {delta}, 1 − δ is not positive)"
    )]
    DegenerateIntersection {
        /// The parameter used.
        lambda: f64,
        /// Minimum of the combined quadratic form.
        delta: f64,
    },
    /// A computed shape matrix is not numerically positive definite (overflow, underflow or
    /// extreme ill-conditioning).
    #[error(
        "{operation}: the computed shape matrix is not numerically positive definite \
         (Cholesky pivot {pivot} is {value:e})"
    )]
    DegenerateResult {
        /// The operation that produced the matrix.
        operation: &'static str,
        /// Index of the failing pivot.
        pivot: usize,
        /// Value of the failing pivot.
        value: f64,
    },
    /// A scalar parameter is outside its admissible range.
    #[error("parameter {name} = {value} is invalid: expected {expected}")]
    InvalidParameter {
        /// Name of the parameter.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The admissible range, in words.
        expected: &'static str,
    },
    /// A coordinate index is out of range.
    #[error("coordinate index {index} is out of range for dimension {dim}")]
    IndexOutOfRange {
        /// The index given.
        index: usize,
        /// The dimension of the ellipsoid.
        dim: usize,
    },
    /// A coordinate index appears twice in a projection.
    #[error("coordinate index {index} appears more than once in the projection")]
    RepeatedIndex {
        /// The repeated index.
        index: usize,
    },
    /// The support point is undefined because `dᵀ P d` is zero (d = 0 or underflow).
    #[error("direction d gives dᵀ P d = 0 (d is zero or too small): the support point is undefined")]
    ZeroDirection,
    /// The symmetric eigendecomposition did not converge.
    #[error("symmetric eigendecomposition of {what} did not converge")]
    EigenDecomposition {
        /// The matrix concerned.
        what: &'static str,
    },
}

/// Result type of the crate.
pub type Result<T> = std::result::Result<T, EllipsoidError>;

#[cfg(test)]
mod tests {
    use crate::test_util::{m, v};
    use nalgebra::{DMatrix, DVector};

    use super::EllipsoidError;
    use crate::{Ellipsoid, MeasurementSet};

    fn unit_disc() -> Ellipsoid {
        Ellipsoid::ball(v(&[0.0, 0.0]), 1.0).expect("valid")
    }

    #[test]
    fn empty() {
        let e = Ellipsoid::new(DVector::zeros(0), DMatrix::zeros(0, 0)).expect_err("empty");
        assert_eq!(e.to_string(), "centre c is empty: the dimension must be at least 1");
        let e = unit_disc().project(&[]).expect_err("empty");
        assert_eq!(e.to_string(), "projection coordinate list is empty: the dimension must be at least 1");
    }

    #[test]
    fn not_square() {
        let e = Ellipsoid::new(v(&[0.0, 0.0]), DMatrix::zeros(2, 3)).expect_err("not square");
        assert_eq!(e.to_string(), "shape matrix P must be square, got 2×3");
    }

    #[test]
    fn dimension_mismatch() {
        let e = Ellipsoid::new(v(&[0.0, 0.0]), DMatrix::identity(3, 3)).expect_err("mismatch");
        assert_eq!(e.to_string(), "dimension mismatch: shape matrix P has dimension 3, expected 2");
        let e = unit_disc().normalized_distance(&v(&[1.0])).expect_err("mismatch");
        assert_eq!(e.to_string(), "dimension mismatch: point x has dimension 1, expected 2");
        let ball3 = Ellipsoid::ball(v(&[0.0, 0.0, 0.0]), 1.0).expect("valid");
        let e = unit_disc().contains_ellipsoid(&ball3).expect_err("mismatch");
        assert_eq!(e.to_string(), "dimension mismatch: inner ellipsoid has dimension 3, expected 2");
        let e = unit_disc().minkowski_sum_outer(&ball3, 1.0).expect_err("mismatch");
        assert_eq!(e.to_string(), "dimension mismatch: second Minkowski operand has dimension 3, expected 2");
        let e = unit_disc().affine_map(&DMatrix::identity(2, 3), &v(&[0.0, 0.0])).expect_err("mismatch");
        assert_eq!(e.to_string(), "dimension mismatch: map matrix A (columns) has dimension 3, expected 2");
        let meas = MeasurementSet::new(m(1, 3, &[1.0, 0.0, 0.0]), v(&[0.0]), m(1, 1, &[1.0])).expect("valid");
        let e = unit_disc().intersect_measurement(&meas, 0.5).expect_err("mismatch");
        assert_eq!(e.to_string(), "dimension mismatch: measurement matrix C (columns) has dimension 3, expected 2");
        let e = MeasurementSet::new(m(2, 2, &[1.0, 0.0, 0.0, 1.0]), v(&[0.0]), m(1, 1, &[1.0])).expect_err("mismatch");
        assert_eq!(e.to_string(), "dimension mismatch: measurement matrix C (rows) has dimension 2, expected 1");
    }

    #[test]
    fn non_finite_entries() {
        let e = Ellipsoid::new(v(&[0.0, f64::INFINITY]), DMatrix::identity(2, 2)).expect_err("non-finite");
        assert_eq!(e.to_string(), "centre c has a non-finite entry inf at index 1");
        let e = Ellipsoid::new(v(&[0.0, 0.0]), m(2, 2, &[1.0, 0.0, f64::NAN, 1.0])).expect_err("non-finite");
        assert_eq!(e.to_string(), "shape matrix P has a non-finite entry NaN at (1, 0)");
        let e = unit_disc().contains(&v(&[f64::NAN, 0.0])).expect_err("non-finite");
        assert_eq!(e.to_string(), "point x has a non-finite entry NaN at index 0");
    }

    #[test]
    fn not_symmetric() {
        let e = Ellipsoid::new(v(&[0.0, 0.0]), m(2, 2, &[1.0, 0.5, 0.25, 1.0])).expect_err("asymmetric");
        assert_eq!(
            e.to_string(),
            "shape matrix P is not symmetric: entries (0, 1) = 0.5 and (1, 0) = 0.25 differ by \
             2.5e-1, more than the tolerance 1e-10"
        );
        // Within the tolerance: accepted and symmetrised.
        let ok = Ellipsoid::new(v(&[0.0, 0.0]), m(2, 2, &[1.0, 0.5, 0.5 + 1e-12, 1.0])).expect("within tolerance");
        assert_eq!(ok.shape()[(0, 1)], ok.shape()[(1, 0)]);
    }

    #[test]
    fn not_positive_definite() {
        let e = Ellipsoid::new(v(&[0.0, 0.0]), m(2, 2, &[1.0, 2.0, 2.0, 1.0])).expect_err("indefinite");
        assert!(matches!(e, EllipsoidError::NotPositiveDefinite { pivot: 1, .. }));
        assert_eq!(
            e.to_string(),
            "shape matrix P is not positive definite: Cholesky pivot 1 is -3e0 (must exceed the \
             relative threshold 1.7763568394002505e-15)"
        );
        let e = MeasurementSet::new(m(1, 1, &[1.0]), v(&[0.0]), m(1, 1, &[0.0])).expect_err("singular");
        assert_eq!(
            e.to_string(),
            "noise matrix R is not positive definite: Cholesky pivot 0 is 0e0 (must exceed the \
             relative threshold 0e0)"
        );
    }

    #[test]
    fn degenerate_image() {
        // Rank one with rounding: the pivot is ~4e-16, below the relative threshold.
        let e = unit_disc().affine_map(&m(2, 2, &[1.0, 1.0, 1.0, 1.0]), &v(&[0.0, 0.0])).expect_err("rank 1");
        assert!(matches!(e, EllipsoidError::DegenerateImage { pivot: 1, .. }));
        let e = unit_disc().affine_map(&m(2, 2, &[1.0, 0.0, 0.0, 0.0]), &v(&[0.0, 0.0])).expect_err("zero row");
        assert_eq!(
            e.to_string(),
            "degenerate affine image: A P Aᵀ is not positive definite (Cholesky pivot 1 is 0e0); \
             the map matrix A (2×2) must have full row rank, a flat image is not representable \
             as 𝓔(c, P) with P ≻ 0"
        );
    }

    #[test]
    fn unbounded_intersection() {
        let meas = MeasurementSet::new(m(1, 2, &[0.0, 1.0]), v(&[0.0]), m(1, 1, &[1.0])).expect("valid");
        let e = unit_disc().intersect_measurement(&meas, 1.0).expect_err("unbounded");
        assert_eq!(
            e.to_string(),
            "intersection bound for λ = 1 is unbounded: (1 − λ) I + λ Wᵀ W (W = R^(-1/2) C \
             P^(1/2)) has Cholesky pivot 0 = 0e0; at λ = 1 the measurement matrix C (1×2) must \
             have full column rank, otherwise use λ < 1"
        );
    }

    #[test]
    fn degenerate_intersection() {
        // Tangent unit discs: at λ = ½, δ = 1 exactly and S_λ is the touching point.
        let a = Ellipsoid::ball(v(&[-1.0, 0.0]), 1.0).expect("valid");
        let b = Ellipsoid::ball(v(&[1.0, 0.0]), 1.0).expect("valid");
        let e = a.intersect_ellipsoid(&b, 0.5).expect_err("single point");
        assert_eq!(
            e.to_string(),
            "intersection bound for λ = 0.5 degenerates to at most a single point (δ = 1, 1 − δ \
             is not positive)"
        );
    }

    #[test]
    fn degenerate_result() {
        let big = Ellipsoid::ball(v(&[0.0, 0.0]), 1e10).expect("valid");
        let e = big.minkowski_sum_outer(&unit_disc(), 1e-300).expect_err("overflow");
        assert_eq!(
            e.to_string(),
            "Minkowski-sum bound: the computed shape matrix is not numerically positive definite \
             (Cholesky pivot 0 is inf)"
        );
    }

    #[test]
    fn invalid_parameters() {
        let d = unit_disc();
        let e = d.minkowski_sum_outer(&d, -1.0).expect_err("p < 0");
        assert_eq!(e.to_string(), "parameter p = -1 is invalid: expected a finite positive number");
        let e = d.intersect_ellipsoid(&d, 1.5).expect_err("λ > 1");
        assert_eq!(e.to_string(), "parameter λ = 1.5 is invalid: expected a number in [0, 1]");
        let e = d.intersect_ellipsoid(&d, f64::NAN).expect_err("λ NaN");
        assert_eq!(e.to_string(), "parameter λ = NaN is invalid: expected a number in [0, 1]");
        let e = Ellipsoid::ball(v(&[0.0]), 0.0).expect_err("radius 0");
        assert_eq!(e.to_string(), "parameter radius = 0 is invalid: expected a finite positive number");
        let e = d.scaled(f64::INFINITY).expect_err("inf scale");
        assert_eq!(e.to_string(), "parameter scale s = inf is invalid: expected a finite positive number");
        let e = Ellipsoid::axis_aligned(v(&[0.0, 0.0]), &[1.0, -2.0]).expect_err("negative");
        assert_eq!(e.to_string(), "parameter semi-axis = -2 is invalid: expected finite positive semi-axis lengths");
    }

    #[test]
    fn index_errors() {
        let d = unit_disc();
        let e = d.interval(2).expect_err("out of range");
        assert_eq!(e.to_string(), "coordinate index 2 is out of range for dimension 2");
        let e = d.projection_boundary(0, 3, 10).expect_err("out of range");
        assert_eq!(e.to_string(), "coordinate index 3 is out of range for dimension 2");
        let e = d.projection_boundary(1, 1, 10).expect_err("repeated");
        assert_eq!(e.to_string(), "coordinate index 1 appears more than once in the projection");
    }

    #[test]
    fn zero_direction() {
        let d = unit_disc();
        let e = d.support_point(&v(&[0.0, 0.0])).expect_err("zero");
        assert_eq!(
            e.to_string(),
            "direction d gives dᵀ P d = 0 (d is zero or too small): the support point is undefined"
        );
        // The support function itself is defined: h(0) = 0.
        assert_eq!(d.support(&v(&[0.0, 0.0])).expect("ok"), 0.0);
    }

    #[test]
    fn eigen_decomposition_message() {
        // Not reachable with finite validated input in practice; check the message only.
        let e = EllipsoidError::EigenDecomposition { what: "Mᵀ M" };
        assert_eq!(e.to_string(), "symmetric eigendecomposition of Mᵀ M did not converge");
    }
}
