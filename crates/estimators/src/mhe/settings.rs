//! Data-only configuration of the moving-horizon estimators (docs/robust-mhe.md §2), validated by
//! [`MheSettings::validate`] before an estimator is built.

use nalgebra::{DMatrix, DVector};

use crate::error::EstimatorError;
use crate::traits::Setup;

/// How the paper's `α ∈ (0, 1)` sets the attenuation weight `λv` of the min–max cost (§2.1 \[A\]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum AlphaMap {
    /// `λv = 1/(1 − α)` (default; `α = 0.9` gives `λv = 10`).
    OneOverOneMinusAlpha,
    /// `λv = 1/α` (`α = 0.9` gives `λv ≈ 1.11`; the coordinate rotation does not converge there).
    OneOverAlpha,
}

impl AlphaMap {
    /// `λv` for `alpha`.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfiguration`] unless `0 < α < 1`.
    pub fn lambda_v(self, alpha: f64) -> Result<f64, EstimatorError> {
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(invalid(format!("alpha must lie in (0, 1), got {alpha}")));
        }
        Ok(match self {
            AlphaMap::OneOverOneMinusAlpha => 1.0 / (1.0 - alpha),
            AlphaMap::OneOverAlpha => 1.0 / alpha,
        })
    }
}

/// The cost of a window (§2.1).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum MheCost {
    /// The min–max cost with attenuation `λv > 1`: the adversary picks `v ∈ V` to maximise
    /// `Σ ‖y − Cx − v‖²_{R⁻¹} − λv ‖v‖²_{R⁻¹}`.
    MinMax {
        /// `λv` (must exceed 1 for the cost to be strictly concave in `v`).
        lambda_v: f64,
    },
    /// Plain least-squares MHE (`λv → ∞`, `v = 0`), the control of the experiment.
    LeastSquares,
}

/// The Riccati-like recursion (20) of the arrival-cost weight (§2.3).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ArrivalRecursion {
    /// Kalman form with `R_eff = R (λv − 1)/λv` (`R` for plain MHE): `P⁺ = A (P⁻¹ + Cᵀ R_eff⁻¹ C)⁻¹ Aᵀ + Q`.
    Kalman,
    /// Game-theoretic H∞ form `P⁺ = A (P⁻¹ − θ I + Cᵀ R⁻¹ C)⁻¹ Aᵀ + Q`, which exists only while
    /// `P⁻¹ − θ I + Cᵀ R⁻¹ C ≻ 0` (checked every step; when it fails the step uses the Kalman
    /// form and reports it).
    HInfinity {
        /// `θ` (the digest takes `θ = α`).
        theta: f64,
    },
}

/// Where the prior mean `x̄_s` of a window's first state comes from (§2.3, digest §6.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum PriorMean {
    /// `x̂_{s|T−1}`: the previous window's estimate of `x_s` (default).
    Smoothed,
    /// `A x̂_{s−1|s−1} + B u_{s−1}`: the prediction from the published estimate.
    Filtered,
}

/// How a block's process term is weighted (§2.4, digest §6.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BlockWeighting {
    /// `d_i ‖ω_i‖²_{Q⁻¹}`: the unblocked cost of the blocked sequence (default).
    Length,
    /// `‖ω_i‖²_{Q⁻¹}`.
    Unit,
}

/// The paper's three blocking variants (§2.4), for a horizon `N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BlockingPreset {
    /// RMHE: no blocking, `d = (1, …, 1)` (`N + 1` vector unknowns).
    Rmhe,
    /// RMHE-OP: three blocks in the ratio 3 : 2 : 1, oldest longest (`(3, 2, 1)` for `N = 6`;
    /// the generalisation to other `N` is assumed). Needs `N ≥ 3`.
    RmheOp,
    /// RMHE-OF: the last disturbance alone, the rest one block, `d = (N − 1, 1)`. Needs `N ≥ 2`.
    RmheOf,
}

