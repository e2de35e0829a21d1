//! State estimators for port vehicles.
//!
//! Planned (see the project's issues): a Kalman filter and the improved set-membership filter of
//! the straddle-carrier paper, eqs (13)–(29), with certified containment. Nothing is implemented yet.
