//! The nonlinear set-membership filter (`smf-nl`): equal to the linear filter on a linear model,
//! its remainder bound exact on a quadratic map (closed form), containment with every noise on the
//! boundary of its ellipsoid (the supply vessel and the quadratic map), honest refusals (a Hessian
//! unbounded on the set, bad data) that leave the filter unchanged; the truck through a slalom
//! (mean-value remainder: its slip ratio has a kink), and its refusal when `V_x` may be ≤ 0; declared
//! state bounds: the vessel with speed limits stays bounded where it grows without them, bounds that
//! do not cut the set change nothing, a set outside them is refused.

use estimators::{EstimatorError, NonlinearSetMembershipFilter, SetEstimate, SetMembershipFilter, Setup, registry};
use models::{
    AnyModel, ConstantModel, DifferentiableModel, Dims, DiscreteModel, Interval, ModelError, Noise, SecondOrderModel,
    TaylorEnclosure, Xoshiro256StarStar,
};
use nalgebra::{DMatrix, DVector, dvector};
use truck_dynamics::{Slalom, TruckEkfModel, TruckInput, TruckParams};
use vessel_dynamics::{DiscreteVessel, VesselParams};

/// `x⁺ = [x₀ + a x₁² + u, 0.9 x₁]`, `y = [x₀, x₁] (or 1/x₀ with `reciprocal`)`.
struct Quadratic {
    a: f64,
    reciprocal: bool,
}

impl DiscreteModel for Quadratic {
    fn dims(&self) -> Dims {
        Dims::new(2, 1, 2)
    }
    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = x[0] + self.a * x[1] * x[1] + u[0];
        out[1] = 0.9 * x[1];
        Ok(())
    }
    fn h(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = if self.reciprocal { 1.0 / x[0] } else { x[0] };
        out[1] = x[1];
        Ok(())
    }
}

impl DifferentiableModel for Quadratic {
    fn f_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        out.copy_from(&DMatrix::from_row_slice(2, 2, &[1.0, 2.0 * self.a * x[1], 0.0, 0.9]));
        Ok(())
    }
    fn h_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let d = if self.reciprocal { -1.0 / (x[0] * x[0]) } else { 1.0 };
        out.copy_from(&DMatrix::from_row_slice(2, 2, &[d, 0.0, 0.0, 1.0]));
        Ok(())
    }
}

impl SecondOrderModel for Quadratic {
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        out.clear();
        let a = Interval::point(self.a);
        out.set_value(0, x[0] + a * x[1].sqr() + u[0]);
        out.set_value(1, x[1] * 0.9);
        out.set_jacobian(0, 0, Interval::point(1.0));
        out.set_jacobian(0, 1, a * x[1] * 2.0);
        out.set_jacobian(1, 1, Interval::point(0.9));
        out.set_hessian(0, 1, 1, a * 2.0);
        Ok(())
    }
    fn h_enclosure(&self, x: &[Interval], _u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        out.clear();
        let one = Interval::point(1.0);
        if self.reciprocal {
            out.set_value(0, one / x[0]);
            out.set_jacobian(0, 0, -(one / x[0].sqr()));
            out.set_hessian(0, 0, 0, Interval::point(2.0) / (x[0] * x[0].sqr()));
        } else {
            out.set_value(0, x[0]);
            out.set_jacobian(0, 0, one);
        }
        out.set_value(1, x[1]);
        out.set_jacobian(1, 1, one);
        Ok(())
    }
}

impl AnyModel for Quadratic {
    fn discrete(&self) -> &dyn DiscreteModel {
        self
    }
    fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
        Some(self)
    }
    fn second_order(&self) -> Option<&dyn SecondOrderModel> {
        Some(self)
    }
}

/// `(x − x̂)ᵀ P⁻¹ (x − x̂)`.
fn distance(est: &SetEstimate, x: &DVector<f64>) -> f64 {
    distance_to(&est.center, &est.shape, x)
}