impl BlockingPreset {
    /// Block lengths, oldest first.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfiguration`] if `N` is too small for the preset.
    pub fn lengths(self, horizon: usize) -> Result<Vec<usize>, EstimatorError> {
        let n = horizon;
        match self {
            BlockingPreset::Rmhe if n >= 1 => Ok(vec![1; n]),
            BlockingPreset::RmheOf if n >= 2 => Ok(vec![n - 1, 1]),
            BlockingPreset::RmheOp if n >= 3 => {
                let d3 = ((n as f64) / 6.0).round().max(1.0) as usize;
                let d2 = ((n as f64) / 3.0).round().max(1.0) as usize;
                Ok(vec![n - d2 - d3, d2, d3])
            }
            _ => Err(invalid(format!("the {} preset needs a longer horizon than N = {n}", self.name()))),
        }
    }

    /// The paper's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            BlockingPreset::Rmhe => "RMHE",
            BlockingPreset::RmheOp => "RMHE-OP",
            BlockingPreset::RmheOf => "RMHE-OF",
        }
    }
}

/// The solver of the minimisation step (44) of the coordinate rotation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum InnerSolver {
    /// The dense active-set box-QP solver of [`crate::mhe::boxqp`] (default; allocation-free).
    ActiveSet,
    /// Clarabel's interior-point QP path (pure Rust; allocates per solve). For comparison.
    Clarabel,
}

/// How a window is solved.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum WindowSolver {
    /// The paper's coordinate rotation (44)–(45): alternate the box-constrained least-squares
    /// minimisation over `(x_s, ω)` with the closed-form maximisation over `v`.
    CoordinateRotation {
        /// At most this many min/max sweeps (the paper does one; default 10).
        max_sweeps: usize,
        /// Stop when `‖Δz‖∞` between sweeps is below this (default `1e−8`).
        tolerance: f64,
        /// Solver of the minimisation step.
        inner: InnerSolver,
    },
    /// The exact saddle point: the maximisation done analytically, leaving a convex piecewise-
    /// quadratic minimisation over `(x_s, ω ∈ W)`, solved by Newton's method on the pieces with
    /// the active-set box-QP solver (the reference).
    ExactSaddle {
        /// At most this many Newton iterations (default 50).
        max_iterations: usize,
        /// Stop when the step `‖Δz‖∞` is below this (default `1e−10`).
        tolerance: f64,
    },
}

impl WindowSolver {
    /// The coordinate rotation with the digest's defaults (10 sweeps, `1e−8`, active set).
    #[must_use]
    pub fn coordinate_rotation() -> Self {
        WindowSolver::CoordinateRotation { max_sweeps: 10, tolerance: 1e-8, inner: InnerSolver::ActiveSet }
    }

    /// The exact saddle solver with its defaults.
    #[must_use]
    pub fn exact_saddle() -> Self {
        WindowSolver::ExactSaddle { max_iterations: 50, tolerance: 1e-10 }
    }
}

/// Everything that defines a (robust) moving-horizon estimator beyond its [`Setup`] (the prior
/// mean `x̄₀` and weight `P₀`, the process weight `Q` and the measurement weight `R`, diagonal),
/// as data.
#[derive(Debug, Clone, PartialEq)]
pub struct MheSettings {
    /// Horizon `N` (disturbances per full window; the window holds `N + 1` states).
    pub horizon: usize,
    /// Block lengths `d_1..d_S`, oldest first, summing to `N`.
    pub blocks: Vec<usize>,
    /// Block weighting of the process term.
    pub block_weighting: BlockWeighting,
    /// Min–max or least-squares cost.
    pub cost: MheCost,
    /// Box `W = [w_lo, w_hi]` of the process noise (entries may be infinite).
    pub w_box: (DVector<f64>, DVector<f64>),
    /// Box `V = [v_lo, v_hi]` of the measurement noise (finite, containing 0), used by the min–max cost.
    pub v_box: (DVector<f64>, DVector<f64>),
    /// Arrival-cost recursion (20).
    pub arrival: ArrivalRecursion,
    /// Prior mean of a window's first state.
    pub prior_mean: PriorMean,
    /// Window solver.
    pub solver: WindowSolver,
    /// The paper's (11) read literally: also require `y_k − C x_k ∈ V` for every measured sample
    /// (off by default, digest §6.6). The window QPs then have linear inequalities and are solved
    /// by Clarabel's QP path (allocating); when the constraints cannot all hold, the window is
    /// solved without them and reported `WindowStatus::Infeasible`.
    pub output_constraint: bool,
}

