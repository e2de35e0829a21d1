//! Running estimators over a simulated trajectory and measuring them.

use std::time::Instant;

use estimators::registry::{self, AnyEstimator, EstimatorSettings};
use estimators::{DataChecks, Estimate, EstimateKind, Setup, SolveOutcome};
use models::{StepMatrices, Trajectory};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// An estimator of the registry with the label the report gives it.
pub struct Filter {
    /// Label for tables and legends.
    pub label: String,
    /// The estimator, built by the registry.
    pub estimator: AnyEstimator,
}

impl Filter {
    /// Builds the registry's estimator `name` from `setup` and `settings` (the row's default when
    /// `None`), labelled `label`.
    pub fn new(label: &str, name: &str, setup: Setup, settings: Option<EstimatorSettings>) -> Result<Self, String> {
        let mut estimator = registry::build(name, setup, settings).map_err(|e| format!("{label}: {e}"))?;
        if estimator.entry().kind != EstimateKind::GuaranteedEllipsoid {
            // The papers' Gaussian filters have no innovation gate and their MHE no window check;
            // the set-membership filters keep their proof of inconsistency (data on the boundary
            // of their sets never fail it).
            estimator.set_data_checks(DataChecks::OFF).map_err(|e| format!("{label}: {e}"))?;
        }
        Ok(Self { label: label.to_owned(), estimator })
    }

    /// Whether the estimate is a guaranteed set rather than a mean/covariance.
    pub fn is_set(&self) -> bool {
        self.estimator.estimate().kind() == EstimateKind::GuaranteedEllipsoid
    }

    fn current(&self) -> Snapshot {
        Snapshot::of(self.estimator.estimate())
    }
}

impl Snapshot {
    /// A copy of an estimate.
    pub fn of(e: &dyn Estimate) -> Self {
        let d = e.details();
        Snapshot {
            centre: e.center().clone(),
            shape: e.shape().clone(),
            tau: match [d.get("tau1"), d.get("tau2"), d.get("tau3")] {
                [Some(Some(t1)), Some(Some(t2)), Some(Some(t3))] => Some([t1, t2, t3]),
                _ => None,
            },
            fallback: e.status().outcome == SolveOutcome::FallbackUsed,
            // The solver's iterations, where the estimator reports them (a count, so exact in f64).
            iterations: d.get("iterations").flatten().map(|i| i as u32),
        }
    }
}

/// A copy of an estimator's state after a step.
#[derive(Debug, Clone)]
pub struct Snapshot {
    /// Centre (or mean).
    pub centre: DVector<f64>,
    /// Shape `P` (or covariance).
    pub shape: DMatrix<f64>,
    /// S-procedure multipliers of the step, if any.
    pub tau: Option<[f64; 3]>,
    /// Whether the step fell back to a feasible multiplier because the solver failed.
    pub fallback: bool,
    /// The solver's iterations at the step (set-membership filters).
    pub iterations: Option<u32>,
}

/// The recorded run of one estimator: `k = 0` is the initial estimate.
pub struct Run {
    /// Estimator label.
    pub label: String,
    /// Whether it publishes guaranteed sets.
    pub is_set: bool,
    /// Snapshots for `k = 0..=steps`.
    pub snapshots: Vec<Snapshot>,
    /// Wall-clock time of each step, in nanoseconds.
    pub step_ns: Vec<u64>,
}

/// Runs `filter` over the first `max_steps` steps of `traj` (timing only the step calls).
pub fn run_filter(
    filter: &mut Filter,
    steps: &[StepMatrices],
    traj: &Trajectory,
    max_steps: usize,
) -> Result<Run, String> {
    let n = max_steps.min(steps.len());
    let mut snapshots = Vec::with_capacity(n + 1);
    let mut step_ns = Vec::with_capacity(n);
    snapshots.push(filter.current());
    for k in 0..n {
        let (u, y) = (&traj.inputs[k], &traj.measurements[k + 1]);
        let t0 = Instant::now();
        let r = filter.estimator.step(&steps[k].as_step(), u, y).map(|_| ());
        step_ns.push(t0.elapsed().as_nanos() as u64);
        r.map_err(|e| format!("{} at step {k}: {e}", filter.label))?;
        snapshots.push(filter.current());
    }
    Ok(Run { label: filter.label.clone(), is_set: filter.is_set(), snapshots, step_ns })
}

