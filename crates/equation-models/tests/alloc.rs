//! Evaluations allocate nothing once a thread has evaluated the model (the scratch buffer is
//! per thread): `f`, `h`, their Jacobians and their interval enclosures over a box, for `[f]`,
//! Euler, RK4 and the zero-order hold.

use counting_allocator::{Counting, count};
use equation_models::EquationModel;
use models::{DifferentiableModel, DiscreteModel, Interval, SecondOrderModel, TaylorEnclosure};
use nalgebra::{DMatrix, DVector};

#[global_allocator]
static GLOBAL: Counting = Counting;

fn model(dynamics: &str, head: &str) -> EquationModel {
    let text = format!(
        "[model]\nstates = [\"p\", \"v\"]\ninputs = [\"u\"]\noutputs = [\"y\", \"w\"]\n{head}\n[definitions]\nd = \"atan2(v, 1 + p^2)\"\n{dynamics}\n[h]\ny = \"abs(p) + d\"\nw = \"max(v, u) * d\"\n"
    );
    EquationModel::from_toml_str(&text, "alloc.toml").unwrap()
}

#[test]
fn evaluations_allocate_nothing_after_the_first() {
    let vehicles = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/models");
    let truck = std::fs::read_to_string(vehicles.join("truck.toml")).unwrap();
    let truck = EquationModel::from_toml_str_with_foreign_keys(&truck, "truck.toml", &["x0", "p0", "q", "r"]).unwrap();
    let nonlinear = "[dxdt]\np = \"v\"\nv = \"-sin(p) - d * v + u\"";
    let models = [
        model("[f]\np = \"p + 0.1 * v\"\nv = \"v - 0.1 * sin(p) + u * d\"", ""),
        model(nonlinear, "ts = 0.1\ndiscretization = \"euler\""),
        model(nonlinear, "ts = 0.1\ndiscretization = \"rk4\""),
        model("[dxdt]\np = \"v\"\nv = \"-p - 0.2 * v + u\"", "ts = 0.1\ndiscretization = \"zoh\""),
        truck,
    ];
    for m in &models {
        let d = m.dims();
        let (n, mo) = (d.states, d.outputs);
        let x = DVector::from_fn(n, |i, _| 10.0 + 0.1 * i as f64);
        let u = DVector::from_fn(d.inputs, |i, _| if i == 0 { 0.01 } else { 20.0 });
        let (mut f, mut fj, mut h, mut hj) =
            (DVector::zeros(n), DMatrix::zeros(n, n), DVector::zeros(mo), DMatrix::zeros(mo, n));
        let boxed: Vec<Interval> = x.iter().map(|c| Interval::centered(*c, 0.01)).collect();
        let (mut fe, mut he) = (TaylorEnclosure::new(n, n), TaylorEnclosure::new(mo, n));
        let mut all = || {
            m.f(&x, &u, &mut f).unwrap();
            m.f_jacobian(&x, &u, &mut fj).unwrap();
            m.h(&x, &u, &mut h).unwrap();
            m.h_jacobian(&x, &u, &mut hj).unwrap();
            m.f_with_jacobian(&x, &u, &mut f, &mut fj).unwrap();
            m.h_with_jacobian(&x, &u, &mut h, &mut hj).unwrap();
            m.rhs(&x, &u, &mut f).unwrap();
            m.f_enclosure(&boxed, &u, &mut fe).unwrap();
            m.h_enclosure(&boxed, &u, &mut he).unwrap();
        };
        all();
        let ((), allocations) = count(&mut all);
        assert_eq!(allocations, 0, "{:?}", m.time_model());
    }
}
