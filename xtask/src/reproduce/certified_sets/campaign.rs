//! Boundary noise at scale: the constrained-zonotope filters on three models, every noise on a
//! vertex of its box (the hardest case for containment), seeded runs on every core, each step's
//! published interval checked against the truth.
//!
//! * **carrier** — `czf` on the straddle carrier (paper preset, `T_s` = 1 ms, 4 states, the three
//!   velocities measured) at order 1 without constraints (a box between steps,
//!   docs/constrained-zonotopes.md (C6)), beside the ellipsoidal `smf` on the least-trace ellipsoids
//!   around the same boxes (`d·h²`, a weaker assumption, so both hold on the same data): widths per
//!   state and step times side by side.
//! * **reach-stacker** — `czf-nl` on examples/reach-stacker (kinematic bicycle, GNSS x/y ±0.5 m,
//!   yaw-rate gyro, no compass): whether the heading's interval stays bounded.
//! * **range-bearing** — `czf-nl` on examples/range-bearing (a yard tractor measured by range and
//!   bearing to two landmarks, no GNSS, no compass), driving back and forth.
//! * **range-bearing circling** — the same tractor driving full circles (3 m/s, steering 0.4 rad,
//!   a turn every 18 s): both bearings cross ±π every turn, reported wrapped as a sensor does
//!   (the model declares them angles).
//! * **six-tank** — `czf-nl` on CORA's six-tank model (examples/six-tank).
//!
//! The models written as equations run at the order their model file's `[estimator.czf-nl]` table
//! chose (the vehicles order 1, a box between steps; the six tanks order 2).

use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use equation_models::EquationModel;
use estimators::smf::ObservedSetMembershipFilter;
use estimators::{
    ConstrainedZonotopeFilter, ConstrainedZonotopeSettings, Estimate, EstimatorError, SetMembershipFilter, Setup,
};
use models::{ConstantModel, DiscreteModel, SecondOrderModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::reproduce::runner::{StepTiming, median, quantile};

/// One model's runs.
struct Scenario {
    name: &'static str,
    plant: Plant,
    /// The boxes (diagonal generator matrices): `X₀`, `W`, `V`.
    setup: Setup,
    settings: ConstrainedZonotopeSettings,
    /// The input at step `k` for the true state `x`.
    input: fn(usize, &DVector<f64>) -> DVector<f64>,
    runs: usize,
    steps: usize,
}

enum Plant {
    Linear(ConstantModel),
    Equations(Box<EquationModel>),
}

/// What the runs of one model found.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioResult {
    /// The model.
    pub name: String,
    /// The filter's order (generators per state).
    pub order: usize,
    /// Constraints kept between steps.
    pub max_constraints: usize,
    /// Seeded runs.
    pub runs: usize,
    /// Steps taken over every run.
    pub steps: usize,
    /// Steps with a state outside its published interval (must be 0).
    pub misses: usize,
    /// Runs stopped by an error (`GuaranteeLost`, a refused measurement): must be 0.
    pub stopped: Vec<String>,
    /// Steps marked diverging (a state wider than twice its initial width).
    pub diverging_steps: usize,
    /// Median over runs of each state's median width over the second tenth of the steps.
    pub width_early: Vec<f64>,
    /// The same over the last tenth.
    pub width_late: Vec<f64>,
    /// Per state, the largest ratio over runs of the last tenth's median width to the second
    /// tenth's (the growth rule: at most 2).
    pub worst_growth: Vec<f64>,
    /// Per state, the largest ratio over runs of the last tenth's 90th-percentile width to the
    /// second tenth's: the wide mode of a width that is bimodal (see `widest`).
    pub worst_growth_p90: Vec<f64>,
    /// Per state, the largest published width after the first tenth of any run.
    pub widest: Vec<f64>,
    /// The step time of the constrained-zonotope filter.
    pub step_time: StepTiming,
    /// The ellipsoidal filter beside it (carrier only).
    pub ellipsoid: Option<EllipsoidComparison>,
}

