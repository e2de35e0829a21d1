//! The Gaussian filters' innovation gate: the normalised innovation squared it reports equals an
//! independent computation, no false alarm on data from the filter's own noise model, and each
//! policy does what it says with an outlier (the filter unchanged on an error, the data used and
//! flagged, the measurement dropped, or no check).

use estimators::{
    AdaptiveKalmanFilter, ConstantScaling, DataCheck, DataChecks, Estimator, EstimatorError, ExtendedKalmanFilter,
    InconsistencyPolicy, KalmanFilter, Setup, SolveOutcome, StepModel, UkfParams, UnscentedKalmanFilter,
};
use models::Xoshiro256StarStar;
use nalgebra::{DMatrix, DVector, dmatrix, dvector};

fn setup() -> Setup {
    Setup {
        x0: dvector![0.0, 0.0],
        p0: DMatrix::identity(2, 2) * 0.1,
        process_noise: dmatrix![1e-4, 0.0; 0.0, 1e-3],
        measurement_noise: dmatrix![0.01, 0.002; 0.002, 0.02],
        inputs: 1,
    }
}

fn system() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    (dmatrix![1.0, 0.1; -0.05, 0.97], dmatrix![0.0; 0.1], dmatrix![1.0, 0.0; 0.3, 1.0])
}

/// `n` steps of the system with Gaussian noise of the setup's covariances.
fn data(n: usize, seed: u64) -> (Vec<DVector<f64>>, Vec<DVector<f64>>) {
    let (a, b, c) = system();
    let s = setup();
    let (lq, lr) = (s.process_noise.cholesky().unwrap().l(), s.measurement_noise.cholesky().unwrap().l());
    let mut rng = Xoshiro256StarStar::seed_from_u64(seed);
    let mut g = |k: usize| DVector::from_fn(k, |_, _| rng.standard_normal());
    let mut x = &s.p0.cholesky().unwrap().l() * g(2);
    let (mut us, mut ys) = (Vec::new(), Vec::new());
    for k in 0..n {
        let u = dvector![(k as f64 * 0.05).sin()];
        x = &a * &x + &b * &u + &lq * g(2);
        ys.push(&c * &x + &lr * g(2));
        us.push(u);
    }
    (us, ys)
}

#[test]
fn the_reported_nis_is_the_innovation_against_its_covariance() {
    let (a, b, c) = system();
    let model = StepModel::new(&a, &b, &c);
    let mut kf = KalmanFilter::new(setup()).unwrap();
    let (u, y) = (dvector![0.3], dvector![5.0, -4.0]);
    // Independently: x⁻ = A x̂ + B u, P⁻ = A P Aᵀ + Q, S = C P⁻ Cᵀ + R, ν = y − C x⁻.
    let s = setup();
    let xp = &a * &s.x0 + &b * &u;
    let pp = &a * &s.p0 * a.transpose() + &s.process_noise;
    let sm = &c * &pp * c.transpose() + &s.measurement_noise;
    let nu = &y - &c * &xp;
    let want = (nu.transpose() * sm.try_inverse().unwrap() * &nu)[(0, 0)];
    let before = kf.estimate().clone();
    let Err(EstimatorError::Outlier { step: 1, nis, threshold, .. }) = kf.step(&model, &u, &y) else {
        panic!("an outlier of NIS {want} passed the gate")
    };
    assert!((nis - want).abs() < 1e-9 * want, "{nis} vs {want}");
    assert!(threshold < nis);
    assert_eq!(kf.estimate(), &before, "a refused step leaves the filter unchanged");
}

#[test]
fn data_of_the_filters_own_model_pass_the_gate() {
    let (a, b, c) = system();
    let model = StepModel::new(&a, &b, &c);
    let (us, ys) = data(5000, 11);
    let mut kf = KalmanFilter::new(setup()).unwrap();
    let mut ekf = ExtendedKalmanFilter::new(setup()).unwrap();
    let mut ukf = UnscentedKalmanFilter::new(setup(), UkfParams::default()).unwrap();
    for (u, y) in us.iter().zip(&ys) {
        for e in [kf.step(&model, u, y).unwrap(), ekf.step(&model, u, y).unwrap(), ukf.step(&model, u, y).unwrap()] {
            assert_eq!(e.status.data, DataCheck::Consistent);
        }
    }
}

