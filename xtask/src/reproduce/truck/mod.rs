//! `cargo xtask reproduce --paper truck`: the EKF experiment of the port-truck paper (Yang, Zeng,
//! Lei & Huang, *港口装卸* 2023(6); digest `shared/papers/truck-ekf.md`, note
//! `docs/truck-ekf.md`): the digest's slalom with the richer truth model in place of TruckSim,
//! nominal and four mismatch cases, several noise seeds, figures, CSV files and a report judging
//! the paper's three claims.
//!
//! The paper's Table 2 (its errors) is lost, and so is Table 1 (vehicle data): every number
//! here comes from this reconstruction, none is the paper's.

pub mod cases;
pub mod certified;
pub mod figures;
pub mod report;
pub mod run;

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use truck_dynamics::{Slalom, TruckEkfModel, TruckParams, TruthConfig, TruthTrajectory, simulate_truth};

use super::outputs;
use cases::Case;
use run::{Aggregate, EkfSettings, SeedMetrics, StepTiming, Trace};

/// Sizes of a run: the full reproduction or the few-second `--quick` mode.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Sizes {
    /// Duration of the slalom \[s\] (the paper's 12 s; 4 s in `--quick`).
    pub duration_s: f64,
    /// EKF steps per run (`duration / T`).
    pub steps: usize,
    /// Noise seeds per case (10; 2 in `--quick`; `--runs` overrides).
    pub seeds: usize,
}

impl Sizes {
    /// The sizes of a full or `--quick` run; `runs` overrides the number of seeds.
    #[must_use]
    pub fn new(quick: bool, runs: Option<usize>) -> Self {
        let (duration_s, seeds) = if quick { (4.0, 2) } else { (12.0, 10) };
        let steps = (duration_s / truck_dynamics::PAPER_SAMPLE_PERIOD).round() as usize;
        Self { duration_s, steps, seeds: runs.unwrap_or(seeds) }
    }
}

/// Peaks of a case's truth.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct TruthPeaks {
    /// `max |a_y|` \[m/s²\].
    pub ay_mps2: f64,
    /// `max |γ|` \[°/s\].
    pub gamma_degps: f64,
    /// `max |β|` \[°\].
    pub beta_deg: f64,
    /// `max |V_x − 70 km/h|` \[m/s\].
    pub vx_deviation_mps: f64,
}

/// One case's results in `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct CaseSummary {
    /// Identifier (file names).
    pub id: String,
    /// Title.
    pub title: String,
    /// Shorter label.
    pub short: String,
    /// On which side the change applies (the truth or the EKF) and how.
    pub applies_to: String,
    /// Peaks of the truth.
    pub truth_peaks: TruthPeaks,
    /// Convergence threshold of `β` \[°\]: 10 % of the truth's `max |β|`.
    pub beta_threshold_deg: f64,
    /// Metrics of each seed.
    pub seeds: Vec<SeedMetrics>,
    /// Metrics over the seeds.
    pub aggregate: Aggregate,
    /// Wall time of `ExtendedKalmanFilter::step`, pooled over the seeds.
    pub timing: StepTiming,
    /// Figures written, `(file, caption)`.
    pub figures: Vec<(String, String)>,
    /// The CSV file of the first seed's run (relative to `csv/`).
    pub csv: String,
}

/// Everything `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Whether this was a `--quick` run.
    pub quick: bool,
    /// Base seed; seed `i` of every case is `seed + i`.
    pub seed: u64,
    /// Run sizes.
    pub sizes: Sizes,
    /// The EKF's settings (digest §4, assumed).
    pub settings: EkfSettings,
    /// What is the paper's: no number (Table 2 is lost).
    pub paper_numbers: String,
    /// The cases, nominal first.
    pub cases: Vec<CaseSummary>,
    /// A linear Kalman filter of the same size on the same data, for scale.
    pub kalman_step: StepTiming,
    /// Comparison figures across cases, `(file, caption)`.
    pub figures: Vec<(String, String)>,
    /// The paper's claims and verdicts.
    pub claims: Vec<report::Claim>,
    /// Seconds spent simulating the truths.
    pub truth_seconds: f64,
    /// The certified sideslip of `smf-nl` with bounded noise (not the paper's experiment).
    pub certified: certified::CertifiedSummary,
    /// Machine, build, load and wall-clock time.
    #[serde(flatten)]
    pub run: outputs::RunInfo,
}

/// What `summary.json` says about the paper's own numbers.
pub const PAPER_NUMBERS: &str = "none: the paper's Table 2 (estimation errors) and Table 1 (vehicle parameters) are \
                                 lost; every number here comes from this reconstruction (assumed vehicle, tyres \
                                 mapped from a public 315/80R22.5 file, a truth model in place of TruckSim)";

