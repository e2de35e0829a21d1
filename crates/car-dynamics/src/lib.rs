//! The linear single-track car of the robust min–max moving-horizon estimation paper with
//! disturbance blocking (College of Information Engineering, Zhejiang University of
//! Technology; digest `shared/papers/robust-blocking-mhe.md`, method note
//! `docs/robust-mhe.md`), its exact zero-order-hold discretisation and the data of the
//! experiment (noise boxes, initial state, double lane change). Generic tools (matrix
//! exponential, simulator, noise, PRNG) live in the vehicle-free `models` crate; this crate
//! holds only the car.
//!
//! Only eqs (6), (7), (11) and (25) of the paper survive, so most of this crate is
//! **reconstructed \[R\]** or **assumed \[A\]**; \[P\] marks the paper, \[V\] values checked
//! with the digest's prototype (not the paper's numbers).
//!
//! # Model
//!
//! * State `x = [Y, φ, β, r]`: lateral position, heading, sideslip at the CG, yaw rate
//!   (m, rad, rad, rad/s) \[R\]. The paper calls the measured `x1` "longitudinal position", but
//!   `x(0) = [−2, 0, 0, 0]` with `Y_0 = −2 m`, and `δ_f` cannot move a longitudinal coordinate
//!   at fixed `v_x`, so `x1 = Y`.
//! * Input `u = [δ_f]`, the front steering angle (rad).
//! * Continuous model (1)–(5) \[R, Rajamani ch. 2\]: [`CarModel`], at constant `v_x`, small
//!   angles, linear axle forces with per-axle stiffnesses `C_f`, `C_r`.
//! * Discrete model (6) `x(T+1) = A_c x(T) + B_c δ_f(T) + w(T)` \[P\] by exact ZOH \[A\]
//!   ([`CarModel::discretize`], a [`models::ConstantModel`], so `models::simulate_ltv` and the
//!   linear estimators take it). Forward Euler is unstable at `T_s = 0.5 s` \[V\].
//! * Measurement (7) `y(T) = C x(T) + v(T)`, `C = [1, 0, 0, 0]` \[P\].
//! * Noise sets `W = [−0.1, 0.1]⁴`, `V = [−1, 1]` \[P\], no state set `X` \[A\]:
//!   [`NoiseBounds::digest`].
//!
//! # Decisions on the digest's open points
//!
//! * **Parameters.** [`CarParams::digest_default`] is the digest's default set (A, CarSim
//!   C-Class hatchback). [`CarParams::digest_alternative`] takes `m`, `I_z`, `a`, `b` of the
//!   digest's alternative set and, since the digest gives none for it, **the default set's
//!   `C_f`, `C_r`** (A).
//! * **Discretisation (§6.3).** Exact ZOH; Euler is not offered by this crate (tests show why).
//! * **Truth (§6.7).** The linear proxy manoeuvre [`double_lane_change`] (A), sampled with a
//!   zero-order hold by [`double_lane_change_inputs`]; no nonlinear Pacejka truth yet.
//!
//! # Example
//!
//! ```
//! use car_dynamics::{CarModel, CarParams, DIGEST_SAMPLING_PERIOD};
//! use models::LinearModel;
//!
//! let model = CarModel::new(CarParams::digest_default())?;
//! let d = model.discretize(DIGEST_SAMPLING_PERIOD)?;
//! // Heading integrates into position: A_c[(0, 1)] = v_x T_s = 12.5 m/rad.
//! assert!((d.a()[(0, 1)] - 12.5).abs() < 1e-12);
//! // The digest's test vector: B_c ≈ [14.81982, 3.27111, −0.49716, 8.20710]ᵀ.
//! assert!((d.b()[(0, 0)] - 14.81982).abs() < 1e-5);
//! # Ok::<(), car_dynamics::CarError>(())
//! ```

pub mod error;
pub mod model;
pub mod params;
pub mod scenario;

pub use error::CarError;
pub use model::{
    CarModel, HEADING, INPUT_DIM, InputMatrix, LATERAL_POSITION, OUTPUT_DIM, OutputMatrix, SIDESLIP, STATE_DIM,
    StateMatrix, StateVector, YAW_RATE,
};
pub use params::{CarParams, DIGEST_SPEED};
pub use scenario::{
    DIGEST_INITIAL_STATE, DIGEST_SAMPLING_PERIOD, DIGEST_STEPS, DOUBLE_LANE_CHANGE_AMPLITUDE, NoiseBounds,
    double_lane_change, double_lane_change_inputs,
};
