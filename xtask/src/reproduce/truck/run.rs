//! One EKF run over a truth trajectory (the digest's settings, seeded measurement noise), its
//! timing, and its metrics (digest §5 "Metrics").

use estimators::{DataChecks, Setup};
use std::time::Instant;

use estimators::{ExtendedKalmanFilter, KalmanFilter, StepModel};
use models::{DifferentiableModel, DiscreteModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use truck_dynamics::{TruckEkfModel, TruckInput, TruthTrajectory};

use super::cases::Case;

/// Measurement standard deviations of `V_x` \[m/s\], `a_y` \[m/s²\], `γ` \[rad/s\] (digest §4, A).
pub const SIGMA: [f64; 3] = [0.05, 0.05, 0.002];
/// Continuous process-noise intensities `q_c`; `Q = T·diag(q_c)` (digest §4, A, tuned V).
pub const QC: [f64; 3] = [1e-4, 1e-4, 1e-6];
/// Initial standard deviations; `P0 = diag(σ0²)` (digest §4, A).
pub const P0_SIGMA: [f64; 3] = [0.1, 0.1, 0.01];
/// Initial estimate `x̂0 = [19.44, 0, 0]` (digest §4, A), before a case's `V_y0` error.
pub const X0: [f64; 3] = [19.44, 0.0, 0.0];
/// Start of the "after the initial transient" window \[s\] (digest: 2–12 s).
pub const SETTLE_TIME: f64 = 2.0;
/// `β` has converged once `|e_β|` stays below this fraction of the truth's `max |β|`.
pub const CONVERGENCE_FRACTION: f64 = 0.1;

/// The EKF's settings as written to `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct EkfSettings {
    /// Filter period `T` \[s\] (the paper's 1 ms).
    pub period_s: f64,
    /// `q_c` of `Q = T·diag(q_c)`.
    pub qc: [f64; 3],
    /// Measurement standard deviations (`R = diag(σ²)`), `[V_x, a_y, γ]` in SI units.
    pub r_sigma: [f64; 3],
    /// Initial standard deviations (`P0 = diag(σ0²)`), SI units.
    pub p0_sigma: [f64; 3],
    /// Initial estimate before a case's `V_y0` error.
    pub x0: [f64; 3],
}

impl EkfSettings {
    /// The digest's settings (§4, all assumed).
    #[must_use]
    pub fn digest() -> Self {
        Self { period_s: truck_dynamics::PAPER_SAMPLE_PERIOD, qc: QC, r_sigma: SIGMA, p0_sigma: P0_SIGMA, x0: X0 }
    }
}

fn diag(v: [f64; 3]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_row_slice(&v))
}

/// `Q`, `R`, `P0` of the digest for period `ts`.
fn noise_matrices(ts: f64) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    (diag(QC.map(|q| q * ts)), diag(SIGMA.map(|s| s * s)), diag(P0_SIGMA.map(|s| s * s)))
}

/// One run: truth and estimate of `[V_x, V_y, γ, β]` (SI: m/s, rad/s, rad) with the estimate's
/// standard deviations, at `t_k = k·T` for `k = 0..N` (`k = 0` is the initial estimate), and the
/// wall time of each EKF step.
#[derive(Debug, Clone)]
pub struct Trace {
    /// Times \[s\].
    pub t: Vec<f64>,
    /// Truth `[V_x, V_y, γ, β]`.
    pub truth: Vec<[f64; 4]>,
    /// Estimate `[V̂_x, V̂_y, γ̂, β̂]`, `β̂ = atan(V̂_y/V̂_x)` (2).
    pub estimate: Vec<[f64; 4]>,
    /// Standard deviations of the estimate; that of `β̂` by first-order propagation of `P`.
    pub sigma: Vec<[f64; 4]>,
    /// Nanoseconds spent in each `ExtendedKalmanFilter::step` (nothing else is timed).
    pub step_ns: Vec<u64>,
}