impl MheSettings {
    /// The digest's RMHE settings for the noise boxes `W` (process, length `n`) and `V`
    /// (measurement, length `m`): `N = 6`, min–max with `λv = 10`, Kalman-form arrival cost,
    /// smoothed prior, coordinate rotation.
    #[must_use]
    pub fn new(w_box: (DVector<f64>, DVector<f64>), v_box: (DVector<f64>, DVector<f64>)) -> Self {
        Self {
            horizon: 6,
            blocks: vec![1; 6],
            block_weighting: BlockWeighting::Length,
            cost: MheCost::MinMax { lambda_v: 10.0 },
            w_box,
            v_box,
            arrival: ArrivalRecursion::Kalman,
            prior_mean: PriorMean::Smoothed,
            solver: WindowSolver::coordinate_rotation(),
            output_constraint: false,
        }
    }

    /// Sets the horizon and the blocks of a preset.
    ///
    /// # Errors
    /// As [`BlockingPreset::lengths`].
    pub fn with_preset(mut self, horizon: usize, preset: BlockingPreset) -> Result<Self, EstimatorError> {
        self.blocks = preset.lengths(horizon)?;
        self.horizon = horizon;
        Ok(self)
    }

    /// The vector unknowns of a full window, `1 + S` (`x_s` and one value per block): the paper's
    /// 7 / 4 / 3.
    #[must_use]
    pub fn vector_unknowns(&self) -> usize {
        1 + self.blocks.len()
    }

    /// `R_eff` factor: `(λv − 1)/λv` for the min–max cost, 1 for least squares.
    #[must_use]
    pub fn r_eff_factor(&self) -> f64 {
        match self.cost {
            MheCost::MinMax { lambda_v } => (lambda_v - 1.0) / lambda_v,
            MheCost::LeastSquares => 1.0,
        }
    }

    /// Checks every setting, and the [`Setup`] as this estimator reads it (`R` diagonal); the
    /// error names the first one that is wrong.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfiguration`] naming the setting.
    pub fn validate(&self, setup: &Setup) -> Result<(), EstimatorError> {
        let bad = |s: String| Err(invalid(s));
        let Setup { x0, p0, process_noise: q, measurement_noise: r, .. } = setup;
        let n = x0.len();
        let m = r.nrows();
        if n == 0 {
            return bad("the prior mean x0 is empty (no states)".into());
        }
        if m == 0 || r.ncols() != m {
            return bad(format!("R must be square and non-empty, got {}×{}", r.nrows(), r.ncols()));
        }
        if self.horizon == 0 {
            return bad("the horizon N must be at least 1".into());
        }
        if self.blocks.is_empty() || self.blocks.contains(&0) {
            return bad(format!("block lengths must be positive, got {:?}", self.blocks));
        }
        let sum: usize = self.blocks.iter().sum();
        if sum != self.horizon {
            return bad(format!(
                "block lengths {:?} sum to {sum}, not to the horizon N = {}",
                self.blocks, self.horizon
            ));
        }
        if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
            return bad(format!("x0[{i}] is not finite"));
        }
        check_spd("P0", p0, n)?;
        check_spd("Q", q, n)?;
        for i in 0..m {
            for j in 0..m {
                let v = r[(i, j)];
                if !v.is_finite() || (i != j && v != 0.0) {
                    return bad(format!(
                        "R must be diagonal with finite entries (the min–max cost separates per output); R[({i}, {j})] = {v}"
                    ));
                }
            }
            if r[(i, i)] <= 0.0 {
                return bad(format!("R[({i}, {i})] = {} must be positive", r[(i, i)]));
            }
        }
        check_box("W", &self.w_box, n, false)?;
        check_box("V", &self.v_box, m, true)?;
        match self.cost {
            MheCost::MinMax { lambda_v } if !(lambda_v > 1.0 && lambda_v.is_finite()) => {
                return bad(format!(
                    "lambda_v = {lambda_v} must be finite and exceed 1 (the cost is concave in v only for lambda_v > 1)"
                ));
            }
            _ => {}
        }
        if let ArrivalRecursion::HInfinity { theta } = self.arrival
            && !(theta >= 0.0 && theta.is_finite())
        {
            return bad(format!("theta = {theta} of the H-infinity recursion must be finite and non-negative"));
        }
        match self.solver {
            WindowSolver::CoordinateRotation { max_sweeps, tolerance, .. } => {
                if max_sweeps == 0 || tolerance.is_nan() || tolerance <= 0.0 {
                    return bad(format!(
                        "coordinate rotation needs max_sweeps ≥ 1 and tolerance > 0, got {max_sweeps} and {tolerance}"
                    ));
                }
            }
            WindowSolver::ExactSaddle { max_iterations, tolerance } => {
                if max_iterations == 0 || tolerance.is_nan() || tolerance <= 0.0 {
                    return bad(format!(
                        "the exact saddle solver needs max_iterations ≥ 1 and tolerance > 0, got {max_iterations} and {tolerance}"
                    ));
                }
            }
        }
        Ok(())
    }
}

