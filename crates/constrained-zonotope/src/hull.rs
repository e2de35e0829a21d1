//! Verified bounds (Z7), emptiness (Z8) and point containment.
//!
//! For any multipliers `λ`, `min {qᵀ ξ : A ξ = b, ‖ξ‖∞ ≤ 1} ≥ λᵀ b − ‖q − Aᵀ λ‖₁` (the box's
//! support function; Neumaier & Shcherbina 2004 for boxed variables), so a bound evaluated in
//! outward-rounded interval arithmetic from the solver's `λ` is rigorous whatever the solver
//! returned. Each bound is the best of that, of `λ = 0` (the zonotope's own bound) and of the
//! propagated factor ranges.

use intervals::{Interval, down};
use nalgebra::{DMatrix, DVector};

use crate::enclose::{add_up, dot_error};
use crate::lp::{FactorLp, LpProposal};
use crate::reduce::propagate;
use crate::simplex::{Simplex, SimplexResult};
use crate::{ConstrainedZonotope, SetError};

/// The certified interval hull of a set.
#[derive(Debug, Clone, PartialEq)]
pub struct Hull {
    /// Lower bounds (length `n`); meaningless when [`Hull::certified_empty`].
    pub lower: DVector<f64>,
    /// Upper bounds (length `n`).
    pub upper: DVector<f64>,
    /// Whether the set was proved empty (a verified certificate): no bounds then.
    pub certified_empty: bool,
    /// Linear programs that gave no usable answer (their bounds fell back to the propagated
    /// ranges: still certified, possibly wider).
    pub lp_failures: usize,
}

/// Whether a set is empty.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Emptiness {
    /// Proved empty by a verified certificate.
    CertifiedEmpty,
    /// A point of the factor box meets the constraints to within `residual` (max-norm): not empty
    /// as far as floating point can tell (not a proof).
    Feasible {
        /// `‖A ξ − b‖∞` at the solver's `ξ` clipped to the box.
        residual: f64,
    },
    /// The solver gave no answer and nothing was proved.
    Undecided,
}

/// Whether a point lies in a set.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Containment {
    /// Proved outside (a verified certificate, or outside the certified hull).
    CertifiedOutside,
    /// Inside to within `residual` (max-norm residual of the factor equations; not a proof).
    Inside {
        /// The residual.
        residual: f64,
    },
    /// Nothing was proved.
    Undecided,
}

/// A rigorous lower bound of `min {c + qᵀ ξ : A ξ = b, ‖ξ‖∞ ≤ 1}` from multipliers `λ`:
/// `c + λᵀ b − Σⱼ |qⱼ − (Aᵀ λ)ⱼ|`, each dot product evaluated in floating point with its a-priori
/// error bound ([`dot_error`]) subtracted, the sums of bounds rounded up.
pub(crate) fn verified_lower(c: f64, q: &[f64], a: &DMatrix<f64>, b: &DVector<f64>, lambda: &[f64]) -> f64 {
    let nc = lambda.len();
    let (mut s, mut abs) = (c, c.abs());
    for (l, bl) in lambda.iter().zip(b.iter()) {
        let t = l * bl;
        s += t;
        abs += t.abs();
    }
    // Σⱼ (|rⱼ| + eⱼ) ≥ ‖q − Aᵀ λ‖₁, rounded up.
    let mut penalty = 0.0;
    for (j, qj) in q.iter().enumerate() {
        let (mut r, mut r_abs) = (*qj, qj.abs());
        for (i, l) in lambda.iter().enumerate() {
            let t = l * a[(i, j)];
            r -= t;
            r_abs += t.abs();
        }
        penalty = add_up(penalty, add_up(r.abs(), dot_error(r_abs, nc + 1)));
    }
    let lower = down(down(s - dot_error(abs, nc + 1)) - penalty);
    if lower.is_finite() { lower } else { f64::NEG_INFINITY }
}

/// Whether `λ` proves `{ξ : A ξ = b, ‖ξ‖∞ ≤ 1}` empty: `λᵀ b − ‖Aᵀ λ‖₁ > 0`, rigorously.
pub(crate) fn certifies_empty(a: &DMatrix<f64>, b: &DVector<f64>, lambda: &[f64]) -> bool {
    let zeros = vec![0.0; a.ncols()];
    lambda.iter().all(|l| l.is_finite()) && verified_lower(0.0, &zeros, a, b, lambda) > 0.0
}

