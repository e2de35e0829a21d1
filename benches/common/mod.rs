//! Data shared by the workspace benches: the truck and the supply vessel with their filter
//! setups and a cycle of inputs and measurements.
#![allow(dead_code)]

use estimators::Setup;
use models::DiscreteModel;
use nalgebra::{DMatrix, DVector};
use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams};
use vessel_dynamics::{DiscreteVessel, VesselParams};

/// Steps of a cycle.
pub const CYCLE: usize = 64;

/// A filter setup with the inputs and measurements of its cycle.
pub struct Cycle {
    pub setup: Setup,
    pub inputs: Vec<DVector<f64>>,
    pub ys: Vec<DVector<f64>>,
}

fn diag(v: &[f64]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_row_slice(v))
}

/// The truck (the digest's preset) at 70 km/h through a gentle slalom, one rear wheel slipping
/// by 0.2 %: `x₀ = (v, 0.05, 0.02)`, `P₀ = diag(1e-2, 1e-2, 1e-4)`, `Q = diag(1e-7, 1e-7, 1e-9)`,
/// `R = diag(2.5e-3, 2.5e-3, 4e-6)`, and the model's own measurements along the inputs from `x₀`.
pub fn truck() -> (TruckEkfModel, Cycle) {
    let params = TruckParams::digest_preset();
    let model = TruckEkfModel::paper(params).unwrap();
    let v = 70.0 / 3.6;
    let setup = Setup {
        x0: DVector::from_vec(vec![v, 0.05, 0.02]),
        p0: diag(&[1e-2, 1e-2, 1e-4]),
        process_noise: diag(&[1e-7, 1e-7, 1e-9]),
        measurement_noise: diag(&[2.5e-3, 2.5e-3, 4e-6]),
        inputs: 7,
    };
    let inputs: Vec<DVector<f64>> = (0..CYCLE)
        .map(|k| {
            let mut u = TruckInput::free_rolling(0.02 * ((k as f64) * 0.3).sin(), v, params.rolling_radius);
            u.omega[3] *= 1.002;
            u.to_dvector()
        })
        .collect();
    let (mut x, mut ys) = (setup.x0.clone(), Vec::with_capacity(CYCLE));
    for u in &inputs {
        let mut next = DVector::zeros(3);
        model.f(&x, u, &mut next).unwrap();
        x = next;
        let mut y = DVector::zeros(3);
        model.h(&x, u, &mut y).unwrap();
        ys.push(y);
    }
    (model, Cycle { setup, inputs, ys })
}

/// The supply vessel (the paper's model, Euler at 0.1 s) with the digest's settings
/// (`Q = 1e-2 I`, `R = diag(1, 1, 0.1)`, `P₀ = diag(1, 1, 0.1, 0.1, 0.1, 0.01)`, `x₀ = 0`) and
/// synthetic thrusts and measurements.
pub fn vessel() -> (DiscreteVessel, Cycle) {
    let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let setup = Setup {
        x0: DVector::zeros(6),
        p0: diag(&[1.0, 1.0, 0.1, 0.1, 0.1, 0.01]),
        process_noise: DMatrix::identity(6, 6) * 1e-2,
        measurement_noise: diag(&[1.0, 1.0, 0.1]),
        inputs: 3,
    };
    let inputs = (0..CYCLE)
        .map(|k| DVector::from_vec(vec![1e5 * (k as f64 * 0.1).sin(), 3e4, 1e6 * (k as f64 * 0.2).cos()]))
        .collect();
    let ys =
        (0..CYCLE).map(|k| DVector::from_vec(vec![0.1 * k as f64, 0.05 * k as f64, 0.01 * (k % 7) as f64])).collect();
    (model, Cycle { setup, inputs, ys })
}