/// `[V̂_x, V̂_y, γ̂, β̂]` and their standard deviations from a mean and covariance.
fn with_sideslip(mean: &DVector<f64>, cov: &DMatrix<f64>) -> Result<([f64; 4], [f64; 4]), String> {
    let (vx, vy) = (mean[0], mean[1]);
    let beta = truck_dynamics::sideslip(vx, vy).map_err(|e| format!("estimated sideslip: {e}"))?;
    let d = vx * vx + vy * vy;
    let (gx, gy) = (-vy / d, vx / d);
    let var_beta = gx * gx * cov[(0, 0)] + 2.0 * gx * gy * cov[(0, 1)] + gy * gy * cov[(1, 1)];
    let sd = |i: usize| cov[(i, i)].max(0.0).sqrt();
    Ok(([vx, vy, mean[2], beta], [sd(0), sd(1), sd(2), var_beta.max(0.0).sqrt()]))
}

/// The random streams of one seed: measurement noise and (independent) wheel-speed noise.
fn streams(seed: u64) -> (Xoshiro256StarStar, Xoshiro256StarStar) {
    let meas = Xoshiro256StarStar::seed_from_u64(seed);
    let mut wheels = meas.clone();
    wheels.jump();
    (meas, wheels)
}

/// Runs the digest's EKF with the nominal `model` over `truth` for `case` and `seed`: input
/// `u_k = [δ_k, ω̃_k]` (the truth's wheel speeds, with the case's noise), measurement
/// `y_{k+1} = [V_x, a_y, γ](t_{k+1}) + v`, `v ~ N(0, diag(σ²))` from the seeded xoshiro256\*\*
/// stream (the same noise for every case with the same seed: paired comparisons).
///
/// # Errors
/// A failed EKF step or an estimate with `V̂_x ≤ 0`, naming the case and step.
pub fn run_ekf(truth: &TruthTrajectory, model: &TruckEkfModel, case: &Case, seed: u64) -> Result<Trace, String> {
    let n = truth.len();
    if n < 2 {
        return Err(format!("{}: the truth has {n} samples", case.id));
    }
    let (q, r, p0) = noise_matrices(model.ts());
    let x0 = DVector::from_vec(vec![X0[0], X0[1] + case.vy0_error, X0[2]]);
    let mut ekf = ExtendedKalmanFilter::new(Setup {
        x0: x0.clone(),
        p0: p0.clone(),
        process_noise: q,
        measurement_noise: r,
        inputs: model.dims().inputs,
    })
    .map_err(|e| format!("{}: EKF: {e}", case.id))?;
    let (mut meas, mut wheels) = streams(seed);
    let mut trace = Trace {
        t: Vec::with_capacity(n),
        truth: Vec::with_capacity(n),
        estimate: Vec::with_capacity(n),
        sigma: Vec::with_capacity(n),
        step_ns: Vec::with_capacity(n - 1),
    };
    let truth_row = |k: usize| {
        let s = &truth.samples[k];
        [s.vx, s.vy, s.gamma, s.beta]
    };
    let (e0, s0) = with_sideslip(&x0, &p0)?;
    trace.t.push(truth.samples[0].t);
    trace.truth.push(truth_row(0));
    trace.estimate.push(e0);
    trace.sigma.push(s0);
    let mut u = DVector::zeros(model.dims().inputs);
    let mut y = DVector::zeros(3);
    for k in 0..n - 1 {
        let input = truth.estimator_input(k).ok_or("missing truth input")?;
        u[0] = input.delta;
        for j in 0..input.omega.len() {
            u[1 + j] = input.omega[j] * (1.0 + case.wheel_speed_noise * wheels.standard_normal());
        }
        let z = truth.measurement(k + 1).ok_or("missing truth measurement")?;
        for i in 0..3 {
            y[i] = z[i] + SIGMA[i] * meas.standard_normal();
        }
        let t0 = Instant::now();
        let result = ekf.step(model, &u, &y);
        let ns = t0.elapsed().as_nanos();
        let est = result.map_err(|e| format!("{}: EKF step {k}: {e}", case.id))?;
        let (e, s) = with_sideslip(&est.center, &est.covariance).map_err(|e| format!("{}: step {k}: {e}", case.id))?;
        trace.step_ns.push(u64::try_from(ns).unwrap_or(u64::MAX));
        trace.t.push(truth.samples[k + 1].t);
        trace.truth.push(truth_row(k + 1));
        trace.estimate.push(e);
        trace.sigma.push(s);
    }
    Ok(trace)
}

