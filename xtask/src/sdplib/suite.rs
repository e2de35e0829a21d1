//! The SDPLIB peer test suite: locating the problems and their reference outcomes.
//!
//! The problems are read from a directory (by default `../shared/sdplib` next to the workspace,
//! or the directory named by the environment variable `SDPLIB_DIR`), and the expected outcomes
//! from the table in that directory's `README.md` (`| problem | m | blocks | optimum |`), so that
//! the reference values live in one place.
//!
//! Naming of infeasible problems: the README's labels use SDPA's naming, the same as this crate
//! (primal = the problem in `x`). `infp1` is [`SolveStatus::PrimalInfeasible`] (a certificate
//! `Y ⪰ 0`, `tr(FᵢY) = 0`, `tr(F₀Y) > 0` exists) and `infd1` is [`SolveStatus::DualInfeasible`];
//! [`check_certificate`] verifies each certificate independently of the solver, which is how
//! this was established (CSDP and the SDPLIB paper call the problem in `Y` the primal, so the
//! labels there are swapped).

use std::path::{Path, PathBuf};

use lmi::LmiError;
use lmi::SdpProblem;
use lmi::{SdpSolution, SolveStatus, SolverSettings};

/// Environment variable that overrides the SDPLIB directory.
pub const SDPLIB_DIR_VAR: &str = "SDPLIB_DIR";

/// The SDPLIB directory: `$SDPLIB_DIR` if set, else `<workspace>/../shared/sdplib`; `None` if
/// it does not exist.
pub fn sdplib_dir() -> Option<PathBuf> {
    let dir = match std::env::var_os(SDPLIB_DIR_VAR) {
        Some(d) => PathBuf::from(d),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/sdplib"),
    };
    dir.is_dir().then_some(dir)
}

/// What a problem of the suite should end with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Expected {
    /// An optimum with this objective, given to `digits` significant digits.
    Optimal {
        /// The reference objective value.
        value: f64,
        /// Significant digits of the reference.
        digits: u32,
    },
    /// Infeasibility on the side named by the status (this crate's naming).
    Infeasible(SolveStatus),
}

impl Expected {
    /// Tolerance on the objective: relative `1e-6` where the reference has at least 7
    /// significant digits, otherwise half a unit in its last digit.
    pub fn tolerance(&self) -> f64 {
        match *self {
            Expected::Optimal { value, digits } => {
                if digits >= 7 {
                    1e-6 * value.abs()
                } else {
                    let exponent = value.abs().log10().floor() as i32;
                    0.5 * 10f64.powi(exponent + 1 - digits as i32)
                }
            }
            Expected::Infeasible(_) => 0.0,
        }
    }
}

/// One problem of the suite.
#[derive(Debug, Clone)]
pub struct SuiteProblem {
    /// Name (file stem), e.g. `control1`.
    pub name: String,
    /// Path of the `.dat-s` file.
    pub path: PathBuf,
    /// The reference outcome.
    pub expected: Expected,
}

/// Parses the reference table of the suite's `README.md` and pairs it with the files present.
/// Problems listed without a file, or files without a reference, are errors.
pub fn suite(dir: &Path) -> Result<Vec<SuiteProblem>, LmiError> {
    let readme = dir.join("README.md");
    let text = std::fs::read_to_string(&readme)
        .map_err(|e| LmiError::Sdpa { line: 0, message: format!("{}: {e}", readme.display()) })?;
    let mut out = Vec::new();
    for (lineno, line) in text.lines().enumerate() {
        let cells: Vec<&str> = line.trim().trim_matches('|').split('|').map(str::trim).collect();
        if cells.len() != 4 || cells[0] == "problem" || cells[0].starts_with("---") {
            continue;
        }
        let name = cells[0];
        if cells[1].parse::<usize>().is_err() {
            continue;
        }
        let expected = parse_outcome(cells[3]).ok_or_else(|| LmiError::Sdpa {
            line: lineno + 1,
            message: format!("{}: cannot read the reference outcome {:?}", readme.display(), cells[3]),
        })?;
        let path = dir.join(format!("{name}.dat-s"));
        if !path.is_file() {
            return Err(LmiError::Sdpa {
                line: lineno + 1,
                message: format!("{} is listed but missing", path.display()),
            });
        }
        out.push(SuiteProblem { name: name.to_owned(), path, expected });
    }
    if out.is_empty() {
        return Err(LmiError::Sdpa { line: 0, message: format!("{}: no reference table found", readme.display()) });
    }
    Ok(out)
}

fn parse_outcome(cell: &str) -> Option<Expected> {
    match cell {
        "primal infeasible" => return Some(Expected::Infeasible(SolveStatus::PrimalInfeasible)),
        "dual infeasible" => return Some(Expected::Infeasible(SolveStatus::DualInfeasible)),
        _ => {}
    }
    let s = cell.replace('\u{2212}', "-");
    let value: f64 = s.parse().ok()?;
    let mantissa = s.trim_start_matches(['-', '+']).split(['e', 'E']).next()?;
    let digits = mantissa.trim_start_matches(['0', '.']).chars().filter(char::is_ascii_digit).count() as u32;
    Some(Expected::Optimal { value, digits: digits.max(1) })
}

