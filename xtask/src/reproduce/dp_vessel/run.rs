//! One closed-loop run of the supply vessel (plant → measurement → estimator → NSAMPC → plant,
//! through `vessel_control::run_closed_loop`) and its metrics: settling, overshoot, saturation,
//! total variation of the forces, RMSE of the estimate, Table 1 statistics and time per step.
//!
//! The estimators come from [`ESTIMATORS`], each built by the registry and stepped by the loop
//! through the estimator trait.

use estimators::registry::{self, AnyEstimator, EstimatorSettings, names};
use estimators::{DataChecks, EstimatorError, Setup, UkfParams};
use models::{AnyModel, Noise};
use nalgebra::{DMatrix, DVector, Vector3};
use serde::Serialize;
use vessel_control::{
    LoopConfig, LoopRecord, Nsampc, NsampcParams, ReferenceFilter, SetPoint, VesselController, run_closed_loop,
};
use vessel_dynamics::{DiscreteVessel, ForceNoise, VesselParams};

/// The set point `(50 m, 50 m, 0°)` **\[P\]**.
pub const TARGET: [f64; 3] = [50.0, 50.0, 0.0];
/// Settling band of north and east \[m\] (digest §5).
pub const POSITION_BAND_M: f64 = 1.0;
/// Settling band of the heading \[°\] (digest §5).
pub const HEADING_BAND_DEG: f64 = 1.0;

/// The estimators' settings (digest §4): `Q`, `R`, `x̄₀`, `P₀`, UKF `α, β, κ`.
#[derive(Debug, Clone, Serialize)]
pub struct FilterSettings {
    /// `diag(Q)` **\[P\]** (the MHE/UKF weight `1e−2 I₆`).
    pub q_diag: Vec<f64>,
    /// `diag(R)` (m², m², rad²).
    pub r_diag: Vec<f64>,
    /// `x̄₀` **\[A\]**.
    pub x0: Vec<f64>,
    /// `diag(P₀)` **\[A\]**.
    pub p0_diag: Vec<f64>,
    /// UKF `[α, β, κ]` **\[P\]**.
    pub ukf: [f64; 3],
}

impl FilterSettings {
    /// The digest's settings with heading-noise variance `r_psi` \[rad²\].
    #[must_use]
    pub fn digest(r_psi: f64) -> Self {
        let u = UkfParams::paper();
        Self {
            q_diag: vec![1e-2; 6],
            r_diag: vec![1.0, 1.0, r_psi],
            x0: vec![0.0; 6],
            p0_diag: vec![1.0, 1.0, 0.1, 0.1, 0.1, 0.01],
            ukf: [u.alpha, u.beta, u.kappa],
        }
    }

    fn matrices(&self) -> (DVector<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let diag = |v: &[f64]| DMatrix::from_diagonal(&DVector::from_column_slice(v));
        (DVector::from_column_slice(&self.x0), diag(&self.p0_diag), diag(&self.q_diag), diag(&self.r_diag))
    }
}

/// An estimator of the reproduction.
pub struct EstimatorSpec {
    /// Identifier (file names, JSON).
    pub id: &'static str,
    /// Label for tables and figures.
    pub label: &'static str,
    /// Builds a fresh estimator (through the registry).
    pub build: fn(&FilterSettings) -> Result<AnyEstimator, EstimatorError>,
}

fn setup(s: &FilterSettings) -> Setup {
    let (x0, p0, process_noise, measurement_noise) = s.matrices();
    Setup { x0, p0, process_noise, measurement_noise, inputs: 3 }
}

fn ukf_params(s: &FilterSettings) -> UkfParams {
    UkfParams { alpha: s.ukf[0], beta: s.ukf[1], kappa: s.ukf[2] }
}

fn build_ekf(s: &FilterSettings) -> Result<AnyEstimator, EstimatorError> {
    registry::build(names::EKF, setup(s), None)
}

fn build_ukf(s: &FilterSettings) -> Result<AnyEstimator, EstimatorError> {
    registry::build(names::UKF, setup(s), Some(EstimatorSettings::Unscented(ukf_params(s))))
}

fn mhe(
    s: &FilterSettings,
    prior: estimators::mhe::NonlinearPrior,
    real_time_iterations: Option<usize>,
) -> Result<AnyEstimator, EstimatorError> {
    use estimators::mhe::{NonlinearArrival, NonlinearMheSettings};
    let mut settings = NonlinearMheSettings::paper();
    settings.arrival = NonlinearArrival::Ukf(ukf_params(s));
    settings.prior = prior;
    settings.real_time_iterations = real_time_iterations;
    registry::build(names::MHE_UKF, setup(s), Some(EstimatorSettings::NonlinearMovingHorizon(Box::new(settings))))
}

