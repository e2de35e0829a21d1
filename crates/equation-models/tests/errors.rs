//! Every error class, with the `file:line:column` of the offending key.

use equation_models::{EquationError, EquationModel};
use models::{DiscreteModel, ModelError};
use nalgebra::DVector;

fn error(text: &str) -> EquationError {
    EquationModel::from_toml_str(text, "car.toml").expect_err("the file must be refused")
}

/// Asserts the message starts with the location and contains `needle`.
fn assert_at(e: &EquationError, location: &str, needle: &str) {
    let message = e.to_string();
    assert!(message.starts_with(location), "`{message}` is not at {location}");
    assert!(message.contains(needle), "`{message}` does not mention `{needle}`");
}

const HEAD: &str = "[model]\nstates = [\"x\", \"v\"]\ninputs = [\"a\"]\noutputs = [\"y\"]\n";

#[test]
fn unknown_symbol_names_it_and_the_equation() {
    let e = error(&format!("{HEAD}[f]\nx = \"x + v\"\nv = \"v + a * mass\"\n[h]\ny = \"x\"\n"));
    assert!(
        matches!(&e, EquationError::UnknownSymbol { symbol, equation, .. } if symbol == "mass" && equation == "f.v")
    );
    assert_at(&e, "car.toml:7:1", "`mass`");
    // A definition may use only earlier ones.
    let e = error(&format!(
        "{HEAD}[definitions]\nd1 = \"d2 * 2\"\nd2 = \"x\"\n[f]\nx = \"d1\"\nv = \"v\"\n[h]\ny = \"x\"\n"
    ));
    assert!(
        matches!(&e, EquationError::UnknownSymbol { symbol, equation, .. } if symbol == "d2" && equation == "definitions.d1")
    );
    assert_at(&e, "car.toml:6:1", "d2");
}

#[test]
fn unknown_function_and_parse_errors() {
    let e = error(&format!("{HEAD}[f]\nx = \"x\"\nv = \"sinus(v)\"\n[h]\ny = \"x\"\n"));
    assert!(matches!(&e, EquationError::UnknownFunction { function, .. } if function == "sinus"));
    assert_at(&e, "car.toml:7:1", "sinus");
    for bad in ["x +* ", "(x", "x)", "x $ v", "", "1e999", "x + ,"] {
        let e = error(&format!("{HEAD}[f]\nx = \"x\"\nv = \"{bad}\"\n[h]\ny = \"x\"\n"));
        assert!(matches!(e, EquationError::Parse { .. }), "`{bad}`: {e}");
        assert_at(&e, "car.toml:7:1", "f.v");
    }
    let e = error("[model\nstates = 1");
    assert!(matches!(e, EquationError::Toml { .. }), "{e}");
    assert_at(&e, "car.toml:1:", "TOML");
}

#[test]
fn missing_and_unknown_equations() {
    let e = error(&format!("{HEAD}[f]\nx = \"x\"\n[h]\ny = \"x\"\n"));
    assert!(matches!(&e, EquationError::MissingEquation { name, section, .. } if name == "v" && section == "f"));
    assert_at(&e, "car.toml:5:2", "`v`");
    let e = error(&format!("{HEAD}[f]\nx = \"x\"\nv = \"v\"\nw = \"v\"\n[h]\ny = \"x\"\n"));
    assert!(matches!(&e, EquationError::UnknownTarget { name, .. } if name == "w"));
    assert_at(&e, "car.toml:8:1", "`w`");
    let e = error(&format!("{HEAD}[f]\nx = \"x\"\nv = \"v\"\n[h]\nz = \"x\"\n"));
    assert!(matches!(&e, EquationError::UnknownTarget { name, expected, .. } if name == "z" && expected == "output"));
    let e = error(&format!("{HEAD}[f]\nx = \"x\"\nv = \"v\"\n"));
    assert!(matches!(&e, EquationError::MissingEquation { name, section, .. } if name == "y" && section == "h"));
    let e = error(&format!("{HEAD}[h]\ny = \"x\"\n"));
    assert!(matches!(e, EquationError::Format { .. }));
    let e =
        error(&format!("{HEAD}ts = 0.1\n[f]\nx = \"x\"\nv = \"v\"\n[dxdt]\nx = \"v\"\nv = \"a\"\n[h]\ny = \"x\"\n"));
    assert_at(&e, "car.toml:9:2", "not both");
}

#[test]
fn duplicate_and_reserved_names() {
    let e = error("[model]\nstates = [\"x\", \"v\"]\ninputs = [\"x\"]\noutputs = [\"y\"]\n");
    assert!(matches!(&e, EquationError::DuplicateName { name, .. } if name == "x"));
    assert_at(&e, "car.toml:3:11", "`x`");
    let e = error(&format!("{HEAD}[parameters]\nv = 1.0\n"));
    assert!(matches!(&e, EquationError::DuplicateName { name, .. } if name == "v"));
    assert_at(&e, "car.toml:6:1", "`v`");
    let e = error("[model]\nstates = [\"x\", \"sin\"]\noutputs = [\"y\"]\n");
    assert!(matches!(&e, EquationError::InvalidName { name, .. } if name == "sin"));
    assert_at(&e, "car.toml:2:16", "function");
    let e = error(&format!("{HEAD}[parameters]\npi = 3.0\n"));
    assert!(matches!(&e, EquationError::InvalidName { name, .. } if name == "pi"));
    let e = error("[model]\nstates = [\"2x\"]\noutputs = [\"y\"]\n");
    assert!(matches!(&e, EquationError::InvalidName { .. }));
}

