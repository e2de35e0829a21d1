//! State estimators for port vehicles: Kalman, extended and unscented Kalman filters, the
//! certified set-membership filters of the straddle-carrier paper (Lin, Zhang, Ding & Niu,
//! *Control and Decision* 39(1), 2024), a fuzzy-adaptive Kalman filter and moving-horizon
//! estimators, behind one interface.
//!
//! # A first estimate
//!
//! Four concepts, as in filterpy: the sizes and attributes of a [`Setup`] (initial estimate,
//! noise, number of inputs), and the verbs [`Estimator::predict`] and [`Estimator::update`]
//! ([`Estimator::step`] does both). Every estimate says what it is ([`Estimate::kind`]), how its
//! step ended ([`Estimate::status`]) and the estimator's own details ([`Estimate::details`]).
//!
//! ```
//! use estimators::nalgebra::{DMatrix, DVector, dmatrix, dvector};
//! use estimators::{Estimate, KalmanFilter, SetMembershipFilter, Setup, StepModel};
//!
//! // A damped oscillator with a position sensor, sampled at 0.1 s.
//! let (a, b, c) = (dmatrix![1.0, 0.1; -0.1, 0.98], dmatrix![0.0; 0.1], dmatrix![1.0, 0.0]);
//! let model = StepModel::new(&a, &b, &c);
//! let setup = Setup {
//!     x0: dvector![0.0, 0.0],
//!     p0: DMatrix::identity(2, 2),
//!     process_noise: DMatrix::identity(2, 2) * 1e-4, // covariance for the Kalman filter,
//!     measurement_noise: dmatrix![1e-2],              // ellipsoid shapes for the set-membership filter
//!     inputs: 1,
//! };
//! let mut kf = KalmanFilter::new(setup.clone())?;
//! let mut smf = SetMembershipFilter::new(setup)?;
//! let (u, y) = (dvector![1.0], dvector![0.02]);
//! kf.predict(&model, &u)?;
//! let gaussian = kf.update(&model, &y)?;
//! let guaranteed = smf.step(&model, &u, &y)?;
//! // The set-membership filter's bounds certainly contain the state (noises within their bounds).
//! let (lo, hi) = guaranteed.bounds(0).unwrap();
//! assert!(lo <= gaussian.center[0] && gaussian.center[0] <= hi);
//! assert!(guaranteed.status().is_clean());
//! # Ok::<(), estimators::EstimatorError>(())
//! ```
//!
//! # Conventions
//!
//! Discrete-time models `x_{k+1} = f(x_k, u_k) + w_k`, `y_{k+1} = h(x_{k+1}, u_k) + v_{k+1}`,
//! linear time-varying ones `x_{k+1} = A_k x_k + B_k u_k + w_k`, `y_{k+1} = C_{k+1} x_{k+1} + v_{k+1}`,
//! passed per step (any [`LinearModel`], e.g. [`StepModel`]). One step consumes `u_k` and the
//! measurement `y_{k+1}` taken after it, and returns the estimate of `x_{k+1}`. Matrices are
//! [`nalgebra::DMatrix`] (re-exported as [`nalgebra`]), dimensions fixed at construction.
//!
//! * [`KalmanFilter`]: `Q`, `R` are covariances; Joseph-form update (`docs/kalman.md`).
//! * [`ExtendedKalmanFilter`]: the same over any [`DifferentiableModel`] (analytic Jacobians),
//!   the truck paper's (7)–(11).
//! * [`UnscentedKalmanFilter`]: scaled sigma points over any [`DiscreteModel`]
//!   (`docs/dp-vessel.md`).
//! * [`SetMembershipFilter`]: unknown-but-bounded noise `w ∈ 𝓔(0, Q)`, `v ∈ 𝓔(0, R)` (8)–(9),
//!   `𝓔(c, P) = {x : (x − c)ᵀ P⁻¹ (x − c) ≤ 1}`; the update (13)–(29) with any
//!   [`UpdateSolver`]: the exact [`TwoMultiplierSolver`] or an SDP backend ([`SdpUpdateSolver`] on
//!   LMI (28)). The published shape is certified (module [`smf`]); [`yang_li`] reconstructs the
//!   paper's reference \[17\].
//! * [`AdaptiveKalmanFilter`]: the Kalman step with `R` scaled every epoch by `t_k` from any
//!   [`NoiseScaling`]; [`FuzzyKalmanFilter`] is the BDS/INS paper's (`docs/bds-ins-fuzzy-kf.md`).
//! * [`mhe`]: the robust min–max moving-horizon estimator of the car paper and plain MHE
//!   (`docs/robust-mhe.md`), and [`NonlinearMhe`] with a UKF arrival cost (`docs/dp-vessel.md`).
//!
//! The crate root holds what a user names (the estimators, their settings, the traits, the status
//! vocabulary, the errors); reports, solver internals and the registry's parts stay in their
//! modules ([`smf`], [`czf`], [`ukf`], [`adaptive`], [`error`], [`registry`]).
//!
//! Every filter implements [`Estimator`] for the model capability it needs; [`registry`] builds
//! any of them by name behind [`DynEstimator`] over `dyn` [`AnyModel`]. Equation numbers refer to
//! `docs/carrier-smf.md` unless a module says otherwise.
//!
//! Every call validates its input (dimensions, NaN/∞, declared boxes) and returns a typed
//! [`EstimatorError`] leaving the estimator unchanged; nothing panics on input. After
//! construction, the Kalman, set-membership (two-multiplier, or an SDP backend after its first
//! step) and adaptive steps perform no heap allocation (tested with a counting allocator).

pub mod adaptive;
mod angle_branch;
pub mod checks;
pub mod czf;
pub mod ekf;
pub mod error;
mod gaussian_update;
pub mod kalman;
pub mod mhe;
mod partial;
pub mod registry;
pub mod smf;
mod status;
pub mod traits;
pub mod ukf;
mod validate;
pub mod yang_li;

pub use adaptive::{
    AdaptiveError, AdaptiveKalmanFilter, ConstantScaling, FuzzyKalmanFilter, FuzzyScaling, NoiseScaling, ScalingContext,
};
pub use checks::{DataChecks, InnovationGate};
pub use czf::{ConstrainedZonotopeFilter, ConstrainedZonotopeSettings};
pub use ekf::ExtendedKalmanFilter;
pub use error::{ErrorKind, EstimatorError};
pub use kalman::{GaussianEstimate, KalmanFilter};
pub use mhe::{MheSettings, MovingHorizonEstimator, NonlinearMhe, NonlinearMheSettings};
pub use models::{AnyModel, Capability, DifferentiableModel, Dims, DiscreteModel, LinearModel, StepModel};
/// The linear algebra of every signature (`DVector`, `DMatrix`, `dvector!`, `dmatrix!`).
pub use nalgebra;
pub use registry::{AnyEstimator, SmfSolver};
pub use smf::{
    InconsistencyPolicy, NonlinearSetMembershipFilter, NonlinearSmfSettings, SdpUpdateSolver, SetEstimate,
    SetMembershipFilter, TwoMultiplierSolver, UpdateSolver,
};
pub use traits::{
    DataCheck, DetailField, DynEstimator, Estimate, EstimateKind, Estimator, Guarantee, Setup, SolveOutcome,
    StepDetails, StepStatus,
};
pub use ukf::{UkfParams, UnscentedKalmanFilter};
pub use validate::SYMMETRY_TOLERANCE;
