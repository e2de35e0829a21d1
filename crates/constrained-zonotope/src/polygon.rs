//! Planar convex polygons as vertex lists: the independent reference the tests compare every set
//! operation with (convex hulls, linear maps, Minkowski sums of vertex sums, half-plane clipping).
//! Plain floating point, not enclosed: a reference, not a bound.

use nalgebra::DMatrix;

/// A point of the plane.
pub type P = [f64; 2];

/// `(a − o) × (b − o)`: positive when `o, a, b` turn counter-clockwise.
#[must_use]
pub fn cross(o: P, a: P, b: P) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// Convex hull (Andrew's monotone chain), counter-clockwise.
#[must_use]
pub fn hull(mut pts: Vec<P>) -> Vec<P> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let mut lower: Vec<P> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<P> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// The box of centre `c` and radii `r`.
#[must_use]
pub fn box_poly(c: P, r: P) -> Vec<P> {
    vec![[c[0] - r[0], c[1] - r[1]], [c[0] + r[0], c[1] - r[1]], [c[0] + r[0], c[1] + r[1]], [c[0] - r[0], c[1] + r[1]]]
}

/// The image `M x + d` of a polygon (`M` is `2 × 2`).
#[must_use]
pub fn map_poly(m: &DMatrix<f64>, d: P, poly: &[P]) -> Vec<P> {
    hull(
        poly.iter()
            .map(|p| [m[(0, 0)] * p[0] + m[(0, 1)] * p[1] + d[0], m[(1, 0)] * p[0] + m[(1, 1)] * p[1] + d[1]])
            .collect(),
    )
}

/// The Minkowski sum: the hull of the sums of vertices.
#[must_use]
pub fn sum_poly(a: &[P], b: &[P]) -> Vec<P> {
    hull(a.iter().flat_map(|p| b.iter().map(move |q| [p[0] + q[0], p[1] + q[1]])).collect())
}

/// `poly ∩ {x : hᵀ x ≤ k}` (Sutherland–Hodgman on one half-plane).
#[must_use]
pub fn clip(poly: &[P], h: P, k: f64) -> Vec<P> {
    let f = |p: P| h[0] * p[0] + h[1] * p[1] - k;
    let mut out = Vec::new();
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (fp, fq) = (f(p), f(q));
        if fp <= 0.0 {
            out.push(p);
        }
        if (fp < 0.0 && fq > 0.0) || (fp > 0.0 && fq < 0.0) {
            let t = fp / (fp - fq);
            out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
        }
    }
    out
}

/// `poly ∩ {x : |hᵀ x − y| ≤ v}`.
#[must_use]
pub fn strip(poly: &[P], h: P, y: f64, v: f64) -> Vec<P> {
    clip(&clip(poly, h, y + v), [-h[0], -h[1]], -(y - v))
}

/// The bounding box `(lower, upper)`.
#[must_use]
pub fn bbox(poly: &[P]) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in poly {
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    (lo, hi)
}
