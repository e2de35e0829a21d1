//! Independent checks of infeasibility certificates, on the problem as the caller stated it.
//!
//! A backend that ends [`SolveStatus::PrimalInfeasible`] (or `DualInfeasible`, or an `Almost…`
//! variant) returns a Farkas-type certificate. The backends judge it on the problem they solved —
//! scaled (see "Equilibration" in [`SolverSettings`]) and, for Clarabel, rescaled again
//! internally — with their own normalisation. A rounding accident on badly scaled data can then
//! produce a "certificate" that proves nothing about the caller's problem (a feasible SDP with
//! data of magnitude `1e-12` reported dual infeasible, one with an entry of `1e308` reported
//! primal infeasible). Both backends therefore hand their certificate to [`CertificateChecker`]
//! on the **original** data, and report the infeasibility only when it passes; otherwise the
//! outcome is [`SolveStatus::NumericalTrouble`] and [`SdpSolution::rejected_certificate`] says
//! what was claimed and why it was rejected.
//!
//! # The tests
//!
//! The measures are invariant under any positive rescaling of the certificate, of `c`, of `F₀`
//! and of each `Fᵢ` separately (so under the backends' equilibration as well), and are computed
//! without overflow for any finite data. With `Ŷ = Y/‖Y‖_F` and `F̂ᵢ = Fᵢ/‖Fᵢ‖_F`:
//!
//! * **Primal infeasible** (no `x` makes `Σ xᵢFᵢ − F₀ ⪰ 0`), certificate `Y` in `dual`:
//!   the *margin* `tr(F̂₀Ŷ)` must be at least [`MIN_MARGIN`]; the *residual*
//!   `maxᵢ |tr(F̂ᵢŶ)|` and the *negativity* `max(0, −λ_min(Ŷ))` (per block, eigenvalues of the
//!   dense blocks) must both be at most `tol · margin`. (If `X = A(x) − F₀ ⪰ 0` and `Y ⪰ 0`, then
//!   `0 ≤ ⟨X, Y⟩ = xᵀA*(Y) − tr(F₀Y)`; a small `A*(Y)` against a positive `tr(F₀Y)` leaves no
//!   room for `x`.)
//! * **Dual infeasible** (no `Y ⪰ 0` with `tr(FᵢY) = cᵢ`), certificate ray `x` in `x`: the
//!   margin `−cᵀx / Σ|cᵢxᵢ|` must be at least [`MIN_MARGIN`] and the negativity
//!   `max(0, −λ_min(Σ xᵢFᵢ)) / Σ|xᵢ|‖Fᵢ‖_F` at most `tol · margin`. (For such a `Y`,
//!   `cᵀx = ⟨Σ xᵢFᵢ, Y⟩ ≥ 0` when `Σ xᵢFᵢ ⪰ 0`.)
//!
//! Non-finite certificate entries are rejected. The backends use [`certificate_tolerance`]:
//! `tol_infeas` (times `reduced_tol_factor` for an `Almost…` status) times
//! [`CERTIFICATE_SLACK`], which allows for the different normalisations of the backends' own
//! tests; a genuine certificate passes with orders of magnitude to spare, the bogus ones of the
//! hostile cases have measures of order one.
//!
//! # Allocation
//!
//! [`CertificateChecker::new`] allocates scratch for one structure (the dense blocks once more,
//! and a few vectors of length `m + 1`); [`CertificateChecker::check`] then allocates nothing.
//! The free function [`check_certificate`] does both, for tests and tools.

use std::fmt;

use nalgebra::DMatrix;

use crate::error::saturate_bytes;
use crate::ipm::eig::sym_eig;
use crate::problem::{Block, SdpProblem};
use crate::solver::{SdpSolution, SolveStatus, SolverSettings};

/// The smallest accepted margin (objective side of the certificate, normalised to `[−1, 1]`):
/// well above the rounding error of the inner product, far below the margin of any genuine
/// certificate.
pub const MIN_MARGIN: f64 = 1e-10;

