//! Partial measurements in the set-membership filters (`smf`, `yang-li*`, `smf-nl`): a step with
//! the outputs `S` only is the step of the model with those outputs and the projection `R_SS` of
//! the noise ellipsoid (the same numbers, bit for bit, for the linear filter), the set holds the
//! truth with every noise on the boundary of its ellipsoid whatever is measured, refused steps
//! change nothing, and partial steps do not allocate after the first of their size.

use counting_allocator::{Counting, count};
use estimators::smf::SdpUpdateSolver;
use estimators::{Estimate, Estimator, EstimatorError, NonlinearSetMembershipFilter, SetMembershipFilter, Setup};
use models::{DiscreteModel, Noise, StepModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector, dmatrix, dvector};
use vessel_dynamics::{DiscreteVessel, VesselParams};

#[global_allocator]
static GLOBAL: Counting = Counting;

fn setup(r: DMatrix<f64>) -> Setup {
    Setup {
        x0: dvector![0.2, -0.1, 0.4],
        p0: DMatrix::identity(3, 3),
        process_noise: DMatrix::identity(3, 3) * 1e-3,
        measurement_noise: r,
        inputs: 1,
    }
}

/// A full (not diagonal) measurement ellipsoid, so that `R_SS` is a true sub-block.
fn r_full() -> DMatrix<f64> {
    dmatrix![0.05, 0.01, 0.02; 0.01, 0.04, -0.01; 0.02, -0.01, 0.09]
}

fn distance(est: &dyn Estimate, x: &DVector<f64>) -> f64 {
    let d = x - est.center();
    (d.transpose() * est.shape().clone().try_inverse().unwrap() * d)[(0, 0)]
}

#[test]
fn a_partial_step_is_the_step_of_the_model_with_the_measured_outputs_bit_for_bit() {
    let a = dmatrix![1.0, 0.1, 0.0; 0.0, 1.0, 0.1; 0.0, 0.0, 0.95];
    let b = dmatrix![0.0; 0.05; 0.1];
    let c = dmatrix![1.0, 0.0, 0.0; 0.5, 1.0, 0.0; 0.0, 0.2, 1.0];
    let full = StepModel::new(&a, &b, &c);
    for (mask, rows) in [([true, false, true], [0, 2]), ([false, true, true], [1, 2])] {
        let c_sub = DMatrix::from_fn(2, 3, |i, j| c[(rows[i], j)]);
        let r = r_full();
        let r_sub = DMatrix::from_fn(2, 2, |i, j| r[(rows[i], rows[j])]);
        let sub = StepModel::new(&a, &b, &c_sub);
        let mut ours = SetMembershipFilter::new(setup(r)).unwrap();
        let mut reference = SetMembershipFilter::new(setup(r_sub.clone())).unwrap();
        let mut rng = Xoshiro256StarStar::seed_from_u64(3);
        let w = Noise::ellipsoid_boundary(DMatrix::identity(3, 3) * 1e-3).unwrap();
        let v = Noise::ellipsoid_boundary(r_full()).unwrap();
        let mut x = dvector![0.5, 0.3, -0.2];
        for k in 0..40 {
            let u = dvector![(0.3 * k as f64).sin()];
            x = &a * &x + &b * &u + w.sample(&mut rng);
            let mut y = &c * &x + v.sample(&mut rng);
            let y_sub = DVector::from_fn(2, |i, _| y[rows[i]]);
            // The unmeasured entry is never read.
            y[(0..3).find(|i| !rows.contains(i)).unwrap()] = f64::NAN;
            let e = ours.step_partial(&full, &u, &y, &mask).unwrap().clone();
            let want = reference.step(&sub, &u, &y_sub).unwrap();
            assert_eq!(e.center, want.center, "{mask:?} step {k}");
            assert_eq!(e.shape, want.shape, "{mask:?} step {k}");
            assert_eq!(e.report.tau, want.report.tau);
            assert!(distance(&e, &x) <= 1.0, "{mask:?} step {k}");
        }
        assert_eq!(ours.steps(), 40);
    }
}

