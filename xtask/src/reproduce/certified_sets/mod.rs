//! `cargo xtask reproduce --paper certified-sets`: the tight certified sets (constrained-zonotope
//! filters, docs/constrained-zonotopes.md) against the targets they were built for — CORA's
//! published six-tank hulls ([`six_tank`]), containment with every noise on the boundary of its
//! box over ≥ 10⁶ steps, bounded widths on a vehicle without a compass and on one measured by
//! range and bearing only, no wider than the
//! ellipsoidal filter on the carrier ([`campaign`]), and the step times side by side.
//!
//! Not one of the five papers: a benchmark of the workspace's own method. The only published
//! numbers are CORA's saved hulls, read from examples/six-tank/cora_hulls.csv.

pub mod campaign;
pub mod six_tank;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use estimators::ConstrainedZonotopeSettings;
use estimators::registry::EstimatorSettings;
use serde::Serialize;

use super::outputs;
use super::{Options, Paper, PaperOutcome};

/// The benchmark in the index.
pub struct CertifiedSetsPaper;

impl Paper for CertifiedSetsPaper {
    fn name(&self) -> &'static str {
        "certified-sets"
    }
    fn title(&self) -> &'static str {
        "Tight certified sets: CORA's six-tank benchmark, boundary noise at scale (not a paper of the five)"
    }
    fn run(&self, opts: &Options, out: &Path) -> Result<PaperOutcome, String> {
        let s = reproduce(opts, out)?;
        Ok(PaperOutcome { claims: s.claims.len(), verdicts: s.claims.iter().map(|c| c.verdict.clone()).collect() })
    }
}

pub use crate::reproduce::outputs::Claim;

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The six-tank comparison.
    pub six_tank: six_tank::SixTank,
    /// The boundary-noise runs.
    pub campaign: Vec<campaign::ScenarioResult>,
    /// The targets.
    pub claims: Vec<Claim>,
}

/// The settings of `czf-nl` that a model file gives (its `[estimator.czf-nl]` table over its
/// bounds), as `port-est filter --estimator czf-nl` runs it.
///
/// # Errors
/// Settings the file lacks, or settings of another kind.
pub fn czf_settings(model: &port_est::Model) -> Result<ConstrainedZonotopeSettings, String> {
    let path = model.path().display();
    match port_est::filter::estimator_settings(model, "czf-nl").map_err(|e| format!("{path}: {e}"))? {
        Some(EstimatorSettings::ConstrainedZonotope(s)) => Ok(s),
        other => Err(format!("{path}: czf-nl's settings are {other:?}, not a constrained zonotope's")),
    }
}

/// The repository's root (xtask runs from a checkout).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Steps the containment target asks for.
pub const CONTAINMENT_STEPS: usize = 1_000_000;

fn verdict(ok: bool) -> String {
    if ok { "met".into() } else { "not met".into() }
}

