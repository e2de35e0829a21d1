//! Solves SDPA files with `faer-ipm` and prints per-file outcomes and timing statistics: a tool
//! for profiling (`valgrind --tool=callgrind`) and for comparing the search directions on the
//! same problems, side by side in one run.
//!
//! `cargo run --release -p lmi --example ipm_files -- [--reps N] [--hkm | --hkm-only] [--quiet]
//! [--verbose] FILE_OR_DIR…`
//!
//! Every file is solved `N` times and the fastest repetition is kept (the minimum is the figure
//! least disturbed by other processes on a shared machine). `--hkm` solves every file with both
//! the NT direction (the default) and the HKM direction ([`FaerIpm::set_direction`]),
//! alternately; `--hkm-only` runs HKM alone.

use std::path::PathBuf;
use std::time::Instant;

use lmi::{FaerIpm, SdpBackend, SdpSolution, SearchDirection, SolverSettings, read_sdpa_file};

/// Per-variant results over all files.
#[derive(Default)]
struct Tally {
    times: Vec<f64>,
    iters: Vec<u32>,
}

impl Tally {
    fn summary(&self, label: &str) -> String {
        let mut t = self.times.clone();
        t.sort_by(f64::total_cmp);
        let q = |p: f64| if t.is_empty() { f64::NAN } else { t[((t.len() - 1) as f64 * p).round() as usize] };
        let mean_it = self.iters.iter().map(|&i| f64::from(i)).sum::<f64>() / self.iters.len().max(1) as f64;
        let max_it = self.iters.iter().copied().max().unwrap_or(0);
        format!(
            "{label}: files {}  median {:.1} us  p99 {:.1} us  max {:.1} us  iterations mean {mean_it:.2} max {max_it}",
            t.len(),
            q(0.5),
            q(0.99),
            q(1.0),
        )
    }
}

fn main() {
    let mut reps = 1usize;
    let mut directions = vec![SearchDirection::NesterovTodd];
    let mut quiet = false;
    let mut verbose = false;
    let mut files: Vec<PathBuf> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--reps" => reps = args.next().and_then(|v| v.parse().ok()).expect("--reps N"),
            "--hkm" => directions = vec![SearchDirection::NesterovTodd, SearchDirection::Hkm],
            "--hkm-only" => directions = vec![SearchDirection::Hkm],
            "--quiet" => quiet = true,
            "--verbose" => verbose = true,
            _ => {
                let p = PathBuf::from(&a);
                if p.is_dir() {
                    let mut v: Vec<PathBuf> = std::fs::read_dir(&p)
                        .expect("directory")
                        .filter_map(|e| e.ok().map(|e| e.path()))
                        .filter(|p| p.extension().is_some_and(|x| x == "dat-s"))
                        .collect();
                    v.sort();
                    files.extend(v);
                } else {
                    files.push(p);
                }
            }
        }
    }
    let settings = SolverSettings::builder().verbose(verbose).build().expect("settings");
    let mut tallies: Vec<Tally> = directions.iter().map(|_| Tally::default()).collect();
    for f in &files {
        let problem = read_sdpa_file(f).expect("SDPA file");
        let mut solvers: Vec<(FaerIpm, SdpSolution, f64)> = directions
            .iter()
            .map(|&direction| {
                let mut ipm = FaerIpm::new(settings.clone()).expect("settings");
                ipm.set_direction(direction);
                ipm.setup(&problem).expect("setup");
                (ipm, SdpSolution::new(&problem), f64::INFINITY)
            })
            .collect();
        for _ in 0..reps {
            for (ipm, sol, best) in &mut solvers {
                let t = Instant::now();
                ipm.solve(&problem, sol).expect("solve");
                *best = best.min(t.elapsed().as_secs_f64() * 1e6);
            }
        }
        for ((ipm, sol, best), tally) in solvers.iter().zip(&mut tallies) {
            tally.times.push(*best);
            tally.iters.push(sol.iterations);
            if !quiet {
                println!(
                    "{} {} {} it {} pobj {:.12e} dobj {:.12e} pres {:.1e} dres {:.1e} {:.1} us",
                    f.file_name().map_or(String::new(), |s| s.to_string_lossy().into_owned()),
                    label(ipm.direction()),
                    sol.status,
                    sol.iterations,
                    sol.primal_objective,
                    sol.dual_objective,
                    sol.primal_residual,
                    sol.dual_residual,
                    best
                );
            }
        }
    }
    for (&direction, tally) in directions.iter().zip(&tallies) {
        println!("{}", tally.summary(label(direction)));
    }
}

fn label(direction: SearchDirection) -> &'static str {
    if direction == SearchDirection::Hkm { "hkm" } else { "nt" }
}
