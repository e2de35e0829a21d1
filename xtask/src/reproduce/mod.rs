//! `cargo xtask reproduce [--paper NAME] [--quick] [--out DIR] [--seed S] [--runs R]`: every
//! paper's experiment (or one), each into `DIR/NAME/` with its report, and `DIR/index.md` linking
//! the reports with their claim counts and wall times.
//!
//! One module per paper (scenarios, runner, report) implements [`Paper`]; the pieces they share
//! are written once: [`runner`] (driving registry estimators over simulated data, metrics),
//! [`outputs`] (CSV, atomic writes, writing the figures of [`svg_plot`]).

pub mod bds_ins;
pub mod carrier;
pub mod dp_vessel;
pub mod outputs;
pub mod rmhe;
pub mod runner;
pub mod truck;

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::args::Args;

/// Options shared by every paper's reproduction.
#[derive(Debug, Clone)]
pub struct Options {
    /// A few-second version (smaller sizes; same code paths).
    pub quick: bool,
    /// Base seed.
    pub seed: u64,
    /// Override of the number of Monte Carlo runs.
    pub runs: Option<usize>,
}

/// What one paper's reproduction reports back to the index.
#[derive(Debug, Clone)]
pub struct PaperOutcome {
    /// Number of the paper's claims judged.
    pub claims: usize,
    /// The verdict of each claim.
    pub verdicts: Vec<String>,
}

/// One paper's reproduction.
pub trait Paper {
    /// Short name (`--paper NAME`, output directory).
    fn name(&self) -> &'static str;
    /// Title for the index.
    fn title(&self) -> &'static str;
    /// Runs the reproduction into `out` (created by the caller), writing at least `report.md`.
    ///
    /// # Errors
    /// A message naming what failed.
    fn run(&self, opts: &Options, out: &Path) -> Result<PaperOutcome, String>;
}

/// Every paper, in the order of the index.
pub fn papers() -> Vec<Box<dyn Paper>> {
    vec![
        Box::new(carrier::CarrierPaper),
        Box::new(truck::TruckPaper),
        Box::new(bds_ins::BdsInsPaper),
        Box::new(rmhe::RmhePaper),
        Box::new(dp_vessel::DpVesselPaper),
    ]
}

/// Default base seed of the reproduction.
pub const DEFAULT_SEED: u64 = carrier::DEFAULT_SEED;

/// A progress bar on standard error, hidden when standard error is not a terminal.
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::with_draw_target(Some(len), indicatif::ProgressDrawTarget::stderr());
    if let Ok(style) = indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({elapsed})") {
        bar.set_style(style.progress_chars("#>-"));
    }
    bar.set_message(what.to_owned());
    bar
}

/// Runs the papers selected by `paper` (all if `None`) into `out/NAME/` and writes
/// `out/index.md`; returns each paper's name, outcome and wall time.
///
/// # Errors
/// An unknown paper name, a failed reproduction, or an output that cannot be written.
pub fn reproduce_papers(
    paper: Option<&str>,
    opts: &Options,
    out: &Path,
) -> Result<Vec<(&'static str, &'static str, PaperOutcome, f64)>, String> {
    let all = papers();
    let selected: Vec<&Box<dyn Paper>> = match paper {
        None => all.iter().collect(),
        Some(name) => {
            let p = all.iter().find(|p| p.name() == name).ok_or_else(|| {
                format!(
                    "unknown paper {name:?} (known: {})",
                    all.iter().map(|p| p.name()).collect::<Vec<_>>().join(", ")
                )
            })?;
            vec![p]
        }
    };
    std::fs::create_dir_all(out).map_err(|e| format!("creating {}: {e}", out.display()))?;
    let mut done = Vec::new();
    for p in selected {
        let dir = out.join(p.name());
        std::fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
        eprintln!("== paper {}: {}", p.name(), p.title());
        let t0 = Instant::now();
        let outcome = p.run(opts, &dir).map_err(|e| format!("paper {}: {e}", p.name()))?;
        done.push((p.name(), p.title(), outcome, t0.elapsed().as_secs_f64()));
    }
    outputs::write_atomic(&out.join("index.md"), index(&done, opts).as_bytes())
        .map_err(|e| format!("writing {}: {e}", out.join("index.md").display()))?;
    Ok(done)
}

fn index(done: &[(&'static str, &'static str, PaperOutcome, f64)], opts: &Options) -> String {
    let mut s = String::from("# Reproductions\n\n");
    s.push_str(&format!(
        "Base seed {}{}. Each report says which numbers are the paper's and which are reconstructed.\n\n",
        opts.seed,
        if opts.quick { ", `--quick` sizes (not the full experiment)" } else { "" }
    ));
    s.push_str("| paper | report | claims | reproduced (fully or with a stated condition) | wall time |\n|---|---|---:|---:|---:|\n");
    for (name, title, o, secs) in done {
        let reproduced = o.verdicts.iter().filter(|v| v.starts_with("reproduced")).count();
        s.push_str(&format!(
            "| {title} | [{name}/report.md]({name}/report.md) | {} | {reproduced} | {secs:.1} s |\n",
            o.claims
        ));
    }
    s
}

/// Entry point of `cargo xtask reproduce`.
///
/// # Errors
/// Bad arguments or a failed reproduction.
pub fn run(args: &[String]) -> Result<(), String> {
    let args = Args::parse(args, &["out", "seed", "runs", "paper"], &["quick"])?;
    let out = PathBuf::from(args.value("out").unwrap_or("out/reproduce"));
    let seed: u64 = match args.value("seed") {
        Some(s) => s.parse().map_err(|_| format!("--seed: not an integer: {s:?}"))?,
        None => DEFAULT_SEED,
    };
    let runs = match args.value("runs") {
        Some(s) => {
            Some(s.parse::<usize>().ok().filter(|r| *r > 0).ok_or(format!("--runs: not a positive integer: {s:?}"))?)
        }
        None => None,
    };
    let opts = Options { quick: args.flag("quick"), seed, runs };
    let t0 = Instant::now();
    let done = reproduce_papers(args.value("paper"), &opts, &out)?;
    for (name, _, o, secs) in &done {
        println!("{name}: {} claims judged, {secs:.1} s → {}", o.claims, out.join(name).join("report.md").display());
    }
    println!("Wrote {} in {:.1} s.", out.join("index.md").display(), t0.elapsed().as_secs_f64());
    Ok(())
}
