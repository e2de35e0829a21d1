//! Angle outputs in the linear set-membership filter (docs/angles.md, (A5)): `y = wrap(C x + v)`.
//!
//! Over the predicted set `A 𝓔(x̂, P) ⊕ 𝓔(0, Q) + B u` the output `C_i x` lies in
//! `C_i (A x̂ + B u) ± (√(gᵀ P g) + √(C_i Q C_iᵀ))`, `g = Aᵀ C_iᵀ` (the supports of the two
//! ellipsoids in the direction `C_iᵀ`), evaluated in interval arithmetic; widened by `V`'s
//! projection `±√R_ii` it holds `C_i x + v`. The measurement's branch is its one representative
//! there ([`crate::angle_branch`]); the shifted value carries a rounding bound, which inflates `R`
//! (a box on those rows, the least-trace ellipsoid around `R` and it: the same inflation as
//! `smf-nl`'s remainders), so containment stays certified. An enclosure 2π wide loses the
//! guarantee (typed); no representative contradicts the set.

use intervals::Interval;
use nalgebra::{DMatrix, DVector};

use models::StepModel;

use super::nonlinear::inflate;
use crate::angle_branch::{Branch, branch};
use crate::error::EstimatorError;

/// The buffers of the branch choice, allocated with the filter.
#[derive(Debug, Clone)]
pub(super) struct AngleWork {
    /// `y` with its angle outputs on their branch.
    pub(super) y: DVector<f64>,
    /// `R` inflated by the shifts' rounding.
    pub(super) r: DMatrix<f64>,
    err: Vec<f64>,
    rho: DVector<f64>,
    v_half: Vec<f64>,
    g: Vec<Interval>,
    /// The measured angle outputs of a partial step.
    pub(super) measured: Vec<usize>,
}

impl AngleWork {
    pub(super) fn new(n: usize, m: usize) -> Self {
        Self {
            y: DVector::zeros(m),
            r: DMatrix::zeros(m, m),
            err: vec![0.0; m],
            rho: DVector::zeros(m),
            v_half: vec![0.0; m],
            g: vec![Interval::ZERO; n],
            measured: Vec::with_capacity(m),
        }
    }

    /// Puts the angle outputs `outputs` of `y` on their branch over the set predicted from
    /// `𝓔(centre, shape)` with `model`, `u` and the process noise `q` into `self.y`, and `R`
    /// inflated by the shifts' rounding into `self.r`. Allocation-free.
    ///
    /// # Errors
    /// [`EstimatorError::GuaranteeLost`] at `step` when an enclosure spans 2π.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn choose(
        &mut self,
        model: &StepModel<'_>,
        outputs: &[usize],
        (centre, shape): (&DVector<f64>, &DMatrix<f64>),
        q: &DMatrix<f64>,
        u: &DVector<f64>,
        r: &DMatrix<f64>,
        y: &DVector<f64>,
        step: u64,
    ) -> Result<Branch, EstimatorError> {
        let n = centre.len();
        for (i, h) in self.v_half.iter_mut().enumerate() {
            *h = Interval::point(r[(i, i)].max(0.0)).sqrt().hi();
        }
        let Self { y: out, err, g, v_half, .. } = self;
        let (a, b, c) = (model.a, model.b, model.c);
        let enclosure = |i: usize| {
            // The centre C_i (A x̂ + B u) and g = Aᵀ C_iᵀ, in intervals.
            let mut mid = Interval::ZERO;
            for (k, gk) in g.iter_mut().enumerate() {
                let mut pred = Interval::ZERO;
                for j in 0..n {
                    pred = pred + Interval::point(a[(k, j)]) * centre[j];
                }
                for j in 0..b.ncols() {
                    pred = pred + Interval::point(b[(k, j)]) * u[j];
                }
                mid = mid + Interval::point(c[(i, k)]) * pred;
                *gk = Interval::ZERO;
            }
            for (j, gj) in g.iter_mut().enumerate() {
                for k in 0..n {
                    *gj = *gj + Interval::point(a[(k, j)]) * c[(i, k)];
                }
            }
            let (mut gpg, mut cqc) = (Interval::ZERO, Interval::ZERO);
            for j in 0..n {
                for l in 0..n {
                    gpg = gpg + g[j] * shape[(j, l)] * g[l];
                    cqc = cqc + Interval::point(c[(i, j)]) * q[(j, l)] * c[(i, l)];
                }
            }
            let radius = gpg.max(Interval::ZERO).sqrt() + cqc.max(Interval::ZERO).sqrt();
            mid + Interval::new(-radius.hi(), radius.hi())
        };
        let found = branch(outputs, y, enclosure, v_half, out, err, step)?;
        for (rho, e) in self.rho.iter_mut().zip(self.err.iter()) {
            *rho = *e;
        }
        inflate(r, &self.rho, &mut self.r);
        Ok(found)
    }
}
