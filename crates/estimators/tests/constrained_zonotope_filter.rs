//! The constrained-zonotope filter (`czf`): on a linear model its interval is the exact set's
//! (an independent polygon computation) before any reduction; with every noise on the boundary
//! of its box the truth stays inside on a nonlinear pendulum and on the supply vessel (heading
//! measured), where `smf-nl` grows; contradicting data are refused with the filter unchanged, or
//! flagged; an undefined model is `GuaranteeLost`; an unmeasured random walk is marked diverging (by
//! the ellipsoid filter too).

use constrained_zonotope::polygon::{bbox, box_poly, map_poly, strip, sum_poly};
use estimators::checks::InconsistencyPolicy;
use estimators::{
    ConstrainedZonotopeFilter, ConstrainedZonotopeSettings, DataCheck, DataChecks, Estimate, EstimatorError, Guarantee,
    NonlinearSetMembershipFilter, Setup,
};
use models::{
    ConstantModel, DifferentiableModel, Dims, DiscreteModel, Interval, ModelError, SecondOrderModel, TaylorEnclosure,
    Xoshiro256StarStar,
};
use nalgebra::{DMatrix, DVector, dmatrix, dvector};
use vessel_dynamics::{DiscreteVessel, VesselParams};

/// A pendulum: `θ⁺ = θ + dt ω`, `ω⁺ = ω − dt (g sin θ) + dt u`, the angle measured.
struct Pendulum {
    dt: f64,
    /// `√θ` in `h` instead of `θ` (undefined for θ < 0).
    root: bool,
}

impl DiscreteModel for Pendulum {
    fn dims(&self) -> Dims {
        Dims::new(2, 1, 1)
    }
    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = x[0] + self.dt * x[1];
        out[1] = x[1] - self.dt * 9.81 * x[0].sin() + self.dt * u[0];
        Ok(())
    }
    fn h(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        out[0] = if self.root { x[0].sqrt() } else { x[0] };
        Ok(())
    }
}

impl DifferentiableModel for Pendulum {
    fn f_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        out.copy_from(&dmatrix![1.0, self.dt; -self.dt * 9.81 * x[0].cos(), 1.0]);
        Ok(())
    }
    fn h_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        out[(0, 0)] = if self.root { 0.5 / x[0].sqrt() } else { 1.0 };
        out[(0, 1)] = 0.0;
        Ok(())
    }
}

impl SecondOrderModel for Pendulum {
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        out.clear();
        let dt = self.dt;
        out.set_value(0, x[0] + x[1] * dt);
        out.set_value(1, x[1] - x[0].sin() * (dt * 9.81) + Interval::point(dt) * u[0]);
        out.set_jacobian(0, 0, Interval::point(1.0));
        out.set_jacobian(0, 1, Interval::point(dt));
        out.set_jacobian(1, 0, x[0].cos() * (-dt * 9.81));
        out.set_jacobian(1, 1, Interval::point(1.0));
        out.set_hessian_invalid();
        Ok(())
    }
    fn h_enclosure(&self, x: &[Interval], _u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        out.clear();
        if self.root {
            out.set_value(0, x[0].sqrt());
            out.set_jacobian(0, 0, Interval::point(0.5) / x[0].sqrt());
        } else {
            out.set_value(0, x[0]);
            out.set_jacobian(0, 0, Interval::point(1.0));
        }
        out.set_hessian_invalid();
        Ok(())
    }
}

fn boxes(x0: DVector<f64>, p0: &[f64], q: &[f64], r: &[f64], inputs: usize) -> Setup {
    Setup {
        x0,
        p0: DMatrix::from_diagonal(&DVector::from_column_slice(p0)),
        process_noise: DMatrix::from_diagonal(&DVector::from_column_slice(q)),
        measurement_noise: DMatrix::from_diagonal(&DVector::from_column_slice(r)),
        inputs,
    }
}

/// A vertex of the box of radii `r`: every noise on the boundary.
fn vertex(rng: &mut Xoshiro256StarStar, r: &[f64]) -> DVector<f64> {
    DVector::from_iterator(r.len(), r.iter().map(|r| if rng.uniform(-1.0, 1.0) < 0.0 { -r } else { *r }))
}

