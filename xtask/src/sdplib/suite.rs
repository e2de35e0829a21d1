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

use std::fmt;
use std::path::{Path, PathBuf};

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

/// What is wrong with the suite's directory or its reference table.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum SuiteError {
    /// The SDPLIB directory does not exist (or is not a directory).
    MissingDir(PathBuf),
    /// The README could not be read.
    Readme {
        /// Path of the README.
        path: PathBuf,
        /// The I/O error.
        message: String,
    },
    /// A line of the reference table is invalid (for example a reference that is not a finite
    /// number).
    Reference {
        /// Path of the README.
        path: PathBuf,
        /// 1-based line number in the README.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A problem listed in the table has no `.dat-s` file.
    MissingProblem {
        /// Path of the README.
        path: PathBuf,
        /// 1-based line number in the README.
        line: usize,
        /// The file that is missing.
        file: PathBuf,
    },
    /// The README holds no reference table.
    NoTable(PathBuf),
}

impl fmt::Display for SuiteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SuiteError::MissingDir(dir) => {
                write!(f, "SDPLIB directory {} does not exist or is not a directory", dir.display())
            }
            SuiteError::Readme { path, message } => write!(f, "cannot read {}: {message}", path.display()),
            SuiteError::Reference { path, line, message } => write!(f, "{}:{line}: {message}", path.display()),
            SuiteError::MissingProblem { path, line, file } => {
                write!(f, "{}:{line}: {} is listed but missing", path.display(), file.display())
            }
            SuiteError::NoTable(path) => write!(f, "{}: no reference table found", path.display()),
        }
    }
}

impl std::error::Error for SuiteError {}

/// Absolute floor of the objective tolerance, relative to the size of the terms of `cᵀx`:
/// `ABSOLUTE_FLOOR · max(1, Σ|cᵢxᵢ|)`. It makes a reference of 0 (or one whose digits-based
/// tolerance is below what a solver can resolve) checkable: the solvers stop at a relative gap of
/// about `1e-9`, and `cᵀx` cannot be more accurate than its terms allow.
pub const ABSOLUTE_FLOOR: f64 = 1e-8;

