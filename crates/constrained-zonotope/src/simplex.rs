//! A dense bounded-variable primal simplex for the factor LPs `min qᵀ ξ  s.t.  A ξ = b,
//! −1 ≤ ξ ≤ 1` (few constraints, many boxed variables), warm-started across the `2n` objectives
//! of one hull: the basis of one optimum is feasible for the next objective, so only phase 2 runs
//! again. Hand-written because the hull solves many tiny LPs on the same constraints, where an
//! interior-point solver's per-solve setup dominates (Clarabel: ~1 ms per LP on the six-tank
//! sets); its answers are proposals, verified by the caller like Clarabel's (crate documentation),
//! and Clarabel remains the fallback when it stops.
//!
//! The basis inverse is kept explicitly (`n_c × n_c`, a few rows) and updated by the pivot's
//! elementary row operations, refactorised from scratch every [`REFACTOR_EVERY`] pivots and
//! before an optimum is declared, so rounding drift cannot accumulate into the answer. After
//! [`Simplex::new`] nothing allocates but the returned vectors.

use nalgebra::{DMatrix, DVector};

/// Where a nonbasic variable sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum At {
    Lower,
    Upper,
}

/// The simplex over `[A diag(sign)]` (factors, then one artificial per row).
#[derive(Debug, Clone)]
pub(crate) struct Simplex {
    ng: usize,
    b: DVector<f64>,
    b_scale: f64,
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// Column `j` of `[A diag(sign)]`.
    cols: DMatrix<f64>,
    /// Its transpose (rows of `[A diag(sign)]` as columns, for pricing).
    rows: DMatrix<f64>,
    basis: Vec<usize>,
    basic: Vec<bool>,
    at: Vec<At>,
    /// Values of the nonbasic variables (at a bound).
    x: Vec<f64>,
    /// Values of the basic variables, in basis order.
    xb: Vec<f64>,
    binv: DMatrix<f64>,
    /// Scratch for refactorisation.
    work: DMatrix<f64>,
    cost: Vec<f64>,
    y: Vec<f64>,
    d: Vec<f64>,
    w: Vec<f64>,
    pivots_since_refactor: usize,
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
/// Pivots between refactorisations of the basis inverse.
const REFACTOR_EVERY: usize = 24;

/// `inv ← m⁻¹` by Gauss–Jordan elimination with partial pivoting (`m` is overwritten);
/// `false` when `m` is numerically singular.
fn invert(m: &mut DMatrix<f64>, inv: &mut DMatrix<f64>) -> bool {
    let n = m.nrows();
    inv.fill(0.0);
    inv.fill_diagonal(1.0);
    let scale = m.amax();
    if !(scale.is_finite() && scale > 0.0) {
        return n == 0;
    }
    for k in 0..n {
        let Some(p) = (k..n).max_by(|&i, &j| m[(i, k)].abs().total_cmp(&m[(j, k)].abs())) else { return false };
        let pivot = m[(p, k)];
        if pivot.abs() <= 1e-13 * scale {
            return false;
        }
        if p != k {
            m.swap_rows(p, k);
            inv.swap_rows(p, k);
        }
        for j in 0..n {
            m[(k, j)] /= pivot;
            inv[(k, j)] /= pivot;
        }
        for i in (0..n).filter(|&i| i != k) {
            let f = m[(i, k)];
            if f != 0.0 {
                for j in 0..n {
                    m[(i, j)] -= f * m[(k, j)];
                    inv[(i, j)] -= f * inv[(k, j)];
                }
            }
        }
    }
    true
}

impl Simplex {
    /// The constraints `A ξ = b`, `‖ξ‖∞ ≤ 1`; phase 1 runs on the first solve.
    pub(crate) fn new(a: &DMatrix<f64>, b: &DVector<f64>) -> Self {
        let (nc, ng) = (a.nrows(), a.ncols());
        let total = ng + nc;
        // Start: every factor at −1; the artificials take the residual b + A·1 with its sign.
        let mut r = b.clone();
        for j in 0..ng {
            for i in 0..nc {
                r[i] += a[(i, j)];
            }
        }
        let mut cols = DMatrix::zeros(nc, total);
        cols.columns_mut(0, ng).copy_from(a);
        for i in 0..nc {
            cols[(i, ng + i)] = if r[i] >= 0.0 { 1.0 } else { -1.0 };
        }
        let mut x = vec![-1.0; total];
        let mut lo = vec![-1.0; total];
        let mut hi = vec![1.0; total];
        for i in 0..nc {
            x[ng + i] = 0.0;
            lo[ng + i] = 0.0;
            hi[ng + i] = f64::INFINITY;
        }
        let mut basic = vec![false; total];
        basic[ng..].iter_mut().for_each(|v| *v = true);
        Self {
            ng,
            b: b.clone(),
            b_scale: 1.0 + b.amax() + a.amax() * ng as f64,
            lo,
            hi,
            rows: cols.transpose(),
            cols,
            basis: (ng..total).collect(),
            basic,
            at: vec![At::Lower; total],
            x,
            xb: r.iter().map(|v| v.abs()).collect(),
            binv: DMatrix::zeros(nc, nc),
            work: DMatrix::zeros(nc, nc),
            cost: vec![0.0; total],
            y: vec![0.0; nc],
            d: vec![0.0; total],
            w: vec![0.0; nc],
            pivots_since_refactor: usize::MAX,
            feasible: false,
        }
    }

