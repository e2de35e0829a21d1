//! Outer ellipsoidal bounds of the intersection of an ellipsoid with a measurement set.
//!
//! # The family (Schweppe; Fogel & Huang)
//!
//! Let `q₁(x) = (x − c)ᵀ P⁻¹ (x − c)` (the prior `𝓔(c, P)`) and
//! `q₂(x) = (y − C x)ᵀ R⁻¹ (y − C x)` (the measurement set `{x : q₂(x) ≤ 1}`, `C` of size
//! `m × n`, `R` an `m × m` SPD matrix). For `λ ∈ [0, 1]` the set
//! `S_λ = {x : (1 − λ) q₁(x) + λ q₂(x) ≤ 1}` contains the intersection, since on it both
//! terms are at most `1 − λ` and `λ`.
//!
//! Completing the square, `(1 − λ) q₁ + λ q₂ = (x − ĉ)ᵀ X (x − ĉ) + δ` with
//!
//! * `X = (1 − λ) P⁻¹ + λ Cᵀ R⁻¹ C`,
//! * `ĉ = X⁻¹ ((1 − λ) P⁻¹ c + λ Cᵀ R⁻¹ y) = c + λ X⁻¹ Cᵀ R⁻¹ r`, with the innovation
//!   `r = y − C c`,
//! * `δ = min_x [(1 − λ) q₁ + λ q₂] ≥ 0`; for `0 < λ < 1`, `δ = rᵀ (C P Cᵀ/(1 − λ) + R/λ)⁻¹ r`.
//!
//! In gain (covariance) form, for `0 < λ < 1`: `K = P Cᵀ (C P Cᵀ + (1 − λ)/λ · R)⁻¹`,
//! `ĉ = c + K r` and `X⁻¹ = (I − K C) P / (1 − λ)`.
//!
//! Hence `S_λ = 𝓔(ĉ, (1 − δ) X⁻¹)` when `δ < 1`, `S_λ = ∅` (so the intersection is empty)
//! when `δ > 1`, and `S_λ` is at most the single point `ĉ` when `δ = 1`
//! ([`EllipsoidError::DegenerateIntersection`]). `λ = 0` returns the prior. `λ = 1` needs
//! `Cᵀ R⁻¹ C ≻ 0` (`C` of full column rank), otherwise `S_1` is an unbounded cylinder
//! ([`EllipsoidError::UnboundedIntersection`]).
//!
//! # Computation
//!
//! Everything is done in the prior's whitened coordinates `x = c + L u` (`P = L Lᵀ`,
//! `R = L_R L_Rᵀ`): with `W = L_R⁻¹ C L` and `z = L_R⁻¹ r`,
//! `X_u = (1 − λ) I + λ Wᵀ W = G Gᵀ`, `û = λ X_u⁻¹ Wᵀ z`,
//! `δ = (1 − λ)‖û‖² + λ ‖z − W û‖²` (a sum of non-negative terms, no cancellation),
//! `ĉ = c + L û` and `(1 − δ) X⁻¹ = (1 − δ) F Fᵀ` with `F = L G⁻ᵀ`. No inverse of `P` or `R`
//! is formed; `X_u` has its eigenvalues in `[1 − λ, 1 − λ + λ σ_max(W)²]`, so it is well
//! conditioned unless `λ` is close to 1, and the result is a Gram matrix (symmetric positive
//! semidefinite by construction).
//!
//! # Emptiness
//!
//! `δ(λ)` is concave (a pointwise minimum of affine functions of `λ`) and, by the minimax
//! theorem, `max_λ δ(λ) = min_x max(q₁(x), q₂(x))`: the intersection is empty exactly when
//! some `λ` gives `δ > 1`. [`Ellipsoid::intersect_measurement_min_trace`] uses this to report
//! emptiness.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

