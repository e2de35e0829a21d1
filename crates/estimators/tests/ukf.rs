//! The unscented Kalman filter: equal to the Kalman filter on linear models (sigma points are
//! exact for first and second moments), close to the EKF on a mildly nonlinear model and on the
//! supply vessel, the positive-definiteness guard against an independent formula, bad input
//! refused with the state unchanged, and no allocation per step.

mod common;

use common::uniform as random;
use counting_allocator::{Counting, count};
use estimators::Setup;
use estimators::{EstimatorError, ExtendedKalmanFilter, KalmanFilter, UkfParams, UnscentedKalmanFilter, registry};
use models::{DifferentiableModel, Dims, DiscreteModel, ModelError, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};
use vessel_dynamics::{DiscreteVessel, VesselParams};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn equals_the_kalman_filter_on_linear_models() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(3);
    let mut worst = 0.0f64;
    for trial in 0..16 {
        let (n, m, p) = (3 + trial % 4, 1 + trial % 3, 1 + trial % 2);
        // The paper's parameters (negative weights) and the default ones.
        let params = if trial % 2 == 0 { UkfParams::paper() } else { UkfParams::default() };
        let sys = common::random_linear_system(&mut rng, n, m, p);
        let mut kf = KalmanFilter::new(sys.setup()).unwrap();
        let mut ukf = UnscentedKalmanFilter::new(sys.setup(), params).unwrap();
        let model = sys.model();
        for k in 0..30 {
            let u = random(&mut rng, p, 1).column(0).into_owned();
            let y = random(&mut rng, m, 1).column(0).into_owned();
            let (km, kp) = if k % 5 == 4 {
                let e = kf.predict(&model, &u).unwrap();
                (e.center.clone(), e.covariance.clone())
            } else {
                let e = kf.step(&model, &u, &y).unwrap();
                (e.center.clone(), e.covariance.clone())
            };
            let e = if k % 5 == 4 { ukf.predict(&model, &u).unwrap() } else { ukf.step(&model, &u, &y).unwrap() };
            let scale = kp.amax().max(1.0);
            worst = worst.max((&e.center - &km).amax() / scale).max((&e.covariance - &kp).amax() / scale);
        }
        assert_eq!(ukf.report().guard_total, 0);
    }
    assert!(worst <= 1e-9, "largest relative difference {worst:e}");
}

/// A mildly nonlinear oscillator with a range-like sensor.
struct Mild;
impl DiscreteModel for Mild {
    fn dims(&self) -> Dims {
        Dims::new(3, 1, 2)
    }
    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = x[0] + 0.1 * x[1];
        out[1] = x[1] - 0.1 * x[0].sin() + 0.1 * u[0];
        out[2] = 0.95 * x[2] + 0.02 * x[0] * x[1];
        Ok(())
    }
    fn h(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = x[0] + 0.05 * x[2] * x[2];
        out[1] = (1.0 + x[1] * x[1]).sqrt();
        Ok(())
    }
}
impl DifferentiableModel for Mild {
    fn f_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        out.fill(0.0);
        out[(0, 0)] = 1.0;
        out[(0, 1)] = 0.1;
        out[(1, 0)] = -0.1 * x[0].cos();
        out[(1, 1)] = 1.0;
        out[(2, 0)] = 0.02 * x[1];
        out[(2, 1)] = 0.02 * x[0];
        out[(2, 2)] = 0.95;
        Ok(())
    }
    fn h_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        out.fill(0.0);
        out[(0, 0)] = 1.0;
        out[(0, 2)] = 0.1 * x[2];
        out[(1, 1)] = x[1] / (1.0 + x[1] * x[1]).sqrt();
        Ok(())
    }
}

