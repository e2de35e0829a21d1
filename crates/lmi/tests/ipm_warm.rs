//! `faer-ipm`'s warm start (`SolverSettings::warm_start`, `docs/sdp.md` §3.7): along a sequence of
//! nearby problems it reaches the cold solve's answer in fewer iterations; after an infeasible
//! problem, a rescaled problem or a new setup it starts cold; a warm solve that fails is repeated
//! cold and then gives exactly the cold method's result.

mod ipm_common;

use lmi::{Block, FaerIpm, SdpBackend, SdpProblem, SdpSolution, SolveStart, SolveStatus, SolverSettings};

fn ipm(warm: bool, max_iterations: u32) -> FaerIpm {
    let settings = SolverSettings::builder().warm_start(warm).max_iterations(max_iterations).build().unwrap();
    FaerIpm::new(settings).unwrap()
}

/// `p` with every value of `F₀` and the `Fᵢ` multiplied by `1 + amplitude·sin(step + 0.7·index)`
/// (a smooth path through nearby problems of the same structure).
fn perturbed(p: &SdpProblem, step: usize, amplitude: f64) -> SdpProblem {
    let mut q = p.clone();
    let values: Vec<f64> = p
        .entries()
        .iter()
        .enumerate()
        .map(|(k, e)| e.value * (1.0 + amplitude * (step as f64 + 0.7 * k as f64).sin()))
        .collect();
    q.set_values(p.c(), &values).unwrap();
    q
}

fn solve(backend: &mut FaerIpm, p: &SdpProblem) -> SdpSolution {
    let mut sol = SdpSolution::new(p);
    backend.solve(p, &mut sol).unwrap();
    sol
}

#[test]
fn nearby_problems_reach_the_cold_answer_in_fewer_iterations() {
    let base = ipm_common::filter_lmi();
    let (mut warm, mut cold) = (ipm(true, 100), ipm(false, 100));
    warm.setup(&base).unwrap();
    cold.setup(&base).unwrap();
    let (mut warm_iterations, mut cold_iterations) = (0, 0);
    for step in 0..12 {
        let p = perturbed(&base, step, 1e-3);
        let (w, c) = (solve(&mut warm, &p), solve(&mut cold, &p));
        assert_eq!(c.status, SolveStatus::Solved, "step {step}");
        assert_eq!(c.start, SolveStart::Cold);
        assert_eq!(w.status, SolveStatus::Solved, "step {step}");
        assert_eq!(w.start, if step == 0 { SolveStart::Cold } else { SolveStart::Warm }, "step {step}");
        let rel = (w.primal_objective - c.primal_objective).abs() / c.primal_objective.abs();
        assert!(rel < 1e-7, "step {step}: warm {} cold {} ({rel:e})", w.primal_objective, c.primal_objective);
        if step > 0 {
            warm_iterations += w.iterations;
            cold_iterations += c.iterations;
        }
    }
    println!("11 warm solves: {warm_iterations} iterations, cold: {cold_iterations}");
    assert!(2 * warm_iterations < cold_iterations, "warm {warm_iterations}, cold {cold_iterations}");
}

#[test]
fn the_same_problem_again_takes_few_iterations() {
    let p = ipm_common::filter_lmi();
    let mut warm = ipm(true, 100);
    warm.setup(&p).unwrap();
    let first = solve(&mut warm, &p);
    let again = solve(&mut warm, &p);
    assert_eq!(again.start, SolveStart::Warm);
    assert_eq!(again.status, SolveStatus::Solved);
    assert!(again.iterations < first.iterations, "{} against {}", again.iterations, first.iterations);
    assert!((again.primal_objective - first.primal_objective).abs() < 1e-7 * first.primal_objective.abs());
}

/// minimise x subject to [[x, 1], [1, 1]] ⪰ 0 and x ≤ b: optimum x = 1 for b ≥ 1, primal
/// infeasible for b < 1.
fn bounded(b: f64) -> SdpProblem {
    ipm_common::problem(
        vec![Block::Psd(2), Block::Nonneg(1)],
        vec![1.0],
        &[(1, 0, 0, 0, 1.0), (0, 0, 0, 1, -1.0), (0, 0, 1, 1, -1.0), (1, 1, 0, 0, -1.0), (0, 1, 0, 0, -b)],
    )
}

#[test]
fn an_infeasible_problem_is_certified_and_the_next_solve_starts_cold() {
    let mut warm = ipm(true, 100);
    warm.setup(&bounded(2.0)).unwrap();
    let s = solve(&mut warm, &bounded(2.0));
    assert_eq!((s.status, s.start), (SolveStatus::Solved, SolveStart::Cold));
    assert!((s.x[0] - 1.0).abs() < 1e-6, "{}", s.x[0]);
    let s = solve(&mut warm, &bounded(1.9));
    assert_eq!((s.status, s.start), (SolveStatus::Solved, SolveStart::Warm));
    assert!((s.x[0] - 1.0).abs() < 1e-6, "{}", s.x[0]);
    // Infeasible: the same status as from a cold start, whichever start gave it.
    let s = solve(&mut warm, &bounded(0.5));
    let mut cold = ipm(false, 100);
    cold.setup(&bounded(0.5)).unwrap();
    let c = solve(&mut cold, &bounded(0.5));
    assert_eq!(c.status, SolveStatus::PrimalInfeasible);
    assert_eq!(s.status, c.status);
    assert_ne!(s.start, SolveStart::Cold);
    // No solution is kept from an infeasible problem.
    let s = solve(&mut warm, &bounded(2.0));
    assert_eq!((s.status, s.start), (SolveStatus::Solved, SolveStart::Cold));
    assert!((s.x[0] - 1.0).abs() < 1e-6, "{}", s.x[0]);
}