use crate::error::{EllipsoidError, Result};
use crate::linalg::{
    back_sub_transpose, check_len, check_matrix_finite, check_vector_finite, forward_sub, forward_sub_mat, symmetrize,
    validate_spd,
};
use crate::{Ellipsoid, PD_RELATIVE_TOLERANCE, RANK_RELATIVE_TOLERANCE};

/// Number of grid intervals of the coarse scan in
/// [`Ellipsoid::intersect_measurement_min_trace`].
const LAMBDA_GRID: usize = 50;
/// Final bracket width of the golden-section searches on `λ`.
const LAMBDA_TOL: f64 = 1e-10;

/// The measurement set `{x : (y − C x)ᵀ R⁻¹ (y − C x) ≤ 1}` (`C` is `m × n`, `R` is `m × m`
/// symmetric positive definite): the states compatible with `y = C x + v`, `vᵀ R⁻¹ v ≤ 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasurementSet {
    output: DMatrix<f64>,
    y: DVector<f64>,
    noise: DMatrix<f64>,
    noise_chol: DMatrix<f64>,
}

impl MeasurementSet {
    /// Builds the set from the output matrix `C` (`m × n`), the measurement `y` (length `m`)
    /// and the noise shape `R` (`m × m`, validated like [`Ellipsoid::new`]'s `P`).
    pub fn new(output: DMatrix<f64>, y: DVector<f64>, noise: DMatrix<f64>) -> Result<Self> {
        let m = y.len();
        if m == 0 {
            return Err(EllipsoidError::Empty { what: "measurement y" });
        }
        if output.ncols() == 0 {
            return Err(EllipsoidError::Empty { what: "measurement matrix C (columns)" });
        }
        if output.nrows() != m {
            return Err(EllipsoidError::DimensionMismatch {
                what: "measurement matrix C (rows)",
                expected: m,
                found: output.nrows(),
            });
        }
        check_vector_finite(&y, "measurement y")?;
        check_matrix_finite(&output, "measurement matrix C")?;
        let (noise, noise_chol) = validate_spd(&noise, m, "noise matrix R")?;
        Ok(Self { output, y, noise, noise_chol })
    }

    /// The ellipsoid `𝓔(c, P)` as a measurement set (`C = I`, `y = c`, `R = P`), so that
    /// ellipsoid–ellipsoid intersections use the same code.
    pub fn from_ellipsoid(e: &Ellipsoid) -> Self {
        Self {
            output: DMatrix::identity(e.dim(), e.dim()),
            y: e.center().clone(),
            noise: e.shape().clone(),
            noise_chol: e.cholesky_factor().clone(),
        }
    }

    /// Output matrix `C` (`m × n`).
    pub fn output_matrix(&self) -> &DMatrix<f64> {
        &self.output
    }

    /// Measurement `y`.
    pub fn measurement(&self) -> &DVector<f64> {
        &self.y
    }

    /// Noise shape matrix `R` (symmetrised).
    pub fn noise_shape(&self) -> &DMatrix<f64> {
        &self.noise
    }

    /// State dimension `n` (columns of `C`).
    pub fn state_dim(&self) -> usize {
        self.output.ncols()
    }

    /// Measurement dimension `m`.
    pub fn measurement_dim(&self) -> usize {
        self.y.len()
    }

    /// `(y − C x)ᵀ R⁻¹ (y − C x)`, through the Cholesky factor of `R`.
    pub fn normalized_distance(&self, x: &DVector<f64>) -> Result<f64> {
        check_len(x, self.state_dim(), "point x")?;
        check_vector_finite(x, "point x")?;
        Ok(forward_sub(&self.noise_chol, &(&self.y - &self.output * x)).norm_squared())
    }

    /// Whether `x` is in the set, with [`crate::CONTAINMENT_TOLERANCE`].
    pub fn contains(&self, x: &DVector<f64>) -> Result<bool> {
        Ok(self.normalized_distance(x)? <= 1.0 + crate::CONTAINMENT_TOLERANCE)
    }
}

