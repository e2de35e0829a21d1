//! Nonlinear models written as equations in a TOML model file, so that a vehicle can be
//! described without writing Rust.
//!
//! A model file declares states, inputs and outputs, optional parameters and named
//! intermediate definitions, and either a discrete map `[f]` or a continuous right-hand side
//! `[dxdt]` (integrated by explicit Euler or RK4 over `ts`, or by the exact zero-order hold when
//! linear), plus the measurements `[h]`. The crate's `README.md` describes the format.
//!
//! * The definitions and equations are compiled once into one computation graph: a definition
//!   is a shared intermediate value, computed once per evaluation whatever the number of
//!   equations that use it. Evaluation works in a per-thread scratch buffer: `f`, `h` and their
//!   Jacobians allocate nothing once a thread has evaluated the model.
//! * The Jacobians are exact: forward-mode chain rule through the graph (a hand-written
//!   derivative for every operation and function, `atan2`, `abs`, `min` and `max` included), and
//!   for `[dxdt]` the chain rule through the Euler or RK4 step (the matrix `e^{A ts}` for the
//!   exact zero-order hold).
//! * [`EquationModel`] implements [`models::DiscreteModel`], [`models::DifferentiableModel`]
//!   and [`models::AnyModel`] (with `linear()` when the equations are linear).
//! * Every problem with a file is an [`EquationError`] at the `file:line:column` of the key it
//!   is about; hostile files are refused by the [`limits`] while they are read.
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

mod enclosure;
pub mod error;
mod file;
mod graph;
mod interval_rules;
pub mod limits;
mod model;
mod ops;
mod parse;
mod scratch;
mod tape;

pub use error::{EquationError, Location};
pub use file::{Discretization, TimeModel};
pub use model::EquationModel;
pub use parse::{CONSTANTS, FUNCTIONS};
