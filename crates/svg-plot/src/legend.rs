//! The legend: its rows and swatches, its size, where it goes (the first corner of the plot area
//! free of data, else beside or below the plot) and drawing it.

use plotters::element::{Circle, DashedPathElement, PathElement, Rectangle, Text};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color, RGBColor, WHITE};

use crate::clip::Shape;
use crate::layout::Frame;
use crate::render::outline;
use crate::style::{K, LEGEND_BORDER, LEGEND_PAD, LEGEND_ROW, MARKER_R, SWATCH, TEXT, THIN, dash};
use crate::text::{LEGEND_FONT, clean, text_style, text_width};
use crate::{Area, Pt};

/// Legend swatch of a series.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Swatch {
    Line { color: RGBColor, width: u32, dashed: bool },
    Band { color: RGBColor, opacity: f64 },
    Dot { color: RGBColor },
    Bar { color: RGBColor },
}

/// Appends a legend row unless `label` is empty or the same row is already there.
pub(crate) fn push_entry(entries: &mut Vec<(String, Swatch)>, label: &str, swatch: Swatch) {
    let label = clean(label);
    if !label.trim().is_empty() && !entries.iter().any(|(l, s)| *l == label && *s == swatch) {
        entries.push((label, swatch));
    }
}

/// Width and height of the legend box, `None` without entries.
pub(crate) fn legend_size(entries: &[(String, Swatch)]) -> Option<(i32, i32)> {
    if entries.is_empty() {
        return None;
    }
    let text = entries.iter().map(|(l, _)| text_width(l, LEGEND_FONT)).max().unwrap_or(0);
    let rows = i32::try_from(entries.len()).unwrap_or(i32::MAX / LEGEND_ROW / 2).min(i32::MAX / LEGEND_ROW / 2);
    Some((2 * LEGEND_PAD + SWATCH + 6 * K + text, 2 * LEGEND_PAD + LEGEND_ROW * rows - 4 * K))
}

pub(crate) fn draw_legend(area: &Area<'_>, entries: &[(String, Swatch)], (x, y): (i32, i32), (w, h): (i32, i32)) {
    let corners = [(x, y), (x + w, y + h)];
    let _ = area.draw(&Rectangle::new(corners, WHITE.mix(0.9).filled()));
    let border = LEGEND_BORDER.stroke_width(THIN);
    let _ = area.draw(&outline(corners, border));
    let text = text_style(LEGEND_FONT, false, TEXT).pos(Pos::new(HPos::Left, VPos::Center));
    for (k, (label, swatch)) in entries.iter().enumerate() {
        let cy = y + LEGEND_PAD + LEGEND_ROW * k as i32 + (LEGEND_ROW - 4 * K) / 2;
        let sx = x + LEGEND_PAD;
        match *swatch {
            Swatch::Line { color, width, dashed: false } => {
                let _ = area.draw(&PathElement::new(vec![(sx, cy), (sx + SWATCH, cy)], color.stroke_width(width)));
            }
            Swatch::Line { color, width, dashed: true } => {
                let (d, style) = (dash(width), color.stroke_width(width));
                let _ = area.draw(&DashedPathElement::new(vec![(sx, cy), (sx + SWATCH, cy)], d.on, d.off, style));
            }
            Swatch::Band { color, opacity } => {
                let rect = [(sx, cy - 5 * K), (sx + SWATCH, cy + 5 * K)];
                let _ = area.draw(&Rectangle::new(rect, color.mix(opacity).filled()));
                let _ = area.draw(&outline(rect, color.stroke_width(THIN)));
            }
            Swatch::Dot { color } => {
                let _ = area.draw(&Circle::new((sx + SWATCH / 2, cy), MARKER_R, color.filled()));
            }
            Swatch::Bar { color } => {
                let _ = area.draw(&Rectangle::new(
                    [(sx + 5 * K, cy - 6 * K), (sx + SWATCH - 5 * K, cy + 6 * K)],
                    color.filled(),
                ));
            }
        }
        let _ = area.draw(&Text::new(label.clone(), (sx + SWATCH + 6 * K, cy), text.clone()));
    }
}

/// The first corner of the plot area (top-right, top-left, bottom-right, bottom-left) where a
/// `lw` × `lh` legend box touches no data.
pub(crate) fn free_corner(f: &Frame, shapes: &[Shape], lw: i32, lh: i32) -> Option<(i32, i32)> {
    let inset = 8 * K;
    if lw + 2 * inset > f.w || lh + 2 * inset > f.h {
        return None;
    }
    let mut cols = vec![(f64::INFINITY, f64::NEG_INFINITY); f.w.max(0) as usize];
    for shape in shapes {
        cover(f, shape, &mut cols);
    }
    let (right, left) = (f.left + f.w - inset - lw, f.left + inset);
    let (top, bottom) = (f.top + inset, f.top + f.h - inset - lh);
    [(right, top), (left, top), (right, bottom), (left, bottom)].into_iter().find(|&(x, y)| {
        let gap = 4 * K;
        let c0 = (x - gap - f.left).max(0) as usize;
        let c1 = ((x + lw + gap - f.left).max(0) as usize).min(cols.len());
        let (y0, y1) = (f64::from(y - gap), f64::from(y + lh + gap));
        cols[c0.min(c1)..c1].iter().all(|&(a, b)| b < y0 || a > y1)
    })
}

