//! The `faer-ipm` backend on small SDPs with known answers, infeasible problems, limits and
//! misuse, and on the set-membership filter's LMI.

mod ipm_common;

use ipm_common::{filter_lmi, problem};
use lmi::{
    Block, FaerIpm, LmiError, SdpBackend, SdpProblem, SdpSolution, SearchDirection, SolveStatus, SolverSettings,
};

fn solve(p: &SdpProblem) -> SdpSolution {
    let mut ipm = FaerIpm::new(SolverSettings::default()).unwrap();
    ipm.setup_and_solve(p).unwrap()
}

/// Solves with the HKM direction.
fn solve_hkm(p: &SdpProblem) -> SdpSolution {
    let mut ipm = FaerIpm::new(SolverSettings::default()).unwrap();
    ipm.set_direction(SearchDirection::Hkm);
    assert_eq!(ipm.direction(), SearchDirection::Hkm);
    ipm.setup_and_solve(p).unwrap()
}

fn assert_close(a: f64, b: f64, rel: f64, what: &str) {
    assert!((a - b).abs() <= rel * (1.0 + b.abs()), "{what}: {a} vs {b}");
}

/// Checks the returned point: X ⪰ 0 (up to a tolerance), tr(FᵢY) = cᵢ, gap.
fn check_optimal(p: &SdpProblem, s: &SdpSolution) {
    assert_eq!(s.status, SolveStatus::Solved, "{s:?}");
    let traces = p.traces(&s.dual).unwrap();
    for (i, c) in p.c().iter().enumerate() {
        assert_close(traces[i + 1], *c, 1e-7, "dual equality");
    }
    assert_close(traces[0], s.dual_objective, 1e-9, "dual objective");
    let cx: f64 = p.c().iter().zip(&s.x).map(|(c, x)| c * x).sum();
    assert_close(cx, s.primal_objective, 1e-9, "primal objective");
    for (blk, y) in p.slack(&s.x).unwrap().iter().zip(&s.dual) {
        let ex = blk.clone().symmetric_eigen().eigenvalues.min();
        let ey = y.clone().symmetric_eigen().eigenvalues.min();
        assert!(ex > -1e-7 && ey > -1e-7, "not PSD: {ex} {ey}");
    }
    assert!(s.relative_gap() < 1e-8);
}

#[test]
fn scalar_schur_complement() {
    // min t  s.t. [[t, a], [a, 1]] ⪰ 0  →  t = a².
    for a in [0.0, 0.5, -2.0, 3.0] {
        let p = problem(vec![Block::Psd(2)], vec![1.0], &[(1, 0, 0, 0, 1.0), (0, 0, 0, 1, -a), (0, 0, 1, 1, -1.0)]);
        let s = solve(&p);
        check_optimal(&p, &s);
        assert_close(s.x[0], a * a, 1e-8, "t");
    }
}

#[test]
fn largest_eigenvalue() {
    // min t  s.t. tI − A ⪰ 0  →  t = λmax(A).
    let n = 5;
    let a = nalgebra::DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 3) % 5) as f64 - 2.0 + ((j * 7 + i * 3) % 5) as f64);
    let mut e = vec![];
    for j in 0..n {
        e.push((1, 0, j, j, 1.0));
        for i in 0..=j {
            e.push((0, 0, i, j, a[(i, j)]));
        }
    }
    let p = problem(vec![Block::Psd(n)], vec![1.0], &e);
    let s = solve(&p);
    check_optimal(&p, &s);
    let lmax = a.symmetric_eigen().eigenvalues.max();
    assert_close(s.x[0], lmax, 1e-8, "λmax");
}

#[test]
fn linear_program() {
    // min x₁ + 2x₂  s.t.  x₁ + x₂ ≥ 1, x₁ ≥ 0, x₂ ≥ 0  →  1 at (1, 0).
    let p = problem(
        vec![Block::Nonneg(3)],
        vec![1.0, 2.0],
        &[(0, 0, 0, 0, 1.0), (1, 0, 0, 0, 1.0), (2, 0, 0, 0, 1.0), (1, 0, 1, 1, 1.0), (2, 0, 2, 2, 1.0)],
    );
    let s = solve(&p);
    check_optimal(&p, &s);
    assert_close(s.primal_objective, 1.0, 1e-8, "objective");
    assert_close(s.x[0], 1.0, 1e-7, "x1");
    assert!(s.x[1].abs() < 1e-7);
}

