//! `cargo xtask reproduce --paper carrier`: the straddle-carrier experiment of the paper (Lin,
//! Zhang, Ding & Niu 2024; `docs/carrier-smf.md`), extended scenarios, a Monte Carlo study,
//! figures and an honest report.

pub mod figures;
pub mod filters;
pub mod report;
pub mod scenarios;

use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use models::{Dims, FnModel, StepMatrices, Trajectory, simulate_ltv};
use serde::Serialize;

use super::outputs;
use super::runner::{Metrics, Run, metrics, run_filter};
use scenarios::Scenario;

/// Sizes of a run: the full reproduction or the few-second `--quick` mode.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Sizes {
    /// Steps of the extended scenarios (10 s at 1 kHz in full mode).
    pub extended_steps: usize,
    /// Steps on which the SDP backends run in the extended scenarios.
    pub sdp_steps: usize,
    /// Monte Carlo runs.
    pub mc_runs: usize,
    /// Steps per Monte Carlo run.
    pub mc_steps: usize,
}

impl Sizes {
    fn new(quick: bool, runs: Option<usize>) -> Self {
        let mut s = if quick {
            Sizes { extended_steps: 400, sdp_steps: 20, mc_runs: 8, mc_steps: 300 }
        } else {
            Sizes { extended_steps: 10_000, sdp_steps: 1_000, mc_runs: 100, mc_steps: 10_000 }
        };
        if let Some(r) = runs {
            s.mc_runs = r;
        }
        s
    }
}

/// One scenario's results in `summary.json`.
#[derive(Debug, Serialize)]
pub struct ScenarioSummary {
    /// Identifier (file names).
    pub id: String,
    /// Description.
    pub title: String,
    /// Filter steps.
    pub steps: usize,
    /// Seed of the simulation.
    pub seed: u64,
    /// Choices made where the paper is silent.
    pub notes: Vec<String>,
    /// Per-estimator figures.
    pub estimators: Vec<Metrics>,
    /// 99th percentile of the wall-clock step time per estimator, microseconds (over the same
    /// timed steps as the median in `estimators`): the tail that matters for a 1 ms loop.
    pub step_p99_us: Vec<(String, f64)>,
    /// The SDP-backed filters' tail taken apart: the first step of a run (no previous solution
    /// to warm-start from; it also builds (28) and sets the backend up) against the later ones.
    pub sdp_tails: Vec<SdpTail>,
    /// Largest relative difference of `tr P` between the filter driven by each SDP backend and
    /// the one driven by the two-multiplier solver, along their own runs (their `P_k` histories
    /// are independent, so this measures trajectory divergence; per-step agreement of the solvers
    /// on the same data is tested in `estimators`).
    pub solver_agreement: Vec<(String, f64)>,
    /// Fraction of (step, state) pairs where the improved filter's interval lies inside the
    /// interval of the \[17\]-style filter without input.
    pub proposed_inside_reference17: f64,
    /// Mean over (step, state) of the improved filter's interval width divided by that of the
    /// \[17\]-style filter without input (1 means the bounds coincide).
    pub width_ratio_reference17: f64,
    /// Figures written, `(file, caption)`.
    pub figures: Vec<(String, String)>,
}

/// Monte Carlo results in `summary.json`.
#[derive(Debug, Serialize)]
pub struct MonteCarloSummary {
    /// Runs.
    pub runs: usize,
    /// Steps per run.
    pub steps: usize,
    /// Seeds used: `base_seed + run`.
    pub base_seed: u64,
    /// Published sets that missed the true state, summed over all runs (must be 0).
    pub steps_outside: usize,
    /// Largest normalised distance over all runs and steps.
    pub max_normalized_distance: f64,
    /// Quantiles (min, 5 %, 50 %, 95 %, max) over runs of the mean bound width per state.
    pub bound_width_quantiles: Vec<[f64; 5]>,
    /// Quantiles over runs of the improved filter's RMSE per state.
    pub smf_rmse_quantiles: Vec<[f64; 5]>,
    /// Quantiles over runs of the Kalman filter's RMSE per state.
    pub kf_rmse_quantiles: Vec<[f64; 5]>,
    /// Wall-clock seconds, and threads used.
    pub seconds: f64,
    /// Worker threads.
    pub threads: usize,
}