/// `(x − c)ᵀ P⁻¹ (x − c)` through the `ellipsoid` crate, or `+∞` if `𝓔(c, P)` is not a valid
/// ellipsoid (P not positive definite, non-finite entries).
pub fn normalized_distance(x: &DVector<f64>, centre: &DVector<f64>, shape: &DMatrix<f64>) -> f64 {
    ellipsoid::Ellipsoid::new(centre.clone(), shape.clone())
        .and_then(|e| e.normalized_distance(x))
        .unwrap_or(f64::INFINITY)
}

/// Per-estimator figures of one scenario (`summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct Metrics {
    /// Estimator label.
    pub estimator: String,
    /// Steps run (`k = 1..=steps` are the published estimates).
    pub steps: usize,
    /// Published sets (k ≥ 1) that do not contain the true state (set-membership filters only).
    pub steps_outside: Option<usize>,
    /// Largest `(x − x̂)ᵀ P⁻¹ (x − x̂)` over k ≥ 1 (set-membership filters only).
    pub max_normalized_distance: Option<f64>,
    /// `(x₀ − x̂₀)ᵀ P₀⁻¹ (x₀ − x̂₀)`: whether the initial set contains the initial state.
    pub initial_normalized_distance: f64,
    /// Root-mean-square error of the centre per state (k ≥ 1).
    pub rmse: Vec<f64>,
    /// Largest absolute error of the centre per state (k ≥ 1).
    pub max_abs_error: Vec<f64>,
    /// Standard deviation of the error per state (its "fluctuation", k ≥ 1).
    pub error_std: Vec<f64>,
    /// Mean width `2√P_ii` of the bounds per state (set-membership filters only, k ≥ 1).
    pub mean_bound_width: Option<Vec<f64>>,
    /// Mean trace of the published shape (k ≥ 1).
    pub mean_trace: f64,
    /// Steps that used the fallback multiplier.
    pub fallback_steps: usize,
    /// Median wall-clock time of a step, microseconds (over all timed repeats).
    pub median_step_us: f64,
    /// Steps timed for the median.
    pub timed_steps: usize,
}

/// The median (the upper one for an even count), NaN for no values.
#[must_use]
pub fn median(v: Vec<f64>) -> f64 {
    quantile(v, 0.5)
}

/// The `q`-quantile as the value of rank `⌊q · len⌋` (`q` in `[0, 1]`), NaN for no values.
#[must_use]
pub fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    // In range for q in [0, 1]: the rank is at most len − 1.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss, clippy::cast_precision_loss)]
    let rank = ((q.clamp(0.0, 1.0) * v.len() as f64) as usize).min(v.len() - 1);
    v[rank]
}

/// The constrained-zonotope filters' sets for a set-membership `setup` of diagonal ellipsoids:
/// their bounding boxes, half-widths `√P_ii` as diagonal generator matrices (each ellipsoid lies
/// in its box, so noise drawn in the ellipsoids respects the boxes).
#[must_use]
pub fn bounding_boxes(setup: &Setup) -> Setup {
    let sqrt_diag = |m: &DMatrix<f64>| DMatrix::from_diagonal(&m.diagonal().map(f64::sqrt));
    Setup {
        p0: sqrt_diag(&setup.p0),
        process_noise: sqrt_diag(&setup.process_noise),
        measurement_noise: sqrt_diag(&setup.measurement_noise),
        ..setup.clone()
    }
}

