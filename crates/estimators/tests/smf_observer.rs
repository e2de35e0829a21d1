//! The linear set-membership filter with its interval observer (docs/carrier-smf.md §4.8,
//! (O1)–(O4)): the ellipsoid is the plain filter's bit for bit, the published interval is inside
//! its projection and holds the truth with every noise on the boundary of its set (full and
//! partial steps, angle outputs across ±π), a state measured alone is held to its noise box (the
//! closed form of (O3) for a unit row), contradictions are refused or published marked, the state
//! bounds cut and are checked, and the registry runs it by default.

mod common;

use common::LinearSystem;
use estimators::registry::{self, EstimatorSettings, SetMembershipSettings, names};
use estimators::smf::ObservedSetMembershipFilter;
use estimators::{
    Estimate, EstimatorError, Guarantee, InconsistencyPolicy, SetEstimate, SetMembershipFilter, Setup, StepModel,
};
use models::{Angles, ConstantModel, Noise, Xoshiro256StarStar};
use nalgebra::{DMatrix, DVector, dmatrix, dvector};

/// Random stable systems of 2–5 states; half of them measure some states one by one (unit rows
/// of `C`, where the observer is exact), the others through random rows.
fn random_system(rng: &mut Xoshiro256StarStar, i: usize) -> LinearSystem {
    let n = 2 + i % 4;
    let m = 1 + (i / 4) % n;
    let c = if i % 2 == 0 {
        DMatrix::from_fn(m, n, |r, k| if r == k { 1.0 } else { 0.0 })
    } else {
        common::gauss(rng, m, n)
    };
    LinearSystem {
        a: common::random_a(rng, n, [0.9, 0.99, 1.0][i % 3]),
        b: common::gauss(rng, n, 2),
        c,
        q: common::spd(rng, n, 0.05, 50.0),
        r: common::spd(rng, m, 0.02, 20.0),
        p0: common::spd(rng, n, 1.0, 5.0),
        x0: common::gauss(rng, n, 1).column(0).into(),
    }
}

fn inside(e: &SetEstimate, x: &DVector<f64>) -> bool {
    (0..x.len()).all(|i| e.lower[i] <= x[i] && x[i] <= e.upper[i])
}

#[test]
fn the_ellipsoid_is_the_plain_filters_and_the_interval_holds_the_truth_inside_its_projection() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(71);
    let (mut steps, mut narrower, mut width_ratio) = (0usize, 0usize, Vec::new());
    for i in 0..24 {
        let sys = random_system(&mut rng, i);
        let (n, m) = (sys.a.nrows(), sys.c.nrows());
        let mut plain = SetMembershipFilter::new(sys.setup()).unwrap();
        let mut ours = ObservedSetMembershipFilter::new(SetMembershipFilter::new(sys.setup()).unwrap());
        let (wn, vn) =
            (Noise::ellipsoid_boundary(sys.q.clone()).unwrap(), Noise::ellipsoid_boundary(sys.r.clone()).unwrap());
        let mut x = common::boundary_point(&mut rng, &sys.x0, &sys.p0);
        let model = StepModel::new(&sys.a, &sys.b, &sys.c);
        let (mut sum_ours, mut sum_plain) = (0.0, 0.0);
        for k in 0..400 {
            let u = DVector::from_fn(2, |_, _| rng.standard_normal());
            x = &sys.a * &x + &sys.b * &u + wn.sample(&mut rng);
            let y = &sys.c * &x + vn.sample(&mut rng);
            // Every third step measures a subset (the first output missing), if there are two.
            let measured: Vec<bool> = (0..m).map(|j| !(k % 3 == 2 && m > 1 && j == 0)).collect();
            let p = plain.step_partial(&model, &u, &y, &measured).unwrap().clone();
            let e = ours.step_partial(&model, &u, &y, &measured).unwrap();
            assert_eq!((&e.center, &e.shape), (&p.center, &p.shape), "system {i}, step {k}: the ellipsoid changed");
            assert!(inside(e, &x), "system {i}, step {k}: {x} outside [{}, {}]", e.lower, e.upper);
            for j in 0..n {
                assert!(p.lower[j] <= e.lower[j] && e.upper[j] <= p.upper[j], "system {i}, step {k}, state {j}");
                sum_ours += e.upper[j] - e.lower[j];
                sum_plain += p.upper[j] - p.lower[j];
            }
            assert!(e.report.guaranteed && e.status().guarantee != Guarantee::Lost);
            steps += 1;
        }
        narrower += usize::from(sum_ours < sum_plain);
        width_ratio.push(sum_ours / sum_plain);
    }
    width_ratio.sort_by(f64::total_cmp);
    println!("{steps} steps; mean width ratio observer/plain: median {:.3}", width_ratio[width_ratio.len() / 2]);
    assert!(narrower >= 12, "the observer narrowed only {narrower} of 24 systems");
}

