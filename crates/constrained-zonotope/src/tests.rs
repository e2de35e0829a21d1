//! Against an independent reference: planar sets as vertex lists ([`crate::polygon`]), so every
//! operation's exact result is known.

use nalgebra::{DMatrix, DVector, dmatrix, dvector};

use super::*;
use crate::polygon::{P, bbox, box_poly, cross, map_poly, strip, sum_poly};

/// A small deterministic generator of test numbers in `[-1, 1]`.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// A random planar estimation run: box, then steps of map, box noise and a strip measurement,
/// as a constrained zonotope and as a polygon.
fn run(seed: u64, steps: usize, limits: Option<ReductionLimits>) -> Vec<(ConstrainedZonotope, Vec<P>)> {
    let mut rng = Lcg(seed);
    let mut z = ConstrainedZonotope::from_box(&dvector![0.3, -0.2], &dvector![1.0, 0.7]).unwrap();
    let mut poly = box_poly([0.3, -0.2], [1.0, 0.7]);
    let mut out = Vec::new();
    for _ in 0..steps {
        let m = dmatrix![0.9 + 0.1 * rng.next(), 0.3 * rng.next(); 0.3 * rng.next(), 0.9 + 0.1 * rng.next()];
        let d = [0.1 * rng.next(), 0.1 * rng.next()];
        let w = [0.05 + 0.05 * rng.next().abs(), 0.05 + 0.05 * rng.next().abs()];
        z = z.affine_map(&m, Some(&dvector![d[0], d[1]])).unwrap();
        z = z
            .minkowski_sum(&ConstrainedZonotope::from_box(&dvector![0.0, 0.0], &dvector![w[0], w[1]]).unwrap())
            .unwrap();
        poly = sum_poly(&map_poly(&m, d, &poly), &box_poly([0.0, 0.0], w));
        // A measurement through the middle of the current set, so the strip cuts it.
        let h = [rng.next(), rng.next()];
        let (lo, hi) = bbox(&poly);
        let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let y = h[0] * mid[0] + h[1] * mid[1] + 0.1 * rng.next();
        let v = 0.2;
        let meas = ConstrainedZonotope::from_box(&dvector![y], &dvector![v]).unwrap();
        z = z.intersect(&dmatrix![h[0], h[1]], &meas).unwrap();
        poly = strip(&poly, h, y, v);
        if let Some(l) = limits {
            z = z.reduce(&l).unwrap();
        }
        out.push((z.clone(), poly.clone()));
    }
    out
}

#[test]
fn the_hull_of_unreduced_operations_is_the_exact_polygon_s() {
    for seed in 0..20 {
        for (k, (z, poly)) in run(seed, 6, None).into_iter().enumerate() {
            let h = z.interval_hull().unwrap();
            assert!(!h.certified_empty);
            let (lo, hi) = bbox(&poly);
            for i in 0..2 {
                // Sound: never inside the exact hull.
                assert!(h.lower[i] <= lo[i] + 1e-12 && h.upper[i] >= hi[i] - 1e-12, "seed {seed} step {k}");
                // Tight: the exact hull up to the solver's and the rounding enclosures' size.
                assert!(
                    lo[i] - h.lower[i] < 1e-7 && h.upper[i] - hi[i] < 1e-7,
                    "seed {seed} step {k} state {i}: \
                         [{}, {}] against [{}, {}]",
                    h.lower[i],
                    h.upper[i],
                    lo[i],
                    hi[i]
                );
            }
        }
    }
}

#[test]
fn every_vertex_of_the_exact_set_lies_in_the_set_and_points_beyond_do_not() {
    for seed in 0..5 {
        let (z, poly) = run(seed, 4, None).pop().unwrap();
        for p in &poly {
            let c = z.contains_point(&dvector![p[0], p[1]]).unwrap();
            assert!(matches!(c, Containment::Inside { residual } if residual < 1e-7), "{c:?}");
        }
        // A point pushed 1 % beyond a vertex, away from the centroid, is outside (certified).
        let n = poly.len() as f64;
        let cen = [poly.iter().map(|p| p[0]).sum::<f64>() / n, poly.iter().map(|p| p[1]).sum::<f64>() / n];
        let p = poly[0];
        let out = [p[0] + 0.01 * (p[0] - cen[0]) + 1e-3, p[1] + 0.01 * (p[1] - cen[1])];
        let q = dvector![out[0], out[1]];
        let inside_poly = (0..poly.len()).all(|i| cross(poly[i], poly[(i + 1) % poly.len()], out) >= 0.0);
        if !inside_poly {
            assert_eq!(z.contains_point(&q).unwrap(), Containment::CertifiedOutside);
        }
    }
}

