//! Angles declared once (examples/range-bearing: `angles = ["psi", "bearing_1", "bearing_2"]`):
//! a yard tractor driving full circles, so that both measured bearings cross ±π every turn. The
//! sensors report `wrap(h(x) + v)`; the certified filters contain the truth across every crossing
//! with every noise on the boundary of its box, and the Gaussian filters take the short way
//! round. Without the declaration the same data stop the EKF at the first crossing.

use equation_models::EquationModel;
use estimators::registry;
use estimators::{
    ConstrainedZonotopeFilter, ConstrainedZonotopeSettings, Estimate, EstimateKind, ExtendedKalmanFilter,
    NonlinearSetMembershipFilter, UnscentedKalmanFilter,
};
use models::{DiscreteModel, Xoshiro256StarStar, wrap_angle};
use nalgebra::{DVector, dvector};

const STEPS: usize = 800;

fn model_text() -> (std::path::PathBuf, String) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/range-bearing/model.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    (path, text)
}

fn compile(text: &str) -> EquationModel {
    EquationModel::from_toml_str_with_foreign_keys(text, "model.toml", &port_est::model::NOISE_KEYS).unwrap()
}

/// States, inputs and wrapped measurements of a run.
type Run = (Vec<DVector<f64>>, Vec<DVector<f64>>, Vec<DVector<f64>>);

/// The circling drive with noise on the vertices of its boxes.
fn circling(model: &EquationModel) -> Run {
    let (w, v) = ([0.01, 0.01, 0.002, 0.02], [0.3, 0.005, 0.3, 0.005]);
    let mut rng = Xoshiro256StarStar::seed_from_u64(5);
    let mut sign = move || if rng.uniform(-1.0, 1.0) < 0.0 { -1.0 } else { 1.0 };
    let mut x = dvector![1.5, -1.5, 0.15, 1.3];
    let (mut next, mut y) = (DVector::zeros(4), DVector::zeros(4));
    let (mut xs, mut us, mut ys) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..STEPS {
        // Speed held at 3 m/s, steering 0.4 rad: a circle of about 8.5 m every 18 s.
        let u = dvector![0.5 * (3.0 - x[3]), 0.4];
        model.f(&x, &u, &mut next).unwrap();
        x = &next + DVector::from_fn(4, |i, _| w[i] * sign());
        model.h(&x, &u, &mut y).unwrap();
        y += DVector::from_fn(4, |i, _| v[i] * sign());
        for i in [1, 3] {
            y[i] = wrap_angle(y[i]);
        }
        xs.push(x.clone());
        us.push(u);
        ys.push(y.clone());
    }
    (xs, us, ys)
}

fn crossings(ys: &[DVector<f64>]) -> usize {
    ys.windows(2).map(|p| [1, 3].iter().filter(|&&i| (p[1][i] - p[0][i]).abs() > std::f64::consts::PI).count()).sum()
}

#[test]
fn certified_filters_contain_the_truth_across_every_crossing() {
    let (path, text) = model_text();
    let model = compile(&text);
    let (xs, us, ys) = circling(&model);
    assert!(crossings(&ys) >= 5, "the drive must cross ±π: {} crossings", crossings(&ys));
    let file = port_est::model::read_model(&path).unwrap();
    let settings = ConstrainedZonotopeSettings { order: 6, max_constraints: 6, ..Default::default() };
    let mut czf =
        ConstrainedZonotopeFilter::new(file.setup(EstimateKind::GuaranteedConstrainedZonotope), settings).unwrap();
    let mut widest: f64 = 0.0;
    for (k, ((x, u), y)) in xs.iter().zip(&us).zip(&ys).enumerate() {
        let e = czf.step(&model, u, y).unwrap_or_else(|e| panic!("czf-nl, step {k}: {e}"));
        assert!(e.status().is_clean(), "czf-nl, step {k}: {:?}", e.status());
        for i in 0..4 {
            let (l, h) = e.bounds(i).unwrap();
            assert!(l <= x[i] && x[i] <= h, "czf-nl, step {k}, state {i}: {} outside [{l}, {h}]", x[i]);
            if k > 100 {
                widest = widest.max(h - l);
            }
        }
    }
    assert!(widest < 2.0, "czf-nl's widest interval after step 100: {widest}");
    // smf-nl on the same data: contained, and never guaranteed-lost.
    let mut smf = NonlinearSetMembershipFilter::new(file.setup(EstimateKind::GuaranteedEllipsoid)).unwrap();
    for (k, ((x, u), y)) in xs.iter().zip(&us).zip(&ys).enumerate() {
        let e = smf.step(&model, u, y).unwrap_or_else(|e| panic!("smf-nl, step {k}: {e}"));
        for i in 0..4 {
            let (l, h) = e.bounds(i).unwrap();
            assert!(l <= x[i] && x[i] <= h, "smf-nl, step {k}, state {i}: {} outside [{l}, {h}]", x[i]);
        }
    }
    // The heading went round more than twice and was never wrapped by the filter.
    assert!(xs.last().unwrap()[2] > 4.0 * std::f64::consts::PI);
}