/// What a problem of the suite should end with.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
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
    /// Tolerance of the reference itself: relative `1e-6` where it has at least 7 significant
    /// digits, otherwise half a unit in its last digit; `0` for a reference of 0 or a value that
    /// is not finite (which [`parse_outcome`] never produces). Computed in floating point: finite
    /// for every finite reference and any number of digits. [`check_outcome`] adds the
    /// [`ABSOLUTE_FLOOR`].
    pub fn tolerance(&self) -> f64 {
        match *self {
            Expected::Optimal { value, digits } => {
                if !value.is_finite() || value == 0.0 {
                    0.0
                } else if digits >= 7 {
                    1e-6 * value.abs()
                } else {
                    // |value| ∈ [1e-324, 1.8e308] and digits ≥ 1: the power is at most 10^308.
                    let exponent = value.abs().log10().floor();
                    0.5 * 10f64.powf(exponent + 1.0 - f64::from(digits.max(1)))
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
/// A missing directory, an unreadable README, a reference that is not a finite number and a
/// problem listed without a file are errors naming the directory, the file or the README line.
pub fn suite(dir: &Path) -> Result<Vec<SuiteProblem>, SuiteError> {
    if !dir.is_dir() {
        return Err(SuiteError::MissingDir(dir.to_owned()));
    }
    let readme = dir.join("README.md");
    let text = std::fs::read_to_string(&readme)
        .map_err(|e| SuiteError::Readme { path: readme.clone(), message: e.to_string() })?;
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
        let expected = parse_outcome(cells[3]).map_err(|message| SuiteError::Reference {
            path: readme.clone(),
            line: lineno + 1,
            message: format!("problem {name}: {message}"),
        })?;
        let path = dir.join(format!("{name}.dat-s"));
        if !path.is_file() {
            return Err(SuiteError::MissingProblem { path: readme.clone(), line: lineno + 1, file: path });
        }
        out.push(SuiteProblem { name: name.to_owned(), path, expected });
    }
    if out.is_empty() {
        return Err(SuiteError::NoTable(readme));
    }
    Ok(out)
}

/// A reference outcome: `primal infeasible`, `dual infeasible`, or a finite decimal number
/// (`−` may be U+2212) whose significant digits are counted. `Err` says why the cell is not
/// one: not a number, `NaN`/`inf`, or a literal that overflows or underflows `f64`.
pub fn parse_outcome(cell: &str) -> Result<Expected, String> {
    match cell {
        "primal infeasible" => return Ok(Expected::Infeasible(SolveStatus::PrimalInfeasible)),
        "dual infeasible" => return Ok(Expected::Infeasible(SolveStatus::DualInfeasible)),
        _ => {}
    }
    let s = cell.replace('\u{2212}', "-");
    let unsigned = s.strip_prefix(['-', '+']).unwrap_or(&s);
    let (mantissa, exponent) = match unsigned.split_once(['e', 'E']) {
        Some((m, e)) => (m, Some(e)),
        None => (unsigned, None),
    };
    let exponent_ok = exponent.is_none_or(|e| {
        let digits = e.strip_prefix(['-', '+']).unwrap_or(e);
        !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())
    });
    let mantissa_ok = mantissa.bytes().any(|b| b.is_ascii_digit())
        && mantissa.bytes().all(|b| b.is_ascii_digit() || b == b'.')
        && mantissa.bytes().filter(|&b| b == b'.').count() <= 1;
    if !(mantissa_ok && exponent_ok) {
        return Err(format!("the reference {cell:?} is not a decimal number or an infeasibility label"));
    }
    let value: f64 = s.parse().map_err(|_| format!("the reference {cell:?} is not a number"))?;
    if !value.is_finite() {
        return Err(format!("the reference {cell:?} overflows f64 (references must be finite)"));
    }
    let significant = mantissa.trim_start_matches(['0', '.']);
    let nonzero = significant.bytes().any(|b| matches!(b, b'1'..=b'9'));
    if nonzero && !value.is_normal() {
        return Err(format!("the reference {cell:?} underflows f64 (its value would be {value:e})"));
    }
    let digits = significant.bytes().filter(u8::is_ascii_digit).count();
    let digits = u32::try_from(digits).unwrap_or(u32::MAX).max(1);
    Ok(Expected::Optimal { value, digits })
}

/// `a ≤ b`, false when either is NaN: a check written `if !at_most(err, tol) { fail }` fails on
/// NaN instead of passing.
fn at_most(a: f64, b: f64) -> bool {
    a <= b
}

/// Checks an infeasibility certificate independently of the solver, returning a description
/// of what is wrong, if anything: the backend-independent check of [`lmi::certificate`] (the one
/// the backends apply before reporting an infeasibility), with tolerance `tol`. For
/// [`SolveStatus::PrimalInfeasible`]: `Y ⪰ 0`, `tr(FᵢY) ≈ 0`, `tr(F₀Y) > 0`; for
/// [`SolveStatus::DualInfeasible`]: `Σ xᵢFᵢ ⪰ 0`, `cᵀx < 0` — each measured relative to the norms
/// of the data and of the certificate, so that a rescaling of the problem cannot make a bogus
/// certificate pass.
pub fn check_certificate(problem: &SdpProblem, solution: &SdpSolution, tol: f64) -> Result<(), String> {
    lmi::check_certificate(problem, solution, tol).map(|_| ()).map_err(|e| e.to_string())
}

/// Objective tolerance of an optimal `solution` against `expected`: the reference's own
/// [`Expected::tolerance`], but at least [`ABSOLUTE_FLOOR`]` · max(1, Σ|cᵢxᵢ|)`.
pub fn objective_tolerance(expected: &Expected, problem: &SdpProblem, solution: &SdpSolution) -> f64 {
    let terms: f64 = problem.c().iter().zip(&solution.x).map(|(c, x)| (c * x).abs()).sum();
    let floor = ABSOLUTE_FLOOR * if terms.is_finite() { terms.max(1.0) } else { 1.0 };
    expected.tolerance().max(floor)
}

/// Whether `solution` matches `expected`: an optimal status with a finite objective within
/// [`objective_tolerance`], or infeasibility on the expected side (an `Almost…` status on that
/// side counts) with a certificate that passes [`check_certificate`] at `1e-6`. `Err` says why not.
pub fn check_outcome(expected: &Expected, problem: &SdpProblem, solution: &SdpSolution) -> Result<(), String> {
    match *expected {
        Expected::Optimal { value, .. } => {
            let err = (solution.primal_objective - value).abs();
            let tol = objective_tolerance(expected, problem, solution);
            if !solution.status.is_optimal() {
                Err(format!("status {} (expected an optimum)", solution.status))
            } else if !at_most(err, tol) {
                // Also a NaN objective or reference: the comparison is false.
                Err(format!(
                    "objective {} differs from {value} by {err:.2e} (tolerance {tol:.2e})",
                    solution.primal_objective
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
    KnownDeviation {
        problem: "hinf4",
        backend: Some("clarabel"),
        rel_tol: 1e-5,
        reason: "Clarabel stops (almost solved) 3.3e-6 relative above the reference 274.764, which faer-ipm's strictly \
                 feasible point meets (cᵀx = 274.76393); with OpenBLAS's kernels for some CPUs (seen on an AMD EPYC \
                 with Debian's OpenBLAS 0.3.21, one thread) its answer is 274.76489, outside the reference's six \
                 digits",
    },
];

/// The outcome of one problem for one backend.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
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
        assert_eq!(parse_outcome("1.778463e+01"), Ok(Expected::Optimal { value: 17.78463, digits: 7 }));
        assert_eq!(parse_outcome("\u{2212}8.999996e+00"), Ok(Expected::Optimal { value: -8.999996, digits: 7 }));
        assert_eq!(parse_outcome("5.69e+01"), Ok(Expected::Optimal { value: 56.9, digits: 3 }));
        assert_eq!(parse_outcome("primal infeasible"), Ok(Expected::Infeasible(SolveStatus::PrimalInfeasible)));
        assert_eq!(parse_outcome("dual infeasible"), Ok(Expected::Infeasible(SolveStatus::DualInfeasible)));
        assert!(parse_outcome("nonsense").is_err());
        assert!((Expected::Optimal { value: 56.9, digits: 3 }.tolerance() - 0.05).abs() < 1e-15);
        assert!((Expected::Optimal { value: 2.0326, digits: 5 }.tolerance() - 5e-5).abs() < 1e-15);
        assert!((Expected::Optimal { value: 17.78463, digits: 7 }.tolerance() - 17.78463e-6).abs() < 1e-15);
    }

    /// Regression: references of 1.5e-400, NaN or 1e400 used to make the tolerance
    /// infinite in release builds (every answer passed) and overflow an `i32` subtraction in
    /// debug builds. They are now rejected with a reason.
    #[test]
    fn references_must_be_finite_decimal_numbers() {
        for (cell, reason) in [
            ("1.5e-400", "underflows"),
            ("-2e-320", "underflows"),
            ("1e400", "overflows"),
            ("NaN", "not a decimal number"),
            ("nan", "not a decimal number"),
            ("inf", "not a decimal number"),
            ("-infinity", "not a decimal number"),
            ("1.2.3", "not a decimal number"),
            ("1e", "not a decimal number"),
            ("", "not a decimal number"),
            ("0x10", "not a decimal number"),
        ] {
            let err = parse_outcome(cell).unwrap_err();
            assert!(err.contains(reason) && err.contains(&format!("{cell:?}")), "{cell}: {err}");
        }
        // Zero is a valid reference, however written.
        for cell in ["0", "0.0", "-0.000e+00"] {
            assert!(matches!(parse_outcome(cell), Ok(Expected::Optimal { value: 0.0, .. })), "{cell}");
        }
    }

    /// Regression: the digits-based tolerance is computed without integer overflow and is finite
    /// for every finite reference and digit count (an `i32` subtraction overflowed before).
    #[test]
    fn tolerances_never_overflow() {
        for value in [0.0, -0.0, f64::MIN_POSITIVE, 5e-324, 1.0, -3.3e-7, 1e308, f64::MAX, f64::NAN, f64::INFINITY] {
            for digits in [0, 1, 2, 6, 7, 40, u32::MAX] {
                let t = Expected::Optimal { value, digits }.tolerance();
                assert!(t.is_finite() && t >= 0.0, "{value:e} with {digits} digits: {t}");
            }
        }
        assert_eq!(Expected::Optimal { value: 0.0, digits: 3 }.tolerance(), 0.0);
        assert_eq!(Expected::Optimal { value: f64::NAN, digits: 3 }.tolerance(), 0.0);
        assert!((Expected::Optimal { value: 1e308, digits: 1 }.tolerance() - 0.5e308).abs() < 1e293);
    }

    fn solved(objective: f64, x: f64) -> (SdpProblem, SdpSolution) {
        use lmi::{Block, Entry};
        let p = SdpProblem::new(
            vec![Block::Nonneg(1)],
            vec![1.0],
            vec![Entry { mat: 1, block: 0, row: 0, col: 0, value: 1.0 }],
        )
        .unwrap();
        let mut sol = SdpSolution::new(&p);
        sol.status = SolveStatus::Solved;
        sol.primal_objective = objective;
        sol.x[0] = x;
        (p, sol)
    }

    /// Regression: a correct −2e-13 against a reference of 0 used to be flagged (tolerance 0);
    /// the absolute floor accepts it, and still rejects a real discrepancy and a NaN objective.
    #[test]
    fn tolerance_near_zero_has_an_absolute_floor() {
        let zero = parse_outcome("0").unwrap();
        let (p, sol) = solved(-2e-13, -2e-13);
        assert_eq!(check_outcome(&zero, &p, &sol), Ok(()));
        let (p, sol) = solved(1e-3, 1e-3);
        assert!(check_outcome(&zero, &p, &sol).unwrap_err().contains("differs from 0"));
        // The floor follows the size of the terms of c'x, not the reference.
        let (p, sol) = solved(3e-6, 1e3);
        assert!((objective_tolerance(&zero, &p, &sol) - 1e-5).abs() < 1e-18);
        // NaN objectives never pass, whatever the tolerance.
        let one = parse_outcome("1.0").unwrap();
        let (p, sol) = solved(f64::NAN, 1.0);
        assert!(check_outcome(&one, &p, &sol).is_err());
        let (p, sol) = solved(f64::NAN, f64::NAN);
        assert!(check_outcome(&zero, &p, &sol).is_err());
    }

    /// A scratch directory under the system's temporary directory, removed on drop.
    struct Scratch(PathBuf);

    impl Scratch {
        fn new(tag: &str, readme: &str) -> Self {
            let dir = std::env::temp_dir().join(format!("xtask-sdplib-{tag}-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(dir.join("README.md"), readme).unwrap();
            std::fs::write(dir.join("tiny.dat-s"), "1\n1\n1\n1.0\n1 1 1 1 1.0\n").unwrap();
            Self(dir)
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// Regression: a bad reference in the README is a typed error naming its line.
    #[test]
    fn bad_references_name_the_readme_line() {
        for (tag, cell) in [("nan", "NaN"), ("huge", "1e400"), ("tiny", "1.5e-400")] {
            let readme = format!(
                "# suite\n\n| problem | m | blocks | optimum |\n|---|---:|---|---:|\n| tiny | 1 | -1 | {cell} |\n"
            );
            let dir = Scratch::new(tag, &readme);
            match suite(&dir.0) {
                Err(e @ SuiteError::Reference { line: 5, .. }) => {
                    let msg = e.to_string();
                    assert!(msg.contains("README.md:5") && msg.contains("tiny") && msg.contains(cell), "{msg}");
                }
                other => panic!("{cell}: expected a reference error at line 5, got {other:?}"),
            }
        }
        let dir = Scratch::new("ok", "| problem | m | blocks | optimum |\n|---|---|---|---|\n| tiny | 1 | -1 | 0 |\n");
        let problems = suite(&dir.0).unwrap();
        assert_eq!(problems.len(), 1);
        assert_eq!(problems[0].expected, Expected::Optimal { value: 0.0, digits: 1 });
        let dir = Scratch::new("missing", "| problem | m | blocks | optimum |\n| gone | 1 | -1 | 1.0 |\n");
        let err = suite(&dir.0).unwrap_err();
        assert!(matches!(err, SuiteError::MissingProblem { line: 2, .. }), "{err:?}");
        assert!(err.to_string().contains("gone.dat-s is listed but missing"), "{err}");
    }

    /// Regression: a directory that does not exist used to be reported as "SDPA format error at
    /// line 0" about its README.
    #[test]
    fn a_missing_directory_is_named() {
        let dir = std::env::temp_dir().join("xtask-sdplib-does-not-exist");
        let err = suite(&dir).unwrap_err();
        assert_eq!(err, SuiteError::MissingDir(dir.clone()));
        let msg = err.to_string();
        assert!(msg.contains(&dir.display().to_string()) && msg.contains("does not exist"), "{msg}");
        assert!(!msg.contains("SDPA"), "{msg}");
    }
}