#[test]
fn the_set_holds_the_truth_whatever_is_measured_and_refused_steps_change_nothing() {
    let a = dmatrix![1.0, 0.1, 0.0; 0.0, 1.0, 0.1; 0.0, 0.0, 0.95];
    let b = dmatrix![0.0; 0.05; 0.1];
    let c = dmatrix![1.0, 0.0, 0.0; 0.5, 1.0, 0.0; 0.0, 0.2, 1.0];
    let model = StepModel::new(&a, &b, &c);
    let masks = [[true; 3], [true, false, false], [false; 3], [false, true, true], [true, false, true]];
    let mut smf = SetMembershipFilter::new(setup(r_full())).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(4);
    let w = Noise::ellipsoid_boundary(DMatrix::identity(3, 3) * 1e-3).unwrap();
    let v = Noise::ellipsoid_boundary(r_full()).unwrap();
    let mut x = dvector![0.5, 0.3, -0.2];
    for k in 0..300 {
        let u = dvector![(0.1 * k as f64).cos()];
        x = &a * &x + &b * &u + w.sample(&mut rng);
        let y = &c * &x + v.sample(&mut rng);
        let mask = masks[k % masks.len()];
        let e = Estimator::step_partial(&mut smf, &model, &u, &y, &mask).unwrap();
        assert!(distance(e, &x) <= 1.0, "step {k}, {mask:?}");
    }
    // A measurement that contradicts the set: refused, nothing changes, the next step goes on.
    let before = smf.estimate().clone();
    let far = dvector![1e3, f64::NAN, 1e3];
    let e = smf.step_partial(&model, &dvector![0.0], &far, &[true, false, true]).unwrap_err();
    assert!(matches!(e, EstimatorError::InconsistentData { step: 301, .. }), "{e}");
    assert_eq!(smf.estimate().center, before.center);
    assert_eq!(smf.estimate().shape, before.shape);
    assert_eq!(smf.steps(), 300);
    // A mask of the wrong length, a NaN where measured: refused by name.
    assert!(matches!(
        smf.step_partial(&model, &dvector![0.0], &far, &[true, false]),
        Err(EstimatorError::DimensionMismatch { what: "measured", .. })
    ));
    assert!(matches!(
        smf.step_partial(&model, &dvector![0.0], &far, &[true, true, false]),
        Err(EstimatorError::NonFinite { what: "y", index: 1 })
    ));
    assert_eq!(smf.estimate().shape, before.shape);
}

#[test]
fn nothing_measured_is_the_prediction_and_everything_measured_is_the_step() {
    let a = dmatrix![1.0, 0.1, 0.0; 0.0, 1.0, 0.1; 0.0, 0.0, 0.95];
    let b = dmatrix![0.0; 0.05; 0.1];
    let c = dmatrix![1.0, 0.0, 0.0; 0.5, 1.0, 0.0; 0.0, 0.2, 1.0];
    let model = StepModel::new(&a, &b, &c);
    let (u, y) = (dvector![0.3], dvector![0.1, 0.2, 0.3]);
    let mut ours = SetMembershipFilter::new(setup(r_full())).unwrap();
    let mut reference = ours.clone();
    assert_eq!(
        ours.step_partial(&model, &u, &DVector::from_element(3, f64::NAN), &[false; 3]).unwrap().shape,
        reference.predict(&model, &u).unwrap().shape
    );
    let mut ours = SetMembershipFilter::new(setup(r_full())).unwrap();
    let mut reference = ours.clone();
    let (e, want) = (ours.step_partial(&model, &u, &y, &[true; 3]).unwrap(), reference.step(&model, &u, &y).unwrap());
    assert_eq!((&e.center, &e.shape, e.report.tau), (&want.center, &want.shape, want.report.tau));
}

