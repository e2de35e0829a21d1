//! Hostile model files: refused with a typed error or evaluated to a typed error, never a panic
//! or a hang.

use counting_allocator::{Counting, measure};
use equation_models::{EquationError, EquationModel, limits};
use models::{DifferentiableModel, DiscreteModel};
use nalgebra::{DMatrix, DVector};

#[global_allocator]
static GLOBAL: Counting = Counting;

fn with_f(expr: &str) -> Result<EquationModel, EquationError> {
    EquationModel::from_toml_str(
        &format!("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[f]\nx = \"{expr}\"\n[h]\ny = \"x\"\n"),
        "hostile.toml",
    )
}

#[test]
fn deep_nesting_is_refused_before_parsing() {
    let deep = format!("{}x{}", "(".repeat(100_000), ")".repeat(100_000));
    let e = with_f(&deep).unwrap_err();
    assert!(matches!(e, EquationError::LimitExceeded { .. }), "{e}");
    let deep = format!("{}x{}", "(".repeat(10_000), ")".repeat(10_000));
    let e = with_f(&deep).unwrap_err();
    assert!(matches!(e, EquationError::LimitExceeded { limit, .. } if limit == limits::MAX_DEPTH), "{e}");
    assert!(e.to_string().starts_with("hostile.toml:5:1"), "{e}");
    let deep = format!("{}x{}", "sin(".repeat(300), ")".repeat(300));
    assert!(matches!(with_f(&deep), Err(EquationError::LimitExceeded { .. })));
    // Within the limit it works, derivatives included.
    let nested = format!("{}x{}", "sin(".repeat(40), ")".repeat(40));
    let model = with_f(&nested).unwrap();
    let mut j = DMatrix::zeros(1, 1);
    model.f_jacobian(&DVector::from_vec(vec![0.1]), &DVector::zeros(0), &mut j).unwrap();
    assert!(j[(0, 0)] > 0.0 && j[(0, 0)] <= 1.0);
    let parens = format!("{}x{}", "(".repeat(200), ")".repeat(200));
    assert!(with_f(&parens).is_ok());
}

#[test]
fn huge_sums_are_refused_or_compiled_quickly() {
    let huge = vec!["x"; 100_000].join(" + ");
    let e = with_f(&huge).unwrap_err();
    assert!(matches!(e, EquationError::LimitExceeded { .. }), "{e}");
    // Definitions that double at each level are shared values, not text: one node each.
    let mut text = String::from("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[definitions]\nd0 = \"x\"\n");
    for i in 1..40 {
        text.push_str(&format!("d{i} = \"d{} + d{}\"\n", i - 1, i - 1));
    }
    text.push_str("[f]\nx = \"d39\"\n[h]\ny = \"x\"\n");
    let model = EquationModel::from_toml_str(&text, "hostile.toml").unwrap();
    let (mut out, mut j) = (DVector::zeros(1), DMatrix::zeros(1, 1));
    model.f_with_jacobian(&DVector::from_vec(vec![0.5]), &DVector::zeros(0), &mut out, &mut j).unwrap();
    assert_eq!((out[0], j[(0, 0)]), (2f64.powi(38), 2f64.powi(39)));
    // Many definitions at the per-expression limit exceed the total.
    let mut text = String::from("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[definitions]\n");
    let per = limits::MAX_OPERATORS;
    for i in 0..=limits::MAX_TOTAL_OPERATORS / per {
        text.push_str(&format!("d{i} = \"{}\"\n", vec!["x"; per].join("+")));
    }
    text.push_str("[f]\nx = \"d0\"\n[h]\ny = \"x\"\n");
    let e = EquationModel::from_toml_str(&text, "hostile.toml").unwrap_err();
    assert!(
        matches!(&e, EquationError::LimitExceeded { limit, what, .. } if *limit == limits::MAX_TOTAL_OPERATORS && what.contains("together")),
        "{e}"
    );
    assert!(e.to_string().starts_with(&format!("hostile.toml:{}:1", 5 + limits::MAX_TOTAL_OPERATORS / per)), "{e}");
    // The largest sum allowed compiles and differentiates.
    let big = vec!["x"; limits::MAX_OPERATORS].join("+");
    let model = with_f(&big).unwrap();
    let mut j = DMatrix::zeros(1, 1);
    model.f_jacobian(&DVector::from_vec(vec![0.5]), &DVector::zeros(0), &mut j).unwrap();
    assert_eq!(j[(0, 0)], limits::MAX_OPERATORS as f64);
    let too_big = vec!["x"; limits::MAX_OPERATORS + 2].join("+");
    assert!(matches!(with_f(&too_big), Err(EquationError::LimitExceeded { .. })));
}

