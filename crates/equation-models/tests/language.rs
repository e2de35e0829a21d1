//! Values of the expression language: functions, constants, negative parameters, precedence.

use equation_models::EquationModel;
use models::DiscreteModel;
use nalgebra::DVector;

/// `h(x = 3, u = 0.5)` of a one-output model with parameter `k = -2`.
fn value(expr: &str) -> f64 {
    let text = format!(
        "[model]\nstates = [\"x\"]\ninputs = [\"u\"]\noutputs = [\"y\"]\n[parameters]\nk = -2\n[f]\nx = \"x\"\n[h]\ny = \"x * 0 + {expr}\"\n"
    );
    let model = EquationModel::from_toml_str(&text, "lang.toml").unwrap_or_else(|e| panic!("{expr}: {e}"));
    let mut y = DVector::zeros(1);
    model.h(&DVector::from_vec(vec![3.0]), &DVector::from_vec(vec![0.5]), &mut y).unwrap();
    y[0]
}

#[test]
fn functions_constants_and_parameters_evaluate_as_written() {
    let cases: [(&str, f64); 18] = [
        // The expression library binds a leading minus tighter than `^` (documented).
        ("-x^2", 9.0),
        ("2*-x", -6.0),
        ("k^2", 4.0),
        ("x^k", 1.0 / 9.0),
        ("2^-1", 0.5),
        ("-(x^2)", -9.0),
        ("(-x)^2", 9.0),
        ("atan2(u, x)", 0.5f64.atan2(3.0)),
        ("min(x, u) + max(x, u)", 3.5),
        ("pi + tau + E", std::f64::consts::PI + std::f64::consts::TAU + std::f64::consts::E),
        ("ln(x) - log(x)", 0.0),
        ("log10(100) + log2(8)", 5.0),
        ("sqrt(x^2 + 16)", 5.0),
        ("tanh(u) - sinh(u) / cosh(u)", 0.0),
        ("exp(0) + abs(k)", 3.0),
        ("1.5e1 + .5 + 2E-1", 15.7),
        ("x - u - 1", 1.5),
        ("x / u / 2", 3.0),
    ];
    for (expr, expected) in cases {
        let v = value(expr);
        assert!((v - expected).abs() < 1e-12, "{expr} = {v}, expected {expected}");
    }
}

#[test]
fn precedence_is_that_of_the_expression_library_used_before() {
    // Values that `exmex` 0.21, which this crate evaluated with before it compiled its own
    // graph, gives at x = 3 (`h` here evaluates `x * 0 + ...`).
    let cases: [(&str, f64); 9] = [
        ("1 + -x^2", 10.0),
        ("1 - -x^2", -8.0),
        ("2 * -x^2", 18.0),
        ("2^-x", 0.125),
        ("2^-x^2", 0.015625),
        ("-x^2 + 2^-x", 9.125),
        ("- (1) + -x^2", 8.0),
        ("2 * (1 - x^2)", -16.0),
        ("-2 * -x", 6.0),
    ];
    for (expr, expected) in cases {
        let v = value(expr);
        assert!((v - expected).abs() < 1e-12, "{expr} = {v}, expected {expected}");
    }
}

#[test]
fn models_can_be_shared_between_threads() {
    fn assert_send_sync<T: Send + Sync + Clone>() {}
    assert_send_sync::<EquationModel>();
}
