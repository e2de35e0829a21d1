//! Real-time iterations of the paper's MHE measured against the fully iterated windows: every
//! closed-loop run of `mhe-ukf` is replayed (its inputs and measurements, step by step) through
//! the same estimator and through it with one and with two Gauss–Newton iterations per update
//! (`NonlinearMheSettings::real_time_iterations`). The replay of the full estimator must give the
//! run's own estimates bit for bit (checked); the distance of each real-time estimate to the
//! converged one is counted in the converged estimate's standard deviations (the largest over the
//! six states), and the three update times are measured side by side in the same replay.

use std::time::Instant;

use estimators::registry::AnyEstimator;
use estimators::{DataChecks, DynEstimator};
use models::AnyModel;
use nalgebra::DVector;
use serde::Serialize;
use vessel_control::LoopRecord;
use vessel_dynamics::{DiscreteVessel, VesselParams};

use super::run::{self, Scenario, StepTiming};
use crate::reproduce::runner::quantile;

/// The iteration budgets compared.
pub const BUDGETS: [usize; 2] = [1, 2];

/// One scenario's replays, pooled over its seeds.
#[derive(Debug, Clone, Serialize)]
pub struct RealTimeReplay {
    /// Scenario identifier.
    pub scenario: &'static str,
    /// Updates compared (per budget).
    pub steps: usize,
    /// Per budget: the median, 99th percentile and largest distance to the converged estimate,
    /// in its standard deviations.
    pub distance_sigma: Vec<[f64; 3]>,
    /// The fully iterated update's time in the replay.
    pub full_timing: StepTiming,
    /// Per budget, the real-time update's time in the same replay.
    pub timing: Vec<StepTiming>,
}

/// Distances and times of one run, to pool.
#[derive(Debug, Default)]
pub struct ReplayTally {
    distances: Vec<Vec<f64>>,
    full_ns: Vec<u64>,
    ns: Vec<Vec<u64>>,
}

fn timed(est: &mut AnyEstimator, model: &dyn AnyModel, u: &DVector<f64>, z: &DVector<f64>) -> Result<u64, String> {
    let t0 = Instant::now();
    est.step_dyn(model, u, z).map_err(|e| e.to_string())?;
    Ok(u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX))
}

/// Replays the `mhe-ukf` run `rec` of `scenario` into `tally`.
///
/// # Errors
/// An estimator that cannot be built or fails a step, or a full replay that differs from the run.
pub fn replay(scenario: &Scenario, rec: &LoopRecord, tally: &mut ReplayTally) -> Result<(), String> {
    let plant = DiscreteVessel::paper(VesselParams::paper()).map_err(|e| format!("vessel: {e}"))?;
    let model: &dyn AnyModel = &plant;
    let settings = run::filter_settings(scenario)?;
    let full_spec =
        run::ESTIMATORS.iter().find(|s| s.id == estimators::registry::names::MHE_UKF).ok_or("no mhe-ukf")?;
    let mut full = (full_spec.build)(&settings).map_err(|e| e.to_string())?;
    let mut fast = BUDGETS
        .iter()
        .map(|&k| run::build_mhe_real_time(&settings, k).map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    for e in std::iter::once(&mut full).chain(fast.iter_mut()) {
        e.set_data_checks(DataChecks::OFF).map_err(|e| e.to_string())?;
    }
    tally.distances.resize(BUDGETS.len(), Vec::new());
    tally.ns.resize(BUDGETS.len(), Vec::new());
    for k in 0..rec.steps {
        let u = DVector::from_column_slice(rec.input(k));
        let z = DVector::from_column_slice(rec.measurement(k + 1));
        tally.full_ns.push(timed(&mut full, model, &u, &z).map_err(|e| format!("replay, step {}: {e}", k + 1))?);
        let (center, shape) = (full.estimate_dyn().center().clone(), full.estimate_dyn().shape().clone());
        if center.as_slice() != rec.estimate(k + 1) {
            return Err(format!("the replay of mhe-ukf differs from its run at step {}", k + 1));
        }
        for (i, est) in fast.iter_mut().enumerate() {
            let ns = timed(est, model, &u, &z).map_err(|e| format!("real-time replay, step {}: {e}", k + 1))?;
            tally.ns[i].push(ns);
            let x = est.estimate_dyn().center();
            let d = (0..center.len()).map(|j| (x[j] - center[j]).abs() / shape[(j, j)].sqrt()).fold(0.0, f64::max);
            tally.distances[i].push(d);
        }
    }
    Ok(())
}

impl RealTimeReplay {
    /// Pools a scenario's tallies.
    #[must_use]
    pub fn of(scenario: &'static str, tallies: Vec<ReplayTally>) -> Self {
        let mut pooled = ReplayTally::default();
        pooled.distances.resize(BUDGETS.len(), Vec::new());
        pooled.ns.resize(BUDGETS.len(), Vec::new());
        for mut t in tallies {
            pooled.full_ns.append(&mut t.full_ns);
            for i in 0..t.distances.len().min(BUDGETS.len()) {
                pooled.distances[i].append(&mut t.distances[i]);
                pooled.ns[i].append(&mut t.ns[i]);
            }
        }
        let steps = pooled.full_ns.len();
        Self {
            scenario,
            steps,
            distance_sigma: pooled
                .distances
                .iter()
                .map(|d| [quantile(d.clone(), 0.5), quantile(d.clone(), 0.99), d.iter().copied().fold(0.0, f64::max)])
                .collect(),
            full_timing: StepTiming::of(pooled.full_ns),
            timing: pooled.ns.into_iter().map(StepTiming::of).collect(),
        }
    }
}

/// The report's section.
#[must_use]
pub fn markdown(replays: &[RealTimeReplay]) -> String {
    let mut s = String::from(
        "## Real-time iterations (this reproduction's measurement, not the paper's)\n\nEvery closed-loop run of \
         `mhe-ukf` replayed through the same estimator (its estimates reproduced bit for bit) and through it with one \
         and two Gauss–Newton iterations per update from the shifted previous window \
         (`real_time_iterations`, docs/dp-vessel.md); distance to the converged estimate in its standard deviations \
         (largest over the six states), and the update times measured side by side in the replay. `mhe-ukf-rti` in \
         the tables above runs the two-iteration variant in the loop.\n\n| scenario | updates | 1 iteration: \
         median / p99 / worst σ | 2 iterations: median / p99 / worst σ | update median µs: full / 1 / 2 | p99 µs: \
         full / 1 / 2 |\n|---|---:|---|---|---|---|\n",
    );
    for r in replays {
        let d = |i: usize| {
            r.distance_sigma.get(i).map_or("–".into(), |d| format!("{:.2e} / {:.2e} / {:.2e}", d[0], d[1], d[2]))
        };
        let t = |f: &dyn Fn(&StepTiming) -> f64| {
            let fast: Vec<String> = r.timing.iter().map(|x| format!("{:.1}", f(x))).collect();
            format!("{:.1} / {}", f(&r.full_timing), fast.join(" / "))
        };
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            r.scenario,
            r.steps,
            d(0),
            d(1),
            t(&|x| x.median_us),
            t(&|x| x.p99_us)
        ));
    }
    s
}