/// `smf` on the same data.
#[derive(Debug, Clone, Serialize)]
pub struct EllipsoidComparison {
    /// Steps after the first 50 of each run where `czf`'s interval is wider than `smf`'s on some
    /// state (the claim: 0).
    pub czf_wider_steps: usize,
    /// Steps compared.
    pub steps_compared: usize,
    /// Per state, the median of `czf` width / `smf` width over the compared steps.
    pub median_width_ratio: Vec<f64>,
    /// Steps with a state outside `smf`'s interval (must be 0).
    pub misses: usize,
    /// The step time of `smf`.
    pub step_time: StepTiming,
    /// Steps with a state outside the interval of `smf` with its interval observer (the
    /// registry's default, docs/carrier-smf.md §4.8; must be 0).
    pub observer_misses: usize,
    /// Per state, the median of its width / `smf`'s alone over the compared steps.
    pub observer_width_ratio: Vec<f64>,
}

/// One run's counts.
#[derive(Default)]
struct RunTally {
    steps: usize,
    misses: usize,
    stopped: Option<String>,
    diverging: usize,
    early: Vec<f64>,
    late: Vec<f64>,
    early_p90: Vec<f64>,
    late_p90: Vec<f64>,
    widest: Vec<f64>,
    ns: Vec<u64>,
    smf_ns: Vec<u64>,
    smf_misses: usize,
    observer_misses: usize,
    observer_ratios: Vec<Vec<f64>>,
    czf_wider: usize,
    compared: usize,
    ratios: Vec<Vec<f64>>,
}

