//! The error-state truth of the paper's simulation (`docs/bds-ins-fuzzy-kf.md` §3, experiment
//! (a)): `X_{k+1} = Φ X_k + w_k`, `w_k ~ N(0, Q_k)`, from a given initial error. `Q_k` of the
//! digest's model is only positive semidefinite (constant biases), so samples are drawn with a
//! symmetric square root from the eigendecomposition rather than a Cholesky factor.

use models::validate::ParamError;
use nalgebra::{DMatrix, DVector};

use models::Xoshiro256StarStar;

use crate::error::BdsInsError;
use crate::model::{DiscreteInsModel, STATES};

/// Draws `N(0, C)` samples for a symmetric positive semidefinite `C` as `L z`, `z ~ N(0, I)`,
/// with `L = V diag(√λ)` from `C = V diag(λ) Vᵀ` (eigenvalues within `−1e−12 max λ` of zero are
/// taken as zero).
#[derive(Debug, Clone, PartialEq)]
pub struct GaussianSampler {
    factor: DMatrix<f64>,
    z: DVector<f64>,
}

impl GaussianSampler {
    /// A sampler for covariance `c` (square, symmetric within `1e−10` relative, PSD).
    ///
    /// # Errors
    /// [`BdsInsError::DimensionMismatch`] for a non-square matrix,
    /// [`BdsInsError::NotPositiveSemidefinite`] for a non-finite, asymmetric or indefinite one.
    pub fn new(what: &'static str, c: &DMatrix<f64>) -> Result<Self, BdsInsError> {
        let n = c.nrows();
        if c.ncols() != n {
            return Err(BdsInsError::DimensionMismatch { what, expected: n, found: c.ncols() });
        }
        let scale = c.amax();
        let asym = (c - c.transpose()).amax();
        if !scale.is_finite() || asym > 1e-10 * scale {
            return Err(BdsInsError::NotPositiveSemidefinite { what, min_eigenvalue: f64::NAN });
        }
        let sym = (c + c.transpose()) * 0.5;
        let eig = sym.symmetric_eigen();
        let lmax = eig.eigenvalues.amax();
        let lmin = eig.eigenvalues.min();
        if lmin < -1e-12 * lmax {
            return Err(BdsInsError::NotPositiveSemidefinite { what, min_eigenvalue: lmin });
        }
        let mut factor = eig.eigenvectors;
        for (j, l) in eig.eigenvalues.iter().enumerate() {
            let s = l.max(0.0).sqrt();
            factor.column_mut(j).iter_mut().for_each(|v| *v *= s);
        }
        Ok(Self { factor, z: DVector::zeros(n) })
    }

    /// The square root `L` (`L Lᵀ = C`).
    #[must_use]
    pub fn factor(&self) -> &DMatrix<f64> {
        &self.factor
    }

    /// Writes one sample into `out` (length `n`; no allocation).
    ///
    /// # Errors
    /// [`BdsInsError::DimensionMismatch`] if `out` has the wrong length.
    pub fn sample_into(&mut self, rng: &mut Xoshiro256StarStar, out: &mut DVector<f64>) -> Result<(), BdsInsError> {
        if out.len() != self.z.len() {
            return Err(BdsInsError::DimensionMismatch { what: "sample", expected: self.z.len(), found: out.len() });
        }
        for z in self.z.iter_mut() {
            *z = rng.standard_normal();
        }
        self.factor.mul_to(&self.z, out);
        Ok(())
    }
}

/// Simulates the error state for `steps` periods from `x0` (13 entries): returns
/// `X_0, X_1, …, X_steps` with `X_{k+1} = Φ X_k + w_k`, `w_k ~ N(0, Q_k)` drawn from `rng`
/// (13 normal draws per step).
///
/// # Errors
/// A wrong length of `x0`, a non-finite `x0`, or a `Q_k` that is not PSD.
pub fn simulate_error_states(
    model: &DiscreteInsModel,
    x0: &DVector<f64>,
    steps: usize,
    rng: &mut Xoshiro256StarStar,
) -> Result<Vec<DVector<f64>>, BdsInsError> {
    if x0.len() != STATES {
        return Err(BdsInsError::DimensionMismatch { what: "x0", expected: STATES, found: x0.len() });
    }
    if let Some(v) = x0.iter().find(|v| !v.is_finite()) {
        return Err(ParamError::NonFinite { name: "x0 (initial error state)", value: *v }.into());
    }
    let mut sampler = GaussianSampler::new("Q_k", &model.q)?;
    let mut w = DVector::zeros(STATES);
    let mut states = Vec::with_capacity(steps + 1);
    states.push(x0.clone());
    for k in 0..steps {
        sampler.sample_into(rng, &mut w)?;
        let next = &model.phi * &states[k] + &w;
        states.push(next);
    }
    Ok(states)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sampler_reproduces_a_singular_covariance() {
        // Rank one: C = v vᵀ.
        let v = DVector::from_vec(vec![1.0, 2.0, -1.0]);
        let c = &v * v.transpose();
        let s = GaussianSampler::new("C", &c).unwrap();
        assert!((s.factor() * s.factor().transpose() - &c).amax() < 1e-12);
        let bad = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, -1.0]);
        assert!(matches!(GaussianSampler::new("C", &bad), Err(BdsInsError::NotPositiveSemidefinite { .. })));
        let asym = DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.0, 1.0]);
        assert!(GaussianSampler::new("C", &asym).is_err());
        assert!(GaussianSampler::new("C", &DMatrix::zeros(2, 3)).is_err());
        // Sample covariance of 20 000 draws within a few percent.
        let c = DMatrix::from_row_slice(2, 2, &[4.0, 1.0, 1.0, 1.0]);
        let mut s = GaussianSampler::new("C", &c).unwrap();
        let mut rng = Xoshiro256StarStar::seed_from_u64(3);
        let mut out = DVector::zeros(2);
        let mut acc = DMatrix::zeros(2, 2);
        let n = 20_000;
        for _ in 0..n {
            s.sample_into(&mut rng, &mut out).unwrap();
            acc += &out * out.transpose();
        }
        acc /= n as f64;
        assert!((acc - c).amax() < 0.12);
        assert!(s.sample_into(&mut rng, &mut DVector::zeros(3)).is_err());
    }
}
