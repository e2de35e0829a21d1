//! `cargo xtask sdplib [--dir D] [--backend NAME]`: solve the SDPLIB suite, print a table.

use std::ffi::OsString;
use std::time::Instant;

pub mod suite;

use lmi::{backend_by_name, backend_names, read_sdpa_file};
use suite::{Expected, Verdict, objective_tolerance, sdplib_dir, suite, suite_settings, verdict};

use crate::args::{Args, Parsed};

/// `cargo xtask sdplib --help`.
pub const HELP: &str = "\
cargo xtask sdplib [--dir D] [--backend NAME]

Solves the SDPLIB suite with every compiled SDP backend (or one) and prints a table: status,
objective against the reference, relative error, iterations, times; infeasibility certificates
are checked independently. Exits non-zero when a problem fails.

Options:
  --dir D          the directory of the SDPLIB problems (default: $SDPLIB_DIR, else ../shared/sdplib)
  --backend NAME   one backend (faer-ipm; clarabel when built with that feature)
  -h, --help       this text
";

/// Runs `cargo xtask sdplib` with the given arguments.
///
/// # Errors
/// Bad arguments, a missing suite, a failed problem.
pub fn run(args: &[OsString]) -> Result<(), String> {
    let args = match Args::parse(args, &["dir", "backend"], &[])? {
        Parsed::Run(args) => args,
        Parsed::Help => {
            print!("{HELP}");
            return Ok(());
        }
    };
    let dir = match args.path("dir") {
        Some(d) => d,
        None => sdplib_dir().ok_or("SDPLIB directory not found: pass --dir or set SDPLIB_DIR")?,
    };
    // A missing directory is named as such (`SuiteError::MissingDir`).
    let problems = suite(&dir).map_err(|e| e.to_string())?;
    let backends: Vec<String> = match args.value("backend")? {
        Some(b) => vec![b.to_owned()],
        None => backend_names().into_iter().map(str::to_owned).collect(),
    };
    if backends.is_empty() {
        return Err("no SDP backend compiled in".into());
    }
    println!(
        "| backend | problem | status | objective | reference | rel. error | iterations | solve time | setup+solve |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|");
    let mut failures = 0;
    let mut notes = Vec::new();
    for name in &backends {
        for p in &problems {
            let problem = read_sdpa_file(&p.path).map_err(|e| format!("{}: {e}", p.path.display()))?;
            let mut backend = backend_by_name(name, suite_settings()).map_err(|e| e.to_string())?;
            let t0 = Instant::now();
            let sol = backend.setup_and_solve(&problem).map_err(|e| e.to_string())?;
            let total = t0.elapsed();
            let verdict = verdict(p, name, &problem, &sol);
            let ok = !matches!(verdict, Verdict::Fail(_));
            if let Verdict::KnownDeviation(reason) = verdict {
                notes.push(format!("{name}/{}: known deviation — {reason}", p.name));
            }
            let (reference, err) = match p.expected {
                Expected::Optimal { value, .. } => {
                    let err = (sol.primal_objective - value).abs();
                    // Relative to the reference, or to the tolerance's floor for a reference of 0.
                    let scale = value.abs().max(objective_tolerance(&p.expected, &problem, &sol));
                    (format!("{value:.6e}"), format!("{:.1e}", err / scale))
                }
                Expected::Infeasible(side) => (
                    side.label().to_owned(),
                    if ok { "certificate ok".to_owned() } else { "certificate FAILED".to_owned() },
                ),
            };
            if !ok {
                failures += 1;
            }
            println!(
                "| {name} | {} | {}{} | {:.9e} | {reference} | {err} | {} | {:.3} ms | {:.3} ms |",
                p.name,
                sol.status.label(),
                if !ok {
                    " (MISMATCH)"
                } else if matches!(verdict, Verdict::KnownDeviation(_)) {
                    " (known deviation)"
                } else {
                    ""
                },
                sol.primal_objective,
                sol.iterations,
                sol.solve_time.as_secs_f64() * 1e3,
                total.as_secs_f64() * 1e3
            );
        }
    }
    for n in &notes {
        println!("\n* {n}");
    }
    if failures > 0 {
        return Err(format!("{failures} problem(s) did not match their reference"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: `cargo xtask sdplib --dir D` with a directory that does not exist
    /// said "SDPA format error at line 0"; now the error names the directory.
    #[test]
    fn a_missing_dir_is_reported_as_such() {
        let dir = std::env::temp_dir().join("xtask-sdplib-no-such-dir");
        let err = run(&["--dir".into(), dir.clone().into_os_string()]).unwrap_err();
        assert!(err.contains(&format!("SDPLIB directory {} does not exist", dir.display())), "{err}");
        assert!(!err.contains("SDPA format error"), "{err}");
    }

    #[test]
    fn help_is_an_answer_not_an_unknown_option() {
        assert_eq!(run(&["--help".into()]), Ok(()));
        assert_eq!(run(&["--dir".into(), "x".into(), "-h".into()]), Ok(()));
        assert!(HELP.contains("--backend NAME"));
    }
}
