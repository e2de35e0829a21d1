//! `cargo xtask reproduce --paper dp-vessel`: the closed-loop experiment of the supply-vessel
//! paper (Su & Zhao, *Journal of Harbin Engineering University* 37(10), 2016; digest
//! `shared/papers/dp-vessel-ukf-mhe.md`, note `docs/dp-vessel.md`): the vessel moves from
//! (0, 0, 0°) to (50 m, 50 m, 0°) and holds there for 500 s, with the NSAMPC controller fed by
//! an estimator, in run A (the literal step) and run B (reference filter), 20 seeds each,
//! with the heading noise read as 0.1 rad² and as 0.1 deg².
//!
//! The paper's estimator, an MHE with a UKF arrival cost (`estimators::mhe::NonlinearMhe`), runs
//! beside the EKF and the UKF as baselines ([`run::ESTIMATORS`]). Every formula,
//! Table 1 and Figs 2–3 of the paper are lost: no number here is the paper's.

pub mod certified;
pub mod figures;
pub mod real_time;
pub mod report;
pub mod run;

use std::path::Path;

use serde::Serialize;
use vessel_control::{NsampcParams, ReferenceFilter};
use vessel_dynamics::{ForceNoise, VesselParams};

use super::outputs;
use run::{Aggregate, FilterSettings, RunMetrics, SCENARIOS, Scenario, StepTiming};

/// Sizes of a run: the full reproduction or the few-second `--quick` mode.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Sizes {
    /// Duration \[s\] (the paper's 500 s; 300 s in `--quick`).
    pub duration_s: f64,
    /// Steps per run (`duration / δ`).
    pub steps: usize,
    /// Start of the steady-state window \[s\] (200 s, digest §4; the window ends with the run).
    pub steady_from_s: f64,
    /// Seeds per scenario and estimator (20; 2 in `--quick`; `--runs` overrides).
    pub seeds: usize,
}

impl Sizes {
    /// The sizes of a full or `--quick` run; `runs` overrides the number of seeds.
    #[must_use]
    pub fn new(quick: bool, runs: Option<usize>) -> Self {
        let (duration_s, seeds) = if quick { (300.0, 2) } else { (500.0, 20) };
        let steps = (duration_s / vessel_dynamics::PAPER_SAMPLE_PERIOD).round() as usize;
        Self { duration_s, steps, steady_from_s: 200.0, seeds: runs.unwrap_or(seeds) }
    }
}

/// One (scenario, estimator) pair over the seeds.
#[derive(Debug, Clone, Serialize)]
pub struct ResultSummary {
    /// The scenario.
    pub scenario: Scenario,
    /// Estimator identifier.
    pub estimator: String,
    /// Estimator label.
    pub estimator_label: String,
    /// Metrics of each seed.
    pub seeds: Vec<RunMetrics>,
    /// Over the seeds.
    pub aggregate: Aggregate,
    /// Wall time of one estimator update, pooled over the seeds.
    pub timing: StepTiming,
    /// Figures of the first seed, `(file, caption)`.
    pub figures: Vec<(String, String)>,
    /// CSV of the first seed (relative to `csv/`).
    pub csv: String,
}

/// The controller's and the plant's settings, for the record.
#[derive(Debug, Clone, Serialize)]
pub struct LoopSettings {
    /// `[Tp, μ1, μ2, μ3]` **\[P\]** (roles of μ assumed).
    pub nsampc: [f64; 4],
    /// `[k0, k1]` from them.
    pub gains: [f64; 2],
    /// `[m, L, g]`.
    pub vessel: [f64; 3],
    /// Thrust limits.
    pub thrust_limits: [f64; 3],
    /// Force-noise standard deviations **\[A\]**.
    pub force_noise_sigma: [f64; 3],
    /// Reference-filter bandwidth of run B \[rad/s\] **\[A\]**.
    pub reference_omega: f64,
    /// Plant: Euler at δ = 0.1 s, the paper's discrete model.
    pub plant: String,
}

impl LoopSettings {
    fn digest() -> Result<Self, String> {
        let p = NsampcParams::paper();
        let g = p.gains().map_err(|e| e.to_string())?;
        let v = VesselParams::paper();
        Ok(Self {
            nsampc: [p.tp, p.mu1, p.mu2, p.mu3],
            gains: [g.k0, g.k1],
            vessel: [v.mass, v.length, v.gravity],
            thrust_limits: v.thrust.max,
            force_noise_sigma: ForceNoise::digest().sigma,
            reference_omega: ReferenceFilter::DIGEST_OMEGA,
            plant: "Euler at 0.1 s (the paper's discrete model (16)-(20)); the estimators use the same model".into(),
        })
    }
}