#[test]
fn a_state_measured_alone_is_held_to_its_noise_box() {
    // x₀ measured with |v| ≤ 0.1 every step; the ellipsoid's trace is dominated by the drifting,
    // unmeasured x₁, so its projection on x₀ stays wide. (O3) for the unit row is exactly
    // [y − 0.1, y + 0.1] ∩ O⁺₀ (rounded outward).
    let a = dmatrix![1.0, 0.1; 0.0, 1.0];
    let (b, c) = (DMatrix::zeros(2, 0), dmatrix![1.0, 0.0]);
    let setup = Setup {
        x0: dvector![0.0, 0.0],
        p0: DMatrix::identity(2, 2) * 4.0,
        process_noise: dmatrix![1e-4, 0.0; 0.0, 1.0],
        measurement_noise: dmatrix![0.01],
        inputs: 0,
    };
    let mut plain = SetMembershipFilter::new(setup.clone()).unwrap();
    let mut ours = ObservedSetMembershipFilter::new(SetMembershipFilter::new(setup).unwrap());
    let model = StepModel::new(&a, &b, &c);
    let mut rng = Xoshiro256StarStar::seed_from_u64(5);
    let (wn, vn) = (
        Noise::ellipsoid_boundary(dmatrix![1e-4, 0.0; 0.0, 1.0]).unwrap(),
        Noise::ellipsoid_boundary(dmatrix![0.01]).unwrap(),
    );
    let mut x = dvector![0.5, -1.0];
    let u = DVector::zeros(0);
    for k in 0..300 {
        x = &a * &x + wn.sample(&mut rng);
        let y = &c * &x + vn.sample(&mut rng);
        let p = plain.step(&model, &u, &y).unwrap().clone();
        let e = ours.step(&model, &u, &y).unwrap();
        assert!(inside(e, &x), "step {k}");
        let ulps = 8.0 * f64::EPSILON * y[0].abs().max(1.0);
        assert!(
            e.lower[0] >= y[0] - 0.1 - ulps && e.upper[0] <= y[0] + 0.1 + ulps,
            "step {k}: [{}, {}]",
            e.lower[0],
            e.upper[0]
        );
        if k > 20 {
            assert!(
                p.upper[0] - p.lower[0] > 0.3,
                "step {k}: the plain filter is already narrow; the test shows nothing"
            );
        }
    }
}

#[test]
fn predict_then_update_is_the_step() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(9);
    let sys = random_system(&mut rng, 5);
    let model = StepModel::new(&sys.a, &sys.b, &sys.c);
    let mut one = ObservedSetMembershipFilter::new(SetMembershipFilter::new(sys.setup()).unwrap());
    let mut two = one.clone();
    let mut x = sys.x0.clone();
    let vn = Noise::ellipsoid_boundary(sys.r.clone()).unwrap();
    for _ in 0..50 {
        let u = DVector::from_fn(2, |_, _| rng.standard_normal());
        x = &sys.a * &x + &sys.b * &u;
        let y = &sys.c * &x + vn.sample(&mut rng);
        let a = one.step(&model, &u, &y).unwrap().clone();
        let predicted = two.predict(&model, &u).unwrap().clone();
        assert!(inside(&predicted, &x));
        let b = two.update(&model, &y).unwrap();
        assert_eq!((&a.center, &a.shape), (&b.center, &b.shape));
        for j in 0..x.len() {
            // The update contracts the predicted box (cut by the predicted ellipsoid) instead of
            // (O1)'s own: at least as narrow, and it holds the truth.
            assert!(b.lower[j] >= a.lower[j] - 1e-12 && b.upper[j] <= a.upper[j] + 1e-12);
        }
        assert!(inside(b, &x));
    }
    let e = two.update(&model, &DVector::zeros(sys.c.nrows())).unwrap_err();
    assert!(matches!(e, EstimatorError::UpdateWithoutPrediction { .. }), "{e}");
}