#[test]
fn close_to_the_ekf_on_a_mildly_nonlinear_model() {
    let check = models::check_jacobians(&Mild, &DVector::from_vec(vec![0.3, 0.8, -0.2]), &DVector::from_vec(vec![0.1]))
        .unwrap();
    assert!(check.f_error < 1e-8 && check.h_error < 1e-8, "{check:?}");
    let x0 = DVector::from_vec(vec![0.5, 1.0, 0.2]);
    let p0 = DMatrix::identity(3, 3) * 1e-3;
    let q = DMatrix::identity(3, 3) * 1e-5;
    let r = DMatrix::identity(2, 2) * 1e-3;
    let mut ekf = ExtendedKalmanFilter::new(common::setup(&x0, &p0, &q, &r, 1)).unwrap();
    let mut ukf = UnscentedKalmanFilter::new(common::setup(&x0, &p0, &q, &r, 1), UkfParams::paper()).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(8);
    let mut x = x0;
    let (mut xn, mut y) = (DVector::zeros(3), DVector::zeros(2));
    let mut worst = 0.0f64;
    for k in 0..200 {
        let u = DVector::from_vec(vec![(k as f64 * 0.05).sin()]);
        Mild.f(&x, &u, &mut xn).unwrap();
        x.copy_from(&xn);
        x.iter_mut().for_each(|v| *v += 3e-3 * rng.standard_normal());
        Mild.h(&x, &u, &mut y).unwrap();
        y.iter_mut().for_each(|v| *v += 3e-2 * rng.standard_normal());
        let e = ekf.step(&Mild, &u, &y).unwrap().clone();
        let s = ukf.step(&Mild, &u, &y).unwrap();
        // Differences in units of the EKF's own standard deviation.
        for i in 0..3 {
            worst = worst.max((s.center[i] - e.center[i]).abs() / e.std_dev[i]);
            worst = worst.max((s.std_dev[i] / e.std_dev[i] - 1.0).abs());
        }
    }
    // Not equal (the UKF sees the curvature), but within a small fraction of a standard deviation.
    assert!(worst < 0.1, "largest difference {worst} (in EKF standard deviations)");
    assert!(worst > 1e-6, "suspiciously equal: {worst}");
}

/// The digest's vessel settings: `Q = 1e-2 I`, `R = diag(1, 1, 0.1)`, `P₀ = diag(1, 1, 0.1, 0.1, 0.1, 0.01)`.
fn vessel_setup() -> (DVector<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    (
        DVector::zeros(6),
        DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.1, 0.1, 0.1, 0.01])),
        DMatrix::identity(6, 6) * 1e-2,
        DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.1])),
    )
}

#[test]
fn tracks_the_vessel_like_the_ekf_without_the_guard() {
    let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let (x0, p0, q, r) = vessel_setup();
    let mut ekf = ExtendedKalmanFilter::new(common::setup(&x0, &p0, &q, &r, 3)).unwrap();
    let mut ukf = UnscentedKalmanFilter::new(common::setup(&x0, &p0, &q, &r, 3), UkfParams::paper()).unwrap();
    assert_eq!(ukf.weights(), (-5.0, -2.25, 0.5));
    let mut rng = Xoshiro256StarStar::seed_from_u64(21);
    let mut x = x0;
    let (mut xn, mut y) = (DVector::zeros(6), DVector::zeros(3));
    let (mut se, mut su) = (0.0, 0.0);
    let steps = 600;
    for k in 0..steps {
        // A turning manoeuvre: the heading sweeps through ±1 rad.
        let u = DVector::from_vec(vec![2e5, 5e4 * (k as f64 * 0.02).sin(), 3e6 * (k as f64 * 0.01).cos()]);
        model.f(&x, &u, &mut xn).unwrap();
        x.copy_from(&xn);
        model.h(&x, &u, &mut y).unwrap();
        for (i, s) in [1.0, 1.0, 0.1f64.sqrt()].into_iter().enumerate() {
            y[i] += s * rng.standard_normal();
        }
        let e = ekf.step(&model, &u, &y).unwrap();
        se += (&e.center - &x).rows(0, 3).norm_squared();
        let s = ukf.step(&model, &u, &y).unwrap();
        su += (&s.center - &x).rows(0, 3).norm_squared();
    }
    let (re, ru) = ((se / steps as f64).sqrt(), (su / steps as f64).sqrt());
    assert!((ru / re - 1.0).abs() < 0.05, "RMSE of position/heading: EKF {re}, UKF {ru}");
    // β ≥ −α²κ/n: the sample covariances are positive semidefinite without the guard.
    assert_eq!(ukf.report().guard_total, 0);
}

