//! One certified step of the nonlinear set-membership filter (`smf-nl`) on the truck (3 states,
//! 7 inputs, 3 measurements; Euler at 1 ms, mean-value remainder) beside the truck's EKF step and
//! the linear set-membership filter's step of the same size, and the enclosures alone (`f` and
//! `h` over a box with their Jacobians, as `smf-nl` evaluates them: at the centre and over the
//! box, twice each). `cargo bench --bench nonlinear_smf`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use estimators::{ExtendedKalmanFilter, NonlinearSetMembershipFilter, SetMembershipFilter, Setup, StepModel};
use models::{Interval, SecondOrderModel, TaylorEnclosure};
use nalgebra::{DMatrix, DVector};
use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams};

fn diag(v: [f64; 3]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_row_slice(&v))
}

fn truck(crit: &mut Criterion) {
    let params = TruckParams::digest_preset();
    let model = TruckEkfModel::paper(params).unwrap();
    let v = 70.0 / 3.6;
    let setup = Setup {
        x0: DVector::from_vec(vec![v, 0.05, 0.02]),
        p0: diag([1e-2, 1e-2, 1e-4]),
        process_noise: diag([1e-7, 1e-7, 1e-9]),
        measurement_noise: diag([2.5e-3, 2.5e-3, 4e-6]),
        inputs: 7,
    };
    let inputs: Vec<DVector<f64>> = (0..64)
        .map(|k| {
            let mut u = TruckInput::free_rolling(0.02 * ((k as f64) * 0.3).sin(), v, params.rolling_radius);
            u.omega[3] *= 1.002;
            u.to_dvector()
        })
        .collect();
    // Measurements of the model itself along the inputs (consistent data for the set filters).
    let mut ys = Vec::with_capacity(inputs.len());
    let mut x = setup.x0.clone();
    for u in &inputs {
        let mut next = DVector::zeros(3);
        models::DiscreteModel::f(&model, &x, u, &mut next).unwrap();
        x = next;
        let mut y = DVector::zeros(3);
        models::DiscreteModel::h(&model, &x, u, &mut y).unwrap();
        ys.push(y);
    }
    let mut group = crit.benchmark_group("truck_certified_step");
    // The filters restart from the initial set each lap of the 64 steps.
    let nl0 = NonlinearSetMembershipFilter::new(setup.clone()).unwrap();
    let mut nl = nl0.clone();
    // Step i of a filter takes measurement i; a filter restarts after the last one.
    let mut i = 0;
    group.bench_function("smf-nl", |b| {
        b.iter(|| {
            if i == ys.len() {
                (nl, i) = (nl0.clone(), 0);
            }
            i += 1;
            black_box(nl.step(&model, &inputs[i - 1], &ys[i - 1]).unwrap().center[0])
        })
    });
    let mut k = 0;
    let mut ekf = ExtendedKalmanFilter::new(setup.clone()).unwrap();
    group.bench_function("ekf", |b| {
        b.iter(|| {
            k = (k + 1) % ys.len();
            black_box(ekf.step(&model, &inputs[k], &ys[k]).unwrap().center[0])
        })
    });
    // The linear filter of the same size on the truck's linearisation at x̂0 (A = I + T J, C = H).
    let (mut a, mut c) = (DMatrix::zeros(3, 3), DMatrix::zeros(3, 3));
    models::DifferentiableModel::f_jacobian(&model, &setup.x0, &inputs[0], &mut a).unwrap();
    models::DifferentiableModel::h_jacobian(&model, &setup.x0, &inputs[0], &mut c).unwrap();
    let bm = DMatrix::zeros(3, 7);
    let lin = StepModel::new(&a, &bm, &c);
    let mut xl = setup.x0.clone();
    let lin_ys: Vec<DVector<f64>> = (0..ys.len())
        .map(|_| {
            xl = &a * &xl;
            &c * &xl
        })
        .collect();
    let smf0 = SetMembershipFilter::new(setup.clone()).unwrap();
    let mut smf = smf0.clone();
    let mut i = 0;
    group.bench_function("smf-linear-same-size", |b| {
        b.iter(|| {
            if i == lin_ys.len() {
                (smf, i) = (smf0.clone(), 0);
            }
            i += 1;
            black_box(smf.step(&lin, &inputs[i - 1], &lin_ys[i - 1]).unwrap().center[0])
        })
    });
    // The four enclosures one smf-nl step evaluates on the truck: f and h with their Jacobians over
    // a box, their values alone at the centre (the truck's Hessians do not hold: (N2')).
    let point: Vec<Interval> = setup.x0.iter().map(|x| Interval::point(*x)).collect();
    let boxed: Vec<Interval> = setup.x0.iter().zip([0.1, 0.1, 0.01]).map(|(x, r)| Interval::centered(*x, r)).collect();
    let mut e = TaylorEnclosure::new(3, 3);
    group.bench_function("enclosures-f-h-box-and-centre-values", |b| {
        b.iter(|| {
            k = (k + 1) % ys.len();
            let u = &inputs[k];
            model.f_value_enclosure(&point, u, &mut e).unwrap();
            model.f_enclosure(&boxed, u, &mut e).unwrap();
            model.h_value_enclosure(&point, u, &mut e).unwrap();
            model.h_enclosure(&boxed, u, &mut e).unwrap();
            black_box(e.value(1).hi())
        })
    });
    group.finish();
}

criterion_group!(benches, truck);
criterion_main!(benches);