fn inside(e: &dyn Estimate, x: &DVector<f64>) -> bool {
    (0..x.len()).all(|i| e.bounds(i).is_some_and(|(l, h)| l <= x[i] && x[i] <= h))
}

#[test]
fn on_a_linear_model_the_interval_is_the_exact_set_s() {
    // x⁺ = A x + B u + w, y = c x + v, boxes; no reduction in 5 steps at order 50: the published
    // interval is the bounding box of the exact polygon (sound, and tight to the solver's 1e-7).
    let a = dmatrix![0.95, 0.2; -0.15, 0.9];
    let b = dmatrix![0.1; 0.05];
    let c = dmatrix![1.0, -0.5];
    let model = ConstantModel::new(a.clone(), b.clone(), c.clone()).unwrap();
    let s = boxes(dvector![0.5, -0.2], &[1.0, 0.8], &[0.05, 0.02], &[0.1], 1);
    let settings = ConstrainedZonotopeSettings { order: 50, max_constraints: 20, ..Default::default() };
    let mut f = ConstrainedZonotopeFilter::new(s, settings).unwrap();
    let mut poly = box_poly([0.5, -0.2], [1.0, 0.8]);
    let mut rng = Xoshiro256StarStar::seed_from_u64(5);
    let mut x = dvector![0.5 + 0.9, -0.2 - 0.7];
    for k in 0..5 {
        let u = dvector![rng.uniform(-1.0, 1.0)];
        x = &a * &x + &b * &u + vertex(&mut rng, &[0.05, 0.02]);
        let y = &c * &x + vertex(&mut rng, &[0.1]);
        let e = f.step(&model, &u, &y).unwrap();
        poly = sum_poly(&map_poly(&a, [b[0] * u[0], b[1] * u[0]], &poly), &box_poly([0.0, 0.0], [0.05, 0.02]));
        poly = strip(&poly, [c[0], c[1]], y[0], 0.1);
        let (lo, hi) = bbox(&poly);
        for i in 0..2 {
            let (l, h) = e.bounds(i).unwrap();
            assert!(l <= lo[i] && h >= hi[i], "step {k}, state {i}: [{l}, {h}] misses [{}, {}]", lo[i], hi[i]);
            assert!(
                lo[i] - l < 1e-7 && h - hi[i] < 1e-7,
                "step {k}, state {i}: [{l}, {h}] wider than [{}, {}]",
                lo[i],
                hi[i]
            );
        }
        assert!(inside(e, &x));
        assert!(e.status().is_clean(), "{}", e.status());
    }
}

#[test]
fn the_pendulum_s_truth_stays_inside_with_noise_on_the_boundary() {
    let model = Pendulum { dt: 0.05, root: false };
    let (q, r) = ([0.002, 0.01], [0.02]);
    // The default order, and order 1 with no constraints (a box between steps, (C6)).
    let box_between_steps = ConstrainedZonotopeSettings { order: 1, max_constraints: 0, ..Default::default() };
    for settings in [ConstrainedZonotopeSettings::default(), box_between_steps] {
        let s = boxes(dvector![0.3, 0.0], &[0.5, 1.0], &q, &r, 1);
        let order = settings.order;
        let mut f = ConstrainedZonotopeFilter::new(s, settings).unwrap();
        let mut rng = Xoshiro256StarStar::seed_from_u64(11);
        let mut x = dvector![0.3 + 0.5, -1.0];
        let mut next = DVector::zeros(2);
        let mut y = DVector::zeros(1);
        let mut widths = Vec::new();
        for k in 0..3000 {
            let u = dvector![2.0 * (k as f64 * 0.01).sin()];
            model.f(&x, &u, &mut next).unwrap();
            x = &next + vertex(&mut rng, &q);
            model.h(&x, &u, &mut y).unwrap();
            y += vertex(&mut rng, &r);
            let e = f.step(&model, &u, &y).unwrap_or_else(|e| panic!("order {order}, step {k}: {e}"));
            assert!(
                inside(e, &x),
                "order {order}, step {k}: {x} outside {:?}",
                (0..2).map(|i| e.bounds(i)).collect::<Vec<_>>()
            );
            assert_eq!(e.status().data, DataCheck::Consistent);
            widths.push(e.bounds(1).map(|(l, h)| h - l).unwrap());
        }
        // Bounded: the angular rate's width at the end no more than twice its width early on.
        let early = widths[500..1000].iter().copied().fold(0.0, f64::max);
        let late = widths[2500..].iter().copied().fold(0.0, f64::max);
        assert!(late <= 2.0 * early, "order {order}: rate width grew from {early} to {late}");
    }
}

