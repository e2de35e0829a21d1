//! One certified step of the nonlinear set-membership filter (`smf-nl`) on the truck (3 states,
//! 7 inputs, 3 measurements; Euler at 1 ms, mean-value remainder) beside the truck's EKF step and
//! the linear set-membership filter's step of the same size, and the enclosures alone (`f` and
//! `h` over a box with their Jacobians, as `smf-nl` evaluates them: at the centre and over the
//! box, twice each). `cargo bench --bench nonlinear_smf`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use estimators::{ExtendedKalmanFilter, NonlinearSetMembershipFilter, SetMembershipFilter, StepModel};
use models::{Interval, SecondOrderModel, TaylorEnclosure};
use nalgebra::{DMatrix, DVector};

mod common;

fn truck(crit: &mut Criterion) {
    // The model's own measurements along the inputs: consistent data for the set filters.
    let (model, common::Cycle { setup, inputs, ys }) = common::truck();
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
