//! A reusable closed-loop runner: plant → measurement → estimator → controller → plant
//! (docs/dp-vessel.md §3, "closed loop"), generic over any [`DiscreteModel`] plant, any
//! estimator of the `estimators` crate (its object-safe [`DynEstimator`] face, over the model the
//! estimator is given, which may differ from the plant) and a [`Controller`].
//!
//! One run, for `k = 0 … steps − 1`:
//!
//! ```text
//! τ_k      = controller(k, x̂_k)                 (x̂_0: the estimator's initial estimate)
//! x_{k+1}  = f(x_k, τ_k + w_τ,k) + w_k            (input noise w_τ, e.g. force noise; process noise w)
//! z_{k+1}  = h(x_{k+1}, τ_k) + v_{k+1}
//! x̂_{k+1}  = estimator.step(τ_k, z_{k+1})         (the estimator convention: u_k, then y_{k+1})
//! ```
//!
//! The estimator sees the commanded `τ_k`, never the noise. `z_0` is drawn and recorded (for
//! tables of raw measurements) but not given to the estimator, whose `x̂_0` is its prior. The three
//! noises come from independent streams of one seed (xoshiro256** jumps), so a seed reproduces a
//! run.

use std::time::Instant;

use estimators::{DynEstimator, EstimatorError};
use models::{DiscreteModel, ModelError, Noise, Xoshiro256StarStar};
use nalgebra::DVector;
use thiserror::Error;

/// A controller in the loop.
pub trait Controller {
    /// The controller's error.
    type Error: std::error::Error + Send + Sync + 'static;
    /// Number of inputs it produces.
    fn input_dim(&self) -> usize;
    /// Writes the input `u_k` for the estimate `x̂_k` into `u`.
    ///
    /// # Errors
    /// Whatever the controller rejects.
    fn control(&mut self, k: usize, x_hat: &DVector<f64>, u: &mut DVector<f64>) -> Result<(), Self::Error>;
    /// The reference used by the last [`Controller::control`] (recorded when present).
    fn reference(&self) -> Option<&[f64]> {
        None
    }
    /// Element-wise input limits `|u_i| ≤ limit_i`, if the controller has them (the runner checks
    /// them and records saturation).
    fn input_limits(&self) -> Option<&[f64]> {
        None
    }
}

/// The run's settings.
#[derive(Debug, Clone)]
pub struct LoopConfig {
    /// Initial true state `x_0`.
    pub x0: DVector<f64>,
    /// Number of steps.
    pub steps: usize,
    /// Sampling period (for the time axis) \[s\].
    pub ts: f64,
    /// Noise added to the commanded input before it reaches the plant (dimension `p`).
    pub input_noise: Noise,
    /// Additive process noise on the state (dimension `n`).
    pub process_noise: Noise,
    /// Measurement noise (dimension `m`).
    pub measurement_noise: Noise,
    /// Seed of the three noise streams.
    pub seed: u64,
}

/// Everything a run produced, stored row-wise in flat vectors (`k · dim + i`).
#[derive(Debug, Clone, PartialEq)]
pub struct LoopRecord {
    /// `n`, `p`, `m`.
    pub dims: models::Dims,
    /// Sampling period \[s\].
    pub ts: f64,
    /// Number of steps (`steps + 1` states).
    pub steps: usize,
    /// True states `x_0 … x_steps`.
    pub states: Vec<f64>,
    /// Estimates `x̂_0 … x̂_steps`.
    pub estimates: Vec<f64>,
    /// Measurements `z_0 … z_steps`.
    pub measurements: Vec<f64>,
    /// Commanded inputs `u_0 … u_{steps−1}`.
    pub inputs: Vec<f64>,
    /// References of the controller at `t_0 … t_{steps−1}` (empty if it has none), with their
    /// dimension.
    pub references: Vec<f64>,
    /// Dimension of a reference (0 if none).
    pub reference_dim: usize,
    /// Per step and input: whether `|u_i|` reached its limit (empty without limits).
    pub saturated: Vec<bool>,
    /// Wall time of each estimator step \[s\] (`steps` entries).
    pub estimator_seconds: Vec<f64>,
}

