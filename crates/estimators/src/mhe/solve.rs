//! The two window solvers of docs/robust-mhe.md §2.6–2.7 on a built [`WindowProblem`]:
//! the paper's coordinate rotation (44)–(45) and the exact saddle point (Newton's method on the
//! pieces of the convex piecewise-quadratic reduction). Allocation-free with the active-set
//! inner solver.

use crate::mhe::boxqp::{BoxQp, BoxQpStatus};
use crate::mhe::settings::{InnerSolver, MheCost};
use crate::mhe::window::{Target, WindowProblem};

/// Outcome of one window solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum WindowStatus {
    /// The solver met its tolerance (for the coordinate rotation: `‖Δz‖∞` below it; for the
    /// exact saddle: the optimality conditions of the piecewise-quadratic problem hold).
    Converged,
    /// The sweep or iteration limit was reached first; the last iterate is published.
    NotConverged,
    /// An inner box-QP reported a failure (iteration limit or a Hessian that is not positive
    /// definite); the last finite iterate is published.
    InnerFailure,
    /// The constraints of the window cannot all hold (the nonlinear MHE's boxes on `ω` and `ν`):
    /// the unconstrained estimate is published.
    Infeasible,
    /// The nonlinear MHE's real-time iterations spent their budget (as configured: not
    /// converged by design); the last iterate is published.
    RealTimeIteration,
}

/// Counters of one window solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveCounters {
    /// Status.
    pub status: WindowStatus,
    /// Min/max sweeps of the coordinate rotation (Newton iterations of the exact saddle).
    pub sweeps: usize,
    /// Inner box-QP iterations in total (active-set iterations, or Clarabel's IPM iterations).
    pub inner_iterations: usize,
    /// `‖Δz‖∞` of the last sweep or Newton step.
    pub last_change: f64,
}

/// Scratch shared by the solvers.
#[derive(Debug, Clone)]
pub(crate) struct SolverScratch {
    pub qp: BoxQp,
    pub targets: Vec<Target>,
    pub e: Vec<f64>,
    pub z_prev: Vec<f64>,
    pub z_trial: Vec<f64>,
}

impl SolverScratch {
    pub fn new(nz_cap: usize, meas_cap: usize) -> Self {
        Self {
            qp: BoxQp::new(nz_cap),
            targets: vec![Target { weight: 0.0, offset: 0.0 }; meas_cap],
            e: vec![0.0; meas_cap],
            z_prev: vec![0.0; nz_cap],
            z_trial: vec![0.0; nz_cap],
        }
    }
}

/// Noise data the solvers need: `1/R_ii`, the box `V` and the cost.
#[derive(Debug, Clone, Copy)]
pub(crate) struct NoiseData<'a> {
    pub r_inv: &'a [f64],
    pub v_lo: &'a [f64],
    pub v_hi: &'a [f64],
    pub cost: MheCost,
    /// Whether the output constraints `y − C x ∈ V` are imposed (Clarabel solves the QPs then).
    pub output_constraint: bool,
}

/// Solves the window QP with Clarabel under the output constraints; maps the failure to a status.
fn constrained_qp(w: &WindowProblem, noise: &NoiseData<'_>, z: &mut [f64]) -> Result<usize, WindowStatus> {
    crate::mhe::clarabel_inner::solve_qp(w, z, Some((noise.v_lo, noise.v_hi))).map_err(|e| match e {
        crate::mhe::clarabel_inner::QpFailure::Infeasible => WindowStatus::Infeasible,
        crate::mhe::clarabel_inner::QpFailure::Failed => WindowStatus::InnerFailure,
    })
}

impl NoiseData<'_> {
    /// The maximising `v` for residual `e` of output `i`: `clip(−e/(λv − 1), v_lo, v_hi)` (45).
    pub fn v_star(&self, i: usize, e: f64) -> f64 {
        match self.cost {
            MheCost::MinMax { lambda_v } => (-e / (lambda_v - 1.0)).clamp(self.v_lo[i], self.v_hi[i]),
            MheCost::LeastSquares => 0.0,
        }
    }

    /// The maximised stage cost `g(e) = max_v ((e − v)² − λv v²)/R` (least squares: `e²/R`).
    pub fn stage(&self, i: usize, e: f64) -> f64 {
        let v = self.v_star(i, e);
        match self.cost {
            MheCost::MinMax { lambda_v } => ((e - v) * (e - v) - lambda_v * v * v) * self.r_inv[i],
            MheCost::LeastSquares => e * e * self.r_inv[i],
        }
    }
}

