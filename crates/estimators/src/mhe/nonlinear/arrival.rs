//! The arrival cost of [`NonlinearMhe`](super::NonlinearMhe) (docs/dp-vessel.md §3.2): how the
//! prior `(x̄_s, P_s)` of the window's first state advances when the window slides by one sample.

use nalgebra::{DMatrix, DVector};

use dense_kernels as dense;
use models::DifferentiableModel;

use super::settings::{NonlinearArrival, NonlinearPrior};
use crate::error::EstimatorError;
use crate::traits::Setup;
use crate::ukf::UnscentedKalmanFilter;

/// An arrival prior: the mean `x̄_s`, the weight `P_s` and its inverse.
#[derive(Debug, Clone)]
pub(super) struct Prior {
    pub(super) mean: DVector<f64>,
    pub(super) cov: DMatrix<f64>,
    pub(super) inv: DMatrix<f64>,
}

impl Prior {
    /// `n`-dimensional zeros.
    pub(super) fn zeros(n: usize) -> Self {
        Self { mean: DVector::zeros(n), cov: DMatrix::zeros(n, n), inv: DMatrix::zeros(n, n) }
    }

    /// Copies `other` without allocating.
    pub(super) fn copy_from(&mut self, other: &Prior) {
        self.mean.copy_from(&other.mean);
        self.cov.copy_from(&other.cov);
        self.inv.copy_from(&other.inv);
    }
}

/// The sample at the start `s` of the window that slides away: the input `u_s` of the transition
/// `s → s + 1`, and the measurement `y_s` with the input passed with it, if one was taken.
#[derive(Debug, Clone, Copy)]
pub(super) struct StartSample<'a> {
    pub(super) u: &'a DVector<f64>,
    pub(super) measured: Option<(&'a DVector<f64>, &'a DVector<f64>)>,
    /// A partial measurement's mask and weight `(R_SS)⁻¹` embedded in `m × m`.
    pub(super) partial: Option<(&'a [bool], &'a DMatrix<f64>)>,
}

/// The arrival update and its buffers (allocated at construction).
#[derive(Debug, Clone)]
pub(super) struct Arrival {
    kind: NonlinearArrival,
    prior: NonlinearPrior,
    ukf: Option<UnscentedKalmanFilter>,
    p0: DMatrix<f64>,
    q: DMatrix<f64>,
    r_inv: DMatrix<f64>,
    centre: DVector<f64>,
    ekf_p: DMatrix<f64>,
    f_jac: DMatrix<f64>,
    h_jac: DMatrix<f64>,
    hx: DVector<f64>,
    fx: DVector<f64>,
    tmp_n: DVector<f64>,
    tmp_nm: DMatrix<f64>,
    tmp_nn: DMatrix<f64>,
    work: DMatrix<f64>,
}

impl Arrival {
    /// The update `kind` about the point `prior` says, for the setup's weights (`r_inv = R⁻¹`).
    ///
    /// # Errors
    /// UKF parameters that give no weights, and the UKF's validation of the setup.
    pub(super) fn new(
        kind: NonlinearArrival,
        prior: NonlinearPrior,
        setup: &Setup,
        r_inv: &DMatrix<f64>,
    ) -> Result<Self, EstimatorError> {
        let (n, m) = (setup.x0.len(), setup.measurement_noise.nrows());
        let ukf = match kind {
            NonlinearArrival::Ukf(params) => {
                // The arrival update re-weighs the window's oldest sample; it is not a data check.
                let mut ukf = UnscentedKalmanFilter::new(setup.clone(), params)?;
                ukf.set_data_checks(crate::checks::DataChecks::OFF)?;
                Some(ukf)
            }
            _ => None,
        };
        Ok(Self {
            kind,
            prior,
            ukf,
            p0: setup.p0.clone(),
            q: setup.process_noise.clone(),
            r_inv: r_inv.clone(),
            centre: DVector::zeros(n),
            ekf_p: DMatrix::zeros(n, n),
            f_jac: DMatrix::zeros(n, n),
            h_jac: DMatrix::zeros(m, n),
            hx: DVector::zeros(m),
            fx: DVector::zeros(n),
            tmp_n: DVector::zeros(n),
            tmp_nm: DMatrix::zeros(n, m),
            tmp_nn: DMatrix::zeros(n, n),
            work: DMatrix::zeros(n, n),
        })
    }

