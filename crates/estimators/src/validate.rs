//! The validation shared by all filters (allocation-free on the hot path).

use nalgebra::{DMatrix, DVector};

use models::{Dims, LinearModel};

use crate::error::EstimatorError;
use crate::traits::Setup;

/// Relative symmetry tolerance for `Q`, `R`, `P`: `|M_ij − M_ji| ≤ 1e-10 · max |M_kl|` (the
/// workspace's, from `dense-kernels`).
pub const SYMMETRY_TOLERANCE: f64 = dense_kernels::SYMMETRY_TOLERANCE;

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
    if all_finite(v) {
        return Ok(());
    }
    let index = v.iter().position(|x| !x.is_finite()).unwrap_or(0);
    Err(EstimatorError::NonFinite { what, index })
}

/// Whether every entry is finite: one pass without an early exit, which the compiler vectorises
/// (the hot paths' check; [`check_finite`] looks for the index only on failure).
pub(crate) fn all_finite(v: &[f64]) -> bool {
    v.iter().fold(true, |ok, x| ok & x.is_finite())
}

/// The model's dimensions are the estimator's `(n, p, m)`.
pub(crate) fn check_dims(found: models::Dims, n: usize, p: usize, m: usize) -> Result<(), EstimatorError> {
    for (what, expected, found) in
        [("model states", n, found.states), ("model inputs", p, found.inputs), ("model outputs", m, found.outputs)]
    {
        if expected != found {
            return Err(EstimatorError::DimensionMismatch { what, expected, found });
        }
    }
    Ok(())
}

/// [`check_dims`] for a model, and its declaration of angles against its dimensions.
pub(crate) fn check_discrete<M: models::DiscreteModel + ?Sized>(
    model: &M,
    n: usize,
    p: usize,
    m: usize,
) -> Result<(), EstimatorError> {
    check_dims(model.dims(), n, p, m)?;
    Ok(model.angles().validate(Dims::new(n, p, m))?)
}

pub(crate) fn check_vec(what: &'static str, v: &DVector<f64>, len: usize) -> Result<(), EstimatorError> {
    if v.len() != len {
        return Err(EstimatorError::DimensionMismatch { what, expected: len, found: v.len() });
    }
    check_finite(what, v.as_slice())
}

/// Checks the step matrices against `(n, p, m)`; allocation-free.
pub(crate) fn check_model<M: LinearModel + ?Sized>(
    model: &M,
    n: usize,
    p: usize,
    m: usize,
) -> Result<(), EstimatorError> {
    check_shape(("rows of A", "columns of A"), model.a(), n, n)?;
    check_shape(("rows of B", "columns of B"), model.b(), n, p)?;
    check_shape(("rows of C", "columns of C"), model.c(), m, n)?;
    check_finite("A", model.a().as_slice())?;
    check_finite("B", model.b().as_slice())?;
    check_finite("C", model.c().as_slice())?;
    Ok(LinearModel::angles(model).validate(Dims::new(n, p, m))?)
}

/// Validates a square symmetric positive definite matrix of order `n` and returns its
/// symmetrised copy. Allocates (used at construction and in setters only).
pub(crate) fn check_spd(what: &'static str, m: &DMatrix<f64>, n: usize) -> Result<DMatrix<f64>, EstimatorError> {
    // Square: the order is the size that matters, so both dimensions are reported as `what`.
    check_shape((what, what), m, n, n)?;
    check_finite(what, m.as_slice())?;
    if dense_kernels::max_asymmetry(m, SYMMETRY_TOLERANCE).is_some() {
        return Err(EstimatorError::NotSymmetric { what });
    }
    let mut s = m.clone();
    dense_kernels::symmetrize(&mut s);
    // Positive definite to working precision: every pivot above 4 ε n times its own diagonal
    // entry (`dense_kernels::spd`).
    if n == 0 || dense_kernels::cholesky_checked(&s, dense_kernels::PD_RELATIVE_TOLERANCE).is_err() {
        return Err(EstimatorError::NotPositiveDefinite { what });
    }
    Ok(s)
}

/// As [`check_spd`] for a positive semidefinite matrix ([`check_psd_no_alloc`]). Allocates.
pub(crate) fn check_psd(what: &'static str, m: &DMatrix<f64>, n: usize) -> Result<DMatrix<f64>, EstimatorError> {
    check_psd_no_alloc(what, m, n, &mut DMatrix::zeros(n, n))?;
    let mut s = m.clone();
    dense_kernels::symmetrize(&mut s);
    Ok(s)
}

/// [`check_spd`] without allocating: the Cholesky factorisation runs in `work` (`n × n`,
/// overwritten). Used by the in-place noise setters.
pub(crate) fn check_spd_no_alloc(
    what: &'static str,
    m: &DMatrix<f64>,
    n: usize,
    work: &mut DMatrix<f64>,
) -> Result<(), EstimatorError> {
    let not_definite = EstimatorError::NotPositiveDefinite { what };
    symmetric_into(what, m, n, work, not_definite.clone())?;
    // Positive definite to working precision: the pivot rule of `dense_kernels`.
    dense_kernels::cholesky_in_place(work).map_err(|_| not_definite)
}