/// Outcome of an intersection bound.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum IntersectionBound {
    /// The intersection is contained in this ellipsoid.
    Bounded(Ellipsoid),
    /// The parameterised set is empty (`δ > 1`), so the intersection is empty (up to
    /// rounding in `δ`).
    Empty {
        /// The minimum `δ` of the combined quadratic form (greater than 1).
        delta: f64,
    },
}

impl IntersectionBound {
    /// The bounding ellipsoid, if any.
    pub fn ellipsoid(&self) -> Option<&Ellipsoid> {
        match self {
            Self::Bounded(e) => Some(e),
            Self::Empty { .. } => None,
        }
    }

    /// Consumes the outcome, returning the bounding ellipsoid, if any.
    pub fn into_ellipsoid(self) -> Option<Ellipsoid> {
        match self {
            Self::Bounded(e) => Some(e),
            Self::Empty { .. } => None,
        }
    }

    /// Whether the intersection was found empty.
    pub fn is_empty(&self) -> bool {
        matches!(self, Self::Empty { .. })
    }
}

/// The prior in whitened coordinates (see the module documentation).
struct Whitened<'a> {
    prior: &'a Ellipsoid,
    w: DMatrix<f64>,
    z: DVector<f64>,
    gram: DMatrix<f64>,
    g: DVector<f64>,
    rows: usize,
    cols: usize,
}

impl<'a> Whitened<'a> {
    fn new(prior: &'a Ellipsoid, meas: &MeasurementSet) -> Result<Self> {
        if meas.state_dim() != prior.dim() {
            return Err(EllipsoidError::DimensionMismatch {
                what: "measurement matrix C (columns)",
                expected: prior.dim(),
                found: meas.state_dim(),
            });
        }
        let r = &meas.y - &meas.output * prior.center();
        let z = forward_sub(&meas.noise_chol, &r);
        let w = forward_sub_mat(&meas.noise_chol, &(&meas.output * prior.cholesky_factor()));
        let gram = symmetrize(&(w.transpose() * &w));
        let g = w.transpose() * &z;
        check_vector_finite(&z, "whitened innovation R^(-1/2)(y − C c)")?;
        check_matrix_finite(&w, "whitened measurement matrix R^(-1/2) C L")?;
        Ok(Self { prior, w, z, gram, g, rows: meas.output.nrows(), cols: meas.output.ncols() })
    }

    /// Cholesky factor of `X_u = (1 − λ) I + λ Wᵀ W`.
    fn factor(&self, lambda: f64) -> Result<DMatrix<f64>> {
        let n = self.gram.nrows();
        let xu = DMatrix::<f64>::identity(n, n) * (1.0 - lambda) + &self.gram * lambda;
        // At λ = 1, X_u = Wᵀ W is singular exactly when C is rank-deficient; the workspace's 4 ε
        // would accept a numerically rank-deficient Gram matrix whose rounding errors then
        // dominate the bound, so a rank decision there needs the coarser RANK_RELATIVE_TOLERANCE.
        let rel_tol = if lambda >= 1.0 { RANK_RELATIVE_TOLERANCE } else { PD_RELATIVE_TOLERANCE };
        dense_kernels::cholesky_checked(&xu, rel_tol).map_err(|f| EllipsoidError::UnboundedIntersection {
            lambda,
            rows: self.rows,
            cols: self.cols,
            pivot: f.pivot,
            value: f.value,
        })
    }

