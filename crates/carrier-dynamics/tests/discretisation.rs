//! The carrier through the generic tools of `models`: exact ZOH against a fine RK4, the matrix
//! exponential against nalgebra's on the carrier's block, and seeded simulation.

use carrier_dynamics::{CarrierModel, CarrierParams};
use models::{
    Dims, FnModel, LinearTimeVarying, Noise, SimulationConfig, StepMatrices, expm, simulate_ltv, zoh_discretize,
    zoh_discretize_fixed,
};
use nalgebra::{DMatrix, DVector};

fn max_rel_err(got: &DMatrix<f64>, want: &DMatrix<f64>) -> f64 {
    (got - want).amax() / want.amax().max(1e-300)
}

#[test]
fn carrier_block_exponential_agrees_with_nalgebra() {
    let model = CarrierModel::new(CarrierParams::paper_preset()).unwrap();
    for ts in [1e-3, 0.5] {
        let mut block = DMatrix::zeros(12, 12);
        block.view_mut((0, 0), (4, 4)).copy_from(&(model.a() * ts));
        block.view_mut((0, 4), (4, 8)).copy_from(&(model.b() * ts));
        let err = max_rel_err(&expm(&block).unwrap(), &block.exp());
        assert!(err < 1e-12, "T_s = {ts}: {err}");
    }
}

/// RK4 of ẋ = A x + B u over [0, T] with constant u.
fn rk4(a: &DMatrix<f64>, bu: &DVector<f64>, x0: &DVector<f64>, t: f64, steps: usize) -> DVector<f64> {
    let h = t / steps as f64;
    let f = |x: &DVector<f64>| a * x + bu;
    let mut x = x0.clone();
    for _ in 0..steps {
        let k1 = f(&x);
        let k2 = f(&(&x + &k1 * (h / 2.0)));
        let k3 = f(&(&x + &k2 * (h / 2.0)));
        let k4 = f(&(&x + &k3 * h));
        x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
    }
    x
}

#[test]
fn carrier_zoh_matches_fine_rk4() {
    let model = CarrierModel::new(CarrierParams::for_load(2).unwrap().with_speed(3.0)).unwrap();
    let a = DMatrix::from_column_slice(4, 4, model.a().as_slice());
    let b = DMatrix::from_column_slice(4, 8, model.b().as_slice());
    for (ts, steps) in [(0.01, 50), (0.3, 2000)] {
        let d = zoh_discretize(&a, &b, ts).unwrap();
        for i in 0..4 {
            let x0 = DVector::from_fn(4, |r, _| f64::from(u8::from(r == i)));
            let x = rk4(&a, &DVector::zeros(4), &x0, ts, steps);
            let err = (x - d.a_p.column(i)).amax() / d.a_p.column(i).amax();
            assert!(err < 1e-10, "T_s = {ts}, A_p column {i}: {err}");
        }
        for j in 0..8 {
            let bu = b.column(j).into_owned();
            let x = rk4(&a, &bu, &DVector::zeros(4), ts, steps);
            let err = (x - d.b_p.column(j)).amax() / d.b_p.column(j).amax();
            assert!(err < 1e-10, "T_s = {ts}, B_p column {j}: {err}");
        }
    }
    let (a_p, b_p) = zoh_discretize_fixed(model.a(), model.b(), 0.3).unwrap();
    let d = zoh_discretize(&a, &b, 0.3).unwrap();
    assert_eq!(a_p.as_slice(), d.a_p.as_slice());
    assert_eq!(b_p.as_slice(), d.b_p.as_slice());
}

fn carrier_config(seed: u64, steps: usize) -> SimulationConfig {
    let u_max =
        DVector::from_row_slice(&[22.0, 16.0, 16.0, 21.0, 20.0, 15.0, 15.0, 19.0]) * (std::f64::consts::PI / 180.0);
    SimulationConfig {
        x0: DVector::from_row_slice(&[0.03, -0.08, 0.02, 0.1]),
        inputs: (0..steps).map(|k| &u_max * (k as f64 / steps as f64)).collect(),
        process_noise: Noise::uniform_cube(4, 1e-3).unwrap(),
        measurement_noise: Noise::ellipsoid_boundary(DMatrix::identity(4, 4) * 1e-4).unwrap(),
        seed,
    }
}

#[test]
fn carrier_simulation_follows_the_fixed_size_recursion() {
    let d = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap();
    let cfg = carrier_config(42, 100);
    let t1 = simulate_ltv(&d, &cfg).unwrap();
    let mut x = nalgebra::Vector4::from_column_slice(cfg.x0.as_slice());
    for k in 0..100 {
        let u = nalgebra::SVector::<f64, 8>::from_column_slice(t1.inputs[k].as_slice());
        let w = nalgebra::Vector4::from_column_slice(t1.process_noises[k].as_slice());
        x = d.a_p * x + d.b_p * u + w;
        assert!((x - nalgebra::Vector4::from_column_slice(t1.states[k + 1].as_slice())).amax() < 1e-12);
    }
}

#[test]
fn time_varying_carrier_and_carrier_errors_pass_through() {
    let ts = 0.01;
    let carrier = FnModel::new(Dims::new(4, 8, 4), |k: usize| {
        let v = 4.0 + 0.04 * k as f64;
        let (a, b, c) = CarrierModel::new(CarrierParams::paper_preset().with_speed(v))?.discretize(ts)?.to_dynamic();
        Ok(StepMatrices { a, b, c })
    });
    let mut cfg = carrier_config(1, 100);
    cfg.process_noise = Noise::none(4);
    let t = simulate_ltv(&carrier, &cfg).unwrap();
    let mut x = cfg.x0.clone();
    for k in 0..100 {
        let m = carrier.matrices(k).unwrap();
        x = &m.a * &x + &m.b * &cfg.inputs[k];
    }
    assert!((&x - &t.states[100]).amax() < 1e-12);
    let constant = CarrierModel::new(CarrierParams::paper_preset().with_speed(4.0)).unwrap().discretize(ts).unwrap();
    let tc = simulate_ltv(&constant, &cfg).unwrap();
    assert!((&tc.states[100] - &t.states[100]).amax() > 1e-6);
    let stopping = FnModel::new(Dims::new(4, 8, 4), |k: usize| {
        let (a, b, c) =
            CarrierModel::new(CarrierParams::paper_preset().with_speed(1.0 - k as f64))?.discretize(0.01)?.to_dynamic();
        Ok(StepMatrices { a, b, c })
    });
    let e = simulate_ltv(&stopping, &carrier_config(0, 3)).unwrap_err();
    assert_eq!(e.to_string(), "parameter v (forward speed) must be positive, got 0");
}