#[test]
fn large_products_compile_in_memory_linear_in_their_size_with_exact_derivatives() {
    // Symbolic differentiation of a product of 256 factors took an expression library far longer
    // than the budget (its derivative has 256² terms); the forward chain rule is linear in the
    // size of the expression. Shown by what compiling requests in all (bytes, every allocation
    // summed), not by a clock: a quadratic graph would need 256 × more.
    // (Measured: 3.3 kB for the product's 511 characters, 37 kB for the largest graph's 36 kB of
    // text, its first Jacobian included; the bound is 64 bytes a character.)
    let product = vec!["x"; limits::MAX_OPERATORS].join("*");
    let mut j = DMatrix::zeros(1, 1);
    let (jacobian, usage) = measure(|| {
        let model = with_f(&product).unwrap();
        model.f_jacobian(&DVector::from_vec(vec![1.0]), &DVector::zeros(0), &mut j).map(|()| j[(0, 0)])
    });
    assert_eq!(jacobian.unwrap(), limits::MAX_OPERATORS as f64);
    assert!(usage.bytes <= 64 * product.len(), "{} bytes for {} characters", usage.bytes, product.len());
    // The largest graph allowed, too.
    let mut text = String::from("[model]\nstates = [\"x\"]\noutputs = [\"y\"]\n[definitions]\nd0 = \"x\"\n");
    let per = limits::MAX_OPERATORS;
    for i in 1..limits::MAX_TOTAL_OPERATORS / per {
        let terms: Vec<String> = (0..per / 3).map(|k| format!("sin(d{} * {k})", i - 1)).collect();
        text.push_str(&format!("d{i} = \"{}\"\n", terms.join("+")));
    }
    text.push_str(&format!("[f]\nx = \"d{}\"\n[h]\ny = \"x\"\n", limits::MAX_TOTAL_OPERATORS / per - 1));
    let mut out = DVector::zeros(1);
    let (evaluated, big) = measure(|| {
        let model = EquationModel::from_toml_str(&text, "big.toml").unwrap();
        model.f_with_jacobian(&DVector::from_vec(vec![0.1]), &DVector::zeros(0), &mut out, &mut j)
    });
    evaluated.unwrap();
    assert!(big.bytes <= 64 * text.len(), "{} bytes for {} characters", big.bytes, text.len());
}

#[test]
fn huge_exponents_give_typed_errors() {
    let model = with_f("x^1e308").unwrap();
    let u = DVector::zeros(0);
    let mut out = DVector::zeros(1);
    model.f(&DVector::from_vec(vec![0.5]), &u, &mut out).unwrap();
    assert_eq!(out[0], 0.0);
    let e = model.f(&DVector::from_vec(vec![2.0]), &u, &mut out).unwrap_err();
    assert!(e.to_string().contains("f.x") && e.to_string().contains("inf"), "{e}");
    let mut j = DMatrix::zeros(1, 1);
    assert!(model.f_jacobian(&DVector::from_vec(vec![2.0]), &u, &mut j).is_err());
    assert!(with_f("x^1e999").is_err());
    // Non-finite inputs are reported as such.
    assert!(model.f(&DVector::from_vec(vec![f64::NAN]), &u, &mut out).is_err());
}

#[test]
fn oversized_files_and_name_lists_are_refused() {
    let big = format!("# {}\n", "x".repeat(limits::MAX_FILE_BYTES));
    assert!(matches!(EquationModel::from_toml_str(&big, "big.toml"), Err(EquationError::FileTooLarge { .. })));
    let dir = std::env::temp_dir().join(format!("equation-models-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("big.toml");
    std::fs::write(&path, &big).unwrap();
    assert!(matches!(EquationModel::from_file(&path), Err(EquationError::FileTooLarge { .. })));
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(matches!(
        EquationModel::from_file(std::path::Path::new("/nonexistent/model.toml")),
        Err(EquationError::Io { .. })
    ));
    let names: Vec<String> = (0..=limits::MAX_NAMES).map(|i| format!("\"s{i}\"")).collect();
    let text = format!("[model]\nstates = [{}]\noutputs = [\"y\"]\n", names.join(", "));
    let e = EquationModel::from_toml_str(&text, "many.toml").unwrap_err();
    assert!(matches!(e, EquationError::LimitExceeded { .. }), "{e}");
    assert!(e.to_string().starts_with("many.toml:2:1"), "{e}");
    let e = with_f(&"x+".repeat(limits::MAX_EXPRESSION_BYTES)).unwrap_err();
    assert!(matches!(e, EquationError::LimitExceeded { .. }), "{e}");
}

#[test]
fn garbage_expressions_never_panic() {
    for bad in [
        "x^^x",
        "((((",
        "))))",
        "sin()",
        "sin",
        "atan2(x)",
        "min(x, x, x)",
        ",",
        "x,x",
        "--x",
        "x--x",
        "^x",
        "x^",
        "sin(,)",
        "1..2",
        ".5.5",
        "x 1",
        "x x",
        "()",
        "(x)(x)",
        "e",
        "E^x",
        "x/0",
        "0/0",
        "1e308*1e308",
    ] {
        let result = std::panic::catch_unwind(|| {
            if let Ok(model) = with_f(bad) {
                let mut out = DVector::zeros(1);
                let _ = model.f(&DVector::from_vec(vec![0.3]), &DVector::zeros(0), &mut out);
                let mut j = DMatrix::zeros(1, 1);
                let _ = model.f_jacobian(&DVector::from_vec(vec![0.3]), &DVector::zeros(0), &mut j);
            }
        });
        assert!(result.is_ok(), "`{bad}` panicked");
    }
}