/// Factor between a backend's `tol_infeas` and the tolerance of the independent check (the
/// normalisations differ: see the [module documentation](self)).
pub const CERTIFICATE_SLACK: f64 = 1e3;

/// The tolerance the backends use to check a certificate returned with `status`:
/// `tol_infeas · CERTIFICATE_SLACK`, times `reduced_tol_factor` for an `Almost…` status.
pub fn certificate_tolerance(settings: &SolverSettings, status: SolveStatus) -> f64 {
    let relaxed = matches!(status, SolveStatus::AlmostPrimalInfeasible | SolveStatus::AlmostDualInfeasible);
    settings.tol_infeas * CERTIFICATE_SLACK * if relaxed { settings.reduced_tol_factor } else { 1.0 }
}

/// Which side a certificate proves infeasible.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CertificateKind {
    /// A `Y ⪰ 0` with `tr(FᵢY) = 0`, `tr(F₀Y) > 0`: the primal (in `x`) is infeasible.
    Primal,
    /// A ray `x` with `Σ xᵢFᵢ ⪰ 0`, `cᵀx < 0`: the dual (in `Y`) is infeasible.
    Dual,
}

impl CertificateKind {
    /// The kind of certificate an infeasibility status claims, `None` for other statuses.
    pub fn of(status: SolveStatus) -> Option<Self> {
        match status {
            SolveStatus::PrimalInfeasible | SolveStatus::AlmostPrimalInfeasible => Some(Self::Primal),
            SolveStatus::DualInfeasible | SolveStatus::AlmostDualInfeasible => Some(Self::Dual),
            _ => None,
        }
    }
}

/// The scale-free measures of a certificate (see the [module documentation](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CertificateMeasures {
    /// Which side the certificate is about.
    pub kind: CertificateKind,
    /// The normalised objective side: `tr(F̂₀Ŷ)`, resp. `−cᵀx / Σ|cᵢxᵢ|`; positive for a
    /// certificate.
    pub margin: f64,
    /// The normalised equality residual `maxᵢ |tr(F̂ᵢŶ)|` (0 for a dual certificate, whose
    /// equalities hold by construction).
    pub residual: f64,
    /// How far the certificate's matrix is from PSD, normalised.
    pub negativity: f64,
    /// The block with the most negative eigenvalue (0 when none is negative).
    pub worst_block: usize,
    /// The variable with the largest residual (1-based; 0 for a dual certificate).
    pub worst_variable: usize,
}

/// Why a certificate was rejected.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum CertificateFailure {
    /// The status claims no infeasibility.
    NotAnInfeasibilityStatus(SolveStatus),
    /// The certificate has a NaN or infinite entry.
    NonFinite,
    /// The certificate is zero.
    Zero,
    /// The objective side has the wrong sign or too small a margin (below [`MIN_MARGIN`]).
    Margin(CertificateMeasures),
    /// The equalities `tr(FᵢY) = 0` are violated by more than `tol · margin`.
    Residual {
        /// The measures.
        measures: CertificateMeasures,
        /// The tolerance used.
        tol: f64,
    },
    /// The certificate's matrix has an eigenvalue below `−tol · margin` (normalised).
    NotPsd {
        /// The measures.
        measures: CertificateMeasures,
        /// The tolerance used.
        tol: f64,
    },
    /// The problem or the solution does not have the checker's sizes.
    SizeMismatch,
    /// The eigenvalues of this block could not be computed.
    Eigenvalues {
        /// The block.
        block: usize,
    },
}

