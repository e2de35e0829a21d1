//! The linear set-membership filter with an angle output (`y = wrap(C x + v)`, docs/angles.md
//! (A5)): across many turns it is the filter fed the unwrapped measurement (to the rounding of
//! the shift, which inflates `R` by ~1e-15), the set holds the truth with the noise on the
//! boundary of its ellipsoid, a set too wide to choose a branch loses the guarantee, a reading on
//! no branch contradicts it; partial steps branch the measured angles only.

use estimators::{Estimate, EstimatorError, SetMembershipFilter, Setup};
use models::{Angles, ConstantModel, Noise, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector, dmatrix, dvector};

/// A heading `θ` turning at the rate `ω`, both states; the compass measures `θ`, a gyro `ω`.
fn turning(angle: bool) -> ConstantModel {
    let model =
        ConstantModel::new(dmatrix![1.0, 0.1; 0.0, 1.0], DMatrix::zeros(2, 0), dmatrix![1.0, 0.0; 0.0, 1.0]).unwrap();
    if angle { model.with_angles(Angles { states: &[0], outputs: &[0] }).unwrap() } else { model }
}

fn setup(p0: f64) -> Setup {
    Setup {
        x0: dvector![3.0, 0.5],
        p0: DMatrix::identity(2, 2) * p0,
        process_noise: DMatrix::identity(2, 2) * 1e-4,
        measurement_noise: dmatrix![0.01, 0.0; 0.0, 1e-4],
        inputs: 0,
    }
}

fn wrap(a: f64) -> f64 {
    models::wrap_angle(a)
}

#[test]
fn across_many_turns_it_is_the_filter_of_the_unwrapped_measurement_and_holds_the_truth() {
    let (angled, plain) = (turning(true), turning(false));
    let mut ours = SetMembershipFilter::new(setup(0.1)).unwrap();
    let mut reference = SetMembershipFilter::new(setup(0.1)).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(21);
    let w = Noise::ellipsoid_boundary(DMatrix::identity(2, 2) * 1e-4).unwrap();
    let v = Noise::ellipsoid_boundary(dmatrix![0.01, 0.0; 0.0, 1e-4]).unwrap();
    let mut x = dvector![3.05, 0.5];
    let u = DVector::zeros(0);
    for k in 0..600 {
        x = dmatrix![1.0, 0.1; 0.0, 1.0] * &x + w.sample(&mut rng);
        let unwrapped = &x + v.sample(&mut rng);
        let y = dvector![wrap(unwrapped[0]), unwrapped[1]];
        let e = ours.step(&angled, &u, &y).unwrap_or_else(|e| panic!("step {k}: {e}"));
        let want = reference.step(&plain, &u, &unwrapped).unwrap();
        let scale = 1.0 + x[0].abs();
        assert!((&e.center - &want.center).amax() < 1e-9 * scale, "step {k}: {} vs {}", e.center, want.center);
        assert!((&e.shape - &want.shape).amax() < 1e-9 * want.shape.amax(), "step {k}");
        let d = &x - e.center();
        let inside = (d.transpose() * e.shape().clone().try_inverse().unwrap() * &d)[(0, 0)];
        assert!(inside <= 1.0, "step {k}: the truth at {inside}");
    }
    assert!(x[0] > 30.0, "{} rad: several turns", x[0]);
}

#[test]
fn a_set_too_wide_for_a_branch_loses_the_guarantee_and_a_reading_off_every_branch_is_refused() {
    let model = turning(true);
    let u = DVector::zeros(0);
    // θ uncertain by ±4 rad: no branch can be chosen.
    let mut wide = SetMembershipFilter::new(setup(16.0)).unwrap();
    let e = wide.step(&model, &u, &dvector![0.0, 0.5]).unwrap_err();
    assert!(matches!(e, EstimatorError::GuaranteeLost { step: 1, .. }), "{e}");
    assert_eq!(wide.steps(), 0);
    // θ near 3.05 ± 0.35: a compass reading of 1.0 (or 1.0 + 2π k) is on no branch.
    let mut narrow = SetMembershipFilter::new(setup(0.1)).unwrap();
    let before = narrow.estimate().clone();
    let e = narrow.step(&model, &u, &dvector![1.0, 0.5]).unwrap_err();
    assert!(matches!(e, EstimatorError::SetMissed { step: 1, .. }), "{e}");
    assert_eq!(narrow.estimate().center, before.center);
    // A reading across the cut (3.1 + 0.3 − 2π) is on the branch near 3.4.
    let e = narrow.step(&model, &u, &dvector![wrap(3.4), 0.5]).unwrap();
    assert!((e.center[0] - 3.4).abs() < 0.2, "{}", e.center);
}

#[test]
fn a_partial_step_branches_its_measured_angle_only() {
    let (angled, plain) = (turning(true), turning(false));
    let u = DVector::zeros(0);
    let mut ours = SetMembershipFilter::new(setup(0.1)).unwrap();
    let mut reference = SetMembershipFilter::new(setup(0.1)).unwrap();
    let mut theta = 3.05;
    for k in 0..40 {
        theta += 0.05;
        // The compass every other step (across the cut), the gyro always.
        let mask = [k % 2 == 0, true];
        let y = dvector![if mask[0] { wrap(theta) } else { f64::NAN }, 0.5];
        let unwrapped = dvector![if mask[0] { theta } else { f64::NAN }, 0.5];
        let e = ours.step_partial(&angled, &u, &y, &mask).unwrap_or_else(|e| panic!("step {k}: {e}"));
        let want = reference.step_partial(&plain, &u, &unwrapped, &mask).unwrap();
        assert!((&e.center - &want.center).amax() < 1e-9 * (1.0 + theta), "step {k}: {} vs {}", e.center, want.center);
    }
}