#[test]
fn sampling_period_of_dxdt_models() {
    let body = "[dxdt]\nx = \"v\"\nv = \"a\"\n[h]\ny = \"x\"\n";
    let e = error(&format!("{HEAD}{body}"));
    assert!(matches!(e, EquationError::SamplingPeriod { .. }));
    assert_at(&e, "car.toml:1:2", "ts");
    for ts in ["0.0", "-0.1", "\"fast\"", "nan", "inf"] {
        let e = error(&format!("{HEAD}ts = {ts}\n{body}"));
        assert!(matches!(e, EquationError::SamplingPeriod { .. }), "ts = {ts}: {e}");
        assert_at(&e, "car.toml:5:1", "ts");
    }
    let e = error(&format!("{HEAD}ts = 0.1\ndiscretization = \"euler2\"\n{body}"));
    assert_at(&e, "car.toml:6:1", "discretization");
    let e = error(&format!("{HEAD}discretization = \"rk4\"\n[f]\nx = \"x\"\nv = \"v\"\n[h]\ny = \"x\"\n"));
    assert_at(&e, "car.toml:5:1", "discretization");
    // Integers are accepted for ts and parameters.
    assert!(EquationModel::from_toml_str(&format!("{HEAD}ts = 1\n{body}"), "car.toml").is_ok());
}

#[test]
fn outputs_that_see_no_state_are_refused() {
    let e = error(&format!("{HEAD}[parameters]\nk = 2\n[f]\nx = \"x\"\nv = \"v\"\n[h]\ny = \"k * a + 1\"\n"));
    assert!(matches!(&e, EquationError::Unobservable { output, .. } if output == "y"));
    assert_at(&e, "car.toml:11:1", "unobservable");
}

#[test]
fn format_errors() {
    let e = error("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\nspeed = 3\n");
    assert_at(&e, "car.toml:4:1", "speed");
    let e = error("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[g]\nx = \"x\"\n");
    assert_at(&e, "car.toml:4:2", "`g`");
    let e = error("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[parameters]\nk = \"one\"\n");
    assert_at(&e, "car.toml:5:5", "number");
    let e = error("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[f]\nx = 1.0\n");
    assert_at(&e, "car.toml:5:1", "string");
    let e = error("[model]\noutputs = [\"y\"]\n");
    assert_at(&e, "car.toml:1:2", "states");
    let e = error("x = 1\n");
    assert!(matches!(e, EquationError::Format { .. }));
}

#[test]
fn non_finite_evaluations_name_the_equation_and_the_values() {
    let model = EquationModel::from_toml_str(
        &format!("{HEAD}[f]\nx = \"x + v\"\nv = \"a / x\"\n[h]\ny = \"ln(x)\"\n"),
        "car.toml",
    )
    .unwrap();
    let (x, u) = (DVector::from_vec(vec![0.0, 1.0]), DVector::from_vec(vec![2.0]));
    let mut out = DVector::zeros(2);
    let e = model.f(&x, &u, &mut out).unwrap_err();
    let ModelError::Evaluation(message) = &e else { panic!("{e:?}") };
    assert!(message.contains("f.v") && message.contains("inf"), "{message}");
    assert!(message.contains("x = 0") && message.contains("v = 1") && message.contains("a = 2"), "{message}");
    let mut y = DVector::zeros(1);
    let e = model.h(&DVector::from_vec(vec![-1.0, 0.0]), &u, &mut y).unwrap_err();
    assert!(e.to_string().contains("h.y") && e.to_string().contains("NaN"), "{e}");
    // Wrong dimensions are reported, not panics.
    assert!(matches!(model.f(&DVector::zeros(3), &u, &mut out), Err(ModelError::DimensionMismatch { .. })));
}

#[test]
fn angles_name_states_and_outputs_once() {
    let body = "[f]\nx = \"x + v\"\nv = \"v + a\"\n[h]\ny = \"x\"\n";
    let ok = EquationModel::from_toml_str(&format!("{HEAD}angles = [\"y\", \"x\"]\n{body}"), "car.toml").unwrap();
    assert_eq!(ok.angles(), models::Angles::new(&[0], &[0]));
    // The linear view of a linear model carries them too.
    use models::AnyModel;
    assert_eq!(models::LinearModel::angles(ok.linear().unwrap()), models::Angles::new(&[0], &[0]));
    let e = error(&format!("{HEAD}angles = [\"x\", \"a\"]\n{body}"));
    assert_at(&e, "car.toml:5:16", "`a` in `angles` is neither a state nor an output");
    let e = error(&format!("{HEAD}angles = [\"x\", \"x\"]\n{body}"));
    assert_at(&e, "car.toml:5:16", "twice");
    let e = error(&format!("{HEAD}angles = \"x\"\n{body}"));
    assert_at(&e, "car.toml:5:1", "array");
    let e = error(&format!("{HEAD}angles = [1]\n{body}"));
    assert_at(&e, "car.toml:5:11", "strings");
}