impl fmt::Display for CertificateFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotAnInfeasibilityStatus(s) => write!(f, "status {s} has no infeasibility certificate"),
            Self::NonFinite => f.write_str("the certificate has non-finite entries"),
            Self::Zero => f.write_str("the certificate is zero"),
            Self::Margin(m) => match m.kind {
                CertificateKind::Primal => {
                    write!(f, "tr(F0 Y) / (|F0| |Y|) = {:.3e}: not positive by the margin {MIN_MARGIN:e}", m.margin)
                }
                CertificateKind::Dual => {
                    write!(f, "-c'x / sum|c_i x_i| = {:.3e}: not positive by the margin {MIN_MARGIN:e}", m.margin)
                }
            },
            Self::Residual { measures: m, tol } => write!(
                f,
                "|tr(F{} Y)| / (|F{}| |Y|) = {:.3e} exceeds {tol:.1e} times the margin {:.3e}",
                m.worst_variable, m.worst_variable, m.residual, m.margin
            ),
            Self::NotPsd { measures: m, tol } => match m.kind {
                CertificateKind::Primal => write!(
                    f,
                    "Y has eigenvalue -{:.3e} |Y| in block {}, beyond {tol:.1e} times the margin {:.3e}",
                    m.negativity, m.worst_block, m.margin
                ),
                CertificateKind::Dual => write!(
                    f,
                    "sum x_i F_i has eigenvalue -{:.3e} sum|x_i||F_i| in block {}, beyond {tol:.1e} times the \
                     margin {:.3e}",
                    m.negativity, m.worst_block, m.margin
                ),
            },
            Self::SizeMismatch => f.write_str("the problem or the solution does not have the checker's sizes"),
            Self::Eigenvalues { block } => write!(f, "the eigenvalues of block {block} could not be computed"),
        }
    }
}

impl std::error::Error for CertificateFailure {}

/// An infeasibility a backend claimed and the independent check rejected; the status became
/// [`SolveStatus::NumericalTrouble`] (see [`SdpSolution::rejected_certificate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RejectedCertificate {
    /// The status the backend reported.
    pub claimed: SolveStatus,
    /// Why the certificate was rejected.
    pub reason: CertificateFailure,
}

impl fmt::Display for RejectedCertificate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} claimed, certificate rejected: {}", self.claimed, self.reason)
    }
}

/// Scratch for checking certificates of one structure without allocating (see the
/// [module documentation](self)).
#[derive(Debug, Clone)]
pub struct CertificateChecker {
    /// Start of each block in `ray` (dense `n × n` for PSD blocks, `n` for nonnegative ones).
    offsets: Vec<usize>,
    /// `Σ xᵢFᵢ`, scaled, block by block.
    ray: Vec<f64>,
    /// A copy of one dense block for the eigenvalues.
    mat: Vec<f64>,
    d: Vec<f64>,
    e: Vec<f64>,
    /// Per matrix `F₀ … F_m`: largest magnitude, Frobenius norm of the matrix divided by it,
    /// and the traces.
    fmax: Vec<f64>,
    fnorm: Vec<f64>,
    t: Vec<f64>,
    num_vars: usize,
    blocks: Vec<Block>,
}

impl CertificateChecker {
    /// Scratch sized for `problem`'s structure.
    pub fn new(problem: &SdpProblem) -> Self {
        let mut offsets = Vec::with_capacity(problem.blocks().len() + 1);
        let mut len = 0;
        let mut nmax = 0;
        for blk in problem.blocks() {
            offsets.push(len);
            len += match *blk {
                Block::Psd(n) => n * n,
                Block::Nonneg(n) => n,
            };
            nmax = nmax.max(blk.size());
        }
        offsets.push(len);
        let m1 = problem.num_vars() + 1;
        Self {
            offsets,
            ray: vec![0.0; len],
            mat: vec![0.0; nmax * nmax],
            d: vec![0.0; nmax],
            e: vec![0.0; nmax],
            fmax: vec![0.0; m1],
            fnorm: vec![0.0; m1],
            t: vec![0.0; m1],
            num_vars: problem.num_vars(),
            blocks: problem.blocks().to_vec(),
        }
    }

