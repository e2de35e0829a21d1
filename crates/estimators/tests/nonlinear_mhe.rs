//! The nonlinear moving-horizon estimator (vessel paper (21)–(23)) against independent
//! references: the Kalman filter (full information on a linear model), the linear MHE of the car
//! paper (same arrival recursion on a linear model, after the window fills), UKF = EKF arrival on
//! a linear model, the optimality conditions of the window problem by central differences of an
//! independently written cost on a nonlinear model, bad input, and no allocation.

mod common;

use counting_allocator::{Counting, count};

use estimators::mhe::{
    ArrivalRecursion, MheCost, MheSettings, MovingHorizonEstimator, NonlinearArrival, NonlinearMhe,
    NonlinearMheSettings, PriorMean, WindowSolver, WindowStatus,
};
use estimators::ukf::UkfParams;
use estimators::{Estimator, EstimatorError, KalmanFilter};
use models::{DifferentiableModel, Dims, DiscreteModel, ModelError};
use nalgebra::{DMatrix, DVector};

#[global_allocator]
static GLOBAL: Counting = Counting;

fn linear() -> models::ConstantModel {
    let a = DMatrix::from_row_slice(3, 3, &[1.0, 0.1, 0.0, -0.05, 0.95, 0.1, 0.0, 0.0, 0.9]);
    let b = DMatrix::from_column_slice(3, 1, &[0.0, 0.1, 0.05]);
    let c = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    models::ConstantModel::new(a, b, c).unwrap()
}

fn data(model: &dyn DiscreteModel, steps: usize, seed: u64) -> (Vec<DVector<f64>>, Vec<DVector<f64>>) {
    let mut rng = models::Xoshiro256StarStar::seed_from_u64(seed);
    let d = model.dims();
    let mut x = DVector::from_element(d.states, 0.2);
    let (mut us, mut ys) = (Vec::new(), Vec::new());
    let mut out = DVector::zeros(d.states);
    let mut z = DVector::zeros(d.outputs);
    for k in 0..steps {
        let u = DVector::from_element(d.inputs, (0.2 * k as f64).sin());
        model.f(&x, &u, &mut out).unwrap();
        x = &out + DVector::from_fn(d.states, |_, _| 0.05 * rng.uniform(-1.0, 1.0));
        model.h(&x, &u, &mut z).unwrap();
        ys.push(&z + DVector::from_fn(d.outputs, |_, _| 0.1 * rng.uniform(-1.0, 1.0)));
        us.push(u);
    }
    (us, ys)
}

type Case = common::Case<NonlinearMheSettings>;

fn new_mhe(case: Case, inputs: usize) -> Result<NonlinearMhe, EstimatorError> {
    NonlinearMhe::new(case.setup(inputs), case.settings)
}

fn settings(n: usize, m: usize, horizon: usize, arrival: NonlinearArrival) -> Case {
    let mut s = NonlinearMheSettings::paper();
    s.horizon = horizon;
    s.arrival = arrival;
    Case {
        x0: DVector::zeros(n),
        p0: DMatrix::identity(n, n) * 0.5,
        q: DMatrix::identity(n, n) * 0.01,
        r: DMatrix::identity(m, m) * 0.04,
        settings: s,
    }
}

#[test]
fn full_information_on_a_linear_model_is_the_kalman_filter() {
    let model = linear();
    let s = settings(3, 2, 40, NonlinearArrival::Ekf);
    let mut kf = KalmanFilter::new(s.setup(1)).unwrap();
    let mut mhe = new_mhe(s, 1).unwrap();
    let (us, ys) = data(&model, 30, 1);
    for (u, y) in us.iter().zip(&ys) {
        let xk = kf.step(&model, u, y).unwrap().center.clone();
        let e = mhe.step(&model, u, y).unwrap();
        assert!((&e.center - &xk).amax() < 1e-8, "{} vs {xk}", e.center);
        assert_eq!(e.report.unwrap().status, WindowStatus::Converged);
    }
}