/// Everything `summary.json` holds.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// Whether this was a `--quick` run.
    pub quick: bool,
    /// Base seed.
    pub seed: u64,
    /// Run sizes.
    pub sizes: Sizes,
    /// SDP backends compiled in.
    pub backends: Vec<String>,
    /// The scenarios.
    pub scenarios: Vec<ScenarioSummary>,
    /// The Monte Carlo study.
    pub monte_carlo: MonteCarloSummary,
    /// The paper's inconsistencies, with numbers.
    pub inconsistencies: Vec<report::Inconsistency>,
    /// The paper's claims and verdicts.
    pub claims: Vec<report::Claim>,
    /// Total wall-clock seconds of the reproduction.
    pub total_seconds: f64,
}

fn simulate_scenario(sc: &Scenario) -> Result<Trajectory, String> {
    let steps: &[StepMatrices] = &sc.steps;
    let (n, p, m) = (steps[0].a.nrows(), steps[0].b.ncols(), steps[0].c.nrows());
    let model = FnModel::new(Dims::new(n, p, m), |k: usize| Ok(steps[k.min(steps.len() - 1)].clone()));
    simulate_ltv(&model, &sc.sim).map_err(|e| format!("simulating {}: {e}", sc.id))
}

/// How often scenarios shorter than 1000 steps are rerun to time their steps.
pub const TIMING_REPEATS: usize = 20;

/// Runs every estimator of a scenario and writes its CSV files and figures.
fn run_scenario(sc: &Scenario, out: &Path) -> Result<(ScenarioSummary, Vec<Run>), String> {
    eprintln!("scenario {}: {} steps …", sc.id, sc.len());
    let traj = simulate_scenario(sc)?;
    let mut runs = Vec::new();
    for (mut f, max_steps) in filters::for_scenario(sc)? {
        runs.push(run_filter(&mut f, &sc.steps, &traj, max_steps)?);
    }
    // Short scenarios give too few steps for a stable median: rerun fresh filters for timing only.
    let repeats = if sc.len() < 1000 { TIMING_REPEATS } else { 1 };
    for _ in 1..repeats {
        for (run, (mut f, max_steps)) in runs.iter_mut().zip(filters::for_scenario(sc)?) {
            let again = run_filter(&mut f, &sc.steps, &traj, max_steps)?;
            run.step_ns.extend(again.step_ns);
        }
    }
    let io = |e: std::io::Error| e.to_string();
    for run in &runs {
        let path = out.join("csv").join(format!("{}_{}.csv", sc.id, outputs::slug(&run.label)));
        outputs::write_csv(&path, run, &traj.states, scenarios::TS).map_err(io)?;
    }
    let find = |label: &str| runs.iter().find(|r| r.label == label);
    let proposed = find(filters::PROPOSED).ok_or("missing the improved filter")?;
    let yl_a = find(filters::YANG_LI_NO_INPUT).ok_or("missing the [17] reconstruction")?;
    let kf = find(filters::KALMAN).ok_or("missing the Kalman filter")?;
    let figures = figures::write_figures(&out.join("figures"), &sc.id, &sc.id, &traj.states, &[proposed, yl_a], &[kf])
        .map_err(io)?;
    let solver_agreement = runs
        .iter()
        .filter(|r| r.label.starts_with(filters::PROPOSED_VIA))
        .map(|r| {
            let worst = r
                .snapshots
                .iter()
                .zip(&proposed.snapshots)
                .skip(1)
                .map(|(a, b)| (a.shape.trace() - b.shape.trace()).abs() / b.shape.trace())
                .fold(0.0, f64::max);
            (r.label.clone(), worst)
        })
        .collect();
    let mut inside = 0usize;
    let mut total = 0usize;
    let mut ratio_sum = 0.0;
    for (a, b) in proposed.snapshots.iter().zip(&yl_a.snapshots).skip(1) {
        for i in 0..a.centre.len() {
            let (ra, rb) = (a.shape[(i, i)].sqrt(), b.shape[(i, i)].sqrt());
            total += 1;
            ratio_sum += ra / rb;
            if a.centre[i] - ra >= b.centre[i] - rb - 1e-12 && a.centre[i] + ra <= b.centre[i] + rb + 1e-12 {
                inside += 1;
            }
        }
    }
    let summary = ScenarioSummary {
        id: sc.id.clone(),
        title: sc.title.clone(),
        steps: sc.len(),
        seed: sc.sim.seed,
        notes: sc.notes.clone(),
        estimators: runs.iter().map(|r| metrics(r, &traj.states)).collect(),
        step_p99_us: runs.iter().map(|r| (r.label.clone(), quantile_us(&r.step_ns, 0.99))).collect(),
        sdp_tails: runs.iter().filter(|r| r.label.starts_with(filters::PROPOSED_VIA)).map(SdpTail::of).collect(),
        solver_agreement,
        proposed_inside_reference17: inside as f64 / total.max(1) as f64,
        width_ratio_reference17: ratio_sum / total.max(1) as f64,
        figures,
    };
    Ok((summary, runs))
}