fn claims(t: &six_tank::SixTank, c: &[campaign::ScenarioResult]) -> Vec<Claim> {
    let mut out = Vec::new();
    let beats = (0..6).all(|i| t.widths[i] <= t.cora_best[i]) && t.widths[0] < 0.490 && t.mean < t.cora_best_mean;
    out.push(Claim {
        claim: "Six-tank (CORA's published case): every final width at most CORA's best, x1 below 0.490, the mean \
                below CORA's best mean"
            .into(),
        verdict: verdict(beats),
        evidence: format!(
            "czf-nl at order {}, {} constraints (the model file's choice) {:.4?} (mean {:.4}); at the default order \
             {}, {} constraints {:.4?} (mean {:.4}); CORA's best {:.4?} (mean {:.4})",
            t.order.0,
            t.order.1,
            t.widths,
            t.mean,
            t.default_order.order.0,
            t.default_order.order.1,
            t.default_order.widths,
            t.default_order.mean,
            t.cora_best,
            t.cora_best_mean
        ),
    });
    let steps: usize = c.iter().map(|s| s.steps).sum();
    // Every certified filter's misses: `czf`/`czf-nl`, and `smf` alone and observed beside the carrier's.
    let misses: usize =
        c.iter().map(|s| s.misses + s.ellipsoid.as_ref().map_or(0, |e| e.misses + e.observer_misses)).sum();
    let stopped: usize = c.iter().map(|s| s.stopped.len()).sum();
    let per: Vec<String> = c.iter().map(|s| format!("{} {} steps, {} misses", s.name, s.steps, s.misses)).collect();
    out.push(Claim {
        claim: format!("0 containment misses over ≥ {CONTAINMENT_STEPS} steps with every noise on its box's boundary"),
        verdict: if misses == 0 && stopped == 0 && steps >= CONTAINMENT_STEPS {
            verdict(true)
        } else if misses == 0 && stopped == 0 {
            format!("not met at these sizes: 0 misses, but {steps} steps (the full run takes ≥ {CONTAINMENT_STEPS})")
        } else {
            verdict(false)
        },
        evidence: format!("{}; runs stopped: {stopped}", per.join("; ")),
    });
    if let Some(r) = c.iter().find(|s| s.name == "reach-stacker") {
        let bounded = r.stopped.is_empty() && r.misses == 0 && r.worst_growth[2] <= 2.0;
        let per_run = r.steps / r.runs.max(1);
        out.push(Claim {
            claim: "Reach stacker without a compass: no GuaranteeLost, the heading's median width over the last \
                    tenth at most twice that over the second tenth, in every run"
                .into(),
            verdict: if bounded && per_run < 10_000 {
                format!("not met at these sizes: bounded, but {per_run} steps per run (the full run takes 10 000)")
            } else {
                verdict(bounded)
            },
            evidence: format!(
                "{} runs × {} steps; heading width {:.4} rad (second tenth) → {:.4} rad (last tenth), medians over \
                 runs; worst ratio {:.3}",
                r.runs, per_run, r.width_early[2], r.width_late[2], r.worst_growth[2]
            ),
        });
    }
    for (name, drive) in [
        ("range-bearing", "driving back and forth"),
        ("range-bearing circling", "circling, both bearings crossing ±π every turn"),
    ] {
        let Some(r) = c.iter().find(|s| s.name == name) else { continue };
        let worst = r.worst_growth.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let bounded = r.stopped.is_empty() && r.misses == 0 && worst <= 2.0;
        let per_run = r.steps / r.runs.max(1);
        out.push(Claim {
            claim: format!(
                "Range–bearing vehicle (no GNSS, no compass), {drive}: no GuaranteeLost, every state's median \
                 width over the last tenth at most twice that over the second tenth, in every run"
            ),
            verdict: if bounded && per_run < 10_000 {
                format!("not met at these sizes: bounded, but {per_run} steps per run (the full run takes 10 000)")
            } else if per_run < 10_000 {
                format!("not met at these sizes: {per_run} steps per run compare different phases of the drive")
            } else {
                verdict(bounded)
            },
            evidence: format!(
                "{} runs × {} steps; widths (second tenth → last tenth, medians over runs) {:.4?} → {:.4?}; worst \
                 ratio {:.3} (per state {:.2?}); the same rule on the 90th percentile instead of the median: worst \
                 ratio per state {:.2?}; widest after the first tenth, any run: {:.4?}",
                r.runs, per_run, r.width_early, r.width_late, worst, r.worst_growth, r.worst_growth_p90, r.widest
            ),
        });
    }
    if let Some(e) = c.iter().find(|s| s.name == "carrier").and_then(|s| s.ellipsoid.as_ref()) {
        out.push(Claim {
            claim: "Carrier: czf's interval no wider than smf's on every state (after step 50)".into(),
            verdict: verdict(e.czf_wider_steps == 0),
            evidence: format!(
                "wider on some state at {} of {} steps; median width ratio czf/smf per state {:.3?}",
                e.czf_wider_steps, e.steps_compared, e.median_width_ratio
            ),
        });
    }
    let carrier = c.iter().find(|s| s.name == "carrier").map_or(f64::NAN, |s| s.step_time.median_us);
    let carrier_order = c.iter().find(|s| s.name == "carrier").map_or(0, |s| s.order);
    out.push(Claim {
        claim: "Cost per step: six-tank nonlinear step ≤ 200 µs at the chosen order; carrier linear step ≤ 20 µs"
            .into(),
        verdict: verdict(t.step_time.median_us <= 200.0 && carrier <= 20.0),
        evidence: format!(
            "medians: six-tank {:.0} µs at order {}, {} constraints (the default order: {:.0} µs), carrier {:.0} µs at \
             order {} (this run's carrier steps share both cores with the other runs; the criterion bench, quiet, is \
             in docs/results/performance.md)",
            t.step_time.median_us, t.order.0, t.order.1, t.default_order.step_time.median_us, carrier, carrier_order
        ),
    });
    out
}

