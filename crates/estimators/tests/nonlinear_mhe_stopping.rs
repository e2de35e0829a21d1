//! The nonlinear MHE's early stopping rule (`estimate_tolerance`): on the supply vessel (the
//! paper's model and settings) every estimate stays within 1e-8 (relative) of the one iterated to
//! the 1e-10 step tolerance, with fewer Gauss–Newton iterations. Its real-time iterations
//! (`real_time_iterations`): exact on a linear model after one iteration (the window's problem is
//! quadratic), marked as such, and close to the converged windows on the vessel.

use estimators::mhe::{NonlinearMhe, NonlinearMheSettings, WindowStatus};
use estimators::{Estimate, Estimator, Setup, SolveOutcome};
use models::{DiscreteModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector, dvector};
use vessel_dynamics::{DiscreteVessel, VesselParams};

#[test]
fn stopping_early_keeps_every_estimate_within_1e_8_of_the_converged_one() {
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let setup = vessel_setup();
    let early = NonlinearMheSettings::paper();
    assert_eq!(early.estimate_tolerance, Some(1e-9));
    let full = NonlinearMheSettings { estimate_tolerance: None, ..NonlinearMheSettings::paper() };
    let mut a = NonlinearMhe::new(setup.clone(), early).unwrap();
    let mut b = NonlinearMhe::new(setup, full).unwrap();
    let (mut iterations_a, mut iterations_b, mut worst) = (0, 0, 0.0f64);
    for (u, y) in &vessel_run(&vessel) {
        let ea = a.step(&vessel, u, y).unwrap().clone();
        let eb = b.step(&vessel, u, y).unwrap().clone();
        iterations_a += ea.report.as_ref().unwrap().iterations;
        iterations_b += eb.report.as_ref().unwrap().iterations;
        let scale = eb.center.amax().max(1.0);
        worst = worst.max((&ea.center - &eb.center).amax() / scale);
    }
    assert!(worst <= 1e-8, "largest relative difference {worst:e}");
    assert!(iterations_a < iterations_b, "{iterations_a} against {iterations_b} iterations");
    eprintln!("early stopping: {iterations_a} against {iterations_b} iterations; largest difference {worst:e}");
}

/// 300 steps `(u, y)` of the vessel from rest under slowly varying thrusts, with Gaussian process
/// (σ = 0.1) and measurement (σ = 1, 1, 0.3) noise (seed 21).
fn vessel_run(vessel: &DiscreteVessel) -> Vec<(DVector<f64>, DVector<f64>)> {
    let mut rng = Xoshiro256StarStar::seed_from_u64(21);
    let (mut x, mut next, mut y) = (DVector::zeros(6), DVector::zeros(6), DVector::zeros(3));
    (0..300)
        .map(|k| {
            let t = 0.1 * k as f64;
            let u = dvector![1e5 * (1.0 + (t / 19.0).sin()), 5e4 * (t / 14.0).sin(), 1e6 * (t / 9.5).sin()];
            vessel.f(&x, &u, &mut next).unwrap();
            x = &next + DVector::from_fn(6, |_, _| 0.1 * rng.standard_normal());
            vessel.h(&x, &u, &mut y).unwrap();
            y += dvector![rng.standard_normal(), rng.standard_normal(), 0.3 * rng.standard_normal()];
            (u, y.clone())
        })
        .collect()
}

fn vessel_setup() -> Setup {
    Setup {
        x0: DVector::zeros(6),
        p0: DMatrix::from_diagonal(&dvector![1.0, 1.0, 0.1, 0.1, 0.1, 0.01]),
        process_noise: DMatrix::identity(6, 6) * 1e-2,
        measurement_noise: DMatrix::from_diagonal(&dvector![1.0, 1.0, 0.1]),
        inputs: 3,
    }
}