/// The paper's MHE: prior mean `x̂_{s+1|T}` (the previous estimate), UKF arrival weight.
fn build_mhe(s: &FilterSettings) -> Result<AnyEstimator, EstimatorError> {
    mhe(s, estimators::mhe::NonlinearPrior::Smoothed, None)
}

/// The paper's MHE with `k` real-time iterations per update (Gauss–Newton iterations from the
/// shifted previous window) instead of iterating to the tolerance.
pub fn build_mhe_real_time(s: &FilterSettings, k: usize) -> Result<AnyEstimator, EstimatorError> {
    mhe(s, estimators::mhe::NonlinearPrior::Smoothed, Some(k))
}

fn build_mhe_rti(s: &FilterSettings) -> Result<AnyEstimator, EstimatorError> {
    build_mhe_real_time(s, REAL_TIME_ITERATIONS)
}

/// Real-time iterations of the `mhe-ukf-rti` estimator in the loop.
pub const REAL_TIME_ITERATIONS: usize = 2;

/// The MHE whose arrival UKF keeps its own mean (no measurement counted twice).
fn build_mhe_own_mean(s: &FilterSettings) -> Result<AnyEstimator, EstimatorError> {
    mhe(s, estimators::mhe::NonlinearPrior::ArrivalFilter, None)
}

/// The estimators in the loop, in table order: the paper's MHE with a UKF arrival cost
/// (N = 10, Gauss–Newton on the window), its variants (the arrival UKF's own mean; real-time
/// iterations), then the EKF and the UKF as baselines.
pub const ESTIMATORS: &[EstimatorSpec] = &[
    EstimatorSpec { id: names::MHE_UKF, label: "MHE, UKF arrival cost (N = 10)", build: build_mhe },
    EstimatorSpec { id: "mhe-ukf-own", label: "MHE, arrival UKF with its own mean", build: build_mhe_own_mean },
    EstimatorSpec {
        id: "mhe-ukf-rti",
        label: "MHE, UKF arrival cost, 2 real-time iterations per step",
        build: build_mhe_rti,
    },
    EstimatorSpec { id: names::EKF, label: "EKF", build: build_ekf },
    EstimatorSpec { id: names::UKF, label: "UKF (α = 0.5, β = 2, κ = −2)", build: build_ukf },
];

/// A scenario: how the set point is given and how noisy the heading sensor is.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Scenario {
    /// Identifier.
    pub id: &'static str,
    /// Title.
    pub title: &'static str,
    /// Run B: the set point through the reference filter (else run A, the literal step).
    pub reference_filter: bool,
    /// Heading-noise variance \[rad²\] (digest decision 5: 0.1 rad² or 0.1 deg²).
    pub r_psi: f64,
    /// The filters' `Q` matched to the simulated force noise instead of the paper's `1e−2 I₆`
    /// (a variant of this reproduction, not of the paper).
    pub matched_q: bool,
    /// Whether figures are drawn for it.
    pub figures: bool,
}

/// Run A and run B with the heading noise read as 0.1 rad² (σ = 18°), then both with 0.1 deg²
/// (σ = 0.32°), then run B with the filters' `Q` matched to the simulated force noise (this
/// reproduction's variant: the paper's `Q = 1e−2 I₆` lets velocity noise through to the thrust).
pub const SCENARIOS: [Scenario; 5] = [
    Scenario {
        id: "A",
        title: "run A: literal step, R_ψ = 0.1 rad²",
        reference_filter: false,
        r_psi: 0.1,
        matched_q: false,
        figures: true,
    },
    Scenario {
        id: "B",
        title: "run B: reference filter, R_ψ = 0.1 rad²",
        reference_filter: true,
        r_psi: 0.1,
        matched_q: false,
        figures: true,
    },
    Scenario {
        id: "A_deg2",
        title: "run A: literal step, R_ψ = 0.1 deg²",
        reference_filter: false,
        r_psi: 0.1 * (std::f64::consts::PI / 180.0) * (std::f64::consts::PI / 180.0),
        matched_q: false,
        figures: false,
    },
    Scenario {
        id: "B_deg2",
        title: "run B: reference filter, R_ψ = 0.1 deg²",
        reference_filter: true,
        r_psi: 0.1 * (std::f64::consts::PI / 180.0) * (std::f64::consts::PI / 180.0),
        matched_q: false,
        figures: false,
    },
    Scenario {
        id: "B_matched_Q",
        title: "run B with Q matched to the force noise, R_ψ = 0.1 rad²",
        reference_filter: true,
        r_psi: 0.1,
        matched_q: true,
        figures: true,
    },
];

