//! SDPLIB conformance: every problem of the suite, with every backend compiled in.
//!
//! The directory is `$SDPLIB_DIR` or `../shared/sdplib` beside the workspace; the test skips with
//! a message when it is absent. Reference outcomes come from the suite's README (see
//! `lmi::sdplib`): the objective must match to relative 1e-6 (or to the digits given), and the
//! infeasible problems must end infeasible on the correct side with a certificate that checks.

use lmi::sdplib::{check_outcome, sdplib_dir, suite};
use lmi::{SolverSettings, backend_by_name, backend_names, read_sdpa_file};

#[test]
fn every_backend_solves_the_sdplib_suite() {
    let Some(dir) = sdplib_dir() else {
        eprintln!("SKIPPED: SDPLIB directory not found (set SDPLIB_DIR to run the conformance suite)");
        return;
    };
    let problems = suite(&dir).expect("reference table");
    let names = backend_names();
    assert!(!names.is_empty(), "no SDP backend compiled in");
    let mut failures = Vec::new();
    for name in names {
        for p in &problems {
            let problem = read_sdpa_file(&p.path).expect("SDPLIB file parses");
            let mut backend = backend_by_name(name, SolverSettings::default()).unwrap();
            let sol = backend.setup_and_solve(&problem).expect("solve returns an outcome");
            let verdict = check_outcome(&p.expected, &problem, &sol);
            eprintln!(
                "{name:10} {:9} {:24} obj {:>16.9e} it {:3} {:>12?} {verdict:?}",
                p.name,
                sol.status.label(),
                sol.primal_objective,
                sol.iterations,
                sol.solve_time
            );
            if let Err(e) = verdict {
                failures.push(format!("{name}/{}: {e}", p.name));
            }
        }
    }
    assert!(failures.is_empty(), "failures:\n{}", failures.join("\n"));
}
