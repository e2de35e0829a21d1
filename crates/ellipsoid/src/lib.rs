//! Ellipsoidal set algebra for set-membership (guaranteed) state estimation.
//!
//! An ellipsoid is `𝓔(c, P) = {x ∈ ℝⁿ : (x − c)ᵀ P⁻¹ (x − c) ≤ 1}` with centre `c` and a
//! symmetric positive definite shape matrix `P` (its semi-axes are the square roots of the
//! eigenvalues of `P`). Dimensions are dynamic ([`nalgebra::DVector`], [`nalgebra::DMatrix`]).
//!
//! Provided operations, all returning [`Result`] (library code does not panic on input):
//!
//! * validated construction ([`Ellipsoid::new`], [`Ellipsoid::ball`],
//!   [`Ellipsoid::axis_aligned`]);
//! * point queries through the Cholesky factor ([`Ellipsoid::normalized_distance`],
//!   [`Ellipsoid::contains`]);
//! * affine images ([`Ellipsoid::affine_map`]);
//! * outer bounds of Minkowski sums ([`Ellipsoid::minkowski_sum_outer`],
//!   [`Ellipsoid::minkowski_sum_min_trace`], see [`minkowski`]);
//! * outer bounds of intersections with measurement sets
//!   `{x : (y − C x)ᵀ R⁻¹ (y − C x) ≤ 1}` ([`Ellipsoid::intersect_measurement`],
//!   [`Ellipsoid::intersect_measurement_min_trace`], see [`intersection`]);
//! * exact ellipsoid-in-ellipsoid containment ([`Ellipsoid::contains_ellipsoid`],
//!   [`Ellipsoid::max_normalized_distance`], see [`containment`]);
//! * bounds and measures: per-coordinate intervals, support function and point, trace,
//!   log-volume, projections and boundary points of 2-D projections for plots.
//!
//! # Tolerances
//!
//! * [`SYMMETRY_TOLERANCE`]: a shape matrix is accepted as symmetric when
//!   `|P_ij − P_ji| ≤ 1e-10 · max_kl |P_kl|` (scale invariant); the stored matrix is
//!   `(P + Pᵀ)/2`.
//! * [`PD_RELATIVE_TOLERANCE`]: positive definite means every Cholesky pivot `s_j` (the
//!   square of the `j`-th diagonal entry of the factor) is finite and
//!   `s_j > 4 ε · n · P_jj` (`ε` the machine epsilon): positive definite to working precision,
//!   whatever the scaling of the coordinates.
//! * [`RANK_RELATIVE_TOLERANCE`]: at `λ = 1` the intersection bound needs `Cᵀ R⁻¹ C`
//!   non-singular; it is treated as singular when a Cholesky pivot falls below `1e-12 · n` times
//!   its own diagonal entry (the workspace's pivot rule with a coarser tolerance).
//! * [`CONTAINMENT_TOLERANCE`]: point and ellipsoid containment accept a normalised distance
//!   up to `1 + 1e-9`.
//!
//! # Example
//!
//! ```
//! use ellipsoid::{Ellipsoid, MeasurementSet};
//! use nalgebra::{DMatrix, DVector};
//!
//! # fn main() -> Result<(), ellipsoid::EllipsoidError> {
//! // Prior: a disc of radius 2; one step of x ↦ A x, then add the noise disc of radius 0.1.
//! let prior = Ellipsoid::ball(DVector::from_vec(vec![0.0, 0.0]), 2.0)?;
//! let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.0, 1.0]);
//! let noise = Ellipsoid::ball(DVector::zeros(2), 0.1)?;
//! let (predicted, _p) = prior
//!     .affine_map(&a, &DVector::zeros(2))?
//!     .minkowski_sum_min_trace(&noise)?;
//!
//! // Measure the first coordinate: y = x₁ + v, |v| ≤ 0.5.
//! let meas = MeasurementSet::new(
//!     DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
//!     DVector::from_vec(vec![1.0]),
//!     DMatrix::from_element(1, 1, 0.25),
//! )?;
//! let (bound, lambda) = predicted.intersect_measurement_min_trace(&meas)?;
//! let updated = bound.ellipsoid().expect("the sets intersect");
//! assert!((0.0..=1.0).contains(&lambda));
//! assert!(updated.trace() < predicted.trace());
//! // The update contains the part of the prediction compatible with the measurement.
//! let x = DVector::from_vec(vec![1.2, 0.3]);
//! assert!(predicted.contains(&x)? && meas.contains(&x)?);
//! assert!(updated.contains(&x)?);
//! let (lo, hi) = updated.interval(0)?;
//! assert!(lo <= 1.2 && 1.2 <= hi);
//! # Ok(())
//! # }
//! ```

pub mod containment;
mod ellipsoid;
mod error;
pub mod intersection;
mod linalg;
pub mod minkowski;

pub use crate::ellipsoid::Ellipsoid;
pub use crate::error::{EllipsoidError, Result};
pub use crate::intersection::{IntersectionBound, MeasurementSet};

/// Relative symmetry tolerance: `|P_ij − P_ji| ≤ SYMMETRY_TOLERANCE · max_kl |P_kl|` (the
/// workspace's, from `dense-kernels`).
pub use dense_kernels::SYMMETRY_TOLERANCE;

/// Relative positive-definiteness tolerance: every Cholesky pivot `s_j` must exceed
/// `PD_RELATIVE_TOLERANCE · n · P_jj` (the workspace's, from `dense-kernels`).
pub use dense_kernels::PD_RELATIVE_TOLERANCE;

/// Relative rank tolerance for `Cᵀ R⁻¹ C` (in whitened form) at `λ = 1` in the intersection
/// bound: pivots must exceed `RANK_RELATIVE_TOLERANCE · n` times their own diagonal entry.
pub const RANK_RELATIVE_TOLERANCE: f64 = 1e-12;

/// Containment tolerance on the normalised distance: `x ∈ 𝓔` when
/// `(x − c)ᵀ P⁻¹ (x − c) ≤ 1 + CONTAINMENT_TOLERANCE`, and likewise for ellipsoids.
pub const CONTAINMENT_TOLERANCE: f64 = 1e-9;

/// Short constructors for the unit tests.
#[cfg(test)]
mod test_util {
    use nalgebra::{DMatrix, DVector};

    /// A column vector.
    pub(crate) fn v(x: &[f64]) -> DVector<f64> {
        DVector::from_column_slice(x)
    }

    /// An `r × c` matrix from its rows.
    pub(crate) fn m(r: usize, c: usize, x: &[f64]) -> DMatrix<f64> {
        DMatrix::from_row_slice(r, c, x)
    }
}