/// A scalar state bounded to [−1, 1] with a wide ellipsoid; the measurement `y = 3 ± 0.1`
/// agrees with the ellipsoid but not with the bounds.
fn bounded_scalar() -> (ObservedSetMembershipFilter, ConstantModel) {
    let setup = Setup {
        x0: dvector![0.0],
        p0: dmatrix![100.0],
        process_noise: dmatrix![1e-4],
        measurement_noise: dmatrix![0.01],
        inputs: 0,
    };
    let f = ObservedSetMembershipFilter::new(SetMembershipFilter::new(setup).unwrap())
        .with_state_bounds(&[-1.0], &[1.0])
        .unwrap();
    (f, ConstantModel::new(dmatrix![1.0], DMatrix::zeros(1, 0), dmatrix![1.0]).unwrap())
}

#[test]
fn contradicted_data_are_refused_or_published_marked() {
    let (mut f, model) = bounded_scalar();
    // The bounds cut the initial interval [−10, 10].
    assert_eq!((f.estimate().lower[0], f.estimate().upper[0]), (-1.0, 1.0));
    let before = f.clone();
    let u = DVector::zeros(0);
    let e = f.step(&model, &u, &dvector![3.0]).unwrap_err();
    assert!(matches!(e, EstimatorError::SetMissed { step: 1, .. }), "{e}");
    assert_eq!(f.estimate(), before.estimate());
    assert_eq!(f.steps(), 0);
    // Data the ellipsoid's own proof refutes too: its error, with the excess.
    let e = f.step(&model, &u, &dvector![1e4]).unwrap_err();
    assert!(matches!(e, EstimatorError::InconsistentData { step: 1, excess } if excess > 1.0), "{e}");
    assert_eq!(f.estimate(), before.estimate());
    // Consistent data are taken and narrow the interval to the noise box.
    let e = f.step(&model, &u, &dvector![0.5]).unwrap();
    assert!(e.lower[0] >= 0.4 - 1e-12 && e.upper[0] <= 0.6 + 1e-12);
    // Published, marked and no longer guaranteed when the policy lets it through.
    f.set_inconsistency_policy(InconsistencyPolicy::FlagAndContinue);
    let e = f.step(&model, &u, &dvector![3.0]).unwrap();
    assert!(!e.report.guaranteed);
    assert_eq!(e.status().guarantee, Guarantee::Lost);
    assert!(e.lower[0] >= -1.0 && e.upper[0] <= 1.0, "the bounds still cut");
}

#[test]
fn state_bounds_are_checked() {
    let setup = Setup {
        x0: dvector![0.0, 0.0],
        p0: DMatrix::identity(2, 2),
        process_noise: DMatrix::identity(2, 2) * 0.01,
        measurement_noise: dmatrix![0.01],
        inputs: 0,
    };
    let f = || ObservedSetMembershipFilter::new(SetMembershipFilter::new(setup.clone()).unwrap());
    let e = f().with_state_bounds(&[5.0, -1.0], &[6.0, 1.0]).unwrap_err();
    assert!(matches!(e, EstimatorError::OutsideStateBounds { step: 0, state: 0, .. }), "{e}");
    assert!(matches!(f().with_state_bounds(&[0.0], &[1.0]), Err(EstimatorError::DimensionMismatch { .. })));
    assert!(matches!(f().with_state_bounds(&[f64::NAN, 0.0], &[1.0, 1.0]), Err(EstimatorError::InvalidSetting { .. })));
    assert!(matches!(f().with_state_bounds(&[2.0, 0.0], &[1.0, 1.0]), Err(EstimatorError::InvalidSetting { .. })));
    // A state whose interval spans its finite bounds says nothing they did not: diverging.
    let mut g = f().with_state_bounds(&[-0.5, f64::NEG_INFINITY], &[0.5, f64::INFINITY]).unwrap();
    let model = ConstantModel::new(DMatrix::identity(2, 2), DMatrix::zeros(2, 0), dmatrix![0.0, 1.0]).unwrap();
    let e = g.step(&model, &DVector::zeros(0), &dvector![0.0]).unwrap();
    assert_eq!((e.lower[0], e.upper[0]), (-0.5, 0.5));
    assert_eq!(e.status().guarantee, Guarantee::Diverging);
}