fn equations(root: &Path, file: &str) -> Result<(Box<EquationModel>, Setup), String> {
    let path = root.join(file);
    let model = port_est::model::read_model(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let setup = model.setup(estimators::EstimateKind::GuaranteedConstrainedZonotope);
    match model.dynamics {
        port_est::model::Dynamics::Equations(m) => Ok((Box::new((*m).clone()), setup)),
        _ => Err(format!("{}: not a model written as equations", path.display())),
    }
}

/// The settings of `czf-nl` that the model file `file` gives (its `[estimator.czf-nl]` table).
fn file_settings(root: &Path, file: &str) -> Result<ConstrainedZonotopeSettings, String> {
    let path = root.join(file);
    let model = port_est::model::read_model(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    super::czf_settings(&model)
}

fn radii(m: &DMatrix<f64>) -> Vec<f64> {
    (0..m.nrows()).map(|i| m[(i, i)]).collect()
}

/// The scenarios at full (`quick = false`) or `--quick` sizes; `runs` overrides the runs
/// per model.
fn scenarios(root: &Path, quick: bool, runs: Option<usize>) -> Result<Vec<Scenario>, String> {
    let d = carrier_dynamics::CarrierModel::new(carrier_dynamics::CarrierParams::paper_preset())
        .and_then(|m| m.discretize(1e-3))
        .map_err(|e| format!("carrier: {e}"))?;
    let (a, b, _) = d.to_dynamic();
    let c = DMatrix::from_fn(3, 4, |i, j| if j == 1 + i { 1.0 } else { 0.0 });
    let carrier = ConstantModel::new(a, b, c).map_err(|e| format!("carrier: {e}"))?;
    let (w, v) = (1e-3, 4e-3);
    let carrier_setup = Setup {
        x0: DVector::zeros(4),
        p0: DMatrix::identity(4, 4) * 0.1,
        process_noise: DMatrix::identity(4, 4) * w,
        measurement_noise: DMatrix::identity(3, 3) * v,
        inputs: 8,
    };
    let (stacker, stacker_setup) = equations(root, "examples/reach-stacker/model.toml")?;
    let (tanks, tank_setup) = equations(root, "examples/six-tank/model.toml")?;
    let (tractor, tractor_setup) = equations(root, "examples/range-bearing/model.toml")?;
    let (circling, circling_setup) = equations(root, "examples/range-bearing/model.toml")?;
    let size = |full: (usize, usize), small: (usize, usize)| {
        let (r, s) = if quick { small } else { full };
        (runs.unwrap_or(r), s)
    };
    let stacker_settings = file_settings(root, "examples/reach-stacker/model.toml")?;
    let tractor_settings = file_settings(root, "examples/range-bearing/model.toml")?;
    let tank_settings = file_settings(root, "examples/six-tank/model.toml")?;
    let scenario = |name, plant, setup, settings, input: fn(usize, &DVector<f64>) -> DVector<f64>, full, small| {
        let (runs, steps) = size(full, small);
        Scenario { name, plant, setup, settings, input, runs, steps }
    };
    let out = vec![
        scenario(
            "carrier",
            Plant::Linear(carrier),
            carrier_setup,
            // Order 1, no constraints: a box between steps (docs/constrained-zonotopes.md (C6)).
            ConstrainedZonotopeSettings { order: 1, max_constraints: 0, ..Default::default() },
            |k, _| DVector::from_fn(8, |j, _| 0.01 * (1.0 + (1e-3 * k as f64 + j as f64).sin())),
            (30, 25_000),
            (2, 1000),
        ),
        // Driving between the stacks: speed held near 2 m/s, slaloms and turns.
        scenario(
            "reach-stacker",
            Plant::Equations(stacker),
            stacker_setup,
            stacker_settings,
            |k, x| {
                let t = k as f64 * 0.1;
                DVector::from_column_slice(&[0.5 * (2.0 - x[3]) + 0.2 * (0.05 * t).sin(), 0.25 * (0.07 * t).sin()])
            },
            (20, 10_000),
            (2, 1000),
        ),
        // Back and forth along the quay (speed 2 sin(t/40)), weaving gently, heading held near 0.
        scenario(
            "range-bearing",
            Plant::Equations(tractor),
            tractor_setup,
            tractor_settings.clone(),
            |k, x| {
                let t = k as f64 * 0.1;
                DVector::from_column_slice(&[0.5 * (2.0 * (t / 40.0).sin() - x[3]), 0.1 * (0.2 * t).sin() - 0.3 * x[2]])
            },
            (5, 10_000),
            (2, 1000),
        ),
        // Full circles: speed held at 3 m/s, steering 0.4 rad.
        scenario(
            "range-bearing circling",
            Plant::Equations(circling),
            circling_setup,
            tractor_settings,
            |_, x| DVector::from_column_slice(&[0.5 * (3.0 - x[3]), 0.4]),
            (5, 10_000),
            (2, 1000),
        ),
        scenario(
            "six-tank",
            Plant::Equations(tanks),
            tank_setup,
            tank_settings,
            |k, _| DVector::from_fn(3, |i, _| 0.1 + 0.05 * ((k as f64 * 0.05) + i as f64).sin()),
            (20, 5000),
            (2, 200),
        ),
    ];
    Ok(out)
}

/// One seeded run of `sc` on `model`; `smf` beside it for the linear plant.
fn drive<M: DiscreteModel + SecondOrderModel>(
    sc: &Scenario,
    model: &M,
    linear: Option<&ConstantModel>,
    seed: u64,
    progress: &indicatif::ProgressBar,
) -> Result<RunTally, String> {
    let (w, v) = (radii(&sc.setup.process_noise), radii(&sc.setup.measurement_noise));
    let (n, m) = (sc.setup.x0.len(), v.len());
    let mut rng = Xoshiro256StarStar::seed_from_u64(seed);
    let mut sign = move || if rng.uniform(-1.0, 1.0) < 0.0 { -1.0 } else { 1.0 };
    let x0_radius = radii(&sc.setup.p0);
    let mut x = DVector::from_fn(n, |i, _| sc.setup.x0[i] + x0_radius[i] * sign());
    let mut czf = ConstrainedZonotopeFilter::new(sc.setup.clone(), sc.settings.clone())
        .map_err(|e| format!("{}: {e}", sc.name))?;
    // The least-trace ellipsoids around the boxes: d · diag(h²).
    let around =
        |h: &[f64]| DMatrix::from_diagonal(&DVector::from_iterator(h.len(), h.iter().map(|v| h.len() as f64 * v * v)));
    let mut smf = match linear {
        Some(_) => Some(
            SetMembershipFilter::new(Setup {
                p0: around(&x0_radius),
                process_noise: around(&w),
                measurement_noise: around(&v),
                ..sc.setup.clone()
            })
            .map_err(|e| format!("{} smf: {e}", sc.name))?,
        ),
        None => None,
    };
    let mut observed = smf.clone().map(ObservedSetMembershipFilter::new);
    let mut t = RunTally { ratios: vec![Vec::new(); n], observer_ratios: vec![Vec::new(); n], ..RunTally::default() };
    let mut widths: Vec<Vec<f64>> = vec![Vec::with_capacity(sc.steps); n];
    let (mut next, mut y) = (DVector::zeros(n), DVector::zeros(m));
    for k in 0..sc.steps {
        let u = (sc.input)(k, &x);
        model.f(&x, &u, &mut next).map_err(|e| format!("{} truth: {e}", sc.name))?;
        x = &next + DVector::from_fn(n, |i, _| w[i] * sign());
        model.h(&x, &u, &mut y).map_err(|e| format!("{} truth: {e}", sc.name))?;
        let mut y = &y + DVector::from_fn(m, |i, _| v[i] * sign());
        // Angle outputs as a sensor reports them (an angle already in (−π, π] is unchanged).
        for &i in model.angles().outputs {
            y[i] = models::wrap_angle(y[i]);
        }
        let t0 = Instant::now();
        let est = match czf.step(model, &u, &y) {
            Ok(e) => e,
            Err(e @ (EstimatorError::GuaranteeLost { .. } | EstimatorError::SetMissed { .. })) => {
                t.stopped = Some(format!("seed {seed}, step {k}: {e}"));
                break;
            }
            Err(e) => return Err(format!("{}, seed {seed}, step {k}: {e}", sc.name)),
        };
        t.ns.push(u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX));
        t.steps += 1;
        t.diverging += usize::from(!est.status().is_clean());
        let czf_bounds: Vec<(f64, f64)> = (0..n).map(|i| est.bounds(i).unwrap_or((f64::NAN, f64::NAN))).collect();
        t.misses += usize::from(czf_bounds.iter().enumerate().any(|(i, &(l, h))| !(l <= x[i] && x[i] <= h)));
        for (i, (l, h)) in czf_bounds.iter().enumerate() {
            widths[i].push(h - l);
        }
        if let (Some(smf), Some(lin)) = (smf.as_mut(), linear) {
            let t0 = Instant::now();
            let e = smf.step(lin, &u, &y).map_err(|e| format!("{} smf, seed {seed}, step {k}: {e}", sc.name))?;
            t.smf_ns.push(u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX));
            let b: Vec<(f64, f64)> = (0..n).map(|i| e.bounds(i).unwrap_or((f64::NAN, f64::NAN))).collect();
            t.smf_misses += usize::from(b.iter().enumerate().any(|(i, &(l, h))| !(l <= x[i] && x[i] <= h)));
            let o = match observed.as_mut() {
                Some(f) => {
                    f.step(lin, &u, &y).map_err(|e| format!("{} smf observed, seed {seed}, step {k}: {e}", sc.name))?
                }
                None => return Err(format!("{}: the observed smf is missing", sc.name)),
            };
            let ob: Vec<(f64, f64)> = (0..n).map(|i| o.bounds(i).unwrap_or((f64::NAN, f64::NAN))).collect();
            t.observer_misses += usize::from(ob.iter().enumerate().any(|(i, &(l, h))| !(l <= x[i] && x[i] <= h)));
            if k >= 50 {
                t.compared += 1;
                let wider = (0..n).any(|i| czf_bounds[i].1 - czf_bounds[i].0 > b[i].1 - b[i].0);
                t.czf_wider += usize::from(wider);
                for i in 0..n {
                    t.ratios[i].push((czf_bounds[i].1 - czf_bounds[i].0) / (b[i].1 - b[i].0));
                    t.observer_ratios[i].push((ob[i].1 - ob[i].0) / (b[i].1 - b[i].0));
                }
            }
        }
        if k % 256 == 255 {
            progress.inc(256);
        }
    }
    let s = widths[0].len();
    t.early = widths.iter().map(|w| median(w[s / 10..s / 5].to_vec())).collect();
    t.late = widths.iter().map(|w| median(w[s * 9 / 10..].to_vec())).collect();
    t.early_p90 = widths.iter().map(|w| quantile(w[s / 10..s / 5].to_vec(), 0.9)).collect();
    t.late_p90 = widths.iter().map(|w| quantile(w[s * 9 / 10..].to_vec(), 0.9)).collect();
    t.widest = widths.iter().map(|w| w[s / 10..].iter().copied().fold(0.0, f64::max)).collect();
    Ok(t)
}

