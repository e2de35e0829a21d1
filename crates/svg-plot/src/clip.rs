//! What is drawn, as [`Shape`]s in data coordinates, and their clipping to the plot area
//! (plotters itself would only clamp points to its edges): Liang–Barsky for polylines,
//! Sutherland–Hodgman for polygons; points that fall on their predecessor's position are dropped,
//! and long dashed lines get longer dashes.

use std::collections::BTreeSet;

use plotters::style::RGBColor;

use crate::layout::Frame;
use crate::style::{Dash, K, MAX_DASHES};
use crate::{Polyline, Pt};

/// Something to draw. Produced in data coordinates, then clipped to the plot ranges and rid of
/// points that fall on the position (in drawing units) of their predecessor by [`clip_shapes`].
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Shape {
    /// A filled polygon (a band).
    Fill { pts: Vec<Pt>, color: RGBColor, opacity: f64 },
    /// A polyline.
    Stroke { pts: Vec<Pt>, color: RGBColor, width: u32, dashed: Option<Dash> },
    /// Dots of radius `r` drawing units.
    Dots { pts: Vec<Pt>, color: RGBColor, r: u32 },
    /// A filled bar between the corners `a` and `b`.
    Bar { a: Pt, b: Pt, color: RGBColor },
}

/// Clips every shape to the axis ranges of `f` and drops points that land on the same position (in
/// drawing units) as their predecessor (dots: in the same half-pixel cell as any other dot of the shape).
pub(crate) fn clip_shapes(shapes: Vec<Shape>, f: &Frame) -> Vec<Shape> {
    let to_frac = |(x, y): Pt| (f.x.frac(x), f.y.frac(y));
    let to_data = |(u, v): Pt| (f.x.value(u), f.y.value(v));
    // Fractions to data coordinates, skipping points on the position of the previous one.
    let thin = |pts: &[Pt]| -> Vec<Pt> {
        let mut out: Vec<Pt> = Vec::with_capacity(pts.len());
        let mut last = None;
        for &p in pts {
            let d = to_data(p);
            let px = f.pixel(d);
            if last != Some(px) {
                out.push(d);
                last = Some(px);
            }
        }
        out
    };
    let mut out = Vec::with_capacity(shapes.len());
    for shape in shapes {
        match shape {
            Shape::Fill { pts, color, opacity } => {
                let pts = thin(&clip_polygon(pts.into_iter().map(to_frac).collect()));
                if pts.len() >= 3 {
                    out.push(Shape::Fill { pts, color, opacity });
                }
            }
            Shape::Stroke { pts, color, width, dashed } => {
                let frac: Vec<Pt> = pts.into_iter().map(to_frac).collect();
                for piece in clip_polyline(&frac) {
                    let pts = thin(&piece);
                    if pts.len() >= 2 {
                        out.push(Shape::Stroke { pts, color, width, dashed });
                    }
                }
            }
            Shape::Dots { pts, color, r } => {
                let mut seen = BTreeSet::new();
                let pts: Vec<Pt> = pts
                    .into_iter()
                    .map(to_frac)
                    .filter(|&p| inside(p))
                    .map(to_data)
                    // One dot per half-pixel cell is indistinguishable from all of them.
                    .filter(|&p| seen.insert((f.pixel(p).0.div_euclid(K / 2), f.pixel(p).1.div_euclid(K / 2))))
                    .collect();
                if !pts.is_empty() {
                    out.push(Shape::Dots { pts, color, r });
                }
            }
            Shape::Bar { a, b, color } => {
                let (a, b) = (to_frac(a), to_frac(b));
                let (a, b) = ((a.0.clamp(0.0, 1.0), a.1.clamp(0.0, 1.0)), (b.0.clamp(0.0, 1.0), b.1.clamp(0.0, 1.0)));
                if a.0 != b.0 && a.1 != b.1 {
                    out.push(Shape::Bar { a: to_data(a), b: to_data(b), color });
                }
            }
        }
    }
    // Dashes: at most MAX_DASHES per series of the same colour and pattern.
    let mut length: Vec<(RGBColor, Dash, f64)> = Vec::new();
    for shape in &out {
        if let Shape::Stroke { pts, color, dashed: Some(d), .. } = shape {
            let l: f64 = pts.windows(2).map(|s| pixel_distance(f, s[0], s[1])).sum();
            match length.iter_mut().find(|(c, dd, _)| c == color && dd == d) {
                Some(e) => e.2 += l,
                None => length.push((*color, *d, l)),
            }
        }
    }
    for shape in &mut out {
        if let Shape::Stroke { color, dashed: Some(d), .. } = shape {
            if let Some(&(_, _, l)) = length.iter().find(|(c, dd, _)| c == color && dd == d) {
                let scale = (l / (MAX_DASHES * (d.on + d.off))).max(1.0);
                *d = Dash { on: d.on * scale, off: d.off * scale };
            }
        }
    }
    out
}