/// Simulates the digest's slalom with `params` for `duration` seconds.
fn simulate(params: &TruckParams, duration: f64) -> Result<TruthTrajectory, String> {
    let slalom = Slalom::digest();
    let config = TruthConfig { duration, ..TruthConfig::digest() };
    simulate_truth(params, &config, |t| slalom.angle(t)).map_err(|e| format!("truth simulation: {e}"))
}

fn peaks(truth: &TruthTrajectory) -> TruthPeaks {
    let max =
        |f: &dyn Fn(&truck_dynamics::TruthSample) -> f64| truth.samples.iter().map(|s| f(s).abs()).fold(0.0, f64::max);
    let v = TruthConfig::digest().target_speed;
    TruthPeaks {
        ay_mps2: max(&|s| s.ay),
        gamma_degps: max(&|s| s.gamma).to_degrees(),
        beta_deg: max(&|s| s.beta).to_degrees(),
        vx_deviation_mps: max(&|s| s.vx - v),
    }
}

/// Runs every seed of one case; returns its summary and the first seed's trace.
fn run_case(
    case: &Case,
    truth: &TruthTrajectory,
    model: &TruckEkfModel,
    sizes: Sizes,
    base_seed: u64,
    out: &Path,
    bar: &indicatif::ProgressBar,
) -> Result<(CaseSummary, Trace), String> {
    let truth_peaks = peaks(truth);
    let threshold = run::CONVERGENCE_FRACTION * truth_peaks.beta_deg.to_radians();
    let mut seeds = Vec::with_capacity(sizes.seeds);
    let mut step_ns = Vec::with_capacity(sizes.seeds * sizes.steps);
    let mut first = None;
    for i in 0..sizes.seeds {
        let seed = base_seed.wrapping_add(i as u64);
        let trace = run::run_ekf(truth, model, case, seed)?;
        seeds.push(run::seed_metrics(&trace, seed, threshold));
        step_ns.extend_from_slice(&trace.step_ns);
        if first.is_none() {
            first = Some(trace);
        }
        bar.inc(1);
    }
    let first = first.ok_or("no seed to run (--runs 0?)")?;
    let csv = format!("{}.csv", case.id);
    figures::write_csv(&out.join("csv").join(&csv), &first).map_err(|e| format!("writing {csv}: {e}"))?;
    let figures = figures::case_figure(&out.join("figures"), case, &first, base_seed)
        .map_err(|e| format!("writing the figure of {}: {e}", case.id))?;
    let summary = CaseSummary {
        id: case.id.to_owned(),
        title: case.title.to_owned(),
        short: case.short.to_owned(),
        applies_to: case.applies_to.to_owned(),
        truth_peaks,
        beta_threshold_deg: threshold.to_degrees(),
        aggregate: run::aggregate(&seeds),
        seeds,
        timing: StepTiming::of(step_ns),
        figures,
        csv,
    };
    Ok((summary, first))
}

/// Runs the whole reproduction into `out` and returns its summary (also written as
/// `summary.json`, with `report.md`, `figures/` and `csv/`). `runs` overrides the number of
/// seeds.
///
/// # Errors
/// A failed simulation or filter step, or an output that cannot be written.
pub fn reproduce(quick: bool, out: &Path, seed: u64, runs: Option<usize>) -> Result<Summary, String> {
    let sizes = Sizes::new(quick, runs);
    let run = outputs::RunInfo::start();
    for sub in ["figures", "csv"] {
        std::fs::create_dir_all(out.join(sub)).map_err(|e| format!("creating {}: {e}", out.join(sub).display()))?;
    }
    let cases = cases::all();
    let model = TruckEkfModel::paper(TruckParams::digest_preset()).map_err(|e| format!("EKF model: {e}"))?;
    // One truth per distinct set of vehicle data (the EKF-side cases reuse the nominal truth).
    let t_truth = Instant::now();
    let mut truths: Vec<(TruckParams, TruthTrajectory)> = Vec::new();
    for c in &cases {
        if !truths.iter().any(|(p, _)| *p == c.truth_params) {
            eprintln!("truck: simulating the truth for {} ({} s) …", c.id, sizes.duration_s);
            truths.push((c.truth_params, simulate(&c.truth_params, sizes.duration_s)?));
        }
    }
    let truth_seconds = t_truth.elapsed().as_secs_f64();
    let truth_of =
        |c: &Case| truths.iter().find(|(p, _)| *p == c.truth_params).map(|(_, t)| t).ok_or("truth not simulated");
    let bar = super::progress_bar((cases.len() * sizes.seeds) as u64, "truck EKF runs");
    let mut summaries = Vec::new();
    let mut traces = Vec::new();
    for c in &cases {
        let (s, trace) = run_case(c, truth_of(c)?, &model, sizes, seed, out, &bar)?;
        summaries.push(s);
        traces.push(trace);
    }
    bar.finish_and_clear();
    let kalman_step = run::kalman_step_timing(truth_of(&cases[0])?, &model, seed)?;
    eprintln!("truck: certified sideslip (smf-nl) …");
    let certified = certified::run(truth_of(&cases[0])?, &model, seed, quick, out)?;
    let figures = figures::comparison_figures(&out.join("figures"), &summaries, &traces)
        .map_err(|e| format!("writing the comparison figures: {e}"))?;
    let claims = report::claims(&summaries, &kalman_step);
    let summary = Summary {
        quick,
        seed,
        sizes,
        settings: EkfSettings::digest(),
        paper_numbers: PAPER_NUMBERS.to_owned(),
        cases: summaries,
        kalman_step,
        figures,
        claims,
        truth_seconds,
        certified,
        run: run.finished(),
    };
    let report = format!("{}\n{}", report::markdown(&summary), certified::markdown(&summary.certified));
    outputs::write_summary_and_report(out, &summary, &report)?;
    Ok(summary)
}

