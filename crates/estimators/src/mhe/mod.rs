//! Moving-horizon estimation for linear models with box-bounded noise: the robust min–max MHE
//! with disturbance blocking of the car paper (seed 002; method note `docs/robust-mhe.md`, whose
//! section numbers the code cites) and plain least-squares MHE as its control.
//!
//! * [`MheSettings`]: everything as data — horizon, block lengths (any `d_1..d_S` summing to
//!   `N`, the paper's RMHE / RMHE-OP / RMHE-OF as [`BlockingPreset`]s), block weighting, the
//!   cost ([`MheCost::MinMax`] with `λv`, or [`MheCost::LeastSquares`]; the paper's `α` through
//!   either [`AlphaMap`]), boxes `W`, `V`, the arrival-cost recursion (20) in Kalman or H∞ form,
//!   the prior mean, the window solver.
//! * [`MovingHorizonEstimator`]: windowing (full information for `T ≤ N`), arrival cost, the
//!   condensed window problem and its solution by the paper's coordinate rotation (44)–(45)
//!   ([`WindowSolver::CoordinateRotation`], with the active-set [`boxqp`] solver or Clarabel's QP
//!   path as the minimisation step) or by the exact saddle solver
//!   ([`WindowSolver::ExactSaddle`]). Every update reports status, sweeps, inner iterations,
//!   unknowns, the arrival recursion used and its wall time ([`MheReport`]); a solver that stops
//!   early is an outcome ([`WindowStatus`]), never a panic, and the published estimate is finite
//!   (a non-finite window solution is an error that leaves the estimator unchanged).
//! * [`NonlinearMhe`]: moving-horizon estimation for any differentiable nonlinear model (the
//!   supply-vessel paper's (21)–(23), `docs/dp-vessel.md`): Gauss–Newton / Levenberg–Marquardt
//!   on the block-tridiagonal window problem, arrival cost by one unscented (or extended) Kalman
//!   step (§3.2).

pub mod boxqp;
mod clarabel_inner;
mod consistency;
mod estimator;
mod nonlinear;
pub mod settings;
mod solve;
mod window;

pub use estimator::{ArrivalStatus, DETAILS, MheEstimate, MheReport, MovingHorizonEstimator};
pub use nonlinear::DETAILS as NONLINEAR_DETAILS;
pub use nonlinear::{
    NonlinearArrival, NonlinearMhe, NonlinearMheEstimate, NonlinearMheReport, NonlinearMheSettings, NonlinearPrior,
};
pub use settings::{
    AlphaMap, ArrivalRecursion, BlockWeighting, BlockingPreset, InnerSolver, MheCost, MheSettings, PriorMean,
    WindowSolver, memory_estimate,
};
pub use solve::{SolveCounters, WindowStatus};