/// Times a linear Kalman filter of the EKF's size (3 states, 7 inputs, 3 outputs) on the same
/// measurements: `A`, `C` are the EKF model's Jacobians at `x̂0` in straight running, `B = 0`.
/// This is the cost of the matrix algebra alone, without the tyre model and its Jacobians.
///
/// # Errors
/// A model or filter error.
pub fn kalman_step_timing(truth: &TruthTrajectory, model: &TruckEkfModel, seed: u64) -> Result<StepTiming, String> {
    let d = model.dims();
    let x0 = DVector::from_row_slice(&X0);
    let u0 = TruckInput::free_rolling(0.0, X0[0], model.planar().params().rolling_radius).to_dvector();
    let (mut a, b, mut c) =
        (DMatrix::zeros(d.states, d.states), DMatrix::zeros(d.states, d.inputs), DMatrix::zeros(3, 3));
    model.f_jacobian(&x0, &u0, &mut a).map_err(|e| e.to_string())?;
    model.h_jacobian(&x0, &u0, &mut c).map_err(|e| e.to_string())?;
    let (q, r, p0) = noise_matrices(model.ts());
    let mut kf = KalmanFilter::new(Setup { x0, p0, process_noise: q, measurement_noise: r, inputs: d.inputs })
        .map_err(|e| e.to_string())?;
    kf.set_data_checks(DataChecks::OFF).map_err(|e| e.to_string())?;
    let lin = StepModel::new(&a, &b, &c);
    let (mut meas, _) = streams(seed);
    let mut y = DVector::zeros(3);
    let mut ns = Vec::with_capacity(truth.len());
    for k in 0..truth.len().saturating_sub(1) {
        let z = truth.measurement(k + 1).ok_or("missing truth measurement")?;
        for i in 0..3 {
            y[i] = z[i] + SIGMA[i] * meas.standard_normal();
        }
        let t0 = Instant::now();
        let result = kf.step(&lin, &u0, &y);
        let dt = t0.elapsed().as_nanos();
        result.map_err(|e| format!("Kalman step {k}: {e}"))?;
        ns.push(u64::try_from(dt).unwrap_or(u64::MAX));
    }
    Ok(StepTiming::of(ns))
}

pub use crate::reproduce::runner::StepTiming;

/// Error statistics of one signal over one time window.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct ErrorStats {
    /// `max |e|`.
    pub max_abs: f64,
    /// Root mean square of `e`.
    pub rmse: f64,
    /// Mean of `|e|`.
    pub mean_abs: f64,
}

impl ErrorStats {
    /// Statistics of `errors` (NaN for an empty window).
    pub fn of(errors: impl Iterator<Item = f64>) -> Self {
        let (mut max, mut sq, mut abs, mut n) = (0.0f64, 0.0, 0.0, 0usize);
        for e in errors {
            max = max.max(e.abs());
            sq += e * e;
            abs += e.abs();
            n += 1;
        }
        if n == 0 {
            return Self { max_abs: f64::NAN, rmse: f64::NAN, mean_abs: f64::NAN };
        }
        Self { max_abs: max, rmse: (sq / n as f64).sqrt(), mean_abs: abs / n as f64 }
    }
}

/// Error statistics of one signal over the digest's windows.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct SignalErrors {
    /// Over the whole run, `0 ≤ t ≤ t_end` (the initial estimate included).
    pub whole: ErrorStats,
    /// Over the initial transient, `t < 2 s`.
    pub first_2s: ErrorStats,
    /// After it, `2 s ≤ t ≤ t_end`.
    pub after_2s: ErrorStats,
}

impl SignalErrors {
    fn of(t: &[f64], e: &[f64]) -> Self {
        let window =
            |keep: &dyn Fn(f64) -> bool| ErrorStats::of(t.iter().zip(e).filter(|(t, _)| keep(**t)).map(|(_, e)| *e));
        Self {
            whole: window(&|_| true),
            first_2s: window(&|t| t < SETTLE_TIME - 1e-9),
            after_2s: window(&|t| t >= SETTLE_TIME - 1e-9),
        }
    }
}

