//! The [`Ellipsoid`] type: construction, point queries, affine maps and bounds.

use std::f64::consts::PI;

use nalgebra::{DMatrix, DVector};

use crate::CONTAINMENT_TOLERANCE;
use crate::error::{EllipsoidError, Result};
use crate::linalg::{check_len, check_matrix_finite, check_vector_finite, forward_sub, symmetrize, validate_spd};

/// The ellipsoid `𝓔(c, P) = {x : (x − c)ᵀ P⁻¹ (x − c) ≤ 1}` with `P` symmetric positive
/// definite.
///
/// The value stores the centre `c`, the symmetrised shape matrix `P` and its lower Cholesky
/// factor `L` (`P = L Lᵀ`); it is immutable, every operation returns a new value.
#[derive(Debug, Clone, PartialEq)]
pub struct Ellipsoid {
    center: DVector<f64>,
    shape: DMatrix<f64>,
    chol: DMatrix<f64>,
}

impl Ellipsoid {
    /// Builds `𝓔(center, shape)` after validation.
    ///
    /// Checks, in this order: `center` non-empty; `shape` square with the dimension of
    /// `center`; all entries finite; `shape` symmetric within [`crate::SYMMETRY_TOLERANCE`]
    /// (relative to its largest entry); `shape` positive definite (Cholesky with pivots above
    /// [`crate::PD_RELATIVE_TOLERANCE`]` · n · P_jj`). The symmetrised `(P + Pᵀ)/2` is
    /// stored.
    pub fn new(center: DVector<f64>, shape: DMatrix<f64>) -> Result<Self> {
        let n = center.len();
        if n == 0 {
            return Err(EllipsoidError::Empty { what: "centre c" });
        }
        crate::linalg::check_square(&shape, "shape matrix P")?;
        check_vector_finite(&center, "centre c")?;
        let (shape, chol) = validate_spd(&shape, n, "shape matrix P")?;
        Ok(Self { center, shape, chol })
    }

