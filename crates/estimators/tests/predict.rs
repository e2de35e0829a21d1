//! Prediction-only steps (a measurement missing from a log): the set-membership filter's set
//! still contains the truth with noise on the boundary of its sets (and grows while measurements
//! are missing), the Kalman filter's prediction is `A x + B u`, `A P Aᵀ + Q`, the EKF's equals the
//! Kalman filter's on a linear model, and bad input leaves the filters unchanged.

mod common;

use carrier_dynamics::{CarrierModel, CarrierParams};
use estimators::Setup;
use estimators::{DynEstimator, ExtendedKalmanFilter, KalmanFilter, LinearModel, SetMembershipFilter, StepModel};
use models::{ConstantModel, Noise, SimulationConfig, simulate_ltv};
use nalgebra::{DMatrix, DVector};

#[test]
fn sets_with_gaps_still_contain_the_truth_and_grow_while_blind() {
    let d = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap();
    let (a, b, _) = d.to_dynamic();
    let c = DMatrix::from_row_slice(3, 4, &[0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]);
    let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1.6e-7, 1e-6, 4e-10, 1e-6]));
    let r = DMatrix::identity(3, 3) * 2e-5;
    let p0 = DMatrix::identity(4, 4) * 1e-2;
    let model = StepModel::new(&a, &b, &c);
    for seed in 0..3 {
        let run = simulate_ltv(
            &ConstantModel::new(a.clone(), b.clone(), c.clone()).unwrap(),
            &SimulationConfig {
                x0: DVector::from_vec(vec![0.02, -0.03, 0.01, 0.0]),
                inputs: (0..1500).map(|k| DVector::from_element(8, 0.05 * (k as f64 * 0.01).sin())).collect(),
                process_noise: Noise::ellipsoid_boundary(q.clone()).unwrap(),
                measurement_noise: Noise::ellipsoid_boundary(r.clone()).unwrap(),
                seed,
            },
        )
        .unwrap();
        let mut f = SetMembershipFilter::new(common::setup(&DVector::zeros(4), &p0, &q, &r, 8)).unwrap();
        let mut worst = 0.0f64;
        let mut previous_trace = f64::INFINITY;
        for k in 0..run.steps() {
            // Blind stretches: steps 300–349 and every seventh step.
            let blind = (300..350).contains(&k) || k % 7 == 3;
            let e = if blind {
                f.predict(&model, &run.inputs[k]).unwrap()
            } else {
                f.step(&model, &run.inputs[k], &run.measurements[k + 1]).unwrap()
            };
            let ell = e.to_ellipsoid().unwrap();
            worst = worst.max(ell.normalized_distance(&run.states[k + 1]).unwrap());
            if (301..350).contains(&k) {
                assert!(e.trace() > previous_trace, "the set must grow while blind (step {k})");
            }
            assert!(e.report.guaranteed && e.report.consistency.is_consistent());
            previous_trace = e.trace();
        }
        assert!(worst <= 1.0 + 1e-9, "seed {seed}: the truth left a predicted set ({worst})");
    }
}

#[test]
fn kalman_and_extended_kalman_predictions() {
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, -0.2, 0.95]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 0.1]);
    let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
    let (q, r, p0) = (DMatrix::identity(2, 2) * 0.01, DMatrix::identity(1, 1) * 0.1, DMatrix::identity(2, 2));
    let x0 = DVector::from_vec(vec![1.0, -1.0]);
    let u = DVector::from_vec(vec![0.5]);
    let model = StepModel::new(&a, &b, &c);
    let mut kf = KalmanFilter::new(common::setup(&x0, &p0, &q, &r, 1)).unwrap();
    let mut ekf = ExtendedKalmanFilter::new(common::setup(&x0, &p0, &q, &r, 1)).unwrap();
    let e = kf.predict(&model, &u).unwrap().clone();
    assert!((&e.center - (&a * &x0 + &b * &u)).amax() < 1e-15);
    assert!((&e.covariance - (&a * &p0 * a.transpose() + &q)).amax() < 1e-15);
    let g = ekf.predict(&model, &u).unwrap();
    assert!((&g.center - &e.center).amax() < 1e-15 && (&g.covariance - &e.covariance).amax() < 1e-15);
    // Through the registry's object-safe face, and bad input leaves the filter unchanged.
    let mut boxed: Box<dyn for<'m> DynEstimator<dyn LinearModel + 'm>> = Box::new(kf.clone());
    let before = boxed.estimate_dyn().center().clone();
    assert!(boxed.predict_dyn(&model, &DVector::from_vec(vec![f64::NAN])).is_err());
    assert_eq!(boxed.estimate_dyn().center(), &before);
    assert!(boxed.predict_dyn(&model, &u).is_ok());
    let mut smf =
        SetMembershipFilter::new(Setup { x0, p0, process_noise: q, measurement_noise: r, inputs: 1 }).unwrap();
    let snapshot = smf.estimate().clone();
    assert!(smf.predict(&model, &DVector::zeros(2)).is_err());
    assert_eq!(smf.estimate(), &snapshot);
}