#[test]
fn reduction_gives_a_superset_within_its_limits() {
    let limits = ReductionLimits::new(8, 2).unwrap();
    for seed in 0..20 {
        let full = run(seed, 8, None);
        let reduced = run(seed, 8, Some(limits));
        for ((zf, poly), (zr, _)) in full.iter().zip(&reduced) {
            assert!(zr.generators() <= 8 && zr.constraints() <= 2);
            let hr = zr.interval_hull().unwrap();
            let (lo, hi) = bbox(poly);
            for i in 0..2 {
                assert!(hr.lower[i] <= lo[i] + 1e-12 && hr.upper[i] >= hi[i] - 1e-12);
            }
            for p in poly {
                assert_ne!(zr.contains_point(&dvector![p[0], p[1]]).unwrap(), Containment::CertifiedOutside);
            }
            let _ = zf;
        }
    }
}

#[test]
fn one_reduction_contains_the_set_it_reduces() {
    // A single reduction from the exact set: every vertex of the exact polygon stays inside.
    for seed in 0..20 {
        let (z, poly) = run(seed, 5, None).pop().unwrap();
        for limits in [ReductionLimits::new(30, 1).unwrap(), ReductionLimits::new(6, 0).unwrap()] {
            let r = z.reduce(&limits).unwrap();
            assert!(r.generators() <= limits.max_generators() && r.constraints() <= limits.max_constraints());
            for p in &poly {
                assert_ne!(r.contains_point(&dvector![p[0], p[1]]).unwrap(), Containment::CertifiedOutside);
            }
        }
    }
}

#[test]
fn an_exact_elimination_loses_nothing() {
    // The strip |x₁| ≤ 0.5 on the square: the constraint's implied range of its slack-free factor
    // lies inside [-1, 1] after rescaling, so eliminating it keeps the exact hull.
    let square = ConstrainedZonotope::from_box(&dvector![0.0, 0.0], &dvector![1.0, 1.0]).unwrap();
    let cut = square
        .intersect(&dmatrix![1.0, 0.0], &ConstrainedZonotope::from_box(&dvector![0.0], &dvector![0.5]).unwrap())
        .unwrap();
    let r = cut.reduce(&ReductionLimits::new(10, 0).unwrap()).unwrap();
    assert_eq!(r.constraints(), 0);
    let h = r.interval_hull().unwrap();
    assert!((h.upper[0] - 0.5).abs() < 1e-12 && (h.lower[0] + 0.5).abs() < 1e-12, "{h:?}");
    assert!((h.upper[1] - 1.0).abs() < 1e-12);
}

#[test]
fn contradicting_data_are_certified_empty_and_consistent_data_are_not() {
    let square = ConstrainedZonotope::from_box(&dvector![0.0, 0.0], &dvector![1.0, 1.0]).unwrap();
    let far = ConstrainedZonotope::from_box(&dvector![2.5], &dvector![0.4]).unwrap();
    let cut = square.intersect(&dmatrix![1.0, 1.0], &far).unwrap();
    assert_eq!(cut.emptiness(), Emptiness::CertifiedEmpty);
    assert!(cut.interval_hull().unwrap().certified_empty);
    // Touching at the corner x = (1, 1): x₁ + x₂ = 2 lies in [2.0, 2.8] — not empty.
    let touch = ConstrainedZonotope::from_box(&dvector![2.4], &dvector![0.4]).unwrap();
    let cut = square.intersect(&dmatrix![1.0, 1.0], &touch).unwrap();
    assert!(matches!(cut.emptiness(), Emptiness::Feasible { .. }));
    let h = cut.interval_hull().unwrap();
    assert!(!h.certified_empty && h.lower[0] <= 1.0 && h.upper[0] >= 1.0);
}

