use super::*;
use crate::ukf::UkfParams;
use models::{ConstantModel, DifferentiableView, DiscreteView};
use nalgebra::{DMatrix, dvector};

fn setup() -> Setup {
    Setup {
        x0: dvector![0.0, 0.0],
        p0: DMatrix::identity(2, 2),
        process_noise: DMatrix::identity(2, 2) * 0.01,
        measurement_noise: DMatrix::identity(1, 1) * 0.1,
        inputs: 1,
    }
}

#[test]
fn registry_estimators_can_move_to_another_thread() {
    fn send<T: Send>(_: &T) {}
    let est = build(names::SMF, setup(), None).unwrap();
    send(&est);
    let handle = std::thread::spawn(move || est.estimate().center().len());
    assert_eq!(handle.join().unwrap(), 2);
}

#[test]
fn names_are_unique_and_defaults_match_their_rows() {
    for (i, e) in ESTIMATORS.iter().enumerate() {
        assert!(ESTIMATORS[..i].iter().all(|o| o.name != e.name), "{} twice", e.name);
        if let Some(s) = e.settings.default_settings() {
            assert_eq!(s.kind(), e.settings, "{}", e.name);
        }
    }
    assert!(matches!(lookup("nope"), Err(EstimatorError::UnknownEstimator { .. })));
}

#[test]
fn a_model_without_the_capability_is_named() {
    let m =
        ConstantModel::new(DMatrix::identity(2, 2), DMatrix::zeros(2, 1), DMatrix::from_row_slice(1, 2, &[1.0, 0.0]))
            .unwrap();
    let (u, y) = (DVector::zeros(1), DVector::zeros(1));
    let mut kf = build("kf", setup(), None).unwrap();
    let Err(e) = kf.step_dyn(&DifferentiableView(&m), &u, &y) else { panic!("a linear filter ran without A, B, C") };
    assert!(matches!(e, EstimatorError::ModelLacksCapability { needs: Capability::Linear, .. }), "{e}");
    let mut ekf = build("ekf", setup(), None).unwrap();
    assert!(ekf.step_dyn(&DifferentiableView(&m), &u, &y).is_ok());
    assert!(ekf.step_dyn(&DiscreteView(&m), &u, &y).is_err());
    let mut ukf = build("ukf", setup(), None).unwrap();
    assert!(ukf.step_dyn(&DiscreteView(&m), &u, &y).is_ok());
    assert_eq!(runs_on(&DiscreteView(&m)).map(|e| e.name).collect::<Vec<_>>(), ["ukf"]);
}

#[test]
fn settings_are_checked_against_the_row() {
    let e = build("kf", setup(), Some(EstimatorSettings::Unscented(UkfParams::default()))).unwrap_err();
    assert!(matches!(e, EstimatorError::WrongSettings { estimator: "kf", .. }), "{e}");
    let e = build("yang-li", setup(), None).unwrap_err();
    assert!(matches!(e, EstimatorError::MissingSetting { estimator: "yang-li", .. }), "{e}");
    let b = InputBox { lower: dvector![-1.0], upper: dvector![1.0] };
    let s = EstimatorSettings::SetMembershipInputBox(SetMembershipSettings::default(), b);
    assert!(build("yang-li", setup(), Some(s)).is_ok());
    assert!(matches!(SmfSolver::by_name("nope"), Err(EstimatorError::UnknownSolver { .. })));
    assert_eq!(SmfSolver::by_name("two-multiplier").unwrap(), SmfSolver::TwoMultiplier);
}

#[test]
fn every_row_declares_the_details_its_estimator_reports() {
    // Two states, both measured (the fuzzy-adaptive filter needs two horizontal outputs).
    let (a, b, c) =
        (DMatrix::identity(2, 2) * 0.9, DMatrix::from_row_slice(2, 1, &[0.0, 0.1]), DMatrix::identity(2, 2));
    let m = ConstantModel::new(a, b, c).unwrap();
    let setup = Setup { measurement_noise: DMatrix::identity(2, 2) * 0.1, ..setup() };
    let boxed = |n: usize, h: f64| (DVector::from_element(n, -h), DVector::from_element(n, h));
    for e in ESTIMATORS {
        let settings = match e.settings {
            SettingsKind::SetMembershipInputBox => Some(EstimatorSettings::SetMembershipInputBox(
                SetMembershipSettings::default(),
                InputBox { lower: dvector![-1.0], upper: dvector![1.0] },
            )),
            SettingsKind::MovingHorizon => {
                Some(EstimatorSettings::MovingHorizon(Box::new(MheSettings::new(boxed(2, 0.1), boxed(2, 0.3)))))
            }
            _ => None,
        };
        let mut est = e.build(setup.clone(), settings).unwrap_or_else(|err| panic!("{}: {err}", e.name));
        assert_eq!(est.estimate().details().fields(), e.details, "{}: initial estimate", e.name);
        let y = DVector::from_iterator(
            e.measurement_len(2),
            [0.05, -0.02, 12.0, 3.0].into_iter().take(e.measurement_len(2)),
        );
        let step = est.step(&m, &dvector![0.0], &y).unwrap_or_else(|err| panic!("{}: {err}", e.name));
        let mut names = Vec::new();
        step.details().for_each_field(&mut |name, _| names.push(name));
        let declared: Vec<_> = e.details.iter().map(|f| f.name).collect();
        assert_eq!(names, declared, "{}: a step", e.name);
        assert!(e.details.iter().all(|f| !f.meaning.is_empty()), "{}", e.name);
    }
}
