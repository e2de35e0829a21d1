//! The ellipsoidal filter update as an SDP: LMI (28) and problem (29) of the straddle-carrier
//! set-membership filter, for any linear system (nothing here is vehicle-specific).
//!
//! Given `x_{k+1} = A x_k + B u_k + w_k`, `y_{k+1} = C x_{k+1} + v_{k+1}`, `w ∈ 𝓔(0, Q)`,
//! `v ∈ 𝓔(0, R)` and the current set `𝓔(x̂_k, P_k)` with `P_k = E Eᵀ`, the estimation error of
//! the filter `x̂_{k+1} = G x̂_k + (I − LC) B u_k + L y_{k+1}` (13) is `Π η` with
//! `η = [1, z, w, v]`, `‖z‖ ≤ 1` and (19)
//!
//! ```text
//! Π = [ g,  (I − LC) A E,  (I − LC),  −L ],      g = (I − LC) A x̂_k − G x̂_k  (free)
//! ```
//!
//! (the paper prints `A − A L C`; the product that follows from (15) is `(I − LC) A`). The
//! S-procedure with multipliers `τ₁, τ₂, τ₃ ≥ 0` gives (28) in the equivalent form used here:
//!
//! ```text
//! [ P    Π   ]
//! [ Πᵀ   Θ(τ)] ⪰ 0,   Θ(τ) = diag(1 − τ₁ − τ₂ − τ₃,  τ₁ Iₙ,  τ₂ Q⁻¹,  τ₃ R⁻¹)     (26), (28)
//! ```
//!
//! and (29) minimises `tr P` over `P`, `L`, `g`, `τ`. The block has order `n + 1 + 2n + m`; the
//! decision vector holds `P` (`n(n+1)/2`), `L` (`n·m`), `g` (`n`) and `τ` (3), in that order.
//! The LMI implies `τ ≥ 0` through the diagonal blocks of `Θ`, so no separate cone is added.
//!
//! The structure depends only on `(n, m)`: [`FilterSdp::update`] rewrites the numbers of the
//! same problem, so a backend set up once can solve it at every step.

use nalgebra::{DMatrix, DVector};

use crate::builder::{AffineMatrix, LmiBuilder, Var, VariableMap};
use crate::error::LmiError;
use crate::problem::SdpProblem;

/// The data of one filter step.
#[derive(Debug, Clone, Copy)]
pub struct FilterSdpData<'a> {
    /// State transition `A_p` (`n × n`).
    pub a: &'a DMatrix<f64>,
    /// Output matrix `C` (`m × n`).
    pub c: &'a DMatrix<f64>,
    /// Process-noise shape `Q` (`n × n`, symmetric positive definite).
    pub q: &'a DMatrix<f64>,
    /// Measurement-noise shape `R` (`m × m`, symmetric positive definite).
    pub r: &'a DMatrix<f64>,
    /// Current shape `P_k` (`n × n`, symmetric positive definite).
    pub p: &'a DMatrix<f64>,
    /// Current centre `x̂_k` (`n`).
    pub x_hat: &'a DVector<f64>,
}

/// What a solution of (29) says, read back from the decision vector.
#[derive(Debug, Clone, PartialEq)]
pub struct FilterSdpSolution {
    /// `P_{k+1}` as returned by the solver (not certified: see the estimators crate).
    pub p_next: DMatrix<f64>,
    /// The gain `L_k` (`n × m`).
    pub l: DMatrix<f64>,
    /// The free first column `g` of `Π` (zero at the optimum, since the noise sets are symmetric).
    pub g: DVector<f64>,
    /// `G_k x̂_k = (I − L C) A x̂_k − g`, the part of (13) that the LMI determines.
    pub g_x_hat: DVector<f64>,
    /// The S-procedure multipliers `(τ₁, τ₂, τ₃)`.
    pub tau: [f64; 3],
}

