//! Loosely coupled BDS/INS positioning of a port vehicle (Yang, Chi & Yao, Shanghai Maritime
//! University; digest `shared/papers/bds-ins-fuzzy-kf.md`, method note
//! `docs/bds-ins-fuzzy-kf.md`): the INS error model, its discretisation and measurement, and a
//! simulator of the BDS receiver. The fuzzy-adaptive filter itself lives in
//! `estimators::adaptive`; this crate knows nothing of estimation.
//!
//! The paper's error model (10) and measurement (13) are lost, so they are reconstructed
//! **\[R\]** (Qin; Groves; PSINS `etm.m`); **\[P\]** marks the paper, **\[A\]** assumptions.
//!
//! * [`InsErrorModel`]: the 13-state planar φ-angle error model (10) in the paper's state order
//!   ([`idx`]), with Earth rate and latitude or the "flat" option ([`Earth`]), nav-frame or
//!   body-frame biases ([`BiasFrame`]); [`InsErrorModel::discretize`] gives the exact `Φ = e^{FT}`
//!   and Van Loan's `Q_k` (1) as a [`DiscreteInsModel`] (a `models::LinearModel`).
//! * [`measurement_matrix`] (the explicit `H` of (13)), [`measurement`] (INS − BDS with the
//!   heading difference wrapped to `(−π, π]` by [`wrap_angle`]), [`correct`] (output correction).
//! * [`BdsSimulator`]: white noise plus a Gauss–Markov bias per [`Zone`], the RTK status
//!   ([`RtkStatus`], the paper's codes) and the satellite count per epoch, outages.
//! * [`simulate_error_states`]: the error-state truth of the paper's simulation.
//! * [`scenario`]: the data of experiments (a) and (b).
//!
//! # Example
//!
//! ```
//! use bds_ins_dynamics::{InsErrorModel, InsNoise, InsParams, idx};
//!
//! let model = InsErrorModel::new(InsParams::digest(), InsNoise::digest())?.discretize(1.0)?;
//! // A north tilt makes the east velocity error grow as −g·δθy·T.
//! let phi = &model.phi;
//! assert!((phi[(idx::DVE, idx::DTHY)] + 9.7803).abs() < 1e-3);
//! # Ok::<(), bds_ins_dynamics::BdsInsError>(())
//! ```

pub mod bds;
pub mod error;
pub mod model;
pub mod params;
pub mod scenario;
pub mod truth;

pub use bds::{BdsEpoch, BdsFix, BdsSimulator, RtkStatus, Zone};
pub use error::BdsInsError;
pub use model::{
    DiscreteInsModel, InsErrorModel, MEASUREMENTS, NOISE_INPUTS, STATE_NAMES, STATES, correct, idx, measurement,
    measurement_matrix, wrap_angle,
};
pub use params::{
    ARCSEC, BiasFrame, DEG_PER_HOUR, DIGEST_LATITUDE, EARTH_RADIUS, EARTH_RATE, Earth, GRAVITY, InsNoise, InsParams,
};
pub use truth::{GaussianSampler, simulate_error_states};