    /// The bound `S_λ` for `λ ∈ [0, 1]` (validated by the caller).
    fn evaluate(&self, lambda: f64) -> Result<IntersectionBound> {
        if lambda == 0.0 {
            return Ok(IntersectionBound::Bounded(self.prior.clone()));
        }
        let gf = self.factor(lambda)?;
        let u = back_sub_transpose(&gf, &forward_sub(&gf, &self.g)) * lambda;
        let res = &self.z - &self.w * &u;
        let delta = (1.0 - lambda) * u.norm_squared() + lambda * res.norm_squared();
        if delta > 1.0 {
            return Ok(IntersectionBound::Empty { delta });
        }
        let factor = 1.0 - delta;
        if factor.is_nan() || factor <= 0.0 {
            return Err(EllipsoidError::DegenerateIntersection { lambda, delta });
        }
        let l = self.prior.cholesky_factor();
        // Fᵀ = G⁻¹ Lᵀ, shape = (1 − δ) F Fᵀ = (1 − δ) (Fᵀ)ᵀ Fᵀ.
        let ft = forward_sub_mat(&gf, &l.transpose());
        let shape = ft.transpose() * &ft * factor;
        let center = self.prior.center() + l * &u;
        Ellipsoid::from_computed(center, &shape, "intersection centre ĉ", |pivot, value| {
            EllipsoidError::DegenerateResult { operation: "intersection bound", pivot, value }
        })
        .map(IntersectionBound::Bounded)
    }
}

/// Closed-form scalar functions `δ(λ)` and `tr((1 − δ) X⁻¹)` from the eigendecomposition
/// `Wᵀ W = V diag(s) Vᵀ`: with `μ_i = 1 − λ + λ s_i`, `g' = Vᵀ Wᵀ z` and `a_i = ‖L v_i‖²`,
/// `δ = λ‖z‖² − λ² Σ g'_i²/μ_i` and `tr = (1 − δ) Σ a_i/μ_i`.
struct Scalar {
    s: Vec<f64>,
    gp2: Vec<f64>,
    a: Vec<f64>,
    zz: f64,
    lambda_one_bounded: bool,
}

impl Scalar {
    fn new(wh: &Whitened<'_>) -> Result<Self> {
        let n = wh.gram.nrows();
        let eig = SymmetricEigen::try_new(wh.gram.clone(), f64::EPSILON, 1000 * n.max(1))
            .ok_or(EllipsoidError::EigenDecomposition { what: "Wᵀ W (whitened Cᵀ R⁻¹ C)" })?;
        let gp = eig.eigenvectors.transpose() * &wh.g;
        let lv = wh.prior.cholesky_factor() * &eig.eigenvectors;
        Ok(Self {
            s: eig.eigenvalues.iter().map(|s| s.max(0.0)).collect(),
            gp2: gp.iter().map(|v| v * v).collect(),
            a: (0..n).map(|i| lv.column(i).norm_squared()).collect(),
            zz: wh.z.norm_squared(),
            lambda_one_bounded: matches!(wh.evaluate(1.0), Ok(IntersectionBound::Bounded(_))),
        })
    }

    fn delta(&self, lambda: f64) -> f64 {
        let mut acc = 0.0;
        for (s, gp2) in self.s.iter().zip(&self.gp2) {
            let mu = 1.0 - lambda + lambda * s;
            if mu > 0.0 {
                acc += gp2 / mu;
            }
        }
        lambda * self.zz - lambda * lambda * acc
    }

    /// Trace of the bound; `+∞` where unbounded, `−∞` where empty.
    fn trace(&self, lambda: f64) -> f64 {
        if lambda >= 1.0 && !self.lambda_one_bounded {
            return f64::INFINITY;
        }
        let delta = self.delta(lambda);
        if delta > 1.0 {
            return f64::NEG_INFINITY;
        }
        let mut acc = 0.0;
        for (s, a) in self.s.iter().zip(&self.a) {
            let mu = 1.0 - lambda + lambda * s;
            if mu <= 0.0 {
                return f64::INFINITY;
            }
            acc += a / mu;
        }
        (1.0 - delta) * acc
    }
}

