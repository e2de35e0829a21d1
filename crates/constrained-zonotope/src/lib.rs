//! Constrained zonotopes `Z = ⟨c, G, A, b⟩ = {c + G ξ : ‖ξ‖∞ ≤ 1, A ξ = b}` (Scott, Raimondo,
//! Marseglia & Braatz, Automatica 2016), sound in floating point.
//!
//! Operations (docs/constrained-zonotopes.md numbers the equations (Z1)–(Z9)):
//!
//! * [`ConstrainedZonotope::affine_map`] `M Z + d` (Z1), [`ConstrainedZonotope::minkowski_sum`]
//!   (Z2), [`ConstrainedZonotope::intersect`], the generalised intersection
//!   `Z ∩_R Y = {x ∈ Z : R x ∈ Y}` (Z3) — exact in exact arithmetic;
//! * [`ConstrainedZonotope::reduce`]: factor rescaling by interval constraint propagation (Z4),
//!   constraint elimination (Z5) and generator reduction of the lifted zonotope (Z6), down to a
//!   [`ReductionLimits`];
//! * [`ConstrainedZonotope::interval_hull`] from linear programs whose bounds are verified (Z7),
//!   [`ConstrainedZonotope::emptiness`] (Z8) and [`ConstrainedZonotope::contains_point`].
//!
//! # Soundness in floating point
//!
//! The set a value stands for is the one its stored numbers describe in exact arithmetic. Every
//! operation returns a set that contains the exact result of the operation on its operands:
//! the rounding errors of a new centre and generator matrix are bounded a priori (Higham's
//! `γ_k` bound of a dot product, [`enclose`]) and added as an axis-aligned box of new
//! generators; those of new constraint rows as one slack factor per row (a column of `A` with
//! the row's error bound and a zero column of `G`), so every point of the exact result keeps a
//! feasible `ξ`. Bounds of the interval hull never trust the LP solver: any multiplier vector `λ`
//! gives `min cᵢ + Gᵢ ξ ≥ cᵢ + λᵀ b − ‖Gᵢᵀ − Aᵀ λ‖₁` over the constraints (weak duality with the
//! box), evaluated in outward-rounded interval arithmetic; the solver only proposes `λ`. The set
//! is declared empty only on a verified Farkas certificate `λᵀ b − ‖Aᵀ λ‖₁ > 0`.
//!
//! ```
//! use constrained_zonotope::{ConstrainedZonotope, ReductionLimits};
//! use nalgebra::{dmatrix, dvector};
//!
//! // The square [-1, 1]² cut by the strip |x₁ + x₂ − 1| ≤ 0.1.
//! let square = ConstrainedZonotope::from_box(&dvector![0.0, 0.0], &dvector![1.0, 1.0])?;
//! let strip = ConstrainedZonotope::from_box(&dvector![1.0], &dvector![0.1])?;
//! let cut = square.intersect(&dmatrix![1.0, 1.0], &strip)?;
//! let hull = cut.interval_hull()?;
//! assert!(hull.lower[0] >= -0.1 - 1e-9 && hull.upper[0] <= 1.0 + 1e-12);
//! let reduced = cut.reduce(&ReductionLimits::new(4, 0)?)?;
//! assert_eq!(reduced.constraints(), 0);
//! # Ok::<(), constrained_zonotope::SetError>(())
//! ```

#![warn(missing_docs)]

pub mod enclose;
mod hull;
mod lp;
mod ops;
pub mod polygon;
mod reduce;
mod simplex;

use nalgebra::{DMatrix, DVector};
use thiserror::Error;

pub use hull::{Containment, Emptiness, Hull};
pub use reduce::ReductionLimits;

/// Most states a set may have.
pub const MAX_DIMENSION: usize = 256;
/// Most generators (factors) a set may have; an operation whose result would have more is refused
/// before allocating.
pub const MAX_GENERATORS: usize = 4096;
/// Most equality constraints a set may have.
pub const MAX_CONSTRAINTS: usize = 2048;