#[test]
fn the_factor_kept_from_an_update_is_the_one_a_fresh_factorisation_gives() {
    // A step keeps the Cholesky factor of the covariance it publishes for the next prediction.
    // A second filter reset to its own estimate after every step (which drops that factor, so
    // its next prediction factorises afresh) must stay equal bit for bit, through the paths that
    // publish without an update (a prediction alone, an update alone after it) too.
    let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let (x0, p0, q, r) = vessel_setup();
    let setup = Setup { x0, p0, process_noise: q, measurement_noise: r, inputs: 3 };
    let mut kept = UnscentedKalmanFilter::new(setup.clone(), UkfParams::paper()).unwrap();
    let mut fresh = UnscentedKalmanFilter::new(setup, UkfParams::paper()).unwrap();
    for k in 0..60 {
        let u = DVector::from_vec(vec![2e5, 5e4 * (k as f64 * 0.1).sin(), 3e6 * (k as f64 * 0.05).cos()]);
        let y = DVector::from_vec(vec![0.01 * k as f64, -0.02 * k as f64, 0.005 * k as f64]);
        for f in [&mut kept, &mut fresh] {
            if k % 7 == 3 {
                f.predict(&model, &u).unwrap();
                f.update(&model, &y).unwrap();
            } else if k % 11 == 5 {
                f.predict(&model, &u).unwrap();
            } else {
                f.step(&model, &u, &y).unwrap();
            }
        }
        let (c, p) = (fresh.estimate().center.clone(), fresh.estimate().covariance.clone());
        fresh.reset(&c, &p).unwrap();
        assert_eq!(kept.estimate().center, fresh.estimate().center, "step {k}");
        assert_eq!(kept.estimate().covariance, fresh.estimate().covariance, "step {k}");
    }
}

/// `f(x) = [x₀, x₁ + x₀², x₂]` with `β = −10 < −α²κ/n`: the unguarded `P⁻` is indefinite.
struct Bend;
impl DiscreteModel for Bend {
    fn dims(&self) -> Dims {
        Dims::new(3, 1, 1)
    }
    fn f(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = x[0];
        out[1] = x[1] + x[0] * x[0];
        out[2] = x[2];
        Ok(())
    }
    fn h(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = x[0];
        Ok(())
    }
}

#[test]
fn guard_keeps_the_prediction_positive_definite() {
    let params = UkfParams { alpha: 1.0, beta: -10.0, kappa: 0.0 };
    let q = DMatrix::identity(3, 3) * 1e-6;
    let mut ukf = UnscentedKalmanFilter::new(
        Setup {
            x0: DVector::zeros(3),
            p0: DMatrix::identity(3, 3),
            process_noise: q.clone(),
            measurement_noise: DMatrix::identity(1, 1),
            inputs: 1,
        },
        params,
    )
    .unwrap();
    let u = DVector::zeros(1);
    let e = ukf.predict(&Bend, &u).unwrap().clone();
    assert!(ukf.report().guarded_prediction);
    assert_eq!(ukf.report().guard_total, 1);
    // Independent formula: γ = √3, points ±√3 e_j; about the central point Y₀ = 0 with weights 1/6:
    // the (1, 1) entry gets 2 · (1/6) · (3)² from x₀ = ±√3, plus 2 · (1/6) · 3 from x₁ = ±√3.
    let mut want = q.clone();
    want[(0, 0)] += 2.0 / 6.0 * 3.0;
    want[(1, 1)] += 2.0 / 6.0 * 9.0 + 2.0 / 6.0 * 3.0;
    want[(2, 2)] += 2.0 / 6.0 * 3.0;
    assert!((&e.covariance - &want).amax() < 1e-12, "{}", e.covariance);
    // The mean is Y₀ + S with S = Σ W_i d_i = [0, 1, 0], and the unguarded (1, 1) entry would be
    // Σ W_i d_i,1² + (β − α²) S₁² = 4 − 11 = −7 < 0.
    assert!((e.center[1] - 1.0).abs() < 1e-12);
    assert!(e.covariance.clone().cholesky().is_some());
}

