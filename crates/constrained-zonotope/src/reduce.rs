//! Order reduction (docs/constrained-zonotopes.md (Z4)–(Z6)), as in Scott et al. (2016, §4) and
//! CORA's `conZonotope/reduceConstraints`:
//!
//! 1. **Rescaling** (Z4): interval constraint propagation over `A ξ = b` gives, for every factor,
//!    the range `E_j ⊆ [−1, 1]` it can take in the set and the range `R_j` that the constraints
//!    alone imply for it (its own bound ignored); `ξ_j = m_j + r_j ξ'_j` maps `E_j` onto
//!    `[−1, 1]` (the same set in exact arithmetic).
//! 2. **Constraint elimination** (Z5): while there are too many constraints, one factor is
//!    solved for from one row and substituted; the set can only grow (the factor's own bound is
//!    dropped), by nothing when `R_j ⊆ E_j`. The factor is the one with the least estimate of
//!    the Hausdorff error `H_j = ρ_j² / (K⁻¹)_jj`, `ρ_j = max(0, |R'_j| − 1)` its range's excess
//!    and `K = [[GᵀG + I, Aᵀ], [A, 0]]` (CORA's measure: the least-norm move of the factors that
//!    keeps `A ξ = b` and moves `ξ_j` by `ρ_j`); the row is the one where the factor's
//!    coefficient is largest in magnitude (CORA takes the first), for a well-conditioned pivot.
//! 3. **Generator reduction** (Z6): the lifted zonotope `⟨[c; −b], [G; A]⟩` keeps its largest
//!    columns (2-norm, Combastel's order) and encloses the rest in a box, whose constraint rows
//!    become slack factors: a superset, and at most `max_generators` factors.
//!
//! Every new entry's rounding is enclosed as in the other operations.

use nalgebra::{DMatrix, DVector};

use intervals::{Interval, down, up};

use crate::enclose::{add_up, dot_error};
use crate::{ConstrainedZonotope, SetError};

/// The most generators and constraints a reduced set keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReductionLimits {
    max_generators: usize,
    max_constraints: usize,
}

impl ReductionLimits {
    /// At most `max_generators` factors and `max_constraints` constraints. A set of dimension
    /// `n` can be reduced only when `max_generators ≥ n + max_constraints` (checked by
    /// [`ConstrainedZonotope::reduce`]).
    ///
    /// # Errors
    /// [`SetError::InvalidLimits`] for `max_generators = 0` or limits above the set size limits.
    pub fn new(max_generators: usize, max_constraints: usize) -> Result<Self, SetError> {
        if max_generators == 0 {
            return Err(SetError::InvalidLimits("max_generators must be at least 1".into()));
        }
        crate::check_size("max_generators", max_generators, crate::MAX_GENERATORS)?;
        crate::check_size("max_constraints", max_constraints, crate::MAX_CONSTRAINTS)?;
        Ok(Self { max_generators, max_constraints })
    }

    /// The most factors.
    #[must_use]
    pub fn max_generators(&self) -> usize {
        self.max_generators
    }

    /// The most constraints.
    #[must_use]
    pub fn max_constraints(&self) -> usize {
        self.max_constraints
    }
}

/// Factor ranges from interval constraint propagation: `e` the ranges within the box, `r` the
/// ranges the constraints alone imply (`ENTIRE` for a factor in no constraint).
pub(crate) struct FactorRanges {
    pub(crate) e: Vec<Interval>,
    pub(crate) r: Vec<Interval>,
}

/// Below this a positive excess `ρ` might give `H = ρ² / (K⁻¹)_jj = 0` by underflow (the KKT
/// diagonal entry is held to at most 1, so `ρ ≥ 10⁻¹⁴⁷` gives `H ≥ ρ² ≥ 10⁻²⁹⁴`, a normal
/// number; the crude measure `ρ² (1 + ‖g_j‖²)` only grows).
const TINY_EXCESS: f64 = 1e-147;

/// Sweeps of the propagation (each visits every row once).
const PROPAGATION_SWEEPS: usize = 3;