    /// The basis inverse from scratch and `x_B = B⁻¹ (b − N x_N)`.
    fn refactor(&mut self) -> bool {
        let nc = self.basis.len();
        for (k, &j) in self.basis.iter().enumerate() {
            for i in 0..nc {
                self.work[(i, k)] = self.cols[(i, j)];
            }
        }
        if !invert(&mut self.work, &mut self.binv) {
            return false;
        }
        self.basic_values();
        self.pivots_since_refactor = 0;
        true
    }

    /// `x_B = B⁻¹ (b − N x_N)` with the current inverse.
    fn basic_values(&mut self) {
        let nc = self.basis.len();
        // w ← b − N x_N (w as scratch), then x_B = B⁻¹ w.
        self.w.copy_from_slice(self.b.as_slice());
        for j in (0..self.cols.ncols()).filter(|&j| !self.basic[j]) {
            let v = self.x[j];
            if v != 0.0 {
                for i in 0..nc {
                    self.w[i] -= self.cols[(i, j)] * v;
                }
            }
        }
        for k in 0..nc {
            self.xb[k] = (0..nc).map(|i| self.binv[(k, i)] * self.w[i]).sum();
        }
    }

    /// The duals `y = B⁻ᵀ c_B` and the reduced costs of the nonbasic variables.
    fn price(&mut self) {
        let nc = self.basis.len();
        for i in 0..nc {
            let column = self.binv.column(i);
            self.y[i] = column.iter().zip(&self.basis).map(|(v, &j)| v * self.cost[j]).sum();
        }
        // d = c − Aᵀ y as axpys over the rows of A (contiguous in `rows`, independent per entry:
        // a column dot product is bound by the latency of its additions).
        self.d.copy_from_slice(&self.cost);
        for (i, row) in self.rows.column_iter().enumerate() {
            let yi = self.y[i];
            if yi != 0.0 {
                self.d.iter_mut().zip(row.iter()).for_each(|(d, a)| *d -= a * yi);
            }
        }
        for j in 0..self.d.len() {
            if self.basic[j] || self.lo[j] == self.hi[j] {
                self.d[j] = 0.0;
            }
        }
    }

    /// The improving nonbasic variable (Dantzig's rule, or Bland's first index).
    fn entering(&self, bland: bool) -> Option<usize> {
        let mut enter: Option<(usize, f64)> = None;
        for j in (0..self.cols.ncols()).filter(|&j| !self.basic[j]) {
            let d = self.d[j];
            let improving = match self.at[j] {
                At::Lower => d < -TOL,
                At::Upper => d > TOL,
            };
            if improving && enter.is_none_or(|(_, best)| !bland && d.abs() > best) {
                enter = Some((j, d.abs()));
                if bland {
                    break;
                }
            }
        }
        enter.map(|(j, _)| j)
    }