#[test]
fn the_vessel_stays_bounded_where_the_ellipsoid_filter_grows() {
    let vessel = DiscreteVessel::paper(VesselParams::paper()).unwrap();
    let q = [0.1, 0.1, 0.01, 0.01, 0.01, 0.001];
    let r = [1.0, 1.0, 0.1];
    let psi0 = std::f64::consts::FRAC_PI_4;
    let s = boxes(dvector![0.0, 0.0, psi0, 0.0, 0.0, 0.0], &[2.0, 2.0, 0.1, 0.1, 0.1, 0.01], &q, &r, 3);
    let settings = ConstrainedZonotopeSettings { order: 4, max_constraints: 6, ..Default::default() };
    let mut f = ConstrainedZonotopeFilter::new(s, settings).unwrap();
    // The ellipsoid filter with the least-trace ellipsoids of the same boxes (d·diag(h²)).
    let ell = |h: &[f64]| DMatrix::from_diagonal(&DVector::from_iterator(h.len(), h.iter().map(|h| 6.0 * h * h)));
    let es = Setup {
        x0: dvector![0.0, 0.0, psi0, 0.0, 0.0, 0.0],
        p0: ell(&[2.0, 2.0, 0.1, 0.1, 0.1, 0.01]),
        process_noise: ell(&q),
        measurement_noise: DMatrix::from_diagonal(&DVector::from_iterator(3, r.iter().map(|h| 3.0 * h * h))),
        inputs: 3,
    };
    let mut smf = NonlinearSetMembershipFilter::new(es).unwrap();
    let mut rng = Xoshiro256StarStar::seed_from_u64(31);
    let mut x = dvector![1.5, -1.5, psi0 + 0.08, 0.05, -0.05, 0.005];
    let (mut next, mut y) = (DVector::zeros(6), DVector::zeros(3));
    let mut smf_alive = true;
    for k in 0..300 {
        let t = k as f64 * vessel.ts();
        let u = DVector::from_fn(3, |i, _| [2e5, 5e4, 1e6][i] * (t / (5.0 + i as f64)).sin());
        vessel.f(&x, &u, &mut next).unwrap();
        x = &next + vertex(&mut rng, &q);
        vessel.h(&x, &u, &mut y).unwrap();
        y += vertex(&mut rng, &r);
        let e = f.step(&vessel, &u, &y).unwrap_or_else(|e| panic!("step {k}: {e}"));
        assert!(inside(e, &x), "step {k}: the truth is outside");
        if smf_alive {
            smf_alive = smf.step(&vessel, &u, &y).is_ok();
        }
    }
    let w = |i: usize| f.estimate().bounds(i).map(|(l, h)| h - l).unwrap();
    // The position within a few metres of the measurement's ±1 m, the heading within ±0.1 rad.
    assert!(w(0) < 2.5 && w(1) < 2.5 && w(2) < 0.25, "widths {} {} {}", w(0), w(1), w(2));
    // Measured: czf-nl 0.73 m, smf-nl (on the least-trace ellipsoids of the same boxes) 47 m.
    let ws = 2.0 * smf.estimate().shape[(0, 0)].sqrt();
    assert!(smf_alive, "smf-nl stopped on this run");
    assert!(ws > 10.0 * w(0), "smf-nl's x width {ws} against czf-nl's {}", w(0));
}

