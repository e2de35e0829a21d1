//! Exact Jacobians against central finite differences, for `[f]` and `[dxdt]` (Euler, RK4).

mod common;

use common::Lcg;
use equation_models::{Discretization, EquationModel, TimeModel};
use models::{AnyModel, DiscreteModel, check_jacobians};
use nalgebra::DVector;

const BICYCLE: &str = include_str!("../examples/models/kinematic_bicycle.toml");

fn pendulum(discretization: &str) -> EquationModel {
    let text = format!(
        r#"
[model]
states = ["theta", "omega"]
inputs = ["torque"]
outputs = ["tip_x", "tip_y"]
ts = 0.05
discretization = "{discretization}"

[parameters]
g = 9.81
l = 0.7
damping = 0.3

[definitions]
gravity = "-g / l * sin(theta)"

[dxdt]
theta = "omega"
omega = "gravity - damping * omega * abs_free + torque"

[h]
tip_x = "l * sin(theta)"
tip_y = "-l * cos(theta) + 0.1 * omega^2"
"#
    )
    .replace("abs_free", "sqrt(1 + omega^2)");
    EquationModel::from_toml_str(&text, "pendulum.toml").unwrap()
}

/// The kinematic bicycle written as a discrete `[f]` map (one Euler step by hand).
const BICYCLE_F: &str = r#"
[model]
states = ["x", "y", "psi", "v"]
inputs = ["a", "delta"]
outputs = ["range", "compass"]

[parameters]
lf = 1.2
lr = 1.6
dt = 0.1

[definitions]
beta = "atan(lr / (lf + lr) * tan(delta))"

[f]
x = "x + dt * v * cos(psi + beta)"
y = "y + dt * v * sin(psi + beta)"
psi = "psi + dt * v / lr * sin(beta)"
v = "v + dt * a - 0.01 * v^2 * dt"

[h]
range = "sqrt(x^2 + y^2 + 1)"
compass = "psi"
"#;

fn check_random_points(model: &EquationModel, seed: u64) {
    let d = model.dims();
    let mut rng = Lcg(seed);
    for _ in 0..25 {
        let x = rng.vector(d.states, -2.0, 2.0);
        let u = rng.vector(d.inputs, -0.4, 0.4);
        let check = check_jacobians(model, &x, &u).unwrap();
        assert!(check.f_error < 1e-7, "F error {} at x = {x}, u = {u}", check.f_error);
        assert!(check.h_error < 1e-7, "H error {} at x = {x}, u = {u}", check.h_error);
    }
}

#[test]
fn discrete_bicycle_jacobians_match_finite_differences() {
    let model = EquationModel::from_toml_str(BICYCLE_F, "bicycle_f.toml").unwrap();
    assert_eq!(model.time_model(), TimeModel::Discrete);
    assert!(model.differentiable().is_some());
    assert!(model.linear().is_none());
    check_random_points(&model, 1);
}

#[test]
fn continuous_pendulum_jacobians_match_finite_differences() {
    for (scheme, expected) in [("euler", Discretization::Euler), ("rk4", Discretization::Rk4)] {
        let model = pendulum(scheme);
        assert_eq!(model.time_model(), TimeModel::Continuous { ts: 0.05, discretization: expected });
        check_random_points(&model, 2);
    }
}

#[test]
fn example_bicycle_file_reads_and_differentiates() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/models/kinematic_bicycle.toml");
    let model = EquationModel::from_file(&path).unwrap();
    assert_eq!(model.state_names(), ["x", "y", "psi", "v"]);
    assert_eq!(model.input_names(), ["a", "delta"]);
    assert_eq!(model.output_names(), ["gnss_x", "gnss_y", "compass"]);
    assert_eq!(model.parameters(), [("lf".to_owned(), 1.2), ("lr".to_owned(), 1.6)]);
    check_random_points(&model, 3);
    // Straight ahead at 10 m/s for one step of 0.05 s.
    let mut next = DVector::zeros(4);
    model.f(&DVector::from_vec(vec![0.0, 0.0, 0.0, 10.0]), &DVector::zeros(2), &mut next).unwrap();
    assert!((next[0] - 0.5).abs() < 1e-12 && next[1].abs() < 1e-15 && (next[3] - 10.0).abs() < 1e-15);
    let same = EquationModel::from_toml_str(BICYCLE, "kinematic_bicycle.toml").unwrap();
    assert_eq!(same.dims(), model.dims());
}

#[test]
fn functions_without_derivative_leave_a_discrete_model() {
    let model = EquationModel::from_toml_str(
        r#"
[model]
states = ["x", "y"]
outputs = ["bearing"]
[f]
x = "max(x, 0.5 * y)"
y = "y"
[h]
bearing = "atan2(y, x)"
"#,
        "m.toml",
    )
    .unwrap();
    assert!(model.differentiable().is_none());
    assert!(model.not_differentiable().unwrap().contains("f.x"));
    let mut out = DVector::zeros(1);
    model.h(&DVector::from_vec(vec![1.0, 1.0]), &DVector::zeros(0), &mut out).unwrap();
    assert!((out[0] - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    let mut next = DVector::zeros(2);
    model.f(&DVector::from_vec(vec![1.0, 4.0]), &DVector::zeros(0), &mut next).unwrap();
    assert_eq!(next[0], 2.0);
}