/// Checks an infeasibility certificate independently of the solver, returning a description
/// of what is wrong, if anything. For [`SolveStatus::PrimalInfeasible`]: `Y ⪰ 0`,
/// `tr(FᵢY) ≈ 0`, `tr(F₀Y) > 0`; for [`SolveStatus::DualInfeasible`]: `Σ xᵢFᵢ ⪰ 0`, `cᵀx < 0`
/// (both up to relative tolerance `tol`).
pub fn check_certificate(problem: &SdpProblem, solution: &SdpSolution, tol: f64) -> Result<(), String> {
    // Every comparison below is false for NaN: reject non-finite certificates first.
    if solution.x.iter().chain(solution.dual.iter().flat_map(|y| y.iter())).any(|v| !v.is_finite()) {
        return Err("the certificate has non-finite entries".into());
    }
    match solution.status {
        SolveStatus::PrimalInfeasible | SolveStatus::AlmostPrimalInfeasible => {
            let t = problem.traces(&solution.dual).map_err(|e| e.to_string())?;
            let scale = t[0];
            if scale <= 0.0 {
                return Err(format!("tr(F0 Y) = {scale} is not positive"));
            }
            let worst = t[1..].iter().fold(0.0f64, |m, v| m.max(v.abs())) / scale;
            if worst > tol {
                return Err(format!("max |tr(Fi Y)| / tr(F0 Y) = {worst:e}"));
            }
            let min_eig =
                solution.dual.iter().map(|y| y.clone().symmetric_eigenvalues().min()).fold(f64::INFINITY, f64::min);
            let ynorm = solution.dual.iter().map(|y| y.norm()).fold(0.0, f64::max);
            if min_eig < -tol * ynorm {
                return Err(format!("Y has eigenvalue {min_eig:e}"));
            }
            Ok(())
        }
        SolveStatus::DualInfeasible | SolveStatus::AlmostDualInfeasible => {
            let cx: f64 = problem.c().iter().zip(&solution.x).map(|(c, x)| c * x).sum();
            if cx >= 0.0 {
                return Err(format!("c'x = {cx} is not negative"));
            }
            // Σ xᵢFᵢ = slack(x) + F₀; scale by |cᵀx|.
            let zero = vec![0.0; problem.num_vars()];
            let f0 = problem.slack(&zero).map_err(|e| e.to_string())?;
            let s = problem.slack(&solution.x).map_err(|e| e.to_string())?;
            for (sb, f0b) in s.iter().zip(&f0) {
                let ray = sb - f0b; // Σ xᵢFᵢ (slack(0) = −F₀)
                let min_eig = ray.symmetric_eigenvalues().min();
                if min_eig < -tol * cx.abs() {
                    return Err(format!("sum x_i F_i has eigenvalue {min_eig:e} (c'x = {cx:e})"));
                }
            }
            Ok(())
        }
        s => Err(format!("status {s} is not an infeasibility status")),
    }
}

/// Whether `solution` matches `expected`: an optimal status with the objective within
/// [`Expected::tolerance`], or infeasibility on the expected side (an `Almost…` status on that
/// side counts) with a certificate that passes [`check_certificate`] at `1e-6`. `Err` says why not.
pub fn check_outcome(expected: &Expected, problem: &SdpProblem, solution: &SdpSolution) -> Result<(), String> {
    match *expected {
        Expected::Optimal { value, .. } => {
            let err = (solution.primal_objective - value).abs();
            if !solution.status.is_optimal() {
                Err(format!("status {} (expected an optimum)", solution.status))
            } else if err > expected.tolerance() {
                Err(format!(
                    "objective {} differs from {value} by {err:.2e} (tolerance {:.2e})",
                    solution.primal_objective,
                    expected.tolerance()
                ))
            } else {
                Ok(())
            }
        }
        Expected::Infeasible(side) => {
            let same_side = solution.status == side
                || matches!(
                    (side, solution.status),
                    (SolveStatus::PrimalInfeasible, SolveStatus::AlmostPrimalInfeasible)
                        | (SolveStatus::DualInfeasible, SolveStatus::AlmostDualInfeasible)
                );
            if !same_side {
                return Err(format!("status {} (expected {side})", solution.status));
            }
            check_certificate(problem, solution, 1e-6).map_err(|e| format!("certificate: {e}"))
        }
    }
}

/// Settings for the suite: tolerances `1e-9`, tighter than the defaults, because several
/// references are given to 7 digits and the `hinf*` problems are ill-conditioned (with `1e-8`
/// Clarabel stops `5.8e-4` away from `hinf2`'s reference).
pub fn suite_settings() -> SolverSettings {
    SolverSettings::builder().tolerance(1e-9).build().expect("valid settings")
}