/// Golden-section minimisation of `f` on `[a, b]` to bracket width `tol`; updates `best`
/// (argument, value) with every evaluation, so the result is never worse than what `best`
/// held on entry.
fn golden_min(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, tol: f64, best: &mut (f64, f64)) {
    const INV_PHI: f64 = 0.618_033_988_749_894_8;
    let (mut a, mut b) = (a, b);
    let mut eval = |x: f64, best: &mut (f64, f64)| {
        let v = f(x);
        if v < best.1 {
            *best = (x, v);
        }
        v
    };
    let mut x1 = b - INV_PHI * (b - a);
    let mut x2 = a + INV_PHI * (b - a);
    let mut f1 = eval(x1, best);
    let mut f2 = eval(x2, best);
    let mut iter = 0;
    while b - a > tol && iter < 200 {
        iter += 1;
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - INV_PHI * (b - a);
            f1 = eval(x1, best);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + INV_PHI * (b - a);
            f2 = eval(x2, best);
        }
    }
}

fn check_lambda(lambda: f64) -> Result<()> {
    if (0.0..=1.0).contains(&lambda) {
        Ok(())
    } else {
        Err(EllipsoidError::InvalidParameter { name: "λ", value: lambda, expected: "a number in [0, 1]" })
    }
}

impl Ellipsoid {
    /// The outer bound `S_λ` of `self ∩ meas` for a given `λ ∈ [0, 1]` (see the
    /// [module documentation](crate::intersection) for the formulas).
    ///
    /// Returns [`IntersectionBound::Empty`] when `δ > 1`. Errors: dimension mismatch,
    /// `λ ∉ [0, 1]`, [`EllipsoidError::UnboundedIntersection`] (at `λ = 1`, `C` not of full
    /// column rank within [`crate::RANK_RELATIVE_TOLERANCE`]; or `λ` so close to 1 that the
    /// bound is numerically unbounded), [`EllipsoidError::DegenerateIntersection`] (`δ = 1`),
    /// [`EllipsoidError::DegenerateResult`] (the bound is too ill-conditioned to factor, e.g.
    /// at `λ = 1` with `C` close to rank-deficient).
    pub fn intersect_measurement(&self, meas: &MeasurementSet, lambda: f64) -> Result<IntersectionBound> {
        check_lambda(lambda)?;
        Whitened::new(self, meas)?.evaluate(lambda)
    }

    /// [`Ellipsoid::intersect_measurement`] with the ellipsoid `other` as the second set
    /// ([`MeasurementSet::from_ellipsoid`]).
    pub fn intersect_ellipsoid(&self, other: &Ellipsoid, lambda: f64) -> Result<IntersectionBound> {
        self.intersect_measurement(&MeasurementSet::from_ellipsoid(other), lambda)
    }