/// Marks the vertical extent `shape` covers in every column (of drawing units) of the plot area.
pub(crate) fn cover(f: &Frame, shape: &Shape, cols: &mut [(f64, f64)]) {
    let px = |&(x, y): &Pt| (f.px(f.x.frac(x)), f.py(f.y.frac(y)));
    match shape {
        Shape::Fill { pts, .. } => {
            // The closed outline; a column's extent of the outline contains the inside.
            let outline = pts.iter().chain(pts.first()).map(px).map(|(x, y)| (x, y, y));
            cover_path(f, cols, outline);
        }
        Shape::Stroke { pts, width, .. } => {
            let half = f64::from(*width) / 2.0;
            cover_path(f, cols, pts.iter().map(px).map(|(x, y)| (x, y - half, y + half)));
        }
        Shape::Dots { pts, r, .. } => {
            let r = f64::from(*r);
            for (x, y) in pts.iter().map(px) {
                for dx in [-r, 0.0, r] {
                    cover_path(f, cols, std::iter::once((x + dx, y - r, y + r)));
                }
            }
        }
        Shape::Bar { a, b, .. } => {
            let ((x0, y0), (x1, y1)) = (px(a), px(b));
            cover_path(f, cols, [(x0, y0.min(y1), y0.max(y1)), (x1, y0.min(y1), y0.max(y1))].into_iter());
        }
    }
}

/// Adds the extent of the polyline `pts` (`(x, top, bottom)` per vertex, in units) to `cols`.
pub(crate) fn cover_path(f: &Frame, cols: &mut [(f64, f64)], pts: impl Iterator<Item = (f64, f64, f64)>) {
    let ncols = cols.len() as f64;
    let mut mark = |c: f64, a: f64, b: f64| {
        if c >= 0.0 && c < ncols {
            let e = &mut cols[c as usize];
            *e = (e.0.min(a.min(b)), e.1.max(a.max(b)));
        }
    };
    let mut prev: Option<(f64, f64, f64)> = None;
    for (x, a, b) in pts {
        let x = x - f64::from(f.left);
        match prev {
            None => mark(x.floor(), a, b),
            Some((px, pa, pb)) => {
                let (lo, hi) = (px.min(x), px.max(x));
                let lerp = |u: f64, p: f64, q: f64| if hi > lo { p + (q - p) * (u - px) / (x - px) } else { q };
                let mut c = lo.floor().max(-1.0);
                while c <= hi.floor() && c < ncols {
                    let (u0, u1) = (c.max(lo), (c + 1.0).min(hi));
                    let ys = [lerp(u0, pa, a), lerp(u1, pa, a), lerp(u0, pb, b), lerp(u1, pb, b)];
                    let top = ys.iter().copied().fold(f64::INFINITY, f64::min);
                    let bottom = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    mark(c, top, bottom);
                    c += 1.0;
                }
            }
        }
        prev = Some((x, a, b));
    }
}

#[cfg(test)]
mod tests {
    use crate::layout::Frame;
    use crate::style::K;
    use crate::test_util::*;
    use crate::{Chart, PALETTE, Series};

    #[test]
    fn legend_goes_to_a_free_corner_or_beside_the_plot() {
        // A rising diagonal leaves the top-left corner free.
        let mut c = Chart::new("", "", "");
        c.add(Series::line("rising", vec![0.0, 10.0], vec![0.0, 10.0], PALETTE[1]));
        let f = Frame::layout(&c.spec(), (800 * K, 380 * K), (0, 0));
        let (x, y, _) = texts(&c.to_svg()).into_iter().find(|t| t.2 == "rising").expect("legend text");
        assert!(x < f.left + f.w / 4 && y < f.top + f.h / 4, "legend at ({x}, {y})");
        // Data in every corner: the legend goes right of the plot.
        let svg = sample_chart().to_svg();
        // The frame: the closed outline in the axis colour.
        let frame = paths(&svg, "polyline", "#333333").into_iter().find(|p| p.len() == 5).expect("frame");
        let right = f64::from(frame.iter().map(|p| p.0).max().expect("corners"));
        let (x, _, _) = texts(&svg).into_iter().find(|t| t.2 == "SMF A").expect("legend text");
        assert!(f64::from(x) > right, "legend text at {x}, plot ends at {right}");
    }
}