/// LMI (28) with a fixed structure for given dimensions; the numbers change per step.
#[derive(Debug, Clone)]
pub struct FilterSdp {
    n: usize,
    m: usize,
    problem: SdpProblem,
    map: VariableMap,
    vars: FilterVars,
}

#[derive(Debug, Clone, Copy)]
struct FilterVars {
    p: Var,
    l: Var,
    g: Var,
    tau: [Var; 3],
}

fn check_dims(d: &FilterSdpData<'_>) -> Result<(usize, usize), LmiError> {
    let n = d.a.nrows();
    let m = d.c.nrows();
    let dim = |what, expected, found| {
        if expected == found { Ok(()) } else { Err(LmiError::DimensionMismatch { what, expected, found }) }
    };
    if n == 0 || m == 0 {
        return Err(LmiError::InvalidProblem("the system needs at least one state and one output".into()));
    }
    dim("columns of A", n, d.a.ncols())?;
    dim("columns of C", n, d.c.ncols())?;
    dim("rows of Q", n, d.q.nrows())?;
    dim("columns of Q", n, d.q.ncols())?;
    dim("rows of R", m, d.r.nrows())?;
    dim("columns of R", m, d.r.ncols())?;
    dim("rows of P", n, d.p.nrows())?;
    dim("columns of P", n, d.p.ncols())?;
    dim("length of x_hat", n, d.x_hat.len())?;
    for (name, mat) in [("A", d.a), ("C", d.c), ("Q", d.q), ("R", d.r), ("P", d.p)] {
        if mat.iter().any(|v| !v.is_finite()) {
            return Err(LmiError::InvalidProblem(format!("{name} has a non-finite entry")));
        }
    }
    if d.x_hat.iter().any(|v| !v.is_finite()) {
        return Err(LmiError::InvalidProblem("x_hat has a non-finite entry".into()));
    }
    Ok((n, m))
}

/// Cholesky factor of a symmetric positive definite matrix (symmetry within `1e-10` relative).
fn spd_factor(m: &DMatrix<f64>, name: &'static str) -> Result<nalgebra::Cholesky<f64, nalgebra::Dyn>, LmiError> {
    let scale = m.amax().max(f64::MIN_POSITIVE);
    if (m - m.transpose()).amax() > 1e-10 * scale {
        return Err(LmiError::NotPositiveDefinite(name));
    }
    let sym = (m + m.transpose()) * 0.5;
    nalgebra::Cholesky::new(sym).ok_or(LmiError::NotPositiveDefinite(name))
}

/// Builds (28)/(29) with the builder; the same code path is used at setup and at each update,
/// with structural zeros kept so that the structure depends on `(n, m)` only.
fn build(d: &FilterSdpData<'_>) -> Result<(SdpProblem, VariableMap, FilterVars), LmiError> {
    let (n, m) = check_dims(d)?;
    let e = spd_factor(d.p, "P")?.l();
    let q_inv = spd_factor(d.q, "Q")?.inverse();
    let r_inv = spd_factor(d.r, "R")?.inverse();
    let mut b = LmiBuilder::new().keep_structural_zeros(true);
    let p = b.symmetric("P", n)?;
    let l = b.matrix("L", n, m)?; // m outputs
    let g = b.matrix("g", n, 1)?;
    let tau = [b.scalar("tau1")?, b.scalar("tau2")?, b.scalar("tau3")?];
    let pm = b.matrix_expr(p)?;
    let lm = b.matrix_expr(l)?;
    let gm = b.matrix_expr(g)?;
    let t = [b.expr(tau[0])?, b.expr(tau[1])?, b.expr(tau[2])?];

    let ae = d.a * &e;
    // (19): Π = [g, (I − LC) A E, (I − LC), −L]
    let col_z = AffineMatrix::constant(&ae).sub(&lm.mul_right(&(d.c * &ae))?)?;
    let col_w = AffineMatrix::constant(&DMatrix::identity(n, n)).sub(&lm.mul_right(d.c)?)?;
    let col_v = lm.scale(-1.0);
    let pi = AffineMatrix::block(&[&[&gm, &col_z, &col_w, &col_v]])?;
    // (26): Θ(τ) = diag(1 − τ₁ − τ₂ − τ₃, τ₁ I, τ₂ Q⁻¹, τ₃ R⁻¹)
    let one = DMatrix::from_element(1, 1, 1.0);
    let theta0 = AffineMatrix::constant(&one).sub(&AffineMatrix::constant_times(&one, &t[0].add(&t[1]).add(&t[2])))?;
    let theta = AffineMatrix::diag(&[
        &theta0,
        &AffineMatrix::constant_times(&DMatrix::identity(n, n), &t[0]),
        &AffineMatrix::constant_times(&q_inv, &t[1]),
        &AffineMatrix::constant_times(&r_inv, &t[2]),
    ]);
    // (28) as [[P, Π], [Πᵀ, Θ]] ⪰ 0, (29): minimise tr P.
    b.psd(AffineMatrix::block(&[&[&pm, &pi], &[&pi.transpose(), &theta]])?)?;
    b.minimize(pm.trace());
    let (problem, map) = b.build()?;
    Ok((problem, map, FilterVars { p, l, g, tau }))
}