/// Interval constraint propagation over `A ξ = b, ‖ξ‖∞ ≤ 1`; `None` when it proves the set empty
/// (a range became empty: certified, the arithmetic is outward-rounded).
pub(crate) fn propagate(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<FactorRanges> {
    let (nc, ng) = (a.nrows(), a.ncols());
    let mut e = vec![Interval::new(-1.0, 1.0); ng];
    let mut r = vec![Interval::ENTIRE; ng];
    let mut terms = vec![Interval::ZERO; ng];
    // A row whose factors have not narrowed since its last visit began would imply what it
    // implied then, which the ranges already hold: it is skipped (the same ranges, fewer visits).
    // `tick` counts events; `seen[i]` is the tick at which row i's last visit began,
    // `narrowed[j]` the tick at which `E_j` last narrowed (after the visit's start even when the
    // visit itself narrowed it: its sums were taken before).
    let (mut tick, mut narrowed, mut seen) = (1_usize, vec![1_usize; ng], vec![0_usize; nc]);
    for _ in 0..PROPAGATION_SWEEPS {
        let mut changed = false;
        for i in 0..nc {
            if (0..ng).all(|k| narrowed[k] <= seen[i] || a[(i, k)] == 0.0) {
                continue;
            }
            tick += 1;
            seen[i] = tick;
            // Σ_k a_ik E_k as a lower and an upper sum of the terms' bounds.
            let (mut lo, mut hi) = (0.0, 0.0);
            for k in 0..ng {
                let t = e[k] * a[(i, k)];
                lo = down(lo + t.lo());
                hi = up(hi + t.hi());
                terms[k] = t;
            }
            for j in 0..ng {
                let aij = a[(i, j)];
                if aij == 0.0 {
                    continue;
                }
                let rest = Interval::new(down(lo - terms[j].lo()), up(hi - terms[j].hi()));
                let implied = (Interval::point(b[i]) - rest) / aij;
                if !implied.is_bounded() {
                    continue;
                }
                let r_new = r[j].meet(implied)?;
                r[j] = r_new;
                let e_new = e[j].meet(implied)?;
                if e_new != e[j] {
                    changed = true;
                    e[j] = e_new;
                    tick += 1;
                    narrowed[j] = tick;
                }
            }
        }
        if !changed {
            break;
        }
    }
    Some(FactorRanges { e, r })
}

/// The diagonal of the top-left block of `K⁻¹`, `K = [[H, Aᵀ], [A, 0]]`, `H = I + GᵀG`, in the
/// low-rank form that costs `O(n_g (n + n_c)²)` instead of `O((n_g + n_c)³)`:
/// `H⁻¹ = I − Gᵀ (I + G Gᵀ)⁻¹ G` (Woodbury), `U = H⁻¹ Aᵀ`, `S = A U`, and
/// `(K⁻¹)_jj = (H⁻¹)_jj − u_jᵀ S⁻¹ u_j` (`u_j` the row `j` of `U`). `NaN` entries when a factor
/// is singular (the caller falls back to a cruder measure).
fn kkt_inverse_diagonal(g: &DMatrix<f64>, a: &DMatrix<f64>) -> Vec<f64> {
    let (n, ng, nc) = (g.nrows(), g.ncols(), a.nrows());
    let singular = || vec![f64::NAN; ng];
    // One buffer: L (n × n, the Cholesky factor of I + G Gᵀ), Z = (I + G Gᵀ)⁻¹ G (n × ng),
    // G Aᵀ (n × nc), U (ng × nc), S and its inverse (nc × nc each), column-major.
    let mut buf = vec![0.0; n * n + n * ng + n * nc + ng * nc + 2 * nc * nc];
    let (l, rest) = buf.split_at_mut(n * n);
    let (z, rest) = rest.split_at_mut(n * ng);
    let (gat, rest) = rest.split_at_mut(n * nc);
    let (u, rest) = rest.split_at_mut(ng * nc);
    let (sm, sinv) = rest.split_at_mut(nc * nc);
    // The lower triangle of I + G Gᵀ, factorised with any positive pivot: its eigenvalues are at
    // least 1, so only an overflow can make it fail.
    for c in 0..n {
        for r in c..n {
            let mut v = if r == c { 1.0 } else { 0.0 };
            for j in 0..ng {
                v += g[(r, j)] * g[(c, j)];
            }
            l[r + c * n] = v;
        }
    }
    if dense_kernels::cholesky_slice_with(l, n, 0.0).is_err() {
        return singular();
    }
    // Z's columns by forward and back substitution; H⁻¹'s diagonal 1 − g_jᵀ z_j (Woodbury).
    z.copy_from_slice(g.as_slice());
    dense_kernels::cholesky_solve(l, n, z);
    let mut diag: Vec<f64> = (0..ng).map(|j| 1.0 - (0..n).map(|r| g[(r, j)] * z[r + j * n]).sum::<f64>()).collect();
    if nc == 0 {
        return diag;
    }
    // U = H⁻¹ Aᵀ = Aᵀ − Zᵀ (G Aᵀ); S = A U.
    for c in 0..nc {
        for r in 0..n {
            gat[r + c * n] = (0..ng).map(|j| g[(r, j)] * a[(c, j)]).sum();
        }
    }
    for c in 0..nc {
        for j in 0..ng {
            u[j + c * ng] = a[(c, j)] - (0..n).map(|k| z[k + j * n] * gat[k + c * n]).sum::<f64>();
        }
    }
    for c in 0..nc {
        for r in 0..nc {
            sm[r + c * nc] = (0..ng).map(|j| a[(r, j)] * u[j + c * ng]).sum();
        }
    }
    if !invert_in_place(sm, sinv, nc) {
        return singular();
    }
    for (j, dj) in diag.iter_mut().enumerate() {
        let mut q = 0.0;
        for c in 0..nc {
            let sc: f64 = (0..nc).map(|r| sinv[r + c * nc] * u[j + r * ng]).sum();
            q += u[j + c * ng] * sc;
        }
        *dj -= q;
    }
    diag
}

/// `inv ← m⁻¹` (`k × k`, column-major) by Gauss–Jordan elimination with partial pivoting; `m` is
/// overwritten. `false` on a zero or non-finite pivot.
fn invert_in_place(m: &mut [f64], inv: &mut [f64], k: usize) -> bool {
    inv.fill(0.0);
    for i in 0..k {
        inv[i + i * k] = 1.0;
    }
    for c in 0..k {
        let Some(p) = (c..k).max_by(|&x, &y| m[x + c * k].abs().total_cmp(&m[y + c * k].abs())) else {
            return false;
        };
        let pivot = m[p + c * k];
        if pivot == 0.0 || !pivot.is_finite() {
            return false;
        }
        if p != c {
            for j in 0..k {
                m.swap(p + j * k, c + j * k);
                inv.swap(p + j * k, c + j * k);
            }
        }
        for j in 0..k {
            m[c + j * k] /= pivot;
            inv[c + j * k] /= pivot;
        }
        for r in (0..k).filter(|&r| r != c) {
            let f = m[r + c * k];
            if f != 0.0 {
                for j in 0..k {
                    m[r + j * k] -= f * m[c + j * k];
                    inv[r + j * k] -= f * inv[c + j * k];
                }
            }
        }
    }
    true
}

impl ConstrainedZonotope {
    /// Reduces the set to at most `limits.max_generators()` factors and
    /// `limits.max_constraints()` constraints (module documentation of the method); a set
    /// within the limits is returned as it is.
    ///
    /// # Errors
    /// [`SetError::InvalidLimits`] when `max_generators < n + max_constraints` and the set needs
    /// generator reduction; overflow of an error bound.
    pub fn reduce(&self, limits: &ReductionLimits) -> Result<Self, SetError> {
        if self.generators() <= limits.max_generators && self.constraints() <= limits.max_constraints {
            return Ok(self.clone());
        }
        let mut z = self.clone();
        while z.constraints() > limits.max_constraints {
            let Some(ranges) = propagate(&z.a, &z.b) else { break };
            z = z.rescaled(&ranges)?;
            let excess = z.range_excess(&ranges);
            let Some((row, col)) = z.elimination_choice(&excess) else { break };
            z = z.eliminate(row, col)?;
        }
        if z.constraints() > limits.max_constraints {
            // No factor could be eliminated (every column of A zero): the rows say nothing about
            // ξ beyond 0 = b and are dropped (a superset).
            z.drop_constraints(limits.max_constraints);
        }
        if z.generators() > limits.max_generators {
            let n = z.dim();
            let nc = z.constraints();
            if limits.max_generators < n + nc {
                return Err(SetError::InvalidLimits(format!(
                    "max_generators = {} is below n + constraints = {} + {}: the box of a generator reduction needs \
                     that many",
                    limits.max_generators, n, nc
                )));
            }
            z = z.reduce_generators(limits.max_generators - n - nc)?;
        }
        Ok(z)
    }

    /// The same set with every factor's range `E_j` mapped onto `[−1, 1]` (Z4).
    fn rescaled(&self, ranges: &FactorRanges) -> Result<Self, SetError> {
        let (n, nc, ng) = (self.dim(), self.constraints(), self.generators());
        let mut z = self.clone();
        let mut box_err = vec![0.0; n];
        let mut slack = vec![0.0; nc];
        // c' = c + G m, b' = b − A m: dot products of length ng + 1.
        let mids: Vec<(f64, f64)> = ranges.e.iter().map(|e| e.mid_rad()).collect();
        for i in 0..n {
            let (mut s, mut abs) = (self.c[i], self.c[i].abs());
            for j in 0..ng {
                let t = self.g[(i, j)] * mids[j].0;
                s += t;
                abs += t.abs();
            }
            z.c[i] = s;
            box_err[i] = dot_error(abs, ng + 1);
        }
        for i in 0..nc {
            let (mut s, mut abs) = (self.b[i], self.b[i].abs());
            for j in 0..ng {
                let t = self.a[(i, j)] * mids[j].0;
                s -= t;
                abs += t.abs();
            }
            z.b[i] = s;
            slack[i] = dot_error(abs, ng + 1);
        }
        // G'_j = r_j g_j, A'_j = r_j a_j: one rounding per entry.
        for j in 0..ng {
            let r = mids[j].1;
            for i in 0..n {
                let v = self.g[(i, j)] * r;
                z.g[(i, j)] = v;
                box_err[i] = add_up(box_err[i], dot_error(v.abs(), 1));
            }
            for i in 0..nc {
                let v = self.a[(i, j)] * r;
                z.a[(i, j)] = v;
                slack[i] = add_up(slack[i], dot_error(v.abs(), 1));
            }
        }
        if z.c.iter().chain(z.b.iter()).any(|v| !v.is_finite()) {
            return Err(SetError::Overflow("rescaling"));
        }
        z.push_box(&box_err)?;
        z.push_slack(&slack)?;
        Ok(z)
    }

    /// `ρ_j = max(0, |R'_j| − 1)` for the rescaled factors (the implied range mapped as `E_j`
    /// was); factors pushed by the rescaling itself (rounding) get `+∞` (never eliminated).
    fn range_excess(&self, ranges: &FactorRanges) -> Vec<f64> {
        let mut out = vec![f64::INFINITY; self.generators()];
        for (j, (e, r)) in ranges.e.iter().zip(&ranges.r).enumerate() {
            if !r.is_bounded() {
                continue;
            }
            let (m, rad) = e.mid_rad();
            if rad == 0.0 {
                // A factor fixed by the constraints: eliminating it loses nothing.
                out[j] = 0.0;
                continue;
            }
            let mag = ((r.lo() - m).abs().max((r.hi() - m).abs())) / rad;
            out[j] = (mag - 1.0).max(0.0);
        }
        out
    }

    /// The factor to eliminate and the row to solve it from, `None` when none can be.
    fn elimination_choice(&self, excess: &[f64]) -> Option<(usize, usize)> {
        let (nc, ng) = (self.constraints(), self.generators());
        let candidates: Vec<usize> =
            (0..ng).filter(|&j| excess[j].is_finite() && (0..nc).any(|i| self.a[(i, j)] != 0.0)).collect();
        if candidates.is_empty() {
            return None;
        }
        // A factor with no excess loses nothing (H_j = 0): the first such is the choice, and the
        // KKT diagonal is not needed unless an earlier candidate's excess is small enough that its
        // H_j could round to 0 as well (the same choice as the full scan, bit for bit).
        let free = candidates.iter().position(|&j| excess[j] == 0.0);
        let col = match free {
            Some(p) if candidates[..p].iter().all(|&j| excess[j] >= TINY_EXCESS) => candidates[p],
            _ => self.least_hausdorff_error(&candidates, excess, &kkt_inverse_diagonal(&self.g, &self.a))?,
        };
        self.pivot_row(col).map(|row| (row, col))
    }

    /// The candidate with the least `H_j` (the first of equals), `kinv` the KKT diagonal.
    fn least_hausdorff_error(&self, candidates: &[usize], excess: &[f64], kinv: &[f64]) -> Option<usize> {
        let mut best: Option<(f64, usize)> = None;
        for &j in candidates {
            let h = if excess[j] == 0.0 {
                0.0
            } else if kinv[j].is_finite() && kinv[j] > 0.0 {
                // (K⁻¹)_jj ≤ (H⁻¹)_jj ≤ 1 in exact arithmetic; a larger computed value is rounding
                // of an ill-conditioned S, and is held to 1 (so H_j ≥ ρ², which `TINY_EXCESS` keeps
                // above 0).
                excess[j] * excess[j] / kinv[j].min(1.0)
            } else {
                excess[j] * excess[j] * (1.0 + self.g.column(j).norm_squared())
            };
            if best.is_none_or(|(bh, _)| h < bh) {
                best = Some((h, j));
            }
        }
        best.map(|(_, j)| j)
    }

    /// The row where factor `col`'s coefficient is largest in magnitude.
    fn pivot_row(&self, col: usize) -> Option<usize> {
        let nc = self.constraints();
        (0..nc).max_by(|&p, &q| self.a[(p, col)].abs().total_cmp(&self.a[(q, col)].abs()))
    }

    /// Eliminates factor `col` with constraint `row` (Z5): `ξ_col = β − Σ_{k≠col} w_k ξ_k`,
    /// `w = a_row / a_row,col`, `β = b_row / a_row,col`; the division's rounding (at most `d`)
    /// becomes the factor that takes the freed column.
    fn eliminate(&self, row: usize, col: usize) -> Result<Self, SetError> {
        let (n, nc, ng) = (self.dim(), self.constraints(), self.generators());
        let p = self.a[(row, col)];
        let mut w = vec![0.0; ng];
        let mut d_abs = 0.0;
        for k in 0..ng {
            if k == col {
                w[k] = 1.0;
                continue;
            }
            w[k] = self.a[(row, k)] / p;
            d_abs = add_up(d_abs, w[k].abs());
        }
        let beta = self.b[row] / p;
        d_abs = add_up(d_abs, beta.abs());
        // Correctly rounded divisions: each off by at most EPS·|result| (and η below MIN_POSITIVE).
        let d = up(up(f64::EPSILON * d_abs) + (ng + 1) as f64 * f64::from_bits(1));
        let gcol: Vec<f64> = (0..n).map(|i| self.g[(i, col)]).collect();
        let acol: Vec<f64> = (0..nc).map(|i| self.a[(i, col)]).collect();
        let mut c = self.c.clone();
        let mut g = self.g.clone();
        let mut box_err = vec![0.0; n];
        for i in 0..n {
            let t = gcol[i] * beta;
            c[i] = self.c[i] + t;
            box_err[i] = dot_error(self.c[i].abs() + t.abs(), 2);
            for k in 0..ng {
                if k == col {
                    let v = gcol[i] * d;
                    g[(i, k)] = v;
                    box_err[i] = add_up(box_err[i], dot_error(v.abs(), 1));
                } else {
                    let t = gcol[i] * w[k];
                    let v = self.g[(i, k)] - t;
                    g[(i, k)] = v;
                    box_err[i] = add_up(box_err[i], dot_error(self.g[(i, k)].abs() + t.abs(), 2));
                }
            }
        }
        let rows: Vec<usize> = (0..nc).filter(|&l| l != row).collect();
        let mut a = DMatrix::zeros(nc - 1, ng);
        let mut b = DVector::zeros(nc - 1);
        let mut slack = vec![0.0; nc - 1];
        for (li, &l) in rows.iter().enumerate() {
            let t = acol[l] * beta;
            b[li] = self.b[l] - t;
            slack[li] = dot_error(self.b[l].abs() + t.abs(), 2);
            for k in 0..ng {
                if k == col {
                    let v = acol[l] * d;
                    a[(li, k)] = v;
                    slack[li] = add_up(slack[li], dot_error(v.abs(), 1));
                } else {
                    let t = acol[l] * w[k];
                    let v = self.a[(l, k)] - t;
                    a[(li, k)] = v;
                    slack[li] = add_up(slack[li], dot_error(self.a[(l, k)].abs() + t.abs(), 2));
                }
            }
        }
        if c.iter().chain(g.iter()).chain(a.iter()).chain(b.iter()).any(|v| !v.is_finite()) {
            return Err(SetError::Overflow("constraint elimination"));
        }
        let mut z = Self { c, g, a, b };
        z.drop_zero_columns();
        z.push_box(&box_err)?;
        z.push_slack(&slack)?;
        Ok(z)
    }

    /// Keeps the first `keep` constraint rows (a superset: constraints dropped).
    fn drop_constraints(&mut self, keep: usize) {
        let keep = keep.min(self.constraints());
        self.a = self.a.rows(0, keep).into_owned();
        self.b = self.b.rows(0, keep).into_owned();
    }

    /// Removes factors whose columns of `G` and `A` are both zero (they change nothing).
    pub(crate) fn drop_zero_columns(&mut self) {
        let keep: Vec<usize> = (0..self.generators())
            .filter(|&j| self.g.column(j).iter().chain(self.a.column(j).iter()).any(|v| *v != 0.0))
            .collect();
        if keep.len() == self.generators() {
            return;
        }
        self.g = self.g.select_columns(&keep);
        self.a = self.a.select_columns(&keep);
    }

    /// Keeps the `keep` largest lifted columns `[g_j; a_j]` and boxes the rest (Z6).
    fn reduce_generators(&self, keep: usize) -> Result<Self, SetError> {
        let (n, nc, ng) = (self.dim(), self.constraints(), self.generators());
        let mut order: Vec<(f64, usize)> =
            (0..ng).map(|j| (self.g.column(j).norm_squared() + self.a.column(j).norm_squared(), j)).collect();
        order.sort_by(|x, y| y.0.total_cmp(&x.0));
        let mut kept: Vec<usize> = order.iter().take(keep).map(|&(_, j)| j).collect();
        kept.sort_unstable();
        let mut sx = vec![0.0; n];
        let mut sa = vec![0.0; nc];
        for &(_, j) in order.iter().skip(keep) {
            for i in 0..n {
                sx[i] = add_up(sx[i], self.g[(i, j)].abs());
            }
            for i in 0..nc {
                sa[i] = add_up(sa[i], self.a[(i, j)].abs());
            }
        }
        let mut z = Self {
            c: self.c.clone(),
            g: self.g.select_columns(&kept),
            a: self.a.select_columns(&kept),
            b: self.b.clone(),
        };
        if z.a.nrows() == 0 {
            z.a = DMatrix::zeros(0, kept.len());
        }
        z.push_box(&sx)?;
        z.push_slack(&sa)?;
        Ok(z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The propagation as first written: every row in every sweep.
    fn propagate_every_row(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<FactorRanges> {
        let (nc, ng) = (a.nrows(), a.ncols());
        let mut e = vec![Interval::new(-1.0, 1.0); ng];
        let mut r = vec![Interval::ENTIRE; ng];
        let mut terms = vec![Interval::ZERO; ng];
        for _ in 0..PROPAGATION_SWEEPS {
            let mut changed = false;
            for i in 0..nc {
                let (mut lo, mut hi) = (0.0, 0.0);
                for k in 0..ng {
                    let t = e[k] * a[(i, k)];
                    lo = down(lo + t.lo());
                    hi = up(hi + t.hi());
                    terms[k] = t;
                }
                for j in (0..ng).filter(|&j| a[(i, j)] != 0.0) {
                    let rest = Interval::new(down(lo - terms[j].lo()), up(hi - terms[j].hi()));
                    let implied = (Interval::point(b[i]) - rest) / a[(i, j)];
                    if !implied.is_bounded() {
                        continue;
                    }
                    r[j] = r[j].meet(implied)?;
                    let e_new = e[j].meet(implied)?;
                    changed |= e_new != e[j];
                    e[j] = e_new;
                }
            }
            if !changed {
                break;
            }
        }
        Some(FactorRanges { e, r })
    }

    #[test]
    fn skipping_unchanged_rows_gives_the_ranges_of_every_row_bit_for_bit() {
        let mut seed = 3_u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let (mut narrowing, mut empty) = (0, 0);
        for case in 0..400 {
            let (nc, ng) = (1 + case % 5, 2 + case % 9);
            // Sparse rows (about a third zero), right-hand sides from a point of the box, pushed
            // out now and then so that some sets are empty.
            let a = DMatrix::from_fn(nc, ng, |_, _| if next() < -0.33 { 0.0 } else { next() });
            let xi = DVector::from_fn(ng, |_, _| next());
            let b = &a * xi + DVector::from_fn(nc, |_, _| if case % 7 == 0 { 3.0 * next() } else { 0.0 });
            let (fast, every) = (propagate(&a, &b), propagate_every_row(&a, &b));
            match (&fast, &every) {
                (Some(f), Some(e)) => {
                    assert_eq!((&f.e, &f.r), (&e.e, &e.r), "case {case}");
                    narrowing += usize::from(f.e.iter().any(|x| x.hi() - x.lo() < 2.0));
                }
                (None, None) => empty += 1,
                _ => panic!("case {case}: one proves the set empty, the other not"),
            }
        }
        assert!(narrowing > 100 && empty > 5, "{narrowing} narrowing, {empty} empty");
    }

    #[test]
    fn a_factor_without_excess_is_the_choice_of_the_full_scan() {
        let mut seed = 11_u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut shortcuts = 0;
        for case in 0..300 {
            let (n, nc, ng) = (1 + case % 4, 1 + case % 3, 3 + case % 7);
            let z = ConstrainedZonotope::new(
                DVector::from_fn(n, |_, _| next()),
                DMatrix::from_fn(n, ng, |_, _| next()),
                DMatrix::from_fn(nc, ng, |_, _| if next() < -0.5 { 0.0 } else { next() }),
                DVector::from_fn(nc, |_, _| 0.1 * next()),
            )
            .unwrap();
            // Excesses: zero, tiny (where H could underflow), ordinary or infinite.
            let excess: Vec<f64> = (0..ng)
                .map(|_| match next() {
                    v if v < -0.6 => 0.0,
                    v if v < -0.5 => 1e-200,
                    v if v > 0.9 => f64::INFINITY,
                    v => v.abs(),
                })
                .collect();
            let candidates: Vec<usize> =
                (0..ng).filter(|&j| excess[j].is_finite() && (0..nc).any(|i| z.a[(i, j)] != 0.0)).collect();
            let kinv = kkt_inverse_diagonal(&z.g, &z.a);
            let full =
                z.least_hausdorff_error(&candidates, &excess, &kinv).and_then(|c| z.pivot_row(c).map(|r| (r, c)));
            assert_eq!(z.elimination_choice(&excess), full, "case {case}");
            let free = candidates.iter().position(|&j| excess[j] == 0.0);
            shortcuts += usize::from(free.is_some_and(|p| candidates[..p].iter().all(|&j| excess[j] >= TINY_EXCESS)));
        }
        assert!(shortcuts > 50, "{shortcuts}");
    }

    #[test]
    fn the_low_rank_kkt_diagonal_is_the_direct_inverse_s() {
        // Sizes (n, n_g, n_c), the last with a first column of S that needs a row swap.
        for (n, ng, nc) in [(3, 9, 2), (4, 10, 3), (2, 6, 4)] {
            let g = DMatrix::from_fn(n, ng, |i, j| ((i * 7 + j * 3) as f64).sin());
            // Rows of distinct frequencies: independent (cos(α + βj) rows would span two only).
            let mut a = DMatrix::from_fn(nc, ng, |i, j| (0.7 * ((i + 1) * (j + 1)) as f64 + i as f64).cos());
            if nc == 4 {
                a.row_mut(0).scale_mut(1e-3);
            }
            let mut k = DMatrix::zeros(ng + nc, ng + nc);
            k.view_mut((0, 0), (ng, ng)).copy_from(&(DMatrix::identity(ng, ng) + g.transpose() * &g));
            k.view_mut((ng, 0), (nc, ng)).copy_from(&a);
            k.view_mut((0, ng), (ng, nc)).copy_from(&a.transpose());
            let direct = k.try_inverse().unwrap();
            let fast = kkt_inverse_diagonal(&g, &a);
            for j in 0..ng {
                let tol = 1e-10 * (1.0 + direct[(j, j)].abs());
                assert!(
                    (direct[(j, j)] - fast[j]).abs() < tol,
                    "{n}, {ng}, {nc}, {j}: {} vs {}",
                    direct[(j, j)],
                    fast[j]
                );
            }
        }
        // Two equal rows of A: S is singular, and the caller is told so (NaN: the cruder measure).
        let g = DMatrix::from_fn(2, 5, |i, j| ((i + 2 * j) as f64).sin());
        let a = DMatrix::from_fn(2, 5, |_, j| (j as f64).cos());
        assert!(kkt_inverse_diagonal(&g, &a).iter().all(|v| v.is_nan()));
    }
}