/// Why a set or an operation was refused.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SetError {
    /// Matrices or vectors of inconsistent sizes.
    #[error("{what}: expected {expected}, found {found}")]
    Dimension {
        /// Which operand.
        what: &'static str,
        /// The size it must have.
        expected: String,
        /// The size it has.
        found: String,
    },
    /// A NaN or infinite entry.
    #[error("{what}: entry {index} is {value} (must be finite)")]
    NotFinite {
        /// Which operand.
        what: &'static str,
        /// The entry's position (row, column) or index.
        index: String,
        /// The value.
        value: f64,
    },
    /// A negative radius of a box.
    #[error("{what}: radius {index} is {value} (must be non-negative)")]
    NegativeRadius {
        /// Which operand.
        what: &'static str,
        /// Index of the radius.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The result would exceed a size limit ([`MAX_DIMENSION`], [`MAX_GENERATORS`],
    /// [`MAX_CONSTRAINTS`]); nothing was allocated.
    #[error("{what}: {requested} exceeds the limit of {limit}")]
    TooLarge {
        /// What would be too large.
        what: &'static str,
        /// The size asked for.
        requested: usize,
        /// The limit.
        limit: usize,
    },
    /// A reduction limit that cannot hold (fewer generators than the reduced set needs).
    #[error("reduction limits: {0}")]
    InvalidLimits(String),
    /// The rounding-error bounds of an operation overflowed (entries near `f64::MAX`).
    #[error("{0}: the rounding-error bound overflowed")]
    Overflow(&'static str),
}

/// A constrained zonotope `{c + G ξ : ‖ξ‖∞ ≤ 1, A ξ = b}`: `c` of length `n`, `G` of `n × n_g`,
/// `A` of `n_c × n_g`, `b` of length `n_c`. A zonotope has `n_c = 0`.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstrainedZonotope {
    c: DVector<f64>,
    g: DMatrix<f64>,
    a: DMatrix<f64>,
    b: DVector<f64>,
}

fn check_finite(what: &'static str, m: &DMatrix<f64>) -> Result<(), SetError> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            let v = m[(i, j)];
            if !v.is_finite() {
                return Err(SetError::NotFinite { what, index: format!("({i}, {j})"), value: v });
            }
        }
    }
    Ok(())
}

fn check_finite_vec(what: &'static str, v: &DVector<f64>) -> Result<(), SetError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(SetError::NotFinite { what, index: i.to_string(), value: v[i] }),
        None => Ok(()),
    }
}

pub(crate) fn check_size(what: &'static str, requested: usize, limit: usize) -> Result<(), SetError> {
    if requested > limit { Err(SetError::TooLarge { what, requested, limit }) } else { Ok(()) }
}

impl ConstrainedZonotope {
    /// `⟨c, G, A, b⟩`, validated: consistent sizes, finite entries, sizes within the limits.
    ///
    /// # Errors
    /// [`SetError::Dimension`], [`SetError::NotFinite`], [`SetError::TooLarge`].
    pub fn new(c: DVector<f64>, g: DMatrix<f64>, a: DMatrix<f64>, b: DVector<f64>) -> Result<Self, SetError> {
        check_size("dimension", c.len(), MAX_DIMENSION)?;
        check_size("generators", g.ncols(), MAX_GENERATORS)?;
        check_size("constraints", a.nrows(), MAX_CONSTRAINTS)?;
        if g.nrows() != c.len() {
            return Err(SetError::Dimension {
                what: "G",
                expected: format!("{} rows (the length of c)", c.len()),
                found: format!("{} rows", g.nrows()),
            });
        }
        if a.ncols() != g.ncols() && a.nrows() > 0 {
            return Err(SetError::Dimension {
                what: "A",
                expected: format!("{} columns (those of G)", g.ncols()),
                found: format!("{} columns", a.ncols()),
            });
        }
        if a.nrows() != b.len() {
            return Err(SetError::Dimension {
                what: "b",
                expected: format!("length {} (the rows of A)", a.nrows()),
                found: format!("length {}", b.len()),
            });
        }
        check_finite_vec("c", &c)?;
        check_finite("G", &g)?;
        check_finite("A", &a)?;
        check_finite_vec("b", &b)?;
        let a = if a.nrows() == 0 { DMatrix::zeros(0, g.ncols()) } else { a };
        Ok(Self { c, g, a, b })
    }

    /// The zonotope `⟨c, G⟩ = {c + G ξ : ‖ξ‖∞ ≤ 1}`.
    ///
    /// # Errors
    /// As [`ConstrainedZonotope::new`].
    pub fn zonotope(c: DVector<f64>, g: DMatrix<f64>) -> Result<Self, SetError> {
        let ng = g.ncols();
        Self::new(c, g, DMatrix::zeros(0, ng), DVector::zeros(0))
    }

