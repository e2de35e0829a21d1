//! No heap allocation when the EKF evaluates the truck model: `f`, `h` and both Jacobians write
//! into the caller's buffers (a counting global allocator, counting only on this test's thread).

use counting_allocator::{Counting, count};

use models::{DifferentiableModel, DiscreteModel};
use nalgebra::{DMatrix, DVector};
use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams};

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn model_evaluations_do_not_allocate() {
    let model = TruckEkfModel::paper(TruckParams::digest_preset()).unwrap();
    let x = DVector::from_vec(vec![19.44, 0.15, 0.06]);
    let mut input = TruckInput::free_rolling(0.02, 19.44, 0.52);
    input.omega[2..].iter_mut().for_each(|w| *w *= 1.004);
    let u = input.to_dvector();
    let (mut fx, mut hx) = (DVector::zeros(3), DVector::zeros(3));
    let (mut fj, mut hj) = (DMatrix::zeros(3, 3), DMatrix::zeros(3, 3));
    let (r, n) = count(|| {
        for _ in 0..100 {
            model.f(&x, &u, &mut fx)?;
            model.h(&x, &u, &mut hx)?;
            model.f_jacobian(&x, &u, &mut fj)?;
            model.h_jacobian(&x, &u, &mut hj)?;
        }
        Ok::<(), models::ModelError>(())
    });
    r.unwrap();
    assert_eq!(n, 0, "{n} allocations in 100 evaluations of f, h, F, H");
    assert!(fx[0] > 0.0 && hj[(0, 0)] == 1.0 && fj[(2, 2)] < 1.0);
}
