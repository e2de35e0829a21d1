//! The fuzzy-adaptive Kalman filter (`docs/bds-ins-fuzzy-kf.md` §2) on the 13-state BDS/INS
//! model: agreement with the plain Kalman filter when `t ≡ 1`, agreement with an independent
//! textbook implementation of (9) for a scale that depends on `d_k`, the FIS's scales, bad input
//! (typed errors, state unchanged), partial fixes (the measured rows with the scale of the fix,
//! against the same independent implementation), and no allocation per step.

use bds_ins_dynamics::{DiscreteInsModel, InsErrorModel, InsNoise, InsParams, scenario, simulate_error_states};
use counting_allocator::{Counting, count};
use estimators::adaptive::ReceiverStatus;
use estimators::{
    AdaptiveError, AdaptiveKalmanFilter, ConstantScaling, EstimatorError, FuzzyScaling, KalmanFilter, NoiseScaling,
    ScalingContext,
};
use estimators::{DataChecks, Setup};
use fuzzy_inference::FuzzySystem;
use models::Xoshiro256StarStar;
use nalgebra::{DMatrix, DVector};

#[global_allocator]
static GLOBAL: Counting = Counting;

fn model() -> DiscreteInsModel {
    InsErrorModel::new(InsParams::digest(), InsNoise::digest_filter()).unwrap().discretize(1.0).unwrap()
}

/// Measurements of the paper's simulation: the error-state truth and `R0` (×25 after `switch`).
fn measurements(model: &DiscreteInsModel, steps: usize, switch: usize, seed: u64) -> Vec<DVector<f64>> {
    let mut rng = Xoshiro256StarStar::seed_from_u64(seed);
    let truth = simulate_error_states(model, &scenario::initial_error(), steps, &mut rng).unwrap();
    let r = scenario::nominal_r();
    truth[1..]
        .iter()
        .enumerate()
        .map(|(k, x)| {
            let f = if k >= switch { 5.0 } else { 1.0 };
            let v = DVector::from_fn(3, |i, _| f * r[(i, i)].sqrt() * rng.standard_normal());
            &model.h * x + v
        })
        .collect()
}

/// The filter of the paper, without an innovation gate: these tests feed it the paper's
/// scenario, whose noise grows fivefold after 600 s, to check the algebra of (9).
fn filter<S: NoiseScaling>(model: &DiscreteInsModel, scaling: S) -> AdaptiveKalmanFilter<S> {
    let mut f = AdaptiveKalmanFilter::new(
        Setup {
            x0: DVector::zeros(13),
            p0: scenario::initial_covariance(),
            process_noise: model.q.clone(),
            measurement_noise: scenario::nominal_r(),
            inputs: 0,
        },
        scaling,
    )
    .unwrap();
    f.set_data_checks(DataChecks::OFF).unwrap();
    f
}

fn status() -> ReceiverStatus {
    ReceiverStatus::new(20.0, 4.0).unwrap()
}

