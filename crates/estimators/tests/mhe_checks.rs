//! The moving-horizon estimators check their windows against the noise boxes (docs/robust-mhe.md
//! §2.8): noise on the boundary of `W` and `V` is consistent, whatever the cost and solver; a
//! measurement far outside `V`, a jump `W` forbids and an unstable model against stable data are
//! proved inconsistent, with each policy doing what it says.

mod common;

use common::lcg::{Data, Lcg, system};
use estimators::mhe::{MheCost, MheSettings, MovingHorizonEstimator, WindowSolver};
use estimators::{
    DataCheck, DataChecks, Estimate, Estimator, EstimatorError, InconsistencyPolicy, Setup, SolveOutcome, StepModel,
};
use nalgebra::{DMatrix, DVector};

fn mhe(n: usize, m: usize, cost: MheCost, solver: WindowSolver, w: f64, v: f64) -> MovingHorizonEstimator {
    let mut s = MheSettings::new(
        (DVector::repeat(n, -w), DVector::repeat(n, w)),
        (DVector::repeat(m, -v), DVector::repeat(m, v)),
    );
    s.cost = cost;
    s.horizon = 6;
    s.blocks = vec![1; 6];
    s.solver = solver;
    let setup = Setup {
        x0: DVector::zeros(n),
        p0: DMatrix::identity(n, n),
        process_noise: DMatrix::identity(n, n) * (w * w),
        measurement_noise: DMatrix::identity(m, m) * (v * v),
        inputs: 1,
    };
    MovingHorizonEstimator::new(setup, s).unwrap()
}

/// Inputs and measurements with every noise component on the boundary of its box.
fn boundary_data(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    steps: usize,
    w: f64,
    v: f64,
    seed: u64,
) -> Data {
    common::lcg::simulate((a, b, c), steps, &mut Lcg(seed ^ 0x5bd1), 0.5, (w, v), Lcg::sign)
}

#[test]
fn noise_on_the_boundary_of_its_boxes_is_consistent_for_every_cost_and_solver() {
    for seed in 0..4 {
        let (n, m) = (3 + seed as usize % 2, 1 + seed as usize % 3);
        let (a, b, c) = system(n, m, 70 + seed);
        let model = StepModel::new(&a, &b, &c);
        let (us, ys) = boundary_data(&a, &b, &c, 25, 0.05, 0.2, seed);
        for cost in [MheCost::MinMax { lambda_v: 10.0 }, MheCost::LeastSquares] {
            for solver in [WindowSolver::exact_saddle(), WindowSolver::coordinate_rotation()] {
                let mut e = mhe(n, m, cost, solver, 0.05, 0.2);
                for k in 0..us.len() {
                    let est = e
                        .step(&model, &us[k], &ys[k])
                        .unwrap_or_else(|err| panic!("seed {seed} {cost:?} step {}: {err}", k + 1));
                    assert_eq!(est.status().data, DataCheck::Consistent, "seed {seed} {cost:?} step {}", k + 1);
                }
            }
        }
    }
}

/// What each step of a run returned: the centre, the outcome and the data check, or the error.
type Steps = Vec<Result<(DVector<f64>, SolveOutcome, DataCheck), EstimatorError>>;

/// A random walk measured directly: `|w| ≤ 0.1`, `|v| ≤ 0.5`, `y` constant at 0 until `jump_at`.
fn walk(policy: InconsistencyPolicy, ys: &[f64]) -> Steps {
    let (a, b, c) = (DMatrix::identity(1, 1), DMatrix::zeros(1, 1), DMatrix::identity(1, 1));
    let model = StepModel::new(&a, &b, &c);
    let mut e = mhe(1, 1, MheCost::MinMax { lambda_v: 10.0 }, WindowSolver::exact_saddle(), 0.1, 0.5);
    e.set_data_checks(DataChecks::with_policy(policy)).unwrap();
    let u = DVector::zeros(1);
    ys.iter()
        .map(|&y| {
            e.step(&model, &u, &DVector::from_element(1, y))
                .map(|est| (est.center.clone(), est.status().outcome, est.status().data))
        })
        .collect()
}

