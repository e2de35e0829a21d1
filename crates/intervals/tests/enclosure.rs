//! Every operation contains the exact result at points of its operands: checked on random
//! intervals against the operation at many points inside them (computed in `f64`, which the
//! outward rounding must cover), against exact small cases, and on the edge cases (zero in a
//! divisor, extrema of the trigonometric functions inside the interval).

use intervals::{Interval, down, up};
use proptest::prelude::*;

fn interval() -> impl Strategy<Value = Interval> {
    (-50.0f64..50.0, 0.0f64..20.0).prop_map(|(lo, w)| Interval::new(lo, lo + w))
}

fn points(i: Interval) -> impl Iterator<Item = f64> {
    (0..=64).map(move |k| i.lo() + (i.hi() - i.lo()) * f64::from(k) / 64.0).map(move |x| x.clamp(i.lo(), i.hi()))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn arithmetic_contains_the_pointwise_results(a in interval(), b in interval()) {
        for x in points(a) {
            for y in points(b) {
                prop_assert!((a + b).contains(x + y));
                prop_assert!((a - b).contains(x - y));
                prop_assert!((a * b).contains(x * y));
                // A number known exactly: the same enclosure as the interval product.
                prop_assert_eq!(a * y, a * Interval::point(y));
                prop_assert!((a * y).contains(x * y) && (y * a).contains(x * y));
                let q = a / b;
                prop_assert!(!q.is_bounded() || q.contains(x / y), "{a} / {b} at {x}, {y}");
            }
        }
    }

    #[test]
    fn sin_and_cos_of_narrow_intervals_contain_the_pointwise_results(lo in -7.0f64..7.0, w in 0.0f64..0.5) {
        // Narrow intervals: the monotone pieces, and the extrema near their ends.
        let a = Interval::new(lo, lo + w);
        for x in points(a) {
            prop_assert!(a.sin().contains(x.sin()), "sin {a} at {x}");
            prop_assert!(a.cos().contains(x.cos()), "cos {a} at {x}");
        }
    }

    #[test]
    fn functions_contain_the_pointwise_results(a in interval()) {
        for x in points(a) {
            prop_assert!(a.sin().contains(x.sin()), "sin {a} at {x}");
            prop_assert!(a.cos().contains(x.cos()), "cos {a} at {x}");
            prop_assert!(a.atan().contains(x.atan()));
            prop_assert!(a.tanh().contains(x.tanh()));
            prop_assert!(a.sqr().contains(x * x));
            prop_assert!((a * 0.02).exp().contains((x * 0.02).exp()));
            if a.lo() >= 0.0 {
                prop_assert!(a.sqrt().contains(x.sqrt()));
            }
            if a.lo() > 0.0 {
                prop_assert!(a.ln().contains(x.ln()));
            }
        }
    }
}

#[test]
fn rounding_is_outward_and_exact_cases_are_tight() {
    let third = Interval::point(1.0) / Interval::point(3.0);
    assert!(third.lo() < third.hi() && third.lo() < 1.0 / 3.0 && 1.0 / 3.0 < third.hi());
    assert_eq!(up(1.0), 1.0 + f64::EPSILON);
    assert_eq!(down(1.0), 1.0 - f64::EPSILON / 2.0);
    assert!(up(0.0) > 0.0 && down(0.0) < 0.0 && up(-0.0) > 0.0);
    let s = Interval::new(1.0, 2.0) + Interval::new(3.0, 4.0);
    assert!(s.lo() <= 4.0 && s.lo() > 3.99 && s.hi() >= 6.0 && s.hi() < 6.01);
    assert_eq!(Interval::new(-1.0, 2.0).sqr().lo(), 0.0);
}

#[test]
fn undefined_operations_are_unbounded_not_narrowed() {
    assert!(!(Interval::point(1.0) / Interval::new(-1.0, 1.0)).is_bounded());
    assert!(!Interval::new(-1.0, 1.0).sqrt().is_bounded());
    assert!(!Interval::new(0.0, 1.0).ln().is_bounded());
    assert!(!Interval::new(f64::NAN, 1.0).is_bounded());
    assert!(!(Interval::ENTIRE * Interval::point(2.0)).is_bounded());
    let z = Interval::ENTIRE * Interval::ZERO;
    assert!(z.contains(0.0) && z.mag() < 1e-300, "{z}");
    assert_eq!(Interval::ENTIRE * 0.0, Interval::ZERO);
    assert!(!(Interval::ENTIRE * -2.0).is_bounded() && !(Interval::point(1.0) * f64::NAN).is_bounded());
}

#[test]
fn trigonometric_extrema_inside_the_interval_are_reached() {
    let c = Interval::new(-0.1, 0.1).cos();
    assert_eq!(c.hi(), 1.0);
    assert!(c.lo() < 0.1f64.cos() && c.lo() > 0.99);
    let s = Interval::new(1.5, 1.6).sin();
    assert_eq!(s.hi(), 1.0);
    assert_eq!(Interval::new(3.0, 3.3).cos().lo(), -1.0);
    assert_eq!(Interval::new(0.0, 7.0).sin(), Interval::new(-1.0, 1.0));
    // Far from the origin the shift by kτ is tested with a margin: still an enclosure.
    let far = Interval::new(1e6, 1e6 + 0.5);
    for x in points(far) {
        assert!(far.cos().contains(x.cos()) && far.sin().contains(x.sin()));
    }
}
