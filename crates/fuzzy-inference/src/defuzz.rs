//! Centroid defuzzification of the aggregated output `μ(x) = max_k min(β_k, μ_k(x))`, where `β_k` is
//! the largest strength of the rules concluding output set `k` (implication = min, aggregation = max).
//!
//! Three methods:
//!
//! * [`sampled`]: `Σ x_i μ(x_i) / Σ μ(x_i)` on `n` equally spaced points of the universe, ends
//!   included (the textbook reference). When `μ` vanishes at both ends of the universe this equals
//!   scikit-fuzzy's `centroid`, the exact centroid of the linear interpolant of the samples: the two
//!   differ by `h² (μ_0 − μ_{n−1}) / 6` in the moment.
//! * [`exact`]: the centroid of the piecewise-linear `μ` itself. Between consecutive breakpoints (set
//!   corners, the points where a set's edge crosses its clip level `β_k`, the universe's ends) every
//!   clipped set is linear, and their maximum is the upper envelope of at most `K` segments, whose
//!   crossings are found exactly; each linear piece is integrated in closed form.
//! * [`CentroidGrid`]: area and moment of `μ` tabulated once (by the exact method) on a regular grid
//!   of `β ∈ [0, 1]^K` and interpolated multilinearly; the centroid is the ratio of the two
//!   interpolants (interpolating area and moment, not their ratio, keeps it defined near `β = 0`).

use crate::FuzzyError;
use crate::membership::degree;

/// The most output sets a system may have (stack scratch of the allocation-free evaluation).
pub const MAX_OUTPUT_SETS: usize = 16;

/// Area `∫μ` and first moment `∫xμ` of the aggregated output, by the sampled sums (`h`-weighted, so
/// they approximate the integrals).
pub(crate) fn sampled(sets: &[[f64; 4]], beta: &[f64], (lo, hi): (f64, f64), points: usize) -> (f64, f64) {
    let step = (hi - lo) / (points - 1) as f64;
    let (mut area, mut moment) = (0.0, 0.0);
    for i in 0..points {
        // As numpy's `linspace`: `i * step + lo`, the last point exactly `hi`.
        let x = if i + 1 == points { hi } else { i as f64 * step + lo };
        let mut mu = 0.0_f64;
        for (s, &b) in sets.iter().zip(beta) {
            if b > 0.0 {
                mu = mu.max(b.min(degree(s, x)));
            }
        }
        area += mu;
        moment += x * mu;
    }
    (area * step, moment * step)
}

/// The values at `x0` and `x1` of the linear piece of trapezoid `s` that contains the open interval
/// `(x0, x1)` (which contains no corner of `s`). One-sided, so vertical edges are handled.
#[inline]
fn piece(&[a, b, c, d]: &[f64; 4], x0: f64, x1: f64) -> (f64, f64) {
    let mid = 0.5 * (x0 + x1);
    if mid <= a || mid >= d {
        (0.0, 0.0)
    } else if mid < b {
        ((x0 - a) / (b - a), (x1 - a) / (b - a))
    } else if mid <= c {
        (1.0, 1.0)
    } else {
        ((d - x0) / (d - c), (d - x1) / (d - c))
    }
}