impl Summary {
    /// The deterministic part of the summary (no timings, no machine, no timing verdict), with
    /// numbers rounded to 5 significant digits: what snapshot tests compare.
    #[must_use]
    pub fn deterministic_view(&self) -> serde_json::Value {
        use serde_json::json;
        let r = outputs::five_digits;
        let spread = |s: &run::Spread| json!({"mean": r(s.mean), "min": r(s.min), "max": r(s.max)});
        let stats = |s: &run::StatsSpread| json!({"max_abs": spread(&s.max_abs), "rmse": spread(&s.rmse), "mean_abs": spread(&s.mean_abs)});
        let signal = |s: &run::SignalSpread| json!({"whole": stats(&s.whole), "first_2s": stats(&s.first_2s), "after_2s": stats(&s.after_2s)});
        let cases: Vec<_> = self
            .cases
            .iter()
            .map(|c| {
                let a = &c.aggregate;
                json!({
                    "id": c.id,
                    "truth_peaks": {
                        "ay_mps2": r(c.truth_peaks.ay_mps2),
                        "gamma_degps": r(c.truth_peaks.gamma_degps),
                        "beta_deg": r(c.truth_peaks.beta_deg),
                        "vx_deviation_mps": r(c.truth_peaks.vx_deviation_mps),
                    },
                    "beta_threshold_deg": r(c.beta_threshold_deg),
                    "seeds": c.seeds.iter().map(|s| s.seed).collect::<Vec<_>>(),
                    "vx_mps": signal(&a.vx_mps),
                    "gamma_degps": signal(&a.gamma_degps),
                    "beta_deg": signal(&a.beta_deg),
                    "beta_convergence_s": spread(&a.beta_convergence_s),
                    "beta_not_converged": a.beta_not_converged,
                    "beta_within_2sigma": spread(&a.beta_within_2sigma),
                    "figures": c.figures.iter().map(|f| f.0.clone()).collect::<Vec<_>>(),
                    "csv": c.csv,
                })
            })
            .collect();
        json!({
            "quick": self.quick,
            "seed": self.seed,
            "sizes": self.sizes,
            "settings": self.settings,
            "paper_numbers": self.paper_numbers,
            "cases": cases,
            "figures": self.figures.iter().map(|f| f.0.clone()).collect::<Vec<_>>(),
            "certified": {
                "steps": self.certified.steps,
                "misses": self.certified.misses,
                "beta_misses": self.certified.beta_misses,
                "guarantee_lost": self.certified.guarantee_lost,
                "median_beta_width_deg": r(self.certified.median_beta_width_deg),
                "median_ekf_band_width_deg": r(self.certified.median_ekf_band_width_deg),
                "zonotope_misses": self.certified.zonotope.misses,
                "zonotope_stopped": self.certified.zonotope.stopped.is_some(),
                "monte_carlo": {
                    "seeds": self.certified.monte_carlo.seeds,
                    "steps": self.certified.monte_carlo.steps,
                    "misses": self.certified.monte_carlo.misses,
                    "guarantee_lost": self.certified.monte_carlo.guarantee_lost,
                },
            },
            "claims": self.claims.iter().map(|c| {
                if c.timing_dependent {
                    json!({"claim": c.claim})
                } else {
                    json!({"claim": c.claim, "verdict": c.verdict})
                }
            }).collect::<Vec<_>>(),
        })
    }
}

/// The truck paper in the multi-paper reproduction.
pub struct TruckPaper;

impl super::Paper for TruckPaper {
    fn name(&self) -> &'static str {
        "truck"
    }
    fn title(&self) -> &'static str {
        "Port container truck, extended Kalman filter (Yang, Zeng, Lei & Huang 2023)"
    }
    fn run(&self, opts: &super::Options, out: &Path) -> Result<super::PaperOutcome, String> {
        let summary = reproduce(opts.quick, out, opts.seed, opts.runs)?;
        println!("{}", report::console(&summary));
        let verdicts = summary.claims.iter().map(|c| c.verdict.clone()).collect();
        Ok(super::PaperOutcome { claims: summary.claims.len(), verdicts })
    }
}