#[test]
fn mixed_blocks() {
    // min t + s  s.t. [[t, 1], [1, s]] ⪰ 0, t ≥ 2 (diagonal block)  →  t = 2, s = 1/2.
    let p = problem(
        vec![Block::Psd(2), Block::Nonneg(1)],
        vec![1.0, 1.0],
        &[(1, 0, 0, 0, 1.0), (2, 0, 1, 1, 1.0), (0, 0, 0, 1, -1.0), (1, 1, 0, 0, 1.0), (0, 1, 0, 0, 2.0)],
    );
    let s = solve(&p);
    check_optimal(&p, &s);
    assert_close(s.x[0], 2.0, 1e-7, "t");
    assert_close(s.x[1], 0.5, 1e-7, "s");
    assert_close(s.primal_objective, 2.5, 1e-8, "objective");
}

#[test]
fn infeasible_primal_is_certified() {
    // [[x, 0], [0, −x − 1]] ⪰ 0 has no solution.
    let p = problem(vec![Block::Psd(2)], vec![1.0], &[(1, 0, 0, 0, 1.0), (1, 0, 1, 1, -1.0), (0, 0, 1, 1, 1.0)]);
    let s = solve(&p);
    assert_eq!(s.status, SolveStatus::PrimalInfeasible, "{s:?}");
    let t = p.traces(&s.dual).unwrap();
    assert!((t[0] - 1.0).abs() < 1e-9 && t[1].abs() < 1e-7);
    assert!(s.dual[0].clone().symmetric_eigen().eigenvalues.min() > -1e-9);
    // Same with nonnegative scalars: x ≥ 1 and −x ≥ 0.
    let p = problem(vec![Block::Nonneg(2)], vec![0.0], &[(1, 0, 0, 0, 1.0), (1, 0, 1, 1, -1.0), (0, 0, 0, 0, 1.0)]);
    assert_eq!(solve(&p).status, SolveStatus::PrimalInfeasible);
}

#[test]
fn infeasible_dual_is_certified() {
    // min −x − y  s.t. [[x, 0], [0, y]] ⪰ 0 … unbounded: (D) has no solution.
    let p = problem(vec![Block::Psd(2)], vec![-1.0, -1.0], &[(1, 0, 0, 0, 1.0), (2, 0, 1, 1, 1.0)]);
    let s = solve(&p);
    assert_eq!(s.status, SolveStatus::DualInfeasible, "{s:?}");
    let cx: f64 = p.c().iter().zip(&s.x).map(|(c, x)| c * x).sum();
    assert!((cx + 1.0).abs() < 1e-9);
    let x = p.slack(&s.x).unwrap();
    // A(x) = X + F₀ with F₀ = 0 here: A(x) ⪰ 0.
    assert!(x[0].clone().symmetric_eigen().eigenvalues.min() > -1e-7);
    let p = problem(vec![Block::Nonneg(1)], vec![-1.0], &[(1, 0, 0, 0, 1.0)]);
    assert_eq!(solve(&p).status, SolveStatus::DualInfeasible);
}

#[test]
fn iteration_limit_is_not_solved() {
    let p = filter_lmi();
    let settings = SolverSettings::builder().max_iterations(2).build().unwrap();
    let mut ipm = FaerIpm::new(settings).unwrap();
    let s = ipm.setup_and_solve(&p).unwrap();
    assert_eq!(s.status, SolveStatus::IterationLimit);
    assert_eq!(s.iterations, 2);
}

#[test]
fn time_limit_is_reported() {
    let p = filter_lmi();
    let settings = SolverSettings::builder().time_limit(std::time::Duration::from_nanos(1)).build().unwrap();
    let mut ipm = FaerIpm::new(settings).unwrap();
    let s = ipm.setup_and_solve(&p).unwrap();
    assert_eq!(s.status, SolveStatus::TimeLimit);
}

