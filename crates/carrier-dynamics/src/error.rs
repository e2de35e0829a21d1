//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in this crate. Every variant names the offending parameter,
/// matrix or step, so that the message alone locates the problem.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum DynamicsError {
    /// A scalar parameter is NaN or infinite.
    #[error("parameter {name} must be finite, got {value}")]
    NonFinite {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// A parameter that must be strictly positive is zero or negative.
    #[error("parameter {name} must be positive, got {value}")]
    NotPositive {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// A parameter that must be non-negative is negative.
    #[error("parameter {name} must be non-negative, got {value}")]
    Negative {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// The roll inertia about the CG, `I_x = I_xeq − m h²`, is not positive: no rigid body has
    /// such inertias (parallel-axis theorem). This is the literal reading of Table 1.
    #[error(
        "roll inertia about the CG I_x = I_xeq - m h^2 = {i_x} must be positive \
         (I_xeq = {i_xeq}, m h^2 = {m_h2}): non-physical parameters"
    )]
    NonPhysicalRollInertia {
        /// The given roll inertia about the roll axis `I_xeq`.
        i_xeq: f64,
        /// `m h²`.
        m_h2: f64,
        /// The resulting `I_x = I_xeq − m h²`.
        i_x: f64,
    },
    /// The load model covers 0, 1 or 2 containers only.
    #[error("unsupported load of {containers} containers: the load model covers 0, 1 or 2")]
    UnsupportedLoad {
        /// The requested number of containers.
        containers: usize,
    },
    /// The sampling period `T_s` is not positive and finite.
    #[error("sampling period T_s must be positive and finite, got {0}")]
    InvalidSamplingPeriod(f64),
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
    /// A half-width of a box noise is negative or not finite.
    #[error("box noise half-width {index} must be finite and non-negative, got {value}")]
    InvalidHalfWidth {
        /// Component index.
        index: usize,
        /// The rejected value.
        value: f64,
    },
    /// The ellipsoid shape matrix `Q` is not symmetric.
    #[error("ellipsoid shape matrix Q is not symmetric: max |Q - Q^T| = {asymmetry} exceeds {tolerance}")]
    NotSymmetric {
        /// `max |Q_ij − Q_ji|`.
        asymmetry: f64,
        /// The tolerance it exceeded (`1e-10 · max |Q_ij|`).
        tolerance: f64,
    },
    /// The ellipsoid shape matrix `Q` is not positive definite.
    #[error("ellipsoid shape matrix Q is not positive definite (Cholesky factorisation failed)")]
    NotPositiveDefinite,
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
}

/// Checks that every entry of a matrix is finite, naming it in the error.
pub(crate) fn check_finite<R, C, S>(what: &str, m: &nalgebra::Matrix<f64, R, C, S>) -> Result<(), DynamicsError>
where
    R: nalgebra::Dim,
    C: nalgebra::Dim,
    S: nalgebra::RawStorage<f64, R, C>,
{
    for col in 0..m.ncols() {
        for row in 0..m.nrows() {
            if !m[(row, col)].is_finite() {
                return Err(DynamicsError::NonFiniteEntry { what: what.to_owned(), row, col });
            }
        }
    }
    Ok(())
}

/// Checks the dimensions of a matrix, naming it in the error.
pub(crate) fn check_dims<R, C, S>(
    what: &str,
    m: &nalgebra::Matrix<f64, R, C, S>,
    expected_rows: usize,
    expected_cols: usize,
) -> Result<(), DynamicsError>
where
    R: nalgebra::Dim,
    C: nalgebra::Dim,
    S: nalgebra::RawStorage<f64, R, C>,
{
    if m.nrows() != expected_rows || m.ncols() != expected_cols {
        return Err(DynamicsError::DimensionMismatch {
            what: what.to_owned(),
            expected_rows,
            expected_cols,
            rows: m.nrows(),
            cols: m.ncols(),
        });
    }
    Ok(())
}