/// `diag(Q)` matched to the simulated force noise: the Euler step adds `δ M⁻¹ w_τ` to `ν`, so
/// `Q_νν = (δ σ_i / M_ii)²`; positions and heading get no noise in the model, floored at
/// `1e−10` (m², rad²) to keep `Q` positive definite.
///
/// # Errors
/// The vessel's parameters are invalid.
pub fn matched_q_diag() -> Result<Vec<f64>, String> {
    let m = VesselParams::paper().validate().map_err(|e| format!("vessel: {e}"))?.m.diagonal();
    let sigma = ForceNoise::digest().sigma;
    let dt = vessel_dynamics::PAPER_SAMPLE_PERIOD;
    let mut q = vec![1e-10; 3];
    q.extend((0..3).map(|i| (dt * sigma[i] / m[i]).powi(2)));
    Ok(q)
}

/// The estimators' settings of `scenario`.
///
/// # Errors
/// The vessel's parameters are invalid.
pub fn filter_settings(scenario: &Scenario) -> Result<FilterSettings, String> {
    let mut settings = FilterSettings::digest(scenario.r_psi);
    if scenario.matched_q {
        settings.q_diag = matched_q_diag()?;
    }
    Ok(settings)
}

/// Runs one closed loop of `duration_s` seconds.
///
/// # Errors
/// A message naming what failed.
pub fn run_one(scenario: &Scenario, spec: &EstimatorSpec, steps: usize, seed: u64) -> Result<LoopRecord, String> {
    let params = VesselParams::paper();
    let plant = DiscreteVessel::paper(params).map_err(|e| format!("vessel: {e}"))?;
    let settings = filter_settings(scenario)?;
    let mut est = (spec.build)(&settings).map_err(|e| format!("{}: {e}", spec.id))?;
    // The paper's estimators have no data check.
    est.set_data_checks(DataChecks::OFF).map_err(|e| format!("{}: {e}", spec.id))?;
    let target = Vector3::from(TARGET);
    let set_point = if scenario.reference_filter {
        let f = ReferenceFilter::new(ReferenceFilter::DIGEST_OMEGA, plant.ts(), Vector3::zeros())
            .map_err(|e| format!("reference filter: {e}"))?;
        SetPoint::filtered(target, f)
    } else {
        SetPoint::step(target)
    }
    .map_err(|e| format!("set point: {e}"))?;
    let nsampc = Nsampc::new(&params, NsampcParams::paper()).map_err(|e| format!("NSAMPC: {e}"))?;
    let mut controller = VesselController::new(nsampc, set_point);
    let measurement_noise = Noise::gaussian(DMatrix::from_diagonal(&DVector::from_column_slice(&settings.r_diag)))
        .map_err(|e| format!("measurement noise: {e}"))?;
    let config = LoopConfig {
        x0: DVector::zeros(6),
        steps,
        ts: plant.ts(),
        input_noise: ForceNoise::digest().to_noise().map_err(|e| format!("force noise: {e}"))?,
        process_noise: Noise::none(6),
        measurement_noise,
        seed,
    };
    let model: &dyn AnyModel = &plant;
    run_closed_loop(&plant, model, &mut est, &mut controller, &config)
        .map_err(|e| format!("{} / {} / seed {seed}: {e}", scenario.id, spec.id))
}

/// Mean and variance of one signal over the steady window.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct MeanVar {
    /// Mean.
    pub mean: f64,
    /// Variance (population).
    pub var: f64,
}

impl MeanVar {
    fn of(values: impl Iterator<Item = f64>) -> Self {
        let v: Vec<f64> = values.collect();
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
        Self { mean, var }
    }
}