/// The saddle value `Φ(z, v*(z))` (§2.1) of the window at `z`.
pub(crate) fn saddle_value(w: &mut WindowProblem, noise: &NoiseData<'_>, z: &[f64], e: &mut [f64]) -> f64 {
    let m = noise.r_inv.len();
    w.residuals(z, e);
    let mut total = w.prior_and_process(z);
    for j in 0..w.len {
        if w.measured[j] {
            for i in 0..m {
                total += noise.stage(i, e[j * m + i]);
            }
        }
    }
    total
}

fn inf_norm_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0_f64, |s, (x, y)| s.max((x - y).abs()))
}

/// The coordinate rotation (44)–(45) from `z` (warm start) and `v` (initial noise, `len · m`);
/// both hold the result on exit.
pub(crate) fn coordinate_rotation(
    w: &mut WindowProblem,
    noise: &NoiseData<'_>,
    s: &mut SolverScratch,
    z: &mut [f64],
    v: &mut [f64],
    max_sweeps: usize,
    tolerance: f64,
    inner: InnerSolver,
) -> SolveCounters {
    let m = noise.r_inv.len();
    let nz = w.nz;
    let meas = w.len * m;
    // The Hessian does not depend on v: weights 1/R on every measured output.
    for j in 0..w.len {
        for i in 0..m {
            s.targets[j * m + i] = Target { weight: noise.r_inv[i], offset: 0.0 };
        }
    }
    if matches!(noise.cost, MheCost::LeastSquares) {
        v[..meas].fill(0.0);
    }
    let mut counters = SolveCounters {
        status: WindowStatus::NotConverged,
        sweeps: 0,
        inner_iterations: 0,
        last_change: f64::INFINITY,
    };
    for sweep in 0..max_sweeps {
        for k in 0..meas {
            s.targets[k].offset = v[k];
        }
        if sweep == 0 {
            w.assemble(&s.targets);
        } else {
            w.assemble_b(&s.targets);
        }
        s.z_prev[..nz].copy_from_slice(&z[..nz]);
        // (44) the minimisation over (x_s, ω ∈ W) with v fixed.
        if noise.output_constraint {
            match constrained_qp(w, noise, &mut z[..nz]) {
                Ok(iterations) => counters.inner_iterations += iterations,
                Err(status) => {
                    z[..nz].copy_from_slice(&s.z_prev[..nz]);
                    counters.status = status;
                    counters.sweeps = sweep + 1;
                    return counters;
                }
            }
        } else {
            match inner {
                InnerSolver::ActiveSet => {
                    let o = s.qp.solve(
                        &w.h[..nz * nz],
                        &w.b[..nz],
                        &w.lo[..nz],
                        &w.hi[..nz],
                        &mut z[..nz],
                        20 * nz + 20,
                        sweep > 0,
                    );
                    counters.inner_iterations += o.iterations;
                    if o.status != BoxQpStatus::Optimal {
                        counters.status = WindowStatus::InnerFailure;
                        counters.sweeps = sweep + 1;
                        return counters;
                    }
                }
                InnerSolver::Clarabel => match crate::mhe::clarabel_inner::solve_box_qp(w, &mut z[..nz]) {
                    Ok(iterations) => counters.inner_iterations += iterations,
                    Err(()) => {
                        z[..nz].copy_from_slice(&s.z_prev[..nz]);
                        counters.status = WindowStatus::InnerFailure;
                        counters.sweeps = sweep + 1;
                        return counters;
                    }
                },
            }
        }
        counters.sweeps = sweep + 1;
        counters.last_change = inf_norm_diff(&z[..nz], &s.z_prev[..nz]);
        if matches!(noise.cost, MheCost::LeastSquares) {
            counters.status = WindowStatus::Converged;
            return counters;
        }
        // (45) the maximisation over v ∈ V in closed form.
        w.residuals(&z[..nz], &mut s.e[..meas]);
        for j in 0..w.len {
            for i in 0..m {
                let k = j * m + i;
                v[k] = if w.measured[j] { noise.v_star(i, s.e[k]) } else { 0.0 };
            }
        }
        let scale = z[..nz].iter().fold(1.0_f64, |a, b| a.max(b.abs()));
        if sweep > 0 && counters.last_change <= tolerance * scale {
            counters.status = WindowStatus::Converged;
            return counters;
        }
    }
    counters
}