#[test]
fn on_a_linear_model_it_is_the_linear_mhe_with_the_same_arrival_recursion() {
    let model = linear();
    for arrival in [NonlinearArrival::Ekf, NonlinearArrival::Ukf(UkfParams::paper())] {
        let s = settings(3, 2, 5, arrival);
        let mut reference = MovingHorizonEstimator::new(s.setup(1), least_squares_window(5)).unwrap();
        let mut mhe = new_mhe(s, 1).unwrap();
        let (us, ys) = data(&model, 25, 2);
        for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
            let xr = reference.step(&model, u, y).unwrap().center.clone();
            let x = mhe.step(&model, u, y).unwrap().center.clone();
            assert!((&x - &xr).amax() < 1e-8, "{arrival:?} step {k}: {x} vs {xr}");
        }
    }
}

/// The linear MHE's window problem that is the nonlinear MHE's on a linear model: least squares,
/// no disturbance box, the Kalman arrival recursion about the smoothed estimate, solved exactly.
fn least_squares_window(horizon: usize) -> MheSettings {
    let mut lin = MheSettings::new(
        (DVector::repeat(3, f64::NEG_INFINITY), DVector::repeat(3, f64::INFINITY)),
        (DVector::repeat(2, -1.0), DVector::repeat(2, 1.0)),
    );
    lin.horizon = horizon;
    lin.blocks = vec![1; horizon];
    lin.cost = MheCost::LeastSquares;
    lin.arrival = ArrivalRecursion::Kalman;
    lin.prior_mean = PriorMean::Smoothed;
    lin.solver = WindowSolver::exact_saddle();
    lin
}

/// A pendulum-like nonlinear model: `θ' = ω`, `ω' = −sin θ + u`, Euler at 0.1 s, measured
/// `[sin θ, θ + ω²/10]`.
struct Pendulum;

impl DiscreteModel for Pendulum {
    fn dims(&self) -> Dims {
        Dims::new(2, 1, 2)
    }
    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = x[0] + 0.1 * x[1];
        out[1] = x[1] + 0.1 * (-x[0].sin() + u[0]);
        Ok(())
    }
    fn h(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = x[0].sin();
        out[1] = x[0] + x[1] * x[1] / 10.0;
        Ok(())
    }
}

impl DifferentiableModel for Pendulum {
    fn f_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        out[(0, 0)] = 1.0;
        out[(0, 1)] = 0.1;
        out[(1, 0)] = -0.1 * x[0].cos();
        out[(1, 1)] = 1.0;
        Ok(())
    }
    fn h_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        out[(0, 0)] = x[0].cos();
        out[(0, 1)] = 0.0;
        out[(1, 0)] = 1.0;
        out[(1, 1)] = x[1] / 5.0;
        Ok(())
    }
}

/// The window cost written independently of the estimator (full information, prior (x̄0, P0)).
fn window_cost(s: &Case, xs: &[DVector<f64>], us: &[DVector<f64>], ys: &[DVector<f64>]) -> f64 {
    let (p0i, qi, ri) =
        (s.p0.clone().try_inverse().unwrap(), s.q.clone().try_inverse().unwrap(), s.r.clone().try_inverse().unwrap());
    let m = Pendulum;
    let d0 = &xs[0] - &s.x0;
    let mut c = (d0.transpose() * &p0i * &d0)[0];
    let mut f = DVector::zeros(2);
    let mut h = DVector::zeros(2);
    for j in 0..xs.len() - 1 {
        m.f(&xs[j], &us[j], &mut f).unwrap();
        let d = &xs[j + 1] - &f;
        c += (d.transpose() * &qi * &d)[0];
        m.h(&xs[j + 1], &us[j], &mut h).unwrap();
        let e = &ys[j] - &h;
        c += (e.transpose() * &ri * &e)[0];
    }
    c
}

#[test]
fn the_window_solution_satisfies_the_optimality_conditions_on_a_nonlinear_model() {
    let s = settings(2, 2, 12, NonlinearArrival::Ukf(UkfParams { alpha: 1.0, beta: 2.0, kappa: 1.0 }));
    let mut mhe = new_mhe(s.clone(), 1).unwrap();
    let (us, ys) = data(&Pendulum, 10, 3);
    for t in 0..us.len() {
        mhe.step(&Pendulum, &us[t], &ys[t]).unwrap();
        let traj: Vec<DVector<f64>> = mhe.trajectory().to_vec();
        assert_eq!(traj.len(), t + 2);
        let base = window_cost(&s, &traj, &us[..=t], &ys[..=t]);
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        for j in 0..traj.len() {
            for i in 0..2 {
                let mut plus = traj.clone();
                plus[j][i] += h;
                let mut minus = traj.clone();
                minus[j][i] -= h;
                let grad = (window_cost(&s, &plus, &us[..=t], &ys[..=t])
                    - window_cost(&s, &minus, &us[..=t], &ys[..=t]))
                    / (2.0 * h);
                worst = worst.max(grad.abs());
            }
        }
        assert!(worst < 1e-5 * base.max(1.0), "T = {}: gradient {worst:e} at cost {base}", t + 1);
    }
}

