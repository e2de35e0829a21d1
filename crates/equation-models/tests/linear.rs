//! Linear models written as equations: recognised, their matrices exact; RK4 of a linear
//! `[dxdt]` against the matrix exponential.

use equation_models::EquationModel;
use models::{AnyModel, DiscreteModel, expm};
use nalgebra::{DMatrix, DVector};

#[test]
fn discrete_linear_equations_give_exact_matrices() {
    let model = EquationModel::from_toml_str(
        r#"
[model]
states = ["p", "v"]
inputs = ["u"]
outputs = ["y"]
[parameters]
k = 0.3
[f]
p = "0.9 * p + 0.1 * v"
v = "-k * p + v + 0.5 * u - (p - p)"
[h]
y = "2 * p"
"#,
        "m.toml",
    )
    .unwrap();
    assert!(model.is_linear());
    let lin = model.linear().unwrap();
    assert_eq!(lin.a(), &DMatrix::from_row_slice(2, 2, &[0.9, 0.1, -0.3, 1.0]));
    assert_eq!(lin.b(), &DMatrix::from_row_slice(2, 1, &[0.0, 0.5]));
    assert_eq!(lin.c(), &DMatrix::from_row_slice(1, 2, &[2.0, 0.0]));
}

#[test]
fn affine_nonlinear_or_input_dependent_outputs_are_not_linear() {
    let make = |f_v: &str, h: &str| {
        let text = format!(
            "[model]\nstates = [\"p\", \"v\"]\ninputs = [\"u\"]\noutputs = [\"y\"]\n[f]\np = \"p + v\"\nv = \"{f_v}\"\n[h]\ny = \"{h}\"\n"
        );
        EquationModel::from_toml_str(&text, "m.toml").unwrap()
    };
    assert!(make("v + u", "p").is_linear());
    assert!(!make("v + u + 1", "p").is_linear(), "a constant term is affine, not linear");
    assert!(!make("v * u", "p").is_linear());
    assert!(!make("sin(v)", "p").is_linear());
    assert!(!make("v", "p + u").is_linear(), "h = C x has no input term");
    assert!(!make("v", "p^2").is_linear());
}

const OSCILLATOR: &str = r#"
[model]
states = ["p", "v"]
inputs = ["u"]
outputs = ["y"]
ts = 0.1
discretization = "DISC"
[parameters]
k = 4.0
c = 0.4
[dxdt]
p = "v"
v = "-k * p - c * v + u"
[h]
y = "p"
"#;

#[test]
fn rk4_of_a_linear_dxdt_matches_the_matrix_exponential() {
    let ts: f64 = 0.1;
    let ac = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, -0.4]);
    let bc = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    // Exact zero-order hold through the augmented exponential.
    let mut m = DMatrix::zeros(3, 3);
    m.view_mut((0, 0), (2, 2)).copy_from(&(&ac * ts));
    m.view_mut((0, 2), (2, 1)).copy_from(&(&bc * ts));
    let e = expm(&m).unwrap();
    let (ad, bd) = (e.view((0, 0), (2, 2)).into_owned(), e.view((0, 2), (2, 1)).into_owned());

    let model = EquationModel::from_toml_str(&OSCILLATOR.replace("DISC", "rk4"), "osc.toml").unwrap();
    let x = DVector::from_vec(vec![1.0, -0.5]);
    let u = DVector::from_vec(vec![0.7]);
    let mut next = DVector::zeros(2);
    model.f(&x, &u, &mut next).unwrap();
    let exact = &ad * &x + &bd * &u;
    // Local error of RK4: O((‖A‖ ts)^5 / 120) relative.
    let err = (&next - &exact).amax();
    assert!(err < 1e-5, "RK4 step error {err}");
    assert!(err > 0.0, "RK4 is not exact");

    // The matrices offered are those of the RK4 map itself (consistent with f).
    let lin = model.linear().expect("linear");
    let ah = &ac * ts;
    let id = DMatrix::<f64>::identity(2, 2);
    let ah2 = &ah * &ah;
    let ah3 = &ah2 * &ah;
    let phi = &id + &ah + &ah2 / 2.0 + &ah3 / 6.0 + &ah3 * &ah / 24.0;
    let gamma = (&id + &ah / 2.0 + &ah2 / 6.0 + &ah3 / 24.0) * ts * &bc;
    assert!((lin.a() - &phi).amax() < 1e-15);
    assert!((lin.b() - &gamma).amax() < 1e-15);
    assert!((lin.a() * &x + lin.b() * &u - &next).amax() < 1e-14);
    assert!((lin.a() - &ad).amax() < 1e-5);
    assert_eq!(lin.c(), &DMatrix::from_row_slice(1, 2, &[1.0, 0.0]));

    // Euler: I + ts A, ts B.
    let euler = EquationModel::from_toml_str(&OSCILLATOR.replace("DISC", "euler"), "osc.toml").unwrap();
    let lin = euler.linear().expect("linear");
    assert!((lin.a() - (&id + &ac * ts)).amax() < 1e-15);
    assert!((lin.b() - &bc * ts).amax() < 1e-15);
    euler.f(&x, &u, &mut next).unwrap();
    assert!((lin.a() * &x + lin.b() * &u - &next).amax() < 1e-14);
}

