//! A linear system with its noise shapes and prior, shared by the estimators' tests and the
//! workspace benches (which include this file by path).
#![allow(dead_code)]

use carrier_dynamics::{CarrierModel, CarrierParams};
use estimators::{Setup, StepModel};
use nalgebra::{DMatrix, DVector};

/// `x⁺ = A x + B u`, `y = C x` with the noise shapes `Q`, `R` and the prior `(x₀, P₀)`.
#[derive(Debug, Clone)]
pub struct LinearSystem {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub q: DMatrix<f64>,
    pub r: DMatrix<f64>,
    pub p0: DMatrix<f64>,
    pub x0: DVector<f64>,
}

impl LinearSystem {
    /// The estimators' setup: the prior, the noise shapes and as many inputs as `B` has columns.
    pub fn setup(&self) -> Setup {
        setup(&self.x0, &self.p0, &self.q, &self.r, self.b.ncols())
    }

    /// The step model `(A, B, C)`.
    pub fn model(&self) -> StepModel<'_> {
        StepModel::new(&self.a, &self.b, &self.c)
    }
}

/// A setup of the prior `(x0, p0)`, the noise shapes `q`, `r` and `inputs` inputs (all cloned).
pub fn setup(x0: &DVector<f64>, p0: &DMatrix<f64>, q: &DMatrix<f64>, r: &DMatrix<f64>, inputs: usize) -> Setup {
    Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q.clone(), measurement_noise: r.clone(), inputs }
}

/// The Table 1 carrier at 6 m/s, `T_s` = 1 ms (4 states, 8 inputs), its last `m` states measured:
/// `Q = diag(1.6e-7, 1e-6, 4e-10, 1e-6)`, `R = 2e-5 I`, `P₀ = 1e-2 I`, `x₀ = 0`.
pub fn carrier(m: usize) -> LinearSystem {
    let d = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap();
    let (a, b, _) = d.to_dynamic();
    let c = DMatrix::from_fn(m, 4, |i, j| if j == 4 - m + i { 1.0 } else { 0.0 });
    let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1.6e-7, 1e-6, 4e-10, 1e-6]));
    let r = DMatrix::identity(m, m) * 2e-5;
    LinearSystem { a, b, c, q, r, p0: DMatrix::identity(4, 4) * 1e-2, x0: DVector::zeros(4) }
}

/// The measurements `y₁ … y_steps` of a run of `sys` from `x₀ = 0` under the constant input `u`,
/// with process and measurement noise on the boundary of their ellipsoids (seed `seed`).
pub fn boundary_measurements(sys: &LinearSystem, u: &DVector<f64>, steps: usize, seed: u64) -> Vec<DVector<f64>> {
    let model = models::ConstantModel::new(sys.a.clone(), sys.b.clone(), sys.c.clone()).unwrap();
    let run = models::simulate_ltv(
        &model,
        &models::SimulationConfig {
            x0: DVector::zeros(sys.a.nrows()),
            inputs: vec![u.clone(); steps],
            process_noise: models::Noise::ellipsoid_boundary(sys.q.clone()).unwrap(),
            measurement_noise: models::Noise::ellipsoid_boundary(sys.r.clone()).unwrap(),
            seed,
        },
    )
    .unwrap();
    run.measurements[1..].to_vec()
}