    /// The trace-minimising member of the family `S_λ`, `λ ∈ [0, 1]`, with its `λ`.
    ///
    /// Search: (1) golden-section maximisation of the concave `δ(λ)`; if its maximum
    /// exceeds 1 the intersection is empty and `Empty` is returned with that `λ`. (2) The
    /// trace `τ(λ) = (1 − δ) tr X⁻¹`, in closed form from one eigendecomposition, is scanned
    /// on the grid `λ = k/50`, `k = 0, …, 50` (`λ = 1` only when the bound there can be
    /// computed, i.e. `Cᵀ R⁻¹ C` is numerically non-singular), then refined by golden section on the two grid cells around the best
    /// grid point to a bracket of `1e-10`. The best `λ` evaluated is kept, so the result is
    /// never worse than the grid (and never worse than the prior, `λ = 0`); since every
    /// `λ` gives a valid bound, the guarantee does not depend on the optimisation. The bound
    /// at the chosen `λ` is then computed with [`Ellipsoid::intersect_measurement`]; should
    /// that fail numerically (a shape too ill-conditioned to factor), the best grid point that
    /// evaluates is used instead (`λ = 0`, the prior, always does).
    pub fn intersect_measurement_min_trace(&self, meas: &MeasurementSet) -> Result<(IntersectionBound, f64)> {
        let wh = Whitened::new(self, meas)?;
        let sc = Scalar::new(&wh)?;

        let mut best_delta = (0.0, -sc.delta(0.0));
        let one = -sc.delta(1.0);
        if one < best_delta.1 {
            best_delta = (1.0, one);
        }
        golden_min(|l| -sc.delta(l), 0.0, 1.0, LAMBDA_TOL, &mut best_delta);
        if -best_delta.1 > 1.0 {
            let outcome = wh.evaluate(best_delta.0);
            if let Ok(IntersectionBound::Empty { .. }) = outcome {
                return Ok((outcome?, best_delta.0));
            }
        }

        let grid: Vec<f64> = (0..=LAMBDA_GRID).map(|k| k as f64 / LAMBDA_GRID as f64).collect();
        let values: Vec<f64> = grid.iter().map(|&l| sc.trace(l)).collect();
        let mut k_best = 0;
        for (k, v) in values.iter().enumerate() {
            if *v < values[k_best] {
                k_best = k;
            }
        }
        let mut best = (grid[k_best], values[k_best]);
        let lo = grid[k_best.saturating_sub(1)];
        let hi = grid[(k_best + 1).min(LAMBDA_GRID)];
        golden_min(|l| sc.trace(l), lo, hi, LAMBDA_TOL, &mut best);
        match wh.evaluate(best.0) {
            Ok(bound) => Ok((bound, best.0)),
            Err(err) => {
                // Numerically degenerate at the optimum: fall back to the best grid point
                // that evaluates (λ = 0, the prior, always does).
                let mut order: Vec<usize> = (0..=LAMBDA_GRID).collect();
                order.sort_by(|&i, &j| values[i].total_cmp(&values[j]));
                for k in order {
                    if let Ok(bound) = wh.evaluate(grid[k]) {
                        return Ok((bound, grid[k]));
                    }
                }
                Err(err)
            }
        }
    }