    /// The prior `next` of the window starting at `s + 1` from the prior `current` of the window
    /// starting at `s`, that window's estimates `x̂_{s|T}` (`first`) and `x̂_{s+1|T}` (`second`),
    /// and the sample at `s`: `x̄_{s+1} = x̂_{s+1|T}` (or the arrival filter's prediction) and
    /// `P_{s+1}` by one Kalman step (module documentation). Allocates nothing.
    ///
    /// # Errors
    /// The model's evaluation errors and the UKF's errors; [`EstimatorError::NumericalFailure`]
    /// if the updated or the new weight is not positive definite.
    pub(super) fn advance<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        current: &Prior,
        first: &DVector<f64>,
        second: &DVector<f64>,
        sample: StartSample<'_>,
        next: &mut Prior,
    ) -> Result<(), EstimatorError> {
        // The centre of the update: x̂_{s|T} (the paper's) or the arrival filter's own mean.
        let own = self.prior == NonlinearPrior::ArrivalFilter;
        self.centre.copy_from(if own { &current.mean } else { first });
        // x̄_{s+1} = x̂_{s+1|T}, unless the arrival filter's prediction replaces it below.
        next.mean.copy_from(second);
        let u = sample.u;
        match self.kind {
            NonlinearArrival::Fixed => next.cov.copy_from(&self.p0),
            NonlinearArrival::Ukf(_) => {
                // tidy: invariant — the UKF exists whenever the arrival is `Ukf` (built in `new`).
                let ukf = self.ukf.as_mut().expect("built with the settings");
                ukf.reset(&self.centre, &current.cov)?;
                match (sample.measured, sample.partial) {
                    (Some((uh, y)), Some((mask, _))) => {
                        ukf.correct_partial(model, uh, y, mask)?;
                    }
                    (Some((uh, y)), None) => {
                        ukf.correct(model, uh, y)?;
                    }
                    (None, _) => {}
                }
                let e = ukf.predict(model, u)?;
                next.cov.copy_from(&e.covariance);
                if own {
                    next.mean.copy_from(&e.center);
                }
            }
            NonlinearArrival::Ekf => {
                self.ekf_p.copy_from(&current.cov);
                if let Some((uh, y)) = sample.measured {
                    // P⁺ = (P⁻¹ + Hᵀ R⁻¹ H)⁻¹ at the centre; m⁺ = m + P⁺ Hᵀ R⁻¹ (y − h(m)).
                    model.h_with_jacobian(&self.centre, uh, &mut self.hx, &mut self.h_jac)?;
                    self.tmp_nn.copy_from(&current.inv);
                    let weight = sample.partial.map_or(&self.r_inv, |(_, w)| w);
                    self.tmp_nm.gemm_tr(1.0, &self.h_jac, weight, 0.0);
                    dense::mul_nn(1.0, &self.tmp_nm, &self.h_jac, 1.0, &mut self.tmp_nn);
                    if dense::spd_inverse(&self.tmp_nn, &mut self.work, &mut self.ekf_p).is_err() {
                        return Err(EstimatorError::NumericalFailure(
                            "the arrival-cost update is not positive definite",
                        ));
                    }
                    if own {
                        self.hx.neg_mut();
                        self.hx += y;
                        self.tmp_n.gemv(1.0, &self.tmp_nm, &self.hx, 0.0);
                        self.centre.gemv(1.0, &self.ekf_p, &self.tmp_n, 1.0);
                    }
                }
                model.f_with_jacobian(&self.centre, u, &mut self.fx, &mut self.f_jac)?;
                if own {
                    next.mean.copy_from(&self.fx);
                }
                dense::mul_nn(1.0, &self.f_jac, &self.ekf_p, 0.0, &mut self.tmp_nn);
                next.cov.copy_from(&self.q);
                dense::mul_nt(1.0, &self.tmp_nn, &self.f_jac, 1.0, &mut next.cov);
                dense::symmetrize(&mut next.cov);
            }
        }
        if dense::spd_inverse(&next.cov, &mut self.work, &mut next.inv).is_err() {
            return Err(EstimatorError::NumericalFailure("the arrival-cost weight is not positive definite"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ekf::ExtendedKalmanFilter;
    use crate::ukf::UkfParams;
    use models::{Dims, DiscreteModel, ModelError};

    /// A pendulum-like model with a nonlinear output, `n = 2`, `m = 1`, one input.
    struct Pendulum;

    impl DiscreteModel for Pendulum {
        fn dims(&self) -> Dims {
            Dims::new(2, 1, 1)
        }
        fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
            out[0] = x[0] + 0.1 * x[1];
            out[1] = x[1] - 0.1 * x[0].sin() + 0.1 * u[0];
            Ok(())
        }
        fn h(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
            out[0] = x[0].sin() + 0.5 * x[1];
            Ok(())
        }
    }

    impl DifferentiableModel for Pendulum {
        fn f_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
            out.copy_from_slice(&[1.0, -0.1 * x[0].cos(), 0.1, 1.0]);
            Ok(())
        }
        fn h_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
            out.copy_from_slice(&[x[0].cos(), 0.5]);
            Ok(())
        }
    }

    /// `α, β, κ` valid for `n = 2` (the paper's `κ = −2` needs `n > 2`).
    const PARAMS: UkfParams = UkfParams { alpha: 0.5, beta: 2.0, kappa: 1.0 };

    fn setup() -> Setup {
        Setup {
            x0: DVector::from_vec(vec![0.3, -0.1]),
            p0: DMatrix::from_row_slice(2, 2, &[0.2, 0.05, 0.05, 0.1]),
            process_noise: DMatrix::from_row_slice(2, 2, &[0.01, 0.0, 0.0, 0.02]),
            measurement_noise: DMatrix::from_element(1, 1, 0.04),
            inputs: 1,
        }
    }

    /// The prior `current` (`(x̄_s, P_s)` of the setup), the window's `x̂_{s|T}`, `x̂_{s+1|T}`,
    /// and `u_s`, `y_s`.
    fn data() -> (Prior, DVector<f64>, DVector<f64>, DVector<f64>, DVector<f64>) {
        let s = setup();
        let inv = s.p0.clone().try_inverse().unwrap();
        let current = Prior { mean: s.x0.clone(), cov: s.p0.clone(), inv };
        let v = |x: &[f64]| DVector::from_column_slice(x);
        (current, v(&[0.25, -0.05]), v(&[0.24, 0.0]), v(&[0.7]), v(&[0.4]))
    }

    fn run(kind: NonlinearArrival, prior: NonlinearPrior, measured: bool) -> Prior {
        let (current, first, second, u, y) = data();
        let r_inv = DMatrix::from_element(1, 1, 25.0);
        let mut arrival = Arrival::new(kind, prior, &setup(), &r_inv).unwrap();
        let mut next = Prior::zeros(2);
        let sample = StartSample { u: &u, measured: measured.then_some((&u, &y)), partial: None };
        arrival.advance(&Pendulum, &current, &first, &second, sample, &mut next).unwrap();
        assert!((&next.cov * &next.inv - DMatrix::identity(2, 2)).amax() < 1e-12);
        next
    }

    fn close(a: &DMatrix<f64>, b: &DMatrix<f64>) -> bool {
        (a - b).amax() <= 1e-12 * b.amax()
    }

    #[test]
    fn the_ukf_arrival_is_one_unscented_kalman_step() {
        let (current, first, second, u, y) = data();
        for prior in [NonlinearPrior::Smoothed, NonlinearPrior::ArrivalFilter] {
            for measured in [true, false] {
                let next = run(NonlinearArrival::Ukf(PARAMS), prior, measured);
                // The reference: a fresh filter at the centre, corrected with y_s, predicted with u_s.
                let centre = if prior == NonlinearPrior::Smoothed { &first } else { &current.mean };
                let mut ukf = UnscentedKalmanFilter::new(setup(), PARAMS).unwrap();
                ukf.reset(centre, &current.cov).unwrap();
                if measured {
                    ukf.correct(&Pendulum, &u, &y).unwrap();
                }
                let e = ukf.predict(&Pendulum, &u).unwrap();
                assert!(close(&next.cov, &e.covariance), "{prior:?}, measured {measured}");
                let mean = if prior == NonlinearPrior::Smoothed { &second } else { &e.center };
                assert_eq!(&next.mean, mean);
            }
        }
    }

    #[test]
    fn the_ekf_arrival_is_one_extended_kalman_step() {
        let (current, first, second, u, y) = data();
        for prior in [NonlinearPrior::Smoothed, NonlinearPrior::ArrivalFilter] {
            for measured in [true, false] {
                let next = run(NonlinearArrival::Ekf, prior, measured);
                // The reference: the Joseph-form EKF update with y_s, then the prediction with u_s,
                // linearised about the centre (Smoothed: x̂_{s|T}) or the updated mean.
                let centre = if prior == NonlinearPrior::Smoothed { &first } else { &current.mean };
                let mut ekf = ExtendedKalmanFilter::new(Setup { x0: centre.clone(), ..setup() }).unwrap();
                if measured {
                    ekf.update(&Pendulum, &y).unwrap();
                }
                let from = if prior == NonlinearPrior::Smoothed { centre } else { &ekf.estimate().center };
                let p0 = ekf.estimate().covariance.clone();
                let mut ekf = ExtendedKalmanFilter::new(Setup { x0: from.clone(), p0, ..setup() }).unwrap();
                let e = ekf.predict(&Pendulum, &u).unwrap();
                assert!((&next.cov - &e.covariance).amax() < 1e-12 * e.covariance.amax(), "{prior:?}, {measured}");
                if prior == NonlinearPrior::Smoothed {
                    assert_eq!(next.mean, second);
                } else {
                    assert!((&next.mean - &e.center).amax() < 1e-12, "{measured}");
                }
            }
        }
    }

    #[test]
    fn the_fixed_arrival_keeps_p0() {
        let (_, _, second, _, _) = data();
        let next = run(NonlinearArrival::Fixed, NonlinearPrior::Smoothed, true);
        assert_eq!(next.cov, setup().p0);
        assert_eq!(next.mean, second);
    }

    #[test]
    fn a_weight_that_is_not_positive_definite_is_an_error() {
        let (mut current, first, second, u, _) = data();
        let r_inv = DMatrix::from_element(1, 1, 25.0);
        let mut arrival = Arrival::new(NonlinearArrival::Ekf, NonlinearPrior::Smoothed, &setup(), &r_inv).unwrap();
        // A negative P_s makes F P_s Fᵀ + Q indefinite.
        current.cov *= -10.0;
        let mut next = Prior::zeros(2);
        let sample = StartSample { u: &u, measured: None, partial: None };
        let e = arrival.advance(&Pendulum, &current, &first, &second, sample, &mut next).unwrap_err();
        assert_eq!(e, EstimatorError::NumericalFailure("the arrival-cost weight is not positive definite"));
    }
}