fn distance_to(center: &DVector<f64>, shape: &DMatrix<f64>, x: &DVector<f64>) -> f64 {
    let e = x - center;
    let chol = shape.clone().cholesky().expect("the published shape is positive definite");
    e.dot(&chol.solve(&e))
}

fn setup(x0: DVector<f64>, p0: DMatrix<f64>, q: DMatrix<f64>, r: DMatrix<f64>, inputs: usize) -> Setup {
    Setup { x0, p0, process_noise: q, measurement_noise: r, inputs }
}

#[test]
fn on_a_linear_model_it_is_the_linear_filter() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(3);
    for _ in 0..4 {
        let a = DMatrix::from_fn(3, 3, |i, j| if i == j { 0.95 } else { 0.1 * rng.uniform(-1.0, 1.0) });
        let b = DMatrix::from_fn(3, 1, |_, _| rng.uniform(-1.0, 1.0));
        let c = DMatrix::from_fn(2, 3, |_, _| rng.uniform(-1.0, 1.0));
        let model = ConstantModel::new(a, b, c).unwrap();
        let s = setup(
            DVector::zeros(3),
            DMatrix::identity(3, 3),
            DMatrix::identity(3, 3) * 0.01,
            DMatrix::identity(2, 2) * 0.1,
            1,
        );
        let mut linear = SetMembershipFilter::new(s.clone()).unwrap();
        let mut nonlinear = NonlinearSetMembershipFilter::new(s).unwrap();
        let w = Noise::ellipsoid_boundary(DMatrix::identity(3, 3) * 0.01).unwrap();
        let v = Noise::ellipsoid_boundary(DMatrix::identity(2, 2) * 0.1).unwrap();
        let mut x = DVector::from_vec(vec![0.5, -0.5, 0.2]);
        for k in 0..50 {
            let u = dvector![(0.1 * f64::from(k)).sin()];
            let mut next = DVector::zeros(3);
            model.f(&x, &u, &mut next).unwrap();
            x = next + w.sample(&mut rng);
            let mut y = DVector::zeros(2);
            model.h(&x, &u, &mut y).unwrap();
            y += v.sample(&mut rng);
            let l = linear.step(&model, &u, &y).unwrap().clone();
            let nl = nonlinear.step(&model, &u, &y).unwrap().clone();
            assert!(nonlinear.remainders().process.iter().all(|r| *r < 1e-12), "{:?}", nonlinear.remainders());
            let scale = l.shape.norm();
            assert!((&l.center - &nl.center).norm() <= 1e-12 * (1.0 + l.center.norm()), "step {k}");
            assert!((&l.shape - &nl.shape).norm() <= 1e-12 * scale, "step {k}");
            assert!(distance(&nl, &x) <= 1.0, "step {k}");
        }
    }
}

#[test]
fn the_remainder_bound_of_a_quadratic_map_is_its_exact_worst_case() {
    // f₀ = x₀ + a x₁² + u: the remainder about x̂ is a (x₁ − x̂₁)², whose largest value over the
    // set is a P₁₁ exactly; the bound (N2) is ½ · 2a · s₁² = a P₁₁ (to rounding).
    let model = Quadratic { a: 0.3, reciprocal: false };
    let p0 = DMatrix::from_row_slice(2, 2, &[0.5, 0.1, 0.1, 0.2]);
    let s = setup(dvector![1.0, 2.0], p0.clone(), DMatrix::identity(2, 2) * 1e-4, DMatrix::identity(2, 2) * 1e-2, 1);
    let mut f = NonlinearSetMembershipFilter::new(s).unwrap();
    f.predict(&model, &dvector![0.0]).unwrap();
    let rho = f.remainders().process[0];
    let exact = 0.3 * p0[(1, 1)];
    assert!(rho >= exact && rho <= exact * (1.0 + 1e-12), "ρ = {rho}, exact {exact}");
    assert!(f.remainders().process[1] < 1e-15);
}