fn check_spd(what: &str, a: &DMatrix<f64>, n: usize) -> Result<(), EstimatorError> {
    if a.nrows() != n || a.ncols() != n {
        return Err(invalid(format!("{what} must be {n}×{n}, got {}×{}", a.nrows(), a.ncols())));
    }
    if let Some(i) = a.iter().position(|v| !v.is_finite()) {
        return Err(invalid(format!("{what} has a non-finite entry at index {i} (column-major)")));
    }
    if dense_kernels::max_asymmetry(a, dense_kernels::SYMMETRY_TOLERANCE).is_some() {
        return Err(invalid(format!("{what} is not symmetric")));
    }
    if dense_kernels::cholesky_checked(a, dense_kernels::PD_RELATIVE_TOLERANCE).is_err() {
        return Err(invalid(format!("{what} is not positive definite")));
    }
    Ok(())
}

fn check_box(what: &str, b: &(DVector<f64>, DVector<f64>), len: usize, finite: bool) -> Result<(), EstimatorError> {
    let (lo, hi) = b;
    if lo.len() != len || hi.len() != len {
        return Err(invalid(format!("the box {what} must have {len} components, got {} and {}", lo.len(), hi.len())));
    }
    for i in 0..len {
        let (l, h) = (lo[i], hi[i]);
        if l.is_nan() || h.is_nan() || (finite && !(l.is_finite() && h.is_finite())) {
            return Err(invalid(format!("the box {what} has a NaN or infinite bound at component {i}")));
        }
        if l > 0.0 || h < 0.0 || l >= h {
            return Err(invalid(format!(
                "the box {what} at component {i} is [{l}, {h}]: it must be non-empty (lower < upper) and contain 0"
            )));
        }
    }
    Ok(())
}

fn invalid(message: String) -> EstimatorError {
    EstimatorError::InvalidConfiguration { estimator: "mhe", message }
}

/// The bytes a moving-horizon estimator allocates for a model with `n` states, `m` outputs and
/// `p` inputs, a horizon of `horizon` disturbances in `blocks` blocks: an estimate from above of
/// its buffers — the condensed window maps and rows, the Hessian-sized matrices of the window and
/// the box-QP's factor (three, counted as four; six with `clarabel`, whose QP copies them), the
/// ring buffers of the last `N + 2` steps. `None` when the count overflows `u128`.
#[must_use]
pub fn memory_estimate(n: usize, m: usize, p: usize, horizon: usize, blocks: usize, clarabel: bool) -> Option<u128> {
    let [n, m, p, horizon, blocks] = [n, m, p, horizon, blocks].map(|v| v as u128);
    let mul = |a: u128, b: u128| a.checked_mul(b);
    let add = |a: u128, b: u128| a.checked_add(b);
    // Unknowns of a full window: x_s and one disturbance per block (at most N + 1 vectors).
    let nz = mul(n, add(1, horizon.max(blocks))?)?;
    let samples = add(horizon, 1)?;
    let ring = add(horizon, 2)?;
    let hessians = mul(if clarabel { 6 } else { 4 }, mul(nz, nz)?)?;
    let window = mul(mul(samples, nz)?, add(n, m)?)?;
    let per_step = add(add(mul(2, mul(n, n)?)?, mul(m, n)?)?, add(mul(3, n)?, add(p, mul(4, m)?)?)?)?;
    let rings = mul(ring, per_step)?;
    let vectors = add(mul(12, nz)?, mul(samples, add(mul(4, m)?, mul(2, n)?)?)?)?;
    let f64s = add(add(hessians, window)?, add(rings, vectors)?)?;
    mul(f64s, 8)
}
