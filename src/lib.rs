#![doc = include_str!("../README.md")]
//!
//! ## This crate
//!
//! A facade over the workspace crates, for users who want one dependency: [`models`] (model
//! traits, discretisation, simulation), [`carrier_dynamics`] (the straddle carrier),
//! [`truck_dynamics`] (the 3-axle port truck), [`car_dynamics`] (the robust-MHE paper's car),
//! [`ellipsoid`] (set algebra), [`lmi`] (semidefinite programs and their backends),
//! [`estimators`] (estimator traits, registry and filters) and [`dense_kernels`]. Including the
//! README here also compiles and runs its example as a doctest.

pub use car_dynamics;
pub use carrier_dynamics;
pub use dense_kernels;
pub use ellipsoid;
pub use estimators;
pub use lmi;
pub use models;
pub use truck_dynamics;
