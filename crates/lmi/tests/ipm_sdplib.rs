//! SDPLIB conformance of the `faer-ipm` backend.
//!
//! Problems are read from `$SDPLIB_DIR` (default `../shared/sdplib` next to the workspace); when
//! the directory is missing the test prints a message and passes.
//!
//! The infeasible pair, checked through the certificates returned (independently of the solver's
//! own test): `infp1` is *primal* infeasible in this crate's (SDPA's) naming — no `x` makes
//! `Σ xᵢFᵢ − F₀ ⪰ 0`, and the returned `Y ⪰ 0` has `tr(FᵢY) = 0`, `tr(F₀Y) = 1` — and `infd1` is
//! *dual* infeasible — no `Y ⪰ 0` with `tr(FᵢY) = cᵢ`, and the returned `x` has `Σ xᵢFᵢ ⪰ 0`,
//! `cᵀx = −1`. So the README's labels follow the SDPA convention here (primal = the problem in
//! `x`), not CSDP's.

use std::path::PathBuf;

use lmi::{FaerIpm, SdpBackend, SdpProblem, SdpSolution, SearchDirection, SolveStatus, SolverSettings};

fn sdplib_dir() -> PathBuf {
    std::env::var_os("SDPLIB_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/sdplib")))
}

/// Reference optimum and its number of significant digits.
const OPTIMAL: &[(&str, f64, u32)] = &[
    ("control1", 1.778463e+01, 7),
    ("hinf1", 2.0326e+00, 5),
    ("hinf2", 1.0967e+01, 5),
    ("hinf3", 5.69e+01, 3),
    ("hinf4", 2.74764e+02, 6),
    ("hinf5", 3.63e+02, 3),
    ("truss1", -8.999996e+00, 7),
    ("truss3", -9.109996e+00, 7),
    ("theta1", 2.300000e+01, 7),
];

/// Nearly ill-posed `hinf` problems on which this backend stalls before the relaxed (1e-6)
/// tolerances (the dual residual stagnates near 1e-5 while `τ → 0`): for these the test only
/// requires the objective to match the reference digits and an honest status (optimal, numerical
/// trouble or iteration limit — never infeasible).
const KNOWN_INACCURATE: &[&str] = &["hinf5"];

fn min_eig(m: &nalgebra::DMatrix<f64>) -> f64 {
    m.clone().symmetric_eigen().eigenvalues.min()
}

fn solve(p: &SdpProblem, direction: SearchDirection) -> SdpSolution {
    let mut ipm = FaerIpm::new(SolverSettings::default()).unwrap();
    ipm.set_direction(direction);
    ipm.setup(p).unwrap();
    let mut s = SdpSolution::new(p);
    ipm.solve(p, &mut s).unwrap();
    // Time a few repeated solves (the first one includes page faults and cache misses).
    let reps = if cfg!(debug_assertions) { 1 } else { 5 };
    let mut best = s.solve_time;
    for _ in 0..reps {
        ipm.solve(p, &mut s).unwrap();
        best = best.min(s.solve_time);
    }
    s.solve_time = best;
    s
}

#[test]
fn sdplib_conformance() {
    conformance(SearchDirection::NesterovTodd);
}

/// The same with the HKM direction (`docs/sdp.md` §3.6).
#[test]
fn sdplib_conformance_hkm() {
    conformance(SearchDirection::Hkm);
}

fn conformance(direction: SearchDirection) {
    let dir = sdplib_dir();
    if !dir.is_dir() {
        println!("SDPLIB directory {} not found: skipping the SDPLIB conformance test", dir.display());
        return;
    }
    let mut failures = vec![];
    println!("| problem | status | objective | reference | rel. error | iterations | time |");
    println!("|---|---|---:|---:|---:|---:|---:|");
    for &(name, reference, digits) in OPTIMAL {
        let p = lmi::read_sdpa_file(&dir.join(format!("{name}.dat-s"))).unwrap();
        let s = solve(&p, direction);
        let rel = (s.primal_objective - reference).abs() / reference.abs();
        let tol = if digits >= 7 { 1e-6 } else { 0.5 * 10f64.powi(1 - digits as i32) };
        println!(
            "| {name} | {} | {:.9e} | {reference:e} | {rel:.1e} | {} | {:?} |",
            s.status, s.primal_objective, s.iterations, s.solve_time
        );
        let known_hard = KNOWN_INACCURATE.contains(&name);
        if rel > tol
            || (!s.status.is_optimal() && !known_hard)
            || (known_hard
                && !s.status.is_optimal()
                && s.status != SolveStatus::NumericalTrouble
                && s.status != SolveStatus::IterationLimit)
        {
            failures.push(format!(
                "{name}: {} objective {} (reference {reference}, tol {tol:e})",
                s.status, s.primal_objective
            ));
        }
    }
    // infp1: primal infeasible in this crate's naming (certificate Y ⪰ 0, tr(FᵢY) = 0, tr(F₀Y) > 0).
    let p = lmi::read_sdpa_file(&dir.join("infp1.dat-s")).unwrap();
    let s = solve(&p, direction);
    println!("| infp1 | {} | | primal infeasible | | {} | {:?} |", s.status, s.iterations, s.solve_time);
    if s.status == SolveStatus::PrimalInfeasible {
        let t = p.traces(&s.dual).unwrap();
        let aty = t[1..].iter().map(|v| v * v).sum::<f64>().sqrt();
        let ymin = s.dual.iter().map(min_eig).fold(f64::INFINITY, f64::min);
        let ymax = s.dual.iter().map(|y| y.norm()).fold(0.0, f64::max);
        assert!(
            (t[0] - 1.0).abs() < 1e-9 && aty < 1e-7 && ymin > -1e-9 * ymax.max(1.0),
            "bad certificate: {t:?} {ymin}"
        );
        // The backend-independent check the backends apply, at a tolerance 10x tighter.
        let m = lmi::check_certificate(&p, &s, 1e-6).unwrap();
        println!("infp1 certificate: {m:?}");
    } else {
        failures.push(format!("infp1: {}", s.status));
    }
    // infd1: dual infeasible in this crate's naming (certificate x: Σ xᵢFᵢ ⪰ 0, cᵀx < 0).
    let p = lmi::read_sdpa_file(&dir.join("infd1.dat-s")).unwrap();
    let s = solve(&p, direction);
    println!("| infd1 | {} | | dual infeasible | | {} | {:?} |", s.status, s.iterations, s.solve_time);
    if s.status == SolveStatus::DualInfeasible {
        let cx: f64 = p.c().iter().zip(&s.x).map(|(c, x)| c * x).sum();
        // Σ xᵢFᵢ = slack(x) − slack(0).
        let ax: Vec<_> = p
            .slack(&s.x)
            .unwrap()
            .iter()
            .zip(p.slack(&vec![0.0; p.num_vars()]).unwrap())
            .map(|(sx, s0)| sx - s0)
            .collect();
        let amin = ax.iter().map(min_eig).fold(f64::INFINITY, f64::min);
        let scale = ax.iter().map(|a| a.norm()).fold(0.0, f64::max);
        assert!((cx + 1.0).abs() < 1e-9 && amin > -1e-7 * scale.max(1.0), "bad certificate: {cx} {amin}");
        let m = lmi::check_certificate(&p, &s, 1e-6).unwrap();
        println!("infd1 certificate: {m:?}");
    } else {
        failures.push(format!("infd1: {}", s.status));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