#[test]
fn the_set_contains_the_truth_with_every_noise_on_its_boundary() {
    // The quadratic map (a strong nonlinearity for its noise) and the supply vessel.
    let quadratic = Quadratic { a: 0.2, reciprocal: false };
    let (q, r) = (DMatrix::identity(2, 2) * 1e-3, DMatrix::identity(2, 2) * 1e-2);
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let vq = DMatrix::from_diagonal(&dvector![1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6]);
    let vr = DMatrix::from_diagonal(&dvector![1.0, 1.0, 1e-2]);
    let cases: [(&dyn AnyModel, Setup, usize); 2] = [
        (&quadratic, setup(dvector![0.0, 1.0], DMatrix::identity(2, 2) * 0.1, q, r, 1), 400),
        (
            &vessel,
            setup(DVector::zeros(6), DMatrix::from_diagonal(&dvector![4.0, 4.0, 0.01, 0.01, 0.01, 1e-4]), vq, vr, 3),
            600,
        ),
    ];
    let mut steps = 0;
    for (seed, (model, s, horizon)) in cases.into_iter().enumerate() {
        let (n, p) = (s.x0.len(), s.inputs);
        let mut rng = Xoshiro256StarStar::seed_from_u64(seed as u64 + 10);
        let w = Noise::ellipsoid_boundary(s.process_noise.clone()).unwrap();
        let v = Noise::ellipsoid_boundary(s.measurement_noise.clone()).unwrap();
        let x0 = Noise::ellipsoid_boundary(s.p0.clone()).unwrap();
        let mut x = &s.x0 + x0.sample(&mut rng);
        let mut est = registry::build(registry::names::SMF_NL, s, None).unwrap();
        for k in 0..horizon {
            let t = k as f64 * 0.1;
            let u = DVector::from_fn(p, |i, _| {
                if p == 1 { 0.05 * t.sin() } else { [2e5, 5e4, 1e6][i] * (t / (5.0 + i as f64)).sin() }
            });
            let mut next = DVector::zeros(n);
            model.discrete().f(&x, &u, &mut next).unwrap();
            x = next + w.sample(&mut rng);
            let mut y = DVector::zeros(model.discrete().dims().outputs);
            model.discrete().h(&x, &u, &mut y).unwrap();
            y += v.sample(&mut rng);
            est.step(model, &u, &y).unwrap_or_else(|e| panic!("case {seed}, step {k}: {e}"));
            let d = distance_to(est.estimate().center(), est.estimate().shape(), &x);
            assert!(d <= 1.0, "case {seed}, step {k}: the truth is at distance {d} (> 1)");
            steps += 1;
        }
    }
    assert_eq!(steps, 1000);
}

#[test]
fn a_hessian_unbounded_on_the_set_is_refused_and_the_filter_is_unchanged() {
    // h = 1/x₀ over a predicted set that holds x₀ = 0: no bound exists.
    let model = Quadratic { a: 0.0, reciprocal: true };
    let s = setup(
        dvector![0.5, 0.0],
        DMatrix::identity(2, 2),
        DMatrix::identity(2, 2) * 1e-2,
        DMatrix::identity(2, 2) * 1e-2,
        1,
    );
    let mut f = NonlinearSetMembershipFilter::new(s).unwrap();
    let before = f.estimate().clone();
    let e = f.step(&model, &dvector![0.0], &dvector![2.0, 0.0]).unwrap_err();
    assert!(matches!(e, EstimatorError::GuaranteeLost { step: 1, .. }), "{e}");
    assert!(e.to_string().contains("Hessian of h is unbounded"), "{e}");
    assert_eq!(f.estimate().center, before.center);
    assert_eq!(f.estimate().shape, before.shape);
    // Bad data: unchanged too; then a step on a set away from 0 succeeds.
    assert!(f.step(&model, &dvector![0.0], &dvector![f64::NAN, 0.0]).is_err());
    assert_eq!(f.estimate().shape, before.shape);
    let s = setup(
        dvector![5.0, 0.0],
        DMatrix::identity(2, 2) * 0.01,
        DMatrix::identity(2, 2) * 1e-4,
        DMatrix::identity(2, 2) * 1e-4,
        1,
    );
    let mut f = NonlinearSetMembershipFilter::new(s).unwrap();
    f.step(&model, &dvector![0.0], &dvector![0.2, 0.0]).unwrap();
    assert!(f.remainders().measurement[0] > 0.0);
}