    /// Bytes [`CertificateChecker::new`] allocates for `problem` (saturating).
    pub fn required_bytes(problem: &SdpProblem) -> u64 {
        let mut len: u128 = 0;
        let mut nmax: u128 = 0;
        for blk in problem.blocks() {
            let n = blk.size() as u128;
            len += if matches!(blk, Block::Psd(_)) { n * n } else { n };
            nmax = nmax.max(n);
        }
        let m1 = problem.num_vars() as u128 + 1;
        saturate_bytes(8 * (len + nmax * nmax + 2 * nmax + 3 * m1) + 16 * problem.blocks().len() as u128)
    }

    /// Whether this scratch fits `problem`'s sizes.
    pub fn fits(&self, problem: &SdpProblem) -> bool {
        self.num_vars == problem.num_vars() && self.blocks == problem.blocks()
    }

    /// Checks the certificate `solution` holds for the infeasibility its status claims, on
    /// `problem` as stated (unscaled), with tolerance `tol`; `Ok` gives the measures. A problem
    /// or solution of other sizes than the checker's is [`CertificateFailure::SizeMismatch`].
    /// Does not allocate.
    pub fn check(
        &mut self,
        problem: &SdpProblem,
        solution: &SdpSolution,
        tol: f64,
    ) -> Result<CertificateMeasures, CertificateFailure> {
        let Some(kind) = CertificateKind::of(solution.status) else {
            return Err(CertificateFailure::NotAnInfeasibilityStatus(solution.status));
        };
        if !self.fits(problem) || !solution.fits(problem) {
            return Err(CertificateFailure::SizeMismatch);
        }
        self.matrix_norms(problem);
        match kind {
            CertificateKind::Primal => self.check_primal(problem, &solution.dual, tol),
            CertificateKind::Dual => self.check_dual(problem, &solution.x, tol),
        }
    }

    /// `fmax[i] = max |entries of Fᵢ|`, `fnorm[i] = ‖Fᵢ / fmax[i]‖_F` (0 for a zero matrix).
    fn matrix_norms(&mut self, problem: &SdpProblem) {
        self.fmax.fill(0.0);
        self.fnorm.fill(0.0);
        for e in problem.entries() {
            self.fmax[e.mat] = self.fmax[e.mat].max(e.value.abs());
        }
        for e in problem.entries() {
            let s = self.fmax[e.mat];
            if s > 0.0 {
                let v = e.value / s;
                self.fnorm[e.mat] += if e.row == e.col { v * v } else { 2.0 * v * v };
            }
        }
        self.fnorm.iter_mut().for_each(|v| *v = v.sqrt());
    }

