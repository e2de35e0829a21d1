//! Interval forward-mode AD: at random points of random boxes, the value of an `f64` twin lies in
//! the value's enclosure and its central difference quotients in the gradient's (a difference
//! quotient is a derivative — or, across a kink, a convex combination of the branches' — at a
//! point within `h` of the point: a small tolerance covers the step and the twin's rounding).

use intervals::{Dual, Interval};
use proptest::prelude::*;

type D = Dual<2>;

/// Test functions, written once for `Dual<2>` and once for `f64`.
const CASES: usize = 5;

fn dual_f(case: usize, x: D, y: D) -> D {
    match case {
        0 => x.sin() * y.cos() + (x * 0.3).atan() * y - x / (y.sqr() + 1.0),
        1 => (x * 0.05).exp() * (y.sqr() + 1.0).sqrt() - 2.0 / (x.sqr() + 4.0),
        2 => (x - y).abs() + x.max(y * 2.0) - x.sin().min(y) * 0.5,
        3 => (x * y).sqr() - (x - 3.0) * y * 0.25 + (x.cos() + 2.0).sqrt(),
        _ => (y - x.sqr()).max(Dual::from(0.5)).sqrt() + (x + y).abs().min(Dual::from(1.0)),
    }
}

fn f64_f(case: usize, x: f64, y: f64) -> f64 {
    match case {
        0 => x.sin() * y.cos() + (x * 0.3).atan() * y - x / (y * y + 1.0),
        1 => (x * 0.05).exp() * (y * y + 1.0).sqrt() - 2.0 / (x * x + 4.0),
        2 => (x - y).abs() + x.max(y * 2.0) - x.sin().min(y) * 0.5,
        3 => (x * y).powi(2) - (x - 3.0) * y * 0.25 + (x.cos() + 2.0).sqrt(),
        _ => (y - x * x).max(0.5).sqrt() + (x + y).abs().min(1.0),
    }
}

fn boxed() -> impl Strategy<Value = (f64, f64, f64, f64)> {
    (-4.0f64..4.0, 0.0f64..1.5, -4.0f64..4.0, 0.0f64..1.5)
}

fn within(e: Interval, v: f64, tol: f64) -> bool {
    e.lo() - tol <= v && v <= e.hi() + tol
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn value_and_gradient_lie_in_the_enclosures((cx, rx, cy, ry) in boxed(), case in 0..CASES) {
        let (bx, by) = (Interval::centered(cx, rx), Interval::centered(cy, ry));
        let e = dual_f(case, D::variable(bx, 0), D::variable(by, 1));
        prop_assert!(e.is_bounded(), "case {case} over {bx} × {by}: {e:?}");
        for k in 0..=8 {
            for l in 0..=8 {
                let x = cx + rx * (f64::from(k) / 4.0 - 1.0) * 0.999;
                let y = cy + ry * (f64::from(l) / 4.0 - 1.0) * 0.999;
                let v = f64_f(case, x, y);
                prop_assert!(e.value.contains(v), "case {case}: f({x}, {y}) = {v} not in {}", e.value);
                let h = 1e-7;
                let dx = (f64_f(case, x + h, y) - f64_f(case, x - h, y)) / (2.0 * h);
                let dy = (f64_f(case, x, y + h) - f64_f(case, x, y - h)) / (2.0 * h);
                for (j, d) in [dx, dy].into_iter().enumerate() {
                    let tol = 1e-6 * (1.0 + e.grad[j].mag()) + 1e-5 * (1.0 + v.abs());
                    prop_assert!(within(e.grad[j], d, tol), "case {case}: ∂{j} = {d} not in {} at ({x}, {y})", e.grad[j]);
                }
            }
        }
    }
}