#[test]
fn predict_then_update_is_the_step_when_h_is_linear() {
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let s = setup(
        DVector::zeros(6),
        DMatrix::identity(6, 6),
        DMatrix::identity(6, 6) * 1e-2,
        DMatrix::from_diagonal(&dvector![1.0, 1.0, 0.1]),
        3,
    );
    let (mut a, mut b) =
        (NonlinearSetMembershipFilter::new(s.clone()).unwrap(), NonlinearSetMembershipFilter::new(s).unwrap());
    let u = dvector![1e5, 0.0, 1e5];
    for k in 0..20 {
        let y = dvector![0.01 * f64::from(k), 0.0, 0.001];
        let one = a.step(&vessel, &u, &y).unwrap().clone();
        b.predict(&vessel, &u).unwrap();
        let two = b.update(&vessel, &y).unwrap();
        assert_eq!(one.center, two.center, "step {k}");
        assert_eq!(one.shape, two.shape, "step {k}");
    }
}

/// The truck's filter settings (the reproduction's EKF, digest §4): `Q = T·diag(q_c)`,
/// `R = diag(σ²)`, `P0 = diag(σ0²)`, here the shapes of the noise ellipsoids.
fn truck_setup(ts: f64, p0: [f64; 3]) -> Setup {
    let d = |v: [f64; 3]| DMatrix::from_diagonal(&DVector::from_row_slice(&v));
    setup(
        dvector![19.44, 0.0, 0.0],
        d(p0.map(|s| s * s)),
        d([1e-4 * ts, 1e-4 * ts, 1e-6 * ts]),
        d([0.05f64.powi(2), 0.05f64.powi(2), 0.002f64.powi(2)]),
        7,
    )
}

#[test]
fn the_truck_set_contains_the_truth_through_a_slalom_with_every_noise_on_its_boundary() {
    // The truth is the filter's model (what the guarantee covers), driven by a fast slalom with
    // drive slip on the rear axles and brake slip on the front axle.
    let model = TruckEkfModel::paper(TruckParams::digest_preset()).unwrap();
    let re = model.planar().params().rolling_radius;
    let s = truck_setup(model.ts(), [0.1, 0.1, 0.01]);
    let slalom =
        Slalom { start: 0.0, frequency: 2.0, first_amplitude: 1.5f64.to_radians(), amplitude: 3f64.to_radians() };
    let mut rng = Xoshiro256StarStar::seed_from_u64(21);
    let w = Noise::ellipsoid_boundary(s.process_noise.clone()).unwrap();
    let v = Noise::ellipsoid_boundary(s.measurement_noise.clone()).unwrap();
    let mut x = &s.x0 + Noise::ellipsoid_boundary(s.p0.clone()).unwrap().sample(&mut rng);
    let mut est = registry::build(registry::names::SMF_NL, s, None).unwrap();
    let (mut next, mut y) = (DVector::zeros(3), DVector::zeros(3));
    let mut widest_beta: f64 = 0.0;
    for k in 0..300 {
        let mut input = TruckInput::free_rolling(slalom.angle(k as f64 * model.ts()), x[0], re);
        input.omega[..2].iter_mut().for_each(|o| *o *= 0.998);
        input.omega[2..].iter_mut().for_each(|o| *o *= 1.003);
        let u = input.to_dvector();
        model.f(&x, &u, &mut next).unwrap();
        x = &next + w.sample(&mut rng);
        model.h(&x, &u, &mut y).unwrap();
        y += v.sample(&mut rng);
        est.step(&model, &u, &y).unwrap_or_else(|e| panic!("step {k}: {e}"));
        let (c, p) = (est.estimate().center(), est.estimate().shape());
        let d = distance_to(c, p, &x);
        assert!(d <= 1.0, "step {k}: the truth is at distance {d} (> 1)");
        // The certified sideslip interval atan(V_y box / V_x box) holds the truth's.
        let b = |i: usize| Interval::centered(c[i], p[(i, i)].sqrt() * (1.0 + 1e-12));
        let beta = (b(1) / b(0)).atan();
        assert!(beta.contains((x[1] / x[0]).atan()), "step {k}");
        widest_beta = widest_beta.max(beta.width());
    }
    assert!(widest_beta < 0.1, "the certified β interval reached {widest_beta} rad");
}

