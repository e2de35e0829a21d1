//! Reliability regression tests for the SDP backends: badly scaled problems get the same answer
//! as well scaled ones, huge problems are refused before anything is allocated, and (with the
//! `clarabel` feature) a panic inside Clarabel is contained at the backend boundary.

mod ipm_common;

use ipm_common::known_optimum;
use lmi::{Block, Entry, FaerIpm, LmiError, SdpBackend, SdpProblem, SdpSolution, SolveStatus, SolverSettings};

const SCALES: [f64; 7] = [1.0, 1e-20, 1e-12, 1e-6, 1e6, 1e12, 1e20];

/// Solves the scaled versions of [`known_optimum`] with a fresh backend from `make` and checks
/// status and objectives; returns the list of failures.
fn scaled_failures(make: &dyn Fn() -> Box<dyn SdpBackend>) -> Vec<String> {
    let mut failures = vec![];
    for s in SCALES {
        for (what, s_obj, s_con) in [("all data", s, s), ("objective only", s, 1.0), ("constraints only", 1.0, s)] {
            let p = known_optimum(s_obj, s_con);
            let mut backend = make();
            let sol = match backend.setup_and_solve(&p) {
                Ok(sol) => sol,
                Err(e) => {
                    failures.push(format!("{} scale {s:e} ({what}): error {e}", backend.name()));
                    continue;
                }
            };
            let expected = s_obj;
            let ok = |v: f64| (v - expected).abs() <= 1e-6 * expected.abs();
            if sol.status != SolveStatus::Solved || !ok(sol.primal_objective) || !ok(sol.dual_objective) {
                failures.push(format!(
                    "{} scale {s:e} ({what}): status {}, objectives {:e} / {:e}, expected {expected:e}",
                    backend.name(),
                    sol.status,
                    sol.primal_objective,
                    sol.dual_objective
                ));
                continue;
            }
            // The point itself: x = (1, 1) whatever the scaling; tr(FᵢY) = cᵢ.
            for x in &sol.x {
                if (x - 1.0).abs() > 1e-3 {
                    failures.push(format!("{} scale {s:e} ({what}): x = {:?}", backend.name(), sol.x));
                    break;
                }
            }
            let traces = p.traces(&sol.dual).unwrap();
            for (t, c) in traces[1..].iter().zip(p.c()) {
                if (t - c).abs() > 1e-6 * c.abs() {
                    failures.push(format!("{} scale {s:e} ({what}): tr(FᵢY) = {t:e}, c = {c:e}", backend.name()));
                }
            }
        }
    }
    failures
}

