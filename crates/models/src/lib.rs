//! Vehicle-free model traits and tools, shared by every vehicle crate and estimator.
//!
//! * [`model`]: what an estimator may ask of a model — [`DiscreteModel`] (`f`, `h`),
//!   [`DifferentiableModel`] (plus Jacobians; [`check_jacobians`] against central
//!   differences), [`LinearModel`] (`A`, `B`, `C`; every linear model is a differentiable
//!   discrete model), and [`LinearTimeVarying`] (the matrices of each step).
//! * [`angles`]: which states and outputs are angles ([`Angles`], declared by the model,
//!   none by default) and [`wrap_angle`].
//! * [`capability`]: [`AnyModel`], a model seen through the capabilities it offers (for
//!   estimators chosen at run time), and [`Capability`].
//! * [`closure`]: [`ClosureModel`], a model from two closures `f(x, u)`, `h(x, u)` whose
//!   Jacobians come from forward-mode automatic differentiation ([`dual`]: [`Dual`]).
//! * [`enclosure`]: [`SecondOrderModel`], rigorous enclosures of `f`, `h` and their first and
//!   second derivatives over boxes of states (the nonlinear set-membership filter's remainder
//!   bound); every linear model offers them.
//! * [`continuous`]: continuous-time models and their discretisation — explicit Euler, RK4,
//!   exact zero-order hold ([`discretize`]: own Padé matrix exponential), Van Loan's discrete
//!   process noise.
//! * [`noise`], [`rng`], [`simulate()`]: seeded simulation of any model with Gaussian, box,
//!   in-ellipsoid or ellipsoid-boundary noise, drawn from a documented PRNG
//!   ([`Xoshiro256StarStar`], also a `rand_core` generator) so that a seed reproduces a run
//!   whatever the versions of other crates.
//! * [`validate`]: the vehicle crates' checks of scalar parameters (finite, positive,
//!   non-negative) with their [`validate::ParamError`].
//!
//! Conventions: a step maps `x_k` to `x_{k+1} = f(x_k, u_k) + w_k`; the measurement taken after
//! it is `y_{k+1} = h(x_{k+1}, u_k) + v_{k+1}`; an estimator's step `k` consumes `u_k` and
//! `y_{k+1}`.
//!
//! # Example
//!
//! ```
//! use models::{ConstantModel, Noise, SimulationConfig, simulate_ltv};
//! use nalgebra::{DMatrix, DVector};
//!
//! // A damped oscillator with a position sensor, noise on the boundary of its ellipsoids.
//! let model = ConstantModel::new(
//!     DMatrix::from_row_slice(2, 2, &[1.0, 0.1, -0.1, 0.98]),
//!     DMatrix::from_row_slice(2, 1, &[0.0, 0.1]),
//!     DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
//! )?;
//! let run = simulate_ltv(&model, &SimulationConfig {
//!     x0: DVector::from_vec(vec![1.0, 0.0]),
//!     inputs: vec![DVector::zeros(1); 50],
//!     process_noise: Noise::ellipsoid_boundary(DMatrix::identity(2, 2) * 1e-6)?,
//!     measurement_noise: Noise::uniform_cube(1, 0.01)?,
//!     seed: 7,
//! })?;
//! assert_eq!(run.states.len(), 51);
//! # Ok::<(), models::ModelError>(())
//! ```

pub mod angles;
pub mod capability;
pub mod closure;
pub mod continuous;
pub mod dims;
pub mod discretize;
pub mod dual;
pub mod enclosure;
pub mod error;
pub mod model;
pub mod noise;
pub mod rng;
pub mod simulate;
pub mod validate;

pub use angles::{Angles, angle_branch, wrap_angle};
pub use capability::{AnyModel, Capability, DifferentiableView, DiscreteView, LinearView};
pub use closure::ClosureModel;
pub use continuous::{
    ContinuousModel, DifferentiableContinuousModel, Discretized, Integrator, LinearContinuous, van_loan,
};
pub use discretize::{ZohDiscretization, expm, zoh_discretize, zoh_discretize_fixed};
pub use dual::Dual;
pub use enclosure::{SecondOrderModel, TaylorEnclosure, check_enclosure_dims};
pub use error::{ModelError, check_spd};
pub use intervals::Interval;
pub use model::{
    ConstantModel, DifferentiableModel, Dims, DiscreteModel, FnModel, JacobianCheck, LinearModel, LinearTimeVarying,
    StepMatrices, StepModel, check_jacobians, numeric_jacobians,
};
pub use noise::{Noise, NoiseDistribution};
pub use rng::{Xoshiro256StarStar, splitmix64};
pub use simulate::{SimulationConfig, Trajectory, simulate, simulate_ltv};

/// The crate README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