impl LoopRecord {
    /// `x_k`.
    #[must_use]
    pub fn state(&self, k: usize) -> &[f64] {
        let n = self.dims.states;
        &self.states[k * n..(k + 1) * n]
    }
    /// `x̂_k`.
    #[must_use]
    pub fn estimate(&self, k: usize) -> &[f64] {
        let n = self.dims.states;
        &self.estimates[k * n..(k + 1) * n]
    }
    /// `z_k`.
    #[must_use]
    pub fn measurement(&self, k: usize) -> &[f64] {
        let m = self.dims.outputs;
        &self.measurements[k * m..(k + 1) * m]
    }
    /// `u_k`.
    #[must_use]
    pub fn input(&self, k: usize) -> &[f64] {
        let p = self.dims.inputs;
        &self.inputs[k * p..(k + 1) * p]
    }
    /// The reference at `t_k`, if recorded.
    #[must_use]
    pub fn reference(&self, k: usize) -> Option<&[f64]> {
        let d = self.reference_dim;
        (d > 0).then(|| &self.references[k * d..(k + 1) * d])
    }
    /// Time of index `k` \[s\].
    #[must_use]
    pub fn time(&self, k: usize) -> f64 {
        k as f64 * self.ts
    }
}

/// Why a run stopped.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ClosedLoopError {
    /// A dimension of the configuration, the estimator or the controller does not match the plant.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// What has the wrong size.
        what: &'static str,
        /// The plant's dimension.
        expected: usize,
        /// The given one.
        found: usize,
    },
    /// A setting is out of range (no steps, a non-positive period, a non-finite `x_0`).
    #[error("invalid setting {what}: {reason}")]
    InvalidSetting {
        /// Which setting.
        what: &'static str,
        /// Why.
        reason: String,
    },
    /// The plant could not be evaluated.
    #[error("plant at step {step}: {source}")]
    Plant {
        /// The step.
        step: usize,
        /// The model's error.
        source: ModelError,
    },
    /// The plant's state left the range of `f64`.
    #[error("plant diverged at step {step}")]
    Diverged {
        /// The first step with a non-finite state.
        step: usize,
    },
    /// The estimator refused a step.
    #[error("estimator at step {step}: {source}")]
    Estimator {
        /// The step.
        step: usize,
        /// The estimator's error.
        source: EstimatorError,
    },
    /// The controller failed.
    #[error("controller at step {step}: {source}")]
    Controller {
        /// The step.
        step: usize,
        /// The controller's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The controller returned an input beyond its own limits or not finite.
    #[error("controller at step {step}: input {index} = {value} violates its limit {limit}")]
    LimitViolated {
        /// The step.
        step: usize,
        /// Input component.
        index: usize,
        /// The value returned.
        value: f64,
        /// Its limit.
        limit: f64,
    },
}

fn check_dim(what: &'static str, expected: usize, found: usize) -> Result<(), ClosedLoopError> {
    if expected == found { Ok(()) } else { Err(ClosedLoopError::DimensionMismatch { what, expected, found }) }
}

