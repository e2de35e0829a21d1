//! One fuzzy-adaptive Kalman step of the BDS/INS paper (13 states, 3 measurements, one FIS
//! evaluation), beside the plain Kalman step of the same size and the adaptive step with a
//! constant scale (the linear algebra alone); the FIS with each defuzzifier (exact piecewise-linear
//! centroid, precomputed grid, naive 1000-point sampled centroid).
//!
//! The data are the paper's simulation (digest §5 (a)): the error-state truth of the 13-state
//! model and BDS measurements with `R0`, with the receiver status of the second phase (float,
//! 20 satellites) so that the FIS fires several rules.

use criterion::{Criterion, criterion_group, criterion_main};
use estimators::Setup;
use std::hint::black_box;

use bds_ins_dynamics::{InsErrorModel, InsNoise, InsParams, scenario, simulate_error_states};
use estimators::adaptive::ReceiverStatus;
use estimators::{AdaptiveKalmanFilter, ConstantScaling, FuzzyScaling, KalmanFilter};
use fuzzy_inference::{Defuzzifier, FuzzySystem};
use models::Xoshiro256StarStar;
use nalgebra::{DMatrix, DVector};

const STEPS: usize = 1200;

struct Data {
    model: bds_ins_dynamics::DiscreteInsModel,
    ys: Vec<DVector<f64>>,
    p0: DMatrix<f64>,
    r: DMatrix<f64>,
}

fn data() -> Data {
    let model = InsErrorModel::new(InsParams::digest(), InsNoise::digest_filter())
        .and_then(|m| m.discretize(scenario::PAPER_PERIOD))
        .unwrap_or_else(|e| panic!("model: {e}"));
    let mut rng = Xoshiro256StarStar::seed_from_u64(1);
    let truth = simulate_error_states(&model, &scenario::initial_error(), STEPS, &mut rng)
        .unwrap_or_else(|e| panic!("truth: {e}"));
    let r = scenario::nominal_r();
    let ys = truth[1..]
        .iter()
        .map(|x| {
            let v = DVector::from_fn(3, |i, _| r[(i, i)].sqrt() * rng.standard_normal());
            &model.h * x + v
        })
        .collect();
    Data { model, ys, p0: scenario::initial_covariance(), r }
}

fn steps(c: &mut Criterion) {
    let d = data();
    let u = DVector::zeros(0);
    let setup = Setup {
        x0: DVector::zeros(13),
        p0: d.p0.clone(),
        process_noise: d.model.q.clone(),
        measurement_noise: d.r.clone(),
        inputs: 0,
    };
    let status = ReceiverStatus::new(20.0, 4.0).unwrap_or_else(|e| panic!("{e}"));
    let mut group = c.benchmark_group("bds_ins_step_13x3");
    // Each iteration is one step; the filter runs on along the 1200 epochs and restarts.
    let mut kf = KalmanFilter::new(setup.clone()).unwrap_or_else(|e| panic!("{e}"));
    let mut k = 0;
    group.bench_function("kalman", |b| {
        b.iter(|| {
            let _ = black_box(kf.step(&d.model, &u, &d.ys[k]).map(|e| e.center[0]));
            k = (k + 1) % STEPS;
        })
    });
    let mut constant = AdaptiveKalmanFilter::new(setup.clone(), ConstantScaling(1.0)).unwrap_or_else(|e| panic!("{e}"));
    group.bench_function("adaptive_constant_scale", |b| {
        b.iter(|| {
            let _ = black_box(constant.step_with_status(&d.model, &u, &d.ys[k], &status));
            k = (k + 1) % STEPS;
        })
    });
    for (name, defuzz) in [
        ("fuzzy_exact", Defuzzifier::Exact),
        ("fuzzy_grid_33", Defuzzifier::Grid { points_per_axis: 33 }),
        ("fuzzy_sampled_1000", Defuzzifier::SAMPLED_1000),
    ] {
        let system = FuzzySystem::bds_ins_default().with_defuzzifier(defuzz).unwrap_or_else(|e| panic!("{e}"));
        let scaling = FuzzyScaling::new(system).unwrap_or_else(|e| panic!("{e}"));
        let mut f = AdaptiveKalmanFilter::new(setup.clone(), scaling).unwrap_or_else(|e| panic!("{e}"));
        group.bench_function(name, |b| {
            b.iter(|| {
                let _ = black_box(f.step_with_status(&d.model, &u, &d.ys[k], &status));
                k = (k + 1) % STEPS;
            })
        });
    }
    group.finish();
}

criterion_group!(benches, steps);
criterion_main!(benches);