#[test]
fn a_truck_set_that_may_hold_v_x_le_0_is_refused_and_the_filter_is_unchanged() {
    // V_x ∈ 19.44 ± 25 on the set's box: the slip angle divides by the wheel's speed, so the
    // enclosure of f is unbounded and no bound of the remainder exists.
    let model = TruckEkfModel::paper(TruckParams::digest_preset()).unwrap();
    let mut f = NonlinearSetMembershipFilter::new(truck_setup(model.ts(), [25.0, 0.1, 0.01])).unwrap();
    let before = f.estimate().clone();
    let u = TruckInput::free_rolling(0.01, 19.44, model.planar().params().rolling_radius).to_dvector();
    let e = f.step(&model, &u, &dvector![19.44, 0.0, 0.0]).unwrap_err();
    assert!(matches!(e, EstimatorError::GuaranteeLost { step: 1, .. }), "{e}");
    assert!(e.to_string().contains("Jacobian or Hessian of f is unbounded"), "{e}");
    assert_eq!((&f.estimate().center, &f.estimate().shape), (&before.center, &before.shape));
    // A set away from V_x = 0 steps on.
    let mut f = NonlinearSetMembershipFilter::new(truck_setup(model.ts(), [0.1, 0.1, 0.01])).unwrap();
    f.step(&model, &u, &dvector![19.44, 0.0, 0.0]).unwrap();
    assert!(f.remainders().process.iter().all(|r| *r > 0.0 && *r < 1e-3), "{:?}", f.remainders());
}

/// The supply vessel's setup of the reproduction, its heading `psi0`.
fn vessel_setup(psi0: f64) -> Setup {
    let q = DMatrix::from_diagonal(&dvector![1e-2, 1e-2, 1e-4, 1e-4, 1e-4, 1e-6]);
    let r = DMatrix::from_diagonal(&dvector![1.0, 1.0, 1e-2]);
    let p0 = DMatrix::from_diagonal(&dvector![4.0, 4.0, 0.01, 0.01, 0.01, 1e-4]);
    setup(dvector![0.0, 0.0, psi0, 0.0, 0.0, 0.0], p0, q, r, 3)
}