/// The metrics of one run.
#[derive(Debug, Clone, Serialize)]
pub struct RunMetrics {
    /// The seed.
    pub seed: u64,
    /// First time both `|x − 50|` and `|y − 50|` are below the band \[s\] (NaN if never).
    pub arrival_s: f64,
    /// Settling time per axis `[x, y, ψ]`: from then on the error stays in the band \[s\] (NaN if
    /// it never settles).
    pub settling_s: [f64; 3],
    /// Overshoot of north and east beyond the target \[m\] (0 if they never pass it), and the
    /// largest `|ψ|` \[°\] (the heading target is the start heading).
    pub overshoot: [f64; 3],
    /// Fraction of steps at the thrust limit, per axis.
    pub saturation: [f64; 3],
    /// Total variation `Σ|τ_{k+1} − τ_k|` per axis, in units of the axis's limit.
    pub total_variation: [f64; 3],
    /// Largest `|τ_{k+1} − τ_k|` per axis, in units of the limit.
    pub max_jump: [f64; 3],
    /// Standard deviation of `τ` over the steady window, in units of the limit.
    pub steady_tau_std: [f64; 3],
    /// RMSE of `x̂ − x` per state over the whole run (m, m, °, m/s, m/s, °/s).
    pub rmse: [f64; 6],
    /// RMSE per state over the steady window.
    pub rmse_steady: [f64; 6],
    /// Table 1: raw measurements `z` over the steady window (x, y in m; ψ in °).
    pub raw: [MeanVar; 3],
    /// Table 1: filtered `x̂` (x, y, ψ) over the steady window.
    pub filtered: [MeanVar; 3],
    /// Largest position error to the target over the steady window \[m\].
    pub steady_max_position_error_m: f64,
    /// Observer time per step \[ns\] (not in snapshots).
    #[serde(skip)]
    pub step_ns: Vec<u64>,
}

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// Unit factors of the six states for reports (angles in degrees).
pub const STATE_SCALE: [f64; 6] = [1.0, 1.0, DEG, 1.0, 1.0, DEG];

/// The metrics of `rec`, with the steady window `[steady_from_s, end]`.
#[must_use]
pub fn metrics(rec: &LoopRecord, seed: u64, steady_from_s: f64, limits: [f64; 3]) -> RunMetrics {
    let n_states = rec.steps + 1;
    let steady_from = ((steady_from_s / rec.ts).round() as usize).min(rec.steps);
    let err = |k: usize, i: usize| {
        let e = rec.state(k)[i] - TARGET[i];
        if i == 2 { e * DEG } else { e }
    };
    let bands = [POSITION_BAND_M, POSITION_BAND_M, HEADING_BAND_DEG];
    let arrival_s = (0..n_states)
        .find(|&k| err(k, 0).abs() < bands[0] && err(k, 1).abs() < bands[1])
        .map_or(f64::NAN, |k| rec.time(k));
    let settling_s = std::array::from_fn(|i| {
        // Last index outside the band; settled from the next one.
        match (0..n_states).rev().find(|&k| err(k, i).abs() >= bands[i]) {
            None => 0.0,
            Some(k) if k + 1 < n_states => rec.time(k + 1),
            Some(_) => f64::NAN,
        }
    });
    let overshoot = std::array::from_fn(|i| {
        if i == 2 {
            (0..n_states).map(|k| err(k, 2).abs()).fold(0.0, f64::max)
        } else {
            (0..n_states).map(|k| err(k, i)).fold(0.0, f64::max)
        }
    });
    let sat_count =
        |i: usize| (0..rec.steps).filter(|&k| rec.saturated.get(k * 3 + i).copied().unwrap_or(false)).count();
    let saturation = std::array::from_fn(|i| sat_count(i) as f64 / rec.steps as f64);
    let jumps = |i: usize| (1..rec.steps).map(move |k| (rec.input(k)[i] - rec.input(k - 1)[i]).abs() / limits[i]);
    let total_variation = std::array::from_fn(|i| jumps(i).sum());
    let max_jump = std::array::from_fn(|i| jumps(i).fold(0.0, f64::max));
    let steady_tau_std =
        std::array::from_fn(|i| MeanVar::of((steady_from..rec.steps).map(|k| rec.input(k)[i] / limits[i])).var.sqrt());
    let rmse_over = |from: usize| -> [f64; 6] {
        std::array::from_fn(|i| {
            let n = (n_states - from) as f64;
            ((from..n_states).map(|k| ((rec.estimate(k)[i] - rec.state(k)[i]) * STATE_SCALE[i]).powi(2)).sum::<f64>()
                / n)
                .sqrt()
        })
    };
    let raw =
        std::array::from_fn(|i| MeanVar::of((steady_from..n_states).map(|k| rec.measurement(k)[i] * STATE_SCALE[i])));
    let filtered =
        std::array::from_fn(|i| MeanVar::of((steady_from..n_states).map(|k| rec.estimate(k)[i] * STATE_SCALE[i])));
    let steady_max_position_error_m = (steady_from..n_states).map(|k| err(k, 0).hypot(err(k, 1))).fold(0.0, f64::max);
    RunMetrics {
        seed,
        arrival_s,
        settling_s,
        overshoot,
        saturation,
        total_variation,
        max_jump,
        steady_tau_std,
        rmse: rmse_over(0),
        rmse_steady: rmse_over(steady_from),
        raw,
        filtered,
        steady_max_position_error_m,
        step_ns: rec.estimator_seconds.iter().map(|s| (s * 1e9).round() as u64).collect(),
    }
}