#[test]
fn an_angle_output_across_the_seam_keeps_the_truth_inside() {
    // A heading turning at 0.5 rad/step, measured by a compass (wrapped) and a gyro.
    let model = ConstantModel::new(dmatrix![1.0, 0.1; 0.0, 1.0], DMatrix::zeros(2, 0), dmatrix![1.0, 0.0; 0.0, 1.0])
        .unwrap()
        .with_angles(Angles { states: &[0], outputs: &[0] })
        .unwrap();
    let (q, r) = (DMatrix::identity(2, 2) * 1e-4, dmatrix![0.01, 0.0; 0.0, 1e-4]);
    let setup = Setup {
        x0: dvector![3.0, 5.0],
        p0: DMatrix::identity(2, 2) * 0.1,
        process_noise: q.clone(),
        measurement_noise: r.clone(),
        inputs: 0,
    };
    let mut f = ObservedSetMembershipFilter::new(SetMembershipFilter::new(setup).unwrap());
    let mut rng = Xoshiro256StarStar::seed_from_u64(3);
    let (wn, vn) = (Noise::ellipsoid_boundary(q).unwrap(), Noise::ellipsoid_boundary(r).unwrap());
    let mut x = dvector![3.1, 5.0];
    let (a, u) = (dmatrix![1.0, 0.1; 0.0, 1.0], DVector::zeros(0));
    let mut crossings = 0;
    for k in 0..600 {
        let before = models::wrap_angle(x[0]);
        x = &a * &x + wn.sample(&mut rng);
        crossings += usize::from((models::wrap_angle(x[0]) - before).abs() > std::f64::consts::PI);
        let mut y = &x + vn.sample(&mut rng);
        y[0] = models::wrap_angle(y[0]);
        let e = f.step(&model, &u, &y).unwrap();
        assert!(inside(e, &x), "step {k}: {x} outside [{}, {}]", e.lower, e.upper);
        assert!(e.upper[0] - e.lower[0] <= 0.2 + 1e-9, "step {k}: the compass's box holds the heading");
    }
    assert!(crossings >= 20, "{crossings} crossings");
}

#[test]
fn the_registry_runs_it_by_default_and_the_paper_filter_on_request() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(13);
    let sys = random_system(&mut rng, 4);
    let model = ConstantModel::new(sys.a.clone(), sys.b.clone(), sys.c.clone()).unwrap();
    let off = SetMembershipSettings { interval_observer: false, ..SetMembershipSettings::default() };
    let mut by_default = registry::build(names::SMF, sys.setup(), None).unwrap();
    let mut paper =
        registry::build(names::SMF, sys.setup(), Some(EstimatorSettings::SetMembership(off.clone()))).unwrap();
    let mut direct = SetMembershipFilter::new(sys.setup()).unwrap();
    let mut observed = ObservedSetMembershipFilter::new(SetMembershipFilter::new(sys.setup()).unwrap());
    let mut x = sys.x0.clone();
    for _ in 0..30 {
        let u = DVector::from_fn(2, |_, _| rng.standard_normal());
        x = &sys.a * &x + &sys.b * &u;
        let y = &sys.c * &x;
        let d = direct.step(&model, &u, &y).unwrap();
        let o = observed.step(&model, &u, &y).unwrap();
        let p = paper.step(&model, &u, &y).unwrap();
        let b = by_default.step(&model, &u, &y).unwrap();
        for j in 0..x.len() {
            assert_eq!(p.bounds(j), d.bounds(j));
            assert_eq!(b.bounds(j), o.bounds(j));
        }
    }
    // State bounds need the observer.
    let n = sys.a.nrows();
    let bounds = Some((DVector::from_element(n, -10.0), DVector::from_element(n, 10.0)));
    let with_bounds = SetMembershipSettings { state_bounds: bounds.clone(), ..off };
    let e =
        registry::build(names::SMF, sys.setup(), Some(EstimatorSettings::SetMembership(with_bounds))).err().unwrap();
    assert!(matches!(e, EstimatorError::InvalidConfiguration { .. }), "{e}");
    let s = SetMembershipSettings { state_bounds: bounds, ..SetMembershipSettings::default() };
    assert!(registry::build(names::SMF, sys.setup(), Some(EstimatorSettings::SetMembership(s))).is_ok());
}