#[test]
fn speed_limits_keep_the_vessel_set_from_growing_and_it_still_contains_the_truth() {
    // At an oblique heading the unbounded velocity interval feeds the kinematics' remainder,
    // which feeds the velocity interval (docs/nonlinear-smf.md, "The vessel"); declared speed
    // limits (N1') cut the loop. Every noise on its boundary; both filters on the same data.
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let s = vessel_setup(std::f64::consts::FRAC_PI_4);
    let limits = [2.0, 2.0, 0.1];
    let inf = f64::INFINITY;
    let mut bounded = NonlinearSetMembershipFilter::new(s.clone())
        .unwrap()
        .with_state_bounds(&[-inf, -inf, -inf, -2.0, -2.0, -0.1], &[inf, inf, inf, 2.0, 2.0, 0.1])
        .unwrap();
    let mut free = NonlinearSetMembershipFilter::new(s.clone()).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(31);
    let w = Noise::ellipsoid_boundary(s.process_noise.clone()).unwrap();
    let v = Noise::ellipsoid_boundary(s.measurement_noise.clone()).unwrap();
    let mut x = &s.x0 + Noise::ellipsoid_boundary(s.p0.clone()).unwrap().sample(&mut rng);
    let (mut next, mut y) = (DVector::zeros(6), DVector::zeros(3));
    for k in 0..400 {
        let t = k as f64 * vessel.ts();
        let u = DVector::from_fn(3, |i, _| [2e5, 5e4, 1e6][i] * (t / (5.0 + i as f64)).sin());
        vessel.f(&x, &u, &mut next).unwrap();
        x = &next + w.sample(&mut rng);
        vessel.h(&x, &u, &mut y).unwrap();
        y += v.sample(&mut rng);
        assert!((0..3).all(|j| x[3 + j].abs() <= limits[j]), "step {k}: the truth breaks the speed limits");
        for (name, f) in [("bounded", &mut bounded), ("free", &mut free)] {
            let est = f.step(&vessel, &u, &y).unwrap_or_else(|e| panic!("{name}, step {k}: {e}"));
            let d = distance(est, &x);
            assert!(d <= 1.0, "{name}, step {k}: the truth is at distance {d} (> 1)");
        }
    }
    let width = |f: &NonlinearSetMembershipFilter| 2.0 * f.estimate().shape[(0, 0)].sqrt();
    let (wb, wf) = (width(&bounded), width(&free));
    // Measured: 3.85 m with the limits (the linear filter at rest: 3.3 m), 26.8 m without.
    assert!(wb < 5.0, "x width with the speed limits {wb} m");
    assert!(wf > 3.0 * wb, "x width without them {wf} m, with them {wb} m");
    assert!(bounded.remainders().process[0] < 0.2 * free.remainders().process[0]);
}