#[test]
fn each_policy_does_what_it_says_with_an_outlier() {
    let (a, b, c) = system();
    let model = StepModel::new(&a, &b, &c);
    let (us, ys) = data(30, 3);
    let outlier = dvector![50.0, -50.0];
    // Every Gaussian filter, boxed behind the trait over this linear model.
    type Boxed = Box<dyn for<'m> estimators::DynEstimator<StepModel<'m>>>;
    let filters = || -> Vec<(&'static str, Boxed)> {
        let adaptive = AdaptiveKalmanFilter::new(setup(), ConstantScaling(1.0)).unwrap();
        vec![
            ("kf", Box::new(KalmanFilter::new(setup()).unwrap())),
            ("ekf", Box::new(ExtendedKalmanFilter::new(setup()).unwrap())),
            ("ukf", Box::new(UnscentedKalmanFilter::new(setup(), UkfParams::default()).unwrap())),
            ("adaptive", Box::new(AdaptiveOnOutputs(adaptive))),
        ]
    };
    for policy in [
        InconsistencyPolicy::Error,
        InconsistencyPolicy::FlagAndContinue,
        InconsistencyPolicy::Restart,
        InconsistencyPolicy::Off,
    ] {
        for (name, mut f) in filters() {
            f.set_data_checks_dyn(DataChecks::with_policy(policy)).unwrap();
            for k in 0..10 {
                f.step_dyn(&model, &us[k], &ys[k]).unwrap();
            }
            let before = f.estimate_dyn().center().clone();
            let mut reference = filters().into_iter().find(|(n, _)| *n == name).unwrap().1;
            reference.set_data_checks_dyn(DataChecks::OFF).unwrap();
            for k in 0..10 {
                reference.step_dyn(&model, &us[k], &ys[k]).unwrap();
            }
            let predicted = reference.predict_dyn(&model, &us[10]).unwrap().center().clone();
            match (policy, f.step_dyn(&model, &us[10], &outlier)) {
                (InconsistencyPolicy::Error, Err(EstimatorError::Outlier { step: 11, .. })) => {
                    assert_eq!(f.estimate_dyn().center(), &before, "{name}: unchanged after the error");
                }
                (InconsistencyPolicy::FlagAndContinue, Ok(e)) => {
                    let s = e.status();
                    assert_eq!((s.outcome, s.data), (SolveOutcome::Converged, DataCheck::Inconsistent), "{name}");
                    assert!((e.center() - &predicted).amax() > 1.0, "{name}: the outlier was used");
                }
                (InconsistencyPolicy::Restart, Ok(e)) => {
                    let s = e.status();
                    assert_eq!((s.outcome, s.data), (SolveOutcome::Predicted, DataCheck::Inconsistent), "{name}");
                    assert_eq!(e.center(), &predicted, "{name}: the measurement was dropped");
                }
                (InconsistencyPolicy::Off, Ok(e)) => assert_eq!(e.status().data, DataCheck::NotChecked, "{name}"),
                (p, other) => panic!("{name} with {p:?}: {:?}", other.map(|e| e.status())),
            }
        }
    }
    assert!(
        KalmanFilter::new(setup())
            .unwrap()
            .set_data_checks(DataChecks { gate_probability: 1.0, ..DataChecks::default() })
            .is_err()
    );
}

/// The adaptive filter with an RTK-fixed status travelling with every measurement, as a filter of
/// the model's outputs (so that it runs beside the others).
struct AdaptiveOnOutputs(AdaptiveKalmanFilter<ConstantScaling>);

impl<'m> Estimator<StepModel<'m>> for AdaptiveOnOutputs {
    type Estimate = estimators::GaussianEstimate;
    fn step(
        &mut self,
        model: &StepModel<'m>,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&Self::Estimate, EstimatorError> {
        let with_status = DVector::from_iterator(y.len() + 2, y.iter().copied().chain([12.0, 3.0]));
        self.0.step(model, u, &with_status)
    }
    fn predict(&mut self, model: &StepModel<'m>, u: &DVector<f64>) -> Result<&Self::Estimate, EstimatorError> {
        self.0.predict(model, u)
    }
    fn update(&mut self, model: &StepModel<'m>, y: &DVector<f64>) -> Result<&Self::Estimate, EstimatorError> {
        let with_status = DVector::from_iterator(y.len() + 2, y.iter().copied().chain([12.0, 3.0]));
        self.0.update(model, &with_status)
    }
    fn estimate(&self) -> &Self::Estimate {
        self.0.estimate()
    }
    fn dims(&self) -> estimators::Dims {
        self.0.dims()
    }
    fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.0.set_data_checks(checks)
    }
}

#[test]
fn an_outlier_names_the_output_with_the_largest_normalised_innovation() {
    let (a, b, c) = system();
    let model = StepModel::new(&a, &b, &c);
    let s = setup();
    let (u, y) = (dvector![0.3], dvector![0.1, 40.0]);
    // Independently: ν = y − C x⁻ and S = C P⁻ Cᵀ + R; the worst output maximises |ν_i| / √S_ii.
    let xp = &a * &s.x0 + &b * &u;
    let pp = &a * &s.p0 * a.transpose() + &s.process_noise;
    let sm = &c * &pp * c.transpose() + &s.measurement_noise;
    let nu = &y - &c * &xp;
    let z: Vec<f64> = (0..2).map(|i| nu[i].abs() / sm[(i, i)].sqrt()).collect();
    let want = if z[0] > z[1] { 0 } else { 1 };
    let mut kf = KalmanFilter::new(s.clone()).unwrap();
    let e = kf.step(&model, &u, &y).unwrap_err();
    let EstimatorError::Outlier { worst: Some(w), .. } = e else { panic!("{e}") };
    assert_eq!(w.index, want);
    assert!((w.residual - nu[want]).abs() < 1e-12 * nu[want].abs());
    assert!((w.sigmas - z[want]).abs() < 1e-9 * z[want], "{} vs {}", w.sigmas, z[want]);
    assert!(e.to_string().contains(&format!("the largest innovation is y[{want}]")), "{e}");
    // The same from the EKF, the UKF (statistically linearised: the same here), and a partial
    // step that measured only that output (its index in the whole measurement).
    let mut ekf = ExtendedKalmanFilter::new(s.clone()).unwrap();
    let Err(EstimatorError::Outlier { worst: Some(w), .. }) = ekf.step(&model, &u, &y) else { panic!() };
    assert_eq!(w.index, want);
    let mut ukf = UnscentedKalmanFilter::new(s.clone(), UkfParams::default()).unwrap();
    let Err(EstimatorError::Outlier { worst: Some(w), .. }) = ukf.step(&model, &u, &y) else { panic!() };
    assert_eq!(w.index, want);
    let mask = [want == 0, want == 1];
    for e in [
        KalmanFilter::new(s.clone()).unwrap().step_partial(&model, &u, &y, &mask).unwrap_err(),
        UnscentedKalmanFilter::new(s, UkfParams::default()).unwrap().step_partial(&model, &u, &y, &mask).unwrap_err(),
    ] {
        let EstimatorError::Outlier { worst: Some(w), .. } = e else { panic!("{e}") };
        assert_eq!(w.index, want);
    }
}