#[test]
fn closed_forms_and_the_clarke_hull_at_kinks() {
    let b = Interval::new(-1.0, 2.0);
    let x = D::variable(b, 0);
    // (x²)' = 2x over [−1, 2] is [−2, 4]; the other variable's derivative is 0.
    let s = x.sqr();
    assert!(s.grad[0].contains(-2.0) && s.grad[0].contains(4.0) && s.grad[0].width() < 6.0 + 1e-12);
    assert_eq!(s.grad[1], Interval::ZERO);
    // |x| across 0: the derivative's enclosure holds the whole Clarke gradient [−1, 1].
    let a = x.abs();
    assert_eq!(a.value, Interval::new(0.0, 2.0));
    assert!(a.grad[0].contains(-1.0) && a.grad[0].contains(1.0));
    // max(x, 0.5) with the kink inside: hull of 1 and 0; away from it: one branch exactly.
    let m = x.max(D::from(0.5));
    assert_eq!((m.value, m.grad[0]), (Interval::new(0.5, 2.0), Interval::new(0.0, 1.0)));
    let m = x.max(D::from(3.0));
    assert_eq!((m.value, m.grad[0]), (Interval::point(3.0), Interval::ZERO));
    let m = x.min(D::from(0.5));
    assert_eq!((m.value, m.grad[0]), (Interval::new(-1.0, 0.5), Interval::new(0.0, 1.0)));
    // Division by an interval holding 0, and sqrt at 0: unbounded.
    assert!(!(D::from(1.0) / x).is_bounded());
    assert!(!(x / x).is_bounded());
    assert!(!x.sqrt().is_bounded());
    assert!(!D::variable(Interval::new(0.0, 1.0), 0).sqrt().is_bounded());
    // Exact cases: d(x·y)/dy = x, d(1/y)/dy = −1/y², d atan(x)/dx at 0 is 1.
    let y = D::variable(Interval::new(2.0, 4.0), 1);
    let p = x * y;
    assert!(p.grad[1].contains(-1.0) && p.grad[1].contains(2.0));
    let r = 1.0 / y;
    assert!(r.grad[1].contains(-0.25) && r.grad[1].contains(-1.0 / 16.0) && r.grad[1].hi() < 0.0);
    let t = D::variable(Interval::point(0.0), 0).atan();
    assert!(t.grad[0].contains(1.0) && t.grad[0].width() < 1e-15);
    // Scalars: ± touch the value only; × scales the gradient.
    let z = (x + 2.0) * 3.0 - Interval::point(1.0);
    assert!(z.grad[0].contains(3.0) && z.grad[0].width() < 1e-14);
    assert_eq!(D::variable(b, 5).grad, [Interval::ZERO; 2]);
}

#[test]
fn a_scalar_function_mapped_once_encloses_as_forward_mode_does_or_tighter() {
    let g1 = |s: Dual<1>| (s.atan() * 1.3).sin() * 2.0 + s * 0.1;
    let g2 = |s: D| (s.atan() * 1.3).sin() * 2.0 + s * 0.1;
    let (bx, by) = (Interval::new(0.2, 0.5), Interval::new(-1.0, -0.4));
    let a = D::variable(bx, 0) * D::variable(by, 1) + D::variable(bx, 0);
    let (mapped, forward) = (a.map_scalar(g1), g2(a));
    assert_eq!(mapped.value, forward.value);
    for j in 0..2 {
        let (m, f) = (mapped.grad[j], forward.grad[j]);
        // Within the forward-mode enclosure up to the rounding of the final products.
        let slack = 1e-14 * (1.0 + f.mag());
        assert!(f.lo() - slack <= m.lo() && m.hi() <= f.hi() + slack, "∂{j}: {m} not within {f}");
    }
    // Central differences at a grid of the box lie in the mapped gradient.
    let g = |x: f64, y: f64| {
        let s = x * y + x;
        (s.atan() * 1.3).sin() * 2.0 + s * 0.1
    };
    for k in 0..=10 {
        for l in 0..=10 {
            let x = 0.2 + 0.3 * f64::from(k) / 10.0;
            let y = -1.0 + 0.6 * f64::from(l) / 10.0;
            let h = 1e-7;
            let dx = (g(x + h, y) - g(x - h, y)) / (2.0 * h);
            let dy = (g(x, y + h) - g(x, y - h)) / (2.0 * h);
            assert!(within(mapped.grad[0], dx, 1e-6) && within(mapped.grad[1], dy, 1e-6), "({x}, {y})");
            assert!(mapped.value.contains(g(x, y)));
        }
    }
}
