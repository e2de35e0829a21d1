//! One update of the moving-horizon estimators of the car paper on a full window (N = 6), side by
//! side: RMHE, RMHE-OP, RMHE-OF (coordinate rotation, λv = 10, active-set minimisation step), the
//! exact saddle solver, plain MHE, and RMHE with Clarabel's QP path as the minimisation step.
//! Each without the window's data check, and RMHE and plain MHE also with it (`-checked`: the
//! witness of the published window, the linear programme when the witness fails).
//! `cargo bench --bench mhe`. Each sample clones an estimator warmed on the digest's double lane
//! change (outside the timing) and times one `step`.
//!
//! Also the supply vessel's nonlinear MHE (N = 10, 66 unknowns) with the UKF and the EKF arrival
//! cost, beside one UKF step.

use estimators::{DataChecks, Setup};
use std::hint::black_box;

use car_dynamics::{CarModel, CarParams, NoiseBounds, double_lane_change_inputs};
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use estimators::Estimator;
use estimators::mhe::{BlockingPreset, InnerSolver, MheCost, MheSettings, MovingHorizonEstimator, WindowSolver};
use models::{LinearModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};

fn bench(c: &mut Criterion) {
    let model = CarModel::new(CarParams::digest_default()).unwrap().discretize(0.5).unwrap();
    let inputs = double_lane_change_inputs(0.5, 40).unwrap();
    let bounds = NoiseBounds::digest();
    let (wn, vn) = (bounds.process_noise().unwrap(), bounds.measurement_noise().unwrap());
    let mut rng = Xoshiro256StarStar::seed_from_u64(7);
    let mut x = DVector::from_row_slice(&car_dynamics::DIGEST_INITIAL_STATE);
    let mut ys = Vec::new();
    for u in &inputs {
        x = model.a() * &x + model.b() * u + wn.sample(&mut rng);
        ys.push(model.c() * &x + vn.sample(&mut rng));
    }
    let w = bounds.process_vector();
    let setup = Setup {
        x0: DVector::from_row_slice(&car_dynamics::DIGEST_INITIAL_STATE),
        p0: DMatrix::identity(4, 4) * 0.01,
        process_noise: DMatrix::identity(4, 4) * 9e-4,
        measurement_noise: DMatrix::from_element(1, 1, 0.1),
        inputs: 1,
    };
    let base = MheSettings::new(
        (DVector::from_fn(4, |i, _| -w[i]), DVector::from_fn(4, |i, _| w[i])),
        (DVector::from_element(1, -1.0), DVector::from_element(1, 1.0)),
    );
    let cr = |inner| WindowSolver::CoordinateRotation { max_sweeps: 10, tolerance: 1e-8, inner };
    let (off, on) = (DataChecks::OFF, DataChecks::default());
    let min_max = MheCost::MinMax { lambda_v: 10.0 };
    let cases = [
        ("rmhe", BlockingPreset::Rmhe, min_max, cr(InnerSolver::ActiveSet), off),
        ("rmhe-op", BlockingPreset::RmheOp, min_max, cr(InnerSolver::ActiveSet), off),
        ("rmhe-of", BlockingPreset::RmheOf, min_max, cr(InnerSolver::ActiveSet), off),
        ("exact-saddle", BlockingPreset::Rmhe, min_max, WindowSolver::exact_saddle(), off),
        ("plain-mhe", BlockingPreset::Rmhe, MheCost::LeastSquares, WindowSolver::exact_saddle(), off),
        ("rmhe-clarabel-inner", BlockingPreset::Rmhe, min_max, cr(InnerSolver::Clarabel), off),
        ("rmhe-checked", BlockingPreset::Rmhe, min_max, cr(InnerSolver::ActiveSet), on),
        ("plain-mhe-checked", BlockingPreset::Rmhe, MheCost::LeastSquares, WindowSolver::exact_saddle(), on),
    ];
    let mut group = c.benchmark_group("mhe_update");
    for (name, preset, cost, solver, checks) in cases {
        let mut s = base.clone().with_preset(6, preset).unwrap();
        s.cost = cost;
        s.solver = solver;
        let mut warm = MovingHorizonEstimator::new(setup.clone(), s).unwrap();
        warm.set_data_checks(checks).unwrap();
        // Warm up to k = 20 (a full window in the middle of the manoeuvre).
        for k in 0..20 {
            warm.step(&model, &inputs[k], &ys[k]).unwrap();
        }
        group.bench_function(name, |b| {
            b.iter_batched(
                || warm.clone(),
                |mut e| {
                    black_box(e.step(&model, &inputs[20], &ys[20]).unwrap().center[0]);
                    e
                },
                BatchSize::SmallInput,
            );
        });
    }
    group.finish();
}

