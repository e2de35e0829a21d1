//! A dense primal active-set solver for small box-constrained convex quadratic programs
//!
//! ```text
//! minimise ½ zᵀ H z − bᵀ z   subject to   lo ≤ z ≤ hi      (H ≻ 0, bounds may be ±∞)
//! ```
//!
//! written for the window problems of the moving-horizon estimators (at most a few dozen
//! unknowns, few active bounds). Each iteration solves the equality-constrained problem on the
//! free variables by a Cholesky factorisation of `H_FF`, steps to it or to the first bound it
//! crosses, and frees the bound whose multiplier has the wrong sign when the step is zero. The
//! method terminates finitely for `H ≻ 0` (Nocedal & Wright, *Numerical Optimization*, §16.5).
//! All buffers are allocated by [`BoxQp::new`]; [`BoxQp::solve`] allocates nothing.

/// What happened in one box-QP solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BoxQpStatus {
    /// The KKT conditions hold (to rounding).
    Optimal,
    /// The iteration limit was reached; the iterate is feasible but may not be optimal.
    IterationLimit,
    /// A free block `H_FF` was not positive definite to working precision (the pivot rule of
    /// `dense_kernels`).
    NotConvex,
}

/// Outcome of [`BoxQp::solve`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoxQpOutcome {
    /// Status.
    pub status: BoxQpStatus,
    /// Active-set iterations (factorisations).
    pub iterations: usize,
    /// Number of bounds active at the end.
    pub active: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Bound {
    Free,
    Lower,
    Upper,
}

/// Workspace of the active-set solver for problems of up to `capacity` unknowns.
#[derive(Debug, Clone)]
pub struct BoxQp {
    capacity: usize,
    state: Vec<Bound>,
    free: Vec<usize>,
    chol: Vec<f64>,
    rhs: Vec<f64>,
    grad: Vec<f64>,
    /// The free set whose factor `chol` holds, valid while `factor_valid`.
    factored_free: Vec<usize>,
    factor_valid: bool,
}

impl BoxQp {
    /// A workspace for problems of at most `capacity` unknowns.
    #[must_use]
    pub fn new(capacity: usize) -> Self {
        Self {
            capacity,
            state: vec![Bound::Free; capacity],
            free: Vec::with_capacity(capacity),
            chol: vec![0.0; capacity * capacity],
            rhs: vec![0.0; capacity],
            grad: vec![0.0; capacity],
            factored_free: Vec::with_capacity(capacity),
            factor_valid: false,
        }
    }