/// Every scenario's runs, spread over the machine's cores; seeds `seed + 3000 + run`.
///
/// # Errors
/// A model file that cannot be read, or a filter error other than a stopped run.
pub fn run(root: &Path, seed: u64, quick: bool, runs: Option<usize>) -> Result<Vec<ScenarioResult>, String> {
    let all = scenarios(root, quick, runs)?;
    let jobs: Vec<(usize, usize)> =
        all.iter().enumerate().flat_map(|(s, sc)| (0..sc.runs).map(move |r| (s, r))).collect();
    let total: usize = all.iter().map(|sc| sc.runs * sc.steps).sum();
    let progress = crate::reproduce::progress_bar(total as u64, "boundary-noise steps");
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<(usize, Result<RunTally, String>)>> = Mutex::new(Vec::new());
    let workers = std::thread::available_parallelism().map_or(1, usize::from).min(jobs.len().max(1));
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let j = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(s, r)) = jobs.get(j) else { break };
                    let sc = &all[s];
                    let seed = seed.wrapping_add(3000 + r as u64);
                    let tally = match &sc.plant {
                        Plant::Linear(model) => drive(sc, model, Some(model), seed, &progress),
                        Plant::Equations(model) => drive(sc, model.as_ref(), None, seed, &progress),
                    };
                    if let Ok(mut out) = results.lock() {
                        out.push((s, tally));
                    }
                }
            });
        }
    });
    progress.finish_and_clear();
    let results = results.into_inner().map_err(|_| "a campaign worker panicked".to_owned())?;
    let mut per: Vec<Vec<RunTally>> = (0..all.len()).map(|_| Vec::new()).collect();
    for (s, tally) in results {
        per[s].push(tally?);
    }
    Ok(all.iter().zip(per).map(|(sc, tallies)| summarise(sc, tallies)).collect())
}

