//! The closure model against an independent reference: the same equations compiled by the
//! equation models (hand-written derivative rules through a graph, the chain rule through RK4
//! and Euler written out by hand) agree to 1e-12 in `f`, `h` and both Jacobians; and every
//! registry estimator that the model can serve (EKF, UKF, the MHE with a UKF arrival cost) steps
//! on it through `&dyn AnyModel`.

use std::path::Path;

use equation_models::EquationModel;
use models::{Angles, ClosureModel, DifferentiableModel, Dual, Integrator};
use nalgebra::{DMatrix, DVector};

/// `f`, `F`, `h`, `H` of both models at `(x, u)`, to 1e-12 relative to the largest entry.
fn agree(a: &impl DifferentiableModel, b: &impl DifferentiableModel, x: &[f64], u: &[f64]) {
    let (x, u) = (DVector::from_column_slice(x), DVector::from_column_slice(u));
    let d = a.dims();
    assert_eq!(d, b.dims());
    let eval = |m: &dyn DifferentiableModel| {
        let (mut f, mut fj) = (DVector::zeros(d.states), DMatrix::zeros(d.states, d.states));
        let (mut h, mut hj) = (DVector::zeros(d.outputs), DMatrix::zeros(d.outputs, d.states));
        m.f_with_jacobian(&x, &u, &mut f, &mut fj).unwrap();
        m.h_with_jacobian(&x, &u, &mut h, &mut hj).unwrap();
        (f, fj, h, hj)
    };
    let (fa, fja, ha, hja) = eval(a);
    let (fb, fjb, hb, hjb) = eval(b);
    let close = |p: &DMatrix<f64>, q: &DMatrix<f64>, what: &str| {
        assert!((p - q).amax() <= 1e-12 * q.amax().max(1.0), "{what} at x = {x}: {p} vs {q}");
    };
    close(
        &DMatrix::from_column_slice(d.states, 1, fa.as_slice()),
        &DMatrix::from_column_slice(d.states, 1, fb.as_slice()),
        "f",
    );
    close(&fja, &fjb, "F");
    close(
        &DMatrix::from_column_slice(d.outputs, 1, ha.as_slice()),
        &DMatrix::from_column_slice(d.outputs, 1, hb.as_slice()),
        "h",
    );
    close(&hja, &hjb, "H");
}

const POINTS: [([f64; 4], [f64; 2]); 4] = [
    ([0.0, 0.0, 0.0, 3.0], [0.5, 0.0]),
    ([12.0, -4.0, 0.8, 7.5], [-1.0, 0.3]),
    ([-3.0, 25.0, -2.9, 0.2], [0.2, -0.45]),
    ([100.0, 50.0, 6.5, 15.0], [2.0, 0.05]),
];

#[test]
fn kinematic_bicycle_matches_its_model_file() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/models/kinematic_bicycle.toml");
    let file = EquationModel::from_file(&path).unwrap();
    let (lf, lr) = (1.2, 1.6);
    let closures = ClosureModel::continuous(
        2,
        0.05,
        Integrator::Rk4 { substeps: 1 },
        |x, u| {
            let beta = (lr / (lf + lr) * u[1].tan()).atan();
            let course = x[2] + beta;
            [x[3] * course.cos(), x[3] * course.sin(), x[3] / lr * beta.sin(), u[0].into()]
        },
        |x, _| [x[0], x[1], x[2]],
    )
    .unwrap();
    for (x, u) in POINTS {
        agree(&closures, &file, &x, &u);
    }
}

/// One model written both ways: states and inputs inside every kind of function, plain
/// numbers on both sides of the operators.
const EQUATIONS: &str = r#"
[model]
states = ["p", "q", "r", "s"]
inputs = ["a", "b"]
outputs = ["range", "bearing", "mix"]
TIME
[definitions]
w = "atan2(q, 1 + p^2)"
[RHS]
p = "0.1 * q - 0.5 * sin(p) * cos(r) + a"
q = "(1 - p) * exp(-0.1 * s^2) / (2 + tanh(q))"
r = "sqrt(1 + p^2 + q^2) - 0.2 * r + w * b"
s = "abs(s) * 0.1 - max(p, q) + min(r, 0.5) + ln(2 + cos(s))"
[h]
range = "sqrt(p^2 + q^2)"
bearing = "atan2(q, p)"
mix = "p^3 / (1 + r^2) + cbrt(s + 10) - asin(0.5 * tanh(q))"
"#;

