//! Per-step model matrices and the validation shared by all filters.

use nalgebra::{DMatrix, DVector};

use crate::dense;
use crate::error::EstimatorError;

/// The matrices of one step of `x_{k+1} = A_k x_k + B_k u_k + w_k`, `y_{k+1} = C_{k+1} x_{k+1} +
/// v_{k+1}`: `a` is `n × n`, `b` is `n × p`, `c` is `m × n`. Borrowed, so a time-varying model
/// costs nothing per step.
#[derive(Debug, Clone, Copy)]
pub struct StepModel<'a> {
    /// `A_k`.
    pub a: &'a DMatrix<f64>,
    /// `B_k`.
    pub b: &'a DMatrix<f64>,
    /// `C_{k+1}`, the output matrix of the measurement taken after the step.
    pub c: &'a DMatrix<f64>,
}

impl<'a> StepModel<'a> {
    /// Bundles the three matrices.
    pub fn new(a: &'a DMatrix<f64>, b: &'a DMatrix<f64>, c: &'a DMatrix<f64>) -> Self {
        Self { a, b, c }
    }
}

/// Relative symmetry tolerance for `Q`, `R`, `P`: `|M_ij − M_ji| ≤ 1e-10 · max |M_kl|`.
pub const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// Checks that `m` is `rows × cols`; the error names the wrong dimension: `what.0` (for
/// example "rows of A") or `what.1` ("columns of A").
pub(crate) fn check_shape(
    what: (&'static str, &'static str),
    m: &DMatrix<f64>,
    rows: usize,
    cols: usize,
) -> Result<(), EstimatorError> {
    if m.nrows() != rows {
        return Err(EstimatorError::DimensionMismatch { what: what.0, expected: rows, found: m.nrows() });
    }
    if m.ncols() != cols {
        return Err(EstimatorError::DimensionMismatch { what: what.1, expected: cols, found: m.ncols() });
    }
    Ok(())
}

pub(crate) fn check_finite(what: &'static str, v: &[f64]) -> Result<(), EstimatorError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(EstimatorError::NonFinite { what, index }),
        None => Ok(()),
    }
}

pub(crate) fn check_vec(what: &'static str, v: &DVector<f64>, len: usize) -> Result<(), EstimatorError> {
    if v.len() != len {
        return Err(EstimatorError::DimensionMismatch { what, expected: len, found: v.len() });
    }
    check_finite(what, v.as_slice())
}

/// Checks the step matrices against `(n, p, m)`; allocation-free.
pub(crate) fn check_model(model: &StepModel<'_>, n: usize, p: usize, m: usize) -> Result<(), EstimatorError> {
    check_shape(("rows of A", "columns of A"), model.a, n, n)?;
    check_shape(("rows of B", "columns of B"), model.b, n, p)?;
    check_shape(("rows of C", "columns of C"), model.c, m, n)?;
    check_finite("A", model.a.as_slice())?;
    check_finite("B", model.b.as_slice())?;
    check_finite("C", model.c.as_slice())
}

/// Validates a square symmetric positive definite matrix of order `n` and returns its
/// symmetrised copy. Allocates (used at construction and in setters only).
pub(crate) fn check_spd(what: &'static str, m: &DMatrix<f64>, n: usize) -> Result<DMatrix<f64>, EstimatorError> {
    // Square: the order is the size that matters, so both dimensions are reported as `what`.
    check_shape((what, what), m, n, n)?;
    check_finite(what, m.as_slice())?;
    let scale = m.amax();
    for j in 0..n {
        for i in j + 1..n {
            if (m[(i, j)] - m[(j, i)]).abs() > SYMMETRY_TOLERANCE * scale {
                return Err(EstimatorError::NotSymmetric { what });
            }
        }
    }
    let mut s = m.clone();
    dense::symmetrize(&mut s);
    let mut g = s.clone();
    // Positive definite, and not numerically singular: every pivot above 4 ε n max diag.
    let max_diag = (0..n).map(|i| s[(i, i)]).fold(0.0, f64::max);
    if n == 0 || !dense::cholesky_in_place(&mut g) {
        return Err(EstimatorError::NotPositiveDefinite { what });
    }
    let floor = 4.0 * f64::EPSILON * n as f64 * max_diag;
    if (0..n).any(|i| g[(i, i)] * g[(i, i)] <= floor) {
        return Err(EstimatorError::NotPositiveDefinite { what });
    }
    Ok(s)
}

/// The validated initial data shared by the filters' constructors.
pub(crate) struct InitialData {
    /// States `n`.
    pub n: usize,
    /// Outputs `m`.
    pub m: usize,
    /// Symmetrised `P₀`, `Q`, `R`.
    pub p0: DMatrix<f64>,
    pub q: DMatrix<f64>,
    pub r: DMatrix<f64>,
}

/// Checks `x₀` (finite, at least one state), `P₀`, `Q` (`n × n`) and `R` (`m × m`, at least one
/// output) symmetric positive definite; returns them symmetrised.
pub(crate) fn check_initial(
    x0: &DVector<f64>,
    p0: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<InitialData, EstimatorError> {
    let n = x0.len();
    let m = r.nrows();
    if n == 0 {
        return Err(EstimatorError::EmptySystem("no states"));
    }
    if m == 0 {
        return Err(EstimatorError::EmptySystem("no outputs"));
    }
    check_finite("x0", x0.as_slice())?;
    Ok(InitialData { n, m, p0: check_spd("P0", p0, n)?, q: check_spd("Q", q, n)?, r: check_spd("R", r, m)? })
}
