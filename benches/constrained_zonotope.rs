//! One step of the constrained-zonotope filters: `czf-nl` on CORA's six-tank benchmark (6 states,
//! 3 measured, 2·6 verified LPs per step) at the order the benchmark chose (2, no constraints kept:
//! the six-tank model file's `[estimator.czf-nl]` table) and at the default (20, 8 constraints),
//! and `czf` on the straddle carrier (4 states, 3 measured, T_s = 1 ms) at its chosen order (1, no
//! constraints: a box between steps, docs/constrained-zonotopes.md (C6)) and at order 8 with 6
//! constraints, beside the ellipsoidal `smf` step of the same size, measured side by side.
//! `cargo bench --bench constrained_zonotope`.

use std::hint::black_box;

use carrier_dynamics::{CarrierModel, CarrierParams};
use criterion::{Criterion, criterion_group, criterion_main};
use equation_models::EquationModel;
use estimators::{ConstrainedZonotopeFilter, ConstrainedZonotopeSettings, SetMembershipFilter, Setup, StepModel};
use models::{DiscreteModel, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};

/// `steps` of a run with every noise on a vertex of its box.
fn boundary_run<M: DiscreteModel>(
    model: &M,
    x0: &DVector<f64>,
    u: &dyn Fn(usize) -> DVector<f64>,
    (w, v): (f64, f64),
    steps: usize,
) -> Vec<(DVector<f64>, DVector<f64>)> {
    let d = model.dims();
    let mut rng = Xoshiro256StarStar::seed_from_u64(1);
    let mut sign = move || if rng.uniform(-1.0, 1.0) < 0.0 { -1.0 } else { 1.0 };
    let (mut x, mut next, mut y) = (x0.clone(), DVector::zeros(d.states), DVector::zeros(d.outputs));
    (0..steps)
        .map(|k| {
            let uk = u(k);
            model.f(&x, &uk, &mut next).unwrap();
            x = &next + DVector::from_fn(d.states, |_, _| w * sign());
            model.h(&x, &uk, &mut y).unwrap();
            (uk, &y + DVector::from_fn(d.outputs, |_, _| v * sign()))
        })
        .collect()
}

fn six_tank(crit: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/six-tank/model.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let model = EquationModel::from_toml_str_with_foreign_keys(&text, path, &port_est::model::NOISE_KEYS).unwrap();
    let setup = Setup {
        x0: DVector::from_element(6, 20.0),
        p0: DMatrix::identity(6, 6) * 4.0,
        process_noise: DMatrix::identity(6, 6) * 0.001,
        measurement_noise: DMatrix::identity(3, 3) * 0.2,
        inputs: 3,
    };
    let x0 = DVector::from_element(6, 21.0);
    let run =
        boundary_run(&model, &x0, &|k| DVector::from_element(3, 0.1 + 0.0025 * (k % 20) as f64), (0.001, 0.2), 60);
    let mut group = crit.benchmark_group("czf-nl six-tank step");
    for (name, order, max_constraints) in [("order 2, 0 constraints", 2, 0), ("order 20, 8 constraints", 20, 8)] {
        let settings = ConstrainedZonotopeSettings { order, max_constraints, ..Default::default() };
        let f0 = ConstrainedZonotopeFilter::new(setup.clone(), settings).unwrap();
        // Steps 20..60 of the run, after the set has reached its reduced size.
        let mut warm = f0.clone();
        for (u, y) in &run[..20] {
            warm.step(&model, u, y).unwrap();
        }
        let mut f = warm.clone();
        let mut i = 20;
        group.bench_function(name, |b| {
            b.iter(|| {
                if i == run.len() {
                    (f, i) = (warm.clone(), 20);
                }
                i += 1;
                black_box(f.step(&model, &run[i - 1].0, &run[i - 1].1).unwrap().lower()[0])
            })
        });
    }
    group.finish();
}

fn carrier(crit: &mut Criterion) {
    let d = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap();
    let (a, b, _) = d.to_dynamic();
    let c = DMatrix::from_fn(3, 4, |i, j| if j == 1 + i { 1.0 } else { 0.0 });
    let model = models::ConstantModel::new(a.clone(), b.clone(), c.clone()).unwrap();
    let (w, v) = (1e-3, 4e-3);
    let run = boundary_run(&model, &DVector::zeros(4), &|_| DVector::from_element(8, 0.01), (w, v), 400);
    let boxes = Setup {
        x0: DVector::zeros(4),
        p0: DMatrix::identity(4, 4) * 0.1,
        process_noise: DMatrix::identity(4, 4) * w,
        measurement_noise: DMatrix::identity(3, 3) * v,
        inputs: 8,
    };
    // The ellipsoid filter on the least-trace ellipsoids around the same boxes (d·h²).
    let ellipsoids = Setup {
        x0: DVector::zeros(4),
        p0: DMatrix::identity(4, 4) * (4.0 * 0.01),
        process_noise: DMatrix::identity(4, 4) * (4.0 * w * w),
        measurement_noise: DMatrix::identity(3, 3) * (3.0 * v * v),
        inputs: 8,
    };
    let step_model = StepModel::new(&a, &b, &c);
    let mut group = crit.benchmark_group("carrier_step");
    for (name, order, max_constraints) in
        [("czf order 1 (box between steps)", 1, 0), ("czf order 8, 6 constraints", 8, 6)]
    {
        let settings = ConstrainedZonotopeSettings { order, max_constraints, ..Default::default() };
        let czf0 = ConstrainedZonotopeFilter::new(boxes.clone(), settings).unwrap();
        let (mut czf, mut i) = (czf0.clone(), 0);
        group.bench_function(name, |bch| {
            bch.iter(|| {
                if i == run.len() {
                    (czf, i) = (czf0.clone(), 0);
                }
                i += 1;
                black_box(czf.step(&step_model, &run[i - 1].0, &run[i - 1].1).unwrap().lower()[0])
            })
        });
    }
    let smf0 = SetMembershipFilter::new(ellipsoids).unwrap();
    let (mut smf, mut j) = (smf0.clone(), 0);
    group.bench_function("smf", |bch| {
        bch.iter(|| {
            if j == run.len() {
                (smf, j) = (smf0.clone(), 0);
            }
            j += 1;
            black_box(smf.step(&step_model, &run[j - 1].0, &run[j - 1].1).unwrap().center[0])
        })
    });
    group.finish();
}

criterion_group!(benches, six_tank, carrier);
criterion_main!(benches);
