//! The nonlinear MHE's early stopping rule (`estimate_tolerance`): on the supply vessel (the
//! paper's model and settings) every estimate stays within 1e-8 (relative) of the one iterated to
//! the 1e-10 step tolerance, with fewer Gauss–Newton iterations.

use estimators::mhe::{NonlinearMhe, NonlinearMheSettings};
use estimators::{Estimator, Setup};
use models::{DiscreteModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector, dvector};
use vessel_dynamics::{DiscreteVessel, VesselParams};

#[test]
fn stopping_early_keeps_every_estimate_within_1e_8_of_the_converged_one() {
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let setup = Setup {
        x0: DVector::zeros(6),
        p0: DMatrix::from_diagonal(&dvector![1.0, 1.0, 0.1, 0.1, 0.1, 0.01]),
        process_noise: DMatrix::identity(6, 6) * 1e-2,
        measurement_noise: DMatrix::from_diagonal(&dvector![1.0, 1.0, 0.1]),
        inputs: 3,
    };
    let early = NonlinearMheSettings::paper();
    assert_eq!(early.estimate_tolerance, Some(1e-9));
    let full = NonlinearMheSettings { estimate_tolerance: None, ..NonlinearMheSettings::paper() };
    let mut a = NonlinearMhe::new(setup.clone(), early).unwrap();
    let mut b = NonlinearMhe::new(setup, full).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(21);
    let (mut x, mut next, mut y) = (DVector::zeros(6), DVector::zeros(6), DVector::zeros(3));
    let (mut iterations_a, mut iterations_b, mut worst) = (0, 0, 0.0f64);
    for k in 0..300 {
        let t = 0.1 * k as f64;
        let u = dvector![1e5 * (1.0 + (t / 19.0).sin()), 5e4 * (t / 14.0).sin(), 1e6 * (t / 9.5).sin()];
        vessel.f(&x, &u, &mut next).unwrap();
        x = &next + DVector::from_fn(6, |_, _| 0.1 * rng.standard_normal());
        vessel.h(&x, &u, &mut y).unwrap();
        y += dvector![rng.standard_normal(), rng.standard_normal(), 0.3 * rng.standard_normal()];
        let ea = a.step(&vessel, &u, &y).unwrap().clone();
        let eb = b.step(&vessel, &u, &y).unwrap().clone();
        iterations_a += ea.report.as_ref().unwrap().iterations;
        iterations_b += eb.report.as_ref().unwrap().iterations;
        let scale = eb.center.amax().max(1.0);
        worst = worst.max((&ea.center - &eb.center).amax() / scale);
    }
    assert!(worst <= 1e-8, "largest relative difference {worst:e}");
    assert!(iterations_a < iterations_b, "{iterations_a} against {iterations_b} iterations");
    eprintln!("early stopping: {iterations_a} against {iterations_b} iterations; largest difference {worst:e}");
}