    fn check_primal(
        &mut self,
        problem: &SdpProblem,
        y: &[DMatrix<f64>],
        tol: f64,
    ) -> Result<CertificateMeasures, CertificateFailure> {
        let mut ymax = 0.0f64;
        for v in y.iter().flat_map(|b| b.iter()) {
            if !v.is_finite() {
                return Err(CertificateFailure::NonFinite);
            }
            ymax = ymax.max(v.abs());
        }
        if ymax == 0.0 {
            return Err(CertificateFailure::Zero);
        }
        // Ŷ = Y / ymax, then normalised by ‖Ŷ‖_F below. Off-diagonal entries of the stored
        // dense blocks are averaged (a backend may return a slightly asymmetric Y).
        let mut ynorm2 = 0.0;
        for (b, blk) in self.blocks.iter().enumerate() {
            let yb = &y[b];
            match *blk {
                Block::Psd(n) => {
                    for j in 0..n {
                        for i in 0..n {
                            let v = yb[(i, j)] / ymax;
                            ynorm2 += v * v;
                        }
                    }
                }
                Block::Nonneg(n) => {
                    for i in 0..n {
                        let v = yb[(i, i)] / ymax;
                        ynorm2 += v * v;
                    }
                }
            }
        }
        let ynorm = ynorm2.sqrt();
        self.t.fill(0.0);
        for e in problem.entries() {
            let s = self.fmax[e.mat];
            if s == 0.0 {
                continue;
            }
            let yb = &y[e.block];
            let v = e.value / s;
            self.t[e.mat] += if e.row == e.col {
                v * (yb[(e.row, e.row)] / ymax)
            } else {
                v * (yb[(e.row, e.col)] / ymax + yb[(e.col, e.row)] / ymax)
            };
        }
        let margin = if self.fnorm[0] > 0.0 { self.t[0] / (self.fnorm[0] * ynorm) } else { 0.0 };
        let mut residual = 0.0f64;
        let mut worst_variable = 0;
        for i in 1..=self.num_vars {
            if self.fnorm[i] > 0.0 {
                let r = (self.t[i] / (self.fnorm[i] * ynorm)).abs();
                if r > residual {
                    residual = r;
                    worst_variable = i;
                }
            }
        }
        let mut negativity = 0.0f64;
        let mut worst_block = 0;
        for (b, blk) in self.blocks.iter().enumerate() {
            let yb = &y[b];
            let min = match *blk {
                Block::Psd(n) => {
                    let a = &mut self.mat[..n * n];
                    for j in 0..n {
                        for i in j..n {
                            a[i + j * n] = 0.5 * (yb[(i, j)] / ymax + yb[(j, i)] / ymax) / ynorm;
                        }
                    }
                    if !sym_eig(a, n, &mut self.d[..n], &mut self.e[..n], false) {
                        return Err(CertificateFailure::Eigenvalues { block: b });
                    }
                    self.d[..n].iter().copied().fold(f64::INFINITY, f64::min)
                }
                Block::Nonneg(n) => (0..n).map(|i| yb[(i, i)] / ymax / ynorm).fold(f64::INFINITY, f64::min),
            };
            if -min > negativity {
                negativity = -min;
                worst_block = b;
            }
        }
        let measures = CertificateMeasures {
            kind: CertificateKind::Primal,
            margin,
            residual,
            negativity,
            worst_block,
            worst_variable,
        };
        judge(measures, tol)
    }

    fn check_dual(
        &mut self,
        problem: &SdpProblem,
        x: &[f64],
        tol: f64,
    ) -> Result<CertificateMeasures, CertificateFailure> {
        let mut xmax = 0.0f64;
        for v in x {
            if !v.is_finite() {
                return Err(CertificateFailure::NonFinite);
            }
            xmax = xmax.max(v.abs());
        }
        if xmax == 0.0 {
            return Err(CertificateFailure::Zero);
        }
        // x̂ = x / xmax; the objective side with c / cmax.
        let cmax = problem.c().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let (mut cx, mut cabs) = (0.0, 0.0);
        if cmax > 0.0 {
            for (c, xi) in problem.c().iter().zip(x) {
                let v = (c / cmax) * (xi / xmax);
                cx += v;
                cabs += v.abs();
            }
        }
        let margin = if cabs > 0.0 { -cx / cabs } else { 0.0 };
        // w = max |x̂ᵢ| fmax[i] (finite: |x̂ᵢ| ≤ 1), the ray scaled by 1/w, and its natural size
        // Σ |x̂ᵢ| ‖Fᵢ‖_F / w.
        let mut w = 0.0f64;
        for (i, xi) in x.iter().enumerate() {
            w = w.max((xi / xmax).abs() * self.fmax[i + 1]);
        }
        let mut size = 0.0;
        if w > 0.0 {
            for (i, xi) in x.iter().enumerate() {
                size += ((xi / xmax).abs() * self.fmax[i + 1] / w) * self.fnorm[i + 1];
            }
        }
        let mut negativity = 0.0f64;
        let mut worst_block = 0;
        if size > 0.0 {
            self.ray.fill(0.0);
            for e in problem.entries() {
                if e.mat == 0 || self.fmax[e.mat] == 0.0 {
                    continue;
                }
                let coef = (x[e.mat - 1] / xmax) * self.fmax[e.mat] / w / size;
                let v = (e.value / self.fmax[e.mat]) * coef;
                let off = self.offsets[e.block];
                match self.blocks[e.block] {
                    Block::Psd(n) => {
                        // Lower triangle, column-major.
                        self.ray[off + e.col + e.row * n] += v;
                    }
                    Block::Nonneg(_) => self.ray[off + e.row] += v,
                }
            }
            for (b, blk) in self.blocks.iter().enumerate() {
                let off = self.offsets[b];
                let min = match *blk {
                    Block::Psd(n) => {
                        let a = &mut self.mat[..n * n];
                        a.copy_from_slice(&self.ray[off..off + n * n]);
                        if !sym_eig(a, n, &mut self.d[..n], &mut self.e[..n], false) {
                            return Err(CertificateFailure::Eigenvalues { block: b });
                        }
                        self.d[..n].iter().copied().fold(f64::INFINITY, f64::min)
                    }
                    Block::Nonneg(n) => self.ray[off..off + n].iter().copied().fold(f64::INFINITY, f64::min),
                };
                if -min > negativity {
                    negativity = -min;
                    worst_block = b;
                }
            }
        }
        let measures = CertificateMeasures {
            kind: CertificateKind::Dual,
            margin,
            residual: 0.0,
            negativity,
            worst_block,
            worst_variable: 0,
        };
        judge(measures, tol)
    }
}

