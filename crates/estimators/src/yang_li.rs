//! Reference \[17\] of the paper (Yang & Li, "Set-membership filtering for systems with sensor
//! saturation", Automatica 45(8):1896–1902, 2009), **reconstructed**: its filter-form
//! set-membership filter without sensor saturation, in the two variants the paper's comparison
//! needs. The original's exact recursion is not reproduced from the article; this module
//! documents what the project implements under that name.
//!
//! * **(a) Not using the input** ([`without_input`]): the filter does not see `u_k`. The
//!   effect of `B u_k` over a known input box `[u_lo, u_hi]` is covered as an extra bounded
//!   disturbance: the box lies in `u_mid ⊕ 𝓔(0, W)` with `W = p · diag(h²)` (`h` the half-widths,
//!   `p` the input dimension), so `B u_k ∈ B u_mid ⊕ 𝓔(0, B W Bᵀ)`. The predictor uses the
//!   known centre `B u_mid`, and the process-noise set becomes the trace-optimal outer
//!   Minkowski sum `Q_eff = (1 + 1/s) Q + (1 + s) B W Bᵀ`, `s = √(tr Q / tr BWBᵀ)` (a direct sum
//!   of shapes, valid even when `B W Bᵀ` is singular, because `Q` is positive definite; `Q_eff` is
//!   inflated by a bound on its rounding error). The filter then runs the same update
//!   (28)/(29) with `Q_eff`. The guarantee covers only inputs in the box: a step with `u_k`
//!   outside it is refused with [`EstimatorError::InputOutsideBounds`], the filter unchanged.
//! * **(b) With the input added to its predictor** ([`with_input`]): the predictor
//!   `A x̂ + B u_k` followed by the filter-form update coincides with (13), so this variant
//!   *is* the improved filter's update ([`SetMembershipFilter`] with [`InputModel::Predictor`](crate::smf::InputModel::Predictor)).
//!
//! Both are [`SetMembershipFilter`]s, generic over the solver of (29).

use nalgebra::DVector;

use crate::error::EstimatorError;
use crate::smf::{SetMembershipFilter, UpdateSolver};
use crate::traits::Setup;

/// Variant (a): the input is not used; `B u` over `[u_lo, u_hi]` is a bounded disturbance
/// (`setup.inputs` must be the length of the box).
///
/// # Errors
/// As [`SetMembershipFilter::with_solver`], and [`EstimatorError::InvalidInputBounds`].
pub fn without_input<S: UpdateSolver>(
    setup: Setup,
    u_lo: &DVector<f64>,
    u_hi: &DVector<f64>,
    solver: S,
) -> Result<SetMembershipFilter<S>, EstimatorError> {
    SetMembershipFilter::with_solver(setup, solver)?.with_input_bounds(u_lo, u_hi)
}

/// Variant (b): the input in the predictor; identical to the improved filter (13).
///
/// # Errors
/// As [`SetMembershipFilter::with_solver`].
pub fn with_input<S: UpdateSolver>(setup: Setup, solver: S) -> Result<SetMembershipFilter<S>, EstimatorError> {
    SetMembershipFilter::with_solver(setup, solver)
}