    /// The largest problem this workspace solves.
    #[must_use]
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Solves the problem of size `n = z.len()` (`H` column-major `n × n` in `h`, only its lower
    /// triangle read). `z` holds the warm start on entry (projected onto the box) and the solution
    /// on exit. The caller guarantees `lo ≤ hi`, finite data and `n ≤ capacity`.
    ///
    /// `same_hessian`: the caller promises that `H` (and `n`) are those of the previous call, so
    /// that a factorisation of the same free block is reused (the coordinate rotation changes only
    /// `b` between sweeps).
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        h: &[f64],
        b: &[f64],
        lo: &[f64],
        hi: &[f64],
        z: &mut [f64],
        max_iterations: usize,
        same_hessian: bool,
    ) -> BoxQpOutcome {
        if !same_hessian {
            self.factor_valid = false;
        }
        let n = z.len();
        debug_assert!(n <= self.capacity && h.len() >= n * n && b.len() >= n && lo.len() >= n && hi.len() >= n);
        // Warm start: project, and start with the bounds that the gradient pushes against.
        self.gradient(h, b, z);
        for i in 0..n {
            z[i] = z[i].clamp(lo[i], hi[i]);
        }
        self.gradient(h, b, z);
        for i in 0..n {
            self.state[i] = if z[i] <= lo[i] && self.grad[i] > 0.0 {
                Bound::Lower
            } else if z[i] >= hi[i] && self.grad[i] < 0.0 {
                Bound::Upper
            } else {
                Bound::Free
            };
        }
        let mut iterations = 0;
        loop {
            if iterations >= max_iterations {
                return self.outcome(BoxQpStatus::IterationLimit, iterations, n);
            }
            iterations += 1;
            // Newton step on the free variables: H_FF p = −g_F.
            self.free.clear();
            self.free.extend((0..n).filter(|&i| self.state[i] == Bound::Free));
            let nf = self.free.len();
            if nf > 0 {
                if !(self.factor_valid && self.factored_free == self.free) {
                    self.factor_valid = false;
                    if !self.factor_free(h, n) {
                        return self.outcome(BoxQpStatus::NotConvex, iterations, n);
                    }
                    self.factored_free.clear();
                    self.factored_free.extend_from_slice(&self.free);
                    self.factor_valid = true;
                }
                for (a, &i) in self.free.iter().enumerate() {
                    self.rhs[a] = -self.grad[i];
                }
                self.solve_free(nf);
            }
            // Largest feasible step along p (p = 0 on bound variables).
            let mut alpha = 1.0;
            let mut blocking = None;
            let mut step_norm = 0.0_f64;
            for (a, &i) in self.free.iter().enumerate() {
                let p = self.rhs[a];
                step_norm = step_norm.max(p.abs());
                if p < 0.0 && lo[i].is_finite() {
                    let t = (lo[i] - z[i]) / p;
                    if t < alpha {
                        alpha = t.max(0.0);
                        blocking = Some((i, Bound::Lower));
                    }
                } else if p > 0.0 && hi[i].is_finite() {
                    let t = (hi[i] - z[i]) / p;
                    if t < alpha {
                        alpha = t.max(0.0);
                        blocking = Some((i, Bound::Upper));
                    }
                }
            }
            let scale = z.iter().take(n).fold(1.0_f64, |s, v| s.max(v.abs()));
            if step_norm > 1e-14 * scale {
                for (a, &i) in self.free.iter().enumerate() {
                    z[i] += alpha * self.rhs[a];
                }
                if let Some((i, side)) = blocking {
                    z[i] = if side == Bound::Lower { lo[i] } else { hi[i] };
                    self.state[i] = side;
                }
                self.gradient(h, b, z);
                if blocking.is_some() {
                    continue;
                }
            }
            // At the minimiser on the current face: free the bound with the worst multiplier.
            let mut worst = None;
            let mut worst_value = 0.0;
            let gscale = b.iter().take(n).fold(1.0_f64, |s, v| s.max(v.abs()));
            for i in 0..n {
                let violation = match self.state[i] {
                    Bound::Lower => -self.grad[i],
                    Bound::Upper => self.grad[i],
                    Bound::Free => continue,
                };
                if violation > worst_value && violation > 1e-13 * gscale {
                    worst_value = violation;
                    worst = Some(i);
                }
            }
            match worst {
                Some(i) => self.state[i] = Bound::Free,
                None => return self.outcome(BoxQpStatus::Optimal, iterations, n),
            }
        }
    }

    fn outcome(&self, status: BoxQpStatus, iterations: usize, n: usize) -> BoxQpOutcome {
        let active = self.state[..n].iter().filter(|s| **s != Bound::Free).count();
        BoxQpOutcome { status, iterations, active }
    }

    fn gradient(&mut self, h: &[f64], b: &[f64], z: &[f64]) {
        let n = z.len();
        for i in 0..n {
            self.grad[i] = -b[i];
        }
        // Lower triangle only: H_ij for i ≥ j at h[j n + i].
        for j in 0..n {
            let zj = z[j];
            self.grad[j] += h[j * n + j] * zj;
            for i in j + 1..n {
                let hij = h[j * n + i];
                self.grad[i] += hij * zj;
                self.grad[j] += hij * z[i];
            }
        }
    }

    /// Cholesky factor of `H_FF` into `chol` (column-major `nf × nf`, lower); false if `H_FF` is
    /// not positive definite to working precision (the workspace's pivot rule).
    fn factor_free(&mut self, h: &[f64], n: usize) -> bool {
        let nf = self.free.len();
        for (cb, &j) in self.free.iter().enumerate() {
            for (ca, &i) in self.free.iter().enumerate().skip(cb) {
                self.chol[cb * nf + ca] = h[j * n + i];
            }
        }
        dense_kernels::cholesky_slice(&mut self.chol, nf).is_ok()
    }

