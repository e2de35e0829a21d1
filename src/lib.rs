#![doc = include_str!("../README.md")]
//!
//! ## This crate
//!
//! A facade over the workspace crates, for users who want one dependency: [`models`] (model
//! traits, discretisation, simulation), [`carrier_dynamics`] (the straddle carrier),
//! [`truck_dynamics`] (the 3-axle port truck), [`car_dynamics`] (the robust-MHE paper's car),
//! [`ellipsoid`] (set algebra), [`constrained_zonotope`] (constrained zonotopes, verified hulls), [`lmi`] (semidefinite programs and their backends),
//! [`estimators`] (estimator traits, registry and filters), [`vessel_dynamics`] and
//! [`vessel_control`] (the supply vessel and its dynamic-positioning controller),
//! [`bds_ins_dynamics`] (the BDS/INS error model and BDS simulator), [`fuzzy_inference`] (the
//! Mamdani engine) and
//! [`dense_kernels`]. Including the
//! README here also compiles and runs its example as a doctest.

pub use bds_ins_dynamics;
pub use car_dynamics;
pub use carrier_dynamics;
pub use constrained_zonotope;
pub use dense_kernels;
pub use ellipsoid;
pub use estimators;
pub use fuzzy_inference;
pub use lmi;
pub use models;
pub use truck_dynamics;
pub use vessel_control;
pub use vessel_dynamics;
