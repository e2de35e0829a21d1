//! An extended Kalman filter step on a closure model allocates nothing after setup: the
//! model's evaluations run on the stack (the duals are arrays), the filter's buffers are its own.

use counting_allocator::{Counting, count};
use estimators::{ExtendedKalmanFilter, Setup};
use models::{Angles, ClosureModel, Integrator};
use nalgebra::{DMatrix, DVector};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn an_ekf_step_on_a_closure_model_allocates_nothing() {
    let (lf, lr) = (1.5, 2.0);
    let model = ClosureModel::continuous(
        2,
        0.01,
        Integrator::Rk4 { substeps: 2 },
        |x, u| {
            let beta = (lr / (lf + lr) * u[1].tan()).atan();
            [x[3] * (x[2] + beta).cos(), x[3] * (x[2] + beta).sin(), x[3] / lr * beta.sin(), u[0].into()]
        },
        |x, u| [x[0], x[1], x[3] / lr * (lr / (lf + lr) * u[1].tan()).atan().sin(), x[3], x[2]],
    )
    .unwrap()
    .with_angles(Angles::new(&[2], &[4]))
    .unwrap();
    let diag = |v: &[f64]| DMatrix::from_diagonal(&DVector::from_column_slice(v));
    let mut ekf = ExtendedKalmanFilter::new(Setup {
        x0: DVector::from_vec(vec![0.0, 0.0, 0.0, 3.0]),
        p0: diag(&[4.0, 4.0, 0.1, 1.0]),
        process_noise: diag(&[1e-6, 1e-6, 9e-8, 1e-4]),
        measurement_noise: diag(&[0.25, 0.25, 9e-6, 0.01, 2.5e-3]),
        inputs: 2,
    })
    .unwrap();
    let u = DVector::from_vec(vec![0.5, 0.02]);
    let y = DVector::from_vec(vec![0.03, 0.0, 0.0, 3.005, 0.0]);
    ekf.step(&model, &u, &y).unwrap();
    let (result, allocations) = count(|| ekf.step(&model, &u, &y).map(|e| e.center[0]));
    assert!(result.unwrap().is_finite());
    assert_eq!(allocations, 0);
    // The prediction and the update on their own allocate nothing either.
    let (result, allocations) = count(|| ekf.predict(&model, &u).is_ok() && ekf.update(&model, &y).is_ok());
    assert!(result);
    assert_eq!(allocations, 0);
}