/// Where an SDP-backed filter's step times come from.
#[derive(Debug, Clone, Serialize)]
pub struct SdpTail {
    /// The estimator's label.
    pub estimator: String,
    /// Median time of the runs' first steps \[µs\] (one per timing repeat).
    pub first_step_median_us: f64,
    /// 99th percentile over every later step \[µs\].
    pub later_steps_p99_us: f64,
    /// The solver's iterations per step (first run): median and largest.
    pub iterations: (u32, u32),
    /// Steps of the first run with more iterations than twice the median (restarts and the
    /// transient).
    pub long_steps: usize,
}

impl SdpTail {
    fn of(run: &Run) -> Self {
        // The timing repeats are appended one after the other, each of `per_run` steps.
        let per_run = run.snapshots.len().saturating_sub(1).max(1);
        let (mut first, mut later) = (Vec::new(), Vec::new());
        for (i, &t) in run.step_ns.iter().enumerate() {
            if i % per_run == 0 { first.push(t) } else { later.push(t) }
        }
        let mut its: Vec<u32> = run.snapshots.iter().skip(1).filter_map(|s| s.iterations).collect();
        its.sort_unstable();
        let median = its.get(its.len() / 2).copied().unwrap_or(0);
        SdpTail {
            estimator: run.label.clone(),
            first_step_median_us: quantile_us(&first, 0.5),
            later_steps_p99_us: quantile_us(&later, 0.99),
            iterations: (median, its.last().copied().unwrap_or(0)),
            long_steps: its.iter().filter(|&&i| i > 2 * median).count(),
        }
    }
}

/// The `p`-quantile (nearest rank) of a sample of nanoseconds, in microseconds.
pub fn quantile_us(ns: &[u64], p: f64) -> f64 {
    if ns.is_empty() {
        return f64::NAN;
    }
    let mut v = ns.to_vec();
    v.sort_unstable();
    v[((v.len() - 1) as f64 * p).round() as usize] as f64 / 1e3
}

fn quantiles(mut v: Vec<f64>) -> [f64; 5] {
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    if v.is_empty() { [f64::NAN; 5] } else { [q(0.0), q(0.05), q(0.5), q(0.95), q(1.0)] }
}