fn summarise(sc: &Scenario, tallies: Vec<RunTally>) -> ScenarioResult {
    let n = sc.setup.x0.len();
    let per_state = |f: &dyn Fn(&RunTally, usize) -> f64| -> Vec<Vec<f64>> {
        (0..n).map(|i| tallies.iter().map(|t| f(t, i)).collect()).collect()
    };
    let early = per_state(&|t, i| t.early[i]);
    let late = per_state(&|t, i| t.late[i]);
    let growth = per_state(&|t, i| t.late[i] / t.early[i]);
    let growth_p90 = per_state(&|t, i| t.late_p90[i] / t.early_p90[i]);
    let worst = |g: Vec<Vec<f64>>| -> Vec<f64> {
        g.into_iter().map(|g| g.into_iter().fold(f64::NEG_INFINITY, f64::max)).collect()
    };
    let ellipsoid = (!tallies.iter().all(|t| t.smf_ns.is_empty())).then(|| EllipsoidComparison {
        czf_wider_steps: tallies.iter().map(|t| t.czf_wider).sum(),
        steps_compared: tallies.iter().map(|t| t.compared).sum(),
        median_width_ratio: (0..n)
            .map(|i| median(tallies.iter().flat_map(|t| t.ratios[i].clone()).collect()))
            .collect(),
        misses: tallies.iter().map(|t| t.smf_misses).sum(),
        step_time: StepTiming::of(tallies.iter().flat_map(|t| t.smf_ns.clone()).collect()),
        observer_misses: tallies.iter().map(|t| t.observer_misses).sum(),
        observer_width_ratio: (0..n)
            .map(|i| median(tallies.iter().flat_map(|t| t.observer_ratios[i].clone()).collect()))
            .collect(),
    });
    ScenarioResult {
        name: sc.name.to_owned(),
        order: sc.settings.order,
        max_constraints: sc.settings.max_constraints,
        runs: tallies.len(),
        steps: tallies.iter().map(|t| t.steps).sum(),
        misses: tallies.iter().map(|t| t.misses).sum(),
        stopped: tallies.iter().filter_map(|t| t.stopped.clone()).collect(),
        diverging_steps: tallies.iter().map(|t| t.diverging).sum(),
        width_early: early.into_iter().map(median).collect(),
        width_late: late.into_iter().map(median).collect(),
        worst_growth: worst(growth),
        worst_growth_p90: worst(growth_p90),
        widest: worst(per_state(&|t, i| t.widest[i])),
        step_time: StepTiming::of(tallies.iter().flat_map(|t| t.ns.clone()).collect()),
        ellipsoid,
    }
}