#[test]
fn any_multipliers_give_a_valid_bound() {
    let (z, poly) = run(3, 4, None).pop().unwrap();
    let (lo, _) = bbox(&poly);
    let mut rng = Lcg(99);
    let q: Vec<f64> = (0..z.generators()).map(|j| z.generator_matrix()[(0, j)]).collect();
    for _ in 0..200 {
        let lambda: Vec<f64> = (0..z.constraints()).map(|_| 3.0 * rng.next()).collect();
        let bound = hull::verified_lower(z.center()[0], &q, z.constraint_matrix(), z.constraint_rhs(), &lambda);
        assert!(bound <= lo[0] + 1e-12, "{bound} > {}", lo[0]);
    }
}

#[test]
fn rounding_is_enclosed_for_large_offsets() {
    // A centre of 1e8 and generators of 1e-6: the map's rounding (ulp(1e8) ≈ 1.5e-8) is covered by
    // a box, so the image of the exact corner points stays inside.
    let z = ConstrainedZonotope::from_box(&dvector![1e8, -1e8], &dvector![1e-6, 1e-6]).unwrap();
    let m = dmatrix![1.0 / 3.0, 2.0 / 3.0; -0.7, 0.1];
    let y = z.affine_map(&m, Some(&dvector![0.1, 0.2])).unwrap();
    assert!(y.generators() > z.generators(), "the rounding box was added");
    let h = y.interval_hull().unwrap();
    // Exact images of the corners, in i128 arithmetic on the scaled corner values (1e8 ± 1e-6
    // scaled by 1e6 are integers; the map's entries are handled as rationals with denominator 30).
    for (s0, s1) in [(-1i128, -1i128), (-1, 1), (1, -1), (1, 1)] {
        let x0 = 100_000_000_000_000i128 + s0; // (1e8 + s0·1e-6)·1e6
        let x1 = -100_000_000_000_000i128 + s1;
        // Row 0: (x0/3 + 2 x1/3)/1e6 + 0.1 ; row 1: (−0.7 x0 + 0.1 x1)/1e6 + 0.2.
        let r0 = (x0 + 2 * x1) as f64 / 3.0 / 1e6 + 0.1;
        let r1 = (-7 * x0 + x1) as f64 / 10.0 / 1e6 + 0.2;
        assert!(h.lower[0] <= r0 && r0 <= h.upper[0], "{r0} not in [{}, {}]", h.lower[0], h.upper[0]);
        assert!(h.lower[1] <= r1 && r1 <= h.upper[1], "{r1} not in [{}, {}]", h.lower[1], h.upper[1]);
    }
}

#[test]
fn bad_input_is_refused_before_allocating() {
    assert!(matches!(
        ConstrainedZonotope::from_box(&dvector![0.0], &dvector![-1.0]),
        Err(SetError::NegativeRadius { .. })
    ));
    assert!(matches!(
        ConstrainedZonotope::from_box(&dvector![f64::NAN], &dvector![1.0]),
        Err(SetError::NotFinite { .. })
    ));
    let z = ConstrainedZonotope::from_box(&dvector![0.0, 0.0], &dvector![1.0, 1.0]).unwrap();
    assert!(matches!(z.affine_map(&DMatrix::zeros(2, 3), None), Err(SetError::Dimension { .. })));
    assert!(matches!(ReductionLimits::new(MAX_GENERATORS + 1, 0), Err(SetError::TooLarge { .. })));
    assert!(matches!(ReductionLimits::new(0, 0), Err(SetError::InvalidLimits(_))));
    let huge = DVector::zeros(MAX_DIMENSION + 1);
    assert!(matches!(ConstrainedZonotope::from_box(&huge, &huge), Err(SetError::TooLarge { .. })));
    let mut big = z.clone();
    for _ in 0..12 {
        big = big.minkowski_sum(&big).unwrap_or(big.clone());
    }
    assert!(big.generators() <= MAX_GENERATORS);
    assert!(matches!(big.minkowski_sum(&big), Err(SetError::TooLarge { .. })));
}

#[test]
fn the_simplex_finds_the_exact_bounds_itself() {
    // The simplex alone (no Clarabel fallback): its multipliers give the polygon's bounds.
    use crate::simplex::{Simplex, SimplexResult};
    for seed in 0..20 {
        let (z, poly) = run(seed, 5, None).pop().unwrap();
        let (lo, hi) = bbox(&poly);
        let mut s = Simplex::new(z.constraint_matrix(), z.constraint_rhs());
        for i in 0..2 {
            for sign in [1.0, -1.0] {
                let q: Vec<f64> = (0..z.generators()).map(|j| sign * z.generator_matrix()[(i, j)]).collect();
                let SimplexResult::Optimal { y, .. } = s.solve(&q) else { panic!("seed {seed}: the simplex stopped") };
                let b = hull::verified_lower(sign * z.center()[i], &q, z.constraint_matrix(), z.constraint_rhs(), &y);
                let exact = if sign > 0.0 { lo[i] } else { -hi[i] };
                assert!(b <= exact + 1e-12 && exact - b < 1e-9, "seed {seed}, state {i}, sign {sign}: {b} vs {exact}");
            }
        }
    }
}

