//! Noise models and their seeded samplers: unknown-but-bounded noise (boxes, ellipsoids, the
//! ellipsoid's boundary — the carrier paper's eqs (8)–(9)) and Gaussian noise.

use nalgebra::{DMatrix, DVector};

use crate::error::{ModelError, check_dims, check_finite};
use crate::rng::Xoshiro256StarStar;

/// Which distribution a [`Noise`] draws from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum NoiseDistribution {
    /// Always zero.
    None,
    /// Each component independently uniform in `[−a_i, a_i)`.
    UniformBox,
    /// Uniform inside the ellipsoid `{w : wᵀ Q⁻¹ w ≤ 1}`.
    UniformEllipsoid,
    /// On the ellipsoid's boundary `wᵀ Q⁻¹ w = 1` (direction uniform on the unit sphere mapped
    /// by the Cholesky factor): the worst case for set-membership filters.
    EllipsoidBoundary,
    /// Zero-mean Gaussian with covariance `Q` (`L g`, `g` standard normal, `Q = L Lᵀ`).
    Gaussian,
}

/// A validated noise model of fixed dimension. Construct with [`Noise::none`],
/// [`Noise::gaussian`],
/// [`Noise::uniform_box`], [`Noise::uniform_cube`],
/// [`Noise::uniform_ellipsoid`] or [`Noise::ellipsoid_boundary`].
#[derive(Debug, Clone, PartialEq)]
pub struct Noise {
    distribution: NoiseDistribution,
    /// Box half-widths (box), or the shape matrix `Q` (ellipsoids); empty for none.
    half_widths: Option<DVector<f64>>,
    shape: Option<DMatrix<f64>>,
    /// Lower Cholesky factor `L` of `Q = L Lᵀ` (ellipsoids).
    factor: Option<DMatrix<f64>>,
    dim: usize,
}

/// Relative symmetry tolerance for `Q`: `max |Q_ij − Q_ji| ≤ 1e-10 · max |Q_ij|`.
const SYMMETRY_TOL: f64 = dense_kernels::SYMMETRY_TOLERANCE;

impl Noise {
    /// No noise, of dimension `dim`.
    #[must_use]
    pub fn none(dim: usize) -> Self {
        Self { distribution: NoiseDistribution::None, half_widths: None, shape: None, factor: None, dim }
    }