#[test]
fn partial_steps_do_not_allocate_after_the_first_of_their_size() {
    let a = dmatrix![1.0, 0.1, 0.0; 0.0, 1.0, 0.1; 0.0, 0.0, 0.95];
    let b = dmatrix![0.0; 0.05; 0.1];
    let c = dmatrix![1.0, 0.0, 0.0; 0.5, 1.0, 0.0; 0.0, 0.2, 1.0];
    let model = StepModel::new(&a, &b, &c);
    let mut smf = SetMembershipFilter::new(setup(r_full())).unwrap();
    let (u, y) = (dvector![0.0], dvector![0.1, 0.1, 0.1]);
    let masks = [[true, false, true], [true, false, false], [true; 3], [false; 3], [false, true, true]];
    for mask in masks {
        smf.step_partial(&model, &u, &y, &mask).unwrap();
    }
    let (_, allocations) = count(|| {
        for k in 0..50 {
            smf.step_partial(&model, &u, &y, &masks[k % masks.len()]).unwrap();
        }
    });
    assert_eq!(allocations, 0);
}

#[test]
fn an_sdp_solver_refuses_partial_steps_by_name() {
    let a = dmatrix![1.0, 0.1, 0.0; 0.0, 1.0, 0.1; 0.0, 0.0, 0.95];
    let b = dmatrix![0.0; 0.05; 0.1];
    let c = dmatrix![1.0, 0.0, 0.0; 0.5, 1.0, 0.0; 0.0, 0.2, 1.0];
    let model = StepModel::new(&a, &b, &c);
    let solver = SdpUpdateSolver::by_name("faer-ipm", lmi::SolverSettings::default()).unwrap();
    let mut smf = SetMembershipFilter::with_solver(setup(r_full()), solver).unwrap();
    let e = smf.step_partial(&model, &dvector![0.0], &dvector![0.1, 0.1, 0.1], &[true, false, true]).unwrap_err();
    assert!(matches!(e, EstimatorError::Unsupported { operation: "a partial measurement", .. }), "{e}");
    assert_eq!(smf.steps(), 0);
}

#[test]
fn the_nonlinear_filter_holds_the_vessel_with_its_heading_and_position_measured_apart() {
    // The supply vessel: position at one rate, heading at another, noise on the boundary of
    // the ellipsoid (its projections are what a partial step uses).
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let q = DMatrix::from_diagonal(&dvector![1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6]);
    let r = dmatrix![1.0, 0.2, 0.0; 0.2, 1.0, 0.0; 0.0, 0.0, 1e-2];
    let s = Setup {
        x0: DVector::zeros(6),
        p0: DMatrix::from_diagonal(&dvector![4.0, 4.0, 0.01, 0.01, 0.01, 1e-4]),
        process_noise: q.clone(),
        measurement_noise: r.clone(),
        inputs: 3,
    };
    let mut smf = NonlinearSetMembershipFilter::new(s.clone()).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(12);
    let w = Noise::ellipsoid_boundary(q).unwrap();
    let v = Noise::ellipsoid_boundary(r).unwrap();
    let mut x = Noise::ellipsoid_boundary(s.p0.clone()).unwrap().sample(&mut rng);
    // (100 steps: this single ellipsoid's velocities grow even with every output measured, and
    // with fewer measurements it outgrows its linearisation sooner — GuaranteeLost after about
    // 120 steps here, as it should; the constrained-zonotope filter is the tight one.)
    let masks = [[true, true, true], [false, false, true], [true, true, false], [false; 3], [true, true, false]];
    for k in 0..100 {
        let t = k as f64 * 0.1;
        let u = DVector::from_fn(3, |i, _| [2e5, 5e4, 1e6][i] * (t / (5.0 + i as f64)).sin());
        let mut next = DVector::zeros(6);
        vessel.f(&x, &u, &mut next).unwrap();
        x = next + w.sample(&mut rng);
        let mut y = DVector::zeros(3);
        vessel.h(&x, &u, &mut y).unwrap();
        y += v.sample(&mut rng);
        let mask = masks[k % masks.len()];
        for (i, &m) in mask.iter().enumerate() {
            if !m {
                y[i] = f64::NAN;
            }
        }
        let e = smf.step_partial(&vessel, &u, &y, &mask).unwrap_or_else(|e| panic!("step {k}, {mask:?}: {e}"));
        assert!(distance(e, &x) <= 1.0, "step {k}, {mask:?}");
        for i in 0..6 {
            let (lo, hi) = e.bounds(i).unwrap();
            assert!(lo <= x[i] && x[i] <= hi, "step {k}, state {i}");
        }
    }
}