#[test]
fn an_iteration_limit_is_an_outcome_and_bad_input_leaves_the_estimator_unchanged() {
    let mut s = settings(2, 2, 4, NonlinearArrival::Ukf(UkfParams { alpha: 1.0, beta: 2.0, kappa: 1.0 }));
    s.max_iterations = 1;
    s.x0 = DVector::from_vec(vec![2.5, -1.0]);
    let mut mhe = new_mhe(s, 1).unwrap();
    let (us, ys) = data(&Pendulum, 12, 4);
    let mut limited = 0;
    for (u, y) in us.iter().zip(&ys).take(10) {
        let e = mhe.step(&Pendulum, u, y).unwrap();
        limited += usize::from(e.report.unwrap().status == WindowStatus::NotConverged);
        assert!(e.center.iter().all(|v| v.is_finite()));
    }
    assert!(limited > 0);
    let before = mhe.clone();
    assert!(matches!(
        mhe.step(&Pendulum, &us[10], &DVector::from_element(2, f64::NAN)),
        Err(EstimatorError::NonFinite { .. })
    ));
    assert!(mhe.step(&Pendulum, &DVector::zeros(3), &ys[10]).is_err());
    assert!(mhe.step(&linear(), &us[10], &ys[10]).is_err());
    assert_eq!(mhe.time(), before.time());
    let mut twin = before;
    let a = mhe.step(&Pendulum, &us[10], &ys[10]).unwrap().center.clone();
    let b = twin.step(&Pendulum, &us[10], &ys[10]).unwrap().center.clone();
    assert_eq!(a, b);
    // Settings.
    let mut bad = settings(2, 2, 0, NonlinearArrival::Fixed);
    assert!(matches!(new_mhe(bad.clone(), 1), Err(EstimatorError::InvalidConfiguration { .. })));
    bad.horizon = 3;
    bad.q[(0, 0)] = -1.0;
    assert!(new_mhe(bad, 1).is_err());
}

#[test]
fn updates_do_not_allocate() {
    let model = linear();
    let (us, ys) = data(&model, 30, 5);
    for arrival in [NonlinearArrival::Ekf, NonlinearArrival::Ukf(UkfParams::paper()), NonlinearArrival::Fixed] {
        let mut mhe = new_mhe(settings(3, 2, 10, arrival), 1).unwrap();
        let (_, allocations) = count(|| {
            for k in 0..30 {
                if k % 5 == 2 {
                    mhe.predict(&model, &us[k]).unwrap();
                } else {
                    mhe.step(&model, &us[k], &ys[k]).unwrap();
                }
            }
        });
        assert_eq!(allocations, 0, "{arrival:?}");
    }
}

/// The memory estimate bounds what the estimator requests: at construction, and over one
/// update (with the boxes' QP, which allocates per update), for short and long horizons.
#[test]
fn the_memory_estimate_bounds_what_construction_and_an_update_request() {
    let model = linear();
    let (us, ys) = data(&model, 12, 6);
    for horizon in [1, 10, 200] {
        for boxed in [false, true] {
            let mut case = settings(3, 2, horizon, NonlinearArrival::Ukf(UkfParams::paper()));
            if boxed {
                case.settings.w_box = Some((DVector::repeat(3, -1.0), DVector::repeat(3, 1.0)));
                case.settings.v_box = Some((DVector::repeat(2, -1.0), DVector::repeat(2, 1.0)));
            }
            let estimate = case.settings.memory_estimate(3, 2, 1).unwrap();
            let (mhe, built) = counting_allocator::measure(|| new_mhe(case, 1));
            let mut mhe = mhe.unwrap();
            assert!(built.bytes as u128 <= estimate, "N = {horizon}: {} > {estimate}", built.bytes);
            for k in 0..12 {
                let (r, update) = counting_allocator::measure(|| mhe.step(&model, &us[k], &ys[k]).map(|_| ()));
                r.unwrap();
                assert!(update.bytes as u128 <= estimate, "N = {horizon} update: {} > {estimate}", update.bytes);
            }
            // Without boxes the estimate is not far above: within 16× at the long horizon.
            if horizon == 200 && !boxed {
                assert!(estimate <= 16 * built.bytes as u128, "{estimate} vs {}", built.bytes);
            }
        }
    }
    // A horizon no machine holds is reported, not overflowed.
    let mut huge = NonlinearMheSettings::paper();
    huge.horizon = usize::MAX;
    assert!(huge.memory_estimate(1 << 40, 1 << 40, 1).is_none());
}

