//! Infeasibility is reported only with a certificate that passes the independent check
//! (`lmi::certificate`) on the caller's unscaled problem; otherwise the outcome is numerical
//! trouble with the reason. Three classes: feasible problems with tiny data (every data scaled
//! by `1e-8 … 1e-20`), feasible problems with one entry of `1e308` in various places, and
//! genuinely infeasible problems (both sides, several scalings), whose certificates must pass.
//! Every class runs against every backend compiled in.

use std::sync::atomic::{AtomicUsize, Ordering};

mod ipm_common;

use lmi::certificate::{CertificateFailure, CertificateKind, check_certificate};
use lmi::{Block, Entry, SdpBackend, SdpProblem, SdpSolution, SolveStatus, SolverSettings};

fn e(mat: usize, block: usize, row: usize, col: usize, value: f64) -> Entry {
    Entry { mat, block, row, col, value }
}

fn scaled(p: &SdpProblem, s_obj: f64, s_con: f64) -> SdpProblem {
    let mut q = p.clone();
    let c: Vec<f64> = p.c().iter().map(|v| v * s_obj).collect();
    let values: Vec<f64> = p.entries().iter().map(|e| e.value * s_con).collect();
    q.set_values(&c, &values).unwrap();
    q
}

/// `min (x₁ + x₂)/2  s.t.  [[x₁, 1], [1, x₂]] ⪰ 0, x₁ ≥ 1/4, x₂ ≥ 0`: optimum 1 at `x = (1, 1)`.
fn two_by_two() -> SdpProblem {
    ipm_common::known_optimum(1.0, 1.0)
}

/// `min t  s.t.  t I − A ⪰ 0` with `A = [[0, 1, 0], [1, 0, 0], [0, 0, 1]]` (eigenvalues 1, 1,
/// −1): optimum `λ_max(A) = 1`.
fn largest_eigenvalue() -> SdpProblem {
    let entries =
        vec![e(1, 0, 0, 0, 1.0), e(1, 0, 1, 1, 1.0), e(1, 0, 2, 2, 1.0), e(0, 0, 0, 1, 1.0), e(0, 0, 2, 2, 1.0)];
    SdpProblem::new(vec![Block::Psd(3)], vec![1.0], entries).unwrap()
}

/// `min x₁  s.t.  [[x₁, 1], [1, x₂]] ⪰ 0,  x₂ ≤ 1` (as `1 − x₂ ≥ 0`): optimum 1 at `x = (1, 1)`.
fn schur_with_bound() -> SdpProblem {
    let entries =
        vec![e(1, 0, 0, 0, 1.0), e(2, 0, 1, 1, 1.0), e(0, 0, 0, 1, -1.0), e(2, 1, 0, 0, -1.0), e(0, 1, 0, 0, -1.0)];
    SdpProblem::new(vec![Block::Psd(2), Block::Nonneg(1)], vec![1.0, 0.0], entries).unwrap()
}

/// Primal infeasible, strongly: `[[x, 1], [1, −x]] ⪰ 0` has determinant `−x² − 1 < 0`
/// (certificate `Y = [[1, −1], [−1, 1]]`), plus a harmless second variable.
fn primal_infeasible_psd() -> SdpProblem {
    let entries = vec![e(1, 0, 0, 0, 1.0), e(1, 0, 1, 1, -1.0), e(0, 0, 0, 1, -1.0), e(2, 1, 0, 0, 1.0)];
    SdpProblem::new(vec![Block::Psd(2), Block::Nonneg(1)], vec![1.0, 1.0], entries).unwrap()
}

/// Primal infeasible LP: `x ≥ 1` and `−x ≥ 0`.
fn primal_infeasible_lp() -> SdpProblem {
    SdpProblem::new(
        vec![Block::Nonneg(2)],
        vec![1.0],
        vec![e(1, 0, 0, 0, 1.0), e(0, 0, 0, 0, 1.0), e(1, 0, 1, 1, -1.0)],
    )
    .unwrap()
}

/// Dual infeasible (unbounded below): `min −x₁ + x₂  s.t.  [[x₁, x₂], [x₂, 1]] ⪰ 0`; the ray
/// `x = (1, 0)` has `Σ xᵢFᵢ = diag(1, 0) ⪰ 0`, `cᵀx = −1`.
fn dual_infeasible_psd() -> SdpProblem {
    let entries = vec![e(1, 0, 0, 0, 1.0), e(2, 0, 0, 1, 1.0), e(0, 0, 1, 1, -1.0)];
    SdpProblem::new(vec![Block::Psd(2)], vec![-1.0, 1.0], entries).unwrap()
}

/// Dual infeasible LP: `min −x  s.t.  x ≥ 0`.
fn dual_infeasible_lp() -> SdpProblem {
    SdpProblem::new(vec![Block::Nonneg(1)], vec![-1.0], vec![e(1, 0, 0, 0, 1.0)]).unwrap()
}