/// The metrics of one run (one case, one seed); `γ` in °/s, `β` in degrees.
#[derive(Debug, Clone, Serialize)]
pub struct SeedMetrics {
    /// Seed of the noise streams.
    pub seed: u64,
    /// Errors of `V̂_x` \[m/s\].
    pub vx_mps: SignalErrors,
    /// Errors of `γ̂` \[°/s\].
    pub gamma_degps: SignalErrors,
    /// Errors of `β̂` \[°\].
    pub beta_deg: SignalErrors,
    /// Time \[s\] after which `|e_β|` stays below 10 % of the truth's `max |β|` until the end
    /// (0 if it never exceeds it; `None` if it exceeds it at the last sample).
    pub beta_convergence_s: Option<f64>,
    /// Share of samples with `|e_β| ≤ 2σ_β` (the filter's own uncertainty).
    pub beta_within_2sigma: f64,
}

/// The metrics of `trace`; `beta_threshold` \[rad\] is the convergence threshold.
#[must_use]
pub fn seed_metrics(trace: &Trace, seed: u64, beta_threshold: f64) -> SeedMetrics {
    let err = |i: usize, scale: f64| -> Vec<f64> {
        trace.estimate.iter().zip(&trace.truth).map(|(e, x)| (e[i] - x[i]) * scale).collect()
    };
    let deg = 180.0 / std::f64::consts::PI;
    let e_beta = err(3, 1.0);
    let last_bad = e_beta.iter().rposition(|e| e.abs() >= beta_threshold);
    let beta_convergence_s = match last_bad {
        None => Some(0.0),
        Some(k) => trace.t.get(k + 1).copied(),
    };
    let inside = e_beta.iter().zip(&trace.sigma).filter(|(e, s)| e.abs() <= 2.0 * s[3]).count();
    SeedMetrics {
        seed,
        vx_mps: SignalErrors::of(&trace.t, &err(0, 1.0)),
        gamma_degps: SignalErrors::of(&trace.t, &err(2, deg)),
        beta_deg: SignalErrors::of(&trace.t, &err(3, deg)),
        beta_convergence_s,
        beta_within_2sigma: inside as f64 / e_beta.len().max(1) as f64,
    }
}

/// Mean, standard deviation (over seeds, `n − 1`), smallest and largest of a metric.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one value).
    pub std: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// The spread of `values` (NaN for none).
    #[must_use]
    pub fn of(values: &[f64]) -> Self {
        let n = values.len();
        if n == 0 {
            return Self { mean: f64::NAN, std: f64::NAN, min: f64::NAN, max: f64::NAN };
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let var = if n > 1 { values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64 } else { 0.0 };
        let min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Self { mean, std: var.sqrt(), min, max }
    }
}

/// [`ErrorStats`] over seeds.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StatsSpread {
    /// `max |e|` over seeds.
    pub max_abs: Spread,
    /// RMSE over seeds.
    pub rmse: Spread,
    /// Mean `|e|` over seeds.
    pub mean_abs: Spread,
}

/// [`SignalErrors`] over seeds.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SignalSpread {
    /// Whole run.
    pub whole: StatsSpread,
    /// `t < 2 s`.
    pub first_2s: StatsSpread,
    /// `t ≥ 2 s`.
    pub after_2s: StatsSpread,
}

/// A case's metrics over its seeds.
#[derive(Debug, Clone, Serialize)]
pub struct Aggregate {
    /// `V_x` errors \[m/s\].
    pub vx_mps: SignalSpread,
    /// `γ` errors \[°/s\].
    pub gamma_degps: SignalSpread,
    /// `β` errors \[°\].
    pub beta_deg: SignalSpread,
    /// Convergence time of `β` \[s\] over the seeds where it converged.
    pub beta_convergence_s: Spread,
    /// Seeds where `β` had not converged by the end of the run.
    pub beta_not_converged: usize,
    /// Share of samples with `|e_β| ≤ 2σ_β`.
    pub beta_within_2sigma: Spread,
}