/// Median of a sample of nanoseconds, in microseconds.
pub fn median_us(ns: &[u64]) -> f64 {
    if ns.is_empty() {
        return f64::NAN;
    }
    let mut v = ns.to_vec();
    v.sort_unstable();
    let m = v.len() / 2;
    let med = if v.len() % 2 == 0 { (v[m - 1] + v[m]) as f64 / 2.0 } else { v[m] as f64 };
    med / 1e3
}

/// Tolerance on the normalised distance when counting steps outside a set.
pub const OUTSIDE_TOL: f64 = 1e-9;

/// Computes [`Metrics`] of a run against the true states.
pub fn metrics(run: &Run, truth: &[DVector<f64>]) -> Metrics {
    let n = truth[0].len();
    let steps = run.snapshots.len() - 1;
    let mut sq = vec![0.0; n];
    let mut sum = vec![0.0; n];
    let errors: Vec<DVector<f64>> = (1..=steps).map(|k| &run.snapshots[k].centre - &truth[k]).collect();
    let mut max_abs = vec![0.0f64; n];
    let mut width = vec![0.0; n];
    let mut outside = 0;
    let mut max_d = 0.0f64;
    let mut trace = 0.0;
    for k in 1..=steps {
        let s = &run.snapshots[k];
        let e = &s.centre - &truth[k];
        for i in 0..n {
            sq[i] += e[i] * e[i];
            sum[i] += e[i];
            max_abs[i] = max_abs[i].max(e[i].abs());
            width[i] += 2.0 * s.shape[(i, i)].max(0.0).sqrt();
        }
        trace += s.shape.trace();
        if run.is_set {
            let d = normalized_distance(&truth[k], &s.centre, &s.shape);
            // NaN propagates (f64::max would drop it).
            max_d = if d.is_nan() || max_d.is_nan() { f64::NAN } else { max_d.max(d) };
            // NaN counts as outside.
            if d.is_nan() || d > 1.0 + OUTSIDE_TOL {
                outside += 1;
            }
        }
    }
    let cnt = steps.max(1) as f64;
    let s0 = &run.snapshots[0];
    Metrics {
        estimator: run.label.clone(),
        steps,
        steps_outside: run.is_set.then_some(outside),
        max_normalized_distance: run.is_set.then_some(max_d),
        initial_normalized_distance: normalized_distance(&truth[0], &s0.centre, &s0.shape),
        rmse: sq.iter().map(|s| (s / cnt).sqrt()).collect(),
        max_abs_error: max_abs,
        // Two passes (mean, then spread): no cancellation when the bias dominates.
        error_std: (0..n)
            .map(|i| {
                let mean = sum[i] / cnt;
                (errors.iter().map(|e| (e[i] - mean).powi(2)).sum::<f64>() / cnt).sqrt()
            })
            .collect(),
        mean_bound_width: run.is_set.then(|| width.iter().map(|w| w / cnt).collect()),
        mean_trace: trace / cnt,
        fallback_steps: run.snapshots.iter().filter(|s| s.fallback).count(),
        median_step_us: median_us(&run.step_ns),
        timed_steps: run.step_ns.len(),
    }
}

/// Wall time per filter step.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct StepTiming {
    /// Steps timed.
    pub steps_timed: usize,
    /// Median \[µs\].
    pub median_us: f64,
    /// 99th percentile \[µs\].
    pub p99_us: f64,
    /// Mean \[µs\].
    pub mean_us: f64,
    /// Largest \[µs\] (includes preemption by other processes).
    pub max_us: f64,
}

impl StepTiming {
    /// Statistics of per-step nanoseconds.
    #[must_use]
    pub fn of(mut ns: Vec<u64>) -> Self {
        ns.sort_unstable();
        let n = ns.len();
        let q = |p: f64| if n == 0 { f64::NAN } else { ns[((n - 1) as f64 * p).round() as usize] as f64 / 1e3 };
        let mean = if n == 0 { f64::NAN } else { ns.iter().map(|&v| v as f64).sum::<f64>() / n as f64 / 1e3 };
        Self { steps_timed: n, median_us: q(0.5), p99_us: q(0.99), mean_us: mean, max_us: q(1.0) }
    }
}
