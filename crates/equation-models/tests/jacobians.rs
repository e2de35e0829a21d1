//! Exact Jacobians against central finite differences, for `[f]` and `[dxdt]` (Euler, RK4).

mod common;

use common::Lcg;
use equation_models::{Discretization, EquationModel, TimeModel};
use models::{AnyModel, DifferentiableModel, DiscreteModel, check_jacobians};
use nalgebra::{DMatrix, DVector};

const BICYCLE: &str = include_str!("../../../examples/models/kinematic_bicycle.toml");

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
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/models/kinematic_bicycle.toml");
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
fn nonsmooth_functions_have_exact_derivatives_away_from_their_kinks() {
    let model = EquationModel::from_toml_str(
        r#"
[model]
states = ["x", "y"]
inputs = ["u"]
outputs = ["bearing", "size"]
[f]
x = "max(x, 0.5 * y) + min(x * y, u) + abs(x - y) * atan2(y, x + 3)"
y = "atan2(x * u, y) - abs(sin(y)) + max(min(x, y), u)"
[h]
bearing = "atan2(y, x)"
size = "max(abs(x), abs(y)) + signum(x) + floor(y) + fract(x)"
"#,
        "m.toml",
    )
    .unwrap();
    assert!(model.differentiable().is_some() && model.not_differentiable().is_none());
    let mut out = DVector::zeros(2);
    model.h(&DVector::from_vec(vec![1.0, 1.0]), &DVector::zeros(1), &mut out).unwrap();
    assert!((out[0] - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    // Random points keep (with probability one) away from the kinks and jumps.
    check_random_points(&model, 4);
    // The choices at the kinks: abs'(0) = 0, ties of max and min take the first argument.
    let at = |expr: &str, x: f64| {
        let text = format!("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[f]\nx = \"{expr}\"\n[h]\ny = \"x\"\n");
        let model = EquationModel::from_toml_str(&text, "kink.toml").unwrap();
        let mut j = DMatrix::zeros(1, 1);
        model.f_jacobian(&DVector::from_vec(vec![x]), &DVector::zeros(0), &mut j).unwrap();
        j[(0, 0)]
    };
    assert_eq!(at("abs(x)", 0.0), 0.0);
    assert_eq!(at("abs(x)", -2.0), -1.0);
    assert_eq!(at("max(2 * x, 1)", 0.5), 2.0);
    assert_eq!(at("max(1, 2 * x)", 0.5), 0.0);
    assert_eq!(at("min(3 * x, 1 + x)", 0.5), 3.0);
    assert_eq!(at("signum(x) + floor(x) + ceil(x) + round(x) + trunc(x)", 0.3), 0.0);
    assert_eq!(at("fract(x)", 2.3), 1.0);
    assert_eq!(at("atan2(1, x)", 0.0), -1.0);
    // atan2 at the origin has no derivative: a typed error naming the derivative.
    let text = "[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[f]\nx = \"atan2(x, x)\"\n[h]\ny = \"x\"\n";
    let model = EquationModel::from_toml_str(text, "origin.toml").unwrap();
    let mut j = DMatrix::zeros(1, 1);
    let e = model.f_jacobian(&DVector::from_vec(vec![0.0]), &DVector::zeros(0), &mut j).unwrap_err();
    assert!(e.to_string().contains("d(f.x)/dx"), "{e}");
}

#[test]
fn a_shared_definition_equals_its_inlined_twin() {
    let make = |defs: &str, a: &str, b: &str| {
        let text = format!(
            "[model]\nstates = [\"x\", \"y\"]\ninputs = [\"u\"]\noutputs = [\"o\"]\nts = 0.1\n[definitions]\n{defs}\n[dxdt]\nx = \"{a}\"\ny = \"{b}\"\n[h]\no = \"{a}\"\n"
        );
        EquationModel::from_toml_str(&text, "twin.toml").unwrap()
    };
    let shared = make("d = \"sin(x) * y + atan2(y, u + 2)\"", "d + d^2", "u - d * x");
    let inlined = make(
        "",
        "(sin(x) * y + atan2(y, u + 2)) + (sin(x) * y + atan2(y, u + 2))^2",
        "u - (sin(x) * y + atan2(y, u + 2)) * x",
    );
    let mut rng = Lcg(5);
    for _ in 0..20 {
        let (x, u) = (rng.vector(2, -2.0, 2.0), rng.vector(1, -0.5, 0.5));
        let values = |m: &EquationModel| {
            let (mut f, mut fj, mut h, mut hj) =
                (DVector::zeros(2), DMatrix::zeros(2, 2), DVector::zeros(1), DMatrix::zeros(1, 2));
            m.f_with_jacobian(&x, &u, &mut f, &mut fj).unwrap();
            m.h_with_jacobian(&x, &u, &mut h, &mut hj).unwrap();
            (f, fj, h, hj)
        };
        assert_eq!(values(&shared), values(&inlined));
    }
}
