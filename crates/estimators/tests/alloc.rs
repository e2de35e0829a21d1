//! No heap allocation in a Kalman step or a set-membership step (two-multiplier, compiled for its
//! size or on the runtime-size kernels, fallback,
//! re-certification with the fallback, Yang–Li (a), SDP-backed) after a warm-up step (a counting global allocator, counting only on this test's thread).

mod common;

use counting_allocator::{Counting, count};
use estimators::Setup;

use estimators::{KalmanFilter, SdpUpdateSolver, SetMembershipFilter, StepModel, TwoMultiplierSolver, yang_li};
use nalgebra::{DMatrix, DVector};

#[global_allocator]
static GLOBAL: Counting = Counting;

fn r_mat(m: usize) -> DMatrix<f64> {
    DMatrix::identity(m, m) * 0.05
}

/// Reports "solved" with a finite gain whose certified shape overflows.
fn overflowing() -> common::FixedSolver {
    common::FixedSolver {
        l: 1e200,
        tau: [0.25, 0.25, 0.5],
        status: estimators::smf::UpdateStatus::Solved,
        iterations: 0,
        closed_form: true,
    }
}

#[test]
fn steps_do_not_allocate_after_warm_up() {
    let a = common::reference_a();
    let b = DMatrix::from_fn(4, 2, |i, j| 0.01 * (i + 2 * j) as f64);
    for m in [3, 4] {
        let c = if m == 3 { common::reference_c() } else { DMatrix::identity(4, 4) };
        let model = StepModel::new(&a, &b, &c);
        let u = DVector::from_vec(vec![0.2, -0.1]);
        let ys: Vec<DVector<f64>> =
            (0..200).map(|k| DVector::from_fn(m, |i, _| ((k * 7 + i) as f64).sin() * 0.1)).collect();
        let (x0, p0, q, r) = (
            DVector::zeros(4),
            DMatrix::identity(4, 4) * 0.5,
            DMatrix::identity(4, 4) * 0.01,
            DMatrix::identity(m, m) * 0.05,
        );

        let mut kf = KalmanFilter::new(common::setup(&x0, &p0, &q, &r, 2)).unwrap();
        kf.step(&model, &u, &ys[0]).unwrap();
        let (_, n) = count(|| {
            for y in &ys {
                kf.step(&model, &u, y).unwrap();
            }
        });
        assert_eq!(n, 0, "Kalman step allocated (m = {m})");

        let mut smf = SetMembershipFilter::new(common::setup(&x0, &p0, &q, &r, 2)).unwrap();
        smf.step(&model, &u, &ys[0]).unwrap();
        let (_, n) = count(|| {
            for y in &ys {
                smf.step(&model, &u, y).unwrap();
            }
        });
        assert_eq!(n, 0, "two-multiplier step allocated (m = {m})");
        assert!(smf.estimate().report.fallback.is_none());
        assert!(smf.runs_compiled_step(), "(4, {m}) runs the step compiled for its size");
        // The runtime-size step, as a filter of another size runs it.
        let mut general = smf.clone();
        general.use_general_kernels();
        general.step(&model, &u, &ys[0]).unwrap();
        let (_, n) = count(|| {
            for y in &ys {
                general.step(&model, &u, y).unwrap();
            }
        });
        assert_eq!(n, 0, "two-multiplier step with the runtime-size kernels allocated (m = {m})");

        // Also: the fallback path and the Yang–Li (a) reconstruction.
        smf.set_time_budget(Some(std::time::Duration::ZERO));
        let (_, n) = count(|| smf.step(&model, &u, &ys[1]).map(|e| e.report.fallback.is_some()));
        assert_eq!(n, 0, "fallback step allocated (m = {m})");
        let mut yl = yang_li::without_input(
            common::setup(&x0, &p0, &q, &r, DVector::from_vec(vec![-1.0, -1.0]).len()),
            &DVector::from_vec(vec![-1.0, -1.0]),
            &DVector::from_vec(vec![1.0, 1.0]),
            TwoMultiplierSolver::new(),
        )
        .unwrap();
        yl.step(&model, &u, &ys[0]).unwrap();
        let (_, n) = count(|| {
            for y in &ys {
                yl.step(&model, &u, y).unwrap();
            }
        });
        assert_eq!(n, 0, "Yang-Li step allocated (m = {m})");
        // An input outside the box is refused without allocating.
        let outside = DVector::from_vec(vec![2.0, 0.0]);
        let (r, n) = count(|| yl.step(&model, &outside, &ys[0]).is_err());
        assert!(r);
        assert_eq!(n, 0, "refusing an input outside the box allocated (m = {m})");
        // A "solved" result whose certification overflows: redone with the fallback.
        let mut bad = SetMembershipFilter::with_solver(
            Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q.clone(), measurement_noise: r_mat(m), inputs: 2 },
            overflowing(),
        )
        .unwrap();
        bad.step(&model, &u, &ys[0]).unwrap();
        let (_, n) = count(|| {
            for y in &ys {
                let e = bad.step(&model, &u, y).unwrap();
                assert_eq!(e.report.fallback, Some(estimators::smf::FallbackReason::InvalidSolution));
            }
        });
        assert_eq!(n, 0, "re-certification with the fallback allocated (m = {m})");
        // Errors allocate nothing either (their messages are static).
        let (_, n) = count(|| smf.step(&model, &DVector::zeros(0), &ys[0]).is_err());
        assert_eq!(n, 0);
    }
}