    /// `rhs ← (L Lᵀ)⁻¹ rhs` with the factor in `chol`.
    fn solve_free(&mut self, nf: usize) {
        dense_kernels::cholesky_solve(&self.chol, nf, &mut self.rhs[..nf]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spd(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let a: Vec<f64> = (0..n * n).map(|_| rnd()).collect();
        let mut h = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                h[j * n + i] =
                    (0..n).map(|k| a[k * n + i] * a[k * n + j]).sum::<f64>() + if i == j { 0.1 } else { 0.0 };
            }
        }
        h
    }

    /// KKT residual: projected gradient norm.
    fn kkt(h: &[f64], b: &[f64], lo: &[f64], hi: &[f64], z: &[f64]) -> f64 {
        let n = z.len();
        let mut worst = 0.0_f64;
        for i in 0..n {
            let g: f64 = (0..n).map(|j| h[j * n + i] * z[j]).sum::<f64>() - b[i];
            let pg = (z[i] - g).clamp(lo[i], hi[i]) - z[i];
            worst = worst.max(pg.abs());
            assert!(z[i] >= lo[i] && z[i] <= hi[i]);
        }
        worst
    }

    #[test]
    fn unconstrained_problem_is_a_linear_solve() {
        let n = 6;
        let h = spd(n, 1);
        let x_true: Vec<f64> = (0..n).map(|i| i as f64 - 2.5).collect();
        let b: Vec<f64> = (0..n).map(|i| (0..n).map(|j| h[j * n + i] * x_true[j]).sum()).collect();
        let mut qp = BoxQp::new(n);
        let mut z = vec![0.0; n];
        let inf = vec![f64::INFINITY; n];
        let minf = vec![f64::NEG_INFINITY; n];
        let o = qp.solve(&h, &b, &minf, &inf, &mut z, 50, false);
        assert_eq!(o.status, BoxQpStatus::Optimal);
        for i in 0..n {
            assert!((z[i] - x_true[i]).abs() < 1e-10);
        }
    }

    #[test]
    fn random_boxes_satisfy_kkt_from_any_warm_start() {
        for seed in 0..200 {
            let n = 1 + (seed as usize % 28);
            let h = spd(n, seed);
            let b: Vec<f64> = (0..n).map(|i| ((i * 7 + seed as usize) % 11) as f64 - 5.0).collect();
            let lo: Vec<f64> = (0..n).map(|i| if i % 3 == 0 { f64::NEG_INFINITY } else { -0.5 }).collect();
            let hi: Vec<f64> = (0..n).map(|i| if i % 5 == 0 { f64::INFINITY } else { 0.3 }).collect();
            let mut qp = BoxQp::new(28);
            for start in [0.0, 10.0, -10.0] {
                let mut z = vec![start; n];
                let o = qp.solve(&h, &b, &lo, &hi, &mut z, 500, false);
                assert_eq!(o.status, BoxQpStatus::Optimal, "seed {seed}");
                assert!(kkt(&h, &b, &lo, &hi, &z) < 1e-9, "seed {seed}: {}", kkt(&h, &b, &lo, &hi, &z));
            }
        }
    }

    #[test]
    fn reusing_the_factor_for_a_new_linear_term_gives_the_fresh_solution() {
        let n = 12;
        let h = spd(n, 77);
        let lo = vec![-0.2; n];
        let hi = vec![0.2; n];
        let mut reused = BoxQp::new(n);
        let mut z = vec![0.0; n];
        for k in 0..20 {
            let b: Vec<f64> =
                (0..n).map(|i| ((i * 3 + k) as f64 * 0.7).sin() * if k % 4 == 0 { 0.01 } else { 3.0 }).collect();
            let o = reused.solve(&h, &b, &lo, &hi, &mut z, 500, k > 0);
            assert_eq!(o.status, BoxQpStatus::Optimal);
            let mut fresh = vec![0.0; n];
            BoxQp::new(n).solve(&h, &b, &lo, &hi, &mut fresh, 500, false);
            for i in 0..n {
                assert!((z[i] - fresh[i]).abs() < 1e-10, "k {k}");
            }
        }
    }

    #[test]
    fn an_indefinite_hessian_is_reported() {
        let h = vec![1.0, 0.0, 0.0, -1.0];
        let mut z = vec![0.0; 2];
        let o = BoxQp::new(2).solve(&h, &[1.0, 1.0], &[-1.0; 2], &[1.0; 2], &mut z, 10, false);
        assert_eq!(o.status, BoxQpStatus::NotConvex);
    }
}
