//! One filter step, side by side: the Kalman filter, the improved set-membership filter with the
//! exact two-multiplier solver, and with each SDP backend compiled in, for (n, m) = (4, 3) (no
//! sideslip sensor) and (4, 4) (the paper's C = I), on the Table 1 carrier at 6 m/s, T_s = 1 ms.
//! `faer-ipm` is timed cold (`smf-faer-ipm`) and warm-started from the previous step (`smf-faer-ipm-warm`).
//! `cargo bench --bench estimators` (add `--features clarabel` for Clarabel).
//!
//! Also the truck paper's EKF step (3 states, 6 tyre positions, 7 inputs, 3 measurements) beside a
//! Kalman step of the same size, and the truck model's evaluations alone (f, ∂f/∂x, h, ∂h/∂x: the
//! tyre forces and their derivatives), so that the EKF's time splits into tyre evaluations and
//! linear algebra.
//!
//! And the supply vessel's UKF step (paper's α, β, κ; 6 states, Euler at 0.1 s) beside its EKF
//! step, and one NSAMPC control law.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use estimators::{KalmanFilter, SdpUpdateSolver, SetMembershipFilter, StepModel};
use lmi::SolverSettings;
use nalgebra::{DMatrix, DVector};

mod common;
#[path = "../crates/estimators/tests/common/system.rs"]
mod system;

use system::LinearSystem;

/// The carrier, a constant input and the measurements of a long simulated run.
struct Case {
    sys: LinearSystem,
    ys: Vec<DVector<f64>>,
    u: DVector<f64>,
}

/// The carrier with its last `m` states measured and a long simulated run with noise on the
/// boundary of its sets (consistent with the bounds, as real data are); the benchmark cycles
/// through it and restarts the filter at each wrap.
fn case(m: usize) -> Case {
    let sys = system::carrier(m);
    let u = DVector::from_element(8, 0.01);
    let ys = system::boundary_measurements(&sys, &u, RUN, 1);
    Case { sys, ys, u }
}

/// Steps of the simulated run the benchmarks cycle through.
const RUN: usize = 200_000;

/// The next index of the cycle; `true` when it wrapped (the caller restarts its filter).
fn advance(k: &mut usize, len: usize) -> bool {
    *k = (*k + 1) % len;
    *k == 0
}

fn steps(crit: &mut Criterion) {
    let mut group = crit.benchmark_group("filter_step");
    for m in [3, 4] {
        let cs = case(m);
        let model = cs.sys.model();
        let label = format!("n4m{m}");

        let kf0 = KalmanFilter::new(cs.sys.setup()).unwrap();
        let mut kf = kf0.clone();
        let mut k = 0;
        group.bench_function(BenchmarkId::new("kalman", &label), |b| {
            b.iter(|| {
                if advance(&mut k, cs.ys.len()) {
                    kf = kf0.clone();
                }
                black_box(kf.step(&model, &cs.u, &cs.ys[k]).unwrap().center[0])
            })
        });

        let smf0 = SetMembershipFilter::new(cs.sys.setup()).unwrap();
        let mut smf = smf0.clone();
        k = 0;
        group.bench_function(BenchmarkId::new("smf-two-multiplier", &label), |b| {
            b.iter(|| {
                if advance(&mut k, cs.ys.len()) {
                    smf = smf0.clone();
                }
                black_box(smf.step(&model, &cs.u, &cs.ys[k]).unwrap().center[0])
            })
        });

        // Each backend cold (`smf-NAME`) and warm-started from the previous step's solution
        // (`smf-NAME-warm`, the default of filters built through `LinearSetup`; Clarabel cannot
        // warm start and solves cold either way, so only faer-ipm gets the second line).
        let names = lmi::backend_names();
        let variants = names
            .iter()
            .flat_map(|&name| [(name, false), (name, true)])
            .filter(|&(name, warm)| !warm || name == "faer-ipm");
        for (name, warm_start) in variants {
            let settings = SolverSettings { warm_start, ..SolverSettings::default() };
            let solver = SdpUpdateSolver::by_name(name, settings).unwrap();
            let mut f = SetMembershipFilter::with_solver(cs.sys.setup(), solver).unwrap();
            k = 0;
            let id = if warm_start { format!("smf-{name}-warm") } else { format!("smf-{name}") };
            // An SDP step takes 0.1–0.5 ms: the run never wraps within a benchmark.
            group.bench_function(BenchmarkId::new(id, &label), |b| {
                b.iter(|| {
                    k = (k + 1) % cs.ys.len();
                    black_box(f.step(&model, &cs.u, &cs.ys[k]).unwrap().center[0])
                })
            });
        }
    }
    group.finish();
}