pub(crate) fn pixel_distance(f: &Frame, a: Pt, b: Pt) -> f64 {
    let (pa, pb) = (f.pixel(a), f.pixel(b));
    f64::from(pa.0 - pb.0).hypot(f64::from(pa.1 - pb.1))
}

/// Whether the point (in fractions of the ranges) is inside the plot.
pub(crate) fn inside((u, v): Pt) -> bool {
    (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)
}

/// The part of the segment `p`–`q` inside the unit square (Liang–Barsky), keeping the ends that are inside.
pub(crate) fn clip_segment(p: Pt, q: Pt) -> Option<(Pt, Pt)> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (pk, qk) in [(-dx, p.0), (dx, 1.0 - p.0), (-dy, p.1), (dy, 1.0 - p.1)] {
        if pk == 0.0 {
            if qk < 0.0 {
                return None;
            }
        } else {
            let t = qk / pk;
            if pk < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
            if t0 > t1 {
                return None;
            }
        }
    }
    let at = |t: f64| (p.0 + t * dx, p.1 + t * dy);
    let a = if t0 == 0.0 { p } else { at(t0) };
    let b = if t1 == 1.0 { q } else { at(t1) };
    Some((a, b))
}

/// The pieces of a polyline (in fractions of the ranges) inside the unit square.
pub(crate) fn clip_polyline(pts: &[Pt]) -> Vec<Polyline> {
    if let [p] = pts {
        return if inside(*p) { vec![vec![*p]] } else { Vec::new() };
    }
    let mut out = Vec::new();
    let mut cur: Polyline = Vec::new();
    for s in pts.windows(2) {
        match clip_segment(s[0], s[1]) {
            None => {
                if !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
            }
            Some((a, b)) => {
                if cur.last() != Some(&a) {
                    if !cur.is_empty() {
                        out.push(std::mem::take(&mut cur));
                    }
                    cur.push(a);
                }
                cur.push(b);
                if b != s[1] {
                    out.push(std::mem::take(&mut cur));
                }
            }
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// A polygon (in fractions of the ranges) clipped to the unit square (Sutherland–Hodgman).
pub(crate) fn clip_polygon(mut poly: Vec<Pt>) -> Vec<Pt> {
    // Each edge of the square as (coordinate index, bound, keep the side above the bound).
    for (axis, bound, above) in [(0, 0.0, true), (0, 1.0, false), (1, 0.0, true), (1, 1.0, false)] {
        let coord = |p: &Pt| if axis == 0 { p.0 } else { p.1 };
        let keep = |p: &Pt| if above { coord(p) >= bound } else { coord(p) <= bound };
        let cross = |a: &Pt, b: &Pt| {
            let t = (bound - coord(a)) / (coord(b) - coord(a));
            let p = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            if axis == 0 { (bound, p.1) } else { (p.0, bound) }
        };
        let mut out = Vec::with_capacity(poly.len() + 4);
        for i in 0..poly.len() {
            let (cur, prev) = (&poly[i], &poly[(i + poly.len() - 1) % poly.len()]);
            match (keep(prev), keep(cur)) {
                (true, true) => out.push(*cur),
                (true, false) => out.push(cross(prev, cur)),
                (false, true) => {
                    out.push(cross(prev, cur));
                    out.push(*cur);
                }
                (false, false) => {}
            }
        }
        poly = out;
    }
    poly
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::*;
    use crate::{Chart, PALETTE, Series};

    #[test]
    fn lines_are_clipped_not_clamped() {
        // With a fixed range narrower than the data, plotters alone would run the line along the
        // frame; clipped, no segment lies on the top or bottom edge of the plot.
        let t: Vec<f64> = (0..2000).map(|i| i as f64 * 0.01).collect();
        let mut c = Chart::new("", "", "");
        c.add(Series::line("", t.clone(), t.iter().map(|t| t.sin()).collect(), PALETTE[1]));
        c.y_range = Some((-0.5, 0.5));
        c.x_range = Some((2.0, 18.0));
        let svg = c.to_svg();
        let f = Frame::layout(&c.spec(), (800 * K, 380 * K), (0, 0));
        let pieces = paths(&svg, "polyline", "#0072B2");
        assert!(pieces.len() >= 4, "the line is cut where it leaves the range: {} pieces", pieces.len());
        for piece in &pieces {
            for s in piece.windows(2) {
                let on_edge = |y: i32| y <= f.top || y >= f.top + f.h - 1;
                assert!(!(on_edge(s[0].1) && s[0].1 == s[1].1 && s[0].0 != s[1].0), "segment along the frame: {s:?}");
            }
        }
    }
}