    /// Minimises `self.cost` from the current basis. Between basis changes the duals stay valid,
    /// so every bound flip (an entering variable that crosses its box before any basic variable
    /// reaches a bound) costs one column solve.
    fn optimise(&mut self) -> Result<(), ()> {
        let nc = self.basis.len();
        let total = self.cols.ncols();
        let max_iter = 50 + 20 * total;
        let mut degenerate = 0usize;
        // The inverse is fresh when no pivot followed the last factorisation (the previous
        // objective's optimum): only the basic values are recomputed (bound flips and fixed
        // artificials moved the nonbasic ones).
        if self.pivots_since_refactor == 0 {
            self.basic_values();
        } else if !self.refactor() {
            return Err(());
        }
        self.price();
        for _ in 0..max_iter {
            let Some(j) = self.entering(degenerate > 2 * total) else {
                if self.pivots_since_refactor == 0 {
                    return Ok(());
                }
                // Declare the optimum on a fresh factorisation only.
                if !self.refactor() {
                    return Err(());
                }
                self.price();
                continue;
            };
            let dir = if self.at[j] == At::Lower { 1.0 } else { -1.0 };
            // w = B⁻¹ a_j, by columns of B⁻¹ (contiguous).
            self.w.iter_mut().for_each(|v| *v = 0.0);
            for (i, &a) in self.cols.column(j).iter().enumerate() {
                if a != 0.0 {
                    self.w.iter_mut().zip(self.binv.column(i).iter()).for_each(|(w, b)| *w += b * a);
                }
            }
            let wmax = self.w.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            let mut t = self.hi[j] - self.lo[j];
            let mut leave: Option<(usize, At)> = None;
            for k in 0..nc {
                let wk = dir * self.w[k];
                let jb = self.basis[k];
                if wk > TOL * wmax {
                    let s = (self.xb[k] - self.lo[jb]).max(0.0) / wk;
                    if s < t {
                        t = s;
                        leave = Some((k, At::Lower));
                    }
                } else if wk < -TOL * wmax && self.hi[jb].is_finite() {
                    let s = (self.hi[jb] - self.xb[k]).max(0.0) / -wk;
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
            for k in 0..nc {
                self.xb[k] -= dir * t * self.w[k];
            }
            match leave {
                None => {
                    // A bound flip: the basis, its inverse and the duals stay.
                    self.at[j] = if self.at[j] == At::Lower { At::Upper } else { At::Lower };
                    self.x[j] = if self.at[j] == At::Lower { self.lo[j] } else { self.hi[j] };
                }
                Some((k, side)) => {
                    let jb = self.basis[k];
                    self.at[jb] = side;
                    self.x[jb] = if side == At::Lower { self.lo[jb] } else { self.hi[jb] };
                    self.basic[jb] = false;
                    self.basic[j] = true;
                    self.basis[k] = j;
                    self.xb[k] = self.x[j] + dir * t;
                    // B⁻¹ ← E B⁻¹: row k divided by w_k, eliminated from the other rows.
                    let wk = self.w[k];
                    for i in 0..nc {
                        self.binv[(k, i)] /= wk;
                    }
                    for r in (0..nc).filter(|&r| r != k) {
                        let f = self.w[r];
                        if f != 0.0 {
                            for i in 0..nc {
                                self.binv[(r, i)] -= f * self.binv[(k, i)];
                            }
                        }
                    }
                    self.pivots_since_refactor += 1;
                    if self.pivots_since_refactor >= REFACTOR_EVERY && !self.refactor() {
                        return Err(());
                    }
                    self.price();
                }
            }
        }
        Err(())
    }

    /// Solves `min qᵀ ξ` (phase 1 first, once).
    pub(crate) fn solve(&mut self, q: &[f64]) -> SimplexResult {
        let (nc, ng) = (self.basis.len(), self.ng);
        if !self.feasible {
            self.cost[..ng].iter_mut().for_each(|c| *c = 0.0);
            self.cost[ng..].iter_mut().for_each(|c| *c = 1.0);
            if self.optimise().is_err() {
                return SimplexResult::Stopped;
            }
            let infeasibility: f64 = (0..nc)
                .map(|k| if self.basis[k] >= ng { self.xb[k] } else { 0.0 })
                .chain((ng..ng + nc).filter(|&j| !self.basic[j]).map(|j| self.x[j]))
                .sum();
            if infeasibility > 1e-9 * self.b_scale {
                return SimplexResult::Infeasible { y: self.y.clone() };
            }
            // The artificials are fixed at 0 from now on.
            for j in ng..ng + nc {
                self.hi[j] = 0.0;
                if !self.basic[j] {
                    self.x[j] = 0.0;
                    self.at[j] = At::Lower;
                }
            }
            self.feasible = true;
        }
        self.cost[..ng].copy_from_slice(q);
        self.cost[ng..].iter_mut().for_each(|c| *c = 0.0);
        match self.optimise() {
            Ok(()) => {
                let mut xi = self.x[..ng].to_vec();
                for (k, &j) in self.basis.iter().enumerate() {
                    if j < ng {
                        xi[j] = self.xb[k];
                    }
                }
                SimplexResult::Optimal { y: self.y.clone(), xi }
            }
            Err(()) => SimplexResult::Stopped,
        }
    }
}