/// Monte Carlo over seeds of the no-sideslip scenario with noise on the boundary of its sets, in
/// parallel over the cores, with a progress bar on standard error (hidden when it is not a
/// terminal).
fn monte_carlo(sizes: Sizes, base_seed: u64) -> Result<MonteCarloSummary, String> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(sizes.mc_runs.max(1));
    let t0 = Instant::now();
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<(Metrics, Metrics)>>> = Mutex::new((0..sizes.mc_runs).map(|_| None).collect());
    let error: Mutex<Option<String>> = Mutex::new(None);
    let bar = super::progress_bar(sizes.mc_runs as u64, "Monte Carlo runs");
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    if i >= sizes.mc_runs {
                        break;
                    }
                    let res = (|| -> Result<(Metrics, Metrics), String> {
                        let sc = scenarios::no_sideslip(sizes.mc_steps, 0, base_seed.wrapping_add(i as u64))?;
                        let traj = simulate_scenario(&sc)?;
                        let mut smf = filters::proposed(&sc)?;
                        let mut kf = filters::kalman(&sc)?;
                        let a = run_filter(&mut smf, &sc.steps, &traj, sc.len())?;
                        let b = run_filter(&mut kf, &sc.steps, &traj, sc.len())?;
                        Ok((metrics(&a, &traj.states), metrics(&b, &traj.states)))
                    })();
                    match res {
                        Ok(r) => results.lock().unwrap()[i] = Some(r),
                        Err(e) => *error.lock().unwrap() = Some(e),
                    }
                    bar.inc(1);
                }
            });
        }
    });
    bar.finish_and_clear();
    if let Some(e) = error.into_inner().unwrap() {
        return Err(e);
    }
    let results: Vec<(Metrics, Metrics)> = results.into_inner().unwrap().into_iter().flatten().collect();
    let per_state = |f: &dyn Fn(&(Metrics, Metrics)) -> Vec<f64>| -> Vec<[f64; 5]> {
        (0..4).map(|i| quantiles(results.iter().map(|r| f(r)[i]).collect())).collect()
    };
    Ok(MonteCarloSummary {
        runs: results.len(),
        steps: sizes.mc_steps,
        base_seed,
        steps_outside: results.iter().map(|r| r.0.steps_outside.unwrap_or(0)).sum(),
        max_normalized_distance: results.iter().filter_map(|r| r.0.max_normalized_distance).fold(0.0, f64::max),
        bound_width_quantiles: per_state(&|r| r.0.mean_bound_width.clone().unwrap_or_default()),
        smf_rmse_quantiles: per_state(&|r| r.0.rmse.clone()),
        kf_rmse_quantiles: per_state(&|r| r.1.rmse.clone()),
        seconds: t0.elapsed().as_secs_f64(),
        threads,
    })
}

/// Default base seed of the reproduction.
pub const DEFAULT_SEED: u64 = 2024;