/// Exact area `∫μ` and moment `∫xμ` of the aggregated piecewise-linear output over the universe.
/// Allocation-free: at most `6 K + 2` breakpoints on the stack.
pub(crate) fn exact(sets: &[[f64; 4]], beta: &[f64], (lo, hi): (f64, f64)) -> (f64, f64) {
    let mut xs = [0.0_f64; 6 * MAX_OUTPUT_SETS + 2];
    let mut n = 0;
    let mut push = |x: f64| {
        xs[n] = x.clamp(lo, hi);
        n += 1;
    };
    push(lo);
    push(hi);
    for (&[a, b, c, d], &beta_k) in sets.iter().zip(beta) {
        if beta_k <= 0.0 {
            continue;
        }
        for x in [a, b, c, d] {
            push(x);
        }
        if beta_k < 1.0 {
            push(a + beta_k * (b - a));
            push(d - beta_k * (d - c));
        }
    }
    let xs = &mut xs[..n];
    xs.sort_unstable_by(f64::total_cmp);

    let k = sets.len();
    let (mut y0, mut y1) = ([0.0_f64; MAX_OUTPUT_SETS], [0.0_f64; MAX_OUTPUT_SETS]);
    let (mut area, mut moment) = (0.0, 0.0);
    for w in xs.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        if x1 <= x0 {
            continue;
        }
        for j in 0..k {
            let (p, q) = if beta[j] > 0.0 { piece(&sets[j], x0, x1) } else { (0.0, 0.0) };
            y0[j] = beta[j].min(p).max(0.0);
            y1[j] = beta[j].min(q).max(0.0);
        }
        // Upper envelope of the k segments on the parameter s ∈ [0, 1]: start with the highest line at
        // s = 0 (ties: the steeper); switch to the first steeper line that overtakes it. Slopes
        // strictly increase, so at most k switches.
        let slope = |j: usize| y1[j] - y0[j];
        let value = |j: usize, s: f64| y0[j] + slope(j) * s;
        let mut cur = 0;
        for j in 1..k {
            if y0[j] > y0[cur] || (y0[j] == y0[cur] && slope(j) > slope(cur)) {
                cur = j;
            }
        }
        let mut s = 0.0;
        loop {
            let mut next = 1.0;
            let mut next_line = None;
            for j in 0..k {
                let ds = slope(j) - slope(cur);
                if ds > 0.0 {
                    let cross = ((y0[cur] - y0[j]) / ds).max(s);
                    if cross < next || (cross == next && next_line.is_some_and(|l: usize| slope(j) > slope(l))) {
                        next = cross;
                        next_line = Some(j);
                    }
                }
            }
            let (xa, xb) = (x0 + s * (x1 - x0), x0 + next * (x1 - x0));
            let (ya, yb) = (value(cur, s), value(cur, next));
            let width = xb - xa;
            if width > 0.0 {
                let piece_area = 0.5 * width * (ya + yb);
                area += piece_area;
                moment += xa * piece_area + width * width * (ya + 2.0 * yb) / 6.0;
            }
            match next_line {
                Some(j) if next < 1.0 => {
                    s = next;
                    cur = j;
                }
                _ => break,
            }
        }
    }
    (area, moment)
}

/// The area and moment of the aggregated output tabulated on a regular grid of the clip levels
/// `β ∈ [0, 1]^K`, for multilinear interpolation. Built once by [`exact`]; `points_per_axis^K`
/// nodes.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CentroidGrid {
    points: usize,
    dims: usize,
    area: Vec<f64>,
    moment: Vec<f64>,
}

/// The largest grid accepted, in nodes.
pub(crate) const MAX_GRID_NODES: usize = 1 << 22;
/// The most output sets the grid accepts (the interpolation visits `2^K` nodes).
pub(crate) const MAX_GRID_DIMS: usize = 8;

impl CentroidGrid {
    pub(crate) fn new(sets: &[[f64; 4]], universe: (f64, f64), points: usize) -> Result<Self, FuzzyError> {
        let dims = sets.len();
        if points < 2 {
            return Err(FuzzyError::InvalidDefuzzifier {
                reason: format!("grid needs >= 2 points per axis, got {points}"),
            });
        }
        let nodes = (0..dims).try_fold(1_usize, |acc, _| acc.checked_mul(points).filter(|&n| n <= MAX_GRID_NODES));
        let Some(nodes) = nodes.filter(|_| dims <= MAX_GRID_DIMS) else {
            return Err(FuzzyError::InvalidDefuzzifier {
                reason: format!(
                    "grid of {points}^{dims} nodes exceeds the limit ({MAX_GRID_NODES} nodes, {MAX_GRID_DIMS} output sets)"
                ),
            });
        };
        let mut area = Vec::with_capacity(nodes);
        let mut moment = Vec::with_capacity(nodes);
        let mut beta = [0.0_f64; MAX_OUTPUT_SETS];
        let scale = 1.0 / (points - 1) as f64;
        for node in 0..nodes {
            let mut rest = node;
            for b in beta.iter_mut().take(dims) {
                *b = (rest % points) as f64 * scale;
                rest /= points;
            }
            let (a, m) = exact(sets, &beta[..dims], universe);
            area.push(a);
            moment.push(m);
        }
        Ok(Self { points, dims, area, moment })
    }

