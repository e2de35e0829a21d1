//! Dynamic positioning control of the supply vessel (Su & Zhao 2016, through
//! `docs/dp-vessel.md`, whose equation numbers the code cites; every formula of the paper is
//! lost, so the controller is **reconstructed \[R\]** from Chen, Ballance & Gawthrop,
//! *Automatica* 39, 2003, with control order 0):
//!
//! * [`nsampc`]: the non-switching analytic predictive controller (NSAMPC) (38)–(61) — Lie
//!   derivatives ([`lie_derivatives`]), the Taylor prediction of the output error, closed-form
//!   gains from `Tp, μ1, μ2, μ3` ([`NsampcParams::gains`]) and element-wise saturation to the
//!   thrust limits;
//! * [`reference`](mod@reference): the set point, as a literal step (run A) or through the third-order reference
//!   filter (run B, assumed);
//! * [`closed_loop`]: a reusable closed-loop runner — plant → measurement → estimator →
//!   [`Controller`] → plant — generic over any [`models::DiscreteModel`] plant and any estimator
//!   of the `estimators` crate (through [`estimators::DynEstimator`], so a registry estimator
//!   chosen by name plugs in as it is).
//!
//! # Example
//!
//! ```
//! use vessel_control::{NsampcParams, Nsampc};
//! use vessel_dynamics::VesselParams;
//!
//! let gains = NsampcParams::paper().gains()?;
//! assert!((gains.k0 - 1.6722).abs() < 1e-4 && (gains.k1 - 1.7738).abs() < 1e-4);
//! let ctrl = Nsampc::new(&VesselParams::paper(), NsampcParams::paper())?;
//! # let _ = ctrl;
//! # Ok::<(), vessel_control::ControlError>(())
//! ```

pub mod closed_loop;
pub mod error;
pub mod nsampc;
pub mod reference;

pub use closed_loop::{ClosedLoopError, Controller, LoopConfig, LoopRecord, run_closed_loop};
pub use error::ControlError;
pub use nsampc::{
    ControlOutput, Gains, LieDerivatives, Nsampc, NsampcParams, Saturation, VesselController, lie_derivatives,
};
pub use reference::{ReferenceFilter, ReferenceSample, SetPoint};