    /// The box `{x : |xᵢ − cᵢ| ≤ rᵢ}` (radii zero allowed: a degenerate box).
    ///
    /// # Errors
    /// [`SetError::NegativeRadius`], and as [`ConstrainedZonotope::new`].
    pub fn from_box(center: &DVector<f64>, radius: &DVector<f64>) -> Result<Self, SetError> {
        if center.len() != radius.len() {
            return Err(SetError::Dimension {
                what: "box radius",
                expected: format!("length {}", center.len()),
                found: format!("length {}", radius.len()),
            });
        }
        check_size("dimension", center.len(), MAX_DIMENSION)?;
        check_finite_vec("box radius", radius)?;
        if let Some(i) = radius.iter().position(|r| *r < 0.0) {
            return Err(SetError::NegativeRadius { what: "box radius", index: i, value: radius[i] });
        }
        let nz: Vec<usize> = (0..radius.len()).filter(|&i| radius[i] > 0.0).collect();
        let mut g = DMatrix::zeros(center.len(), nz.len());
        for (j, &i) in nz.iter().enumerate() {
            g[(i, j)] = radius[i];
        }
        Self::zonotope(center.clone(), g)
    }

    /// The box `[lower, upper]` (componentwise; `lower ≤ upper`), enclosed outward.
    ///
    /// # Errors
    /// A lower bound above its upper bound ([`SetError::NegativeRadius`]), and as
    /// [`ConstrainedZonotope::from_box`].
    pub fn from_bounds(lower: &DVector<f64>, upper: &DVector<f64>) -> Result<Self, SetError> {
        if lower.len() != upper.len() {
            return Err(SetError::Dimension {
                what: "upper bounds",
                expected: format!("length {}", lower.len()),
                found: format!("length {}", upper.len()),
            });
        }
        check_finite_vec("lower bounds", lower)?;
        check_finite_vec("upper bounds", upper)?;
        let mut c = DVector::zeros(lower.len());
        let mut r = DVector::zeros(lower.len());
        for i in 0..lower.len() {
            if lower[i] > upper[i] {
                return Err(SetError::NegativeRadius { what: "box bounds", index: i, value: upper[i] - lower[i] });
            }
            c[i] = 0.5 * lower[i] + 0.5 * upper[i];
            // The radius covers both bounds from the rounded centre.
            r[i] = intervals::up(intervals::up(upper[i] - c[i]).max(intervals::up(c[i] - lower[i])));
        }
        Self::from_box(&c, &r)
    }

    /// The dimension `n`.
    #[must_use]
    pub fn dim(&self) -> usize {
        self.c.len()
    }

    /// The number of generators (factors) `n_g`.
    #[must_use]
    pub fn generators(&self) -> usize {
        self.g.ncols()
    }

    /// The number of equality constraints `n_c`.
    #[must_use]
    pub fn constraints(&self) -> usize {
        self.a.nrows()
    }

    /// The centre `c`.
    #[must_use]
    pub fn center(&self) -> &DVector<f64> {
        &self.c
    }

    /// The generator matrix `G`.
    #[must_use]
    pub fn generator_matrix(&self) -> &DMatrix<f64> {
        &self.g
    }

    /// The constraint matrix `A`.
    #[must_use]
    pub fn constraint_matrix(&self) -> &DMatrix<f64> {
        &self.a
    }

    /// The constraint right-hand side `b`.
    #[must_use]
    pub fn constraint_rhs(&self) -> &DVector<f64> {
        &self.b
    }

    /// The interval hull of the zonotope `⟨c, G⟩` that contains the set (constraints ignored),
    /// rounded outward: `cᵢ ∓ Σⱼ |Gᵢⱼ|`.
    #[must_use]
    pub fn zonotope_hull(&self) -> (DVector<f64>, DVector<f64>) {
        let n = self.dim();
        let mut lo = DVector::zeros(n);
        let mut hi = DVector::zeros(n);
        for i in 0..n {
            let r = enclose::abs_row_sum_up(&self.g, i);
            lo[i] = intervals::down(self.c[i] - r);
            hi[i] = intervals::up(self.c[i] + r);
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests;