#[test]
fn with_the_arrival_filters_own_mean_and_the_ekf_arrival_it_is_the_kalman_filter_on_a_linear_model() {
    let model = linear();
    let mut s = settings(3, 2, 4, NonlinearArrival::Ekf);
    s.prior = estimators::mhe::NonlinearPrior::ArrivalFilter;
    let mut kf = KalmanFilter::new(s.setup(1)).unwrap();
    let mut mhe = new_mhe(s.clone(), 1).unwrap();
    s.arrival = NonlinearArrival::Ukf(UkfParams::paper());
    let mut mhe_ukf = new_mhe(s, 1).unwrap();
    let (us, ys) = data(&model, 30, 6);
    for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
        let xk = kf.step(&model, u, y).unwrap().center.clone();
        let x = mhe.step(&model, u, y).unwrap().center.clone();
        let xu = mhe_ukf.step(&model, u, y).unwrap().center.clone();
        assert!((&x - &xk).amax() < 1e-8, "step {k}: {x} vs {xk}");
        assert!((&xu - &xk).amax() < 1e-8, "UKF arrival, step {k}: {xu} vs {xk}");
    }
}

#[test]
fn boxes_on_the_disturbances_give_the_linear_mhes_box_constrained_solution() {
    // Full information on a linear model: the same convex QP, solved by the linear MHE's active
    // set on the condensed problem and by Clarabel on the states here.
    let model = linear();
    let w = 0.01;
    let mut s = settings(3, 2, 30, NonlinearArrival::Ekf);
    s.w_box = Some((DVector::repeat(3, -w), DVector::repeat(3, w)));
    let mut wide = s.clone();
    wide.w_box = Some((DVector::repeat(3, -1e3), DVector::repeat(3, 1e3)));
    wide.v_box = Some((DVector::repeat(2, -1e3), DVector::repeat(2, 1e3)));
    let mut lin = MheSettings::new(
        (DVector::repeat(3, -w), DVector::repeat(3, w)),
        (DVector::repeat(2, -1.0), DVector::repeat(2, 1.0)),
    );
    lin.horizon = 30;
    lin.blocks = vec![1; 30];
    lin.cost = MheCost::LeastSquares;
    lin.solver = WindowSolver::exact_saddle();
    let mut reference = MovingHorizonEstimator::new(s.setup(1), lin).unwrap();
    let mut boxed = new_mhe(s.clone(), 1).unwrap();
    let mut inactive = new_mhe(wide, 1).unwrap();
    let mut free = new_mhe(settings(3, 2, 30, NonlinearArrival::Ekf), 1).unwrap();
    let (us, ys) = data(&model, 12, 7);
    let mut active = 0;
    for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
        let xr = reference.step(&model, u, y).unwrap().center.clone();
        let xb = boxed.step(&model, u, y).unwrap().center.clone();
        let xi = inactive.step(&model, u, y).unwrap().center.clone();
        let xf = free.step(&model, u, y).unwrap().center.clone();
        assert!((&xb - &xr).amax() < 1e-6, "step {k}: {xb} vs {xr}");
        assert!((&xi - &xf).amax() < 1e-6, "inactive boxes change nothing, step {k}: {xi} vs {xf}");
        active += usize::from((&xf - &xb).amax() > 1e-4);
        // The estimated disturbances respect the box.
        let traj = boxed.trajectory();
        let mut f = DVector::zeros(3);
        for j in 0..traj.len() - 1 {
            model.f(&traj[j], &us[j], &mut f).unwrap();
            assert!((&traj[j + 1] - &f).amax() <= w + 1e-7, "ω beyond the box at j = {j}");
        }
    }
    assert!(active > 0, "the box never bound: the test does not exercise it");
}