/// The supply vessel's nonlinear MHE (N = 10, 66 unknowns, UKF arrival cost with the paper's
/// α, β, κ; Gauss–Newton on the block-tridiagonal window) and, for scale, one UKF step, on data
/// simulated from the Euler model with force noise.
fn vessel(c: &mut Criterion) {
    use estimators::mhe::{NonlinearArrival, NonlinearMhe, NonlinearMheSettings};
    use estimators::{UkfParams, UnscentedKalmanFilter};
    use models::DiscreteModel;
    use vessel_dynamics::{DiscreteVessel, VesselParams};
    let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(3);
    let mut x = DVector::zeros(6);
    let mut next = DVector::zeros(6);
    let mut z = DVector::zeros(3);
    let (mut us, mut ys) = (Vec::new(), Vec::new());
    for k in 0..40 {
        let u = DVector::from_vec(vec![2e5 * (0.05 * k as f64).sin(), 5e4, 1e6 * (0.03 * k as f64).cos()]);
        let noisy = &u
            + DVector::from_vec(vec![
                2e4 * rng.standard_normal(),
                6e3 * rng.standard_normal(),
                1.5e5 * rng.standard_normal(),
            ]);
        model.f(&x, &noisy, &mut next).unwrap();
        x.copy_from(&next);
        model.h(&x, &u, &mut z).unwrap();
        ys.push(
            &z + DVector::from_vec(vec![rng.standard_normal(), rng.standard_normal(), 0.3 * rng.standard_normal()]),
        );
        us.push(u);
    }
    let x0 = DVector::zeros(6);
    let p0 = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.1, 0.1, 0.1, 0.01]));
    let q = DMatrix::identity(6, 6) * 1e-2;
    let r = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.1]));
    let mut group = c.benchmark_group("vessel_mhe");
    // The default stopping rule (the estimate within 1e-9 of the converged one by the observed
    // contraction), and iterating to the 1e-10 step tolerance, side by side.
    let paper = NonlinearMheSettings::paper().estimate_tolerance;
    // Then real-time iterations: one and two Gauss–Newton iterations per update.
    for (name, arrival, estimate_tolerance, real_time_iterations) in [
        ("mhe-ukf-arrival", NonlinearArrival::Ukf(UkfParams::paper()), paper, None),
        ("mhe-ukf-arrival-full", NonlinearArrival::Ukf(UkfParams::paper()), None, None),
        ("mhe-ekf-arrival", NonlinearArrival::Ekf, paper, None),
        ("mhe-ukf-arrival-rti-1", NonlinearArrival::Ukf(UkfParams::paper()), paper, Some(1)),
        ("mhe-ukf-arrival-rti-2", NonlinearArrival::Ukf(UkfParams::paper()), paper, Some(2)),
    ] {
        let mut s = NonlinearMheSettings::paper();
        s.arrival = arrival;
        s.estimate_tolerance = estimate_tolerance;
        s.real_time_iterations = real_time_iterations;
        let setup =
            Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q.clone(), measurement_noise: r.clone(), inputs: 3 };
        let mut warm = NonlinearMhe::new(setup, s).unwrap();
        for k in 0..20 {
            warm.step(&model, &us[k], &ys[k]).unwrap();
        }
        let mut probe = warm.clone();
        let report = probe.step(&model, &us[20], &ys[20]).unwrap().report.unwrap();
        eprintln!(
            "{name}: {} Gauss–Newton iterations, {} unknowns, status {:?}",
            report.iterations, report.unknowns, report.status
        );
        group.bench_function(name, |b| {
            b.iter_batched(
                || warm.clone(),
                |mut e| {
                    black_box(e.step(&model, &us[20], &ys[20]).unwrap().center[0]);
                    e
                },
                BatchSize::SmallInput,
            );
        });
    }
    let mut ukf = UnscentedKalmanFilter::new(
        Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q.clone(), measurement_noise: r.clone(), inputs: 3 },
        UkfParams::paper(),
    )
    .unwrap();
    for k in 0..20 {
        ukf.step(&model, &us[k], &ys[k]).unwrap();
    }
    group.bench_function("ukf-step", |b| {
        b.iter_batched(
            || ukf.clone(),
            |mut e| {
                black_box(e.step(&model, &us[20], &ys[20]).unwrap().center[0]);
                e
            },
            BatchSize::SmallInput,
        );
    });
    group.finish();
}

criterion_group!(benches, bench, vessel);
criterion_main!(benches);