    /// Interpolated `(area, moment)` at `beta` (each in `[0, 1]`).
    pub(crate) fn lookup(&self, beta: &[f64]) -> (f64, f64) {
        let last = (self.points - 1) as f64;
        let mut base = [0_usize; MAX_GRID_DIMS];
        let mut frac = [0.0_f64; MAX_GRID_DIMS];
        let mut stride = [0_usize; MAX_GRID_DIMS];
        let mut st = 1;
        for j in 0..self.dims {
            let t = beta[j].clamp(0.0, 1.0) * last;
            let i = (t.floor() as usize).min(self.points - 2);
            base[j] = i;
            frac[j] = t - i as f64;
            stride[j] = st;
            st *= self.points;
        }
        let origin: usize = (0..self.dims).map(|j| base[j] * stride[j]).sum();
        let (mut area, mut moment) = (0.0, 0.0);
        for corner in 0..(1_usize << self.dims) {
            let mut w = 1.0;
            let mut idx = origin;
            for j in 0..self.dims {
                if corner >> j & 1 == 1 {
                    w *= frac[j];
                    idx += stride[j];
                } else {
                    w *= 1.0 - frac[j];
                }
            }
            if w != 0.0 {
                area += w * self.area[idx];
                moment += w * self.moment[idx];
            }
        }
        (area, moment)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SETS: [[f64; 4]; 3] = [[-0.7, 0.0, 0.0, 0.7], [0.0, 0.7, 0.7, 1.4], [0.7, 1.4, 1.4, 2.1]];
    const U: (f64, f64) = (-0.7, 2.1);

    #[test]
    fn single_full_triangle() {
        let (a, m) = exact(&SETS, &[0.0, 1.0, 0.0], U);
        assert!((a - 0.7).abs() < 1e-15);
        assert!((m / a - 0.7).abs() < 1e-15);
    }

    #[test]
    fn clipped_triangle_area() {
        for beta in [0.1, 0.25, 0.5, 0.9] {
            let (a, m) = exact(&SETS, &[0.0, beta, 0.0], U);
            assert!((a - 0.7 * beta * (2.0 - beta)).abs() < 1e-14, "{beta}: {a}");
            assert!((m / a - 0.7).abs() < 1e-14);
        }
    }

    #[test]
    fn exact_matches_fine_sampling() {
        // Overlapping clipped sets with crossings inside segments; vertical edges.
        let sets = [[0.0, 1.0, 1.0, 3.0], [1.0, 2.5, 3.0, 3.0], [0.5, 0.5, 0.8, 1.7]];
        for beta in [[0.6, 0.8, 0.0], [1.0, 0.3, 0.7], [0.2, 0.2, 0.2], [0.05, 1.0, 0.9]] {
            // μ vanishes at both ends, so the sampled sums are trapezoid-rule integrals; a vertical edge
            // (a jump of up to 1) costs them O(h): |Δc| <= h · jump · |x − c| / A ≈ 1e-5 · 2 / 1.
            let (a, m) = exact(&sets, &beta, (0.0, 3.5));
            let (sa, sm) = sampled(&sets, &beta, (0.0, 3.5), 350_001);
            assert!((m / a - sm / sa).abs() < 2e-5, "{beta:?}: {} vs {}", m / a, sm / sa);
            assert!((a - sa).abs() < 1e-5, "{beta:?}: {a} vs {sa}");
        }
    }

    #[test]
    fn grid_is_exact_at_nodes() {
        let grid = CentroidGrid::new(&SETS, U, 5).unwrap();
        let beta = [0.25, 0.5, 1.0];
        let (a, m) = grid.lookup(&beta);
        let (ea, em) = exact(&SETS, &beta, U);
        assert!((a - ea).abs() < 1e-14 && (m - em).abs() < 1e-14);
        assert!(CentroidGrid::new(&SETS, U, 1).is_err());
        assert!(CentroidGrid::new(&SETS, U, 1 << 12).is_err());
    }
}