#[test]
fn a_measurement_far_outside_v_is_an_error_naming_its_step_and_changes_nothing() {
    // 2 500 times the box: an error at step 6, and the estimator continues as if it never came.
    let mut ys = vec![0.0; 12];
    ys[5] = 1250.0;
    let out = walk(InconsistencyPolicy::Error, &ys);
    match &out[5] {
        Err(EstimatorError::InconsistentWindow { step: 6, samples: 6, excess }) => {
            // V must widen by about half the jump: the trajectory can meet the outlier halfway.
            assert!((*excess - 624.45).abs() < 1e-3, "{excess}")
        }
        other => panic!("{other:?}"),
    }
    let mut clean = ys.clone();
    clean.remove(5);
    let reference = walk(InconsistencyPolicy::Error, &clean);
    let ours: Vec<_> = out.into_iter().filter_map(Result::ok).collect();
    let theirs: Vec<_> = reference.into_iter().map(Result::unwrap).collect();
    assert_eq!(ours, theirs);
}

#[test]
fn a_jump_the_process_box_forbids_is_caught_though_each_measurement_fits_v() {
    // x moves at most 0.1 per step and each measurement is within 0.5 of it: a jump of y from 0
    // to exactly 1.1 in one step fits (both noises on their boundaries), 1.2 does not.
    let ok = walk(InconsistencyPolicy::Error, &[0.0, 0.0, 0.0, 1.1]);
    assert!(ok.iter().all(Result::is_ok), "{ok:?}");
    let bad = walk(InconsistencyPolicy::Error, &[0.0, 0.0, 0.0, 1.2]);
    assert!(matches!(bad[3], Err(EstimatorError::InconsistentWindow { step: 4, .. })), "{:?}", bad[3]);
}

#[test]
fn flag_publishes_and_marks_every_window_holding_the_sample_and_restart_drops_it() {
    let mut ys = vec![0.0; 14];
    ys[3] = 40.0;
    let flagged = walk(InconsistencyPolicy::FlagAndContinue, &ys);
    let data: Vec<DataCheck> = flagged.iter().map(|r| r.as_ref().unwrap().2).collect();
    // The window holds the last 7 samples (horizon 6): steps 4 … 10 see the outlier.
    for (k, d) in data.iter().enumerate() {
        let expected = if (3..=9).contains(&k) { DataCheck::Inconsistent } else { DataCheck::Consistent };
        assert_eq!(*d, expected, "step {}", k + 1);
    }
    let restarted = walk(InconsistencyPolicy::Restart, &ys);
    let step4 = restarted[3].as_ref().unwrap();
    assert_eq!((step4.1, step4.2), (SolveOutcome::Predicted, DataCheck::Inconsistent));
    assert!(restarted[4..].iter().all(|r| r.as_ref().unwrap().2 == DataCheck::Consistent));
    // The same as an estimator that predicted at step 4.
    let (a, b, c) = (DMatrix::identity(1, 1), DMatrix::zeros(1, 1), DMatrix::identity(1, 1));
    let model = StepModel::new(&a, &b, &c);
    let mut reference = mhe(1, 1, MheCost::MinMax { lambda_v: 10.0 }, WindowSolver::exact_saddle(), 0.1, 0.5);
    let u = DVector::zeros(1);
    for (k, &y) in ys.iter().enumerate() {
        let est = if k == 3 {
            reference.predict(&model, &u)
        } else {
            reference.step(&model, &u, &DVector::from_element(1, y))
        };
        assert_eq!(est.unwrap().center, restarted[k].as_ref().unwrap().0, "step {}", k + 1);
    }
    let off = walk(InconsistencyPolicy::Off, &ys);
    assert!(off.iter().all(|r| r.as_ref().unwrap().2 == DataCheck::NotChecked));
    assert_eq!(off[3].as_ref().unwrap().0, flagged[3].as_ref().unwrap().0);
}

#[test]
fn an_unstable_model_against_stable_data_is_inconsistent() {
    // x_{k+1} = 1.5 x_k + w with |w| ≤ 0.01 cannot stay near 1 (it needs w ≈ −0.5 every step).
    let (a, b, c) = (DMatrix::from_element(1, 1, 1.5), DMatrix::zeros(1, 1), DMatrix::identity(1, 1));
    let model = StepModel::new(&a, &b, &c);
    let mut e = mhe(1, 1, MheCost::LeastSquares, WindowSolver::exact_saddle(), 0.01, 0.1);
    let u = DVector::zeros(1);
    let y = DVector::from_element(1, 1.0);
    let first_error = (1..=8).find_map(|k| e.step(&model, &u, &y).err().map(|err| (k, err)));
    match first_error {
        Some((k, EstimatorError::InconsistentWindow { step, .. })) => assert_eq!(step, k),
        other => panic!("{other:?}"),
    }
}
