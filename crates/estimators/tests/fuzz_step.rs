//! Bounded fuzzing of the filter step (proptest): models and data with NaN, infinities, huge and
//! tiny values never make a step panic; a step either fails and leaves the filter unchanged, or
//! publishes a finite estimate (never a NaN set marked valid).

use estimators::Setup;
use estimators::{Estimate, ExtendedKalmanFilter, InconsistencyPolicy, KalmanFilter, SetMembershipFilter, StepModel};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => -2.0f64..2.0,
        1 => prop::sample::select(vec![0.0, 1e300, -1e300, 1e-300, f64::NAN, f64::INFINITY, -f64::INFINITY, 1e154]),
    ]
}

fn matrix(r: usize, c: usize) -> impl Strategy<Value = DMatrix<f64>> {
    prop::collection::vec(value(), r * c).prop_map(move |v| DMatrix::from_vec(r, c, v))
}

fn finite(e: &dyn Estimate) -> bool {
    e.center().iter().chain(e.shape().iter()).all(|v| v.is_finite())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn steps_on_hostile_data_never_panic_nor_publish_nan(
        a in matrix(3, 3), b in matrix(3, 1), c in matrix(2, 3), u in matrix(1, 1), y in matrix(2, 1),
        steps in 1usize..4,
    ) {
        let model = StepModel::new(&a, &b, &c);
        let (u, y) = (u.column(0).into_owned(), y.column(0).into_owned());
        let (x0, p0) = (DVector::zeros(3), DMatrix::identity(3, 3));
        let (q, r) = (DMatrix::identity(3, 3) * 0.01, DMatrix::identity(2, 2) * 0.1);
        let mut smf = SetMembershipFilter::new(Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q.clone(), measurement_noise: r.clone(), inputs: 1 }).unwrap();
        let mut flagged = smf.clone();
        flagged.set_inconsistency_policy(InconsistencyPolicy::FlagAndContinue);
        let mut kf = KalmanFilter::new(Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q.clone(), measurement_noise: r.clone(), inputs: 1 }).unwrap();
        let mut ekf = ExtendedKalmanFilter::new(Setup { x0, p0, process_noise: q, measurement_noise: r, inputs: 1 }).unwrap();
        for _ in 0..steps {
            let before = smf.estimate().clone();
            match smf.step(&model, &u, &y) {
                Ok(e) => prop_assert!(finite(e)),
                Err(_) => prop_assert_eq!(smf.estimate(), &before),
            }
            let before = flagged.estimate().clone();
            match flagged.step(&model, &u, &y) {
                Ok(e) => prop_assert!(finite(e)),
                Err(_) => prop_assert_eq!(flagged.estimate(), &before),
            }
            let before = kf.estimate().clone();
            match kf.step(&model, &u, &y) {
                Ok(e) => prop_assert!(finite(e)),
                Err(_) => prop_assert_eq!(kf.estimate(), &before),
            }
            let before = ekf.estimate().clone();
            match ekf.step(&model, &u, &y) {
                Ok(e) => prop_assert!(finite(e)),
                Err(_) => prop_assert_eq!(ekf.estimate(), &before),
            }
        }
    }
}
