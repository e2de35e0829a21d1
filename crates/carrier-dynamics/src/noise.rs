//! Unknown-but-bounded noise models (paper eqs (8)–(9)) and their seeded samplers.

use nalgebra::{DMatrix, DVector};

use crate::error::{DynamicsError, check_dims, check_finite};
use crate::rng::Xoshiro256StarStar;

/// Which distribution a [`BoundedNoise`] draws from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
}

/// A validated bounded-noise model of fixed dimension. Construct with [`BoundedNoise::none`],
/// [`BoundedNoise::uniform_box`], [`BoundedNoise::uniform_cube`],
/// [`BoundedNoise::uniform_ellipsoid`] or [`BoundedNoise::ellipsoid_boundary`].
#[derive(Debug, Clone, PartialEq)]
pub struct BoundedNoise {
    distribution: NoiseDistribution,
    /// Box half-widths (box), or the shape matrix `Q` (ellipsoids); empty for none.
    half_widths: Option<DVector<f64>>,
    shape: Option<DMatrix<f64>>,
    /// Lower Cholesky factor `L` of `Q = L Lᵀ` (ellipsoids).
    factor: Option<DMatrix<f64>>,
    dim: usize,
}

/// Relative symmetry tolerance for `Q`: `max |Q_ij − Q_ji| ≤ 1e-10 · max |Q_ij|`.
const SYMMETRY_TOL: f64 = 1e-10;

impl BoundedNoise {
    /// No noise, of dimension `dim`.
    #[must_use]
    pub fn none(dim: usize) -> Self {
        Self { distribution: NoiseDistribution::None, half_widths: None, shape: None, factor: None, dim }
    }

