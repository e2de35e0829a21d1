//! Straddle-carrier lateral/yaw/roll dynamics after Lin, Zhang, Ding & Niu, *Control and
//! Decision* 39(1):129–136, 2024 (paper §1, eqs (1)–(11); `docs/carrier-smf.md`), and its exact
//! zero-order-hold discretisation. Generic tools (matrix exponential, simulator, noise, PRNG)
//! live in the vehicle-free `models` crate; this crate holds only the carrier.
//!
//! # Model
//!
//! The carrier has four rows of wheels, a left and a right wheel per row, all steerable; rows 1
//! and 2 are ahead of the CG, rows 3 and 4 behind, at distances `L_1..L_4`.
//!
//! * State `x = [β, γ, φ, φ̇]`: sideslip angle at the CG, yaw rate, roll angle, roll rate
//!   (rad, rad/s).
//! * Input `u = [δl1, δl2, δl3, δl4, δr1, δr2, δr3, δr4]`: the eight steering angles (rad).
//! * Output `y = C x` with `C = I₄`.
//! * Tyres: slip `α = β ± L_i γ / v − δ` (`+` rows 1, 2; `−` rows 3, 4), force `F = −K α`; a
//!   positive steering angle gives a positive lateral force.
//! * Lateral (4) `m v (β̇ + γ) − m h φ̈ = Σ F`; yaw (5) `I_z γ̇ = Σ_front L_i F − Σ_rear L_i F`;
//!   roll (6) `I_xeq φ̈ − m h v (β̇ + γ) − m g h φ + C_φ φ̇ + K_φ φ = 0`, with
//!   `I_xeq = I_x + m h²`. Eliminating `β̇` and `φ̈` gives `ẋ = A x + B u` (7), built by
//!   [`CarrierModel`].
//!
//! # Conventions settled here (see the items for details)
//!
//! * Rear-row steering enters the yaw equation with a minus sign, as eq (5) says (the paper's
//!   printed `B` shows `+L_i K / I_z` for every row).
//! * Table 1's roll inertia 2 119 600 kg m² is read as `I_x` about the CG
//!   ([`CarrierParams::paper_preset`]); read as `I_xeq` it would give `I_x < 0`, which
//!   [`CarrierParams::validate`] rejects.
//! * Loads of 0, 1, 2 containers follow documented assumptions ([`load`]); one container
//!   reproduces Table 1 exactly.
//! * Discretisation is exact ZOH: `A_p = e^{A T_s}`, `B_p = ∫₀^{T_s} e^{Aτ} dτ B`
//!   ([`models::zoh_discretize`], block exponential, own Padé scaling-and-squaring
//!   [`models::expm`]).
//! * [`DiscreteCarrier`] is a [`models::LinearTimeVarying`] model, so `models::simulate_ltv`
//!   simulates it (`x_{k+1} = A_k x_k + B_k u_k + w_k`, `y_k = C_k x_k + v_k`; an estimator's
//!   step `k` consumes `u_k` and `y_{k+1}`).
//!
//! # Example
//!
//! ```
//! use carrier_dynamics::{CarrierModel, CarrierParams};
//!
//! // Table 1, one container, 6 m/s.
//! let model = CarrierModel::new(CarrierParams::paper_preset())?;
//! assert!(model.is_stable());
//!
//! // Exact ZOH discretisation at T_s = 1 ms (paper §4).
//! let d = model.discretize(1e-3)?;
//! // Roll angle integrates roll rate: A_p[(2, 3)] ≈ T_s.
//! assert!((d.a_p[(2, 3)] - 1e-3).abs() < 1e-5);
//! // A rear-left steering angle turns the carrier the other way than a front-left one.
//! assert!(d.b_p[(1, 0)] > 0.0 && d.b_p[(1, 3)] < 0.0);
//! # Ok::<(), carrier_dynamics::DynamicsError>(())
//! ```

pub mod error;
pub mod load;
pub mod model;
pub mod params;

pub use error::DynamicsError;
pub use load::RigidBody;
pub use model::{
    CarrierModel, DiscreteCarrier, INPUT_DIM, InputMatrix, InputVector, OUTPUT_DIM, STATE_DIM, StateMatrix, StateVector,
};
pub use params::{CarrierParams, RollInertia};