/// Everything `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Whether this was a `--quick` run.
    pub quick: bool,
    /// Base seed; seed `i` of every pair is `seed + i`.
    pub seed: u64,
    /// Run sizes.
    pub sizes: Sizes,
    /// The estimators' settings (heading noise of the rad² scenarios).
    pub filter: FilterSettings,
    /// `diag(Q)` of the matched-`Q` scenario.
    pub matched_q_diag: Vec<f64>,
    /// Controller and plant.
    pub loop_settings: LoopSettings,
    /// What is the paper's: no number.
    pub paper_numbers: String,
    /// Every (scenario, estimator), scenario-major.
    pub results: Vec<ResultSummary>,
    /// Comparison figures, `(file, caption)`.
    pub figures: Vec<(String, String)>,
    /// The paper's claims and verdicts.
    pub claims: Vec<report::Claim>,
    /// The certified position and heading of `smf-nl` with bounded noise (not the paper's
    /// experiment).
    pub certified: certified::CertifiedVessel,
    /// `mhe-ukf`'s runs replayed with real-time iterations, per scenario.
    pub real_time: Vec<real_time::RealTimeReplay>,
    /// Machine, build, load and wall-clock time.
    #[serde(flatten)]
    pub run: outputs::RunInfo,
}

/// What `summary.json` says about the paper's own numbers.
pub const PAPER_NUMBERS: &str = "none: the paper's formulas (1)-(61), Table 1 and Figs. 2-3 are lost; the model, \
                                 controller and estimator settings are the digest's reconstructions and assumptions, \
                                 and every number here comes from this reconstruction";

/// Runs the whole reproduction into `out` (`report.md`, `summary.json`, `figures/`, `csv/`).
///
/// # Errors
/// A failed run, or an output that cannot be written.
pub fn reproduce(quick: bool, out: &Path, seed: u64, runs: Option<usize>) -> Result<Summary, String> {
    let sizes = Sizes::new(quick, runs);
    if sizes.seeds == 0 {
        return Err("no seed to run (--runs 0?)".into());
    }
    let run = outputs::RunInfo::start();
    for sub in ["figures", "csv"] {
        std::fs::create_dir_all(out.join(sub)).map_err(|e| format!("creating {}: {e}", out.join(sub).display()))?;
    }
    let limits = VesselParams::paper().thrust.max;
    let total = SCENARIOS.len() * run::ESTIMATORS.len() * sizes.seeds;
    let bar = super::progress_bar(total as u64, "dp-vessel closed-loop runs");
    let mut results = Vec::new();
    let mut real_time = Vec::new();
    for scenario in &SCENARIOS {
        let mut replays = Vec::new();
        for spec in run::ESTIMATORS {
            let mut seeds = Vec::with_capacity(sizes.seeds);
            let mut step_ns = Vec::new();
            let mut first = None;
            for i in 0..sizes.seeds {
                let s = seed.wrapping_add(i as u64);
                let rec = run::run_one(scenario, spec, sizes.steps, s)?;
                if spec.id == estimators::registry::names::MHE_UKF {
                    let mut tally = real_time::ReplayTally::default();
                    real_time::replay(scenario, &rec, &mut tally)
                        .map_err(|e| format!("{} / seed {s}: {e}", scenario.id))?;
                    replays.push(tally);
                }
                let mut m = run::metrics(&rec, s, sizes.steady_from_s, limits);
                step_ns.append(&mut m.step_ns);
                seeds.push(m);
                if first.is_none() {
                    first = Some(rec);
                }
                bar.inc(1);
            }
            let first = first.ok_or("no seed")?;
            let csv = format!("{}_{}.csv", scenario.id, spec.id);
            figures::write_csv(&out.join("csv").join(&csv), &first).map_err(|e| format!("writing {csv}: {e}"))?;
            let figs = if scenario.figures {
                figures::run_figures(&out.join("figures"), scenario, spec, &first, seed)
                    .map_err(|e| format!("figures of {} / {}: {e}", scenario.id, spec.id))?
            } else {
                Vec::new()
            };
            results.push(ResultSummary {
                scenario: *scenario,
                estimator: spec.id.to_owned(),
                estimator_label: spec.label.to_owned(),
                aggregate: run::aggregate(&seeds),
                seeds,
                timing: StepTiming::of(step_ns),
                figures: figs,
                csv,
            });
        }
        real_time.push(real_time::RealTimeReplay::of(scenario.id, replays));
    }
    bar.finish_and_clear();
    let figures = figures::comparison_figures(&out.join("figures"), &results)
        .map_err(|e| format!("writing the comparison figures: {e}"))?;
    let claims = report::claims(&results);
    eprintln!("dp-vessel: certified position and heading (smf-nl) …");
    let certified = certified::run(seed, quick, &out.join("figures"))?;
    let summary = Summary {
        quick,
        seed,
        sizes,
        filter: FilterSettings::digest(0.1),
        matched_q_diag: run::matched_q_diag()?,
        loop_settings: LoopSettings::digest()?,
        paper_numbers: PAPER_NUMBERS.to_owned(),
        results,
        figures,
        claims,
        certified,
        real_time,
        run: run.finished(),
    };
    let report = format!(
        "{}\n{}\n{}",
        report::markdown(&summary),
        real_time::markdown(&summary.real_time),
        certified::markdown(&summary.certified)
    );
    outputs::write_summary_and_report(out, &summary, &report)?;
    Ok(summary)
}