#[test]
fn faer_ipm_answers_badly_scaled_problems_like_the_original() {
    let failures = scaled_failures(&|| Box::new(FaerIpm::new(SolverSettings::default()).unwrap()));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[cfg(feature = "clarabel")]
#[test]
fn clarabel_answers_badly_scaled_problems_like_the_original() {
    let failures = scaled_failures(&|| Box::new(lmi::ClarabelBackend::new(SolverSettings::default()).unwrap()));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Scaling is exact (powers of two): problems that differ by a power of two and are both badly
/// scaled (so both are scaled back to the same problem) get bit-identical answers, and
/// infeasibility certificates keep their normalisation.
#[test]
fn power_of_two_scalings_give_identical_answers_and_certificates() {
    let solve =
        |s: f64| FaerIpm::new(SolverSettings::default()).unwrap().setup_and_solve(&known_optimum(s, s)).unwrap();
    let base = solve(2f64.powi(-60));
    assert_eq!(base.status, SolveStatus::Solved);
    for k in [-100, -30, 40, 70] {
        let s = 2f64.powi(k);
        let sol = solve(s);
        assert_eq!(sol.status, base.status);
        assert_eq!(sol.x, base.x, "2^{k}");
        assert_eq!(sol.primal_objective, base.primal_objective * 2f64.powi(k + 60), "2^{k}");
        // Y is invariant under a uniform scaling of all data.
        assert_eq!(sol.dual, base.dual, "2^{k}");
    }
    // Primal infeasible: x ≥ 1 and −x ≥ 0 (block of two nonnegative scalars), scaled by 1e-15.
    let s = 1e-15;
    let e = |mat, row, value: f64| Entry { mat, block: 0, row, col: row, value: value * s };
    let p =
        SdpProblem::new(vec![Block::Nonneg(2)], vec![1.0], vec![e(1, 0, 1.0), e(0, 0, 1.0), e(1, 1, -1.0)]).unwrap();
    let sol = FaerIpm::new(SolverSettings::default()).unwrap().setup_and_solve(&p).unwrap();
    assert_eq!(sol.status, SolveStatus::PrimalInfeasible);
    let t = p.traces(&sol.dual).unwrap();
    assert!((t[0] - 1.0).abs() < 1e-9 && t[1].abs() < 1e-9, "certificate traces {t:?}");
    // Dual infeasible (unbounded below): min −x s.t. x ≥ 0, scaled by 1e12.
    let p = SdpProblem::new(
        vec![Block::Nonneg(1)],
        vec![-1e12],
        vec![Entry { mat: 1, block: 0, row: 0, col: 0, value: 1e12 }],
    )
    .unwrap();
    let sol = FaerIpm::new(SolverSettings::default()).unwrap().setup_and_solve(&p).unwrap();
    assert_eq!(sol.status, SolveStatus::DualInfeasible);
    assert!((sol.x[0] * p.c()[0] + 1.0).abs() < 1e-9, "c'x = {}", sol.x[0] * p.c()[0]);
}

/// Equilibration can be switched off; the answer of a well-scaled problem is the same.
#[test]
fn equilibration_can_be_disabled() {
    let settings = SolverSettings::builder().equilibrate(false).build().unwrap();
    let sol = FaerIpm::new(settings).unwrap().setup_and_solve(&known_optimum(1.0, 1.0)).unwrap();
    assert_eq!(sol.status, SolveStatus::Solved);
    assert!((sol.primal_objective - 1.0).abs() < 1e-7);
}

/// A problem with `m` variables, each appearing once in a diagonal block of size 1; small to
/// store (`O(m)`), but a dense Schur matrix for it has `m²` entries.
fn many_variables(m: usize) -> SdpProblem {
    let entries = (1..=m).map(|mat| Entry { mat, block: 0, row: 0, col: 0, value: 1.0 }).collect();
    SdpProblem::new(vec![Block::Nonneg(1)], vec![1.0; m], entries).unwrap()
}

/// An SDPA file of 0.8 MB with m = 200 000 once made faer-ipm request 320 GB and abort. Now
/// the memory is computed first and the setup refused with a typed error (a test process that
/// tried to allocate it would abort).
#[test]
fn faer_ipm_refuses_a_problem_that_needs_more_than_the_memory_limit() {
    let p = many_variables(200_000);
    let mut ipm = FaerIpm::new(SolverSettings::default()).unwrap();
    match ipm.setup(&p) {
        Err(LmiError::MemoryLimit { backend, required_bytes, limit_bytes }) => {
            assert_eq!(backend, "faer-ipm");
            assert!(required_bytes >= 320_000_000_000, "{required_bytes}");
            assert_eq!(limit_bytes, SolverSettings::default().memory_limit_bytes);
            assert_eq!(limit_bytes, 2 << 30);
        }
        other => panic!("expected a memory-limit error, got {other:?}"),
    }
    let msg = ipm.setup(&p).unwrap_err().to_string();
    assert!(msg.contains("faer-ipm") && msg.contains("GiB") && msg.contains("limit"), "{msg}");
    // Not set up: solving is a structure error, not a crash.
    let mut sol = SdpSolution::new(&p);
    assert!(matches!(ipm.solve(&p, &mut sol), Err(LmiError::StructureMismatch(_))));
}

/// The same scenario end to end: an SDPA file of a few MB with m = 200 000 is read
/// (the reader's memory is proportional to its input) and refused by the backend.
#[test]
fn an_sdpa_file_with_200_000_variables_is_refused_not_aborted() {
    let m = 200_000;
    let mut text = format!("{m}\n1\n-1\n");
    text.push_str(&"1 ".repeat(m));
    text.push('\n');
    for i in 1..=m {
        text.push_str(&format!("{i} 1 1 1 1\n"));
    }
    let p = lmi::read_sdpa(&text).unwrap();
    assert_eq!(p.num_vars(), m);
    let err = lmi::backend_by_name(lmi::DEFAULT_BACKEND, SolverSettings::default()).unwrap().setup_and_solve(&p);
    assert!(matches!(err, Err(LmiError::MemoryLimit { required_bytes, .. }) if required_bytes >= 320_000_000_000));
}

/// The limit is configurable and also covers moderate problems; a problem within it solves.
#[test]
fn the_memory_limit_is_a_setting() {
    let p = many_variables(300);
    let tight = SolverSettings::builder().memory_limit_bytes(100_000).build().unwrap();
    let err = FaerIpm::new(tight).unwrap().setup(&p).unwrap_err();
    assert!(
        matches!(err, LmiError::MemoryLimit { required_bytes, limit_bytes: 100_000, .. } if required_bytes > 100_000),
        "{err:?}"
    );
    let sol = FaerIpm::new(SolverSettings::default()).unwrap().setup_and_solve(&p).unwrap();
    assert!(sol.status.is_optimal(), "{}", sol.status);
    // Several blocks, each with per-variable bookkeeping: Σ over blocks of O(m), not only m².
    let blocks = vec![Block::Nonneg(1); 20_000];
    let entries = (0..20_000).map(|b| Entry { mat: 1 + b % 50_000, block: b, row: 0, col: 0, value: 1.0 }).collect();
    let p = SdpProblem::new(blocks, vec![1.0; 50_000], entries).unwrap();
    let err = FaerIpm::new(SolverSettings::default()).unwrap().setup(&p).unwrap_err();
    assert!(matches!(err, LmiError::MemoryLimit { .. }), "{err:?}");
    assert!(SolverSettings::builder().memory_limit_bytes(0).build().is_err());
}

#[cfg(feature = "clarabel")]
mod clarabel {
    use super::*;
    use lmi::ClarabelBackend;

    #[test]
    fn clarabel_refuses_a_problem_that_needs_more_than_the_memory_limit() {
        // A dense PSD block of order 2 000: Clarabel's KKT system holds a dense block of
        // (n(n+1)/2)² entries, 32 TB.
        let p = SdpProblem::new(
            vec![Block::Psd(2000)],
            vec![1.0],
            vec![Entry { mat: 1, block: 0, row: 0, col: 0, value: 1.0 }],
        )
        .unwrap();
        let err = ClarabelBackend::new(SolverSettings::default()).unwrap().setup(&p).unwrap_err();
        assert!(matches!(err, LmiError::MemoryLimit { .. }), "{err:?}");
    }

    /// NaN-free, finite data spanning 10^±300 (found by a randomised search) on which Clarabel
    /// 0.11's PSD cone panics with "Eigval error" (LAPACK fails on a non-finite iterate), even
    /// after this crate's scaling (which cannot shrink the spread inside one matrix).
    const CLARABEL_PANICS: &str = "1\n1\n4\n-1.245143367036688e246\n\
        0 1 1 1 9.645825197080238e140\n0 1 2 2 -9.835747498584869e64\n0 1 1 3 -1.0290972304655127e-150\n\
        0 1 1 4 -2.151886284297813e-298\n0 1 4 4 -3.5339901495996605e244\n1 1 1 1 1.0036352184100885e-234\n\
        1 1 1 2 -2.066539470011755e51\n1 1 2 2 2.1103189064143896e47\n1 1 1 4 -1.782183109665873e-33\n";

    /// The panic used to unwind through `solve` into the caller (the README's Clarabel path died
    /// this way in the load-2 scenario). Now it is contained: the solve ends with
    /// `NumericalTrouble`, the message is kept, and the backend keeps working (it rebuilds
    /// Clarabel's solver on the next solve).
    #[test]
    fn clarabel_panics_are_contained_at_the_backend_boundary() {
        let p = lmi::read_sdpa(CLARABEL_PANICS).unwrap();
        let mut backend = ClarabelBackend::new(SolverSettings::default()).unwrap();
        backend.setup(&p).unwrap();
        let mut sol = SdpSolution::new(&p);
        backend.solve(&p, &mut sol).unwrap();
        assert_eq!(sol.status, SolveStatus::NumericalTrouble);
        let msg = backend.last_panic().expect("Clarabel panicked on this input").to_owned();
        assert!(msg.contains("Eigval error"), "{msg}");
        assert!(sol.x.iter().all(|v| *v == 0.0) && sol.primal_objective.is_nan());
        // Again (a fresh Clarabel solver is built), then a well-posed problem on the same backend.
        backend.solve(&p, &mut sol).unwrap();
        assert_eq!(sol.status, SolveStatus::NumericalTrouble);
        let good = known_optimum(1.0, 1.0);
        let sol = backend.setup_and_solve(&good).unwrap();
        assert_eq!(sol.status, SolveStatus::Solved);
        assert!((sol.primal_objective - 1.0).abs() < 1e-6);
        // Through the registry's trait object as well.
        let mut boxed = lmi::backend_by_name("clarabel", SolverSettings::default()).unwrap();
        assert_eq!(boxed.setup_and_solve(&p).unwrap().status, SolveStatus::NumericalTrouble);
    }
}