#[test]
fn bad_input_is_refused_and_leaves_the_filter_unchanged() {
    let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let (x0, p0, q, r) = vessel_setup();
    let mut ukf = UnscentedKalmanFilter::new(
        Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q.clone(), measurement_noise: r.clone(), inputs: 3 },
        UkfParams::paper(),
    )
    .unwrap();
    let u = DVector::from_vec(vec![1e5, 0.0, 0.0]);
    let y = DVector::from_vec(vec![0.5, -0.2, 0.01]);
    ukf.step(&model, &u, &y).unwrap();
    let before = ukf.estimate().clone();
    let mut nan_y = y.clone();
    nan_y[1] = f64::NAN;
    let cases: Vec<(DVector<f64>, DVector<f64>)> = vec![
        (DVector::zeros(2), y.clone()),
        (u.clone(), DVector::zeros(4)),
        (u.clone(), nan_y),
        (DVector::from_vec(vec![f64::INFINITY, 0.0, 0.0]), y.clone()),
    ];
    for (uu, yy) in &cases {
        assert!(ukf.step(&model, uu, yy).is_err());
        let bad_u = uu.len() != 3 || uu.iter().any(|v| !v.is_finite());
        if bad_u {
            assert!(ukf.predict(&model, uu).is_err());
        }
        assert_eq!(ukf.estimate(), &before);
    }
    // A model of the wrong size.
    let e = ukf.step(&Bend, &DVector::zeros(1), &DVector::zeros(1)).unwrap_err();
    assert!(matches!(e, EstimatorError::DimensionMismatch { what: "model states", .. }), "{e}");
    assert_eq!(ukf.estimate(), &before);
    // Construction.
    assert!(matches!(
        UnscentedKalmanFilter::new(
            Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q.clone(), measurement_noise: r.clone(), inputs: 3 },
            UkfParams { kappa: -6.0, ..UkfParams::paper() }
        ),
        Err(EstimatorError::InvalidSetting { .. })
    ));
    let mut bad_p0 = p0.clone();
    bad_p0[(0, 0)] = -1.0;
    assert!(matches!(
        UnscentedKalmanFilter::new(
            Setup { x0: x0.clone(), p0: bad_p0, process_noise: q.clone(), measurement_noise: r.clone(), inputs: 3 },
            UkfParams::paper()
        ),
        Err(EstimatorError::NotPositiveDefinite { what: "P0" })
    ));
    // Q is a covariance (singular allowed); an indefinite one is refused and changes nothing.
    let mut indefinite = DMatrix::<f64>::zeros(6, 6);
    indefinite[(0, 0)] = -1e-3;
    assert_eq!(ukf.set_process_noise(&indefinite), Err(EstimatorError::NotPositiveSemidefinite { what: "Q" }));
    assert_eq!(ukf.estimate(), &before);
    // The registry builds it by name.
    let setup = Setup { x0, p0, process_noise: q, measurement_noise: r, inputs: 3 };
    let settings = registry::EstimatorSettings::Unscented(UkfParams::paper());
    let mut boxed = registry::build("ukf", setup.clone(), Some(settings)).unwrap();
    assert!(boxed.step(&model, &u, &y).is_ok());
    assert!(matches!(registry::build("mhe?", setup, None), Err(EstimatorError::UnknownEstimator { .. })));
}

#[test]
fn a_step_does_not_allocate() {
    let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let (x0, p0, q, r) = vessel_setup();
    let mut ukf = UnscentedKalmanFilter::new(
        Setup { x0, p0, process_noise: q, measurement_noise: r, inputs: 3 },
        UkfParams::paper(),
    )
    .unwrap();
    let u = DVector::from_vec(vec![1e5, 2e4, 1e6]);
    let ys: Vec<DVector<f64>> = (0..50).map(|k| DVector::from_fn(3, |i, _| ((k * 3 + i) as f64).sin())).collect();
    ukf.step(&model, &u, &ys[0]).unwrap();
    let (_, n) = count(|| {
        for y in &ys {
            ukf.step(&model, &u, y).unwrap();
        }
        ukf.predict(&model, &u).unwrap();
    });
    assert_eq!(n, 0, "UKF step allocated");
    // Also through the object-safe face.
    let dynamic: &mut dyn estimators::DynEstimator<dyn DiscreteModel> = &mut ukf;
    let (_, n) = count(|| dynamic.step_dyn(&model, &u, &ys[1]).map(|_| ()));
    assert_eq!(n, 0, "UKF step through DynEstimator allocated");
}