fn report(s: &Summary, opts: &Options) -> String {
    let mut md = String::from("# Tight certified sets\n\n");
    let _ = writeln!(
        md,
        "Not a paper of the five: the constrained-zonotope filters (docs/constrained-zonotopes.md) against the \
         targets they were built for. The only published numbers are CORA's saved six-tank hulls \
         (examples/six-tank/cora_hulls.csv; provenance in examples/six-tank/README.md). Seed {}{}; machine: {}.\n",
        opts.seed,
        if opts.quick { ", `--quick` sizes" } else { "" },
        outputs::machine()
    );
    md.push_str("## Targets\n\n| target | verdict | evidence |\n|---|---|---|\n");
    for c in &s.claims {
        let _ = writeln!(md, "| {} | **{}** | {} |", c.claim, c.verdict, c.evidence);
    }
    let t = &s.six_tank;
    md.push_str(
        "\n## CORA's six-tank benchmark: final widths (t = 9.5 s)\n\n| | x1 | x2 | x3 | x4 | x5 | x6 | mean |\n",
    );
    md.push_str("|---|---:|---:|---:|---:|---:|---:|---:|\n");
    let row = |name: &str, w: &[f64]| {
        let cells: Vec<String> = w.iter().map(|v| format!("{v:.4}")).collect();
        format!("| {name} | {} | {:.4} |\n", cells.join(" | "), w.iter().sum::<f64>() / w.len() as f64)
    };
    for (name, w) in &t.cora {
        md.push_str(&row(&format!("CORA {name} (published)"), w));
    }
    md.push_str(&row(&format!("`czf-nl`, order {}, {} constraints (this run)", t.order.0, t.order.1), &t.widths));
    let d = &t.default_order;
    md.push_str(&row(
        &format!("`czf-nl`, default order {}, {} constraints (this run)", d.order.0, d.order.1),
        &d.widths,
    ));
    let _ = writeln!(
        md,
        "\nSteps not clean on CORA's data: {}. Step time at order {}, {} constraints (the model file's \
         `[estimator.czf-nl]`): median {:.0} µs, 99th percentile {:.0} µs; at the default order: median {:.0} µs, \
         99th percentile {:.0} µs ({} steps each).\n",
        t.unclean_steps,
        t.order.0,
        t.order.1,
        t.step_time.median_us,
        t.step_time.p99_us,
        d.step_time.median_us,
        d.step_time.p99_us,
        t.step_time.steps_timed
    );
    md.push_str(
        "## Boundary noise\n\nEvery noise on a vertex of its box, the initial state on a vertex of X₀; every step's \
         published interval checked against the truth. Runs on every core at once: step times are side by side \
         within a run (the carrier's `czf` and `smf` alternate on the same data), not quiet-machine figures.\n\n\
         | model | order, constraints | runs × steps | misses | stopped | diverging steps | width, second tenth | \
         width, last tenth | step median / p99 |\n|---|---|---|---:|---:|---:|---|---|---|\n",
    );
    for c in &s.campaign {
        let w = |v: &[f64]| v.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>().join(", ");
        let _ = writeln!(
            md,
            "| {} | {}, {} | {} × {} | {} | {} | {} | [{}] | [{}] | {:.0} / {:.0} µs |",
            c.name,
            c.order,
            c.max_constraints,
            c.runs,
            c.steps / c.runs.max(1),
            c.misses,
            c.stopped.len(),
            c.diverging_steps,
            w(&c.width_early),
            w(&c.width_late),
            c.step_time.median_us,
            c.step_time.p99_us
        );
    }
    for c in &s.campaign {
        for stop in &c.stopped {
            let _ = writeln!(md, "\n- {} stopped: {stop}", c.name);
        }
        if let Some(e) = &c.ellipsoid {
            let _ = writeln!(
                md,
                "\n`smf` beside `czf` on the {} (least-trace ellipsoids around the same boxes): {} misses; `czf` wider \
                 on some state at {} of {} steps; median width ratio czf/smf per state {:.3?}; `smf` step median {:.1} \
                 µs, p99 {:.1} µs — `czf` costs {:.0}× `smf` at the median.",
                c.name,
                e.misses,
                e.czf_wider_steps,
                e.steps_compared,
                e.median_width_ratio,
                e.step_time.median_us,
                e.step_time.p99_us,
                c.step_time.median_us / e.step_time.median_us
            );
            let _ = writeln!(
                md,
                "\n`smf` with its interval observer (the registry's default, docs/carrier-smf.md §4.8) on the same \
                 data: {} misses; median width ratio observer/`smf` alone per state {:.3?}.",
                e.observer_misses, e.observer_width_ratio
            );
        }
    }
    md
}

/// Runs the benchmark into `out`.
///
/// # Errors
/// A file or filter error.
pub fn reproduce(opts: &Options, out: &Path) -> Result<Summary, String> {
    let root = root();
    eprintln!("six-tank: CORA's data");
    let six_tank = six_tank::run(&root, opts.quick)?;
    let campaign = campaign::run(&root, opts.seed, opts.quick, opts.runs)?;
    let claims = claims(&six_tank, &campaign);
    let summary = Summary { six_tank, campaign, claims };
    outputs::write_summary_and_report(out, &summary, &report(&summary, opts))?;
    Ok(summary)
}