#[test]
fn sdp_step_with_the_default_backend_does_not_allocate_after_setup() {
    // The first step builds (28) and sets the backend up; later steps rewrite the numbers in
    // place (`FilterSdp::update`), solve without allocating and read only (L, τ).
    let a = common::reference_a();
    let b = DMatrix::from_fn(4, 2, |i, j| 0.01 * (i + 2 * j) as f64);
    let c = common::reference_c();
    let model = StepModel::new(&a, &b, &c);
    let u = DVector::from_vec(vec![0.2, -0.1]);
    let ys: Vec<DVector<f64>> = (0..20).map(|k| DVector::from_fn(3, |i, _| ((k * 7 + i) as f64).sin() * 0.1)).collect();
    // Cold and warm-started solves (the filters' default through `LinearSetup`).
    for warm_start in [false, true] {
        let settings = lmi::SolverSettings { warm_start, ..lmi::SolverSettings::default() };
        let solver = SdpUpdateSolver::by_name(lmi::DEFAULT_BACKEND, settings).unwrap();
        let mut smf = SetMembershipFilter::with_solver(
            common::setup(
                &DVector::zeros(4),
                &(DMatrix::identity(4, 4) * 0.5),
                &(DMatrix::identity(4, 4) * 0.01),
                &(DMatrix::identity(3, 3) * 0.05),
                2,
            ),
            solver,
        )
        .unwrap();
        smf.step(&model, &u, &ys[0]).unwrap();
        let (_, n) = count(|| {
            for y in &ys {
                let e = smf.step(&model, &u, y).unwrap();
                assert!(e.report.fallback.is_none());
            }
        });
        assert_eq!(n, 0, "SDP-backed step allocated (warm start {warm_start})");
    }
}

#[test]
fn registry_estimators_and_noise_setters_do_not_allocate_after_warm_up() {
    use estimators::registry::{self, EstimatorSettings, InputBox, SetMembershipSettings, SettingsKind};
    use models::AnyModel;
    let a = common::reference_a();
    let b = DMatrix::from_fn(4, 2, |i, j| 0.01 * (i + 2 * j) as f64);
    let c = common::reference_c();
    let model = StepModel::new(&a, &b, &c);
    let dyn_model: &dyn AnyModel = &model;
    let u = DVector::from_vec(vec![0.2, -0.1]);
    let ys: Vec<DVector<f64>> = (0..50).map(|k| DVector::from_fn(3, |i, _| ((k * 7 + i) as f64).sin() * 0.1)).collect();
    let q = DMatrix::identity(4, 4) * 0.01;
    let r = DMatrix::identity(3, 3) * 0.05;
    let setup = common::setup(&DVector::zeros(4), &(DMatrix::identity(4, 4) * 0.5), &q, &r, 2);
    for entry in registry::ESTIMATORS {
        // The nonlinear MHE allocates per update (its window problem), the constrained-zonotope
        // filters per step (their sets change size; their LPs are built per hull); every other
        // estimator runs on this linear model without allocating.
        let settings = match entry.settings {
            SettingsKind::NonlinearMovingHorizon | SettingsKind::ConstrainedZonotope => continue,
            SettingsKind::SetMembershipInputBox => Some(EstimatorSettings::SetMembershipInputBox(
                SetMembershipSettings::default(),
                InputBox { lower: DVector::from_element(2, -1.0), upper: DVector::from_element(2, 1.0) },
            )),
            SettingsKind::MovingHorizon => {
                Some(EstimatorSettings::MovingHorizon(Box::new(estimators::MheSettings::new(
                    (DVector::from_element(4, -0.5), DVector::from_element(4, 0.5)),
                    (DVector::from_element(3, -1.0), DVector::from_element(3, 1.0)),
                ))))
            }
            _ => None,
        };
        let mut est = entry.build(setup.clone(), settings).unwrap();
        // The fuzzy-adaptive filter's measurement carries the receiver status [N, RTK].
        let ys: Vec<DVector<f64>> = ys
            .iter()
            .map(|y| {
                let extra = [12.0, 3.0];
                DVector::from_iterator(
                    y.len() + entry.extra_measurements,
                    y.iter().copied().chain(extra.into_iter().take(entry.extra_measurements)),
                )
            })
            .collect();
        est.step(dyn_model, &u, &ys[0]).unwrap();
        let (_, n) = count(|| {
            for y in &ys {
                let e = est.step(dyn_model, &u, y).unwrap();
                assert_eq!(e.kind(), entry.kind);
            }
        });
        assert_eq!(n, 0, "{} through the registry allocated", entry.name);
    }
    // In-place noise setters: no allocation, and a rejected matrix changes nothing.
    let mut kf = KalmanFilter::new(common::setup(&DVector::zeros(4), &DMatrix::identity(4, 4), &q, &r, 2)).unwrap();
    let mut smf =
        SetMembershipFilter::new(common::setup(&DVector::zeros(4), &DMatrix::identity(4, 4), &q, &r, 2)).unwrap();
    let q2 = &q * 2.0;
    let r2 = DMatrix::identity(3, 3) * 0.07;
    let (ok, n) = count(|| kf.set_noise(&q2, &r2).is_ok() && smf.set_noise(&q2, &r2).is_ok());
    assert!(ok);
    assert_eq!(n, 0, "set_noise allocated");
    let bad = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    let before =
        (kf.clone().step(&model, &u, &ys[0]).unwrap().clone(), smf.clone().step(&model, &u, &ys[0]).unwrap().clone());
    let (rejected, n) = count(|| kf.set_noise(&q2, &bad).is_err() && smf.set_noise(&q2, &bad).is_err());
    assert!(rejected);
    assert_eq!(n, 0, "rejecting a noise matrix allocated");
    assert_eq!(kf.step(&model, &u, &ys[0]).unwrap(), &before.0, "a rejected R changed the Kalman filter");
    assert_eq!(smf.step(&model, &u, &ys[0]).unwrap().center, before.1.center);
}