fn truck(crit: &mut Criterion) {
    use estimators::ExtendedKalmanFilter;
    use models::{DifferentiableModel, DiscreteModel};
    let (model, common::Cycle { setup, inputs, .. }) = common::truck();
    let (x0, v) = (setup.x0.clone(), setup.x0[0]);
    let ys: Vec<DVector<f64>> =
        (0..64).map(|k| DVector::from_vec(vec![v + 0.01 * (k % 5) as f64, 0.3, 0.02])).collect();
    let mut group = crit.benchmark_group("truck_step");
    let mut ekf = ExtendedKalmanFilter::new(setup.clone()).unwrap();
    let mut k = 0;
    group.bench_function("ekf", |b| {
        b.iter(|| {
            k = (k + 1) % ys.len();
            black_box(ekf.step(&model, &inputs[k], &ys[k]).unwrap().center[0])
        })
    });
    // The tyre part: the four model evaluations one EKF step makes.
    let (mut f, mut fj, mut h, mut hj) =
        (DVector::zeros(3), DMatrix::zeros(3, 3), DVector::zeros(3), DMatrix::zeros(3, 3));
    group.bench_function("model-evaluations", |b| {
        b.iter(|| {
            k = (k + 1) % ys.len();
            let u = &inputs[k];
            model.f(&x0, u, &mut f).unwrap();
            model.f_jacobian(&x0, u, &mut fj).unwrap();
            model.h(&f, u, &mut h).unwrap();
            model.h_jacobian(&f, u, &mut hj).unwrap();
            black_box(h[1] + hj[(1, 1)])
        })
    });
    // A linear Kalman step of the same size (3 states, 7 inputs, 3 outputs).
    let a = DMatrix::identity(3, 3) * 0.999;
    let bm = DMatrix::from_element(3, 7, 1e-4);
    let c = DMatrix::identity(3, 3);
    let mut kf = KalmanFilter::new(setup).unwrap();
    // The synthetic measurements are not those of this linear model: without the innovation gate
    // (it would reject them), the step times the linear algebra only.
    kf.set_data_checks(estimators::DataChecks::OFF).unwrap();
    let lin = StepModel::new(&a, &bm, &c);
    group.bench_function("kalman-same-size", |b| {
        b.iter(|| {
            k = (k + 1) % ys.len();
            black_box(kf.step(&lin, &inputs[k], &ys[k]).unwrap().center[0])
        })
    });
    group.finish();
}

/// The supply vessel (dp-vessel note): one UKF step with the paper's `α, β, κ` (6 states, 13 sigma
/// points, Euler model at 0.1 s), the EKF step on the same model, and one NSAMPC control law.
fn vessel(crit: &mut Criterion) {
    use estimators::{ExtendedKalmanFilter, UkfParams, UnscentedKalmanFilter};
    use vessel_control::{Nsampc, NsampcParams, ReferenceSample};
    use vessel_dynamics::VesselParams;
    let (model, common::Cycle { setup, inputs, ys }) = common::vessel();
    let mut group = crit.benchmark_group("vessel_step");
    let mut ukf = UnscentedKalmanFilter::new(setup.clone(), UkfParams::paper()).unwrap();
    let mut k = 0;
    group.bench_function("ukf", |b| {
        b.iter(|| {
            k = (k + 1) % ys.len();
            if k == 0 {
                ukf = UnscentedKalmanFilter::new(setup.clone(), UkfParams::paper()).unwrap();
            }
            black_box(ukf.step(&model, &inputs[k], &ys[k]).unwrap().center[0])
        })
    });
    let mut ekf = ExtendedKalmanFilter::new(setup.clone()).unwrap();
    group.bench_function("ekf", |b| {
        b.iter(|| {
            k = (k + 1) % ys.len();
            if k == 0 {
                ekf = ExtendedKalmanFilter::new(setup.clone()).unwrap();
            }
            black_box(ekf.step(&model, &inputs[k], &ys[k]).unwrap().center[0])
        })
    });
    let ctrl = Nsampc::new(&VesselParams::paper(), NsampcParams::paper()).unwrap();
    let reference = ReferenceSample::hold(nalgebra::Vector3::new(50.0, 50.0, 0.0));
    let x = [10.0, 20.0, 0.1, 0.3, 0.1, 0.01];
    group.bench_function("nsampc-control", |b| {
        b.iter(|| black_box(ctrl.control(black_box(&x), &reference).unwrap().tau[0]))
    });
    group.finish();
}

criterion_group!(benches, steps, truck, vessel);
criterion_main!(benches);
