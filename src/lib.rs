//! Guaranteed (set-membership) and stochastic state estimation for port vehicles.
//!
//! A facade over the workspace crates, for users who want one dependency:
//! [`carrier_dynamics`] (vehicle models), [`ellipsoid`] (set algebra), [`lmi`] (semidefinite
//! programs and their backends) and [`estimators`] (filters).

pub use carrier_dynamics;
pub use ellipsoid;
pub use estimators;
pub use lmi;
