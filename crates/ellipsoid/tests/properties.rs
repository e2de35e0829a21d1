//! Property tests: outer bounds contain what they must, containment is exact, bounds are tight.

use ellipsoid::{Ellipsoid, EllipsoidError, IntersectionBound, MeasurementSet};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

/// Tolerance on normalised distances.
const TOL: f64 = 1e-9;

/// SplitMix64: a small deterministic generator for the many samples of one case.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    fn gaussian(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    fn unit_vector(&mut self, n: usize) -> DVector<f64> {
        loop {
            let g = DVector::from_fn(n, |_, _| self.gaussian());
            let norm = g.norm();
            if norm > 1e-8 {
                return g / norm;
            }
        }
    }

    /// Uniform in the unit ball (`boundary`: on the unit sphere).
    fn ball_point(&mut self, n: usize, boundary: bool) -> DVector<f64> {
        let u = self.unit_vector(n);
        if boundary { u } else { u * self.uniform().powf(1.0 / n as f64) }
    }

    /// Uniform in `e` (or on its boundary): `c + L u`.
    fn sample(&mut self, e: &Ellipsoid, boundary: bool) -> DVector<f64> {
        e.center() + e.cholesky_factor() * self.ball_point(e.dim(), boundary)
    }
}

/// `Q diag(10^{e_i}) Qᵀ` with a random orthogonal `Q`, exponents spanning `log_cond` decades
/// around `log_scale`.
fn spd(n: usize, q: &[f64], ex: &[f64], log_scale: f64, log_cond: f64) -> DMatrix<f64> {
    let qm = DMatrix::from_column_slice(n, n, q).qr().q();
    let d = DVector::from_iterator(n, ex.iter().map(|e| 10f64.powf(log_scale + log_cond * (e - 0.5))));
    let p = &qm * DMatrix::from_diagonal(&d) * qm.transpose();
    (&p + p.transpose()) * 0.5
}

/// A random ellipsoid of dimension `n`; condition numbers up to `10^max_log_cond`.
fn ellipsoid(n: usize, max_log_cond: f64) -> impl Strategy<Value = Ellipsoid> {
    (
        prop::collection::vec(-3.0..3.0f64, n),
        prop::collection::vec(-1.0..1.0f64, n * n),
        prop::collection::vec(0.0..1.0f64, n),
        -1.0..1.0f64,
        0.0..=max_log_cond,
    )
        .prop_map(move |(c, q, ex, ls, lc)| {
            Ellipsoid::new(DVector::from_vec(c), spd(n, &q, &ex, ls, lc)).expect("valid SPD")
        })
}

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() }
}

/// Points in both sets: an interior common point and points pushed to the boundary of the
/// intersection along random rays from it (bisection), plus prior samples that fit.
fn common_points(prior: &Ellipsoid, meas: &MeasurementSet, x0: &DVector<f64>, rng: &mut Rng) -> Vec<DVector<f64>> {
    let inside = |x: &DVector<f64>| {
        prior.normalized_distance(x).expect("dim") <= 1.0 && meas.normalized_distance(x).expect("dim") <= 1.0
    };
    let mut pts = vec![x0.clone()];
    let reach = 2.0 * prior.trace().sqrt() + 1.0;
    for _ in 0..24 {
        let dir = rng.unit_vector(prior.dim());
        let (mut lo, mut hi) = (0.0, reach);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if inside(&(x0 + &dir * mid)) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        pts.push(x0 + &dir * lo);
    }
    for _ in 0..40 {
        let x = rng.sample(prior, false);
        if inside(&x) {
            pts.push(x);
        }
    }
    pts
}

