//! The Kalman filter against independent references: the textbook covariance form
//! `P = (I − K C) P⁻` with `K = P⁻Cᵀ (C P⁻ Cᵀ + R)⁻¹` computed by nalgebra's inverse on random
//! systems, and the closed-form scalar random walk (whose steady-state variance solves
//! `p² + q p − q r = 0`).

mod common;

use common::uniform as random;
use estimators::{Estimate, EstimateKind, Estimator, KalmanFilter, StepModel};
use models::Xoshiro256StarStar;
use nalgebra::{DMatrix, DVector};

fn spd(rng: &mut Xoshiro256StarStar, n: usize, floor: f64) -> DMatrix<f64> {
    let g = random(rng, n, n);
    &g * g.transpose() + DMatrix::identity(n, n) * floor
}

#[test]
fn matches_the_textbook_covariance_form_on_random_systems() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(31);
    let mut worst = 0.0f64;
    for trial in 0..40 {
        let n = 1 + trial % 6;
        let m = 1 + trial % 3;
        let p = 1 + trial % 2;
        let a = random(&mut rng, n, n) * 0.6;
        let b = random(&mut rng, n, p);
        let c = random(&mut rng, m, n);
        let q = spd(&mut rng, n, 0.05);
        let r = spd(&mut rng, m, 0.1);
        let p0 = spd(&mut rng, n, 0.5);
        let x0 = random(&mut rng, n, 1).column(0).into_owned();
        let mut kf = KalmanFilter::new(common::setup(&x0, &p0, &q, &r, p)).unwrap();
        let (mut x, mut pp) = (x0, p0);
        for _ in 0..15 {
            let u = random(&mut rng, p, 1).column(0).into_owned();
            let y = random(&mut rng, m, 1).column(0).into_owned();
            // Reference: predict, gain by explicit inverse, covariance form.
            let xp = &a * &x + &b * &u;
            let pm = &a * &pp * a.transpose() + &q;
            let s = &c * &pm * c.transpose() + &r;
            let k = &pm * c.transpose() * s.try_inverse().unwrap();
            x = &xp + &k * (&y - &c * &xp);
            pp = (DMatrix::identity(n, n) - &k * &c) * &pm;
            pp = (&pp + pp.transpose()) * 0.5;
            let e = Estimator::step(&mut kf, &StepModel::new(&a, &b, &c), &u, &y).unwrap();
            assert_eq!(e.kind(), EstimateKind::Gaussian);
            let scale = pp.amax().max(1.0);
            worst = worst.max((e.center() - &x).amax() / x.amax().max(1.0)).max((e.shape() - &pp).amax() / scale);
        }
    }
    // Joseph form and covariance form agree to rounding for the optimal gain.
    assert!(worst < 1e-9, "largest relative difference {worst:e}");
}

#[test]
fn scalar_random_walk_converges_to_the_closed_form_steady_state() {
    // x⁺ = x + w, y = x + v: steady prior variance p⁻ solves p² − q p − q r = 0 (Riccati), the
    // posterior is p = p⁻ r / (p⁻ + r).
    let (q, r) = (0.3_f64, 2.0_f64);
    let prior = (q + (q * q + 4.0 * q * r).sqrt()) / 2.0;
    let post = prior * r / (prior + r);
    let one = DMatrix::identity(1, 1);
    let zero_b = DMatrix::zeros(1, 1);
    let mut kf =
        KalmanFilter::new(common::setup(&DVector::zeros(1), &(&one * 10.0), &(&one * q), &(&one * r), 1)).unwrap();
    let model = StepModel::new(&one, &zero_b, &one);
    for k in 0..200 {
        let y = DVector::from_element(1, (k as f64 * 0.37).sin());
        kf.step(&model, &DVector::zeros(1), &y).unwrap();
    }
    let p = kf.estimate().covariance[(0, 0)];
    assert!((p - post).abs() < 1e-12 * post, "{p} vs {post}");
    // One step from a known state: x̂ = x̂⁻ + p⁻/(p⁻ + r) (y − x̂⁻).
    let x_before = kf.estimate().center[0];
    let e = kf.step(&model, &DVector::zeros(1), &DVector::from_element(1, 5.0)).unwrap();
    let want = x_before + prior / (prior + r) * (5.0 - x_before);
    assert!((e.center[0] - want).abs() < 1e-12, "{} vs {want}", e.center[0]);
}