fn closure_rhs(x: &[Dual<4>; 4], u: &[f64]) -> [Dual<4>; 4] {
    let [p, q, r, s] = *x;
    let w = q.atan2(1.0 + p.powi(2));
    [
        0.1 * q - 0.5 * p.sin() * r.cos() + u[0],
        (1.0 - p) * (-0.1 * s.powi(2)).exp() / (2.0 + q.tanh()),
        (1.0 + p.powi(2) + q.powi(2)).sqrt() - 0.2 * r + w * u[1],
        s.abs() * 0.1 - p.max(q) + r.min(Dual::constant(0.5)) + (2.0 + s.cos()).ln(),
    ]
}

fn closure_h(x: &[Dual<4>; 4], _: &[f64]) -> [Dual<4>; 3] {
    let [p, q, r, s] = *x;
    [p.hypot(q), q.atan2(p), p.powi(3) / (1.0 + r.powi(2)) + (s + 10.0).cbrt() - (0.5 * q.tanh()).asin()]
}

#[test]
fn every_function_matches_the_equation_models_discrete_euler_and_rk4() {
    let text = |time: &str, rhs: &str| EQUATIONS.replace("TIME", time).replace("RHS", rhs);
    let cases = [
        (text("", "f"), None),
        (text("ts = 0.1\ndiscretization = \"euler\"", "dxdt"), Some(Integrator::Euler)),
        (text("ts = 0.1\ndiscretization = \"rk4\"", "dxdt"), Some(Integrator::Rk4 { substeps: 1 })),
    ];
    let points = [[0.3, -0.7, 1.1, 2.0], [-1.5, 0.4, -0.2, -3.0], [2.0, 2.5, 0.9, 0.4], [0.05, -0.1, 3.0, -0.8]];
    for (toml, integrator) in cases {
        let file = EquationModel::from_toml_str(&toml, "both-ways.toml").unwrap();
        let closures = match integrator {
            None => ClosureModel::discrete(2, closure_rhs, closure_h),
            Some(i) => ClosureModel::continuous(2, 0.1, i, closure_rhs, closure_h),
        }
        .unwrap()
        .with_angles(Angles::NONE)
        .unwrap();
        for x in points {
            agree(&closures, &file, &x, &[0.4, -1.2]);
        }
    }
}

#[test]
fn every_registry_estimator_it_can_serve_steps_on_it() {
    use estimators::{Setup, registry::ESTIMATORS};
    use models::{AnyModel, Capability, DiscreteModel};
    let model = ClosureModel::continuous(
        1,
        0.1,
        Integrator::Rk4 { substeps: 1 },
        |x, u| [x[1], -(x[0].sin()) * 9.81 - 0.2 * x[1] + u[0]],
        |x, _| [x[0].sin() * 2.0, x[0].cos() * -2.0],
    )
    .unwrap();
    assert_eq!(Capability::of(&model), Capability::Differentiable);
    let diag = |v: &[f64]| DMatrix::from_diagonal(&DVector::from_column_slice(v));
    let mut served = Vec::new();
    for entry in ESTIMATORS.iter().filter(|e| e.needs.is_offered_by(&model) && e.extra_measurements == 0) {
        let setup = Setup {
            x0: DVector::from_vec(vec![0.3, 0.0]),
            p0: diag(&[0.1, 0.1]),
            process_noise: diag(&[1e-6, 1e-4]),
            measurement_noise: diag(&[1e-4, 1e-4]),
            inputs: 1,
        };
        let Ok(mut estimator) = entry.build(setup, None) else { continue }; // needs settings of its own
        // Measurements of the model's own noise-free run from the initial mean.
        let (u, mut x, mut next, mut y) =
            (DVector::zeros(1), DVector::from_vec(vec![0.3, 0.0]), DVector::zeros(2), DVector::zeros(2));
        for k in 0..20 {
            model.f(&x, &u, &mut next).unwrap();
            x.copy_from(&next);
            model.h(&x, &u, &mut y).unwrap();
            let step = estimator.step(&model as &dyn AnyModel, &u, &y);
            assert!(step.is_ok(), "{} step {k}: {:?}", entry.name, step.err());
        }
        served.push(entry.name);
    }
    assert!(served.len() >= 2, "{served:?}");
}
