//! `cargo xtask reproduce [--paper NAME] [--quick] [--out DIR] [--seed S] [--runs R]`: every
//! paper's experiment (or one), each into `DIR/NAME/` with its report, and `DIR/index.md` linking
//! the reports with their claim counts, seeds and wall times.
//!
//! A paper's directory is built beside its target and renamed into place when the paper is done
//! ([`atomic_output::AtomicDir`]): an interrupted run leaves the previous complete directory (or
//! none), never a mix of two runs; its hidden build directory is removed on SIGINT/SIGTERM, or by
//! the next run if the process was killed. The index lists every paper present in `DIR`, each
//! with its own record (`index`), so `--paper NAME` keeps the other papers' rows.
//!
//! One module per paper (scenarios, runner, report) implements [`Paper`]; the pieces they share
//! are written once: [`runner`] (driving registry estimators over simulated data, metrics),
//! [`outputs`] (CSV, atomic writes, writing the figures of [`svg_plot`]).

pub mod bds_ins;
pub mod carrier;
pub mod certified_sets;
pub mod dp_vessel;
pub mod index;
pub mod outputs;
pub mod rmhe;
pub mod runner;
pub mod truck;

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Instant;

use atomic_output::AtomicDir;

use crate::args::{Args, Parsed};

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
        Box::new(certified_sets::CertifiedSetsPaper),
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

/// The most Monte Carlo runs `--runs` accepts: some papers keep per-run results, so this bounds
/// their memory (and the time, at about a second per run for the slowest paper).
pub const MAX_RUNS: usize = 10_000;

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
    reproduce_with(&papers(), paper, opts, out)
}

/// [`reproduce_papers`] over the papers `all` (tests use stand-ins).
///
/// # Errors
/// As [`reproduce_papers`].
pub fn reproduce_with(
    all: &[Box<dyn Paper>],
    paper: Option<&str>,
    opts: &Options,
    out: &Path,
) -> Result<Vec<(&'static str, &'static str, PaperOutcome, f64)>, String> {
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
        let target = out.join(p.name());
        // Build directories of runs that were killed: they are ours, and incomplete.
        for stale in atomic_output::stale_temporaries(&target).unwrap_or_default() {
            eprintln!("removing {}, left incomplete by an interrupted run", stale.path.display());
            let _ = std::fs::remove_dir_all(&stale.path);
        }
        let building = AtomicDir::create(&target).map_err(|e| format!("creating {}: {e}", target.display()))?;
        eprintln!("== paper {}: {}", p.name(), p.title());
        let t0 = Instant::now();
        let outcome = p.run(opts, building.path()).map_err(|e| format!("paper {}: {e}", p.name()))?;
        let seconds = t0.elapsed().as_secs_f64();
        let record = index::RunRecord {
            name: p.name().to_owned(),
            title: p.title().to_owned(),
            claims: outcome.claims,
            reproduced: outcome.verdicts.iter().filter(|v| v.starts_with("reproduced") || *v == "met").count(),
            seed: opts.seed,
            quick: opts.quick,
            runs: opts.runs,
            seconds,
        };
        let json = serde_json::to_string_pretty(&record).map_err(|e| e.to_string())?;
        outputs::write_atomic(&building.path().join(index::RECORD), json.as_bytes())
            .map_err(|e| format!("paper {}: writing {}: {e}", p.name(), index::RECORD))?;
        building.commit().map_err(|e| format!("paper {}: publishing {}: {e}", p.name(), target.display()))?;
        done.push((p.name(), p.title(), outcome, seconds));
    }
    let index_path = out.join("index.md");
    let old = std::fs::read_to_string(&index_path).unwrap_or_default();
    let names: Vec<&str> = all.iter().map(|p| p.name()).collect();
    outputs::write_atomic(&index_path, index::index(out, &names, &old).as_bytes())
        .map_err(|e| format!("writing {}: {e}", index_path.display()))?;
    Ok(done)
}

/// `cargo xtask reproduce --help`.
pub const HELP: &str = "\
cargo xtask reproduce [--paper NAME] [--quick] [--out DIR] [--seed S] [--runs R]

Regenerates every paper's experiment (or one) into DIR/NAME/ (report.md, summary.json, figures/,
csv/, run.json) and DIR/index.md. Each paper's directory is built beside it and renamed into place
when done: an interrupted run leaves the previous complete one. The index lists every paper in DIR.