/// Runs the loop (see the module documentation).
///
/// # Errors
/// [`ClosedLoopError`] naming the mismatched dimension, invalid setting, or the step at which the
/// plant, estimator or controller failed.
pub fn run_closed_loop<P, M, E, C>(
    plant: &P,
    model: &M,
    estimator: &mut E,
    controller: &mut C,
    config: &LoopConfig,
) -> Result<LoopRecord, ClosedLoopError>
where
    P: DiscreteModel + ?Sized,
    M: ?Sized,
    E: DynEstimator<M> + ?Sized,
    C: Controller + ?Sized,
{
    let dims = plant.dims();
    let (n, p, m) = (dims.states, dims.inputs, dims.outputs);
    check_dim("x0", n, config.x0.len())?;
    check_dim("estimator states", n, estimator.estimate_dyn().center().len())?;
    check_dim("estimator inputs", p, estimator.dims_dyn().inputs)?;
    check_dim("estimator measurements", m, estimator.dims_dyn().outputs)?;
    check_dim("controller inputs", p, controller.input_dim())?;
    check_dim("input noise", p, config.input_noise.dim())?;
    check_dim("process noise", n, config.process_noise.dim())?;
    check_dim("measurement noise", m, config.measurement_noise.dim())?;
    if let Some(l) = controller.input_limits() {
        check_dim("input limits", p, l.len())?;
    }
    if config.steps == 0 {
        return Err(ClosedLoopError::InvalidSetting { what: "steps", reason: "at least one step".into() });
    }
    if !(config.ts.is_finite() && config.ts > 0.0) {
        return Err(ClosedLoopError::InvalidSetting {
            what: "ts",
            reason: format!("must be positive, got {}", config.ts),
        });
    }
    if config.x0.iter().any(|v| !v.is_finite()) {
        return Err(ClosedLoopError::InvalidSetting { what: "x0", reason: "has a non-finite entry".into() });
    }
    let mut root = Xoshiro256StarStar::seed_from_u64(config.seed);
    let mut rng_input = root.clone();
    root.jump();
    let mut rng_process = root.clone();
    root.jump();
    let mut rng_meas = root;

    let steps = config.steps;
    let mut rec = LoopRecord {
        dims,
        ts: config.ts,
        steps,
        states: Vec::with_capacity((steps + 1) * n),
        estimates: Vec::with_capacity((steps + 1) * n),
        measurements: Vec::with_capacity((steps + 1) * m),
        inputs: Vec::with_capacity(steps * p),
        references: Vec::new(),
        reference_dim: 0,
        saturated: Vec::new(),
        estimator_seconds: Vec::with_capacity(steps),
    };
    let mut x = config.x0.clone();
    let mut x_next = DVector::zeros(n);
    let mut z = DVector::zeros(m);
    let mut u = DVector::zeros(p);
    let mut u_applied = DVector::zeros(p);
    let measure = |x: &DVector<f64>, u: &DVector<f64>, z: &mut DVector<f64>, rng: &mut Xoshiro256StarStar, k| {
        plant.h(x, u, z).map_err(|source| ClosedLoopError::Plant { step: k, source })?;
        *z += config.measurement_noise.sample(rng);
        Ok::<(), ClosedLoopError>(())
    };
    measure(&x, &u, &mut z, &mut rng_meas, 0)?;
    rec.states.extend(x.iter());
    rec.measurements.extend(z.iter());
    rec.estimates.extend(estimator.estimate_dyn().center().iter());
    for k in 0..steps {
        controller
            .control(k, estimator.estimate_dyn().center(), &mut u)
            .map_err(|e| ClosedLoopError::Controller { step: k, source: Box::new(e) })?;
        check_dim("controller output", p, u.len())?;
        if let Some(limits) = controller.input_limits() {
            for i in 0..p {
                let (v, l) = (u[i], limits[i]);
                if !(v.is_finite() && v.abs() <= l) {
                    return Err(ClosedLoopError::LimitViolated { step: k, index: i, value: v, limit: l });
                }
                rec.saturated.push(v.abs() >= l * (1.0 - 1e-12));
            }
        }
        if let Some(r) = controller.reference() {
            if k == 0 {
                rec.reference_dim = r.len();
                rec.references.reserve(steps * r.len());
            }
            check_dim("controller reference", rec.reference_dim, r.len())?;
            rec.references.extend_from_slice(r);
        }
        rec.inputs.extend(u.iter());
        u_applied.copy_from(&u);
        u_applied += config.input_noise.sample(&mut rng_input);
        plant.f(&x, &u_applied, &mut x_next).map_err(|source| ClosedLoopError::Plant { step: k, source })?;
        x_next += config.process_noise.sample(&mut rng_process);
        if x_next.iter().any(|v| !v.is_finite()) {
            return Err(ClosedLoopError::Diverged { step: k + 1 });
        }
        std::mem::swap(&mut x, &mut x_next);
        measure(&x, &u, &mut z, &mut rng_meas, k + 1)?;
        let t0 = Instant::now();
        estimator.step_dyn(model, &u, &z).map_err(|source| ClosedLoopError::Estimator { step: k + 1, source })?;
        rec.estimator_seconds.push(t0.elapsed().as_secs_f64());
        rec.states.extend(x.iter());
        rec.measurements.extend(z.iter());
        rec.estimates.extend(estimator.estimate_dyn().center().iter());
    }
    Ok(rec)
}