#[test]
fn misuse_is_an_error() {
    let p = problem(vec![Block::Psd(2)], vec![1.0], &[(1, 0, 0, 0, 1.0), (0, 0, 1, 1, -1.0)]);
    let mut ipm = FaerIpm::new(SolverSettings::default()).unwrap();
    let mut sol = SdpSolution::new(&p);
    assert!(matches!(ipm.solve(&p, &mut sol), Err(LmiError::StructureMismatch(_))));
    ipm.setup(&p).unwrap();
    let other = problem(vec![Block::Psd(2)], vec![1.0], &[(1, 0, 0, 0, 1.0), (0, 0, 0, 1, -1.0)]);
    assert!(matches!(ipm.solve(&other, &mut sol), Err(LmiError::StructureMismatch(_))));
    ipm.solve(&p, &mut sol).unwrap();
    let bad = SolverSettings { tol_feas: -1.0, ..SolverSettings::default() };
    assert!(matches!(FaerIpm::new(bad), Err(LmiError::InvalidSetting { .. })));
    assert_eq!(ipm.name(), "faer-ipm");
}

#[test]
fn filter_lmi_matches_reference() {
    let p = filter_lmi();
    let settings = SolverSettings::builder().verbose(std::env::var_os("IPM_VERBOSE").is_some()).build().unwrap();
    let mut ipm = FaerIpm::new(settings).unwrap();
    ipm.setup(&p).unwrap();
    let mut s = SdpSolution::new(&p);
    ipm.solve(&p, &mut s).unwrap();
    check_optimal(&p, &s);
    assert_close(s.primal_objective, 0.98464424, 1e-6, "tr P");
    let nv = p.num_vars();
    let tau = &s.x[nv - 3..];
    for (t, r) in tau.iter().zip([0.55710, 0.10383, 0.33907]) {
        assert!((t - r).abs() < 1e-3, "τ = {tau:?}");
    }
    for g in &s.x[nv - 7..nv - 3] {
        assert!(g.abs() < 1e-6, "g = {g}");
    }
    // Solve many times: same answer; report the timing (release builds).
    let reps = if cfg!(debug_assertions) { 20 } else { 2000 };
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        ipm.solve(&p, &mut s).unwrap();
        times.push(s.solve_time);
    }
    times.sort();
    assert_eq!(s.status, SolveStatus::Solved);
    assert_close(s.primal_objective, 0.98464424, 1e-6, "tr P (repeated)");
    println!(
        "filter LMI (n=4, m=3): {} iterations, median solve {:?}, min {:?}",
        s.iterations,
        times[reps / 2],
        times[0]
    );
}

/// The HKM direction on the same problems: the same statuses, the known optima (closed forms and
/// the reference of the filter LMI) and, on the filter LMI, the NT answer.
#[test]
fn hkm_direction_solves_the_same_problems() {
    for a in [0.0, 0.5, -2.0, 3.0] {
        let p = problem(vec![Block::Psd(2)], vec![1.0], &[(1, 0, 0, 0, 1.0), (0, 0, 0, 1, -a), (0, 0, 1, 1, -1.0)]);
        let s = solve_hkm(&p);
        check_optimal(&p, &s);
        assert_close(s.x[0], a * a, 1e-8, "t");
    }
    let p = problem(
        vec![Block::Psd(2), Block::Nonneg(1)],
        vec![1.0, 1.0],
        &[(1, 0, 0, 0, 1.0), (2, 0, 1, 1, 1.0), (0, 0, 0, 1, -1.0), (1, 1, 0, 0, 1.0), (0, 1, 0, 0, 2.0)],
    );
    let s = solve_hkm(&p);
    check_optimal(&p, &s);
    assert_close(s.primal_objective, 2.5, 1e-8, "objective");
    let p = problem(vec![Block::Psd(2)], vec![1.0], &[(1, 0, 0, 0, 1.0), (1, 0, 1, 1, -1.0), (0, 0, 1, 1, 1.0)]);
    assert_eq!(solve_hkm(&p).status, SolveStatus::PrimalInfeasible);
    let p = problem(vec![Block::Psd(2)], vec![-1.0, -1.0], &[(1, 0, 0, 0, 1.0), (2, 0, 1, 1, 1.0)]);
    assert_eq!(solve_hkm(&p).status, SolveStatus::DualInfeasible);
    let p = filter_lmi();
    let s = solve_hkm(&p);
    check_optimal(&p, &s);
    assert_close(s.primal_objective, 0.98464424, 1e-6, "tr P");
    let nt = solve(&p);
    assert_close(s.primal_objective, nt.primal_objective, 1e-7, "HKM vs NT");
    for (h, n) in s.x.iter().zip(&nt.x).skip(p.num_vars() - 3) {
        assert!((h - n).abs() < 1e-4, "τ: {h} vs {n}");
    }
}
