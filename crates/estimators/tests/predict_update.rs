//! `predict` then `update` against `step`, for every recursive filter: the same numbers (bit for
//! bit where the arithmetic is the same), a failed update leaves the filter as it was, the
//! set-membership filter's update needs its prediction, and every estimate reports an honest
//! status (predicted, converged, inconsistent and no longer guaranteed).

use carrier_dynamics::{CarrierModel, CarrierParams};
use estimators::{
    AdaptiveKalmanFilter, ConstantScaling, DataCheck, Estimate, Estimator, EstimatorError, ExtendedKalmanFilter,
    Guarantee, InconsistencyPolicy, KalmanFilter, SetMembershipFilter, Setup, SolveOutcome, StepModel, UkfParams,
    UnscentedKalmanFilter,
};
use models::{ConstantModel, Noise, SimulationConfig, simulate_ltv};
use nalgebra::{DMatrix, DVector};

/// The carrier at 6 m/s, yaw rate, roll and roll rate measured; data on the boundary of the
/// noise sets.
struct Case {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    setup: Setup,
    inputs: Vec<DVector<f64>>,
    ys: Vec<DVector<f64>>,
}

fn case(steps: usize) -> Case {
    let d = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap();
    let (a, b, _) = d.to_dynamic();
    let c = DMatrix::from_row_slice(3, 4, &[0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.]);
    let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1.6e-7, 1e-6, 4e-10, 1e-6]));
    let r = DMatrix::identity(3, 3) * 2e-5;
    let run = simulate_ltv(
        &ConstantModel::new(a.clone(), b.clone(), c.clone()).unwrap(),
        &SimulationConfig {
            x0: DVector::from_vec(vec![0.02, -0.03, 0.01, 0.0]),
            inputs: (0..steps).map(|k| DVector::from_element(8, 0.05 * (k as f64 * 0.01).sin())).collect(),
            process_noise: Noise::ellipsoid_boundary(q.clone()).unwrap(),
            measurement_noise: Noise::ellipsoid_boundary(r.clone()).unwrap(),
            seed: 3,
        },
    )
    .unwrap();
    let setup = Setup {
        x0: DVector::zeros(4),
        p0: DMatrix::identity(4, 4) * 1e-2,
        process_noise: q,
        measurement_noise: r,
        inputs: 8,
    };
    Case { a, b, c, setup, inputs: run.inputs.clone(), ys: run.measurements[1..].to_vec() }
}

/// Runs `f` over the case twice, by `step` and by `predict` + `update`, and returns the largest
/// difference of the centres and shapes.
fn split_against_joint<E>(mut joint: E, mut split: E, cs: &Case) -> f64
where
    E: for<'m> Estimator<StepModel<'m>>,
{
    let model = StepModel::new(&cs.a, &cs.b, &cs.c);
    let mut worst = 0.0f64;
    for (u, y) in cs.inputs.iter().zip(&cs.ys) {
        let j = joint.step(&model, u, y).unwrap();
        let (jc, js) = (j.center().clone(), j.shape().clone());
        let p = split.predict(&model, u).unwrap();
        assert_eq!(p.status().outcome, SolveOutcome::Predicted);
        let s = split.update(&model, y).unwrap();
        assert_eq!(s.status(), joint.estimate().status());
        worst = worst.max((s.center() - &jc).amax()).max((s.shape() - &js).amax());
    }
    worst
}

#[test]
fn predict_then_update_is_a_step() {
    let cs = case(300);
    let kf = || KalmanFilter::new(cs.setup.clone()).unwrap();
    assert_eq!(split_against_joint(kf(), kf(), &cs), 0.0, "Kalman");
    let ekf = || ExtendedKalmanFilter::new(cs.setup.clone()).unwrap();
    assert_eq!(split_against_joint(ekf(), ekf(), &cs), 0.0, "EKF");
    let ukf = || UnscentedKalmanFilter::new(cs.setup.clone(), UkfParams::default()).unwrap();
    assert_eq!(split_against_joint(ukf(), ukf(), &cs), 0.0, "UKF");
    // The set-membership filter's update is the joint step from the set before the prediction.
    let smf = || SetMembershipFilter::new(cs.setup.clone()).unwrap();
    assert_eq!(split_against_joint(smf(), smf(), &cs), 0.0, "set-membership");
}