impl FilterSdp {
    /// Builds (28)/(29) for the given data. Errors name a wrong dimension, a non-finite entry or
    /// a `Q`, `R`, `P` that is not symmetric positive definite.
    pub fn new(data: &FilterSdpData<'_>) -> Result<Self, LmiError> {
        let (problem, map, vars) = build(data)?;
        Ok(Self { n: data.a.nrows(), m: data.c.nrows(), problem, map, vars })
    }

    /// Number of states `n`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of outputs `m`.
    pub fn m(&self) -> usize {
        self.m
    }

    /// The SDP in SDPA form.
    pub fn problem(&self) -> &SdpProblem {
        &self.problem
    }

    /// Rewrites the numbers for new data of the same dimensions (the structure is unchanged, so a
    /// backend set up on [`FilterSdp::problem`] can solve the result). On error, unchanged.
    pub fn update(&mut self, data: &FilterSdpData<'_>) -> Result<(), LmiError> {
        if data.a.nrows() != self.n || data.c.nrows() != self.m {
            return Err(LmiError::StructureMismatch(format!(
                "filter SDP built for n = {}, m = {}; got n = {}, m = {}",
                self.n,
                self.m,
                data.a.nrows(),
                data.c.nrows()
            )));
        }
        let (problem, _, _) = build(data)?;
        debug_assert!(problem.same_structure(&self.problem));
        let values: Vec<f64> = problem.entries().iter().map(|e| e.value).collect();
        self.problem.set_values(problem.c(), &values)
    }

    /// Reads `P_{k+1}`, `L`, `g`, `G x̂` and `τ` from a decision vector `x`.
    pub fn read(&self, x: &[f64], data: &FilterSdpData<'_>) -> Result<FilterSdpSolution, LmiError> {
        check_dims(data)?;
        let p_next = self.map.matrix(x, self.vars.p)?;
        let l = self.map.matrix(x, self.vars.l)?;
        let g = DVector::from_column_slice(self.map.matrix(x, self.vars.g)?.as_slice());
        let tau = [
            self.map.scalar(x, self.vars.tau[0])?,
            self.map.scalar(x, self.vars.tau[1])?,
            self.map.scalar(x, self.vars.tau[2])?,
        ];
        let k = DMatrix::identity(self.n, self.n) - &l * data.c;
        let g_x_hat = &k * (data.a * data.x_hat) - &g;
        Ok(FilterSdpSolution { p_next, l, g, g_x_hat, tau })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data_case() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
        let a = DMatrix::from_row_slice(2, 2, &[0.9, 0.1, -0.2, 0.8]);
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let q = DMatrix::identity(2, 2) * 0.1;
        let r = DMatrix::identity(1, 1) * 0.2;
        let p = DMatrix::identity(2, 2);
        let x = DVector::from_vec(vec![1.0, -1.0]);
        (a, c, q, r, p, x)
    }

