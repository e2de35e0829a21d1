//! Interval enclosures of models written as equations (`SecondOrderModel`): at random points of
//! random boxes, `f`, `h` and their exact Jacobians lie in the box's enclosures — for the vessel
//! (Euler), the truck (Euler, Pacejka tyres with `atan2`, `abs`, `max`), the car (exact
//! zero-order hold), a pendulum (RK4) and CORA's six tanks (a discrete map); the value-only
//! enclosures are the full ones' values bit for bit; functions undefined on the box give
//! unbounded enclosures.

use equation_models::EquationModel;
use models::{AnyModel, DifferentiableModel, Interval, SecondOrderModel, TaylorEnclosure, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector};

const NOISE_KEYS: [&str; 10] = ["x0", "p0", "q", "r", "u_lower", "u_upper", "x_lower", "x_upper", "mhe", "ukf"];

fn vehicle(name: &str) -> EquationModel {
    let path = format!("{}/../../examples/models/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    EquationModel::from_toml_str_with_foreign_keys(&text, &path, &NOISE_KEYS).unwrap()
}

const PENDULUM: &str = include_str!("models/pendulum.toml");

/// Checks `model` on random boxes around `centre` with half-widths up to `spread`.
fn check(model: &EquationModel, centre: &[f64], spread: &[f64], u: &DVector<f64>, seed: u64) {
    let d = models::DiscreteModel::dims(model);
    let (n, m) = (d.states, d.outputs);
    let mut rng = Xoshiro256StarStar::seed_from_u64(seed);
    let (mut fe, mut he) = (TaylorEnclosure::new(n, n), TaylorEnclosure::new(m, n));
    let (mut f, mut h, mut jf, mut jh) =
        (DVector::zeros(n), DVector::zeros(m), DMatrix::zeros(n, n), DMatrix::zeros(m, n));
    for _ in 0..100 {
        let c: Vec<f64> = centre.iter().zip(spread).map(|(c, s)| c + rng.uniform(-s, *s)).collect();
        let r: Vec<f64> = spread.iter().map(|s| rng.uniform(0.0, *s)).collect();
        let boxed: Vec<Interval> = c.iter().zip(&r).map(|(c, r)| Interval::centered(*c, *r)).collect();
        model.f_enclosure(&boxed, u, &mut fe).unwrap();
        model.h_enclosure(&boxed, u, &mut he).unwrap();
        assert!(fe.is_bounded() && he.is_bounded(), "box {boxed:?}");
        // The value-only enclosures skip the derivatives, not a rounding.
        let (mut fv, mut hv) = (TaylorEnclosure::new(n, n), TaylorEnclosure::new(m, n));
        model.f_value_enclosure(&boxed, u, &mut fv).unwrap();
        model.h_value_enclosure(&boxed, u, &mut hv).unwrap();
        let bits = |v: Interval| (v.lo().to_bits(), v.hi().to_bits());
        assert!((0..n).all(|i| bits(fv.value(i)) == bits(fe.value(i))), "f values, box {boxed:?}");
        assert!((0..m).all(|i| bits(hv.value(i)) == bits(he.value(i))), "h values, box {boxed:?}");
        for _ in 0..10 {
            let x = DVector::from_fn(n, |i, _| c[i] + r[i] * rng.uniform(-1.0, 1.0));
            model.f_with_jacobian(&x, u, &mut f, &mut jf).unwrap();
            model.h_with_jacobian(&x, u, &mut h, &mut jh).unwrap();
            for i in 0..n {
                assert!(fe.value(i).contains(f[i]), "f{i} = {} not in {}", f[i], fe.value(i));
                for j in 0..n {
                    assert!(
                        fe.jacobian(i, j).contains(jf[(i, j)]),
                        "F{i}{j} = {} not in {}",
                        jf[(i, j)],
                        fe.jacobian(i, j)
                    );
                }
            }
            for i in 0..m {
                assert!(he.value(i).contains(h[i]), "h{i}");
                for j in 0..n {
                    assert!(he.jacobian(i, j).contains(jh[(i, j)]), "H{i}{j}");
                }
            }
        }
    }
}

#[test]
fn the_enclosures_contain_the_model_and_its_jacobians_at_every_point_of_the_box() {
    let vessel = vehicle("vessel");
    check(
        &vessel,
        &[10.0, -5.0, 0.3, 2.0, 0.2, 0.01],
        &[5.0, 5.0, 0.3, 0.5, 0.2, 0.02],
        &DVector::from_vec(vec![2e5, 5e4, 1e6]),
        1,
    );
    let truck = vehicle("truck");
    let mut u = DVector::from_element(7, 19.0 / 0.52);
    u[0] = 0.05;
    check(&truck, &[19.0, 0.1, 0.05], &[0.5, 0.1, 0.05], &u, 2);
    let car = vehicle("car");
    check(&car, &[0.5, 0.02, 0.01, 0.02], &[0.5, 0.05, 0.05, 0.05], &DVector::from_element(1, 0.02), 3);
    let pendulum = EquationModel::from_toml_str(PENDULUM, "pendulum.toml").unwrap();
    check(&pendulum, &[0.4, 0.0], &[0.2, 0.5], &DVector::from_element(1, 0.1), 4);
    let path = format!("{}/../../examples/six-tank/model.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let tanks = EquationModel::from_toml_str_with_foreign_keys(
        &text,
        &path,
        &[NOISE_KEYS.as_slice(), &["x0_radius", "w_radius", "v_radius", "estimator"]].concat(),
    )
    .unwrap();
    check(&tanks, &[20.0; 6], &[4.0; 6], &DVector::from_element(3, 0.1), 5);
    for model in [&vessel, &truck, &car, &pendulum, &tanks] {
        assert!(model.second_order().is_some());
    }
}

#[test]
fn a_function_undefined_on_the_box_gives_unbounded_enclosures() {
    let text = PENDULUM.replace("tip_x = \"0.8 * sin(theta)\"", "tip_x = \"sqrt(theta)\"");
    let model = EquationModel::from_toml_str(&text, "p.toml").unwrap();
    let mut he = TaylorEnclosure::new(2, 2);
    let u = DVector::from_element(1, 0.0);
    model.h_enclosure(&[Interval::new(-0.1, 0.1), Interval::point(0.0)], &u, &mut he).unwrap();
    assert!(!he.is_bounded());
    model.h_enclosure(&[Interval::new(0.1, 0.2), Interval::point(0.0)], &u, &mut he).unwrap();
    assert!(he.is_bounded());
    let text = PENDULUM.replace("tip_x = \"0.8 * sin(theta)\"", "tip_x = \"atan2(omega, theta)\"");
    let model = EquationModel::from_toml_str(&text, "p.toml").unwrap();
    // Across the cut (θ < 0, ω = 0): no bound.
    model.h_enclosure(&[Interval::new(-1.0, -0.5), Interval::new(-0.1, 0.1)], &u, &mut he).unwrap();
    assert!(!he.is_bounded());
    model.h_enclosure(&[Interval::new(0.5, 1.0), Interval::new(-0.1, 0.1)], &u, &mut he).unwrap();
    assert!(he.is_bounded());
}