#[test]
fn one_real_time_iteration_solves_a_linear_window_exactly() {
    let a = DMatrix::from_row_slice(3, 3, &[1.0, 0.1, 0.0, -0.05, 0.95, 0.1, 0.0, 0.0, 0.9]);
    let b = DMatrix::from_column_slice(3, 1, &[0.0, 0.1, 0.05]);
    let c = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    let model = models::ConstantModel::new(a, b, c).unwrap();
    let setup = Setup {
        x0: DVector::zeros(3),
        p0: DMatrix::identity(3, 3) * 0.5,
        process_noise: DMatrix::identity(3, 3) * 0.01,
        measurement_noise: DMatrix::identity(2, 2) * 0.04,
        inputs: 1,
    };
    let full = NonlinearMheSettings { horizon: 6, ..NonlinearMheSettings::paper() };
    let rti = NonlinearMheSettings { real_time_iterations: Some(1), ..full.clone() };
    let (mut a, mut b) = (NonlinearMhe::new(setup.clone(), full).unwrap(), NonlinearMhe::new(setup, rti).unwrap());
    let mut rng = Xoshiro256StarStar::seed_from_u64(5);
    let (mut x, mut next, mut y) = (DVector::from_element(3, 0.2), DVector::zeros(3), DVector::zeros(2));
    for k in 0..60 {
        let u = DVector::from_element(1, (0.2 * k as f64).sin());
        model.f(&x, &u, &mut next).unwrap();
        x = &next + DVector::from_fn(3, |_, _| 0.05 * rng.uniform(-1.0, 1.0));
        model.h(&x, &u, &mut y).unwrap();
        y += DVector::from_fn(2, |_, _| 0.1 * rng.uniform(-1.0, 1.0));
        let ea = a.step(&model, &u, &y).unwrap().clone();
        let eb = b.step(&model, &u, &y).unwrap().clone();
        let report = eb.report.unwrap();
        assert_eq!(report.iterations, 1, "step {k}");
        assert_eq!(report.status, WindowStatus::RealTimeIteration, "step {k}");
        assert_eq!(eb.status().outcome, SolveOutcome::RealTimeIteration);
        assert!(eb.status().is_clean() && eb.status().label() == "real-time");
        assert!((&ea.center - &eb.center).amax() <= 1e-12, "step {k}: {} vs {}", ea.center, eb.center);
        // The Gauss–Newton matrix of a quadratic window does not depend on the point.
        assert!((&ea.covariance - &eb.covariance).amax() <= 1e-12, "step {k}");
    }
}

#[test]
fn real_time_iterations_stay_near_the_converged_windows_on_the_vessel() {
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let full = NonlinearMheSettings { estimate_tolerance: None, ..NonlinearMheSettings::paper() };
    let mut reference = NonlinearMhe::new(vessel_setup(), full.clone()).unwrap();
    let mut rti: Vec<NonlinearMhe> = [1, 2]
        .map(|k| {
            NonlinearMhe::new(vessel_setup(), NonlinearMheSettings { real_time_iterations: Some(k), ..full.clone() })
        })
        .into_iter()
        .collect::<Result<_, _>>()
        .unwrap();
    let mut worst = [0.0f64; 2];
    for (u, y) in &vessel_run(&vessel) {
        let e = reference.step(&vessel, u, y).unwrap().clone();
        for (i, f) in rti.iter_mut().enumerate() {
            let r = f.step(&vessel, u, y).unwrap();
            assert!(r.report.unwrap().iterations <= i + 1);
            // In standard deviations of the converged estimate, the largest over the states.
            let d = (0..6).map(|j| (r.center[j] - e.center[j]).abs() / e.covariance[(j, j)].sqrt()).fold(0.0, f64::max);
            worst[i] = worst[i].max(d);
        }
    }
    eprintln!("real-time iterations: largest distance to the converged estimate, in its standard deviations {worst:?}");
    // Measured: 0.06 σ (one iteration), 0.002 σ (two); the bounds leave a margin.
    assert!(worst[1] < worst[0], "{worst:?}");
    assert!(worst[0] < 0.2 && worst[1] < 0.01, "{worst:?}");
}
