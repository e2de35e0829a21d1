//! Three-axle port container truck for EKF state estimation after Yang, Zeng, Lei & Huang,
//! *港口装卸* 2023(6) ("state estimation of an intelligent unmanned port container truck with
//! an extended Kalman filter"), through the digest `shared/papers/truck-ekf.md`. The paper's
//! equations survive only in part and its Tables 1–2 are lost, so most of this crate is
//! **reconstructed \[R\]** or **assumed \[A\]**; the table below says which. Generic tools (model
//! traits, RK4, Jacobian checks) live in the vehicle-free `models` crate.
//!
//! * [`tyre`]: Pacejka-89 (paper (3)–(4)) with Adams PAC89 coefficient laws (kN, degrees,
//!   percent → N), truck coefficients, analytic slopes, dual tyres lumped as `n·F(F_z/n)`.
//! * [`kinematics`]: wheel velocities, slip angles, slip ratios and their gradients.
//! * [`planar`]: the estimator's model — [`PlanarTruck`] (continuous, eq (1)) and
//!   [`TruckEkfModel`] (Euler at 1 ms (12), measurement (14), analytic `A = I + T·J` (13) and
//!   `H` (15)), a [`models::DifferentiableModel`] that evaluates without allocating.
//! * [`enclosure`]: interval enclosures of `f`, `h` and their Jacobians over boxes of states
//!   (interval forward-mode AD), so that the nonlinear set-membership filter `smf-nl` runs on
//!   the truck ([`models::SecondOrderModel`]).
//! * [`truth`]: the richer truth model of the experiment ([`TruthModel`], a
//!   [`models::ContinuousModel`]), [`simulate_truth`] (RK4 at 0.1 ms, output at 1 kHz) and the
//!   [`Slalom`] manoeuvre.
//! * [`TruckParams`]: every parameter in one validated struct; [`TruckError`] names the
//!   offending parameter, state or input and converts into [`models::ModelError::Evaluation`].
//!
//! # What comes from where
//!
//! | Item | Tag | Source |
//! |---|---|---|
//! | Planar rigid 3-axle model; no pitch, roll, heave, drag, suspension; rigid steering | P | paper §2 |
//! | State `[V_x, V_y, γ]`, `β = atan(V_y/V_x)` (2) ([`sideslip`]) | P | paper |
//! | Magic Formula shape `D·sin(C·atan(B·X − E·(B·X − atan(B·X)))) + S_V` (3)–(4) | P | paper |
//! | Sampling and filter period `T = 1 ms` ([`PAPER_SAMPLE_PERIOD`]) | P | paper |
//! | Forward-Euler form of (12), `A = I + T·J` (13) | R | digest §3 (the paper implies Euler) |
//! | 70 km/h, 12 s | P | paper |
//! | Frame, wheel kinematics, slip definitions ([`kinematics`]) | R | standard multi-wheel planar model (digest §2) |
//! | Pac89 coefficient laws and units (kN, deg, %) | R | Adams PAC89 as in Chrono's `ChPac89Tire` |
//! | Truck tyre coefficients ([`Pac89Coefficients::truck_315_80r22_5`]) | R | mapped from a 315/80R22.5 PAC2002 example file; **not the paper's** |
//! | Asymmetric tyre shifts set to zero, zero camber | A | digest §2, decision 5 |
//! | Equations of motion (1) written out, `J` (13), `H` (15), measurement `[V_x, a_y, γ]` (14) | R | digest §2–§3 |
//! | `σ_α = 0.65 m`, `f_r = 0.008` | R | tyre file (`PTY1·R_0`, `QSY1`) |
//! | Dual tyres as `n·F(F_z/n)` | A | decision 3 |
//! | Static loads, tandem equalised; `v_min = 0.1 m/s`, `F_z ≥ 1 kN` per tyre | A | decisions 1, 6 |
//! | Every vehicle number ([`TruckParams::digest_preset`]): `m, I_z, a, b, c, T_i, R_e, h_cg, J_w, C_d·A` | A | digest §4–§5 |
//! | `ρ = 1.2 kg/m³`, speed-PI gains, fade of the force below the load clamp, friction scale `λ_μ` | A | this crate |
//! | Truth model (relaxation, wheel spin, 6×4 PI drive, load transfer, drag, friction ellipse) and slalom | A | digest §5 (replaces TruckSim) |
//!
//! The digest's unit-test values (`B = 0.0854 /deg`, `D = 17 243 N`, `F_y(2°) = 4557 N` at
//! 22.5 kN, …) are **\[V\]**: computed from the reconstructed coefficients by a prototype, not
//! taken from the paper.
//!
//! # Decisions (digest §6)
//!
//! * **1.** Tyre forces inside the estimator come from `α` of the state, `s` of the state and
//!   the measured wheel speeds, at static loads. The "exogenous forces" mode is not implemented.
//! * **2.** `α_j = δ_j − atan2(v_j, u_j)` so positive coefficients give the right signs;
//!   mirroring `δ` (and swapping left/right wheel speeds) mirrors `V_y` and `γ` (tested).
//! * **3.** Dual tyres are lumped as `n·F(F_z/n)`.
//! * **4.–5.** Vehicle and tyre data are kept in [`TruckParams`]; no camber, no asymmetry.
//! * **6.** Low-speed guards `max(·, v_min)`; load clamp `F_z ≥ F_z,min = 1 kN` per tyre for the
//!   coefficients, with the force faded to zero below it. `V_x ≤ 0` is an error.
//! * **7.** `a_y = ΣF_Y/m` (no gravity, no roll), in both models.
//! * **8.** `Q`, `R`, `P_0` belong to the estimator, not to this crate.
//! * **9.** Euler at `T = 1 ms` for the estimator; [`PlanarTruck`] is also a
//!   [`models::DifferentiableContinuousModel`], so `models::Discretized` gives RK4 variants.
//!
//! # Example
//!
//! ```
//! use models::{DiscreteModel, check_jacobians};
//! use nalgebra::DVector;
//! use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams};
//!
//! let model = TruckEkfModel::paper(TruckParams::digest_preset())?;
//! // Cornering at 70 km/h with slight drive slip on the rear axles.
//! let x = DVector::from_vec(vec![19.44, 0.1, 0.05]);
//! let mut input = TruckInput::free_rolling(0.02, 19.44, 0.52);
//! input.omega[2..].iter_mut().for_each(|w| *w *= 1.003);
//! let u = input.to_dvector();
//! let mut next = DVector::zeros(3);
//! model.f(&x, &u, &mut next)?;
//! let check = check_jacobians(&model, &x, &u)?;
//! assert!(check.f_error < 1e-7 && check.h_error < 1e-7);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod curve_enclosure;
pub mod enclosure;
pub mod error;
pub mod kinematics;
pub mod params;
pub mod planar;
pub mod truth;
pub mod tyre;

pub use error::TruckError;
pub use kinematics::{
    Geometry, WHEEL_NAMES, WHEELS, WheelGradients, WheelKinematics, wheel_gradients, wheel_kinematics,
};
pub use params::TruckParams;
pub use planar::{
    INPUT_DIM, INPUT_NAMES, OUTPUT_DIM, PAPER_SAMPLE_PERIOD, PlanarTruck, STATE_DIM, STATE_NAMES, TruckEkfModel,
    TruckInput, sideslip,
};
pub use truth::{
    LOAD_TRANSFER_PASSES, Slalom, TRUTH_INPUT_DIM, TRUTH_OUTPUT_DIM, TRUTH_STATE_DIM, TRUTH_STATE_NAMES, TruthConfig,
    TruthEvaluation, TruthModel, TruthSample, TruthTrajectory, simulate_truth,
};
pub use tyre::{MagicFormula, Pac89Coefficients, Pac89Tyre, TyreForce};