/// Runs the whole reproduction into `out` and returns its summary (also written as
/// `summary.json`, with `report.md`, `figures/` and `csv/`). `runs` overrides the number of
/// Monte Carlo runs.
pub fn reproduce(quick: bool, out: &Path, seed: u64, runs: Option<usize>) -> Result<Summary, String> {
    let sizes = Sizes::new(quick, runs);
    let t0 = Instant::now();
    for sub in ["figures", "csv"] {
        std::fs::create_dir_all(out.join(sub)).map_err(|e| format!("creating {}: {e}", out.join(sub).display()))?;
    }
    let e = sizes.extended_steps;
    let list = [
        scenarios::paper(seed)?,
        scenarios::no_sideslip(e, sizes.sdp_steps, seed.wrapping_add(1))?,
        scenarios::load(0, e, sizes.sdp_steps, seed.wrapping_add(2))?,
        scenarios::load(1, e, sizes.sdp_steps, seed.wrapping_add(3))?,
        scenarios::load(2, e, sizes.sdp_steps, seed.wrapping_add(4))?,
        scenarios::speed_schedule(e, sizes.sdp_steps, seed.wrapping_add(5))?,
    ];
    let mut summaries = Vec::new();
    let mut paper_runs = Vec::new();
    for (i, sc) in list.iter().enumerate() {
        let (s, runs) = run_scenario(sc, out)?;
        if i == 0 {
            paper_runs = runs;
        }
        summaries.push(s);
    }
    let mc = monte_carlo(sizes, seed.wrapping_add(1000))?;
    let inconsistencies = report::inconsistencies(&list[0], &paper_runs)?;
    let claims = report::claims(&summaries, &mc);
    let summary = Summary {
        quick,
        seed,
        sizes,
        backends: lmi::backend_names().into_iter().map(str::to_owned).collect(),
        scenarios: summaries,
        monte_carlo: mc,
        inconsistencies,
        claims,
        total_seconds: t0.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    outputs::write_atomic(&out.join("summary.json"), json.as_bytes()).map_err(|e| e.to_string())?;
    let md = report::markdown(&summary);
    outputs::write_atomic(&out.join("report.md"), md.as_bytes()).map_err(|e| e.to_string())?;
    Ok(summary)
}

impl Summary {
    /// The deterministic part of the summary (no timings, no machine-dependent solver figures),
    /// with numbers rounded to 6 significant digits: what snapshot tests compare.
    pub fn deterministic_view(&self) -> serde_json::Value {
        use serde_json::json;
        let r = |v: f64| -> serde_json::Value {
            if v.is_finite() && v != 0.0 {
                let e = v.abs().log10().floor() as i32;
                let f = 10f64.powi(5 - e);
                json!((v * f).round() / f)
            } else {
                json!(v)
            }
        };
        let rv = |v: &[f64]| v.iter().map(|x| r(*x)).collect::<Vec<_>>();
        let scenarios: Vec<_> = self
            .scenarios
            .iter()
            .map(|s| {
                let est: Vec<_> = s
                    .estimators
                    .iter()
                    .filter(|m| !m.estimator.starts_with(filters::PROPOSED_VIA))
                    .map(|m| {
                        json!({
                            "estimator": m.estimator,
                            "steps": m.steps,
                            "steps_outside": m.steps_outside,
                            "max_normalized_distance": m.max_normalized_distance.map(r),
                            "initial_normalized_distance": r(m.initial_normalized_distance),
                            "rmse": rv(&m.rmse),
                            "mean_bound_width": m.mean_bound_width.as_deref().map(rv),
                            "mean_trace": r(m.mean_trace),
                            "fallback_steps": m.fallback_steps,
                        })
                    })
                    .collect();
                json!({
                    "id": s.id, "steps": s.steps, "seed": s.seed, "estimators": est,
                    "proposed_inside_reference17": r(s.proposed_inside_reference17),
                    "width_ratio_reference17": r(s.width_ratio_reference17),
                    "figures": s.figures.iter().map(|f| f.0.clone()).collect::<Vec<_>>(),
                })
            })
            .collect();
        let mc = &self.monte_carlo;
        json!({
            "quick": self.quick,
            "seed": self.seed,
            "sizes": self.sizes,
            "scenarios": scenarios,
            "monte_carlo": {
                "runs": mc.runs, "steps": mc.steps, "steps_outside": mc.steps_outside,
                "max_normalized_distance": r(mc.max_normalized_distance),
            },
            "claims": self.claims.iter().filter(|c| !c.claim.starts_with("Run time") && !c.claim.starts_with("All three"))
                .map(|c| json!({"claim": c.claim, "verdict": c.verdict})).collect::<Vec<_>>(),
        })
    }
}

/// The carrier paper in the multi-paper reproduction.
pub struct CarrierPaper;

impl super::Paper for CarrierPaper {
    fn name(&self) -> &'static str {
        "carrier"
    }
    fn title(&self) -> &'static str {
        "Straddle carrier, improved set-membership filter (Lin, Zhang, Ding & Niu 2024)"
    }
    fn run(&self, opts: &super::Options, out: &Path) -> Result<super::PaperOutcome, String> {
        let summary = reproduce(opts.quick, out, opts.seed, opts.runs)?;
        println!("{}", report::console(&summary));
        let verdicts = summary.claims.iter().map(|c| c.verdict.clone()).collect();
        Ok(super::PaperOutcome { claims: summary.claims.len(), verdicts })
    }
}