Options:
  --paper NAME   one paper: carrier, truck, bds-ins, rmhe, dp-vessel, or the benchmark
                 certified-sets (CORA's six-tank hulls, boundary noise over 10^6 steps)
  --quick        a few-second version (smaller sizes; same code paths)
  --out DIR      the output directory (default out/reproduce)
  --seed S       the base seed (an unsigned integer)
  --runs R       Monte Carlo runs, 1 to 10000 (default: each paper's)
  -h, --help     this text
";

/// Entry point of `cargo xtask reproduce`.
///
/// # Errors
/// Bad arguments or a failed reproduction.
pub fn run(args: &[OsString]) -> Result<(), String> {
    let args = match Args::parse(args, &["out", "seed", "runs", "paper"], &["quick"])? {
        Parsed::Run(args) => args,
        Parsed::Help => {
            print!("{HELP}");
            return Ok(());
        }
    };
    let out = args.path("out").unwrap_or_else(|| PathBuf::from("out/reproduce"));
    let seed: u64 = match args.value("seed")? {
        Some(s) => s.parse().map_err(|_| format!("--seed: not an unsigned integer: {s:?}"))?,
        None => DEFAULT_SEED,
    };
    let runs = match args.value("runs")? {
        Some(s) => Some(
            s.parse::<usize>()
                .ok()
                .filter(|r| (1..=MAX_RUNS).contains(r))
                .ok_or(format!("--runs: not an integer from 1 to {MAX_RUNS}: {s:?}"))?,
        ),
        None => None,
    };
    let opts = Options { quick: args.flag("quick"), seed, runs };
    let t0 = Instant::now();
    let done = reproduce_papers(args.value("paper")?, &opts, &out)?;
    for (name, _, o, secs) in &done {
        println!("{name}: {} claims judged, {secs:.1} s → {}", o.claims, out.join(name).join("report.md").display());
    }
    println!("Wrote {} in {:.1} s.", out.join("index.md").display(), t0.elapsed().as_secs_f64());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stand-in paper: writes its report (and `seed.txt`), or fails after writing half of it.
    struct Fake(&'static str, bool);

    impl Paper for Fake {
        fn name(&self) -> &'static str {
            self.0
        }
        fn title(&self) -> &'static str {
            self.0
        }
        fn run(&self, opts: &Options, out: &Path) -> Result<PaperOutcome, String> {
            std::fs::write(out.join("seed.txt"), opts.seed.to_string()).map_err(|e| e.to_string())?;
            if self.1 {
                return Err("interrupted halfway".into());
            }
            std::fs::write(out.join("report.md"), "# report").map_err(|e| e.to_string())?;
            Ok(PaperOutcome { claims: 2, verdicts: vec!["reproduced".into(), "not reproduced".into()] })
        }
    }

    fn papers(failing: Option<&str>) -> Vec<Box<dyn Paper>> {
        ["a", "b", "c"].into_iter().map(|n| Box::new(Fake(n, Some(n) == failing)) as Box<dyn Paper>).collect()
    }

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("xtask-reproduce-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut n: Vec<String> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        n.sort();
        n
    }

    fn opts(seed: u64) -> Options {
        Options { quick: true, seed, runs: None }
    }

    #[test]
    fn one_paper_into_a_directory_of_all_keeps_the_others_rows() {
        let out = dir("index");
        reproduce_with(&papers(None), None, &opts(1), &out).unwrap();
        reproduce_with(&papers(None), Some("b"), &opts(2), &out).unwrap();
        let index = std::fs::read_to_string(out.join("index.md")).unwrap();
        let rows: Vec<&str> = index.lines().filter(|l| l.contains("/report.md](")).collect();
        assert_eq!(rows.len(), 3, "{index}");
        assert!(rows[0].contains("[a/report.md]") && rows[0].contains("| 1, quick |"), "{index}");
        assert!(rows[1].contains("[b/report.md]") && rows[1].contains("| 2, quick |"), "{index}");
        assert!(rows[2].contains("[c/report.md]") && rows[2].contains("| 1, quick |"), "{index}");
        assert_eq!(names(&out.join("b")), ["report.md", "run.json", "seed.txt"]);
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn an_interrupted_paper_leaves_its_previous_directory_whole() {
        let out = dir("interrupted");
        reproduce_with(&papers(None), None, &opts(1), &out).unwrap();
        // A run that fails halfway through paper b: b keeps the first run's files, seed and all.
        let e = reproduce_with(&papers(Some("b")), Some("b"), &opts(2), &out).unwrap_err();
        assert!(e.contains("interrupted halfway"), "{e}");
        assert_eq!(std::fs::read_to_string(out.join("b").join("seed.txt")).unwrap(), "1");
        assert_eq!(names(&out), ["a", "b", "c", "index.md"], "no half-built directory left");
        // A run killed before it could clean up left its build directory: the next run removes it.
        let killed = out.join(".b.4294967295.AbCdEf.tmp");
        std::fs::create_dir(&killed).unwrap();
        std::fs::write(killed.join("seed.txt"), "3").unwrap();
        reproduce_with(&papers(None), Some("b"), &opts(4), &out).unwrap();
        assert_eq!(names(&out), ["a", "b", "c", "index.md"]);
        assert_eq!(std::fs::read_to_string(out.join("b").join("seed.txt")).unwrap(), "4");
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn arguments_are_checked_and_help_is_answered() {
        let a = |v: &[&str]| v.iter().map(OsString::from).collect::<Vec<_>>();
        assert_eq!(run(&a(&["--help"])), Ok(()));
        assert_eq!(run(&a(&["--quick", "-h"])), Ok(()));
        assert!(HELP.contains("--paper NAME") && HELP.contains("--runs R"));
        for runs in ["0", "10001", "-3", "many"] {
            let e = run(&a(&["--runs", runs])).unwrap_err();
            assert!(e.starts_with("--runs: not an integer from 1 to 10000"), "{runs}: {e}");
        }
        assert!(run(&a(&["--seed", "-1"])).unwrap_err().starts_with("--seed: not an unsigned integer"));
        #[cfg(unix)]
        {
            use std::os::unix::ffi::OsStringExt;
            let e = run(&[OsString::from("--seed"), OsString::from_vec(b"1\xff".to_vec())]).unwrap_err();
            assert!(e.contains("is not valid UTF-8"), "{e}");
            let e = run(&[OsString::from_vec(b"--qu\xffick".to_vec())]).unwrap_err();
            assert!(e.starts_with("unexpected argument"), "{e}");
        }
    }
}
