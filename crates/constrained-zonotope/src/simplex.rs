//! A dense bounded-variable primal simplex for the factor LPs `min qᵀ ξ  s.t.  A ξ = b,
//! −1 ≤ ξ ≤ 1` (few constraints, many boxed variables), warm-started across the `2n` objectives
//! of one hull: the basis of one optimum is feasible for the next objective, so only phase 2 runs
//! again. Hand-written because the hull solves many tiny LPs on the same constraints, where an
//! interior-point solver's per-solve setup dominates (Clarabel: ~1 ms per LP on the six-tank
//! sets); its answers are proposals, verified by the caller like Clarabel's (crate documentation),
//! and Clarabel remains the fallback when it stops.

use nalgebra::{DMatrix, DVector};

/// Where a nonbasic variable sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum At {
    Lower,
    Upper,
}

/// The simplex over `[A I]` (factors, then one artificial per row).
#[derive(Debug, Clone)]
pub(crate) struct Simplex {
    a: DMatrix<f64>,
    b: DVector<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// Column `j` of `[A diag(sign)]`.
    cols: DMatrix<f64>,
    basis: Vec<usize>,
    at: Vec<At>,
    x: Vec<f64>,
    feasible: bool,
}

/// How a solve ended.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum SimplexResult {
    /// Optimal: the duals `y` of `A ξ = b` and the point `ξ`.
    Optimal { y: Vec<f64>, xi: Vec<f64> },
    /// Phase 1 ended above zero: the duals of phase 1 (a proposed Farkas vector).
    Infeasible { y: Vec<f64> },
    /// Iteration limit or a singular basis.
    Stopped,
}

const TOL: f64 = 1e-9;

impl Simplex {
    /// The constraints `A ξ = b`, `‖ξ‖∞ ≤ 1`; phase 1 runs on the first solve.
    pub(crate) fn new(a: &DMatrix<f64>, b: &DVector<f64>) -> Self {
        let (nc, ng) = (a.nrows(), a.ncols());
        // Start: every factor at −1; the artificials take the residual b + A·1 with its sign.
        let mut r = b.clone();
        for j in 0..ng {
            for i in 0..nc {
                r[i] += a[(i, j)];
            }
        }
        let mut cols = DMatrix::zeros(nc, ng + nc);
        cols.columns_mut(0, ng).copy_from(a);
        for i in 0..nc {
            cols[(i, ng + i)] = if r[i] >= 0.0 { 1.0 } else { -1.0 };
        }
        let mut x = vec![-1.0; ng + nc];
        for i in 0..nc {
            x[ng + i] = r[i].abs();
        }
        let mut lo = vec![-1.0; ng + nc];
        let mut hi = vec![1.0; ng + nc];
        for i in 0..nc {
            lo[ng + i] = 0.0;
            hi[ng + i] = f64::INFINITY;
        }
        Self {
            a: a.clone(),
            b: b.clone(),
            lo,
            hi,
            cols,
            basis: (ng..ng + nc).collect(),
            at: vec![At::Lower; ng + nc],
            x,
            feasible: false,
        }
    }

    fn ng(&self) -> usize {
        self.a.ncols()
    }