#[test]
fn a_failed_warm_solve_is_repeated_cold_with_the_cold_result() {
    // A tolerance no iterate can meet: the warm attempt stalls, and the cold attempt (with the
    // rest of the iteration budget, more than it needs to stall) must give exactly what a
    // cold-only backend gives.
    let base = ipm_common::filter_lmi();
    let mut warm = ipm(true, 100);
    warm.setup(&base).unwrap();
    assert_eq!(solve(&mut warm, &base).status, SolveStatus::Solved);
    let unreachable =
        |w: bool| SolverSettings::builder().warm_start(w).tolerance(1e-15).max_iterations(500).build().unwrap();
    warm.set_settings(unreachable(true)).unwrap();
    let mut cold = FaerIpm::new(unreachable(false)).unwrap();
    cold.setup(&base).unwrap();
    let p = perturbed(&base, 1, 1e-3);
    let (w, c) = (solve(&mut warm, &p), solve(&mut cold, &p));
    assert!(!matches!(c.status, SolveStatus::Solved), "{}", c.status);
    assert_eq!((w.status, w.start), (c.status, SolveStart::ColdAfterWarm));
    assert!(w.iterations > c.iterations, "both attempts are counted: {} against {}", w.iterations, c.iterations);
    assert_eq!(w.x, c.x);
    assert_eq!(w.dual, c.dual);
    assert_eq!(w.primal_objective.to_bits(), c.primal_objective.to_bits());
}

#[test]
fn the_iteration_and_time_limits_hold_across_both_attempts() {
    let base = ipm_common::filter_lmi();
    let p = perturbed(&base, 1, 1e-3);
    let mut warm = ipm(true, 100);
    warm.setup(&base).unwrap();
    assert_eq!(solve(&mut warm, &base).status, SolveStatus::Solved);
    // One iteration in all: the warm attempt uses it, no cold attempt follows.
    warm.set_settings(SolverSettings::builder().warm_start(true).max_iterations(1).build().unwrap()).unwrap();
    let s = solve(&mut warm, &p);
    assert_eq!((s.status, s.start, s.iterations), (SolveStatus::IterationLimit, SolveStart::Warm, 1));
    // Nothing was solved, so nothing is stored: the next solve starts cold.
    assert_eq!(solve(&mut warm, &p).start, SolveStart::Cold);
    // With the time used up during the warm attempt, its outcome stands (no cold attempt with no
    // time left).
    warm.set_settings(SolverSettings { warm_start: true, ..SolverSettings::default() }).unwrap();
    assert_eq!(solve(&mut warm, &base).status, SolveStatus::Solved);
    let limited =
        SolverSettings::builder().warm_start(true).time_limit(std::time::Duration::from_nanos(1)).build().unwrap();
    warm.set_settings(limited).unwrap();
    let s = solve(&mut warm, &p);
    assert_eq!(s.start, SolveStart::Warm, "{:?}", s.status);
    assert!(s.iterations <= 1, "{}", s.iterations);
}

#[test]
fn a_rescaled_problem_or_a_new_setup_starts_cold() {
    let base = ipm_common::filter_lmi();
    let mut warm = ipm(true, 100);
    warm.setup(&base).unwrap();
    assert_eq!(solve(&mut warm, &base).start, SolveStart::Cold);
    assert_eq!(solve(&mut warm, &base).start, SolveStart::Warm);
    // Scaled far beyond the equilibration's dead zone: other factors, so the stored solution is in
    // other units and is not used.
    let mut scaled = base.clone();
    let values: Vec<f64> = base.entries().iter().map(|e| e.value * 2f64.powi(30)).collect();
    scaled.set_values(base.c(), &values).unwrap();
    let s = solve(&mut warm, &scaled);
    assert_eq!((s.status, s.start), (SolveStatus::Solved, SolveStart::Cold));
    warm.setup(&base).unwrap();
    assert_eq!(solve(&mut warm, &base).start, SolveStart::Cold);
    // Settings that turn the warm start off are obeyed at once.
    warm.set_settings(SolverSettings::default()).unwrap();
    assert_eq!(solve(&mut warm, &base).start, SolveStart::Cold);
}

#[cfg(feature = "clarabel")]
#[test]
fn clarabel_solves_cold_whatever_the_setting() {
    let base = ipm_common::filter_lmi();
    let settings = SolverSettings::builder().warm_start(true).build().unwrap();
    let mut clarabel = lmi::ClarabelBackend::new(settings).unwrap();
    clarabel.setup(&base).unwrap();
    let mut faer = ipm(false, 100);
    faer.setup(&base).unwrap();
    for step in 0..3 {
        let p = perturbed(&base, step, 1e-3);
        let mut s = SdpSolution::new(&p);
        clarabel.solve(&p, &mut s).unwrap();
        assert_eq!((s.status, s.start), (SolveStatus::Solved, SolveStart::Cold), "step {step}");
        let c = solve(&mut faer, &p);
        assert!((s.primal_objective - c.primal_objective).abs() < 1e-6 * c.primal_objective.abs());
    }
}
