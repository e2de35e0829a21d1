//! Supply vessel for dynamic positioning, after Su & Zhao, *Journal of Harbin Engineering
//! University* 37(10), 2016 ("dynamic positioning controller with UKF moving horizon
//! estimation"), through the digest `shared/papers/dp-vessel-ukf-mhe.md` and the method note
//! `docs/dp-vessel.md`, whose equation numbers the code cites. Every formula of the paper is lost
//! in the extraction: the model is **reconstructed \[R\]** from Fossen, Sagatun & Sørensen (1996)
//! and Fossen's MSS `supply.m`.
//!
//! * [`params`]: the bis coefficients ([`BisCoefficients`]), their conversion to SI
//!   ([`bis_to_si`]), [`ThrustLimits`] (element-wise saturation), [`ForceNoise`] (the simulated
//!   disturbance), [`VesselParams`] (validated).
//! * [`model`]: [`Vessel`] (continuous, (1)–(14)) and [`DiscreteVessel`] (Euler at `δ = 0.1 s`,
//!   the paper's (16)–(20), or RK4 through [`models::Discretized`]), both with analytic
//!   Jacobians; state `[x, y, ψ, u, v, r]`, input `τ = [τ_X, τ_Y, τ_N]`, output `[x, y, ψ]`.
//!
//! | Item | Tag |
//! |---|---|
//! | `L = 76.2 m`, `m = 4.2e6 kg`, bis coefficients, `m23 = m32 = 0`, thrust limits, `δ = 0.1 s` | P |
//! | Low-speed model `M ν' + D ν = τ`, `η' = R(ψ) ν`; the bis → SI conversion | R (Fossen; MSS) |
//! | `g = 9.81 m/s²` (MSS: 9.8); force noise σ = (2e4 N, 6e3 N, 1.5e5 N m) | A |
//!
//! # Example
//!
//! ```
//! use models::{DiscreteModel, check_jacobians};
//! use nalgebra::DVector;
//! use vessel_dynamics::{DiscreteVessel, VesselParams};
//!
//! let model = DiscreteVessel::paper(VesselParams::paper())?;
//! let x = DVector::from_vec(vec![10.0, 5.0, 0.1, 0.5, 0.1, 0.01]);
//! let tau = DVector::from_vec(vec![1e5, -2e4, 1e6]);
//! let mut next = DVector::zeros(6);
//! model.f(&x, &tau, &mut next)?;
//! let check = check_jacobians(&model, &x, &tau)?;
//! assert!(check.f_error < 1e-8);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod enclosure;
pub mod error;
pub mod model;
pub mod params;

pub use error::VesselError;
pub use model::{
    DiscreteVessel, INPUT_DIM, OUTPUT_DIM, PAPER_SAMPLE_PERIOD, STATE_DIM, STATE_NAMES, VESSEL_ANGLES, Vessel, rotation,
};
pub use params::{BisCoefficients, ForceNoise, SiMatrices, ThrustLimits, VesselParams, bis_to_si};