#[test]
fn contradicting_data_are_refused_and_leave_the_filter_unchanged() {
    let model = ConstantModel::new(dmatrix![1.0, 0.1; 0.0, 1.0], dmatrix![0.0; 0.1], dmatrix![1.0, 0.0]).unwrap();
    let s = boxes(dvector![0.0, 0.0], &[1.0, 1.0], &[0.01, 0.01], &[0.1], 1);
    // The default order, and order 1 without constraints (a box between steps, (C6)).
    let box_between_steps = ConstrainedZonotopeSettings { order: 1, max_constraints: 0, ..Default::default() };
    for settings in [ConstrainedZonotopeSettings::default(), box_between_steps] {
        let mut f = ConstrainedZonotopeFilter::new(s.clone(), settings).unwrap();
        let u = dvector![0.0];
        f.step(&model, &u, &dvector![0.3]).unwrap();
        let before = (f.estimate().lower().clone(), f.estimate().upper().clone(), f.estimate().set().clone());
        // 1.3 + 0.1 cannot be reached: the prediction's x₁ is at most ≈ 0.55.
        let err = f.step(&model, &u, &dvector![5.0]).unwrap_err();
        assert!(matches!(err, EstimatorError::SetMissed { step: 2, .. }), "{err}");
        assert_eq!((f.estimate().lower().clone(), f.estimate().upper().clone(), f.estimate().set().clone()), before);
        // The measurement on the edge of the reachable set is accepted.
        let e = f.step(&model, &u, &dvector![0.3]).unwrap();
        assert!(e.status().is_clean());
        // Flagged: the prediction is published, marked inconsistent and no longer guaranteed.
        f.set_data_checks(DataChecks::with_policy(InconsistencyPolicy::FlagAndContinue)).unwrap();
        let e = f.step(&model, &u, &dvector![5.0]).unwrap();
        assert_eq!(e.status().data, DataCheck::Inconsistent);
        assert_eq!(e.status().guarantee, Guarantee::Lost);
        // The set kept holds the published prediction (at order 1, that box itself).
        let (lo, hi) = e.set().zonotope_hull();
        assert!((0..2).all(|i| lo[i] <= e.lower()[i] && hi[i] >= e.upper()[i]));
        let e = f.step(&model, &u, &dvector![0.3]).unwrap();
        assert_eq!(e.status().guarantee, Guarantee::Lost, "every later set is not guaranteed");
    }
}

#[test]
fn an_undefined_model_loses_the_guarantee_and_bad_input_is_refused() {
    // h = √θ over a set that reaches θ < 0: no enclosure, GuaranteeLost, the filter unchanged.
    let model = Pendulum { dt: 0.05, root: true };
    let s = boxes(dvector![0.1, 0.0], &[0.5, 0.1], &[0.001, 0.001], &[0.01], 1);
    let mut f = ConstrainedZonotopeFilter::new(s.clone(), ConstrainedZonotopeSettings::default()).unwrap();
    let before = f.estimate().lower().clone();
    let err = f.step(&model, &dvector![0.0], &dvector![0.3]).unwrap_err();
    assert!(matches!(err, EstimatorError::GuaranteeLost { .. }), "{err}");
    assert_eq!(f.estimate().lower(), &before);
    let model = Pendulum { dt: 0.05, root: false };
    assert!(matches!(f.step(&model, &dvector![f64::NAN], &dvector![0.3]), Err(EstimatorError::NonFinite { .. })));
    assert!(matches!(
        f.step(&model, &dvector![0.0], &dvector![0.3, 1.0]),
        Err(EstimatorError::DimensionMismatch { .. })
    ));
    for (order, nc, factor) in [(0, 0, 2.0), (1, 8, 2.0), (201, 0, 2.0), (20, 0, 1.0), (20, 0, f64::NAN)] {
        let settings =
            ConstrainedZonotopeSettings { order, max_constraints: nc, divergence_factor: factor, ..Default::default() };
        assert!(matches!(
            ConstrainedZonotopeFilter::new(s.clone(), settings),
            Err(EstimatorError::InvalidSetting { .. })
        ));
    }
    // State bounds: ±∞ on its own side means "none" (as in model files); NaN, empty ranges and a
    // bound that excludes every number are refused.
    let inf = f64::INFINITY;
    let with = |lo: [f64; 2], hi: [f64; 2]| ConstrainedZonotopeSettings {
        state_bounds: Some((DVector::from_column_slice(&lo), DVector::from_column_slice(&hi))),
        ..Default::default()
    };
    let mut bounded = ConstrainedZonotopeFilter::new(s.clone(), with([-inf, -2.0], [inf, 2.0])).unwrap();
    let e = bounded.step(&model, &dvector![0.0], &dvector![0.1]).unwrap();
    assert!(e.status().is_clean(), "{}", e.status());
    for (lo, hi) in [([f64::NAN, -2.0], [inf, 2.0]), ([inf, -2.0], [inf, 2.0]), ([-inf, 1.0], [inf, -1.0])] {
        let r = ConstrainedZonotopeFilter::new(s.clone(), with(lo, hi));
        assert!(matches!(r, Err(EstimatorError::InvalidSetting { .. })), "{lo:?} {hi:?}");
    }
    let r = ConstrainedZonotopeFilter::new(
        s.clone(),
        ConstrainedZonotopeSettings { state_bounds: Some((dvector![0.0], dvector![1.0])), ..Default::default() },
    );
    assert!(matches!(r, Err(EstimatorError::DimensionMismatch { .. })));
}

