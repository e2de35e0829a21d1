//! No heap allocation in a moving-horizon update after construction (active-set inner solver,
//! coordinate rotation and exact saddle, every blocking preset, with and without measurements),
//! with the data check on: on data that respect the boxes the published window witnesses
//! consistency and the check's linear programme (which allocates) never runs.

use counting_allocator::{Counting, count};
use estimators::Setup;

use estimators::mhe::{ArrivalRecursion, BlockingPreset, MheCost, MheSettings, MovingHorizonEstimator, WindowSolver};
use estimators::{DataCheck, Estimate, Estimator, StepModel};
use nalgebra::{DMatrix, DVector};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn updates_do_not_allocate() {
    let a = DMatrix::from_row_slice(
        4,
        4,
        &[1.0, 0.5, 0.1, 0.0, 0.0, 1.0, 0.05, 0.1, 0.0, 0.0, 0.3, -0.1, 0.0, 0.0, 0.2, 0.1],
    );
    let b = DMatrix::from_column_slice(4, 1, &[0.5, 0.2, -0.1, 0.4]);
    let c = DMatrix::from_row_slice(1, 4, &[1.0, 0.0, 0.0, 0.0]);
    let model = StepModel::new(&a, &b, &c);
    let inputs: Vec<DVector<f64>> = (0..30).map(|k| DVector::from_element(1, (0.4 * k as f64).sin())).collect();
    // Data of the model with noise well inside W = [-0.1, 0.1]⁴ and V = [-1, 1].
    let mut x = DVector::<f64>::zeros(4);
    let mut outputs = vec![&c * &x + DVector::from_element(1, 0.1)];
    for k in 0..30 {
        x = &a * &x + &b * &inputs[k] + DVector::from_fn(4, |i, _| 0.01 * (0.3 * (k + i) as f64).sin());
        outputs.push(&c * &x + DVector::from_element(1, 0.1 * (0.7 * k as f64).cos()));
    }
    for preset in [BlockingPreset::Rmhe, BlockingPreset::RmheOp, BlockingPreset::RmheOf] {
        for solver in [WindowSolver::coordinate_rotation(), WindowSolver::exact_saddle()] {
            for arrival in [ArrivalRecursion::Kalman, ArrivalRecursion::HInfinity { theta: 0.9 }] {
                let setup = Setup {
                    x0: DVector::zeros(4),
                    p0: DMatrix::identity(4, 4) * 0.01,
                    process_noise: DMatrix::identity(4, 4) * 9e-4,
                    measurement_noise: DMatrix::from_element(1, 1, 0.1),
                    inputs: 1,
                };
                let mut s = MheSettings::new(
                    (DVector::repeat(4, -0.1), DVector::repeat(4, 0.1)),
                    (DVector::repeat(1, -1.0), DVector::repeat(1, 1.0)),
                )
                .with_preset(6, preset)
                .unwrap();
                s.solver = solver;
                s.arrival = arrival;
                s.cost = MheCost::MinMax { lambda_v: 10.0 };
                let mut e = MovingHorizonEstimator::new(setup, s).unwrap();
                let (_, allocations) = count(|| {
                    e.measure_initial(&model, &outputs[0]).unwrap();
                    for k in 0..30 {
                        if k % 7 == 3 {
                            e.predict(&model, &inputs[k]).unwrap();
                        } else {
                            let est = e.step(&model, &inputs[k], &outputs[k + 1]).unwrap();
                            assert_eq!(est.status().data, DataCheck::Consistent);
                        }
                    }
                });
                assert_eq!(allocations, 0, "{preset:?} {solver:?} {arrival:?}");
            }
        }
    }
}