/// Validates a square symmetric positive *semi*definite matrix of order `n` (a covariance may be
/// singular: `Q = 0`, a rank-one white-noise `Q`), without allocating: `M + δI` must factorise in
/// `work` (`n × n`, overwritten), `δ = 64 n ε max(max_i |M_ii|, f64::MIN_POSITIVE)` — a negative
/// eigenvalue beyond rounding is refused.
pub(crate) fn check_psd_no_alloc(
    what: &'static str,
    m: &DMatrix<f64>,
    n: usize,
    work: &mut DMatrix<f64>,
) -> Result<(), EstimatorError> {
    let not_semidefinite = EstimatorError::NotPositiveSemidefinite { what };
    symmetric_into(what, m, n, work, not_semidefinite.clone())?;
    let scale = (0..n).map(|i| work[(i, i)].abs()).fold(f64::MIN_POSITIVE, f64::max);
    let delta = 64.0 * n as f64 * f64::EPSILON * scale;
    for i in 0..n {
        work[(i, i)] += delta;
    }
    dense_kernels::cholesky_in_place(work).map_err(|_| not_semidefinite)
}

/// `m` (`n × n`, finite, symmetric to [`SYMMETRY_TOLERANCE`]) symmetrised into `work`; `empty`
/// for an order 0 or a `work` of another size.
fn symmetric_into(
    what: &'static str,
    m: &DMatrix<f64>,
    n: usize,
    work: &mut DMatrix<f64>,
    empty: EstimatorError,
) -> Result<(), EstimatorError> {
    check_shape((what, what), m, n, n)?;
    check_finite(what, m.as_slice())?;
    if dense_kernels::max_asymmetry(m, SYMMETRY_TOLERANCE).is_some() {
        return Err(EstimatorError::NotSymmetric { what });
    }
    if n == 0 || work.shape() != (n, n) {
        return Err(empty);
    }
    work.copy_from(m);
    dense_kernels::symmetrize(work);
    Ok(())
}

/// As [`replace_spd`] for a positive semidefinite matrix ([`check_psd_no_alloc`]).
pub(crate) fn replace_psd(
    what: &'static str,
    dst: &mut DMatrix<f64>,
    src: &DMatrix<f64>,
    work: &mut DMatrix<f64>,
) -> Result<(), EstimatorError> {
    check_psd_no_alloc(what, src, dst.nrows(), work)?;
    dst.copy_from(src);
    dense_kernels::symmetrize(dst);
    Ok(())
}

/// Validates `src` as [`check_spd`] does and copies it, symmetrised, into `dst` (same order),
/// using `work` (`n × n`) for the factorisation: the in-place noise setters, allocation-free;
/// on error `dst` is unchanged.
pub(crate) fn replace_spd(
    what: &'static str,
    dst: &mut DMatrix<f64>,
    src: &DMatrix<f64>,
    work: &mut DMatrix<f64>,
) -> Result<(), EstimatorError> {
    check_spd_no_alloc(what, src, dst.nrows(), work)?;
    dst.copy_from(src);
    dense_kernels::symmetrize(dst);
    Ok(())
}

/// The validated [`Setup`] shared by the filters' constructors.
pub(crate) struct InitialData {
    /// States `n`.
    pub n: usize,
    /// Outputs `m`.
    pub m: usize,
    /// Inputs `p`.
    pub inputs: usize,
    /// `x₀`.
    pub x0: DVector<f64>,
    /// Symmetrised `P₀`, `Q`, `R`.
    pub p0: DMatrix<f64>,
    pub q: DMatrix<f64>,
    pub r: DMatrix<f64>,
}

/// Which of `P₀`, `Q` may be singular.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Covariances {
    /// Both definite (shapes of sets, weights that are inverted).
    Definite,
    /// `Q` positive semidefinite, `P₀` definite (the UKF takes its square root).
    DefinitePrior,
    /// `P₀` and `Q` positive semidefinite (the Kalman filter, the EKF).
    Semidefinite,
}

/// Checks `x₀` (finite, at least one state), `P₀`, `Q` (`n × n`) and `R` (`m × m`, at least one
/// output) symmetric positive definite; returns them symmetrised.
pub(crate) fn check_initial(setup: Setup) -> Result<InitialData, EstimatorError> {
    check_initial_as(setup, Covariances::Definite)
}

/// [`check_initial`] with `P₀`, `Q` positive semidefinite as `which` says (a Gaussian filter's
/// covariance may be singular); `R` always definite (the innovation covariance must be
/// invertible).
pub(crate) fn check_initial_as(setup: Setup, which: Covariances) -> Result<InitialData, EstimatorError> {
    let Setup { x0, p0, process_noise: q, measurement_noise: r, inputs } = setup;
    let n = x0.len();
    let m = r.nrows();
    if n == 0 {
        return Err(EstimatorError::EmptySystem("no states"));
    }
    if m == 0 {
        return Err(EstimatorError::EmptySystem("no outputs"));
    }
    check_finite("x0", x0.as_slice())?;
    let p0 = match which {
        Covariances::Semidefinite => check_psd("P0", &p0, n)?,
        Covariances::Definite | Covariances::DefinitePrior => check_spd("P0", &p0, n)?,
    };
    let q = match which {
        Covariances::Definite => check_spd("Q", &q, n)?,
        Covariances::Semidefinite | Covariances::DefinitePrior => check_psd("Q", &q, n)?,
    };
    let r = check_spd("R", &r, m)?;
    Ok(InitialData { n, m, inputs, x0, p0, q, r })
}