/// A plain interval observer, written apart: (O1) and (O3) without the ellipsoid.
struct PlainObserver {
    o: Vec<intervals::Interval>,
    w: Vec<f64>,
    v: Vec<f64>,
}

impl PlainObserver {
    fn step(&mut self, sys: &LinearSystem, u: &DVector<f64>, y: &DVector<f64>) {
        use intervals::Interval;
        let n = self.o.len();
        let mut next = vec![Interval::ZERO; n];
        for (i, slot) in next.iter_mut().enumerate() {
            let mut acc = Interval::new(-self.w[i], self.w[i]);
            for j in 0..n {
                acc = acc + self.o[j].times(sys.a[(i, j)]);
            }
            for j in 0..u.len() {
                acc = acc + Interval::point(u[j]).times(sys.b[(i, j)]);
            }
            *slot = acc;
        }
        for _ in 0..2 {
            for i in 0..sys.c.nrows() {
                let target = Interval::point(y[i]) - Interval::new(-self.v[i], self.v[i]);
                for j in 0..n {
                    if sys.c[(i, j)] == 0.0 {
                        continue;
                    }
                    let mut rest = Interval::ZERO;
                    for (k, o) in next.iter().enumerate() {
                        if k != j {
                            rest = rest + o.times(sys.c[(i, k)]);
                        }
                    }
                    let implied = (target - rest) / Interval::point(sys.c[(i, j)]);
                    next[j] = next[j].meet(implied).expect("consistent data");
                }
            }
        }
        self.o = next;
    }
}

#[test]
fn never_wider_than_an_interval_observer_run_alone() {
    let mut rng = Xoshiro256StarStar::seed_from_u64(17);
    let half = |m: &DMatrix<f64>| -> Vec<f64> {
        (0..m.nrows()).map(|i| intervals::Interval::point(m[(i, i)]).sqrt().hi()).collect()
    };
    for i in 0..16 {
        let sys = random_system(&mut rng, i);
        let mut ours = ObservedSetMembershipFilter::new(SetMembershipFilter::new(sys.setup()).unwrap());
        let est = ours.estimate();
        let o = (0..sys.x0.len()).map(|j| intervals::Interval::new(est.lower[j], est.upper[j])).collect();
        let mut alone = PlainObserver { o, w: half(&sys.q), v: half(&sys.r) };
        let (wn, vn) =
            (Noise::ellipsoid_boundary(sys.q.clone()).unwrap(), Noise::ellipsoid_boundary(sys.r.clone()).unwrap());
        let mut x = common::boundary_point(&mut rng, &sys.x0, &sys.p0);
        let model = StepModel::new(&sys.a, &sys.b, &sys.c);
        for k in 0..300 {
            let u = DVector::from_fn(2, |_, _| rng.standard_normal());
            x = &sys.a * &x + &sys.b * &u + wn.sample(&mut rng);
            let y = &sys.c * &x + vn.sample(&mut rng);
            let e = ours.step(&model, &u, &y).unwrap();
            alone.step(&sys, &u, &y);
            for (j, o) in alone.o.iter().enumerate() {
                assert!(o.contains(x[j]), "system {i}, step {k}: the plain observer misses the truth");
                assert!(o.lo() <= e.lower[j] && e.upper[j] <= o.hi(), "system {i}, step {k}, state {j}");
            }
        }
    }
}
