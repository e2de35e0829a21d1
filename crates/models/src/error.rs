//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in this crate. Every variant names the offending matrix,
/// vector, parameter or step, so that the message alone locates the problem.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum ModelError {
    /// A matrix or vector does not have the expected dimensions.
    #[error("{what}: expected {expected_rows}x{expected_cols}, got {rows}x{cols}")]
    DimensionMismatch {
        /// Which matrix or vector.
        what: String,
        /// Expected number of rows.
        expected_rows: usize,
        /// Expected number of columns.
        expected_cols: usize,
        /// Actual number of rows.
        rows: usize,
        /// Actual number of columns.
        cols: usize,
    },
    /// A matrix or vector has a NaN or infinite entry.
    #[error("{what} has a non-finite entry at ({row}, {col})")]
    NonFiniteEntry {
        /// Which matrix or vector.
        what: String,
        /// Row of the first offending entry.
        row: usize,
        /// Column of the first offending entry.
        col: usize,
    },
    /// A declaration of angle states or outputs names an index outside the model or repeats one.
    #[error("angle {what}: index {index} is {reason}")]
    InvalidAngles {
        /// `"states"` or `"outputs"`.
        what: &'static str,
        /// The offending index.
        index: usize,
        /// Why it is refused.
        reason: &'static str,
    },
    /// RK4 with no sub-step, or with more than [`crate::continuous::MAX_RK4_SUBSTEPS`].
    #[error("RK4 sub-steps per sampling period must be in 1..={max}, got {substeps}")]
    InvalidSubsteps {
        /// The rejected count.
        substeps: usize,
        /// The largest accepted.
        max: usize,
    },
    /// The sampling period (or integration step) is not positive and finite.
    #[error("sampling period T_s must be positive and finite, got {0}")]
    InvalidSamplingPeriod(f64),
    /// A half-width of a box noise is negative or not finite.
    #[error("box noise half-width {index} must be finite and non-negative, got {value}")]
    InvalidHalfWidth {
        /// Component index.
        index: usize,
        /// The rejected value.
        value: f64,
    },
    /// A noise shape or covariance matrix is not symmetric.
    #[error("{what} is not symmetric: max |Q - Q^T| = {asymmetry} exceeds {tolerance}")]
    NotSymmetric {
        /// Which matrix.
        what: &'static str,
        /// `max |Q_ij − Q_ji|`.
        asymmetry: f64,
        /// The tolerance it exceeded (`1e-10 · max |Q_ij|`).
        tolerance: f64,
    },
    /// A noise shape or covariance matrix is not positive definite.
    #[error("{what} is not positive definite (Cholesky pivot {pivot} is {value:e})")]
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
        /// Index of the failing pivot.
        pivot: usize,
        /// Its value.
        value: f64,
    },
    /// The matrix exponential overflowed (`‖A T_s‖` far too large for `f64`).
    #[error("matrix exponential overflowed: e^M has non-finite entries (1-norm of M = {norm})")]
    ExponentialOverflow {
        /// 1-norm of the exponentiated matrix.
        norm: f64,
    },
    /// The Padé denominator of the matrix exponential could not be inverted. This does not
    /// happen for finite matrices scaled as the algorithm scales them; it is reported rather
    /// than panicking.
    #[error("matrix exponential: the Pade denominator q(M) is singular")]
    SingularPadeDenominator,
    /// The simulated state left the range of `f64` (unstable model over a long run).
    #[error("simulation diverged: state x_{step} has a non-finite entry")]
    Diverged {
        /// Time index of the first non-finite state.
        step: usize,
    },
    /// A model could not be evaluated at the given state and input (for example a speed of
    /// zero where the model divides by it), or a vehicle model's parameters are invalid. The
    /// message comes from the vehicle crate and names the quantity.
    #[error("{0}")]
    Evaluation(String),
}

impl ModelError {
    /// Whether the error is a numerical failure (an exponential that overflowed, a simulation
    /// that diverged) rather than input the model refuses.
    #[must_use]
    pub fn is_numerical(&self) -> bool {
        matches!(self, Self::ExponentialOverflow { .. } | Self::SingularPadeDenominator | Self::Diverged { .. })
    }
}

/// Checks that every entry of a matrix is finite, naming it in the error.
pub fn check_finite<R, C, S>(what: &str, m: &nalgebra::Matrix<f64, R, C, S>) -> Result<(), ModelError>
where
    R: nalgebra::Dim,
    C: nalgebra::Dim,
    S: nalgebra::RawStorage<f64, R, C>,
{
    for col in 0..m.ncols() {
        for row in 0..m.nrows() {
            if !m[(row, col)].is_finite() {
                return Err(ModelError::NonFiniteEntry { what: what.to_owned(), row, col });
            }
        }
    }
    Ok(())
}

/// Checks the dimensions of a matrix, naming it in the error.
pub fn check_dims<R, C, S>(
    what: &str,
    m: &nalgebra::Matrix<f64, R, C, S>,
    expected_rows: usize,
    expected_cols: usize,
) -> Result<(), ModelError>
where
    R: nalgebra::Dim,
    C: nalgebra::Dim,
    S: nalgebra::RawStorage<f64, R, C>,
{
    if m.nrows() != expected_rows || m.ncols() != expected_cols {
        return Err(ModelError::DimensionMismatch {
            what: what.to_owned(),
            expected_rows,
            expected_cols,
            rows: m.nrows(),
            cols: m.ncols(),
        });
    }
    Ok(())
}

/// Validates a symmetric positive definite `n × n` matrix (symmetry within
/// `dense_kernels::SYMMETRY_TOLERANCE`, Cholesky pivots above `dense_kernels::PD_RELATIVE_TOLERANCE`);
/// returns the symmetrised matrix and its lower Cholesky factor.
pub fn check_spd(
    what: &'static str,
    m: &nalgebra::DMatrix<f64>,
    n: usize,
) -> Result<(nalgebra::DMatrix<f64>, nalgebra::DMatrix<f64>), ModelError> {
    check_dims(what, m, n, n)?;
    check_finite(what, m)?;
    if let Some((_, _, asymmetry, tolerance)) = dense_kernels::max_asymmetry(m, dense_kernels::SYMMETRY_TOLERANCE) {
        return Err(ModelError::NotSymmetric { what, asymmetry, tolerance });
    }
    let sym = (m + m.transpose()) * 0.5;
    let l = dense_kernels::cholesky_checked(&sym, dense_kernels::PD_RELATIVE_TOLERANCE)
        .map_err(|f| ModelError::NotPositiveDefinite { what, pivot: f.pivot, value: f.value })?;
    Ok((sym, l))
}