#[test]
fn ekf_step_on_the_truck_does_not_allocate() {
    use models::DiscreteModel;
    use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams};
    let params = TruckParams::digest_preset();
    let model = TruckEkfModel::paper(params).unwrap();
    let v = 70.0 / 3.6;
    let mut ekf = estimators::ExtendedKalmanFilter::new(common::setup(
        &DVector::from_vec(vec![v, 0.0, 0.0]),
        &(DMatrix::identity(3, 3) * 0.01),
        &(DMatrix::identity(3, 3) * 1e-7),
        &(DMatrix::identity(3, 3) * 1e-3),
        model.dims().inputs,
    ))
    .unwrap();
    let u = TruckInput::free_rolling(0.01, v, params.rolling_radius).to_dvector();
    let y = DVector::from_vec(vec![v, 0.1, 0.01]);
    ekf.step(&model, &u, &y).unwrap();
    let (_, n) = count(|| {
        for _ in 0..100 {
            ekf.step(&model, &u, &y).unwrap();
        }
    });
    assert_eq!(n, 0, "EKF step on the truck allocated");
}

#[test]
fn inconsistent_steps_do_not_allocate_under_any_policy() {
    use estimators::InconsistencyPolicy;
    let a = common::reference_a();
    let b = DMatrix::from_fn(4, 2, |i, j| 0.01 * (i + 2 * j) as f64);
    let c = common::reference_c();
    let model = StepModel::new(&a, &b, &c);
    let u = DVector::from_vec(vec![0.2, -0.1]);
    let y = DVector::from_vec(vec![0.01, 0.0, -0.01]);
    let outlier = DVector::from_vec(vec![50.0, 0.0, 0.0]);
    for policy in [InconsistencyPolicy::Error, InconsistencyPolicy::FlagAndContinue, InconsistencyPolicy::Restart] {
        let mut f = SetMembershipFilter::new(common::setup(
            &DVector::zeros(4),
            &(DMatrix::identity(4, 4) * 0.5),
            &(DMatrix::identity(4, 4) * 0.01),
            &(DMatrix::identity(3, 3) * 0.05),
            2,
        ))
        .unwrap();
        f.set_inconsistency_policy(policy);
        f.step(&model, &u, &y).unwrap();
        let (r, n) = count(|| f.step(&model, &u, &outlier).map(|e| e.report.guaranteed));
        assert_eq!(n, 0, "{policy:?}: an inconsistent step allocated");
        assert_eq!(r.ok(), if policy == InconsistencyPolicy::Error { None } else { Some(false) }, "{policy:?}");
    }
}

#[test]
fn nonlinear_set_membership_steps_do_not_allocate() {
    use models::DiscreteModel;
    use vessel_dynamics::{DiscreteVessel, VesselParams};
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let mut smf = estimators::NonlinearSetMembershipFilter::new(common::setup(
        &DVector::zeros(6),
        &DMatrix::identity(6, 6),
        &(DMatrix::identity(6, 6) * 1e-2),
        &DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.1])),
        vessel.dims().inputs,
    ))
    .unwrap();
    let u = DVector::from_vec(vec![1e5, 0.0, 1e5]);
    let y = DVector::from_vec(vec![0.01, 0.0, 0.001]);
    smf.step(&vessel, &u, &y).unwrap();
    let (_, n) = count(|| {
        for _ in 0..20 {
            smf.step(&vessel, &u, &y).unwrap();
            smf.predict(&vessel, &u).unwrap();
            smf.update(&vessel, &y).unwrap();
        }
    });
    assert_eq!(n, 0, "smf-nl step on the vessel allocated");
}
