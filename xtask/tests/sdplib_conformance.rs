//! SDPLIB conformance: every problem of the suite, with every backend compiled in.
//!
//! The directory is `$SDPLIB_DIR` or `../shared/sdplib` beside the workspace; the test skips with
//! a message when it is absent. Reference outcomes come from the suite's README (see
//! `xtask::sdplib::suite`): the objective must match to relative 1e-6 (or to the digits given), and the
//! infeasible problems must end infeasible on the correct side with a certificate that checks.

use lmi::{DEFAULT_BACKEND, SdpProblem};
use lmi::{backend_by_name, backend_names, read_sdpa_file};
use xtask::sdplib::suite::{Verdict, sdplib_dir, suite, suite_settings, verdict};

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
            let mut backend = backend_by_name(name, suite_settings()).unwrap();
            let sol = backend.setup_and_solve(&problem).expect("solve returns an outcome");
            let verdict = verdict(p, name, &problem, &sol);
            eprintln!(
                "{name:10} {:9} {:24} obj {:>16.9e} it {:3} {:>12?} {verdict:?}",
                p.name,
                sol.status.label(),
                sol.primal_objective,
                sol.iterations,
                sol.solve_time
            );
            if let Verdict::Fail(e) = verdict {
                failures.push(format!("{name}/{}: {e}", p.name));
            }
        }
    }
    assert!(failures.is_empty(), "failures:\n{}", failures.join("\n"));
}

/// Smallest eigenvalue over the blocks of `X = Σ xᵢFᵢ − F₀`.
fn min_slack_eigenvalue(problem: &SdpProblem, x: &[f64]) -> f64 {
    problem.slack(x).unwrap().into_iter().map(|b| b.symmetric_eigenvalues().min()).fold(f64::INFINITY, f64::min)
}

/// The known deviations rest on strictly feasible points found by the default backend; check
/// that they still hold (`cᵀx` of a strictly feasible `x` bounds the optimum from above).
#[test]
fn known_deviations_are_backed_by_strictly_feasible_points() {
    let Some(dir) = sdplib_dir() else {
        eprintln!("SKIPPED: SDPLIB directory not found (set SDPLIB_DIR to run the conformance suite)");
        return;
    };
    let solve = |name: &str| {
        let problem = read_sdpa_file(&dir.join(format!("{name}.dat-s"))).unwrap();
        let mut backend = backend_by_name(DEFAULT_BACKEND, suite_settings()).unwrap();
        let sol = backend.setup_and_solve(&problem).unwrap();
        let min_eig = min_slack_eigenvalue(&problem, &sol.x);
        (sol.primal_objective, min_eig)
    };
    // hinf5: the optimum is below the reference's rounding interval [362.5, 363.5).
    let (obj, min_eig) = solve("hinf5");
    assert!(min_eig > 1e-9, "hinf5: x is not strictly feasible ({min_eig:e})");
    assert!(obj < 362.5, "hinf5: c'x = {obj} no longer contradicts the reference 3.63e2");
    // hinf1: a strictly feasible point inside the reference interval, below Clarabel's answers.
    let (obj, min_eig) = solve("hinf1");
    assert!(min_eig > 1e-9, "hinf1: x is not strictly feasible ({min_eig:e})");
    assert!((obj - 2.0326).abs() <= 5e-5, "hinf1: c'x = {obj}");
    // hinf2: likewise inside the reference interval 10.967 ± 5e-4.
    let (obj, min_eig) = solve("hinf2");
    assert!(min_eig > 0.0, "hinf2: x is not strictly feasible ({min_eig:e})");
    assert!((obj - 10.967).abs() <= 5e-4, "hinf2: c'x = {obj}");
    // hinf4: a strictly feasible point inside the reference interval 274.764 ± 5e-4, below
    // Clarabel's answer.
    let (obj, min_eig) = solve("hinf4");
    assert!(min_eig > 0.0, "hinf4: x is not strictly feasible ({min_eig:e})");
    assert!((obj - 274.764).abs() <= 5e-4, "hinf4: c'x = {obj}");
}