/// The dual bound of [`hull::verified_lower`] evaluated in outward-rounded interval arithmetic
/// instead of a-priori error bounds: an enclosure of the exact value of `c + λᵀb − ‖q − Aᵀλ‖₁`.
fn dual_bound_enclosure(c: f64, q: &[f64], a: &DMatrix<f64>, b: &DVector<f64>, lambda: &[f64]) -> intervals::Interval {
    use intervals::Interval;
    let mut total = Interval::point(c);
    for (l, bl) in lambda.iter().zip(b.iter()) {
        total = total + Interval::point(*l) * *bl;
    }
    for (j, qj) in q.iter().enumerate() {
        let mut r = Interval::point(*qj);
        for (i, l) in lambda.iter().enumerate() {
            r = r - Interval::point(*l) * a[(i, j)];
        }
        total = total - r.abs();
    }
    total
}

#[test]
fn the_a_priori_dual_bound_is_never_above_the_exact_value_and_close_to_it() {
    let mut rng = Lcg(7);
    for case in 0..400 {
        // Magnitudes from 1e-3 to 1e8, and multipliers that nearly cancel q (the optimum's case).
        let scale = 10f64.powi((case % 12) as i32 - 3);
        let (nc, ng) = (1 + case % 5, 3 + case % 17);
        let a = DMatrix::from_fn(nc, ng, |_, _| scale * rng.next());
        let b = DVector::from_fn(nc, |_, _| scale * rng.next());
        let lambda: Vec<f64> = (0..nc).map(|_| rng.next()).collect();
        let q: Vec<f64> =
            (0..ng).map(|j| (0..nc).map(|i| lambda[i] * a[(i, j)]).sum::<f64>() * (1.0 + 1e-14 * rng.next())).collect();
        let c = scale * 1e3 * rng.next();
        let fast = hull::verified_lower(c, &q, &a, &b, &lambda);
        let exact = dual_bound_enclosure(c, &q, &a, &b, &lambda);
        // Above the enclosure's upper end would be above the exact value: unsound.
        assert!(fast <= exact.hi(), "case {case}: {fast} > {}", exact.hi());
        let tol = 1e-12 * (c.abs() + scale * (1 + nc * ng) as f64);
        assert!(fast >= exact.lo() - tol, "case {case}: {fast} far below {}", exact.lo());
    }
}

#[test]
fn boxes_and_slacks_merge_into_existing_axis_factors() {
    let z = ConstrainedZonotope::from_box(&dvector![1.0, -2.0], &dvector![0.5, 0.25]).unwrap();
    let mut y = z.clone();
    for _ in 0..10 {
        y = y.add_box(&dvector![0.1, 0.2]).unwrap();
    }
    assert_eq!(y.generators(), 2, "collinear segments add, no new factors");
    let h = y.interval_hull().unwrap();
    for (i, r) in [1.5, 2.25].into_iter().enumerate() {
        assert!(h.lower[i] <= y.center()[i] - r && h.upper[i] >= y.center()[i] + r);
        assert!(h.upper[i] - h.lower[i] <= 2.0 * r + 1e-12);
    }
    // A strip intersected twice: the second intersection's rounding slacks join the first's.
    let strip = ConstrainedZonotope::from_box(&dvector![0.3], &dvector![0.2]).unwrap();
    let once = y.intersect(&dmatrix![1.0 / 3.0, 0.7], &strip).unwrap();
    let twice = once.intersect(&dmatrix![1.0 / 3.0, 0.7], &strip).unwrap();
    let slack_columns = |s: &ConstrainedZonotope| {
        (0..s.generators()).filter(|&j| s.generator_matrix().column(j).iter().all(|v| *v == 0.0)).count()
    };
    assert!(slack_columns(&twice) <= twice.constraints(), "at most one slack factor per row");
}