/// The exact saddle point: minimise `F(z) = prior + process + Σ g(e_{j,i}(z))` over the box by
/// Newton's method on the pieces of `g` (each piece's quadratic is exact), with a backtracking
/// line search on the convex `F`. `z` holds the warm start and the result; `v` receives `v*(z)`.
pub(crate) fn exact_saddle(
    w: &mut WindowProblem,
    noise: &NoiseData<'_>,
    s: &mut SolverScratch,
    z: &mut [f64],
    v: &mut [f64],
    max_iterations: usize,
    tolerance: f64,
) -> SolveCounters {
    let m = noise.r_inv.len();
    let nz = w.nz;
    let meas = w.len * m;
    let mut counters = SolveCounters {
        status: WindowStatus::NotConverged,
        sweeps: 0,
        inner_iterations: 0,
        last_change: f64::INFINITY,
    };
    // Start from a feasible point.
    for k in 0..nz {
        z[k] = z[k].clamp(w.lo[k], w.hi[k]);
    }
    let mut f = saddle_value(w, noise, &z[..nz], &mut s.e[..meas]);
    for it in 0..max_iterations {
        counters.sweeps = it + 1;
        // The piece of every residual at z: interior (weight λv/((λv−1)R), offset 0) or clipped
        // (weight 1/R, offset v = the bound).
        w.residuals(&z[..nz], &mut s.e[..meas]);
        set_piece_targets(w, noise, &s.e[..meas], &mut s.targets[..meas]);
        w.assemble(&s.targets);
        s.z_trial[..nz].copy_from_slice(&z[..nz]);
        if noise.output_constraint {
            match constrained_qp(w, noise, &mut s.z_trial[..nz]) {
                Ok(iterations) => counters.inner_iterations += iterations,
                Err(status) => {
                    counters.status = status;
                    break;
                }
            }
        } else {
            let o = s.qp.solve(
                &w.h[..nz * nz],
                &w.b[..nz],
                &w.lo[..nz],
                &w.hi[..nz],
                &mut s.z_trial[..nz],
                20 * nz + 20,
                false,
            );
            counters.inner_iterations += o.iterations;
            if o.status != BoxQpStatus::Optimal {
                counters.status = WindowStatus::InnerFailure;
                break;
            }
        }
        // Does the model's minimiser lie on the same pieces? Then it is optimal for F.
        let f_trial = saddle_value(w, noise, &s.z_trial[..nz], &mut s.e[..meas]);
        let same_pieces = pieces_match(w, noise, &s.e[..meas], &s.targets[..meas]);
        let mut t = 1.0;
        let mut f_new = f_trial;
        // The warm start need not satisfy the output constraints; the first QP's minimiser does,
        // and from then on every iterate is feasible.
        if noise.output_constraint && it == 0 {
            f = f64::INFINITY;
        }
        // Backtracking on the convex F along z → z_trial (feasible: the constraints are convex).
        while f_new > f && t > 1e-12 {
            t *= 0.5;
            for k in 0..nz {
                s.z_prev[k] = z[k] + t * (s.z_trial[k] - z[k]);
            }
            f_new = saddle_value(w, noise, &s.z_prev[..nz], &mut s.e[..meas]);
        }
        let step = t * inf_norm_diff(&s.z_trial[..nz], &z[..nz]);
        counters.last_change = step;
        if f_new > f {
            // No descent along the Newton direction to rounding: z is optimal to working precision.
            counters.status = WindowStatus::Converged;
            break;
        }
        if t == 1.0 {
            z[..nz].copy_from_slice(&s.z_trial[..nz]);
        } else {
            z[..nz].copy_from_slice(&s.z_prev[..nz]);
        }
        f = f_new;
        let scale = z[..nz].iter().fold(1.0_f64, |a, b| a.max(b.abs()));
        if (same_pieces && t == 1.0) || step <= tolerance * scale {
            counters.status = WindowStatus::Converged;
            break;
        }
    }
    w.residuals(&z[..nz], &mut s.e[..meas]);
    for j in 0..w.len {
        for i in 0..m {
            let k = j * m + i;
            v[k] = if w.measured[j] { noise.v_star(i, s.e[k]) } else { 0.0 };
        }
    }
    counters
}

fn piece(noise: &NoiseData<'_>, i: usize, e: f64) -> Target {
    match noise.cost {
        MheCost::LeastSquares => Target { weight: noise.r_inv[i], offset: 0.0 },
        MheCost::MinMax { lambda_v } => {
            let v = noise.v_star(i, e);
            if v == noise.v_lo[i] || v == noise.v_hi[i] {
                Target { weight: noise.r_inv[i], offset: v }
            } else {
                Target { weight: noise.r_inv[i] * lambda_v / (lambda_v - 1.0), offset: 0.0 }
            }
        }
    }
}

fn set_piece_targets(w: &WindowProblem, noise: &NoiseData<'_>, e: &[f64], targets: &mut [Target]) {
    let m = noise.r_inv.len();
    for j in 0..w.len {
        for i in 0..m {
            targets[j * m + i] = piece(noise, i, e[j * m + i]);
        }
    }
}

fn pieces_match(w: &WindowProblem, noise: &NoiseData<'_>, e: &[f64], targets: &[Target]) -> bool {
    let m = noise.r_inv.len();
    (0..w.len).filter(|&j| w.measured[j]).all(|j| (0..m).all(|i| piece(noise, i, e[j * m + i]) == targets[j * m + i]))
}