    /// Components independently uniform in `[−a_i, a_i)` (the paper's `|w_k| ≤ 0.3`).
    ///
    /// # Errors
    /// [`DynamicsError::InvalidHalfWidth`] for a negative or non-finite half-width.
    pub fn uniform_box(half_widths: DVector<f64>) -> Result<Self, DynamicsError> {
        for (index, &value) in half_widths.iter().enumerate() {
            if !(value.is_finite() && value >= 0.0) {
                return Err(DynamicsError::InvalidHalfWidth { index, value });
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

    /// [`BoundedNoise::uniform_box`] with the same half-width for all `dim` components.
    ///
    /// # Errors
    /// As [`BoundedNoise::uniform_box`].
    pub fn uniform_cube(dim: usize, half_width: f64) -> Result<Self, DynamicsError> {
        Self::uniform_box(DVector::from_element(dim, half_width))
    }

    /// Uniform inside `{w : wᵀ Q⁻¹ w ≤ 1}`: direction `g/‖g‖` (`g` standard normal), radius
    /// `U^{1/n}`, mapped through the Cholesky factor `L` of `Q`.
    ///
    /// # Errors
    /// See [`BoundedNoise::ellipsoid_boundary`].
    pub fn uniform_ellipsoid(shape: DMatrix<f64>) -> Result<Self, DynamicsError> {
        Self::ellipsoid(shape, NoiseDistribution::UniformEllipsoid)
    }

    /// On the boundary `wᵀ Q⁻¹ w = 1`: as [`BoundedNoise::uniform_ellipsoid`] with radius 1.
    ///
    /// # Errors
    /// [`DynamicsError::DimensionMismatch`] if `Q` is not square,
    /// [`DynamicsError::NonFiniteEntry`], [`DynamicsError::NotSymmetric`] (beyond
    /// `1e-10 · max |Q_ij|`; within it `Q` is symmetrised), [`DynamicsError::NotPositiveDefinite`].
    pub fn ellipsoid_boundary(shape: DMatrix<f64>) -> Result<Self, DynamicsError> {
        Self::ellipsoid(shape, NoiseDistribution::EllipsoidBoundary)
    }

    fn ellipsoid(shape: DMatrix<f64>, distribution: NoiseDistribution) -> Result<Self, DynamicsError> {
        let n = shape.nrows();
        check_dims("ellipsoid shape matrix Q", &shape, n, n)?;
        check_finite("ellipsoid shape matrix Q", &shape)?;
        let asymmetry = (&shape - shape.transpose()).amax();
        let tolerance = SYMMETRY_TOL * shape.amax();
        if asymmetry > tolerance {
            return Err(DynamicsError::NotSymmetric { asymmetry, tolerance });
        }
        let shape = (&shape + shape.transpose()) * 0.5;
        let factor = shape
            .clone()
            .cholesky()
            .map(|c| c.l())
            .filter(|l| l.diagonal().iter().all(|d| d.is_finite() && *d > 0.0))
            .ok_or(DynamicsError::NotPositiveDefinite)?;
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
    fn q_norm2(noise: &BoundedNoise, w: &DVector<f64>) -> f64 {
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
        let noise = BoundedNoise::uniform_box(a.clone()).unwrap();
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
        let cube = BoundedNoise::uniform_cube(4, 0.5).unwrap();
        assert_eq!(cube.dim(), 4);
    }

    #[test]
    fn ellipsoid_samples_are_inside_and_boundary_samples_on_it() {
        let q = test_shape();
        let inside = BoundedNoise::uniform_ellipsoid(q.clone()).unwrap();
        let boundary = BoundedNoise::ellipsoid_boundary(q.clone()).unwrap();
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
        let noise = BoundedNoise::none(3);
        let mut rng = Xoshiro256StarStar::seed_from_u64(5);
        let before = rng.clone();
        assert_eq!(noise.sample(&mut rng), DVector::zeros(3));
        assert_eq!(rng, before);
        assert_eq!(noise.distribution(), NoiseDistribution::None);
        assert!(noise.shape().is_none() && noise.half_widths().is_none());
        // A zero-dimensional ellipsoid is valid and draws nothing either.
        let e = BoundedNoise::ellipsoid_boundary(DMatrix::zeros(0, 0)).unwrap();
        assert_eq!(e.sample(&mut rng).len(), 0);
    }

    #[test]
    fn invalid_noise_parameters_are_named() {
        let e = BoundedNoise::uniform_box(DVector::from_row_slice(&[0.1, -0.2])).unwrap_err();
        assert_eq!(e.to_string(), "box noise half-width 1 must be finite and non-negative, got -0.2");
        let e = BoundedNoise::uniform_cube(2, f64::NAN).unwrap_err();
        assert_eq!(e.to_string(), "box noise half-width 0 must be finite and non-negative, got NaN");
        let e = BoundedNoise::uniform_ellipsoid(DMatrix::zeros(2, 3)).unwrap_err();
        assert_eq!(e.to_string(), "ellipsoid shape matrix Q: expected 2x2, got 2x3");
        let mut q = DMatrix::identity(2, 2);
        q[(0, 1)] = f64::INFINITY;
        let e = BoundedNoise::uniform_ellipsoid(q).unwrap_err();
        assert_eq!(e.to_string(), "ellipsoid shape matrix Q has a non-finite entry at (0, 1)");
        let q = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.4, 1.0]);
        let e = BoundedNoise::ellipsoid_boundary(q).unwrap_err();
        assert!(e.to_string().starts_with("ellipsoid shape matrix Q is not symmetric: max |Q - Q^T| = 0.09999"), "{e}");
        let q = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let e = BoundedNoise::uniform_ellipsoid(q).unwrap_err();
        assert_eq!(e.to_string(), "ellipsoid shape matrix Q is not positive definite (Cholesky factorisation failed)");
        let e = BoundedNoise::uniform_ellipsoid(DMatrix::zeros(2, 2)).unwrap_err();
        assert_eq!(e, DynamicsError::NotPositiveDefinite);
        // Round-off asymmetry is tolerated and removed.
        let mut q = test_shape();
        q[(0, 1)] += 1e-14;
        let noise = BoundedNoise::uniform_ellipsoid(q).unwrap();
        let s = noise.shape().unwrap();
        assert_eq!(s, &s.transpose());
    }
}
