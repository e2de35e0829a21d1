//! `FaerIpm::solve` performs no heap allocation once set up (after one warm-up solve).

use counting_allocator::{Counting, count};
mod ipm_common;
use lmi::{Block, Entry, FaerIpm, SdpBackend, SdpProblem, SdpSolution, SearchDirection, SolveStart, SolverSettings};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// A problem with a dense block large enough for faer's blocked kernels, a small one and a
/// diagonal block, with both sparse and dense `Fᵢ` (both Schur strategies). The identity is
/// strictly feasible for the dual and a large `x₁` for the primal.
fn problem() -> SdpProblem {
    let n = 40;
    let mut entries = vec![];
    let e = |mat, block, row, col, value| Entry { mat, block, row, col, value };
    // x₁ (t): a dense positive definite F₁ in block 0, 1 in the corner of block 1, t ≥ 1 in block 2.
    for j in 0..n {
        for i in 0..=j {
            entries.push(e(1, 0, i, j, if i == j { 2.0 } else { 0.1 / (1.0 + (j - i) as f64) }));
            entries.push(e(0, 0, i, j, ((i + 2 * j) as f64).sin()));
        }
    }
    let mut c = vec![2.0 * n as f64 + 2.0];
    // x₂…x_{n+1}: E_kk + 0.3 (E_k,k+1 + E_k+1,k) in block 0.
    for k in 0..n {
        c.push(1.0);
        entries.push(e(k + 2, 0, k, k, 1.0));
        if k + 1 < n {
            entries.push(e(k + 2, 0, k, k + 1, 0.3));
        }
    }
    // Block 1: [[t, 1], [1, x₂]]; block 2: t ≥ 1, x₃ ≥ 0.
    entries.push(e(1, 1, 0, 0, 1.0));
    entries.push(e(2, 1, 1, 1, 1.0));
    entries.push(e(0, 1, 0, 1, -1.0));
    c[1] += 1.0;
    entries.push(e(1, 2, 0, 0, 1.0));
    entries.push(e(0, 2, 0, 0, 1.0));
    entries.push(e(3, 2, 1, 1, 1.0));
    c[2] += 1.0;
    SdpProblem::new(vec![Block::Psd(n), Block::Psd(2), Block::Nonneg(2)], c, entries).unwrap()
}

/// `p` with every value (objective and matrices) multiplied by `s`.
fn scaled(mut p: SdpProblem, s: f64) -> SdpProblem {
    let c: Vec<f64> = p.c().iter().map(|v| v * s).collect();
    let values: Vec<f64> = p.entries().iter().map(|e| e.value * s).collect();
    p.set_values(&c, &values).unwrap();
    p
}

#[test]
fn solves_after_setup_do_not_allocate() {
    // The second problem (the filter LMI) ends in the QR-based precision mode; the third is
    // badly scaled, so that the solve scales it and maps the answer back.
    // Both search directions (HKM may fall back to NT within a solve).
    let cases = [problem(), ipm_common::filter_lmi(), scaled(ipm_common::filter_lmi(), 1e-12)];
    for (p, direction) in cases.iter().flat_map(|p| [(p, SearchDirection::NesterovTodd), (p, SearchDirection::Hkm)]) {
        let mut ipm =
            FaerIpm::new(SolverSettings::builder().verbose(std::env::var_os("IPM_VERBOSE").is_some()).build().unwrap())
                .unwrap();
        ipm.set_direction(direction);
        ipm.setup(p).unwrap();
        let mut sol = SdpSolution::new(p);
        ipm.solve(p, &mut sol).unwrap();
        assert!(sol.status.is_optimal(), "{}", sol.status);
        let first = sol.primal_objective;
        let ((), allocations) = count(|| {
            for _ in 0..10 {
                ipm.solve(p, &mut sol).unwrap();
            }
        });
        assert_eq!(allocations, 0, "solve allocated {allocations} times in 10 solves");
        assert!(sol.status.is_optimal(), "{}", sol.status);
        assert_eq!(sol.primal_objective, first);
    }
}

#[test]
fn warm_started_solves_do_not_allocate() {
    // Two nearby problems of one structure, solved alternately: every solve after the first
    // starts from the other's solution.
    let a = ipm_common::filter_lmi();
    let mut b = a.clone();
    let values: Vec<f64> =
        a.entries().iter().enumerate().map(|(k, e)| e.value * (1.0 + 1e-3 * (k as f64).sin())).collect();
    b.set_values(a.c(), &values).unwrap();
    for direction in [SearchDirection::NesterovTodd, SearchDirection::Hkm] {
        let mut ipm = FaerIpm::new(SolverSettings::builder().warm_start(true).build().unwrap()).unwrap();
        ipm.set_direction(direction);
        ipm.setup(&a).unwrap();
        let mut sol = SdpSolution::new(&a);
        ipm.solve(&a, &mut sol).unwrap();
        let ((), allocations) = count(|| {
            for k in 0..10 {
                ipm.solve(if k % 2 == 0 { &b } else { &a }, &mut sol).unwrap();
                assert_eq!(sol.start, SolveStart::Warm);
            }
        });
        assert_eq!(allocations, 0, "warm-started solves allocated {allocations} times in 10 solves");
        assert!(sol.status.is_optimal(), "{}", sol.status);
    }
}

/// The independent check of infeasibility certificates runs in the solve without allocating,
/// whether the certificate passes (an infeasible problem) or is rejected (a feasible problem with
/// the bound `x₁ ≥ 1e308`, which `faer-ipm` claims primal infeasible: numerical trouble).
#[test]
fn certificate_checks_do_not_allocate() {
    let e = |mat, block, row, col, value| Entry { mat, block, row, col, value };
    let infeasible = SdpProblem::new(
        vec![Block::Nonneg(2)],
        vec![1.0],
        vec![e(1, 0, 0, 0, 1.0), e(0, 0, 0, 0, 1.0), e(1, 0, 1, 1, -1.0)],
    )
    .unwrap();
    let bogus = SdpProblem::new(
        vec![Block::Psd(2), Block::Nonneg(2)],
        vec![0.5, 0.5],
        vec![
            e(1, 0, 0, 0, 1.0),
            e(2, 0, 1, 1, 1.0),
            e(0, 0, 0, 1, -1.0),
            e(1, 1, 0, 0, 1.0),
            e(0, 1, 0, 0, 1e308),
            e(2, 1, 1, 1, 1.0),
        ],
    )
    .unwrap();
    for p in [&infeasible, &bogus] {
        let mut ipm = FaerIpm::new(SolverSettings::default()).unwrap();
        ipm.setup(p).unwrap();
        let mut sol = SdpSolution::new(p);
        ipm.solve(p, &mut sol).unwrap();
        let (status, rejected) = (sol.status, sol.rejected_certificate);
        let ((), allocations) = count(|| {
            for _ in 0..10 {
                ipm.solve(p, &mut sol).unwrap();
            }
        });
        assert_eq!(allocations, 0, "solve allocated {allocations} times in 10 solves ({status})");
        assert_eq!((sol.status, sol.rejected_certificate), (status, rejected));
    }
    let mut ipm = FaerIpm::new(SolverSettings::default()).unwrap();
    assert_eq!(ipm.setup_and_solve(&infeasible).unwrap().status, lmi::SolveStatus::PrimalInfeasible);
    let sol = ipm.setup_and_solve(&bogus).unwrap();
    assert_eq!(sol.status, lmi::SolveStatus::NumericalTrouble);
    assert_eq!(sol.rejected_certificate.map(|r| r.claimed), Some(lmi::SolveStatus::PrimalInfeasible));
}
