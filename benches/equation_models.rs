//! Models written as equations (`equation-models`, `examples/models/*.toml`) against the
//! compiled vehicle crates they describe: one EKF step and one UKF step on the supply vessel, and
//! one EKF step on the Pac89 truck, with the same filter settings and data on both sides.
//! `cargo bench --bench equation_models`.

use std::hint::black_box;

use criterion::{BenchmarkGroup, Criterion, criterion_group, criterion_main, measurement::WallTime};
use equation_models::EquationModel;
use estimators::{ExtendedKalmanFilter, Setup, UkfParams, UnscentedKalmanFilter};
use models::{DifferentiableModel, DiscreteModel};
use nalgebra::{DMatrix, DVector};

/// A model file of `examples/models`, its `port-est` keys skipped.
fn load(name: &str) -> EquationModel {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/models").join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    EquationModel::from_toml_str_with_foreign_keys(&text, &path.display().to_string(), &port_est::model::NOISE_KEYS)
        .unwrap()
}

/// Filter settings and a cycle of inputs and measurements.
struct Data {
    setup: Setup,
    inputs: Vec<DVector<f64>>,
    ys: Vec<DVector<f64>>,
}

/// One EKF step on `model`, restarting the filter when the data cycle wraps.
fn ekf<M: DifferentiableModel + ?Sized>(group: &mut BenchmarkGroup<'_, WallTime>, name: &str, model: &M, d: &Data) {
    let mut ekf = ExtendedKalmanFilter::new(d.setup.clone()).unwrap();
    let mut k = 0;
    group.bench_function(name, |b| {
        b.iter(|| {
            k = (k + 1) % d.ys.len();
            if k == 0 {
                ekf = ExtendedKalmanFilter::new(d.setup.clone()).unwrap();
            }
            black_box(ekf.step(model, &d.inputs[k], &d.ys[k]).unwrap().center[0])
        })
    });
}

/// One UKF step (the paper's `α, β, κ`) on `model`.
fn ukf<M: DiscreteModel + ?Sized>(group: &mut BenchmarkGroup<'_, WallTime>, name: &str, model: &M, d: &Data) {
    let fresh = || UnscentedKalmanFilter::new(d.setup.clone(), UkfParams::paper()).unwrap();
    let mut ukf = fresh();
    let mut k = 0;
    group.bench_function(name, |b| {
        b.iter(|| {
            k = (k + 1) % d.ys.len();
            if k == 0 {
                ukf = fresh();
            }
            black_box(ukf.step(model, &d.inputs[k], &d.ys[k]).unwrap().center[0])
        })
    });
}

/// The supply vessel of `benches/estimators.rs`: 6 states, Euler at 0.1 s.
fn vessel(crit: &mut Criterion) {
    use vessel_dynamics::{DiscreteVessel, VesselParams};
    let compiled = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let equations = load("vessel.toml");
    let data = Data {
        setup: Setup {
            x0: DVector::zeros(6),
            p0: DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.1, 0.1, 0.1, 0.01])),
            process_noise: DMatrix::identity(6, 6) * 1e-2,
            measurement_noise: DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1.0, 0.1])),
            inputs: 3,
        },
        inputs: (0..64)
            .map(|k| DVector::from_vec(vec![1e5 * (k as f64 * 0.1).sin(), 3e4, 1e6 * (k as f64 * 0.2).cos()]))
            .collect(),
        ys: (0..64).map(|k| DVector::from_vec(vec![0.1 * k as f64, 0.05 * k as f64, 0.01 * (k % 7) as f64])).collect(),
    };
    let mut group = crit.benchmark_group("equations_vessel");
    ekf(&mut group, "ekf-compiled", &compiled, &data);
    ekf(&mut group, "ekf-equations", &equations, &data);
    ukf(&mut group, "ukf-compiled", &compiled, &data);
    ukf(&mut group, "ukf-equations", &equations, &data);
    group.finish();
}

/// The truck of `benches/estimators.rs`: 3 states, 7 inputs, six Pac89 wheels, Euler at 1 ms.
fn truck(crit: &mut Criterion) {
    use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams};
    let params = TruckParams::digest_preset();
    let compiled = TruckEkfModel::paper(params).unwrap();
    let equations = load("truck.toml");
    let v = 70.0 / 3.6;
    let data = Data {
        setup: Setup {
            x0: DVector::from_vec(vec![v, 0.05, 0.02]),
            p0: DMatrix::from_diagonal(&DVector::from_vec(vec![1e-2, 1e-2, 1e-4])),
            process_noise: DMatrix::from_diagonal(&DVector::from_vec(vec![1e-7, 1e-7, 1e-9])),
            measurement_noise: DMatrix::from_diagonal(&DVector::from_vec(vec![2.5e-3, 2.5e-3, 4e-6])),
            inputs: 7,
        },
        inputs: (0..64)
            .map(|k| {
                let mut u = TruckInput::free_rolling(0.02 * ((k as f64) * 0.3).sin(), v, params.rolling_radius);
                u.omega[3] *= 1.002;
                u.to_dvector()
            })
            .collect(),
        ys: (0..64).map(|k| DVector::from_vec(vec![v + 0.01 * (k % 5) as f64, 0.3, 0.02])).collect(),
    };
    let mut group = crit.benchmark_group("equations_truck");
    ekf(&mut group, "ekf-compiled", &compiled, &data);
    ekf(&mut group, "ekf-equations", &equations, &data);
    group.finish();
}

criterion_group!(benches, vessel, truck);
criterion_main!(benches);