impl ConstrainedZonotope {
    /// The certified interval hull (Z7): per state, the LP's verified bounds, never narrower
    /// than the exact hull whatever the solver returned.
    ///
    /// # Errors
    /// None at present for valid sets (the signature leaves room for limits).
    pub fn interval_hull(&self) -> Result<Hull, SetError> {
        let n = self.dim();
        let hull = self.propagated_hull();
        if self.constraints() == 0 || hull.certified_empty {
            return Ok(hull);
        }
        let mut hull = hull;
        let ng = self.generators();
        let mut q = vec![0.0; ng];
        // The simplex runs over the factors that enter a constraint; the others sit at the bound
        // their cost chooses, and the verified bound below accounts for them (`|q_j|`).
        let active: Vec<usize> = (0..ng).filter(|&j| self.a.column(j).iter().any(|v| *v != 0.0)).collect();
        let mut q_active = vec![0.0; active.len()];
        let mut simplex = Simplex::new(&self.a.select_columns(&active), &self.b);
        let mut clarabel: Option<FactorLp> = None;
        for i in 0..n {
            for sign in [1.0, -1.0] {
                for j in 0..ng {
                    q[j] = sign * self.g[(i, j)];
                }
                // The simplex first (warm-started from the last objective's basis), Clarabel when it
                // stops; either only proposes multipliers.
                for (qa, &j) in q_active.iter_mut().zip(&active) {
                    *qa = q[j];
                }
                let proposal = match simplex.solve(&q_active) {
                    SimplexResult::Optimal { y, xi } => LpProposal::Optimal { lambda: y, xi },
                    SimplexResult::Infeasible { y } => LpProposal::Infeasible { lambda: y },
                    SimplexResult::Stopped => {
                        let first = clarabel.is_none();
                        let solver = clarabel.get_or_insert_with(|| FactorLp::new(&self.a, &self.b, &q));
                        solver.solve(&q, first)
                    }
                };
                match proposal {
                    LpProposal::Optimal { lambda, .. } => {
                        let bound = verified_lower(sign * self.c[i], &q, &self.a, &self.b, &lambda);
                        if sign > 0.0 {
                            hull.lower[i] = hull.lower[i].max(bound);
                        } else {
                            hull.upper[i] = hull.upper[i].min(-bound);
                        }
                    }
                    LpProposal::Infeasible { lambda } => {
                        let negated: Vec<f64> = lambda.iter().map(|v| -v).collect();
                        if certifies_empty(&self.a, &self.b, &lambda) || certifies_empty(&self.a, &self.b, &negated) {
                            hull.certified_empty = true;
                            return Ok(hull);
                        }
                        hull.lp_failures += 1;
                    }
                    LpProposal::Failed => hull.lp_failures += 1,
                }
            }
        }
        if (0..n).any(|i| hull.lower[i] > hull.upper[i]) {
            // Rigorous lower and upper bounds that cross prove that no point exists.
            hull.certified_empty = true;
        }
        Ok(hull)
    }

    /// A cheaper certified box, without linear programs: the zonotope's hull tightened by the
    /// factor ranges of interval constraint propagation (Z4), `cᵢ + Σⱼ Gᵢⱼ E_j`. Never narrower than
    /// [`ConstrainedZonotope::interval_hull`]; `certified_empty` when the propagation empties a range.
    #[must_use]
    pub fn propagated_hull(&self) -> Hull {
        let n = self.dim();
        let (zlo, zhi) = self.zonotope_hull();
        let mut hull = Hull { lower: zlo, upper: zhi, certified_empty: false, lp_failures: 0 };
        if self.constraints() == 0 {
            return hull;
        }
        let Some(ranges) = propagate(&self.a, &self.b) else {
            hull.certified_empty = true;
            return hull;
        };
        for i in 0..n {
            let mut s = Interval::point(self.c[i]);
            for (j, e) in ranges.e.iter().enumerate() {
                s = s + *e * self.g[(i, j)];
            }
            if s.is_bounded() {
                hull.lower[i] = hull.lower[i].max(s.lo());
                hull.upper[i] = hull.upper[i].min(s.hi());
            }
        }
        hull
    }

    /// Whether the set is empty (Z8): `CertifiedEmpty` only on a verified certificate.
    #[must_use]
    pub fn emptiness(&self) -> Emptiness {
        if self.constraints() == 0 {
            return Emptiness::Feasible { residual: 0.0 };
        }
        if propagate(&self.a, &self.b).is_none() {
            return Emptiness::CertifiedEmpty;
        }
        let q = vec![0.0; self.generators()];
        let mut lp = FactorLp::new(&self.a, &self.b, &q);
        match lp.solve(&q, true) {
            LpProposal::Optimal { xi, .. } => {
                let xi: Vec<f64> = xi.iter().map(|v| v.clamp(-1.0, 1.0)).collect();
                let residual = (0..self.constraints())
                    .map(|i| ((0..self.generators()).map(|j| self.a[(i, j)] * xi[j]).sum::<f64>() - self.b[i]).abs())
                    .fold(0.0, f64::max);
                Emptiness::Feasible { residual }
            }
            LpProposal::Infeasible { lambda } if certifies_empty(&self.a, &self.b, &lambda) => {
                Emptiness::CertifiedEmpty
            }
            _ => Emptiness::Undecided,
        }
    }

    /// Whether `x` lies in the set: the emptiness of `{ξ : c + G ξ = x, A ξ = b, ‖ξ‖∞ ≤ 1}`.
    ///
    /// # Errors
    /// [`SetError::Dimension`] or [`SetError::NotFinite`] for a bad point.
    pub fn contains_point(&self, x: &DVector<f64>) -> Result<Containment, SetError> {
        let n = self.dim();
        if x.len() != n {
            return Err(SetError::Dimension {
                what: "point",
                expected: format!("length {n}"),
                found: format!("length {}", x.len()),
            });
        }
        crate::check_finite_vec("point", x)?;
        let (lo, hi) = self.zonotope_hull();
        if (0..n).any(|i| x[i] < lo[i] || x[i] > hi[i]) {
            return Ok(Containment::CertifiedOutside);
        }
        let point = ConstrainedZonotope::zonotope(x.clone(), DMatrix::zeros(n, 0))?;
        let with = self.intersect(&DMatrix::identity(n, n), &point)?;
        Ok(match with.emptiness() {
            Emptiness::CertifiedEmpty => Containment::CertifiedOutside,
            Emptiness::Feasible { residual } => Containment::Inside { residual },
            Emptiness::Undecided => Containment::Undecided,
        })
    }
}