#[test]
fn boxes_on_the_measurement_residuals_hold_at_the_solution_and_infeasibility_is_an_outcome() {
    let v = 0.08;
    let mut s = settings(2, 2, 6, NonlinearArrival::Ukf(UkfParams { alpha: 1.0, beta: 2.0, kappa: 1.0 }));
    s.v_box = Some((DVector::repeat(2, -v), DVector::repeat(2, v)));
    let mut mhe = new_mhe(s.clone(), 1).unwrap();
    let (us, ys) = data(&Pendulum, 15, 8);
    let mut h = DVector::zeros(2);
    for (u, y) in us.iter().zip(&ys) {
        let e = mhe.step(&Pendulum, u, y).unwrap();
        assert_eq!(e.report.unwrap().status, WindowStatus::Converged);
        // The last sample's residual (measured with input u) is inside the box.
        let x = e.center.clone();
        Pendulum.h(&x, u, &mut h).unwrap();
        assert!((y - &h).amax() <= v + 1e-6, "ν = {} beyond {v}", y - &h);
    }
    // Boxes that cannot hold together (no disturbance allowed, tiny residuals, noisy data).
    s.w_box = Some((DVector::repeat(2, -1e-9), DVector::repeat(2, 1e-9)));
    s.v_box = Some((DVector::repeat(2, -1e-6), DVector::repeat(2, 1e-6)));
    let mut tight = new_mhe(s, 1).unwrap();
    let mut infeasible = 0;
    for (u, y) in us.iter().zip(&ys) {
        let e = tight.step(&Pendulum, u, y).unwrap();
        assert!(e.center.iter().all(|v| v.is_finite()));
        infeasible += usize::from(e.report.unwrap().status == WindowStatus::Infeasible);
    }
    assert!(infeasible > 0);
    let mut bad = settings(2, 2, 6, NonlinearArrival::Fixed);
    bad.w_box = Some((DVector::repeat(2, 1.0), DVector::repeat(2, -1.0)));
    assert!(matches!(new_mhe(bad, 1), Err(EstimatorError::InvalidConfiguration { .. })));
}

/// A measurement of `x_0` before the first step: the one-sample window is the Kalman update of
/// the prior `(x̄₀, P₀)` with it (the prior term must be there, not zero).
#[test]
fn the_initial_measurement_is_weighed_against_the_prior() {
    use models::LinearModel;
    let model = linear();
    let mut s = settings(3, 2, 5, NonlinearArrival::Ekf);
    s.x0 = DVector::from_vec(vec![0.5, -0.2, 0.1]);
    let (c, p0, r) = (model.c().clone(), s.p0.clone(), s.r.clone());
    let x0 = s.x0.clone();
    let mut mhe = new_mhe(s, 1).unwrap();
    let y0 = DVector::from_vec(vec![0.3, 0.1]);
    let e = mhe.measure_initial(&model, &DVector::zeros(1), &y0).unwrap();
    let gain = &p0 * c.transpose() * (&c * &p0 * c.transpose() + &r).try_inverse().unwrap();
    let want = &x0 + gain * (&y0 - &c * &x0);
    assert!((&e.center - &want).amax() < 1e-9, "{} vs {want}", e.center);
}

/// Masks of the linear model's two outputs: both, the first, none, the second.
const MASKS: [[bool; 2]; 4] = [[true, true], [true, false], [false, false], [false, true]];