impl Summary {
    /// The deterministic part of the summary (no timings, no machine), numbers rounded to 5
    /// significant digits: what snapshot tests compare.
    #[must_use]
    pub fn deterministic_view(&self) -> serde_json::Value {
        use serde_json::json;
        let r = outputs::five_digits;
        let sp = |s: &run::Spread| json!({"mean": r(s.mean), "min": r(s.min), "max": r(s.max), "missing": s.missing});
        let sp3 = |s: &run::Spread3| s.iter().map(sp).collect::<Vec<_>>();
        let mv =
            |m: &[run::MeanVar; 3]| m.iter().map(|v| json!({"mean": r(v.mean), "var": r(v.var)})).collect::<Vec<_>>();
        let results: Vec<_> = self
            .results
            .iter()
            .map(|res| {
                let a = &res.aggregate;
                json!({
                    "scenario": res.scenario.id,
                    "estimator": res.estimator,
                    "seeds": res.seeds.iter().map(|s| s.seed).collect::<Vec<_>>(),
                    "arrival_s": sp(&a.arrival_s),
                    "settling_s": sp3(&a.settling_s),
                    "overshoot": sp3(&a.overshoot),
                    "saturation": sp3(&a.saturation),
                    "total_variation": sp3(&a.total_variation),
                    "rmse_xy_psi": a.rmse[..3].iter().map(sp).collect::<Vec<_>>(),
                    "table1_raw": mv(&a.raw),
                    "table1_filtered": mv(&a.filtered),
                    "figures": res.figures.iter().map(|f| f.0.clone()).collect::<Vec<_>>(),
                    "csv": res.csv,
                })
            })
            .collect();
        json!({
            "quick": self.quick,
            "seed": self.seed,
            "sizes": self.sizes,
            "filter": self.filter,
            "matched_q_diag": self.matched_q_diag.iter().map(|v| r(*v)).collect::<Vec<_>>(),
            "paper_numbers": self.paper_numbers,
            "results": results,
            "figures": self.figures.iter().map(|f| f.0.clone()).collect::<Vec<_>>(),
            "claims": self.claims.iter().map(|c| json!({"claim": c.claim, "verdict": c.verdict})).collect::<Vec<_>>(),
            "real_time_distance_sigma": self
                .real_time
                .iter()
                .map(|x| json!({
                    "scenario": x.scenario,
                    "steps": x.steps,
                    "median_p99_worst": x.distance_sigma.iter().map(|d| d.map(r)).collect::<Vec<_>>(),
                }))
                .collect::<Vec<_>>(),
            "certified": {
                "seeds": self.certified.seeds,
                "steps": self.certified.steps,
                "misses": self.certified.misses,
                "guarantee_lost": self.certified.guarantee_lost,
                "truth_beyond_speed_limits": self.certified.truth_beyond_speed_limits,
                "without_limits_misses": self.certified.without_limits.misses,
                "median_x_width_m": r(self.certified.median_x_width_m),
                "median_psi_width_deg": r(self.certified.median_psi_width_deg),
                "ekf_band_misses": self.certified.ekf_band_misses,
                "zonotope_misses": self.certified.zonotope.misses,
                "zonotope_stopped": self.certified.zonotope.stopped,
            },
        })
    }
}

/// The supply-vessel paper in the multi-paper reproduction.
pub struct DpVesselPaper;

impl super::Paper for DpVesselPaper {
    fn name(&self) -> &'static str {
        "dp-vessel"
    }
    fn title(&self) -> &'static str {
        "Supply vessel, dynamic positioning with NSAMPC and the UKF-arrival-cost MHE (Su & Zhao 2016)"
    }
    fn run(&self, opts: &super::Options, out: &Path) -> Result<super::PaperOutcome, String> {
        let summary = reproduce(opts.quick, out, opts.seed, opts.runs)?;
        println!("{}", report::console(&summary));
        let verdicts = summary.claims.iter().map(|c| c.verdict.clone()).collect();
        Ok(super::PaperOutcome { claims: summary.claims.len(), verdicts })
    }
}