    /// [`Ellipsoid::intersect_measurement_min_trace`] with the ellipsoid `other` as the second
    /// set.
    pub fn intersect_ellipsoid_min_trace(&self, other: &Ellipsoid) -> Result<(IntersectionBound, f64)> {
        self.intersect_measurement_min_trace(&MeasurementSet::from_ellipsoid(other))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::v;

    #[test]
    fn two_unit_discs_half_half() {
        // Discs of radius 1 at (±a, 0): with λ = ½ the combined form is ‖x‖² + a², so the
        // bound is the disc of radius √(1 − a²) centred at 0 (through the lens corners).
        let a = 0.6;
        let d1 = Ellipsoid::ball(v(&[-a, 0.0]), 1.0).expect("valid");
        let d2 = Ellipsoid::ball(v(&[a, 0.0]), 1.0).expect("valid");
        let b = d1.intersect_ellipsoid(&d2, 0.5).expect("ok");
        let e = b.ellipsoid().expect("bounded");
        assert!(e.center().amax() < 1e-15);
        let expected = DMatrix::<f64>::identity(2, 2) * (1.0 - a * a);
        assert!((e.shape() - expected).amax() < 1e-14);
        // The lens corners lie on its boundary.
        let corner = v(&[0.0, (1.0 - a * a).sqrt()]);
        assert!((e.normalized_distance(&corner).expect("ok") - 1.0).abs() < 1e-14);
        // By symmetry λ = ½ is also trace-optimal.
        let (opt, lambda) = d1.intersect_ellipsoid_min_trace(&d2).expect("ok");
        assert!((lambda - 0.5).abs() < 1e-6, "λ* = {lambda}");
        assert!((opt.ellipsoid().expect("bounded").trace() - 2.0 * (1.0 - a * a)).abs() < 1e-9);
    }

    #[test]
    fn disjoint_discs_are_empty() {
        let d1 = Ellipsoid::ball(v(&[-1.5, 0.0]), 1.0).expect("valid");
        let d2 = Ellipsoid::ball(v(&[1.5, 0.0]), 1.0).expect("valid");
        // δ(½) = ‖(1.5, 0)‖² = 2.25 > 1.
        match d1.intersect_ellipsoid(&d2, 0.5).expect("ok") {
            IntersectionBound::Empty { delta } => assert!((delta - 2.25).abs() < 1e-14),
            other => panic!("expected empty, got {other:?}"),
        }
        let (b, _) = d1.intersect_ellipsoid_min_trace(&d2).expect("ok");
        assert!(b.is_empty());
        assert!(b.into_ellipsoid().is_none());
    }

    #[test]
    fn lambda_zero_and_one() {
        let prior = Ellipsoid::ball(v(&[0.0, 0.0]), 2.0).expect("valid");
        let meas = MeasurementSet::new(DMatrix::identity(2, 2), v(&[1.0, 0.0]), DMatrix::identity(2, 2) * 0.25)
            .expect("valid");
        let b0 = prior.intersect_measurement(&meas, 0.0).expect("ok");
        assert_eq!(b0.ellipsoid(), Some(&prior));
        // λ = 1 with C = I: the measurement ellipsoid itself.
        let b1 = prior.intersect_measurement(&meas, 1.0).expect("ok");
        let e1 = b1.ellipsoid().expect("bounded");
        assert!((e1.center() - v(&[1.0, 0.0])).amax() < 1e-15);
        assert!((e1.shape() - DMatrix::identity(2, 2) * 0.25).amax() < 1e-15);
        // Rank-deficient C at λ = 1: unbounded.
        let partial =
            MeasurementSet::new(DMatrix::from_row_slice(1, 2, &[1.0, 0.0]), v(&[0.5]), DMatrix::identity(1, 1))
                .expect("valid");
        let err = prior.intersect_measurement(&partial, 1.0).expect_err("unbounded");
        assert!(matches!(err, EllipsoidError::UnboundedIntersection { .. }));
        // …but any λ < 1 works, and the optimiser avoids λ = 1.
        assert!(prior.intersect_measurement(&partial, 0.9).expect("ok").ellipsoid().is_some());
        let (b, lambda) = prior.intersect_measurement_min_trace(&partial).expect("ok");
        assert!(lambda < 1.0);
        assert!(b.ellipsoid().expect("bounded").trace() < prior.trace());
    }

    #[test]
    fn gain_form_agrees() {
        // Cross-check centre, δ and shape against the covariance (gain) formulas.
        let p = DMatrix::from_row_slice(3, 3, &[2.0, 0.3, 0.1, 0.3, 1.0, -0.2, 0.1, -0.2, 0.5]);
        let c = v(&[0.5, -1.0, 0.2]);
        let prior = Ellipsoid::new(c.clone(), p.clone()).expect("valid");
        let cm = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 1.0, 0.0, 1.0, 0.5]);
        let r = DMatrix::from_row_slice(2, 2, &[0.4, 0.1, 0.1, 0.3]);
        let y = v(&[0.9, -0.7]);
        let meas = MeasurementSet::new(cm.clone(), y.clone(), r.clone()).expect("valid");
        let lambda = 0.37;
        let b = prior.intersect_measurement(&meas, lambda).expect("ok");
        let e = b.ellipsoid().expect("bounded");
        let innov = &y - &cm * &c;
        let s = &cm * &p * cm.transpose() + &r * ((1.0 - lambda) / lambda);
        let s_inv = s.clone().try_inverse().expect("invertible");
        let k = &p * cm.transpose() * &s_inv;
        let center = &c + &k * &innov;
        let s_delta = &cm * &p * cm.transpose() / (1.0 - lambda) + &r / lambda;
        let delta = (innov.transpose() * s_delta.try_inverse().expect("inv") * &innov)[(0, 0)];
        let x_inv = (DMatrix::identity(3, 3) - &k * &cm) * &p / (1.0 - lambda);
        assert!((e.center() - center).amax() < 1e-13);
        assert!((e.shape() - x_inv * (1.0 - delta)).amax() < 1e-13);
    }
}