#[test]
fn partial_measurements_give_the_kalman_filters_partial_steps_on_a_linear_model() {
    // Full information (a horizon longer than the run) and, with the arrival filter's own mean,
    // a short window whose arrival updates are partial too: both are the Kalman filter with the
    // same partial steps (docs/partial-measurements.md), whose own partial steps match filterpy.
    let model = linear();
    let (us, mut ys) = data(&model, 30, 8);
    for (k, y) in ys.iter_mut().enumerate() {
        for (i, &m) in MASKS[k % 4].iter().enumerate() {
            if !m {
                y[i] = f64::NAN; // never read
            }
        }
    }
    let mut cases = vec![("full information", settings(3, 2, 40, NonlinearArrival::Ekf))];
    for arrival in [NonlinearArrival::Ekf, NonlinearArrival::Ukf(UkfParams::paper())] {
        let mut s = settings(3, 2, 4, arrival);
        s.settings.prior = estimators::mhe::NonlinearPrior::ArrivalFilter;
        cases.push(("short window, the arrival filter's mean", s));
    }
    for (what, case) in cases {
        let mut kf = KalmanFilter::new(case.setup(1)).unwrap();
        let mut mhe = new_mhe(case, 1).unwrap();
        for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
            let mask = MASKS[k % 4];
            let want = kf.step_partial(&model, u, y, &mask).unwrap().center.clone();
            let e = mhe.step_partial(&model, u, y, &mask).unwrap_or_else(|e| panic!("{what}, step {k}: {e}"));
            assert!((&e.center - &want).amax() < 1e-7, "{what}, step {k}: {} vs {want}", e.center);
        }
    }
}

#[test]
fn partial_steps_refuse_bad_data_unchanged_and_do_not_allocate() {
    let model = linear();
    let (us, ys) = data(&model, 30, 9);
    let mut mhe = new_mhe(settings(3, 2, 6, NonlinearArrival::Ukf(UkfParams::paper())), 1).unwrap();
    // (The first steps make the buffers of one measured output, in the window and, once it
    // slides, in the arrival filter.)
    for k in 0..16 {
        mhe.step_partial(&model, &us[k], &ys[k], &MASKS[k % 4]).unwrap();
    }
    let before = mhe.estimate().center.clone();
    let nan = DVector::from_vec(vec![f64::NAN, 0.0]);
    assert!(matches!(
        mhe.step_partial(&model, &us[16], &nan, &[true, false]),
        Err(EstimatorError::NonFinite { what: "y", index: 0 })
    ));
    assert!(matches!(
        mhe.step_partial(&model, &us[16], &ys[16], &[true]),
        Err(EstimatorError::DimensionMismatch { what: "measured", .. })
    ));
    assert_eq!(mhe.estimate().center, before);
    let (_, allocations) = count(|| {
        for k in 16..30 {
            mhe.step_partial(&model, &us[k], &ys[k], &MASKS[k % 4]).unwrap();
        }
    });
    assert_eq!(allocations, 0);
}

#[test]
fn the_linear_mhes_partial_steps_are_the_nonlinear_mhes_on_a_linear_model() {
    // The same window problem and arrival recursion (least squares, Kalman arrival), partial
    // samples inside the window and at its start: the two implementations agree, and the
    // nonlinear one is the Kalman filter's partial steps (above).
    let model = linear();
    let (us, ys) = data(&model, 30, 10);
    for arrival in [NonlinearArrival::Ekf, NonlinearArrival::Ukf(UkfParams::paper())] {
        let s = settings(3, 2, 5, arrival);
        let mut reference = MovingHorizonEstimator::new(s.setup(1), least_squares_window(5)).unwrap();
        let mut mhe = new_mhe(s, 1).unwrap();
        for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
            let mask = MASKS[k % 4];
            let xr = reference.step_partial(&model, u, y, &mask).unwrap().center.clone();
            let x = mhe.step_partial(&model, u, y, &mask).unwrap().center.clone();
            assert!((&x - &xr).amax() < 1e-8, "{arrival:?} step {k}: {x} vs {xr}");
        }
    }
    // The data check skips the unmeasured rows: a wild value there is not read.
    let mut s = MheSettings::new(
        (DVector::repeat(3, -0.2), DVector::repeat(3, 0.2)),
        (DVector::repeat(2, -1.0), DVector::repeat(2, 1.0)),
    );
    s.horizon = 5;
    s.blocks = vec![1; 5];
    let mut checked = MovingHorizonEstimator::new(settings(3, 2, 5, NonlinearArrival::Ekf).setup(1), s).unwrap();
    checked.set_data_checks(estimators::DataChecks::default()).unwrap();
    for (k, (u, y)) in us.iter().zip(&ys).enumerate() {
        let mut y = y.clone();
        y[1] = 1e6;
        let e = checked.step_partial(&model, u, &y, &[true, false]).unwrap_or_else(|e| panic!("step {k}: {e}"));
        assert_ne!(e.report.unwrap().data, estimators::DataCheck::Inconsistent, "step {k}");
    }
}