#[test]
fn an_unmeasured_random_walk_is_marked_diverging() {
    // x₂ is never measured and walks with ±0.1 a step: its width grows past twice its initial 2.
    let model = ConstantModel::new(DMatrix::identity(2, 2), dmatrix![0.0; 0.0], dmatrix![1.0, 0.0]).unwrap();
    let s = boxes(dvector![0.0, 0.0], &[1.0, 1.0], &[0.01, 0.1], &[0.1], 1);
    let mut f = ConstrainedZonotopeFilter::new(s, ConstrainedZonotopeSettings::default()).unwrap();
    let mut first = None;
    for k in 1..=30 {
        let e = f.step(&model, &dvector![0.0], &dvector![0.0]).unwrap();
        if e.status().guarantee == Guarantee::Diverging && first.is_none() {
            first = Some(k);
            assert!(!e.status().is_clean() && e.status().label().contains("diverging"));
        }
    }
    // 2 + 0.2 k reaches 4 at k = 10 (the rounding's enclosure may put it just above).
    assert!(matches!(first, Some(10 | 11)), "{first:?}");
    // Declared bounds |x₂| ≤ 3 (range 6): the walk is held to them instead — not diverging at
    // widths 4–6, diverging once its set (before the cut) is wider than 6 (k = 20).
    let bounded = ConstrainedZonotopeSettings {
        state_bounds: Some((dvector![f64::NEG_INFINITY, -3.0], dvector![f64::INFINITY, 3.0])),
        ..Default::default()
    };
    let s = boxes(dvector![0.0, 0.0], &[1.0, 1.0], &[0.01, 0.1], &[0.1], 1);
    let mut f = ConstrainedZonotopeFilter::new(s, bounded).unwrap();
    let mut first = None;
    for k in 1..=30 {
        let e = f.step(&model, &dvector![0.0], &dvector![0.0]).unwrap();
        if e.status().guarantee == Guarantee::Diverging && first.is_none() {
            first = Some(k);
        }
    }
    assert!(matches!(first, Some(20 | 21)), "{first:?}");
    // The ellipsoid filter keeps the same rule: its unmeasured state's interval grows past twice
    // its initial width too, and the status says so (the set is still guaranteed).
    let s = Setup {
        x0: dvector![0.0, 0.0],
        p0: DMatrix::identity(2, 2),
        process_noise: DMatrix::from_diagonal(&dvector![1e-4, 1e-2]),
        measurement_noise: DMatrix::identity(1, 1) * 1e-2,
        inputs: 1,
    };
    let mut smf = estimators::SetMembershipFilter::new(s.clone()).unwrap();
    assert!(smf.estimate().status().is_clean());
    let mut marked = false;
    for _ in 0..200 {
        let e = smf.step(&model, &dvector![0.0], &dvector![0.0]).unwrap();
        marked |= e.status().guarantee == Guarantee::Diverging;
    }
    let (l, h) = smf.estimate().bounds(1).unwrap();
    assert!(h - l > 4.0 && marked, "width {} after 200 steps", h - l);
    assert_eq!(smf.estimate().status().guarantee, Guarantee::Diverging);
    // smf-nl told |x₂| ≤ 3: marked exactly when the published interval spans [−3, 3], although it
    // is wider than twice its initial width (2) long before.
    let inf = f64::INFINITY;
    let mut nl = NonlinearSetMembershipFilter::new(s).unwrap().with_state_bounds(&[-inf, -3.0], &[inf, 3.0]).unwrap();
    let (mut wide_unmarked, mut marked) = (false, false);
    for k in 0..400 {
        let e = nl.step(&model, &dvector![0.0], &dvector![0.0]).unwrap();
        let (l, h) = e.bounds(1).unwrap();
        let spans = l <= -3.0 && h >= 3.0;
        assert_eq!(e.status().guarantee == Guarantee::Diverging, spans, "step {k}: [{l}, {h}]");
        wide_unmarked |= !spans && h - l > 4.0;
        marked |= spans;
    }
    assert!(wide_unmarked && marked);
}