    /// The ball `{x : ‖x − center‖ ≤ radius}` (`radius` finite and positive).
    pub fn ball(center: DVector<f64>, radius: f64) -> Result<Self> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(EllipsoidError::InvalidParameter {
                name: "radius",
                value: radius,
                expected: "a finite positive number",
            });
        }
        let n = center.len();
        Self::new(center, DMatrix::identity(n, n) * (radius * radius))
    }

    /// The axis-aligned ellipsoid with the given semi-axis lengths: `P = diag(a_i²)`.
    pub fn axis_aligned(center: DVector<f64>, semi_axes: &[f64]) -> Result<Self> {
        check_len(&DVector::from_column_slice(semi_axes), center.len(), "semi-axes")?;
        if let Some(index) = semi_axes.iter().position(|a| !(a.is_finite() && *a > 0.0)) {
            return Err(EllipsoidError::InvalidParameter {
                name: "semi-axis",
                value: semi_axes[index],
                expected: "finite positive semi-axis lengths",
            });
        }
        let diag = DVector::from_iterator(semi_axes.len(), semi_axes.iter().map(|a| a * a));
        Self::new(center, DMatrix::from_diagonal(&diag))
    }

    /// Builds an ellipsoid from a computed centre and shape (symmetrised here); a Cholesky
    /// failure is turned into an error by `on_fail(pivot, value)`.
    pub(crate) fn from_computed(
        center: DVector<f64>,
        shape: &DMatrix<f64>,
        center_what: &'static str,
        on_fail: impl FnOnce(usize, f64) -> EllipsoidError,
    ) -> Result<Self> {
        check_vector_finite(&center, center_what)?;
        let shape = symmetrize(shape);
        match dense_kernels::cholesky_checked(&shape, crate::PD_RELATIVE_TOLERANCE) {
            Ok(chol) => Ok(Self { center, shape, chol }),
            Err(f) => Err(on_fail(f.pivot, f.value)),
        }
    }

    /// Builds from already-consistent parts (used where `L` is known exactly).
    pub(crate) fn from_parts(center: DVector<f64>, shape: DMatrix<f64>, chol: DMatrix<f64>) -> Self {
        Self { center, shape, chol }
    }

    /// Dimension `n` of the space.
    pub fn dim(&self) -> usize {
        self.center.len()
    }

    /// Centre `c`.
    pub fn center(&self) -> &DVector<f64> {
        &self.center
    }

    /// Shape matrix `P` (symmetric).
    pub fn shape(&self) -> &DMatrix<f64> {
        &self.shape
    }

    /// Lower Cholesky factor `L` of `P` (`P = L Lᵀ`, positive diagonal).
    pub fn cholesky_factor(&self) -> &DMatrix<f64> {
        &self.chol
    }

    /// Checks a point argument: right length, finite entries.
    pub(crate) fn check_point(&self, x: &DVector<f64>, what: &'static str) -> Result<()> {
        check_len(x, self.dim(), what)?;
        check_vector_finite(x, what)
    }

    /// `(x − c)ᵀ P⁻¹ (x − c)`, computed as `‖L⁻¹ (x − c)‖²` (no explicit inverse).
    ///
    /// `x` must have dimension `n` and finite entries.
    pub fn normalized_distance(&self, x: &DVector<f64>) -> Result<f64> {
        self.check_point(x, "point x")?;
        Ok(forward_sub(&self.chol, &(x - &self.center)).norm_squared())
    }

    /// Whether `x ∈ 𝓔`, i.e. `normalized_distance(x) ≤ 1 + CONTAINMENT_TOLERANCE`.
    pub fn contains(&self, x: &DVector<f64>) -> Result<bool> {
        Ok(self.normalized_distance(x)? <= 1.0 + CONTAINMENT_TOLERANCE)
    }

    /// Image under `x ↦ A x + b`: `𝓔(A c + b, A P Aᵀ)`.
    ///
    /// `A` is `m × n` with `m ≥ 1`, `b` has length `m`. The image is a proper ellipsoid only
    /// when `A` has full row rank (`m ≤ n`); otherwise it is flat, which `𝓔(c, P)` with
    /// `P ≻ 0` cannot represent, and [`EllipsoidError::DegenerateImage`] is returned.
    /// `A P Aᵀ` is formed as `(A L)(A L)ᵀ`.
    pub fn affine_map(&self, a: &DMatrix<f64>, b: &DVector<f64>) -> Result<Self> {
        if a.nrows() == 0 {
            return Err(EllipsoidError::Empty { what: "map matrix A" });
        }
        if a.ncols() != self.dim() {
            return Err(EllipsoidError::DimensionMismatch {
                what: "map matrix A (columns)",
                expected: self.dim(),
                found: a.ncols(),
            });
        }
        check_len(b, a.nrows(), "offset b")?;
        check_matrix_finite(a, "map matrix A")?;
        check_vector_finite(b, "offset b")?;
        let al = a * &self.chol;
        let shape = &al * al.transpose();
        let center = a * &self.center + b;
        let (rows, cols) = a.shape();
        Self::from_computed(center, &shape, "image centre A c + b", |pivot, value| EllipsoidError::DegenerateImage {
            rows,
            cols,
            pivot,
            value,
        })
    }

    /// `𝓔(c + b, P)`.
    pub fn translated(&self, b: &DVector<f64>) -> Result<Self> {
        self.check_point(b, "translation b")?;
        let center = &self.center + b;
        check_vector_finite(&center, "translated centre c + b")?;
        Ok(Self::from_parts(center, self.shape.clone(), self.chol.clone()))
    }

    /// `𝓔(c, s² P)`: the copy scaled by `s > 0` about its centre.
    pub fn scaled(&self, s: f64) -> Result<Self> {
        if !(s.is_finite() && s > 0.0) {
            return Err(EllipsoidError::InvalidParameter {
                name: "scale s",
                value: s,
                expected: "a finite positive number",
            });
        }
        Self::from_computed(self.center.clone(), &(&self.shape * (s * s)), "centre c", |pivot, value| {
            EllipsoidError::DegenerateResult { operation: "scaling", pivot, value }
        })
    }

    /// `[c_i − √P_ii, c_i + √P_ii]`: the exact range of coordinate `i` over `𝓔`.
    pub fn interval(&self, i: usize) -> Result<(f64, f64)> {
        if i >= self.dim() {
            return Err(EllipsoidError::IndexOutOfRange { index: i, dim: self.dim() });
        }
        let r = self.shape[(i, i)].sqrt();
        Ok((self.center[i] - r, self.center[i] + r))
    }

    /// Lower and upper corners of the smallest axis-aligned box containing `𝓔`
    /// (`c ∓ (√P_11, …, √P_nn)`).
    pub fn bounding_box(&self) -> (DVector<f64>, DVector<f64>) {
        let r = DVector::from_iterator(self.dim(), (0..self.dim()).map(|i| self.shape[(i, i)].sqrt()));
        (&self.center - &r, &self.center + &r)
    }

    /// Support function `h(d) = max_{x∈𝓔} dᵀx = dᵀc + √(dᵀ P d)` (`√(dᵀPd) = ‖Lᵀd‖`).
    pub fn support(&self, d: &DVector<f64>) -> Result<f64> {
        self.check_point(d, "direction d")?;
        Ok(d.dot(&self.center) + (self.chol.transpose() * d).norm())
    }

    /// The maximiser of `dᵀx` over `𝓔`: `c + P d / √(dᵀ P d)` (on the boundary).
    ///
    /// Fails with [`EllipsoidError::ZeroDirection`] when `dᵀ P d` is zero.
    pub fn support_point(&self, d: &DVector<f64>) -> Result<DVector<f64>> {
        self.check_point(d, "direction d")?;
        let ltd = self.chol.transpose() * d;
        let s = ltd.norm();
        if !(s.is_finite() && s > 0.0) {
            return Err(EllipsoidError::ZeroDirection);
        }
        Ok(&self.center + &self.chol * (ltd / s))
    }

    /// `tr P`, the sum of the squared semi-axes.
    pub fn trace(&self) -> f64 {
        self.shape.trace()
    }

    /// `log det P = 2 Σ log L_ii`.
    pub fn log_det(&self) -> f64 {
        2.0 * (0..self.dim()).map(|i| self.chol[(i, i)].ln()).sum::<f64>()
    }

    /// Natural logarithm of the volume: `½ log det P + log V_n`, where
    /// `V_n = π^{n/2} / Γ(n/2 + 1)` is the volume of the unit `n`-ball (computed by the
    /// recursion `V_0 = 1`, `V_1 = 2`, `V_n = 2π V_{n−2} / n`).
    pub fn log_volume(&self) -> f64 {
        0.5 * self.log_det() + log_unit_ball_volume(self.dim())
    }

    /// Projection onto the listed coordinates: `𝓔(c_S, P_SS)` (the principal submatrix).
    ///
    /// Indices must be in range and distinct; the order is kept.
    pub fn project(&self, coords: &[usize]) -> Result<Self> {
        if coords.is_empty() {
            return Err(EllipsoidError::Empty { what: "projection coordinate list" });
        }
        for (k, &i) in coords.iter().enumerate() {
            if i >= self.dim() {
                return Err(EllipsoidError::IndexOutOfRange { index: i, dim: self.dim() });
            }
            if coords[..k].contains(&i) {
                return Err(EllipsoidError::RepeatedIndex { index: i });
            }
        }
        let m = coords.len();
        let center = DVector::from_iterator(m, coords.iter().map(|&i| self.center[i]));
        let shape = DMatrix::from_fn(m, m, |r, c| self.shape[(coords[r], coords[c])]);
        Self::from_computed(center, &shape, "projected centre", |pivot, value| EllipsoidError::DegenerateResult {
            operation: "projection",
            pivot,
            value,
        })
    }

    /// `k` points on the boundary of the projection onto coordinates `(i, j)`, for plots.
    ///
    /// The projection is the ellipse with centre `(c_i, c_j)` and shape the 2×2 principal
    /// submatrix `P_{ij}`; the points are `(c_i, c_j) + L₂ (cos θ, sin θ)` with
    /// `θ = 2π m / k`, `m = 0, …, k − 1`, and `L₂` the Cholesky factor of that submatrix.
    /// `k = 0` gives an empty vector.
    pub fn projection_boundary(&self, i: usize, j: usize, k: usize) -> Result<Vec<[f64; 2]>> {
        let proj = self.project(&[i, j])?;
        let l = &proj.chol;
        let (ci, cj) = (proj.center[0], proj.center[1]);
        Ok((0..k)
            .map(|m| {
                let theta = 2.0 * PI * m as f64 / k as f64;
                let (s, c) = theta.sin_cos();
                [ci + l[(0, 0)] * c, cj + l[(1, 0)] * c + l[(1, 1)] * s]
            })
            .collect())
    }
}

