//! The vehicle model files of `examples/models/` against the compiled vehicle crates: `f`, `h`,
//! `∂f/∂x`, `∂h/∂x` on seeded random states and inputs, and `A`, `B`, `C` of the linear ones, to
//! 1e-12 relative.

mod common;

use std::path::PathBuf;

use common::Lcg;
use equation_models::EquationModel;
use models::{AnyModel, DifferentiableModel, DiscreteModel, LinearModel, LinearTimeVarying};
use nalgebra::{DMatrix, DVector};

/// The keys of a model file that `port-est` reads.
const FOREIGN: &[&str] = &["x0", "p0", "q", "r", "u_lower", "u_upper", "x_lower", "x_upper", "mhe", "ukf"];
/// Random states and inputs per vehicle.
const SAMPLES: usize = 64;
/// Elementwise tolerance, relative to `max(|a|, |b|, largest entry of either matrix)`.
const TOLERANCE: f64 = 1e-12;

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/models").join(name)
}

fn text(name: &str) -> String {
    std::fs::read_to_string(path(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn load(name: &str) -> EquationModel {
    EquationModel::from_toml_str_with_foreign_keys(&text(name), &path(name).display().to_string(), FOREIGN)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The port-est value `key` of a model file, as a matrix (a vector is one column).
fn foreign(name: &str, key: &str) -> DMatrix<f64> {
    let table: toml::Table = text(name).parse().unwrap();
    let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)).unwrap();
    let rows = table[key].as_array().unwrap_or_else(|| panic!("{name}: `{key}`"));
    if rows.first().is_some_and(toml::Value::is_array) {
        let rows: Vec<Vec<f64>> = rows.iter().map(|r| r.as_array().unwrap().iter().map(number).collect()).collect();
        DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
    } else {
        DMatrix::from_iterator(rows.len(), 1, rows.iter().map(number))
    }
}

fn assert_close(what: &str, got: &DMatrix<f64>, want: &DMatrix<f64>) {
    assert_eq!(got.shape(), want.shape(), "{what}: shapes");
    let scale = got.amax().max(want.amax());
    for ((i, j), w) in want.iter().enumerate().map(|(k, w)| ((k % want.nrows(), k / want.nrows()), w)) {
        let g = got[(i, j)];
        let bound = TOLERANCE * g.abs().max(w.abs()).max(scale);
        assert!((g - w).abs() <= bound, "{what}[({i}, {j})]: equations {g:e}, compiled {w:e} (difference {:e})", g - w);
    }
}

fn column(v: &DVector<f64>) -> DMatrix<f64> {
    DMatrix::from_column_slice(v.len(), 1, v.as_slice())
}

/// Compares `f`, `h` and their Jacobians of the file's model with `compiled` at `(x, u)`.
fn compare_at(what: &str, eq: &EquationModel, compiled: &dyn DifferentiableModel, x: &DVector<f64>, u: &DVector<f64>) {
    let d = DiscreteModel::dims(eq);
    assert_eq!(d, compiled.dims(), "{what}: dimensions");
    let (n, m) = (d.states, d.outputs);
    let (mut f1, mut f2, mut y1, mut y2) = (DVector::zeros(n), DVector::zeros(n), DVector::zeros(m), DVector::zeros(m));
    eq.f(x, u, &mut f1).unwrap();
    compiled.f(x, u, &mut f2).unwrap();
    assert_close(&format!("{what} f at x = {x:?}, u = {u:?}"), &column(&f1), &column(&f2));
    eq.h(x, u, &mut y1).unwrap();
    compiled.h(x, u, &mut y2).unwrap();
    assert_close(&format!("{what} h"), &column(&y1), &column(&y2));
    let eq_d = eq.differentiable().expect("the equations have Jacobians");
    let (mut a1, mut a2, mut c1, mut c2) =
        (DMatrix::zeros(n, n), DMatrix::zeros(n, n), DMatrix::zeros(m, n), DMatrix::zeros(m, n));
    eq_d.f_jacobian(x, u, &mut a1).unwrap();
    compiled.f_jacobian(x, u, &mut a2).unwrap();
    assert_close(&format!("{what} df/dx"), &a1, &a2);
    eq_d.h_jacobian(x, u, &mut c1).unwrap();
    compiled.h_jacobian(x, u, &mut c2).unwrap();
    assert_close(&format!("{what} dh/dx"), &c1, &c2);
    // One pass for the value and its Jacobian gives the same numbers as two.
    let (mut f3, mut a3, mut y3, mut c3) =
        (DVector::zeros(n), DMatrix::zeros(n, n), DVector::zeros(m), DMatrix::zeros(m, n));
    eq_d.f_with_jacobian(x, u, &mut f3, &mut a3).unwrap();
    eq_d.h_with_jacobian(x, u, &mut y3, &mut c3).unwrap();
    assert_eq!((f3, a3, y3, c3), (f1, a1, y1, c1), "{what}: with_jacobian");
}

/// Compares on `SAMPLES` random points drawn by `sample`.
fn compare(
    what: &str,
    eq: &EquationModel,
    compiled: &dyn DifferentiableModel,
    seed: u64,
    mut sample: impl FnMut(&mut Lcg) -> (DVector<f64>, DVector<f64>),
) {
    let mut rng = Lcg(seed);
    for _ in 0..SAMPLES {
        let (x, u) = sample(&mut rng);
        compare_at(what, eq, compiled, &x, &u);
    }
}

/// `A`, `B`, `C` of the file's model against the compiled matrices.
fn compare_linear(what: &str, eq: &EquationModel, a: &DMatrix<f64>, b: &DMatrix<f64>, c: &DMatrix<f64>) {
    let lin = eq.linear().unwrap_or_else(|| panic!("{what}: the equations are linear"));
    assert_close(&format!("{what} A"), lin.a(), a);
    assert_close(&format!("{what} B"), lin.b(), b);
    assert_close(&format!("{what} C"), lin.c(), c);
}

#[test]
fn car_is_the_zoh_of_the_single_track_model() {
    use car_dynamics::{CarModel, CarParams, DIGEST_INITIAL_STATE, DIGEST_SAMPLING_PERIOD, NoiseBounds};
    let eq = load("car.toml");
    let compiled = CarModel::new(CarParams::digest_default()).unwrap().discretize(DIGEST_SAMPLING_PERIOD).unwrap();
    let (a, b, c) = (compiled.a().clone(), compiled.b().clone(), compiled.c().clone());
    compare_linear("car", &eq, &a, &b, &c);
    compare("car", &eq, &compiled, 1, |rng| {
        let x = DVector::from_vec(vec![
            rng.uniform(-5.0, 5.0),
            rng.uniform(-0.2, 0.2),
            rng.uniform(-0.05, 0.05),
            rng.uniform(-0.5, 0.5),
        ]);
        (x, rng.vector(1, -0.05, 0.05))
    });
    // The port-est values: the reproduction's prior and the paper's noise boxes.
    assert_eq!(foreign("car.toml", "x0"), DMatrix::from_column_slice(4, 1, &DIGEST_INITIAL_STATE));
    let table: toml::Table = text("car.toml").parse().unwrap();
    let w = NoiseBounds::digest();
    let mhe = table["mhe"].as_table().unwrap();
    let list = |k: &str| -> Vec<f64> { mhe[k].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect() };
    assert_eq!(list("w_upper"), w.process_half_widths.to_vec());
    assert_eq!(list("w_lower"), w.process_half_widths.map(|h| -h).to_vec());
    assert_eq!(list("v_upper"), vec![w.measurement_half_width]);
    assert_eq!(list("v_lower"), vec![-w.measurement_half_width]);
}

#[test]
fn carrier_is_the_zoh_of_table_1_with_one_container() {
    use carrier_dynamics::{CarrierModel, CarrierParams};
    let eq = load("carrier.toml");
    assert_eq!(CarrierParams::for_load(1).unwrap(), CarrierParams::paper_preset());
    let model = CarrierModel::new(CarrierParams::paper_preset()).unwrap();
    let step = model.discretize(1e-3).unwrap().matrices(0).unwrap();
    compare_linear("carrier", &eq, &step.a, &step.b, &step.c);
    let compiled = models::ConstantModel::new(step.a, step.b, step.c).unwrap();
    compare("carrier", &eq, &compiled, 2, |rng| {
        let x = DVector::from_vec(vec![
            rng.uniform(-0.1, 0.1),
            rng.uniform(-0.5, 0.5),
            rng.uniform(-0.05, 0.05),
            rng.uniform(-0.2, 0.2),
        ]);
        (x, rng.vector(8, -0.1, 0.1))
    });
    // The continuous right-hand side is eq (7) itself.
    let mut rng = Lcg(3);
    for _ in 0..SAMPLES {
        let x = rng.vector(4, -0.2, 0.2);
        let u = rng.vector(8, -0.1, 0.1);
        let mut g = DVector::zeros(4);
        eq.rhs(&x, &u, &mut g).unwrap();
        let xs = carrier_dynamics::StateVector::from_column_slice(x.as_slice());
        let us = carrier_dynamics::InputVector::from_column_slice(u.as_slice());
        let want = model.derivative(&xs, &us);
        assert_close("carrier dx/dt", &column(&g), &DMatrix::from_column_slice(4, 1, want.as_slice()));
    }
}

#[test]
fn vessel_is_the_euler_step_of_the_low_speed_model() {
    use vessel_dynamics::{DiscreteVessel, VesselParams};
    let eq = load("vessel.toml");
    let compiled = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    assert!(eq.linear().is_none());
    let limits = VesselParams::paper().thrust.max;
    compare("vessel", &eq, &compiled, 4, |rng| {
        let x = DVector::from_vec(vec![
            rng.uniform(-100.0, 100.0),
            rng.uniform(-100.0, 100.0),
            rng.uniform(-std::f64::consts::PI, std::f64::consts::PI),
            rng.uniform(-2.0, 2.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-0.05, 0.05),
        ]);
        let u = DVector::from_fn(3, |i, _| rng.uniform(-limits[i], limits[i]));
        (x, u)
    });
    assert_eq!(foreign("vessel.toml", "u_upper"), DMatrix::from_column_slice(3, 1, &limits));
}

#[test]
fn bds_ins_is_the_exact_discretisation_of_the_error_model() {
    use bds_ins_dynamics::{InsErrorModel, InsNoise, InsParams, scenario};
    let eq = load("bds-ins.toml");
    let compiled = InsErrorModel::new(InsParams::digest(), InsNoise::digest_filter())
        .unwrap()
        .discretize(scenario::PAPER_PERIOD)
        .unwrap();
    compare_linear("bds-ins", &eq, &compiled.phi, &compiled.b, &compiled.h);
    compare("bds-ins", &eq, &compiled, 5, |rng| {
        let scales = [5.0, 5.0, 0.5, 0.5, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-5, 1e-5, 1e-5];
        (DVector::from_fn(13, |i, _| rng.uniform(-scales[i], scales[i])), DVector::zeros(0))
    });
    // The port-est values are the reproduction's.
    assert_close("bds-ins q", &foreign("bds-ins.toml", "q"), &compiled.q);
    assert_close("bds-ins p0", &foreign("bds-ins.toml", "p0"), &scenario::initial_covariance());
    assert_close("bds-ins r", &foreign("bds-ins.toml", "r"), &scenario::nominal_r());
    assert_eq!(foreign("bds-ins.toml", "x0"), DMatrix::zeros(13, 1));
}

#[test]
fn truck_is_the_euler_step_of_the_pac89_planar_model() {
    use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams};
    let eq = load("truck.toml");
    // atan2 (slip angles), abs and max (slip ratios) have derivatives.
    assert!(eq.differentiable().is_some() && eq.linear().is_none());
    let params = TruckParams::digest_preset();
    let compiled = TruckEkfModel::paper(params).unwrap();
    compare("truck", &eq, &compiled, 6, |rng| {
        let x = DVector::from_vec(vec![rng.uniform(5.0, 25.0), rng.uniform(-0.5, 0.5), rng.uniform(-0.2, 0.2)]);
        let delta = rng.uniform(-0.1, 0.1);
        // Wheel speeds within ±2 % of rolling (slip ratios of a few percent, both signs).
        let omega: [f64; 6] = std::array::from_fn(|_| x[0] / params.rolling_radius * rng.uniform(0.98, 1.02));
        (x, TruckInput { delta, omega }.to_dvector())
    });
    // The port-est values are the reproduction's EKF settings.
    assert_eq!(foreign("truck.toml", "x0"), DMatrix::from_column_slice(3, 1, &[19.44, 0.0, 0.0]));
}