/// A prior, a measurement set built to intersect it, the common point and the rng.
fn intersection_case() -> impl Strategy<Value = (Ellipsoid, MeasurementSet, DVector<f64>, u64)> {
    (1usize..=5)
        .prop_flat_map(|n| (Just(n), 1usize..=n + 1))
        .prop_flat_map(|(n, m)| {
            (ellipsoid(n, 3.0), prop::collection::vec(-2.0..2.0f64, m * n), ellipsoid(m, 2.0), any::<u64>())
        })
        .prop_map(|(prior, cvals, noise, seed)| {
            let n = prior.dim();
            let m = noise.dim();
            let c = DMatrix::from_row_slice(m, n, &cvals);
            let mut rng = Rng(seed);
            let x0 = rng.sample(&prior, false);
            let v = noise.cholesky_factor() * rng.ball_point(m, false);
            let y = &c * &x0 + v;
            let meas = MeasurementSet::new(c, y, noise.shape().clone()).expect("valid");
            (prior, meas, x0, seed)
        })
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn minkowski_bounds_contain_sums(
        (a, b, seed) in (1usize..=5).prop_flat_map(|n| (ellipsoid(n, 4.0), ellipsoid(n, 4.0), any::<u64>()))
    ) {
        let mut rng = Rng(seed);
        let (opt, p_star) = a.minkowski_sum_min_trace(&b).expect("ok");
        let mut bounds = vec![opt];
        for p in [p_star * 0.1, p_star * 10.0, 0.5, 2.0] {
            bounds.push(a.minkowski_sum_outer(&b, p).expect("ok"));
        }
        for k in 0..40 {
            let x = rng.sample(&a, k % 2 == 0) + rng.sample(&b, k % 3 != 0);
            for s in &bounds {
                let d = s.normalized_distance(&x).expect("dim");
                prop_assert!(d <= 1.0 + TOL, "sum point at normalised distance {d}");
            }
        }
        // Aligned support points are extreme: x = s_a(d) + s_b(d) maximises dᵀx over the sum,
        // so it cannot lie beyond the bound's support in d either.
        let d = rng.unit_vector(a.dim());
        let x = a.support_point(&d).expect("ok") + b.support_point(&d).expect("ok");
        prop_assert!(bounds[0].normalized_distance(&x).expect("dim") <= 1.0 + TOL);
    }

    #[test]
    fn minkowski_trace_optimum_beats_dense_scan(
        (a, b) in (1usize..=6).prop_flat_map(|n| (ellipsoid(n, 4.0), ellipsoid(n, 4.0)))
    ) {
        let (opt, p_star) = a.minkowski_sum_min_trace(&b).expect("ok");
        let t_star = opt.trace();
        let expected = (a.trace().sqrt() + b.trace().sqrt()).powi(2);
        prop_assert!((t_star - expected).abs() <= 1e-12 * expected);
        for k in 0..=600 {
            // p from p*·10⁻³ to p*·10³ and an absolute grid 10⁻⁴…10⁴.
            for p in [p_star * 10f64.powf(-3.0 + k as f64 / 100.0), 10f64.powf(-4.0 + k as f64 * 8.0 / 600.0)] {
                let t = a.minkowski_sum_outer(&b, p).expect("ok").trace();
                prop_assert!(t_star <= t * (1.0 + 1e-12), "p = {p}: {t} < {t_star}");
            }
        }
    }

    #[test]
    fn intersection_bounds_contain_common_points((prior, meas, x0, seed) in intersection_case()) {
        let mut rng = Rng(seed ^ 0xA5A5);
        let pts = common_points(&prior, &meas, &x0, &mut rng);
        let (best, lambda_star) = prior.intersect_measurement_min_trace(&meas).expect("ok");
        let mut bounds = vec![(lambda_star, best)];
        for lambda in [0.0, 0.05, 0.25, 0.5, 0.75, 0.95, 0.999, 1.0] {
            match prior.intersect_measurement(&meas, lambda) {
                Ok(b) => bounds.push((lambda, b)),
                // At λ = 1 with C close to rank-deficient the bound is (numerically) unbounded.
                Err(
                    EllipsoidError::UnboundedIntersection { .. }
                    | EllipsoidError::DegenerateResult { .. },
                ) if lambda == 1.0 => {}
                Err(e) => prop_assert!(false, "λ = {lambda}: {e}"),
            }
        }
        for (lambda, b) in &bounds {
            let IntersectionBound::Bounded(e) = b else {
                return Err(TestCaseError::fail(format!("λ = {lambda}: empty, but x0 is common")));
            };
            // Evaluating `(x − c)ᵀ P⁻¹ (x − c)` at a boundary point rounds at the level of the
            // shape's condition number times ε: near λ = 1 with an almost rank-deficient `C` the
            // bound is thin in some direction (a CI run met cond ≈ 10⁷ and a distance of
            // 1 + 1.3·10⁻⁹), so the tolerance grows with it; a wrong bound misses by O(1).
            let eig = e.shape().clone().symmetric_eigen().eigenvalues;
            let cond = eig.max() / eig.min();
            let tol = TOL.max(1e3 * f64::EPSILON * cond);
            for x in &pts {
                let d = e.normalized_distance(x).expect("dim");
                prop_assert!(d <= 1.0 + tol, "λ = {lambda}: common point at distance {d} (shape condition {cond:.1e})");
            }
        }
    }

    #[test]
    fn intersection_min_trace_beats_dense_scan((prior, meas, _x0, seed) in intersection_case(), far in 0.0..6.0f64) {
        // Move the measurement away by `far` (in measurement-noise units) so that some cases
        // are disjoint.
        let mut rng = Rng(seed);
        let shift = meas.noise_shape().clone().cholesky().expect("SPD").l()
            * rng.unit_vector(meas.measurement_dim()) * far;
        let meas = MeasurementSet::new(
            meas.output_matrix().clone(),
            meas.measurement() + shift,
            meas.noise_shape().clone(),
        ).expect("valid");
        let (best, lambda_star) = prior.intersect_measurement_min_trace(&meas).expect("ok");
        prop_assert!((0.0..=1.0).contains(&lambda_star));
        let mut scan_min = f64::INFINITY;
        let mut scan_empty = false;
        for k in 0..=400 {
            let lambda = k as f64 / 400.0;
            match prior.intersect_measurement(&meas, lambda) {
                Ok(IntersectionBound::Bounded(e)) => scan_min = scan_min.min(e.trace()),
                Ok(IntersectionBound::Empty { .. }) => scan_empty = true,
                Ok(other) => return Err(TestCaseError::fail(format!("λ = {lambda}: unexpected {other:?}"))),
                Err(
                    EllipsoidError::UnboundedIntersection { .. }
                    | EllipsoidError::DegenerateResult { .. },
                ) if k == 400 => {}
                Err(e) => return Err(TestCaseError::fail(format!("λ = {lambda}: {e}"))),
            }
        }
        if best.is_empty() {
            // Emptiness is certified by δ > 1 at the returned λ.
            prop_assert!(prior.intersect_measurement(&meas, lambda_star).expect("ok").is_empty());
        }
        if scan_empty {
            prop_assert!(best.is_empty(), "scan found emptiness, optimiser did not");
        } else if let IntersectionBound::Bounded(e) = &best {
            prop_assert!(e.trace() <= scan_min * (1.0 + 1e-9), "{} > scan {}", e.trace(), scan_min);
        }
    }

    #[test]
    fn containment_agrees_with_sampling(
        (outer, inner_shape, offset, scale) in (2usize..=3).prop_flat_map(|n| (
            ellipsoid(n, 2.0),
            ellipsoid(n, 2.0),
            prop::collection::vec(-0.5..0.5f64, n),
            -0.6..0.3f64,
        ))
    ) {
        let n = outer.dim();
        // Inner: centred near the outer centre, scaled to the outer size so answers vary.
        let ratio = (outer.trace() / inner_shape.trace()).sqrt() * 10f64.powf(scale);
        let center = outer.center() + outer.cholesky_factor() * DVector::from_vec(offset);
        let inner = Ellipsoid::new(center, inner_shape.shape() * (ratio * ratio)).expect("valid");

        let exact = outer.max_normalized_distance(&inner).expect("ok");
        let answer = outer.contains_ellipsoid(&inner).expect("ok");
        prop_assert_eq!(answer, exact <= 1.0 + 1e-9);
        let (far, far_d) = outer.farthest_point(&inner).expect("ok");
        prop_assert!((far_d - exact).abs() <= 1e-9 * exact.max(1.0), "primal {far_d} vs {exact}");
        prop_assert!((inner.normalized_distance(&far).expect("dim") - 1.0).abs() <= 1e-9);

        let dirs: Vec<DVector<f64>> = if n == 2 {
            (0..2000).map(|k| {
                let t = 2.0 * std::f64::consts::PI * k as f64 / 2000.0;
                DVector::from_vec(vec![t.cos(), t.sin()])
            }).collect()
        } else {
            let count = 3000;
            let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
            (0..count).map(|k| {
                let z = 1.0 - 2.0 * (k as f64 + 0.5) / count as f64;
                let r = (1.0 - z * z).sqrt();
                let t = golden * k as f64;
                DVector::from_vec(vec![r * t.cos(), r * t.sin(), z])
            }).collect()
        };
        let mut sampled_max = 0.0_f64;
        for u in dirs {
            let x = inner.center() + inner.cholesky_factor() * u;
            sampled_max = sampled_max.max(outer.normalized_distance(&x).expect("dim"));
        }
        prop_assert!(sampled_max <= exact + 1e-9 * exact.max(1.0), "sampled {sampled_max} > exact {exact}");
        if sampled_max > 1.0 + 1e-9 {
            prop_assert!(!answer, "a sampled boundary point is outside, yet contained");
        }
        if exact <= 1.0 - 1e-6 {
            prop_assert!(sampled_max <= 1.0);
        }
    }

    #[test]
    fn just_inside_and_just_outside(
        (e, seed) in (1usize..=6).prop_flat_map(|n| (ellipsoid(n, 4.0), any::<u64>()))
    ) {
        let mut rng = Rng(seed);
        for (s, inside) in [(0.999, true), (1.001, false)] {
            let copy = e.scaled(s).expect("ok");
            let m = e.max_normalized_distance(&copy).expect("ok");
            prop_assert!((m - s * s).abs() <= 1e-9, "max {m} vs {}", s * s);
            prop_assert_eq!(e.contains_ellipsoid(&copy).expect("ok"), inside);
        }
        // Homothetic copy c + t (q − c) + s (𝓔 − c) with q on the boundary: max = (t + s)².
        let q = rng.sample(&e, true);
        let t = 0.3;
        for (s, inside) in [(0.699, true), (0.701, false)] {
            let copy = e.scaled(s).expect("ok").translated(&((&q - e.center()) * t)).expect("ok");
            let m = e.max_normalized_distance(&copy).expect("ok");
            prop_assert!((m - (t + s) * (t + s)).abs() <= 1e-9, "max {m} vs {}", (t + s) * (t + s));
            prop_assert_eq!(e.contains_ellipsoid(&copy).expect("ok"), inside);
        }
    }

    #[test]
    fn coordinate_bounds_are_attained(e in (1usize..=8).prop_flat_map(|n| ellipsoid(n, 4.0))) {
        let n = e.dim();
        let (lo, hi) = e.bounding_box();
        for i in 0..n {
            let (a, b) = e.interval(i).expect("ok");
            prop_assert_eq!((a, b), (lo[i], hi[i]));
            let scale = e.shape()[(i, i)].sqrt() + e.center()[i].abs();
            for (sign, bound) in [(1.0, b), (-1.0, a)] {
                let mut d = DVector::zeros(n);
                d[i] = sign;
                let x = e.support_point(&d).expect("ok");
                prop_assert!((x[i] - bound).abs() <= 1e-12 * scale, "coordinate {} vs {bound}", x[i]);
                prop_assert!((e.normalized_distance(&x).expect("dim") - 1.0).abs() <= TOL);
                prop_assert!((sign * e.support(&d).expect("ok") - bound).abs() <= 1e-12 * scale);
            }
        }
    }

    #[test]
    fn support_function_dominates_points(
        (e, seed) in (1usize..=6).prop_flat_map(|n| (ellipsoid(n, 4.0), any::<u64>()))
    ) {
        let mut rng = Rng(seed);
        for _ in 0..8 {
            let d = rng.unit_vector(e.dim()) * (0.1 + 10.0 * rng.uniform());
            let h = e.support(&d).expect("ok");
            let x_star = e.support_point(&d).expect("ok");
            let scale = h.abs() + d.norm() * (e.center().norm() + e.trace().sqrt());
            prop_assert!((d.dot(&x_star) - h).abs() <= 1e-12 * scale);
            prop_assert!((e.normalized_distance(&x_star).expect("dim") - 1.0).abs() <= TOL);
            for _ in 0..20 {
                let x = rng.sample(&e, true);
                prop_assert!(d.dot(&x) <= h + 1e-12 * scale);
            }
        }
    }

    #[test]
    fn affine_images_contain_mapped_points(
        (e, a_vals, m, b_vals, seed) in (1usize..=5).prop_flat_map(|n| (
            ellipsoid(n, 3.0),
            prop::collection::vec(-2.0..2.0f64, n * n),
            1usize..=n,
            prop::collection::vec(-3.0..3.0f64, n),
            any::<u64>(),
        ))
    ) {
        let n = e.dim();
        // The first m rows of a random square matrix (full row rank almost surely).
        let a_full = DMatrix::from_row_slice(n, n, &a_vals);
        let a = a_full.rows(0, m).into_owned();
        let b = DVector::from_column_slice(&b_vals[..m]);
        let img = match e.affine_map(&a, &b) {
            Ok(img) => img,
            // A (numerically) rank-deficient random draw.
            Err(EllipsoidError::DegenerateImage { .. }) => return Ok(()),
            Err(err) => return Err(TestCaseError::fail(err.to_string())),
        };
        // The map is exact: boundary points go to the boundary, up to rounding that grows with
        // the condition number κ of A P Aᵀ (a random A can be nearly singular).
        let eig = img.shape().clone().symmetric_eigen().eigenvalues;
        let kappa = eig.max() / eig.min();
        let tol = TOL.max(1e-14 * kappa);
        let mut rng = Rng(seed);
        for k in 0..30 {
            let x = rng.sample(&e, k % 2 == 0);
            let d = img.normalized_distance(&(&a * &x + &b)).expect("dim");
            prop_assert!(d <= 1.0 + tol, "image point at {d} (κ = {kappa:e})");
            if m == n && k % 2 == 0 {
                prop_assert!((d - 1.0).abs() <= tol, "boundary maps to {d} (κ = {kappa:e})");
            }
        }
    }

    #[test]
    fn projections_contain_projected_points(
        (e, seed) in (2usize..=6).prop_flat_map(|n| (ellipsoid(n, 3.0), any::<u64>()))
    ) {
        let mut rng = Rng(seed);
        let n = e.dim();
        let i = (rng.next_u64() % n as u64) as usize;
        let j = (i + 1 + (rng.next_u64() % (n as u64 - 1)) as usize) % n;
        let proj = e.project(&[i, j]).expect("ok");
        for _ in 0..30 {
            let x = rng.sample(&e, true);
            let d = proj.normalized_distance(&DVector::from_vec(vec![x[i], x[j]])).expect("dim");
            prop_assert!(d <= 1.0 + TOL);
        }
        for p in e.projection_boundary(i, j, 12).expect("ok") {
            let d = proj.normalized_distance(&DVector::from_vec(p.to_vec())).expect("dim");
            prop_assert!((d - 1.0).abs() <= TOL);
        }
        // Volume is consistent with the determinant: scaling by s adds n·ln s.
        let s = 1.7;
        let lv = e.scaled(s).expect("ok").log_volume() - e.log_volume();
        prop_assert!((lv - n as f64 * s.ln()).abs() <= 1e-10);
    }
}