/// `log V_n` for the unit `n`-ball.
pub(crate) fn log_unit_ball_volume(n: usize) -> f64 {
    let mut acc = if n % 2 == 0 { 0.0 } else { 2f64.ln() };
    let mut k = if n % 2 == 0 { 2 } else { 3 };
    while k <= n {
        acc += (2.0 * PI / k as f64).ln();
        k += 2;
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{m, v};

    #[test]
    fn unit_ball_volumes() {
        let vols = [1.0, 2.0, PI, 4.0 * PI / 3.0, PI * PI / 2.0, 8.0 * PI * PI / 15.0];
        for (n, vol) in vols.iter().enumerate() {
            assert!((log_unit_ball_volume(n) - vol.ln()).abs() < 1e-14, "n = {n}");
        }
    }

    #[test]
    fn ball_distance_and_containment() {
        let b = Ellipsoid::ball(v(&[1.0, 2.0]), 2.0).expect("valid");
        assert!((b.normalized_distance(&v(&[3.0, 2.0])).expect("ok") - 1.0).abs() < 1e-15);
        assert!((b.normalized_distance(&v(&[2.0, 3.0])).expect("ok") - 0.5).abs() < 1e-15);
        assert!(b.contains(&v(&[1.0, 4.0])).expect("ok"));
        assert!(!b.contains(&v(&[1.0, 4.001])).expect("ok"));
        assert!((b.trace() - 8.0).abs() < 1e-15);
        assert!((b.log_volume() - (4.0 * PI).ln()).abs() < 1e-14);
        let b3 = Ellipsoid::ball(v(&[0.0, 0.0, 0.0]), 1.0).expect("valid");
        assert!((b3.log_volume() - (4.0 * PI / 3.0).ln()).abs() < 1e-14);
    }

    #[test]
    fn axis_aligned_queries() {
        let e = Ellipsoid::axis_aligned(v(&[1.0, -1.0, 0.5]), &[3.0, 2.0, 0.5]).expect("valid");
        assert_eq!(e.interval(0).expect("ok"), (-2.0, 4.0));
        assert_eq!(e.interval(1).expect("ok"), (-3.0, 1.0));
        assert_eq!(e.interval(2).expect("ok"), (0.0, 1.0));
        let (lo, hi) = e.bounding_box();
        assert_eq!(lo, v(&[-2.0, -3.0, 0.0]));
        assert_eq!(hi, v(&[4.0, 1.0, 1.0]));
        // Support in direction (1, 1, 0): c·d + sqrt(9 + 4).
        let d = v(&[1.0, 1.0, 0.0]);
        assert!((e.support(&d).expect("ok") - 13f64.sqrt()).abs() < 1e-14);
        let p = e.support_point(&d).expect("ok");
        assert!((p - v(&[1.0 + 9.0 / 13f64.sqrt(), -1.0 + 4.0 / 13f64.sqrt(), 0.5])).amax() < 1e-14);
        assert!((e.log_volume() - ((4.0 * PI / 3.0) * 3.0).ln()).abs() < 1e-14);
        assert!((e.log_det() - 9f64.ln()).abs() < 1e-14);
        let proj = e.project(&[2, 0]).expect("ok");
        assert_eq!(proj.center(), &v(&[0.5, 1.0]));
        assert_eq!(proj.shape(), &m(2, 2, &[0.25, 0.0, 0.0, 9.0]));
    }

    #[test]
    fn projection_boundary_of_tilted_ellipse() {
        let p = m(3, 3, &[4.0, 1.0, 0.0, 1.0, 2.0, 0.3, 0.0, 0.3, 1.0]);
        let e = Ellipsoid::new(v(&[1.0, 2.0, 3.0]), p).expect("valid");
        let pts = e.projection_boundary(0, 1, 16).expect("ok");
        assert_eq!(pts.len(), 16);
        let proj = e.project(&[0, 1]).expect("ok");
        for q in pts {
            let d = proj.normalized_distance(&v(&q)).expect("ok");
            assert!((d - 1.0).abs() < 1e-13);
        }
        assert!(e.projection_boundary(0, 1, 0).expect("ok").is_empty());
    }

    #[test]
    fn affine_map_closed_form() {
        let e = Ellipsoid::axis_aligned(v(&[1.0, 2.0]), &[1.0, 2.0]).expect("valid");
        let a = m(2, 2, &[0.0, 1.0, 2.0, 0.0]);
        let img = e.affine_map(&a, &v(&[1.0, 1.0])).expect("ok");
        assert_eq!(img.center(), &v(&[3.0, 3.0]));
        assert!((img.shape() - m(2, 2, &[4.0, 0.0, 0.0, 4.0])).amax() < 1e-14);
        // Projection onto one coordinate via a 1×2 map.
        let row = e.affine_map(&m(1, 2, &[1.0, 1.0]), &v(&[0.0])).expect("ok");
        assert!((row.shape()[(0, 0)] - 5.0).abs() < 1e-14);
        let s = e.scaled(2.0).expect("ok");
        assert!((s.shape() - m(2, 2, &[4.0, 0.0, 0.0, 16.0])).amax() < 1e-14);
        let t = e.translated(&v(&[1.0, -2.0])).expect("ok");
        assert_eq!(t.center(), &v(&[2.0, 0.0]));
    }
}