    #[test]
    fn lmi_at_a_feasible_point_matches_the_schur_form() {
        // For L, τ on the simplex and P = (I−LC) A P Aᵀ (I−LC)ᵀ/τ₁ + (I−LC) Q (I−LC)ᵀ/τ₂ + L R Lᵀ/τ₃
        // (plus a margin), the LMI must be positive semidefinite.
        let (a, c, q, r, p, x) = data_case();
        let d = FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x };
        let sdp = FilterSdp::new(&d).unwrap();
        assert_eq!(sdp.problem().blocks(), &[crate::Block::Psd(2 + 1 + 2 + 2 + 1)]);
        assert_eq!(sdp.problem().num_vars(), 3 + 2 + 2 + 3);
        let l = DMatrix::from_row_slice(2, 1, &[0.5, 0.1]);
        let tau = [0.4, 0.3, 0.3];
        let k = DMatrix::identity(2, 2) - &l * &c;
        let pn = &k * &a * &p * a.transpose() * k.transpose() / tau[0]
            + &k * &q * k.transpose() / tau[1]
            + &l * &r * l.transpose() / tau[2]
            + DMatrix::identity(2, 2) * 1e-6;
        let mut xv = vec![0.0; 10];
        xv[0] = pn[(0, 0)];
        xv[1] = pn[(0, 1)];
        xv[2] = pn[(1, 1)];
        xv[3] = l[(0, 0)];
        xv[4] = l[(1, 0)];
        xv[7..10].copy_from_slice(&tau);
        let s = sdp.problem().slack(&xv).unwrap();
        let min_eig = s[0].clone().symmetric_eigenvalues().min();
        assert!(min_eig > -1e-12, "{min_eig}");
        // Slightly smaller P breaks it.
        xv[0] -= 1e-3;
        let s = sdp.problem().slack(&xv).unwrap();
        assert!(s[0].clone().symmetric_eigenvalues().min() < 0.0);
        let sol = sdp.read(&xv, &d).unwrap();
        assert_eq!(sol.tau, tau);
        assert_eq!(sol.l, l);
        assert!((sol.g_x_hat - &k * &a * &x).norm() < 1e-15);
    }

    #[test]
    fn update_keeps_the_structure_and_errors_are_named() {
        let (a, c, q, r, p, x) = data_case();
        let d = FilterSdpData { a: &a, c: &c, q: &q, r: &r, p: &p, x_hat: &x };
        let mut sdp = FilterSdp::new(&d).unwrap();
        let before = sdp.problem().clone();
        let a2 = DMatrix::zeros(2, 2);
        sdp.update(&FilterSdpData { a: &a2, ..d }).unwrap();
        assert!(sdp.problem().same_structure(&before));
        assert_ne!(sdp.problem(), &before);
        let bad_q = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let snapshot = sdp.problem().clone();
        let err = sdp.update(&FilterSdpData { q: &bad_q, ..d }).unwrap_err();
        assert_eq!(err.to_string(), "Q is not symmetric positive definite");
        assert_eq!(sdp.problem(), &snapshot);
        let c3 = DMatrix::zeros(1, 3);
        let err = FilterSdp::new(&FilterSdpData { c: &c3, ..d }).unwrap_err();
        assert!(err.to_string().contains("columns of C"), "{err}");
        let nan = DMatrix::from_element(2, 2, f64::NAN);
        let err = FilterSdp::new(&FilterSdpData { a: &nan, ..d }).unwrap_err();
        assert!(err.to_string().contains("A has a non-finite entry"), "{err}");
    }
}