proptest! {
    #![proptest_config(config(32))]

    /// Larger dimensions (as used by the estimators): the main operations stay consistent.
    #[test]
    fn large_dimensions(
        (a, b, cvals, seed) in (10usize..=20).prop_flat_map(|n| (
            ellipsoid(n, 3.0),
            ellipsoid(n, 3.0),
            prop::collection::vec(-2.0..2.0f64, 4 * n),
            any::<u64>(),
        ))
    ) {
        let n = a.dim();
        let mut rng = Rng(seed);
        let (sum, _) = a.minkowski_sum_min_trace(&b).expect("ok");
        for _ in 0..10 {
            let x = rng.sample(&a, true) + rng.sample(&b, true);
            prop_assert!(sum.normalized_distance(&x).expect("dim") <= 1.0 + TOL);
        }
        prop_assert!(sum.contains_ellipsoid(&a.translated(b.center()).expect("ok")).expect("ok"));
        let s = 0.999;
        prop_assert!(a.contains_ellipsoid(&a.scaled(s).expect("ok")).expect("ok"));
        prop_assert!(!a.contains_ellipsoid(&a.scaled(1.0 / s).expect("ok")).expect("ok"));

        let c = DMatrix::from_row_slice(4, n, &cvals);
        let x0 = rng.sample(&a, false);
        let noise = DMatrix::<f64>::identity(4, 4) * 0.5;
        let y = &c * &x0 + rng.ball_point(4, false) * 0.5f64.sqrt();
        let meas = MeasurementSet::new(c, y, noise).expect("valid");
        let (bound, _) = a.intersect_measurement_min_trace(&meas).expect("ok");
        let e = bound.ellipsoid().expect("x0 is common");
        for x in common_points(&a, &meas, &x0, &mut rng) {
            prop_assert!(e.normalized_distance(&x).expect("dim") <= 1.0 + TOL);
        }
        prop_assert!(e.trace() <= a.trace() * (1.0 + 1e-12));
    }
}