    /// Minimises `cost` over the current constraints from the current basis. Between basis
    /// changes the factorisation and the duals stay valid, so every bound flip (an entering
    /// variable that crosses its box before any basic variable reaches a bound) is taken at the
    /// price of one column solve.
    fn optimise(&mut self, cost: &[f64]) -> Result<Vec<f64>, ()> {
        let nc = self.a.nrows();
        let total = self.cols.ncols();
        let max_iter = 50 + 20 * total;
        let mut degenerate = 0usize;
        let mut basic = vec![false; total];
        let mut d = vec![0.0; total];
        for _ in 0..max_iter {
            basic.iter_mut().for_each(|v| *v = false);
            for &j in &self.basis {
                basic[j] = true;
            }
            let bmat = self.cols.select_columns(&self.basis);
            let lu = bmat.clone().lu();
            // x_B = B⁻¹ (b − N x_N).
            let mut rhs = self.b.clone();
            for j in (0..total).filter(|&j| !basic[j]) {
                let v = self.x[j];
                if v != 0.0 {
                    for i in 0..nc {
                        rhs[i] -= self.cols[(i, j)] * v;
                    }
                }
            }
            let mut xb = lu.solve(&rhs).ok_or(())?;
            let cb = DVector::from_iterator(nc, self.basis.iter().map(|&j| cost[j]));
            let y = bmat.transpose().lu().solve(&cb).ok_or(())?;
            for j in 0..total {
                d[j] = if basic[j] || self.lo[j] == self.hi[j] { 0.0 } else { cost[j] - self.cols.column(j).dot(&y) };
            }
            // Entering variables until the basis changes: Dantzig's rule, Bland's after many
            // degenerate pivots.
            let bland = degenerate > 2 * total;
            let mut changed = false;
            loop {
                let mut enter: Option<(usize, f64)> = None;
                for j in (0..total).filter(|&j| !basic[j]) {
                    let improving = match self.at[j] {
                        At::Lower => d[j] < -TOL,
                        At::Upper => d[j] > TOL,
                    };
                    if improving && enter.is_none_or(|(_, best)| !bland && d[j].abs() > best) {
                        enter = Some((j, d[j].abs()));
                        if bland {
                            break;
                        }
                    }
                }
                let Some((j, _)) = enter else { break };
                let dir = if self.at[j] == At::Lower { 1.0 } else { -1.0 };
                let w = lu.solve(&self.cols.column(j).into_owned()).ok_or(())?;
                let wmax = w.amax().max(1.0);
                let mut t = self.hi[j] - self.lo[j];
                let mut leave: Option<(usize, At)> = None;
                for k in 0..nc {
                    let wk = dir * w[k];
                    let jb = self.basis[k];
                    if wk > TOL * wmax {
                        let s = (xb[k] - self.lo[jb]).max(0.0) / wk;
                        if s < t {
                            t = s;
                            leave = Some((k, At::Lower));
                        }
                    } else if wk < -TOL * wmax && self.hi[jb].is_finite() {
                        let s = (self.hi[jb] - xb[k]).max(0.0) / -wk;
                        if s < t {
                            t = s;
                            leave = Some((k, At::Upper));
                        }
                    }
                }
                if !t.is_finite() {
                    return Err(());
                }
                degenerate = if t <= TOL { degenerate + 1 } else { 0 };
                match leave {
                    None => {
                        // A bound flip: the basis, its factorisation and the duals stay.
                        xb.axpy(-dir * t, &w, 1.0);
                        self.at[j] = if self.at[j] == At::Lower { At::Upper } else { At::Lower };
                        self.x[j] = if self.at[j] == At::Lower { self.lo[j] } else { self.hi[j] };
                    }
                    Some((k, side)) => {
                        let jb = self.basis[k];
                        self.at[jb] = side;
                        self.x[jb] = if side == At::Lower { self.lo[jb] } else { self.hi[jb] };
                        self.basis[k] = j;
                        self.x[j] += dir * t;
                        changed = true;
                        break;
                    }
                }
            }
            if !changed {
                for (k, &j) in self.basis.iter().enumerate() {
                    self.x[j] = xb[k];
                }
                return Ok(y.iter().copied().collect());
            }
        }
        Err(())
    }

    /// Solves `min qᵀ ξ` (phase 1 first, once).
    pub(crate) fn solve(&mut self, q: &[f64]) -> SimplexResult {
        let (nc, ng) = (self.a.nrows(), self.ng());
        if !self.feasible {
            let mut cost = vec![0.0; ng + nc];
            cost[ng..].iter_mut().for_each(|c| *c = 1.0);
            let Ok(y) = self.optimise(&cost) else { return SimplexResult::Stopped };
            let infeasibility: f64 = self.x[ng..].iter().sum();
            let scale = 1.0 + self.b.amax() + self.a.amax() * ng as f64;
            if infeasibility > 1e-9 * scale {
                return SimplexResult::Infeasible { y };
            }
            // The artificials are fixed at 0 from now on.
            for i in 0..nc {
                self.hi[ng + i] = 0.0;
                self.x[ng + i] = 0.0;
                if !self.basis.contains(&(ng + i)) {
                    self.at[ng + i] = At::Lower;
                }
            }
            self.feasible = true;
        }
        let mut cost = vec![0.0; ng + nc];
        cost[..ng].copy_from_slice(q);
        match self.optimise(&cost) {
            Ok(y) => SimplexResult::Optimal { y, xi: self.x[..ng].to_vec() },
            Err(()) => SimplexResult::Stopped,
        }
    }
}