#[test]
fn on_the_carrier_the_intervals_are_no_wider_than_the_ellipsoid_filter_s() {
    // The straddle carrier at 1 ms, sideslip unmeasured (C = [0 I₃]), box noise on its vertices;
    // the ellipsoid filter gets the least-trace ellipsoids around the same boxes (d·h²), so both
    // are guaranteed for these data. After the first 50 steps, every state's interval of `czf`
    // is no wider than `smf`'s at every step.
    use carrier_dynamics::{CarrierModel, CarrierParams};
    use estimators::SetMembershipFilter;
    let d = CarrierModel::new(CarrierParams::paper_preset()).unwrap().discretize(1e-3).unwrap();
    let (a, b, _) = d.to_dynamic();
    let c = DMatrix::from_fn(3, 4, |i, j| if j == 1 + i { 1.0 } else { 0.0 });
    let model = ConstantModel::new(a.clone(), b.clone(), c.clone()).unwrap();
    let (w, v, h0) = ([1e-3, 2e-3, 1e-4, 2e-3], [4e-3; 3], [0.05; 4]);
    let boxes = boxes(DVector::zeros(4), &h0, &w, &v, 8);
    let ell =
        |h: &[f64]| DMatrix::from_diagonal(&DVector::from_iterator(h.len(), h.iter().map(|x| h.len() as f64 * x * x)));
    let ellipsoids = Setup { p0: ell(&h0), process_noise: ell(&w), measurement_noise: ell(&v), ..boxes.clone() };
    // Order 8 with 6 constraints, and order 1 with none: a box between steps (C6), the published
    // interval itself.
    for (order, max_constraints) in [(8, 6), (1, 0)] {
        let settings = ConstrainedZonotopeSettings { order, max_constraints, ..Default::default() };
        let mut czf = ConstrainedZonotopeFilter::new(boxes.clone(), settings).unwrap();
        let mut smf = SetMembershipFilter::new(ellipsoids.clone()).unwrap();
        let mut rng = Xoshiro256StarStar::seed_from_u64(8);
        let mut x = DVector::from_iterator(4, h0.iter().map(|h| 0.9 * h));
        let u = DVector::from_element(8, 0.01);
        for k in 0..300 {
            x = &a * &x + &b * &u + vertex(&mut rng, &w);
            let y = &c * &x + vertex(&mut rng, &v);
            let ez = czf.step(&model, &u, &y).unwrap();
            assert!(inside(ez, &x), "czf order {order}, step {k}");
            if order == 1 {
                let set = ez.set();
                assert_eq!((set.constraints(), set.generators()), (0, 4), "step {k}");
                let (lo, hi) = set.zonotope_hull();
                for i in 0..4 {
                    // The box holds the published interval and exceeds it by rounding only.
                    assert!(lo[i] <= ez.lower()[i] && hi[i] >= ez.upper()[i], "step {k}, state {i}");
                    let slack = 1e-12 * (1.0 + ez.upper()[i].abs().max(ez.lower()[i].abs()));
                    assert!(ez.lower()[i] - lo[i] <= slack && hi[i] - ez.upper()[i] <= slack, "step {k}, state {i}");
                }
            }
            let es = smf.step(&model, &u, &y).unwrap();
            assert!(inside(es, &x), "smf, step {k}");
            if k >= 50 {
                for i in 0..4 {
                    let wz = ez.bounds(i).map(|(l, h)| h - l).unwrap();
                    let ws = es.bounds(i).map(|(l, h)| h - l).unwrap();
                    assert!(wz <= ws, "order {order}, step {k}, state {i}: czf {wz} wider than smf {ws}");
                }
            }
        }
    }
}