#[test]
fn state_bounds_that_do_not_cut_the_set_change_nothing_and_a_set_outside_them_is_refused() {
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let s = vessel_setup(0.3);
    let far = NonlinearSetMembershipFilter::new(s.clone()).unwrap();
    let mut far = far.with_state_bounds(&[-1e9; 6], &[1e9; 6]).unwrap();
    let mut plain = NonlinearSetMembershipFilter::new(s).unwrap();
    let u = dvector![1e5, 0.0, 0.0];
    for k in 0..20 {
        let y = dvector![0.01 * k as f64, 0.0, 0.3];
        let a = far.step(&vessel, &u, &y).unwrap().clone();
        let b = plain.step(&vessel, &u, &y).unwrap();
        assert_eq!(a.center, b.center, "step {k}");
        assert_eq!(a.shape, b.shape, "step {k}");
    }
    // A set about x₁ = 1 (±0.32) against the bound x₁ ∈ [5, 6].
    let model = Quadratic { a: 0.2, reciprocal: false };
    let s = setup(
        dvector![0.0, 1.0],
        DMatrix::identity(2, 2) * 0.1,
        DMatrix::identity(2, 2) * 1e-3,
        DMatrix::identity(2, 2) * 1e-2,
        1,
    );
    let mut f =
        NonlinearSetMembershipFilter::new(s.clone()).unwrap().with_state_bounds(&[-1.0, 5.0], &[1.0, 6.0]).unwrap();
    let before = f.estimate().clone();
    let e = f.step(&model, &dvector![0.0], &dvector![0.0, 0.9]).unwrap_err();
    assert!(
        matches!(e, EstimatorError::OutsideStateBounds { step: 1, state: 1, bound_lower: 5.0, bound_upper: 6.0, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("state 1"), "{e}");
    assert_eq!(f.estimate().center, before.center);
    assert_eq!(f.estimate().shape, before.shape);
    // Bad bounds.
    let new = || NonlinearSetMembershipFilter::new(s.clone()).unwrap();
    let e = new().with_state_bounds(&[0.0], &[1.0]).unwrap_err();
    assert!(
        matches!(e, EstimatorError::DimensionMismatch { what: "state lower bounds", expected: 2, found: 1 }),
        "{e}"
    );
    let e = new().with_state_bounds(&[0.0, 2.0], &[1.0, 1.0]).unwrap_err();
    assert!(matches!(e, EstimatorError::InvalidSetting { what: "state lower bound", value: 2.0, .. }), "{e}");
    let e = new().with_state_bounds(&[0.0, 0.0], &[1.0, f64::NAN]).unwrap_err();
    assert!(matches!(e, EstimatorError::InvalidSetting { what: "state upper bound", .. }), "{e}");
    let e = new().with_state_bounds(&[f64::INFINITY, 0.0], &[f64::INFINITY, 1.0]).unwrap_err();
    assert!(matches!(e, EstimatorError::InvalidSetting { .. }), "{e}");
}

#[test]
fn the_interval_observer_cuts_the_interval_and_refuses_contradicting_data() {
    use estimators::checks::InconsistencyPolicy;
    use estimators::{DataCheck, DataChecks, Estimate, Guarantee};
    // x₂ drifts unmeasured, x₁ measured to ±0.1 (box around V): the published x₁ interval is the
    // measurement's strip met with the prediction, narrower than the ellipsoid's projection.
    let model = models::ConstantModel::new(
        DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.0, 1.0]),
        DMatrix::zeros(2, 1),
        DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
    )
    .unwrap();
    let setup = Setup {
        x0: dvector![0.0, 0.0],
        p0: DMatrix::identity(2, 2),
        process_noise: DMatrix::from_diagonal(&dvector![1e-4, 1e-4]),
        measurement_noise: DMatrix::identity(1, 1) * 1e-2,
        inputs: 1,
    };
    let mut f = NonlinearSetMembershipFilter::new(setup.clone()).unwrap();
    for k in 0..50 {
        let e = f.step(&model, &dvector![0.0], &dvector![0.05 * (k as f64 * 0.3).sin()]).unwrap();
        let r = e.shape[(0, 0)].sqrt();
        let (l, h) = e.bounds(0).unwrap();
        assert!(l >= e.center[0] - r * (1.0 + 1e-12) && h <= e.center[0] + r * (1.0 + 1e-12), "step {k}");
        assert!(h - l <= 0.2 + 1e-12, "step {k}: x₁ width {} beyond the strip's 0.2", h - l);
    }
    // A measurement 5 units off: the observer proves it contradicts the box and V; refused (the
    // default policy), the filter unchanged.
    let before = f.estimate().clone();
    let err = f.step(&model, &dvector![0.0], &dvector![5.0]).unwrap_err();
    assert!(matches!(err, EstimatorError::SetMissed { step: 51, .. }), "{err}");
    assert_eq!(f.estimate().center, before.center);
    assert_eq!((&f.estimate().lower, &f.estimate().upper), (&before.lower, &before.upper));
    // Flagged instead: published, marked inconsistent, no longer guaranteed (nor later).
    f.set_data_checks(DataChecks::with_policy(InconsistencyPolicy::FlagAndContinue)).unwrap();
    let e = f.step(&model, &dvector![0.0], &dvector![5.0]).unwrap();
    assert_eq!(e.status().data, DataCheck::Inconsistent);
    assert_eq!(e.status().guarantee, Guarantee::Lost);
    let e = f.step(&model, &dvector![0.0], &dvector![0.0]).unwrap();
    assert_eq!(e.status().guarantee, Guarantee::Lost);
}