#[test]
fn the_adaptive_filter_takes_the_receiver_status_with_its_measurement() {
    let cs = case(200);
    let model = StepModel::new(&cs.a, &cs.b, &cs.c);
    let mut adaptive = AdaptiveKalmanFilter::new(cs.setup.clone(), ConstantScaling(1.0)).unwrap();
    let mut kf = KalmanFilter::new(cs.setup.clone()).unwrap();
    assert_eq!(adaptive.dims().outputs, 5);
    for (k, (u, y)) in cs.inputs.iter().zip(&cs.ys).enumerate() {
        // Every fifth epoch without a fix (RTK 0): a prediction.
        let rtk = if k % 5 == 4 { 0.0 } else { 3.0 };
        let measurement = DVector::from_iterator(5, y.iter().copied().chain([12.0, rtk]));
        let e = Estimator::step(&mut adaptive, &model, u, &measurement).unwrap();
        let reference = if rtk == 0.0 { kf.predict(&model, u).unwrap() } else { kf.step(&model, u, y).unwrap() };
        assert_eq!(e.center, reference.center, "with t = 1 it is the Kalman filter (epoch {k})");
        let (scale, status) = (e.details.get("scale"), e.status.outcome);
        match (rtk == 0.0, adaptive.last_step()) {
            (true, None) => assert_eq!((scale, status), (Some(None), SolveOutcome::Predicted)),
            (false, Some(a)) => assert_eq!((a.scale, scale), (1.0, Some(Some(1.0)))),
            other => panic!("epoch {k}: {other:?}"),
        }
    }
    // A bad RTK code names its component and leaves the filter unchanged.
    let before = adaptive.estimate().clone();
    let bad = DVector::from_iterator(5, cs.ys[0].iter().copied().chain([12.0, 9.0]));
    let e = Estimator::step(&mut adaptive, &model, &cs.inputs[0], &bad).unwrap_err();
    assert!(matches!(e, EstimatorError::Adaptive { index: Some(4), .. }), "{e}");
    assert_eq!(adaptive.estimate(), &before);
}

#[test]
fn a_failed_update_leaves_the_filter_unchanged() {
    let cs = case(5);
    let model = StepModel::new(&cs.a, &cs.b, &cs.c);
    let (u, y) = (&cs.inputs[0], &cs.ys[0]);
    let nan = DVector::from_element(3, f64::NAN);
    let mut kf = KalmanFilter::new(cs.setup.clone()).unwrap();
    let predicted = kf.predict(&model, u).unwrap().clone();
    assert!(kf.update(&model, &nan).is_err());
    assert_eq!(kf.estimate(), &predicted);

    let mut smf = SetMembershipFilter::new(cs.setup.clone()).unwrap();
    // No prediction: the update (13)-(29) is joint with one.
    assert!(matches!(smf.update(&model, y), Err(EstimatorError::UpdateWithoutPrediction { .. })));
    let predicted = smf.predict(&model, u).unwrap().clone();
    let far = y.map(|v| v + 10.0);
    assert!(matches!(smf.update(&model, &far), Err(EstimatorError::InconsistentData { step: 1, .. })));
    assert!(smf.update(&model, &nan).is_err());
    let e = smf.estimate();
    assert_eq!((&e.center, &e.shape, e.report.tau), (&predicted.center, &predicted.shape, predicted.report.tau));
    // The prediction is still pending: the update with good data goes through, once.
    let mut reference = SetMembershipFilter::new(cs.setup.clone()).unwrap();
    let want = reference.step(&model, u, y).unwrap().clone();
    let got = smf.update(&model, y).unwrap();
    assert_eq!((&got.center, &got.shape, got.report.tau), (&want.center, &want.shape, want.report.tau));
    assert_eq!(smf.steps(), 1);
    assert!(matches!(smf.update(&model, y), Err(EstimatorError::UpdateWithoutPrediction { .. })));
}

#[test]
fn statuses_say_what_happened() {
    let cs = case(20);
    let model = StepModel::new(&cs.a, &cs.b, &cs.c);
    let mut smf = SetMembershipFilter::new(cs.setup.clone()).unwrap();
    assert_eq!(smf.estimate().status().outcome, SolveOutcome::Initial);
    let s = smf.step(&model, &cs.inputs[0], &cs.ys[0]).unwrap().status();
    assert_eq!((s.outcome, s.data, s.guarantee), (SolveOutcome::Converged, DataCheck::Consistent, Guarantee::Holds));
    // Data far outside the bounds, published by choice: inconsistent, and never guaranteed again.
    smf.set_inconsistency_policy(InconsistencyPolicy::FlagAndContinue);
    let far = cs.ys[1].map(|v| v + 10.0);
    let s = smf.step(&model, &cs.inputs[1], &far).unwrap().status();
    assert_eq!((s.data, s.guarantee), (DataCheck::Inconsistent, Guarantee::Lost));
    assert_eq!(s.label(), "converged+inconsistent+not-guaranteed");
    let s = smf.step(&model, &cs.inputs[2], &cs.ys[2]).unwrap().status();
    assert_eq!(s.guarantee, Guarantee::Lost, "once lost, the guarantee stays lost");
    assert!(!s.is_clean() && s.label().ends_with("+not-guaranteed"));
    // Gaussian estimates are never "guaranteed", point estimates have no bounds.
    let mut kf = KalmanFilter::new(cs.setup.clone()).unwrap();
    let e = kf.step(&model, &cs.inputs[0], &cs.ys[0]).unwrap();
    assert_eq!(e.status().guarantee, Guarantee::NotApplicable);
    let (lo, hi) = e.bounds(0).unwrap();
    assert_eq!((lo, hi), (e.center[0] - e.std_dev[0], e.center[0] + e.std_dev[0]));
}