/// The acceptance rule on the measures.
fn judge(m: CertificateMeasures, tol: f64) -> Result<CertificateMeasures, CertificateFailure> {
    // `at_least(a, b)` is false when either is NaN, so that a NaN measure fails.
    let at_least = |a: f64, b: f64| a.partial_cmp(&b).is_some_and(|o| o.is_ge());
    if !at_least(m.margin, MIN_MARGIN) {
        return Err(CertificateFailure::Margin(m));
    }
    if !at_least(tol * m.margin, m.residual) {
        return Err(CertificateFailure::Residual { measures: m, tol });
    }
    if !at_least(tol * m.margin, m.negativity) {
        return Err(CertificateFailure::NotPsd { measures: m, tol });
    }
    Ok(m)
}

/// Checks the certificate in `solution` against `problem` (unscaled) with tolerance `tol`
/// ([`CertificateChecker::check`] with fresh scratch; allocates).
pub fn check_certificate(
    problem: &SdpProblem,
    solution: &SdpSolution,
    tol: f64,
) -> Result<CertificateMeasures, CertificateFailure> {
    CertificateChecker::new(problem).check(problem, solution, tol)
}

/// What the backends do with a finished solve: an infeasibility status whose certificate fails
/// the check on `problem` becomes [`SolveStatus::NumericalTrouble`], with the claim and the
/// reason in [`SdpSolution::rejected_certificate`] and the objectives NaN (the rejected
/// certificate stays in `x` / `dual`). Other statuses are left alone.
pub(crate) fn vet(
    checker: &mut CertificateChecker,
    problem: &SdpProblem,
    settings: &SolverSettings,
    sol: &mut SdpSolution,
) {
    if CertificateKind::of(sol.status).is_none() {
        return;
    }
    let tol = certificate_tolerance(settings, sol.status);
    if let Err(reason) = checker.check(problem, sol, tol) {
        if settings.verbose {
            eprintln!("lmi: {} claimed, certificate rejected: {reason}", sol.status);
        }
        sol.rejected_certificate = Some(RejectedCertificate { claimed: sol.status, reason });
        sol.status = SolveStatus::NumericalTrouble;
        sol.primal_objective = f64::NAN;
        sol.dual_objective = f64::NAN;
    }
}
