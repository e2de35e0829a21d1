//! The extended Kalman filter: equal to the Kalman filter on linear models (an independent
//! implementation), tracking the truck paper's slalom within the digest's sanity bound
//! (`docs/truck-ekf.md`: a nominal β RMSE above about 0.1° signals a bug), recovering a wrong
//! initial lateral speed, and refusing bad input with its state unchanged.

mod common;

use common::uniform as random;
use estimators::Setup;
use estimators::{EstimatorError, ExtendedKalmanFilter, KalmanFilter, StepModel};
use models::{DiscreteModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};
use truck_dynamics::{Slalom, TruckEkfModel, TruckParams, TruthConfig, simulate_truth};

#[test]
fn equals_the_kalman_filter_on_linear_models() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(5);
    let mut worst = 0.0f64;
    for trial in 0..20 {
        let (n, m, p) = (1 + trial % 5, 1 + trial % 3, 1 + trial % 2);
        let sys = common::random_linear_system(&mut rng, n, m, p);
        let mut kf = KalmanFilter::new(sys.setup()).unwrap();
        let mut ekf = ExtendedKalmanFilter::new(sys.setup()).unwrap();
        let model = sys.model();
        for _ in 0..30 {
            let u = random(&mut rng, p, 1).column(0).into_owned();
            let y = random(&mut rng, m, 1).column(0).into_owned();
            let k = kf.step(&model, &u, &y).unwrap().clone();
            let e = ekf.step(&model, &u, &y).unwrap();
            worst = worst.max((&e.center - &k.center).amax()).max((&e.covariance - &k.covariance).amax());
        }
    }
    assert!(worst <= 1e-12, "largest difference {worst:e}");
}

/// The digest's EKF settings (§4, assumed): `Q = T diag(qc)`, `R = diag(σ²)`, `P₀`.
fn truck_filter(model: &TruckEkfModel, x0: DVector<f64>) -> ExtendedKalmanFilter {
    let t = model.ts();
    let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1e-4 * t, 1e-4 * t, 1e-6 * t]));
    let r = DMatrix::from_diagonal(&DVector::from_vec(vec![0.05f64.powi(2), 0.05f64.powi(2), 0.002f64.powi(2)]));
    let p0 = DMatrix::from_diagonal(&DVector::from_vec(vec![0.01, 0.01, 1e-4]));
    ExtendedKalmanFilter::new(Setup { x0, p0, process_noise: q, measurement_noise: r, inputs: model.dims().inputs })
        .unwrap()
}

/// Runs the EKF over a 6 s slalom; returns the RMSE of β [deg] over 1–6 s and the lateral-speed
/// error after 0.1 s [m/s].
fn run_slalom(vy0_error: f64) -> (f64, f64) {
    let params = TruckParams::digest_preset();
    let config = TruthConfig { duration: 6.0, ..TruthConfig::digest() };
    let slalom = Slalom::digest();
    let truth = simulate_truth(&params, &config, |t| slalom.angle(t)).unwrap();
    let model = TruckEkfModel::paper(params).unwrap();
    let x0 = truth.body_state(0).unwrap();
    let mut ekf = truck_filter(&model, DVector::from_vec(vec![x0[0], x0[1] + vy0_error, x0[2]]));
    let mut rng = Xoshiro256StarStar::seed_from_u64(11);
    let sigma = [0.05, 0.05, 0.002];
    let (mut sq, mut count, mut vy_err_early) = (0.0, 0usize, f64::NAN);
    for k in 0..truth.len() - 1 {
        let u = truth.estimator_input(k).unwrap().to_dvector();
        let z = truth.measurement(k + 1).unwrap();
        let y = DVector::from_fn(3, |i, _| z[i] + sigma[i] * rng.standard_normal());
        let e = ekf.step(&model, &u, &y).unwrap();
        let x = truth.body_state(k + 1).unwrap();
        let t = (k + 1) as f64 * model.ts();
        if (t - 0.1).abs() < 0.5 * model.ts() {
            vy_err_early = (e.center[1] - x[1]).abs();
        }
        if t >= 1.0 {
            let beta = (x[1] / x[0]).atan().to_degrees();
            let beta_hat = (e.center[1] / e.center[0]).atan().to_degrees();
            sq += (beta - beta_hat).powi(2);
            count += 1;
        }
    }
    ((sq / count as f64).sqrt(), vy_err_early)
}

#[test]
fn tracks_the_slalom_within_the_sanity_bound() {
    let (rmse, _) = run_slalom(0.0);
    eprintln!("nominal: β RMSE over 1–6 s = {rmse:.4}°");
    assert!(rmse < 0.1, "β RMSE {rmse:.4}° ≥ 0.1°");
    // A 0.3 m/s error in the initial lateral speed is corrected within a fraction of a second
    // (a_y carries V_y with ∂a_y/∂V_y ≈ −3 s⁻¹).
    let (rmse, vy_err) = run_slalom(0.3);
    eprintln!("V_y0 error 0.3 m/s: β RMSE = {rmse:.4}°, |e_Vy| after 0.1 s = {vy_err:.4} m/s");
    assert!(rmse < 0.1, "β RMSE {rmse:.4}° with V_y0 error");
    assert!(vy_err < 0.1, "lateral-speed error after 0.1 s: {vy_err}");
}

#[test]
fn bad_input_is_refused_and_leaves_the_filter_unchanged() {
    let params = TruckParams::digest_preset();
    let model = TruckEkfModel::paper(params).unwrap();
    let v = 70.0 / 3.6;
    let mut ekf = truck_filter(&model, DVector::from_vec(vec![v, 0.0, 0.0]));
    let u = truck_dynamics::TruckInput::free_rolling(0.0, v, params.rolling_radius).to_dvector();
    let y = DVector::from_vec(vec![v, 0.0, 0.0]);
    ekf.step(&model, &u, &y).unwrap();
    let before = ekf.clone();
    let same = |f: &ExtendedKalmanFilter| f.estimate() == before.estimate();
    let mut nan_u = u.clone();
    nan_u[0] = f64::NAN;
    assert!(matches!(ekf.step(&model, &nan_u, &y), Err(EstimatorError::NonFinite { what: "u", index: 0 })));
    assert!(same(&ekf));
    let mut nan_y = y.clone();
    nan_y[2] = f64::INFINITY;
    assert!(matches!(ekf.step(&model, &u, &nan_y), Err(EstimatorError::NonFinite { what: "y", index: 2 })));
    assert!(same(&ekf));
    assert!(matches!(ekf.step(&model, &DVector::zeros(3), &y), Err(EstimatorError::DimensionMismatch { .. })));
    assert!(same(&ekf));
    // The model refuses a non-positive speed: the error names it, the filter is unchanged.
    let mut stopped = truck_filter(&model, DVector::from_vec(vec![-1.0, 0.0, 0.0]));
    let snapshot = stopped.clone();
    let e = stopped.step(&model, &u, &y).unwrap_err();
    assert!(matches!(e, EstimatorError::Model(_)), "{e}");
    assert!(e.to_string().contains("speed") || e.to_string().contains("V_x") || e.to_string().contains("Vx"), "{e}");
    assert_eq!(stopped.estimate(), snapshot.estimate());
    // A linear model of the wrong size.
    let a = DMatrix::identity(2, 2);
    let b = DMatrix::zeros(2, 7);
    let c = DMatrix::identity(3, 2);
    assert!(matches!(
        ekf.step(&StepModel::new(&a, &b, &c), &u, &y),
        Err(EstimatorError::DimensionMismatch { what: "model states", .. })
    ));
    assert!(same(&ekf));
}