fn backends(settings: &SolverSettings) -> Vec<Box<dyn SdpBackend>> {
    lmi::backend_names().into_iter().map(|name| lmi::backend_by_name(name, settings.clone()).unwrap()).collect()
}

fn solve(backend: &mut dyn SdpBackend, p: &SdpProblem) -> SdpSolution {
    backend.setup(p).unwrap();
    let mut sol = SdpSolution::new(p);
    backend.solve(p, &mut sol).unwrap();
    sol
}

fn is_infeasible(s: SolveStatus) -> bool {
    CertificateKind::of(s).is_some()
}

/// The settings each class runs with: the default (equilibration on) and without equilibration
/// (the backends then see the tiny or huge numbers as they are).
fn settings_variants() -> [(&'static str, SolverSettings); 2] {
    [
        ("equilibrated", SolverSettings::default()),
        ("unequilibrated", SolverSettings::builder().equilibrate(false).build().unwrap()),
    ]
}

/// Infeasibility claims rejected by the check in the feasible classes (each would have been
/// reported as an infeasibility before the check).
static REJECTED: AtomicUsize = AtomicUsize::new(0);

/// A feasible problem with optimum `expected` must never be reported infeasible: with
/// equilibration (the default) either the optimum (to `1e-6` relative) or a status that is not
/// optimal (numerical trouble, a limit); without it, anything but an infeasibility.
/// Returns a description of each violation; prints every outcome.
fn feasible_violations(label: &str, p: &SdpProblem, expected: f64) -> Vec<String> {
    let mut out = vec![];
    for (variant, settings) in settings_variants() {
        let equilibrated = settings.equilibrate;
        for mut backend in backends(&settings) {
            let sol = solve(backend.as_mut(), p);
            let why = sol.rejected_certificate.map(|r| format!(" ({r})")).unwrap_or_default();
            println!(
                "{label}, {variant}, {}: {} objective {:e}{why}",
                backend.name(),
                sol.status,
                sol.primal_objective
            );
            let name = backend.name();
            if is_infeasible(sol.status) {
                out.push(format!("{label}, {variant}, {name}: reported {} for a feasible problem", sol.status));
            } else if equilibrated
                && sol.status.is_optimal()
                && (sol.primal_objective - expected).abs() > 1e-6 * expected.abs()
            {
                // (Without equilibration the tolerances apply in the data's units, and tiny or huge
                // data can end "solved" at a wrong point: documented, and not this test's concern.)
                out.push(format!(
                    "{label}, {variant}, {name}: {} with objective {:e}, expected {expected:e}",
                    sol.status, sol.primal_objective
                ));
            }
            if sol.status == SolveStatus::NumericalTrouble {
                if let Some(r) = sol.rejected_certificate {
                    assert!(is_infeasible(r.claimed), "{r}");
                    REJECTED.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
    }
    out
}

/// Class (a): feasible SDPs with optimum `+1` (times the objective's scale), all data scaled by
/// tiny factors. Clarabel once reported "dual infeasible" with objective `−1` for such a problem:
/// its ray was an improving direction only within Clarabel's absolute tolerances.
#[test]
fn tiny_feasible_problems_are_never_reported_infeasible() {
    let mut violations = vec![];
    for (name, p) in [("2x2", two_by_two()), ("lambda_max", largest_eigenvalue()), ("schur", schur_with_bound())] {
        for s in [1e-8, 1e-10, 1e-12, 1e-14, 1e-16, 1e-20] {
            violations.extend(feasible_violations(&format!("{name} all data x {s:e}"), &scaled(&p, s, s), s));
            violations.extend(feasible_violations(&format!("{name} constraints x {s:e}"), &scaled(&p, 1.0, s), 1.0));
        }
    }
    println!("infeasibility claims rejected so far: {}", REJECTED.load(Ordering::Relaxed));
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

/// Class (b): feasible problems with one entry of `1e308` (in `F₀`, in an `Fᵢ`, in `c`), some
/// with an optimum of 1. Before the check, `faer-ipm` made five infeasibility claims in this
/// class ("primal infeasible" when the bound `x₁ ≥ 1/4` becomes `x₁ ≥ 1e308`, entry 1; "dual
/// infeasible" for costs of `1e308`) and Clarabel seven.
#[test]
fn feasible_problems_with_an_entry_of_1e308_are_never_reported_infeasible() {
    let big = 1e308;
    let base = two_by_two();
    let with = |extra_blocks: Vec<Block>, extra_c: Vec<f64>, extra: Vec<Entry>| {
        let mut blocks = base.blocks().to_vec();
        blocks.extend(extra_blocks);
        let mut c = base.c().to_vec();
        c.extend(extra_c);
        let mut entries = base.entries().to_vec();
        entries.extend(extra);
        SdpProblem::new(blocks, c, entries).unwrap()
    };
    let cases = [
        // x₁ + 1e308 ≥ 0 (F₀ entry −1e308): inactive.
        ("F0 entry -1e308", with(vec![Block::Nonneg(1)], vec![], vec![e(1, 2, 0, 0, 1.0), e(0, 2, 0, 0, -big)])),
        // 1e308 x₁ ≥ 1: active only near x₁ = 1e-308.
        ("Fi entry 1e308", with(vec![Block::Nonneg(1)], vec![], vec![e(1, 2, 0, 0, big), e(0, 2, 0, 0, 1.0)])),
        // x₃ ≥ 0 with cost 1e308: x₃ = 0.
        ("c entry 1e308", with(vec![Block::Nonneg(1)], vec![big], vec![e(3, 2, 0, 0, 1.0)])),
        // [[1e308 x₃ + 1, 0], [0, 1]] ⪰ 0 with x₃ ≥ 0 and cost 1: x₃ = 0.
        (
            "PSD entry 1e308",
            with(
                vec![Block::Psd(2), Block::Nonneg(1)],
                vec![1.0],
                vec![e(3, 2, 0, 0, big), e(0, 2, 0, 0, -1.0), e(0, 2, 1, 1, -1.0), e(3, 3, 0, 0, 1.0)],
            ),
        ),
        // The off-diagonal 1 of the 2x2 block replaced by a huge-scale copy of the same block.
        (
            "F0 off-diagonal -1e308 in a scaled copy",
            with(vec![Block::Psd(2)], vec![], vec![e(1, 2, 0, 0, big), e(2, 2, 1, 1, big), e(0, 2, 0, 1, -big)]),
        ),
    ];
    let mut violations = vec![];
    for (label, p) in &cases {
        violations.extend(feasible_violations(label, p, 1.0));
    }
    // Each value of the base problem in turn replaced by ±1e308 (sign kept): all still feasible
    // (`x₁ ≥ 1e308` included), with optima far from 1, so only the status is judged.
    for k in 0..base.entries().len() {
        let mut values: Vec<f64> = base.entries().iter().map(|e| e.value).collect();
        values[k] = big.copysign(values[k]);
        let mut p = base.clone();
        p.set_values(base.c(), &values).unwrap();
        violations.extend(
            feasible_violations(&format!("entry {k} -> 1e308"), &p, f64::NAN)
                .into_iter()
                .filter(|v| v.contains("reported")),
        );
    }
    for k in 0..base.c().len() {
        let mut c = base.c().to_vec();
        c[k] = big;
        let mut p = base.clone();
        p.set_values(&c, &base.entries().iter().map(|e| e.value).collect::<Vec<_>>()).unwrap();
        violations.extend(
            feasible_violations(&format!("c[{k}] -> 1e308"), &p, f64::NAN)
                .into_iter()
                .filter(|v| v.contains("reported")),
        );
    }
    println!("infeasibility claims rejected so far: {}", REJECTED.load(Ordering::Relaxed));
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

/// Class (c): genuinely infeasible problems, on both sides and at several scalings, are still
/// reported infeasible by every backend, with a certificate the checker accepts at a tolerance
/// far tighter than the backends' own.
#[test]
fn infeasible_problems_are_still_certified() {
    let cases = [
        ("primal PSD", primal_infeasible_psd(), SolveStatus::PrimalInfeasible),
        ("primal LP", primal_infeasible_lp(), SolveStatus::PrimalInfeasible),
        ("dual PSD", dual_infeasible_psd(), SolveStatus::DualInfeasible),
        ("dual LP", dual_infeasible_lp(), SolveStatus::DualInfeasible),
    ];
    let mut failures = vec![];
    for (label, p, side) in &cases {
        for (s_obj, s_con) in [(1.0, 1.0), (1e-12, 1e-12), (1e12, 1e12), (1.0, 1e-15), (1e9, 1.0)] {
            let p = scaled(p, s_obj, s_con);
            for mut backend in backends(&SolverSettings::default()) {
                let sol = solve(backend.as_mut(), &p);
                let name = backend.name();
                let same_side = CertificateKind::of(sol.status) == CertificateKind::of(*side);
                if !same_side {
                    failures.push(format!(
                        "{label} x ({s_obj:e}, {s_con:e}), {name}: {} (expected {side}){}",
                        sol.status,
                        sol.rejected_certificate.map(|r| format!(": {r}")).unwrap_or_default()
                    ));
                    continue;
                }
                assert!(sol.rejected_certificate.is_none());
                match check_certificate(&p, &sol, 1e-7) {
                    Ok(m) => println!("{label} x ({s_obj:e}, {s_con:e}), {name}: {} {m:?}", sol.status),
                    Err(why) => failures.push(format!("{label} x ({s_obj:e}, {s_con:e}), {name}: {why}")),
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The checker itself: exact certificates pass with the same measures at every scaling of the
/// data and of the certificate (also with entries of `1e308`, without overflow); the bogus
/// certificate of class (a) — an "improving ray" of a tiny feasible problem, which a check
/// against `|cᵀx|` alone accepts — is rejected, as are wrong signs, non-PSD matrices, residuals
/// and non-finite entries.
#[test]
fn the_checker_accepts_certificates_and_rejects_impostors() {
    let primal = |p: &SdpProblem, y: Vec<nalgebra::DMatrix<f64>>| {
        let mut sol = SdpSolution::new(p);
        sol.status = SolveStatus::PrimalInfeasible;
        sol.dual = y;
        sol
    };
    let dual = |p: &SdpProblem, x: Vec<f64>| {
        let mut sol = SdpSolution::new(p);
        sol.status = SolveStatus::DualInfeasible;
        sol.x = x;
        sol
    };
    let y_cert =
        |k: f64| vec![nalgebra::DMatrix::from_row_slice(2, 2, &[k, -k, -k, k]), nalgebra::DMatrix::zeros(1, 1)];
    let base = primal_infeasible_psd();
    let reference = check_certificate(&base, &primal(&base, y_cert(1.0)), 1e-12).unwrap();
    assert!(reference.margin > 0.5 && reference.residual == 0.0 && reference.negativity < 1e-15, "{reference:?}");
    for (s_obj, s_con, k) in [(1e-12, 1e-12, 1e5), (1e300, 1e308 / 2.0, 1e-300), (1.0, 1e-300, 1e300)] {
        let p = scaled(&base, s_obj, s_con);
        let m = check_certificate(&p, &primal(&p, y_cert(k)), 1e-12).unwrap();
        assert!((m.margin - reference.margin).abs() < 1e-14, "{m:?}");
    }
    // Wrong sign, a residual, a negative eigenvalue, a NaN, a zero certificate.
    let bad = |y: Vec<nalgebra::DMatrix<f64>>| check_certificate(&base, &primal(&base, y), 1e-6).unwrap_err();
    let m2 = |v: [f64; 4], w: f64| {
        vec![nalgebra::DMatrix::from_row_slice(2, 2, &v), nalgebra::DMatrix::from_element(1, 1, w)]
    };
    assert!(matches!(bad(m2([1.0, 1.0, 1.0, 1.0], 0.0)), CertificateFailure::Margin(_)));
    assert!(matches!(bad(m2([1.0, -1.0, -1.0, 1.0], 1e-3)), CertificateFailure::Residual { .. }));
    assert!(matches!(bad(m2([1.0, -1.1, -1.1, 1.0], 0.0)), CertificateFailure::NotPsd { .. }));
    assert!(matches!(bad(m2([f64::NAN, -1.0, -1.0, 1.0], 0.0)), CertificateFailure::NonFinite));
    assert!(matches!(bad(m2([0.0; 4], 0.0)), CertificateFailure::Zero));

    // Dual side: the exact ray, at every scaling.
    let base = dual_infeasible_psd();
    for (s_obj, s_con, k) in [(1.0, 1.0, 1.0), (1e-12, 1e-12, 1e12), (1e308, 1e308, 1e-308), (1e-300, 1.0, 1e300)] {
        let p = scaled(&base, s_obj, s_con);
        let m = check_certificate(&p, &dual(&p, vec![k, 0.0]), 1e-12).unwrap();
        assert!((m.margin - 1.0).abs() < 1e-15 && m.negativity == 0.0, "{m:?}");
    }
    // The class-(a) impostor: for the feasible problem with constraints scaled by 1e-12, the ray
    // x = (−1, −1) has cᵀx = −1 (the "objective −1") and Σ xᵢFᵢ = −1e-12 I: PSD to within
    // 1e-6 |cᵀx| in absolute terms, yet as negative as it can be relative to its size.
    let s = 1e-12;
    let p = scaled(&two_by_two(), 1.0, s);
    let sol = dual(&p, vec![-1.0, -1.0]);
    let cx: f64 = p.c().iter().zip(&sol.x).map(|(c, x)| c * x).sum();
    let ray_min = -s;
    assert!(cx == -1.0 && ray_min >= -1e-6 * cx.abs(), "an absolute check would accept it");
    let why = check_certificate(&p, &sol, 1e-3).unwrap_err();
    assert!(matches!(why, CertificateFailure::NotPsd { .. }), "{why}");
    assert!(why.to_string().contains("eigenvalue"), "{why}");
    // A status without a certificate.
    let mut sol = SdpSolution::new(&p);
    sol.status = SolveStatus::Solved;
    assert!(matches!(check_certificate(&p, &sol, 1e-6), Err(CertificateFailure::NotAnInfeasibilityStatus(_))));
}