/// A documented deviation from the reference table, with the relaxed relative tolerance that
/// still applies. Each reason is backed by a strictly feasible `x` (whose `cᵀx` is an upper bound
/// on the optimum of the minimisation), which `tests/sdplib_conformance.rs` re-establishes.
#[derive(Debug, Clone, Copy)]
pub struct KnownDeviation {
    /// Problem name.
    pub problem: &'static str,
    /// Backend it applies to (`None`: every backend).
    pub backend: Option<&'static str>,
    /// Relaxed relative tolerance on the objective.
    pub rel_tol: f64,
    /// Why.
    pub reason: &'static str,
}

/// The known deviations (see [`KnownDeviation`]).
pub const KNOWN_DEVIATIONS: &[KnownDeviation] = &[
    KnownDeviation {
        problem: "hinf5",
        backend: None,
        rel_tol: 1e-2,
        reason: "the reference 3.63e+02 is inconsistent with its own digits: faer-ipm returns a strictly feasible x \
                 (smallest eigenvalue of X ≈ 1.5e-7) with cᵀx = 362.2252, so the optimum is at most 362.23 < 362.5",
    },
    KnownDeviation {
        problem: "hinf1",
        backend: Some("clarabel"),
        rel_tol: 1e-4,
        reason: "Clarabel stops about 5e-5 relative above the strictly feasible point cᵀx = 2.032609 that faer-ipm \
                 finds (reference 2.0326); the problem is ill-conditioned (‖x‖∞ ≈ 7e3) and Clarabel's answer moves at \
                 this level with the BLAS threading",
    },
    KnownDeviation {
        problem: "hinf2",
        backend: Some("clarabel"),
        rel_tol: 1e-4,
        reason: "Clarabel stops up to 5e-5 relative above the strictly feasible point cᵀx = 10.967127 that faer-ipm \
                 finds (reference 10.967); its answer moves at this level with the BLAS threading",
    },
];

/// The outcome of one problem for one backend.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Matches the reference.
    Pass,
    /// Matches only within a [`KnownDeviation`]'s relaxed tolerance; the reason is attached.
    KnownDeviation(&'static str),
    /// Does not match; what is wrong.
    Fail(String),
}

/// [`check_outcome`], then the [`KNOWN_DEVIATIONS`] for `backend` if it fails.
pub fn verdict(p: &SuiteProblem, backend: &str, problem: &SdpProblem, solution: &SdpSolution) -> Verdict {
    match check_outcome(&p.expected, problem, solution) {
        Ok(()) => Verdict::Pass,
        Err(e) => {
            let known = KNOWN_DEVIATIONS.iter().find(|d| d.problem == p.name && d.backend.is_none_or(|b| b == backend));
            match (known, p.expected) {
                (Some(d), Expected::Optimal { value, .. })
                    if solution.status.is_optimal()
                        && (solution.primal_objective - value).abs() <= d.rel_tol * value.abs() =>
                {
                    Verdict::KnownDeviation(d.reason)
                }
                _ => Verdict::Fail(e),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_certificates_are_rejected() {
        use lmi::{Block, Entry};
        let p = SdpProblem::new(
            vec![Block::Psd(1)],
            vec![1.0],
            vec![Entry { mat: 1, block: 0, row: 0, col: 0, value: 1.0 }],
        )
        .unwrap();
        for status in [SolveStatus::PrimalInfeasible, SolveStatus::DualInfeasible] {
            let mut sol = SdpSolution::new(&p);
            sol.status = status;
            sol.x[0] = f64::NAN;
            sol.dual[0][(0, 0)] = f64::NAN;
            assert!(check_certificate(&p, &sol, 1e-6).unwrap_err().contains("non-finite"), "{status}");
        }
    }

    #[test]
    fn outcomes_and_tolerances() {
        assert_eq!(parse_outcome("1.778463e+01"), Some(Expected::Optimal { value: 17.78463, digits: 7 }));
        assert_eq!(parse_outcome("\u{2212}8.999996e+00"), Some(Expected::Optimal { value: -8.999996, digits: 7 }));
        assert_eq!(parse_outcome("5.69e+01"), Some(Expected::Optimal { value: 56.9, digits: 3 }));
        assert_eq!(parse_outcome("primal infeasible"), Some(Expected::Infeasible(SolveStatus::PrimalInfeasible)));
        assert_eq!(parse_outcome("dual infeasible"), Some(Expected::Infeasible(SolveStatus::DualInfeasible)));
        assert_eq!(parse_outcome("nonsense"), None);
        assert!((Expected::Optimal { value: 56.9, digits: 3 }.tolerance() - 0.05).abs() < 1e-15);
        assert!((Expected::Optimal { value: 2.0326, digits: 5 }.tolerance() - 5e-5).abs() < 1e-15);
        assert!((Expected::Optimal { value: 17.78463, digits: 7 }.tolerance() - 17.78463e-6).abs() < 1e-15);
    }
}