/// Aggregates per-seed metrics.
#[must_use]
pub fn aggregate(seeds: &[SeedMetrics]) -> Aggregate {
    let stats = |f: &dyn Fn(&SeedMetrics) -> ErrorStats| {
        let v: Vec<ErrorStats> = seeds.iter().map(f).collect();
        StatsSpread {
            max_abs: Spread::of(&v.iter().map(|s| s.max_abs).collect::<Vec<_>>()),
            rmse: Spread::of(&v.iter().map(|s| s.rmse).collect::<Vec<_>>()),
            mean_abs: Spread::of(&v.iter().map(|s| s.mean_abs).collect::<Vec<_>>()),
        }
    };
    let signal = |f: &dyn Fn(&SeedMetrics) -> SignalErrors| SignalSpread {
        whole: stats(&|m| f(m).whole),
        first_2s: stats(&|m| f(m).first_2s),
        after_2s: stats(&|m| f(m).after_2s),
    };
    let converged: Vec<f64> = seeds.iter().filter_map(|m| m.beta_convergence_s).collect();
    Aggregate {
        vx_mps: signal(&|m| m.vx_mps),
        gamma_degps: signal(&|m| m.gamma_degps),
        beta_deg: signal(&|m| m.beta_deg),
        beta_convergence_s: Spread::of(&converged),
        beta_not_converged: seeds.len() - converged.len(),
        beta_within_2sigma: Spread::of(&seeds.iter().map(|m| m.beta_within_2sigma).collect::<Vec<_>>()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trace(errors_deg: &[f64]) -> Trace {
        let n = errors_deg.len();
        Trace {
            t: (0..n).map(|k| k as f64).collect(),
            truth: vec![[20.0, 0.0, 0.0, 0.0]; n],
            estimate: errors_deg.iter().map(|e| [20.0, 0.0, 0.0, e.to_radians()]).collect(),
            sigma: vec![[0.0, 0.0, 0.0, 0.5f64.to_radians()]; n],
            step_ns: vec![],
        }
    }

    #[test]
    fn metrics_windows_and_convergence() {
        // Samples at t = 0..5 s; threshold 0.2°.
        let m = seed_metrics(&trace(&[1.0, -0.5, 0.3, 0.1, -0.1, 0.0]), 7, 0.2f64.to_radians());
        assert_eq!(m.seed, 7);
        assert!((m.beta_deg.whole.max_abs - 1.0).abs() < 1e-12);
        assert!((m.beta_deg.first_2s.max_abs - 1.0).abs() < 1e-12);
        assert!((m.beta_deg.after_2s.max_abs - 0.3).abs() < 1e-12);
        let rmse = ((0.09 + 0.01 + 0.01 + 0.0) / 4.0f64).sqrt();
        assert!((m.beta_deg.after_2s.rmse - rmse).abs() < 1e-12);
        assert!((m.beta_deg.first_2s.mean_abs - 0.75).abs() < 1e-12);
        // Last sample at or above 0.2° is t = 2 (0.3°): converged from t = 3 s.
        assert_eq!(m.beta_convergence_s, Some(3.0));
        // |e| ≤ 2σ = 1°: all six samples.
        assert!((m.beta_within_2sigma - 1.0).abs() < 1e-12);
        assert_eq!(seed_metrics(&trace(&[0.1, 0.0]), 0, 0.2f64.to_radians()).beta_convergence_s, Some(0.0));
        assert_eq!(seed_metrics(&trace(&[0.0, 0.5]), 0, 0.2f64.to_radians()).beta_convergence_s, None);
    }

    #[test]
    fn spreads_and_timing() {
        let s = Spread::of(&[1.0, 2.0, 3.0]);
        assert_eq!((s.mean, s.std, s.min, s.max), (2.0, 1.0, 1.0, 3.0));
        assert!(Spread::of(&[]).mean.is_nan());
        let t = StepTiming::of((1..=100).map(|v| v * 1000).collect());
        assert_eq!((t.steps_timed, t.median_us, t.p99_us, t.max_us), (100, 51.0, 99.0, 100.0));
        let a = aggregate(&[
            seed_metrics(&trace(&[0.0, 0.5]), 0, 0.2f64.to_radians()),
            seed_metrics(&trace(&[0.5, 0.0]), 1, 0.2f64.to_radians()),
        ]);
        assert_eq!(a.beta_not_converged, 1);
        assert_eq!(a.beta_convergence_s.mean, 1.0);
    }
}
