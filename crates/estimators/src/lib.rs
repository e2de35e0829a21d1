//! State estimators for port vehicles: a Kalman filter and the set-membership filters of the
//! straddle-carrier paper (Lin, Zhang, Ding & Niu, *Control and Decision* 39(1), 2024), with
//! certified containment.
//!
//! # Conventions
//!
//! Discrete-time linear time-varying models
//!
//! ```text
//! x_{k+1} = A_k x_k + B_k u_k + w_k,      y_{k+1} = C_{k+1} x_{k+1} + v_{k+1}
//! ```
//!
//! with the matrices passed per step (any [`LinearModel`], e.g. [`StepModel`]). One step consumes `u_k` and the
//! measurement `y_{k+1}` taken after it, and returns the estimate of `x_{k+1}`. Matrices are
//! [`nalgebra::DMatrix`] (column-major), dimensions fixed at construction: `n` states, `p`
//! inputs, `m` outputs.
//!
//! * [`KalmanFilter`]: `Q`, `R` are covariances; Joseph-form update.
//! * [`ExtendedKalmanFilter`]: the same over any [`models::DifferentiableModel`] (analytic
//!   Jacobians), the truck paper's (7)–(11).
//! * [`SetMembershipFilter`]: unknown-but-bounded noise `w ∈ 𝓔(0, Q)`, `v ∈ 𝓔(0, R)` (8)–(9),
//!   `𝓔(c, P) = {x : (x − c)ᵀ P⁻¹ (x − c) ≤ 1}`; the update (13)–(29) with any
//!   [`UpdateSolver`]: the exact [`TwoMultiplierSolver`] (module [`smf::two_multiplier`], the
//!   reduction and its derivatives) or an SDP backend ([`SdpUpdateSolver`] on LMI (28), module
//!   [`smf::lmi28`]). The published shape is certified (module [`smf`]: the inflation rule and
//!   the fallback).
//! * [`yang_li`]: the reconstruction of the paper's reference \[17\].
//! * [`AdaptiveKalmanFilter`] (module [`adaptive`]): the Kalman step with `R` scaled every epoch by
//!   `t_k` from any [`NoiseScaling`]; [`FuzzyKalmanFilter`] is the BDS/INS paper's, with the Mamdani
//!   system of `fuzzy-inference` (`docs/bds-ins-fuzzy-kf.md`).
//! * [`UnscentedKalmanFilter`]: scaled sigma points (`α, β, κ`, negative weights allowed, with a
//!   positive-definiteness guard) over any [`models::DiscreteModel`] (`docs/dp-vessel.md`).
//!
//! Every filter implements [`Estimator`] for the model capability it needs (here
//! [`LinearModel`]) and publishes an [`Estimate`] (centre, shape, bounds, and whether it is a
//! Gaussian covariance or a guaranteed ellipsoid); [`registry`] builds them by name behind the
//! object-safe [`DynEstimator`]. Equation numbers refer to `docs/carrier-smf.md`.
//!
//! Every step validates its input (dimensions, NaN/∞, and for the Yang–Li reconstruction (a)
//! that the input lies in its declared box) and returns a typed [`EstimatorError`] leaving the
//! filter unchanged; nothing panics on input. After construction, a Kalman step and a
//! two-multiplier set-membership step (including its fallbacks) perform no heap allocation, nor
//! does an SDP-backed step after the first (which builds the SDP) with the default backend; all
//! return borrowed views of the filter's estimate.

pub mod adaptive;
pub mod ekf;
pub mod error;
pub mod kalman;
pub mod mhe;
pub mod registry;
pub mod smf;
pub mod traits;
pub mod ukf;
mod validate;
pub mod yang_li;

pub use adaptive::{
    AdaptiveError, AdaptiveKalmanFilter, AdaptiveStep, ConstantScaling, FuzzyKalmanFilter, FuzzyScaling, NoiseScaling,
    ReceiverStatus, ScalingContext,
};
pub use ekf::ExtendedKalmanFilter;
pub use error::EstimatorError;
pub use kalman::{GaussianEstimate, KalmanFilter};
pub use mhe::{MheSettings, MovingHorizonEstimator};
pub use models::{LinearModel, StepModel};
pub use registry::{EstimatorInfo, LINEAR_ESTIMATORS, LinearSetup};
pub use smf::{
    Consistency, FallbackReason, InconsistencyPolicy, Inflation, InputModel, SdpUpdateSolver, SetEstimate,
    SetMembershipFilter, StepReport, TAU_FLOOR, TwoMultiplierSolver, UpdateProblem, UpdateSolution, UpdateSolver,
    UpdateStatus,
};
pub use traits::{DynEstimator, Estimate, EstimateKind, Estimator, NoiseSettings};
pub use ukf::{UkfParams, UkfReport, UnscentedKalmanFilter};
pub use validate::SYMMETRY_TOLERANCE;
