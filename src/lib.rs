#![doc = include_str!("../README.md")]
//!
//! ## This crate
//!
//! A facade over the workspace crates, for users who want one dependency:
//! [`carrier_dynamics`] (vehicle models), [`ellipsoid`] (set algebra), [`lmi`] (semidefinite
//! programs and their backends) and [`estimators`] (filters). Including the README here also
//! compiles and runs its example as a doctest.

pub use carrier_dynamics;
pub use ellipsoid;
pub use estimators;
pub use lmi;