    /// Components independently uniform in `[−a_i, a_i)` (the paper's `|w_k| ≤ 0.3`).
    ///
    /// # Errors
    /// [`ModelError::InvalidHalfWidth`] for a negative or non-finite half-width.
    pub fn uniform_box(half_widths: DVector<f64>) -> Result<Self, ModelError> {
        for (index, &value) in half_widths.iter().enumerate() {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ModelError::InvalidHalfWidth { index, value });
            }
        }
        Ok(Self {
            distribution: NoiseDistribution::UniformBox,
            dim: half_widths.len(),
            half_widths: Some(half_widths),
            shape: None,
            factor: None,
        })
    }

    /// [`Noise::uniform_box`] with the same half-width for all `dim` components.
    ///
    /// # Errors
    /// As [`Noise::uniform_box`].
    pub fn uniform_cube(dim: usize, half_width: f64) -> Result<Self, ModelError> {
        Self::uniform_box(DVector::from_element(dim, half_width))
    }

    /// Uniform inside `{w : wᵀ Q⁻¹ w ≤ 1}`: direction `g/‖g‖` (`g` standard normal), radius
    /// `U^{1/n}`, mapped through the Cholesky factor `L` of `Q`.
    ///
    /// # Errors
    /// See [`Noise::ellipsoid_boundary`].
    pub fn uniform_ellipsoid(shape: DMatrix<f64>) -> Result<Self, ModelError> {
        Self::ellipsoid(shape, NoiseDistribution::UniformEllipsoid)
    }

    /// On the boundary `wᵀ Q⁻¹ w = 1`: as [`Noise::uniform_ellipsoid`] with radius 1.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] if `Q` is not square,
    /// [`ModelError::NonFiniteEntry`], [`ModelError::NotSymmetric`] (beyond
    /// `1e-10 · max |Q_ij|`; within it `Q` is symmetrised), [`ModelError::NotPositiveDefinite`].
    pub fn ellipsoid_boundary(shape: DMatrix<f64>) -> Result<Self, ModelError> {
        Self::ellipsoid(shape, NoiseDistribution::EllipsoidBoundary)
    }

    /// Zero-mean Gaussian noise with covariance `Q` (symmetric positive definite).
    ///
    /// # Errors
    /// As [`Noise::ellipsoid_boundary`], naming the covariance.
    pub fn gaussian(covariance: DMatrix<f64>) -> Result<Self, ModelError> {
        Self::factored(covariance, NoiseDistribution::Gaussian, "noise covariance Q")
    }

    fn ellipsoid(shape: DMatrix<f64>, distribution: NoiseDistribution) -> Result<Self, ModelError> {
        Self::factored(shape, distribution, "ellipsoid shape matrix Q")
    }

    fn factored(shape: DMatrix<f64>, distribution: NoiseDistribution, what: &'static str) -> Result<Self, ModelError> {
        let n = shape.nrows();
        check_dims(what, &shape, n, n)?;
        check_finite(what, &shape)?;
        if let Some((_, _, asymmetry, tolerance)) = dense_kernels::max_asymmetry(&shape, SYMMETRY_TOL) {
            return Err(ModelError::NotSymmetric { what, asymmetry, tolerance });
        }
        let shape = (&shape + shape.transpose()) * 0.5;
        // nalgebra's factor (bit-stable samples across versions of this crate); positive
        // definiteness is judged by the workspace's pivot test.
        let pd = dense_kernels::cholesky_checked(&shape, dense_kernels::PD_RELATIVE_TOLERANCE)
            .map_err(|f| ModelError::NotPositiveDefinite { what, pivot: f.pivot, value: f.value })?;
        let factor = shape.clone().cholesky().map(|c| c.l()).unwrap_or(pd);
        Ok(Self { distribution, half_widths: None, shape: Some(shape), factor: Some(factor), dim: n })
    }

    /// Dimension of the noise vector.
    #[must_use]
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The distribution drawn from.
    #[must_use]
    pub fn distribution(&self) -> NoiseDistribution {
        self.distribution
    }

    /// Box half-widths (box noise only).
    #[must_use]
    pub fn half_widths(&self) -> Option<&DVector<f64>> {
        self.half_widths.as_ref()
    }

    /// The (symmetrised) shape matrix `Q` (ellipsoidal noise only).
    #[must_use]
    pub fn shape(&self) -> Option<&DMatrix<f64>> {
        self.shape.as_ref()
    }

    /// A direction uniform on the unit sphere of dimension `n ≥ 1` (normalised Gaussian;
    /// redrawn in the measure-zero case of a zero or non-finite norm).
    fn unit_direction(n: usize, rng: &mut Xoshiro256StarStar) -> DVector<f64> {
        loop {
            let g = DVector::from_fn(n, |_, _| rng.standard_normal());
            let norm = g.norm();
            if norm.is_finite() && norm > 0.0 {
                return g / norm;
            }
        }
    }

    /// Draws one noise vector. Draw order (fixed forever): box — one `next_f64` per component
    /// in index order; ellipsoids — `n` normals for the direction, then (uniform ellipsoid
    /// only) one `next_f64` for the radius; none — no draws.
    pub fn sample(&self, rng: &mut Xoshiro256StarStar) -> DVector<f64> {
        match (&self.half_widths, &self.factor) {
            (Some(a), _) => a.map(|a_i| rng.uniform(-a_i, a_i)),
            (None, Some(l)) if self.dim > 0 && self.distribution == NoiseDistribution::Gaussian => {
                l * DVector::from_fn(self.dim, |_, _| rng.standard_normal())
            }
            (None, Some(l)) if self.dim > 0 => {
                let dir = Self::unit_direction(self.dim, rng);
                let radius = if self.distribution == NoiseDistribution::UniformEllipsoid {
                    rng.next_f64().powf(1.0 / self.dim as f64)
                } else {
                    1.0
                };
                l * dir * radius
            }
            _ => DVector::zeros(self.dim),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `wᵀ Q⁻¹ w` through the Cholesky factor.
    fn q_norm2(noise: &Noise, w: &DVector<f64>) -> f64 {
        let l = noise.factor.as_ref().unwrap();
        let z = l.solve_lower_triangular(w).unwrap();
        z.norm_squared()
    }

    fn test_shape() -> DMatrix<f64> {
        let m = DMatrix::from_row_slice(3, 3, &[2.0, 0.5, -0.3, 0.1, 1.0, 0.7, -0.4, 0.2, 0.5]);
        &m * m.transpose() + DMatrix::identity(3, 3) * 0.1
    }

    #[test]
    fn box_samples_stay_in_the_box() {
        let a = DVector::from_row_slice(&[0.3, 0.0, 2.0]);
        let noise = Noise::uniform_box(a.clone()).unwrap();
        assert_eq!(noise.distribution(), NoiseDistribution::UniformBox);
        assert_eq!(noise.half_widths(), Some(&a));
        let mut rng = Xoshiro256StarStar::seed_from_u64(3);
        let mut max_seen: f64 = 0.0;
        for _ in 0..2000 {
            let w = noise.sample(&mut rng);
            for i in 0..3 {
                assert!(w[i] >= -a[i] && w[i] <= a[i]);
            }
            assert_eq!(w[1], 0.0);
            max_seen = max_seen.max(w[2].abs());
        }
        assert!(max_seen > 1.9, "box is filled: {max_seen}");
        let cube = Noise::uniform_cube(4, 0.5).unwrap();
        assert_eq!(cube.dim(), 4);
    }

    #[test]
    fn ellipsoid_samples_are_inside_and_boundary_samples_on_it() {
        let q = test_shape();
        let inside = Noise::uniform_ellipsoid(q.clone()).unwrap();
        let boundary = Noise::ellipsoid_boundary(q.clone()).unwrap();
        assert_eq!(boundary.distribution(), NoiseDistribution::EllipsoidBoundary);
        assert_eq!(inside.shape(), Some(&q));
        let mut rng = Xoshiro256StarStar::seed_from_u64(11);
        let n = 4000;
        let mut mean = DVector::zeros(3);
        let mut inner_shell = 0;
        for _ in 0..n {
            let w = inside.sample(&mut rng);
            let r2 = q_norm2(&inside, &w);
            assert!(r2 <= 1.0 + 1e-12, "{r2}");
            // Uniform in 3-D: P(r ≤ 1/2) = 1/8.
            if r2 <= 0.25 {
                inner_shell += 1;
            }
            let b = boundary.sample(&mut rng);
            assert!((q_norm2(&boundary, &b) - 1.0).abs() < 1e-12);
            mean += b;
        }
        mean /= f64::from(n);
        assert!(mean.amax() < 0.1, "boundary mean {mean}");
        let frac = f64::from(inner_shell) / f64::from(n);
        assert!((frac - 0.125).abs() < 0.03, "{frac}");
    }

    #[test]
    fn none_draws_nothing() {
        let noise = Noise::none(3);
        let mut rng = Xoshiro256StarStar::seed_from_u64(5);
        let before = rng.clone();
        assert_eq!(noise.sample(&mut rng), DVector::zeros(3));
        assert_eq!(rng, before);
        assert_eq!(noise.distribution(), NoiseDistribution::None);
        assert!(noise.shape().is_none() && noise.half_widths().is_none());
        // A zero-dimensional ellipsoid is valid and draws nothing either.
        let e = Noise::ellipsoid_boundary(DMatrix::zeros(0, 0)).unwrap();
        assert_eq!(e.sample(&mut rng).len(), 0);
    }

    #[test]
    fn invalid_noise_parameters_are_named() {
        let e = Noise::uniform_box(DVector::from_row_slice(&[0.1, -0.2])).unwrap_err();
        assert_eq!(e.to_string(), "box noise half-width 1 must be finite and non-negative, got -0.2");
        let e = Noise::uniform_cube(2, f64::NAN).unwrap_err();
        assert_eq!(e.to_string(), "box noise half-width 0 must be finite and non-negative, got NaN");
        let e = Noise::uniform_ellipsoid(DMatrix::zeros(2, 3)).unwrap_err();
        assert_eq!(e.to_string(), "ellipsoid shape matrix Q: expected 2x2, got 2x3");
        let mut q = DMatrix::identity(2, 2);
        q[(0, 1)] = f64::INFINITY;
        let e = Noise::uniform_ellipsoid(q).unwrap_err();
        assert_eq!(e.to_string(), "ellipsoid shape matrix Q has a non-finite entry at (0, 1)");
        let q = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.4, 1.0]);
        let e = Noise::ellipsoid_boundary(q).unwrap_err();
        assert!(e.to_string().starts_with("ellipsoid shape matrix Q is not symmetric: max |Q - Q^T| = 0.09999"), "{e}");
        let q = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let e = Noise::uniform_ellipsoid(q).unwrap_err();
        assert_eq!(e.to_string(), "ellipsoid shape matrix Q is not positive definite (Cholesky pivot 1 is -3e0)");
        let e = Noise::uniform_ellipsoid(DMatrix::zeros(2, 2)).unwrap_err();
        assert!(matches!(e, ModelError::NotPositiveDefinite { pivot: 0, .. }));
        let e = Noise::gaussian(DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.1, 1.0])).unwrap_err();
        assert!(e.to_string().starts_with("noise covariance Q is not symmetric"), "{e}");
        // Round-off asymmetry is tolerated and removed.
        let mut q = test_shape();
        q[(0, 1)] += 1e-14;
        let noise = Noise::uniform_ellipsoid(q).unwrap();
        let s = noise.shape().unwrap();
        assert_eq!(s, &s.transpose());
    }

    #[test]
    fn gaussian_samples_have_the_covariance() {
        let q = test_shape();
        let noise = Noise::gaussian(q.clone()).unwrap();
        assert_eq!(noise.distribution(), NoiseDistribution::Gaussian);
        let mut rng = Xoshiro256StarStar::seed_from_u64(17);
        let n = 20_000;
        let mut cov = DMatrix::zeros(3, 3);
        let mut mean = DVector::zeros(3);
        for _ in 0..n {
            let w = noise.sample(&mut rng);
            cov += &w * w.transpose();
            mean += w;
        }
        cov /= f64::from(n);
        mean /= f64::from(n);
        // Standard error of a covariance entry ≈ √(2/n)·‖Q‖ ≈ 0.01·‖Q‖.
        assert!((&cov - &q).amax() < 0.05 * q.amax(), "{cov} vs {q}");
        assert!(mean.amax() < 0.05 * q.amax().sqrt(), "{mean}");
    }
}
