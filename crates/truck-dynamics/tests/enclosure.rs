//! The truck's enclosures over boxes of states (`SecondOrderModel for TruckEkfModel`): at random
//! points of random boxes around realistic states, `f`, `h` and the analytic Jacobians `F` (13),
//! `H` (15) of the compiled model lie in the box's enclosures.

use models::{
    AnyModel, DifferentiableModel, DiscreteModel, Interval, SecondOrderModel, TaylorEnclosure, Xoshiro256StarStar,
};
use nalgebra::{DMatrix, DVector};
use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams, wheel_kinematics};

fn model() -> TruckEkfModel {
    TruckEkfModel::paper(TruckParams::digest_preset()).unwrap()
}

#[test]
fn f_h_and_the_analytic_jacobians_lie_in_the_enclosures() {
    let m = model();
    let re = m.planar().params().rolling_radius;
    let mut rng = Xoshiro256StarStar::seed_from_u64(5);
    let (mut fe, mut he) = (TaylorEnclosure::new(3, 3), TaylorEnclosure::new(3, 3));
    let (mut f, mut h) = (DVector::zeros(3), DVector::zeros(3));
    let (mut fj, mut hj) = (DMatrix::zeros(3, 3), DMatrix::zeros(3, 3));
    let (mut points, mut kinked) = (0, 0);
    for b in 0..250 {
        let centre = [rng.uniform(5.0, 25.0), rng.uniform(-1.0, 1.0), rng.uniform(-0.5, 0.5)];
        // Radii from tiny to a few per cent of the speed (a point box every tenth box).
        let scale = if b % 10 == 0 { 0.0 } else { 10f64.powf(rng.uniform(-4.0, -0.5)) };
        let radius =
            [scale * rng.uniform(0.0, 1.0), 0.3 * scale * rng.uniform(0.0, 1.0), 0.05 * scale * rng.uniform(0.0, 1.0)];
        let boxed: Vec<Interval> = (0..3).map(|i| Interval::centered(centre[i], radius[i])).collect();
        let input = TruckInput {
            delta: rng.uniform(-0.3, 0.3),
            omega: std::array::from_fn(|_| centre[0] / re * (1.0 + rng.uniform(-0.05, 0.05))),
        };
        let u = input.to_dvector();
        m.f_enclosure(&boxed, &u, &mut fe).unwrap();
        m.h_enclosure(&boxed, &u, &mut he).unwrap();
        assert!(fe.is_bounded() && he.is_bounded(), "box {b}: {boxed:?}");
        assert!(!fe.hessian_valid() && !he.hessian_valid());
        // Boxes holding a kink of a slip ratio (free rolling): its sign changes between corners.
        let p = m.planar().params();
        let slip_sign = |j: usize, corner: usize| {
            let state = std::array::from_fn(|i| if (corner >> i) & 1 == 0 { boxed[i].lo() } else { boxed[i].hi() });
            let k = wheel_kinematics(m.planar().geometry(), j, state, input.delta, input.omega[j], re, p.min_speed);
            k.slip > 0.0
        };
        kinked += usize::from((0..6).any(|j| (1..8).any(|c| slip_sign(j, c) != slip_sign(j, 0))));
        for _ in 0..12 {
            let x = DVector::from_fn(3, |i, _| {
                (centre[i] + radius[i] * rng.uniform(-1.0, 1.0)).clamp(boxed[i].lo(), boxed[i].hi())
            });
            m.f(&x, &u, &mut f).unwrap();
            m.h(&x, &u, &mut h).unwrap();
            m.f_jacobian(&x, &u, &mut fj).unwrap();
            m.h_jacobian(&x, &u, &mut hj).unwrap();
            for i in 0..3 {
                assert!(fe.value(i).contains(f[i]), "box {b}: f{i} = {} not in {}", f[i], fe.value(i));
                assert!(he.value(i).contains(h[i]), "box {b}: h{i} = {} not in {}", h[i], he.value(i));
                for j in 0..3 {
                    assert!(
                        fe.jacobian(i, j).contains(fj[(i, j)]),
                        "box {b}: F{i}{j} = {} not in {}",
                        fj[(i, j)],
                        fe.jacobian(i, j)
                    );
                    assert!(
                        he.jacobian(i, j).contains(hj[(i, j)]),
                        "box {b}: H{i}{j} = {} not in {}",
                        hj[(i, j)],
                        he.jacobian(i, j)
                    );
                }
            }
            points += 1;
        }
    }
    assert_eq!(points, 3000);
    assert!(kinked > 20, "{kinked} boxes hold a kink");
}

#[test]
fn point_boxes_are_tight_and_undefined_boxes_unbounded() {
    let m = model();
    assert!(AnyModel::second_order(&m).is_some());
    let x = DVector::from_vec(vec![19.44, 0.1, 0.05]);
    let mut input = TruckInput::free_rolling(0.02, 19.44, 0.52);
    input.omega[2..].iter_mut().for_each(|w| *w *= 1.003);
    let u = input.to_dvector();
    let boxed: Vec<Interval> = x.iter().map(|v| Interval::point(*v)).collect();
    let mut e = TaylorEnclosure::new(3, 3);
    m.f_enclosure(&boxed, &u, &mut e).unwrap();
    let (mut f, mut fj) = (DVector::zeros(3), DMatrix::zeros(3, 3));
    m.f_with_jacobian(&x, &u, &mut f, &mut fj).unwrap();
    for i in 0..3 {
        assert!(e.value(i).width() <= 1e-12 * (1.0 + f[i].abs()), "{}", e.value(i));
        for j in 0..3 {
            assert!(e.jacobian(i, j).width() <= 1e-9 * (1.0 + fj[(i, j)].abs()), "{}", e.jacobian(i, j));
        }
    }
    // V_x may be ≤ 0 on the box: undefined there, so unbounded (not a panic, not an error).
    let across = [Interval::new(-0.5, 3.0), Interval::point(0.0), Interval::point(0.0)];
    m.f_enclosure(&across, &u, &mut e).unwrap();
    assert!(!e.is_bounded());
    m.h_enclosure(&across, &u, &mut e).unwrap();
    assert!(!e.is_bounded());
    // Wrong dimensions and non-finite inputs are typed errors.
    assert!(m.f_enclosure(&boxed[..2], &u, &mut e).is_err());
    assert!(m.h_enclosure(&boxed, &u, &mut TaylorEnclosure::new(2, 3)).is_err());
    let mut bad = u.clone();
    bad[3] = f64::NAN;
    assert!(m.f_enclosure(&boxed, &bad, &mut e).is_err());
    assert!(m.f_enclosure(&boxed, &DVector::zeros(6), &mut e).is_err());
}