#[test]
fn unit_scale_is_the_plain_kalman_filter() {
    let m = model();
    let ys = measurements(&m, 300, 150, 1);
    let u = DVector::zeros(0);
    let mut kf = KalmanFilter::new(Setup {
        x0: DVector::zeros(13),
        p0: scenario::initial_covariance(),
        process_noise: m.q.clone(),
        measurement_noise: scenario::nominal_r(),
        inputs: 0,
    })
    .unwrap();
    kf.set_data_checks(DataChecks::OFF).unwrap();
    let mut constant = filter(&m, ConstantScaling(1.0));
    let mut closure = filter(&m, |_: &ScalingContext<'_>| 1.0);
    for (k, y) in ys.iter().enumerate() {
        // Every seventh epoch is an outage: prediction only.
        if k % 7 == 3 {
            kf.predict(&m, &u).unwrap();
            constant.predict(&m, &u).unwrap();
            closure.predict(&m, &u).unwrap();
            continue;
        }
        kf.step(&m, &u, y).unwrap();
        assert_eq!(constant.step_with_status(&m, &u, y, &status()).unwrap().scale, 1.0);
        closure.step_with_status(&m, &u, y, &status()).unwrap();
        for f in [constant.estimate(), closure.estimate()] {
            assert_eq!(f.center, kf.estimate().center, "step {k}");
            assert_eq!(f.covariance, kf.estimate().covariance, "step {k}");
        }
    }
    assert_eq!(constant.updates(), ys.len() as u64 - (0..ys.len()).filter(|k| k % 7 == 3).count() as u64);
}

/// Equation (9) and the textbook covariance update `P = (I − K H) P⁻`, with an explicit inverse.
struct Reference {
    x: DVector<f64>,
    p: DMatrix<f64>,
}

impl Reference {
    fn step(&mut self, m: &DiscreteInsModel, r: &DMatrix<f64>, y: &DVector<f64>, t_of_d: impl Fn(f64) -> f64) -> f64 {
        self.step_rows(m, r, y, &[0, 1, 2], t_of_d)
    }

    /// The same with the output rows `rows` only (`H_S`, `R_SS`, `ν_S`; rows 0 and 1 among them).
    fn step_rows(
        &mut self,
        m: &DiscreteInsModel,
        r: &DMatrix<f64>,
        y: &DVector<f64>,
        rows: &[usize],
        t_of_d: impl Fn(f64) -> f64,
    ) -> f64 {
        let x_pred = &m.phi * &self.x;
        let p_pred = &m.phi * &self.p * m.phi.transpose() + &m.q;
        let h = m.h.select_rows(rows);
        let innov = DVector::from_iterator(rows.len(), rows.iter().map(|&i| y[i])) - &h * &x_pred;
        let t = t_of_d((innov[0] * innov[0] + innov[1] * innov[1]).sqrt());
        let s = &h * &p_pred * h.transpose() + r.select_rows(rows).select_columns(rows) * t;
        let k = &p_pred * h.transpose() * s.try_inverse().unwrap();
        self.x = &x_pred + &k * innov;
        self.p = (DMatrix::identity(13, 13) - &k * &h) * p_pred;
        t
    }
}

#[test]
fn a_distance_dependent_scale_matches_an_independent_implementation_of_eq_9() {
    let m = model();
    let ys = measurements(&m, 200, 100, 2);
    let t_of_d = |d: f64| 1.0 + 10.0 * d * d;
    let mut f = filter(&m, move |c: &ScalingContext<'_>| t_of_d(c.distance));
    let mut reference = Reference { x: DVector::zeros(13), p: scenario::initial_covariance() };
    let u = DVector::zeros(0);
    let mut largest = 0.0f64;
    for y in &ys {
        let got = f.step_with_status(&m, &u, y, &status()).unwrap();
        let want = reference.step(&m, &scenario::nominal_r(), y, t_of_d);
        largest = largest.max(want);
        assert!((got.scale - want).abs() <= 1e-9 * want, "t {} vs {want}", got.scale);
        let e = f.estimate();
        for i in 0..13 {
            let scale = reference.p[(i, i)].sqrt();
            assert!((e.center[i] - reference.x[i]).abs() <= 1e-7 * scale, "x[{i}]");
            for j in 0..13 {
                let s = (reference.p[(i, i)] * reference.p[(j, j)]).sqrt();
                assert!((e.covariance[(i, j)] - reference.p[(i, j)]).abs() <= 1e-7 * s, "P[{i}][{j}]");
            }
        }
    }
    assert!(largest > 2.0, "the scale never left 1 ({largest}): the test would not test (9)");
}

#[test]
fn a_partial_fix_updates_with_its_rows_and_the_scale_of_its_horizontal_innovation() {
    use estimators::Estimator;
    let m = model();
    let ys = measurements(&m, 200, 100, 4);
    let t_of_d = |d: f64| 1.0 + 10.0 * d * d;
    let mut f = filter(&m, move |c: &ScalingContext<'_>| t_of_d(c.distance));
    let mut reference = Reference { x: DVector::zeros(13), p: scenario::initial_covariance() };
    let u = DVector::zeros(0);
    for (k, y) in ys.iter().enumerate() {
        // The heading missing at every third epoch (NaN in its cell), the whole fix otherwise.
        let heading = k % 3 != 0;
        let mut full = DVector::from_iterator(5, y.iter().copied().chain([20.0, 4.0]));
        if !heading {
            full[2] = f64::NAN;
        }
        let measured = [true, true, heading, true, true];
        let e = Estimator::<DiscreteInsModel>::step_partial(&mut f, &m, &u, &full, &measured).unwrap().clone();
        let rows: &[usize] = if heading { &[0, 1, 2] } else { &[0, 1] };
        let t = reference.step_rows(&m, &scenario::nominal_r(), y, rows, t_of_d);
        assert!((f.last_step().unwrap().scale - t).abs() <= 1e-9 * t, "step {k}");
        for i in 0..13 {
            let scale = reference.p[(i, i)].sqrt();
            assert!((e.center[i] - reference.x[i]).abs() <= 1e-7 * scale, "step {k}: x[{i}]");
            assert!((e.covariance[(i, i)] - reference.p[(i, i)]).abs() <= 1e-7 * reference.p[(i, i)], "P[{i}]");
        }
    }
    assert_eq!(f.updates(), ys.len() as u64);
}

#[test]
fn a_partial_fix_without_its_scale_s_inputs_is_refused_unchanged() {
    use estimators::Estimator;
    let m = model();
    let mut f = filter(&m, ConstantScaling(2.0));
    let u = DVector::zeros(0);
    let y = DVector::from_vec(vec![1.0, 2.0, 0.1, 20.0, 4.0]);
    f.step(&m, &u, &y).unwrap();
    let before = f.estimate().clone();
    let mut step = |measured: [bool; 5], y: &DVector<f64>| {
        Estimator::<DiscreteInsModel>::step_partial(&mut f, &m, &u, y, &measured).map(|e| e.center.clone())
    };
    // A horizontal output or the receiver status missing: d_k or t_k is not defined.
    for mask in [[true, false, true, true, true], [false, true, true, true, true], [true, true, true, false, true]] {
        let e = step(mask, &y).unwrap_err();
        assert!(matches!(e, EstimatorError::Unsupported { estimator: "fkf", .. }), "{mask:?}: {e}");
    }
    // NaN where measured, a mask of the wrong length.
    let nan = DVector::from_vec(vec![1.0, f64::NAN, 0.1, 20.0, 4.0]);
    assert!(matches!(step([true, true, false, true, true], &nan), Err(EstimatorError::NonFinite { index: 1, .. })));
    let e = Estimator::<DiscreteInsModel>::step_partial(&mut f, &m, &u, &y, &[true; 4]).unwrap_err();
    assert!(matches!(e, EstimatorError::DimensionMismatch { what: "measured", .. }), "{e}");
    assert_eq!(f.estimate().center, before.center);
    assert_eq!(f.estimate().covariance, before.covariance);
    // RTK 0 (no fix) with a partial row, or nothing measured: predictions.
    let no_fix = DVector::from_vec(vec![1.0, 2.0, f64::NAN, 20.0, 0.0]);
    let updates = f.updates();
    Estimator::<DiscreteInsModel>::step_partial(&mut f, &m, &u, &no_fix, &[true, true, false, true, true]).unwrap();
    Estimator::<DiscreteInsModel>::step_partial(&mut f, &m, &u, &no_fix, &[false; 5]).unwrap();
    assert_eq!(f.updates(), updates);
}

#[test]
fn the_fuzzy_scaling_gives_the_notes_values_and_reports_them() {
    let m = model();
    let u = DVector::zeros(0);
    // From X̂ = 0 the innovation is y itself: d = |(y1, y2)|.
    for (n, rtk, d, want) in [
        (20.0, 3.0, 0.05, 1.00),
        (20.0, 3.0, 0.7, 5.01),
        (20.0, 4.0, 0.05, 5.01),
        (20.0, 1.0, 0.5, 8.72),
        (9.0, 4.0, 0.7, 12.6),
        (5.0, 1.0, 2.0, 25.1),
    ] {
        let mut f = filter(&m, FuzzyScaling::bds_ins_default());
        let y = DVector::from_vec(vec![0.6 * d, 0.8 * d, 0.0]);
        let s = f.step_with_status(&m, &u, &y, &ReceiverStatus::new(n, rtk).unwrap()).unwrap();
        assert!((s.distance - d).abs() < 1e-12);
        assert!((s.scale - want).abs() <= 0.006 * want, "({n}, {rtk}, {d}) → {} (note: {want})", s.scale);
        assert_eq!(f.last_step(), Some(s));
        let e = f.scaling().last_evaluation().unwrap();
        assert_eq!(e.output, s.scale);
        assert_eq!(e.output, FuzzySystem::bds_ins_default().evaluate(&[n, rtk, d]).unwrap().output);
    }
    // A larger t_k trusts the measurement less: a larger posterior position variance.
    let y = DVector::from_vec(vec![0.1, 0.0, 0.0]);
    let mut a = filter(&m, ConstantScaling(1.0));
    let mut b = filter(&m, ConstantScaling(25.0));
    a.step_with_status(&m, &u, &y, &status()).unwrap();
    b.step_with_status(&m, &u, &y, &status()).unwrap();
    assert!(b.estimate().covariance[(0, 0)] > 10.0 * a.estimate().covariance[(0, 0)]);
    assert!(b.estimate().center[0].abs() < a.estimate().center[0].abs());
}

#[test]
fn bad_input_is_a_typed_error_and_leaves_the_filter_unchanged() {
    let m = model();
    let u = DVector::zeros(0);
    let ys = measurements(&m, 5, 5, 3);
    let mut f = filter(&m, FuzzyScaling::bds_ins_default());
    f.step_with_status(&m, &u, &ys[0], &status()).unwrap();
    let before = f.estimate().clone();
    let last = f.last_step();
    let unchanged = |f: &AdaptiveKalmanFilter<FuzzyScaling>| {
        assert_eq!(f.estimate(), &before);
        assert_eq!(f.last_step(), last);
        assert_eq!(f.updates(), 1);
    };
    let mut nan = ys[1].clone();
    nan[2] = f64::NAN;
    let e = f.step_with_status(&m, &u, &nan, &status()).unwrap_err();
    assert_eq!(e, AdaptiveError::Filter(EstimatorError::NonFinite { what: "y", index: 2 }));
    unchanged(&f);
    let short = DVector::from_vec(vec![0.1, 0.2]);
    assert!(matches!(
        f.step_with_status(&m, &u, &short, &status()),
        Err(AdaptiveError::Filter(EstimatorError::DimensionMismatch { .. }))
    ));
    unchanged(&f);
    assert!(f.predict(&m, &DVector::zeros(1)).is_err());
    unchanged(&f);
    // The receiver status is validated before a step can be asked for.
    assert_eq!(ReceiverStatus::new(-3.0, 3.0), Err(AdaptiveError::NegativeSatellites(-3.0)));
    assert_eq!(ReceiverStatus::new(20.0, 0.0), Err(AdaptiveError::RtkOutOfRange(0.0)));
    assert_eq!(ReceiverStatus::new(20.0, 5.0), Err(AdaptiveError::RtkOutOfRange(5.0)));
    assert!(matches!(ReceiverStatus::new(f64::NAN, 3.0), Err(AdaptiveError::NonFinite { .. })));

    // A scaling that returns a non-physical scale, or fails.
    for bad in [f64::NAN, 0.0, -1.0, f64::INFINITY] {
        let mut g = filter(&m, move |_: &ScalingContext<'_>| bad);
        let before = g.estimate().clone();
        let e = g.step_with_status(&m, &u, &ys[0], &status()).unwrap_err();
        assert!(matches!(e, AdaptiveError::InvalidScale(v) if v.is_nan() == bad.is_nan()), "{e}");
        assert_eq!(g.estimate(), &before);
        assert_eq!((g.updates(), g.last_step()), (0, None));
    }
    struct Failing;
    impl NoiseScaling for Failing {
        fn scale(&mut self, _: &ScalingContext<'_>) -> Result<f64, AdaptiveError> {
            Err(AdaptiveError::InvalidScale(-2.0))
        }
    }
    let mut g = filter(&m, Failing);
    let before = g.estimate().clone();
    assert!(g.step_with_status(&m, &u, &ys[0], &status()).is_err());
    assert_eq!(g.estimate(), &before);

    // Construction errors.
    let e = AdaptiveKalmanFilter::new(
        Setup {
            x0: DVector::zeros(2),
            p0: DMatrix::identity(2, 2),
            process_noise: DMatrix::identity(2, 2),
            measurement_noise: DMatrix::identity(1, 1),
            inputs: 0,
        },
        ConstantScaling(1.0),
    )
    .unwrap_err();
    assert_eq!(e, AdaptiveError::HorizontalComponents { components: [0, 1], outputs: 1 });
    assert!(filter(&m, ConstantScaling(1.0)).with_horizontal([1, 1]).is_err());
    assert!(filter(&m, ConstantScaling(1.0)).with_horizontal([0, 3]).is_err());
    assert!(filter(&m, ConstantScaling(1.0)).with_horizontal([0, 2]).is_ok());
    let two_inputs = FuzzySystem::from_toml_str(
        "default_output = 1.0\n\
         [[inputs]]\nname = \"a\"\nrange = [0.0, 1.0]\nsets = [{ name = \"lo\", trapezoid = [0.0, 0.0, 0.5, 1.0] }]\n\
         [[inputs]]\nname = \"b\"\nrange = [0.0, 1.0]\nsets = [{ name = \"lo\", trapezoid = [0.0, 0.0, 0.5, 1.0] }]\n\
         [output]\nname = \"t\"\nuniverse = [0.0, 1.0]\nsets = [{ name = \"z\", triangle = [0.0, 0.5, 1.0] }]\n\
         [[rules]]\nif = { a = \"lo\", b = \"lo\" }\nthen = \"z\"\n",
        "two.toml",
    )
    .unwrap();
    assert_eq!(FuzzyScaling::new(two_inputs).unwrap_err(), AdaptiveError::FuzzyInputCount(2));
}

#[test]
fn steps_do_not_allocate() {
    let m = model();
    let u = DVector::zeros(0);
    let ys = measurements(&m, 200, 100, 4);
    let mut f = filter(&m, FuzzyScaling::bds_ins_default());
    let statuses = [status(), ReceiverStatus::new(5.0, 1.0).unwrap(), ReceiverStatus::new(12.0, 3.0).unwrap()];
    f.step_with_status(&m, &u, &ys[0], &statuses[0]).unwrap();
    let (_, n) = count(|| {
        for (k, y) in ys.iter().enumerate() {
            if k % 10 == 9 {
                f.predict(&m, &u).unwrap();
            } else {
                f.step_with_status(&m, &u, y, &statuses[k % 3]).unwrap();
            }
        }
    });
    assert_eq!(n, 0, "a fuzzy-adaptive step allocated");
}