#[test]
fn gaussian_filters_take_the_short_way_round() {
    let (path, text) = model_text();
    let model = compile(&text);
    let (xs, us, ys) = circling(&model);
    let file = port_est::model::read_model(&path).unwrap();
    let setup = file.setup(EstimateKind::Gaussian);
    let mut ekf = ExtendedKalmanFilter::new(setup.clone()).unwrap();
    let mut ukf = UnscentedKalmanFilter::new(setup.clone(), estimators::UkfParams::default()).unwrap();
    for (k, ((x, u), y)) in xs.iter().zip(&us).zip(&ys).enumerate() {
        let e = ekf.step(&model, u, y).unwrap_or_else(|e| panic!("EKF, step {k}: {e}"));
        let err = (e.center[0] - x[0]).hypot(e.center[1] - x[1]);
        assert!(err < 2.0 && (e.center[2] - x[2]).abs() < 0.1, "EKF, step {k}: position error {err}");
        let e = ukf.step(&model, u, y).unwrap_or_else(|e| panic!("UKF, step {k}: {e}"));
        let err = (e.center[0] - x[0]).hypot(e.center[1] - x[1]);
        assert!(err < 2.0 && (e.center[2] - x[2]).abs() < 0.1, "UKF, step {k}: position error {err}");
    }
    // The same data without the declaration: the first crossing is an outlier to the EKF.
    let undeclared = compile(&text.replace(r#"angles = ["psi", "bearing_1", "bearing_2"]"#, ""));
    assert!(undeclared.angles().is_empty());
    let mut ekf = ExtendedKalmanFilter::new(setup).unwrap();
    let failed = xs.iter().zip(&us).zip(&ys).position(|((_, u), y)| ekf.step(&undeclared, u, y).is_err());
    assert!(failed.is_some(), "the EKF without angles must refuse the first crossing");
}

#[test]
fn every_registry_estimator_that_runs_on_the_tractor_gets_through_the_crossings() {
    let (path, text) = model_text();
    let model = compile(&text);
    let (_, us, ys) = circling(&model);
    let file = port_est::model::read_model(&path).unwrap();
    let mut ran = Vec::new();
    for entry in registry::runs_on(&model) {
        if entry.measurement_len(4) != 4 {
            continue;
        }
        // Estimators that need settings a model file gives (an MHE's horizon) are built by their
        // own tests; every other one runs here with its defaults.
        let Ok(mut est) = entry.build(file.setup(entry.kind), None) else { continue };
        for (k, (u, y)) in us.iter().zip(&ys).enumerate().take(400) {
            if let Err(e) = est.step(&model, u, y) {
                panic!("{}: step {k}: {e}", entry.name);
            }
        }
        ran.push(entry.name);
    }
    eprintln!("ran: {ran:?}");
    for name in ["ekf", "ukf", "mhe-ukf", "smf-nl", "czf-nl"] {
        assert!(ran.contains(&name), "{name} did not run: {ran:?}");
    }
}