#[test]
fn rk4_converges_at_fourth_order() {
    // Over a fixed horizon, halving ts divides the global error by about 16.
    let ac = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, -0.4]);
    let x0 = DVector::from_vec(vec![1.0, 0.0]);
    let exact = expm(&(&ac * 1.0)).unwrap() * &x0;
    let error = |steps: usize| {
        let text = OSCILLATOR.replace("DISC", "rk4").replace("ts = 0.1", &format!("ts = {}", 1.0 / steps as f64));
        let model = EquationModel::from_toml_str(&text, "osc.toml").unwrap();
        let (mut x, mut next, u) = (x0.clone(), DVector::zeros(2), DVector::zeros(1));
        for _ in 0..steps {
            model.f(&x, &u, &mut next).unwrap();
            x.copy_from(&next);
        }
        (&x - &exact).amax()
    };
    let ratio = error(20) / error(40);
    assert!((12.0..20.0).contains(&ratio), "error ratio {ratio}");
}

#[test]
fn zoh_of_a_linear_dxdt_is_the_workspace_zero_order_hold() {
    use models::{DifferentiableModel, zoh_discretize};
    let model = EquationModel::from_toml_str(&OSCILLATOR.replace("DISC", "zoh"), "osc.toml").unwrap();
    let ac = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, -0.4]);
    let bc = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
    let zoh = zoh_discretize(&ac, &bc, 0.1).unwrap();
    let lin = model.linear().expect("linear");
    assert_eq!(lin.a(), &zoh.a_p);
    assert_eq!(lin.b(), &zoh.b_p);
    assert_eq!(lin.c(), &DMatrix::from_row_slice(1, 2, &[1.0, 0.0]));
    let (x, u) = (DVector::from_vec(vec![1.0, -0.5]), DVector::from_vec(vec![0.7]));
    let (mut next, mut jac) = (DVector::zeros(2), DMatrix::zeros(2, 2));
    model.f_with_jacobian(&x, &u, &mut next, &mut jac).unwrap();
    assert_eq!(next, &zoh.a_p * &x + &zoh.b_p * &u);
    assert_eq!(jac, zoh.a_p);
    // rhs is still the continuous right-hand side.
    let mut g = DVector::zeros(2);
    model.rhs(&x, &u, &mut g).unwrap();
    assert_eq!(g, &ac * &x + &bc * &u);
    // A nonlinear output keeps the exact hold of the dynamics, without matrices.
    let text = OSCILLATOR.replace("DISC", "zoh").replace("y = \"p\"", "y = \"sin(p)\"");
    let model = EquationModel::from_toml_str(&text, "osc.toml").unwrap();
    assert!(model.linear().is_none() && model.differentiable().is_some());
    model.f(&x, &u, &mut next).unwrap();
    assert_eq!(next, &zoh.a_p * &x + &zoh.b_p * &u);
}

#[test]
fn zoh_of_nonlinear_equations_is_refused_at_the_key() {
    use equation_models::EquationError;
    let refused = |v: &str, why: &str| {
        let text = OSCILLATOR.replace("DISC", "zoh").replace("v = \"-k * p - c * v + u\"", &format!("v = \"{v}\""));
        let e = EquationModel::from_toml_str(&text, "osc.toml").unwrap_err();
        assert!(matches!(e, EquationError::ZohNotLinear { .. }), "{e:?}");
        let m = e.to_string();
        assert!(
            m.starts_with("osc.toml:7:1: `discretization = \"zoh\"` needs linear [dxdt] equations: equation `dxdt.v`"),
            "{m}"
        );
        assert!(m.contains(why), "{m}");
    };
    refused("-k * sin(p) + u", "is not linear in `p`");
    refused("v * u", "is not linear in `v`");
    refused("u + 1", "has a constant term (it is 1 at zero states and inputs)");
    // abs has a derivative (±1), but it is not a constant.
    refused("abs(p)", "is not linear in `p`");
    // An unknown value names the three schemes.
    let e = EquationModel::from_toml_str(&OSCILLATOR.replace("DISC", "exact"), "osc.toml").unwrap_err();
    assert!(e.to_string().contains("\"euler\", \"rk4\" or \"zoh\""), "{e}");
}
