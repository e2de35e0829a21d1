//! Bad input: typed errors naming the problem, the filter unchanged (the next valid step is
//! bit-for-bit what it would have been), no panic.

mod common;

use estimators::{EstimatorError, KalmanFilter, SetMembershipFilter, StepModel};
use nalgebra::{DMatrix, DVector};

fn system() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    (common::reference_a(), DMatrix::from_fn(4, 2, |i, j| 0.1 * (i + j) as f64), common::reference_c())
}

fn smf() -> SetMembershipFilter {
    SetMembershipFilter::new(common::setup(
        &DVector::from_vec(vec![0.1, 0.2, -0.1, 0.0]),
        &(DMatrix::identity(4, 4) * 0.5),
        &(DMatrix::identity(4, 4) * 0.01),
        &(DMatrix::identity(3, 3) * 0.05),
        2,
    ))
    .unwrap()
}

fn kf() -> KalmanFilter {
    KalmanFilter::new(common::setup(
        &DVector::from_vec(vec![0.1, 0.2, -0.1, 0.0]),
        &(DMatrix::identity(4, 4) * 0.5),
        &(DMatrix::identity(4, 4) * 0.01),
        &(DMatrix::identity(3, 3) * 0.05),
        2,
    ))
    .unwrap()
}

/// A bad call: the expected error text, then `A`, `B`, `C`, `u`, `y`.
type BadCall = (&'static str, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DVector<f64>, DVector<f64>);

/// The same good step on a reference and on a filter that refused bad calls before it: the
/// same set, bit for bit, and the same multipliers.
fn assert_same_set(r: &estimators::SetEstimate, t: &estimators::SetEstimate, k: usize) {
    assert_eq!(r.center.as_slice(), t.center.as_slice(), "step {k}");
    assert_eq!(r.shape.as_slice(), t.shape.as_slice(), "step {k}");
    assert_eq!(r.report.tau, t.report.tau, "step {k}");
}

/// Bad calls, each with a check of the error.
fn bad_calls() -> Vec<BadCall> {
    let (a, b, c) = system();
    let u = DVector::from_vec(vec![0.3, -0.1]);
    let y = DVector::from_vec(vec![0.1, 0.0, 0.2]);
    let mut a_nan = a.clone();
    a_nan[(1, 2)] = f64::NAN;
    let mut c_inf = c.clone();
    c_inf[(0, 0)] = f64::INFINITY;
    let mut b_nan = b.clone();
    b_nan[(3, 1)] = f64::NAN;
    vec![
        ("u has a non-finite", a.clone(), b.clone(), c.clone(), DVector::from_vec(vec![f64::NAN, 0.0]), y.clone()),
        (
            "y has a non-finite",
            a.clone(),
            b.clone(),
            c.clone(),
            u.clone(),
            DVector::from_vec(vec![0.0, f64::INFINITY, 0.0]),
        ),
        ("dimension mismatch for u", a.clone(), b.clone(), c.clone(), DVector::zeros(3), y.clone()),
        ("dimension mismatch for y", a.clone(), b.clone(), c.clone(), u.clone(), DVector::zeros(4)),
        ("dimension mismatch for rows of A", DMatrix::zeros(3, 4), b.clone(), c.clone(), u.clone(), y.clone()),
        (
            "dimension mismatch for columns of B: expected 2, found 3",
            a.clone(),
            DMatrix::zeros(4, 3),
            c.clone(),
            u.clone(),
            y.clone(),
        ),
        (
            "dimension mismatch for rows of C: expected 3, found 2",
            a.clone(),
            b.clone(),
            DMatrix::zeros(2, 4),
            u.clone(),
            y.clone(),
        ),
        (
            "dimension mismatch for columns of A: expected 4, found 3",
            DMatrix::zeros(4, 3),
            b.clone(),
            c.clone(),
            u.clone(),
            y.clone(),
        ),
        (
            "dimension mismatch for columns of C: expected 4, found 5",
            a.clone(),
            b.clone(),
            DMatrix::zeros(3, 5),
            u.clone(),
            y.clone(),
        ),
        ("A has a non-finite", a_nan, b.clone(), c.clone(), u.clone(), y.clone()),
        ("B has a non-finite", a.clone(), b_nan, c.clone(), u.clone(), y.clone()),
        ("C has a non-finite", a.clone(), b.clone(), c_inf, u.clone(), y.clone()),
    ]
}

#[test]
fn set_membership_filter_is_unchanged_by_bad_calls() {
    let (a, b, c) = system();
    let model = StepModel::new(&a, &b, &c);
    let u = DVector::from_vec(vec![0.3, -0.1]);
    let y = DVector::from_vec(vec![0.1, 0.0, 0.2]);
    let mut reference = smf();
    let mut tested = smf();
    for k in 0..3 {
        reference.step(&model, &u, &y).unwrap();
        tested.step(&model, &u, &y).unwrap();
        for (what, a2, b2, c2, u2, y2) in bad_calls() {
            let err = tested.step(&StepModel::new(&a2, &b2, &c2), &u2, &y2).unwrap_err();
            assert!(err.to_string().contains(what), "{what}: {err}");
        }
        // Setters with bad matrices are rejected and change nothing.
        let bad_q = DMatrix::from_row_slice(
            4,
            4,
            &[1.0, 2.0, 0.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        );
        assert_eq!(tested.set_process_noise(&bad_q).unwrap_err(), EstimatorError::NotPositiveDefinite { what: "Q" });
        let mut asym = DMatrix::identity(3, 3);
        asym[(0, 1)] = 0.5;
        assert_eq!(tested.set_measurement_noise(&asym).unwrap_err(), EstimatorError::NotSymmetric { what: "R" });
        let r = reference.step(&model, &u, &y).unwrap().clone();
        assert_same_set(&r, tested.step(&model, &u, &y).unwrap(), k);
    }
}

#[test]
fn kalman_filter_is_unchanged_by_bad_calls() {
    let (a, b, c) = system();
    let model = StepModel::new(&a, &b, &c);
    let u = DVector::from_vec(vec![0.3, -0.1]);
    let y = DVector::from_vec(vec![0.1, 0.0, 0.2]);
    let mut reference = kf();
    let mut tested = kf();
    for (what, a2, b2, c2, u2, y2) in bad_calls() {
        let err = tested.step(&StepModel::new(&a2, &b2, &c2), &u2, &y2).unwrap_err();
        assert!(err.to_string().contains(what), "{what}: {err}");
    }
    let r = reference.step(&model, &u, &y).unwrap().clone();
    let t = tested.step(&model, &u, &y).unwrap().clone();
    assert_eq!(r.center.as_slice(), t.center.as_slice());
    assert_eq!(r.covariance.as_slice(), t.covariance.as_slice());
}

#[test]
fn constructors_reject_bad_matrices_with_named_errors() {
    let i4 = DMatrix::identity(4, 4);
    let i3 = DMatrix::identity(3, 3);
    let x = DVector::zeros(4);
    let not_pd = -DMatrix::identity(4, 4);
    let e = SetMembershipFilter::new(common::setup(&x, &not_pd, &i4, &i3, 1)).unwrap_err();
    assert_eq!(e, EstimatorError::NotPositiveDefinite { what: "P0" });
    let e = SetMembershipFilter::new(common::setup(&x, &i4, &not_pd, &i3, 1)).unwrap_err();
    assert_eq!(e, EstimatorError::NotPositiveDefinite { what: "Q" });
    let e = SetMembershipFilter::new(common::setup(&x, &i4, &i4, &DMatrix::zeros(3, 3), 1)).unwrap_err();
    assert_eq!(e, EstimatorError::NotPositiveDefinite { what: "R" });
    let e = SetMembershipFilter::new(common::setup(&x, &DMatrix::identity(3, 3), &i4, &i3, 1)).unwrap_err();
    assert!(matches!(e, EstimatorError::DimensionMismatch { what: "P0", .. }), "{e}");
    let mut nan_q = i4.clone();
    nan_q[(2, 2)] = f64::NAN;
    let e = KalmanFilter::new(common::setup(&x, &i4, &nan_q, &i3, 1)).unwrap_err();
    assert_eq!(e, EstimatorError::NonFinite { what: "Q", index: 10 });
    let e = KalmanFilter::new(common::setup(&DVector::from_element(4, f64::NAN), &i4, &i4, &i3, 1)).unwrap_err();
    assert_eq!(e, EstimatorError::NonFinite { what: "x0", index: 0 });
    let e = SetMembershipFilter::new(common::setup(&DVector::zeros(0), &DMatrix::zeros(0, 0), &i4, &i3, 1));
    assert!(matches!(e, Err(EstimatorError::EmptySystem(_))));
    let e = SetMembershipFilter::new(common::setup(&x, &i4, &i4, &i3, 2))
        .unwrap()
        .with_input_bounds(&DVector::from_vec(vec![1.0, 0.0]), &DVector::from_vec(vec![0.0, 1.0]))
        .unwrap_err();
    assert!(matches!(e, EstimatorError::InvalidInputBounds { index: 0, .. }), "{e}");
}

#[test]
fn extreme_values_give_errors_or_results_never_panics() {
    let (a, b, c) = system();
    let big_a = &a * 1e150;
    let mut f = smf();
    let mut k = kf();
    let u = DVector::from_vec(vec![1e300, -1e300]);
    let y = DVector::from_vec(vec![1e300, 0.0, -1e300]);
    for _ in 0..5 {
        let model = StepModel::new(&big_a, &b, &c);
        let before = f.estimate().clone();
        if f.step(&model, &u, &y).is_err() {
            assert_eq!(&before, f.estimate());
        }
        let _ = k.step(&model, &u, &y);
        let _ = f.step(&StepModel::new(&a, &b, &c), &u, &y);
    }
    // The filter still works afterwards when it did not accept the bad data... or it holds
    // finite numbers if it did.
    assert!(f.estimate().center.iter().all(|v| v.is_finite()));
    assert!(f.estimate().shape.iter().all(|v| v.is_finite()));
}

#[test]
fn yang_li_refuses_an_input_outside_its_box_and_stays_unchanged() {
    // Variant (a) covers B u only for u in the declared box; outside it the guarantee would
    // silently break (a normalised distance ~7e5 was observed), so the step is refused.
    let (a, b, c) = system();
    let model = StepModel::new(&a, &b, &c);
    let (lo, hi) = (DVector::from_vec(vec![-1.0, 0.0]), DVector::from_vec(vec![1.0, 0.5]));
    let make = || {
        estimators::yang_li::without_input(
            common::setup(
                &DVector::from_vec(vec![0.1, 0.2, -0.1, 0.0]),
                &(DMatrix::identity(4, 4) * 0.5),
                &(DMatrix::identity(4, 4) * 0.01),
                &(DMatrix::identity(3, 3) * 0.05),
                lo.len(),
            ),
            &lo,
            &hi,
            estimators::TwoMultiplierSolver::new(),
        )
        .unwrap()
    };
    let y = DVector::from_vec(vec![0.1, 0.0, 0.2]);
    let mut reference = make();
    let mut tested = make();
    for k in 0..3 {
        let u = DVector::from_vec(vec![0.3 * k as f64 - 0.5, 0.25]);
        reference.step(&model, &u, &y).unwrap();
        tested.step(&model, &u, &y).unwrap();
        let before = tested.estimate().clone();
        for (bad, index, value) in [
            (vec![1.5, 0.25], 0, 1.5),
            (vec![0.0, -1e-12], 1, -1e-12),
            (vec![-1.0 - 1e-15, 0.5], 0, -1.0 - 1e-15),
            (vec![0.0, f64::MAX], 1, f64::MAX),
        ] {
            let err = tested.step(&model, &DVector::from_vec(bad), &y).unwrap_err();
            let (l, h) = (lo[index], hi[index]);
            assert_eq!(err, EstimatorError::InputOutsideBounds { index, value, lower: l, upper: h });
            let text = err.to_string();
            assert!(text.contains(&format!("u[{index}]")) && text.contains(&format!("[{l}, {h}]")), "{text}");
            assert_eq!(&before, tested.estimate(), "step {k}");
        }
        // NaN is still reported as non-finite.
        let err = tested.step(&model, &DVector::from_vec(vec![f64::NAN, 0.0]), &y).unwrap_err();
        assert_eq!(err, EstimatorError::NonFinite { what: "u", index: 0 });
        // The corners of the box are inside.
        let corner = DVector::from_vec(vec![1.0, 0.0]);
        let r = reference.step(&model, &corner, &y).unwrap().clone();
        assert_same_set(&r, tested.step(&model, &corner, &y).unwrap(), k);
    }
}

#[test]
fn badly_scaled_positive_definite_noise_is_accepted() {
    // diag(1e-12, 1e4) is positive definite to working precision (a conditioning floor relative to
    // the largest diagonal entry used to reject it); a singular one is still refused where a shape
    // must be definite (the set-membership filter's ellipsoid), taken where it is a covariance.
    use estimators::{KalmanFilter, SetMembershipFilter};
    use nalgebra::{DMatrix, DVector};
    let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1e-12, 1e4]));
    let r = DMatrix::identity(1, 1);
    let p0 = DMatrix::identity(2, 2);
    assert!(KalmanFilter::new(common::setup(&DVector::zeros(2), &p0, &q, &r, 1)).is_ok());
    let mut f = SetMembershipFilter::new(common::setup(&DVector::zeros(2), &p0, &q, &r, 1)).unwrap();
    assert!(f.set_process_noise(&q).is_ok());
    let singular = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
    assert!(f.set_process_noise(&singular).is_err());
    // A Gaussian filter's Q is a covariance: singular is allowed, indefinite is not.
    let kf = |q: &DMatrix<f64>| KalmanFilter::new(common::setup(&DVector::zeros(2), &p0, q, &r, 1));
    assert!(kf(&singular).is_ok());
    assert!(kf(&DMatrix::zeros(2, 2)).is_ok());
    let indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 1.0 + 1e-6, 1.0 + 1e-6, 1.0]);
    assert_eq!(kf(&indefinite).unwrap_err(), EstimatorError::NotPositiveSemidefinite { what: "Q" });
    let mut k = kf(&q).unwrap();
    assert!(k.set_process_noise(&singular).is_ok());
    assert_eq!(k.set_process_noise(&indefinite).unwrap_err(), EstimatorError::NotPositiveSemidefinite { what: "Q" });
}