/// Mean, smallest and largest over seeds (NaN entries — never settled — are counted apart).
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Spread {
    /// Mean over the seeds with a finite value.
    pub mean: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// Seeds without a finite value (never arrived or settled).
    pub missing: usize,
}

impl Spread {
    /// Over `values`.
    pub fn of(values: impl Iterator<Item = f64>) -> Self {
        let (mut sum, mut n, mut lo, mut hi, mut missing) = (0.0, 0usize, f64::INFINITY, f64::NEG_INFINITY, 0usize);
        for v in values {
            if v.is_finite() {
                sum += v;
                n += 1;
                lo = lo.min(v);
                hi = hi.max(v);
            } else {
                missing += 1;
            }
        }
        if n == 0 {
            return Self { mean: f64::NAN, min: f64::NAN, max: f64::NAN, missing };
        }
        Self { mean: sum / n as f64, min: lo, max: hi, missing }
    }
}

/// Per-axis spreads.
pub type Spread3 = [Spread; 3];

/// Metrics of one (scenario, estimator) over the seeds.
#[derive(Debug, Clone, Serialize)]
pub struct Aggregate {
    /// Arrival time \[s\].
    pub arrival_s: Spread,
    /// Settling time per axis \[s\].
    pub settling_s: Spread3,
    /// Overshoot (m, m, °).
    pub overshoot: Spread3,
    /// Saturation fraction per axis.
    pub saturation: Spread3,
    /// Total variation per axis (in limits).
    pub total_variation: Spread3,
    /// Largest jump per axis (in limits).
    pub max_jump: Spread3,
    /// Steady-window standard deviation of τ (in limits).
    pub steady_tau_std: Spread3,
    /// RMSE per state, whole run.
    pub rmse: [Spread; 6],
    /// RMSE per state, steady window.
    pub rmse_steady: [Spread; 6],
    /// Table 1, raw: mean over seeds of the window mean and variance (x, y, ψ).
    pub raw: [MeanVar; 3],
    /// Table 1, filtered.
    pub filtered: [MeanVar; 3],
    /// Largest steady position error \[m\].
    pub steady_max_position_error_m: Spread,
}

/// Aggregates seeds.
#[must_use]
pub fn aggregate(seeds: &[RunMetrics]) -> Aggregate {
    let s3 = |f: &dyn Fn(&RunMetrics) -> [f64; 3]| -> Spread3 {
        std::array::from_fn(|i| Spread::of(seeds.iter().map(|m| f(m)[i])))
    };
    let s6 = |f: &dyn Fn(&RunMetrics) -> [f64; 6]| -> [Spread; 6] {
        std::array::from_fn(|i| Spread::of(seeds.iter().map(|m| f(m)[i])))
    };
    let mv = |f: &dyn Fn(&RunMetrics) -> [MeanVar; 3]| -> [MeanVar; 3] {
        let n = seeds.len() as f64;
        std::array::from_fn(|i| MeanVar {
            mean: seeds.iter().map(|m| f(m)[i].mean).sum::<f64>() / n,
            var: seeds.iter().map(|m| f(m)[i].var).sum::<f64>() / n,
        })
    };
    Aggregate {
        arrival_s: Spread::of(seeds.iter().map(|m| m.arrival_s)),
        settling_s: s3(&|m| m.settling_s),
        overshoot: s3(&|m| m.overshoot),
        saturation: s3(&|m| m.saturation),
        total_variation: s3(&|m| m.total_variation),
        max_jump: s3(&|m| m.max_jump),
        steady_tau_std: s3(&|m| m.steady_tau_std),
        rmse: s6(&|m| m.rmse),
        rmse_steady: s6(&|m| m.rmse_steady),
        raw: mv(&|m| m.raw),
        filtered: mv(&|m| m.filtered),
        steady_max_position_error_m: Spread::of(seeds.iter().map(|m| m.steady_max_position_error_m)),
    }
}

pub use crate::reproduce::runner::StepTiming;
