//! Nonlinear models written as equations in a TOML model file, so that a vehicle can be
//! described without writing Rust.
//!
//! A model file declares states, inputs and outputs, optional parameters and named
//! intermediate definitions, and either a discrete map `[f]` or a continuous right-hand side
//! `[dxdt]` (integrated by explicit Euler or RK4 over `ts`, or by the exact zero-order hold when
//! linear), plus the measurements `[h]`. The crate's `README.md` describes the format.
//!
//! * Each expression is parsed once (by the `exmex` expression library) after the definitions
//!   and parameters are substituted into it, so the derivatives see through them; evaluation
//!   fills a stack buffer of the expression's variables (no allocation for up to 32 variables
//!   per expression; the RK4 and Euler steps allocate their stage vectors).
//! * The Jacobians are exact: symbolic partial derivatives, and for `[dxdt]` the chain rule
//!   through the Euler or RK4 step (the matrix `e^{A ts}` for the exact zero-order hold).
//! * [`EquationModel`] implements [`models::DiscreteModel`], [`models::DifferentiableModel`]
//!   and [`models::AnyModel`] (with `linear()` when the equations are linear).
//! * Every problem with a file is an [`EquationError`] at the `file:line:column` of the key it
//!   is about; hostile files are refused by the [`limits`] before any parsing.
//!
//! # Example
//!
//! ```
//! use equation_models::EquationModel;
//! use models::{AnyModel, DiscreteModel};
//! use nalgebra::DVector;
//!
//! let model = EquationModel::from_toml_str(r#"
//! [model]
//! states = ["theta", "omega"]
//! inputs = ["torque"]
//! outputs = ["angle"]
//! ts = 0.01
//! discretization = "rk4"
//!
//! [parameters]
//! g = 9.81
//! l = 0.5
//!
//! [dxdt]
//! theta = "omega"
//! omega = "-g / l * sin(theta) + torque"
//!
//! [h]
//! angle = "theta"
//! "#, "pendulum.toml")?;
//! let mut next = DVector::zeros(2);
//! model.f(&DVector::from_vec(vec![0.1, 0.0]), &DVector::zeros(1), &mut next)?;
//! assert!(next[1] < 0.0);
//! assert!(model.differentiable().is_some() && model.linear().is_none());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod compiled;
pub mod error;
mod expand;
mod file;
pub mod limits;
mod model;

pub use error::{EquationError, Location};
pub use expand::{CONSTANTS, FUNCTIONS};
pub use file::{Discretization, TimeModel};
pub use model::EquationModel;