#[test]
fn a_partial_step_is_the_step_of_the_model_with_the_measured_outputs_only() {
    // Three states, three sensors of different bounds; a step measuring outputs 0 and 2 against
    // a filter of the model whose outputs are those two (its V the same rows), from the same set.
    let a = dmatrix![1.0, 0.1, 0.0; 0.0, 1.0, 0.1; 0.0, 0.0, 0.95];
    let b = DMatrix::zeros(3, 0);
    let c = dmatrix![1.0, 0.0, 0.0; 0.5, 1.0, 0.0; 0.0, 0.2, 1.0];
    let r = [0.05, 0.01, 0.3];
    let full = estimators::StepModel::new(&a, &b, &c);
    let c_sub = dmatrix![1.0, 0.0, 0.0; 0.0, 0.2, 1.0];
    let sub = estimators::StepModel::new(&a, &b, &c_sub);
    let x0 = dvector![0.2, -0.1, 0.4];
    // The default order, and order 1 without constraints (a box between steps, (C6)).
    let box_between_steps = ConstrainedZonotopeSettings { order: 1, max_constraints: 0, ..Default::default() };
    for settings in [ConstrainedZonotopeSettings::default(), box_between_steps] {
        let p0 = boxes(x0.clone(), &[1.0; 3], &[0.01; 3], &r, 0);
        let mut ours = ConstrainedZonotopeFilter::new(p0, settings.clone()).unwrap();
        let p0_sub = boxes(x0.clone(), &[1.0; 3], &[0.01; 3], &[r[0], r[2]], 0);
        let mut reference = ConstrainedZonotopeFilter::new(p0_sub, settings).unwrap();
        let mut rng = Xoshiro256StarStar::seed_from_u64(9);
        let mut x = dvector![0.5, 0.3, -0.2];
        let u = DVector::zeros(0);
        for k in 0..30 {
            x = &a * &x + vertex(&mut rng, &[0.01; 3]);
            let y = &c * &x + vertex(&mut rng, &r);
            let e = ours.step_partial(&full, &u, &y, &[true, false, true]).unwrap();
            let want = reference.step(&sub, &u, &dvector![y[0], y[2]]).unwrap();
            assert!(inside(e, &x), "step {k}");
            for i in 0..3 {
                let ((l, h), (wl, wh)) = (e.bounds(i).unwrap(), want.bounds(i).unwrap());
                assert!(
                    (l - wl).abs() < 1e-9 && (h - wh).abs() < 1e-9,
                    "step {k}, state {i}: [{l}, {h}] vs [{wl}, {wh}]"
                );
            }
        }
        // Nothing measured: the prediction alone, still holding the truth.
        x = &a * &x + vertex(&mut rng, &[0.01; 3]);
        let e = ours.step_partial(&full, &u, &(&c * &x), &[false; 3]).unwrap();
        assert!(inside(e, &x));
    }
}
