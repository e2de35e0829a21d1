//! SVG figures drawn with [`plotters`] through its SVG backend, returned as strings (this crate
//! writes no files).
//!
//! Three kinds of panel:
//! - a [`Chart`] of [`Series`] drawn as lines (solid or dashed), shaded bands (e.g. the interval of a
//!   set-membership filter) or markers, against time or any other abscissa; [`Chart::xy`] makes one
//!   for XY tracks ([`Series::track`], e.g. a vehicle's path y against x) with equal axis scaling;
//! - a [`BarChart`] of grouped bars, one label per group and one legend entry per [`Bars`] series;
//! - a [`Grid`] of panels of both kinds in one SVG document ([`grid`] for charts only).
//!
//! Each renders with `to_svg()` to a standalone SVG document:
//!
//! ```
//! use svg_plot::{Chart, PALETTE, Series};
//!
//! let t: Vec<f64> = (0..500).map(|k| f64::from(k) * 0.01).collect();
//! let truth: Vec<f64> = t.iter().map(|t| t.sin()).collect();
//! let lower = truth.iter().map(|v| v - 0.1).collect();
//! let upper = truth.iter().map(|v| v + 0.1).collect();
//!
//! let mut chart = Chart::new("Yaw rate", "time [s]", "γ [rad/s]");
//! chart.add(Series::band("bound", t.clone(), lower, upper, PALETTE[1]));
//! chart.add(Series::line("truth", t, truth, PALETTE[0]));
//! let svg = chart.to_svg();
//!
//! assert!(svg.starts_with("<?xml") && svg.contains("<svg width=\"800\" height=\"380\""));
//! assert!(svg.contains("γ [rad/s]") && svg.trim_end().ends_with("</svg>"));
//! ```
//!
//! Long series are decimated per pixel column before they reach plotters, keeping the first, last,
//! lowest and highest sample of every column (for a band, of each edge; for a track also the
//! leftmost and rightmost), so a bound that contains the truth still visibly contains it and a
//! 10 000-sample chart stays small (about 90 kB). Non-finite samples break a line into pieces and
//! never reach the axis ranges. Everything is clipped to the plot area here, since plotters only
//! clamps out-of-range points to its edges. Nothing here panics on input: empty, all-NaN or
//! mismatched data draws what is drawable.
//!
//! plotters' SVG backend writes whole-number coordinates; we draw in quarter pixels (four drawing
//! units per pixel) and give the root `<svg>` the figure's size in pixels with a `viewBox` in
//! drawing units, so that slopes do not turn into stairs when a figure is zoomed.
//!
//! # Text and the embedded font
//! The SVG backend writes text as `<text font-family="sans-serif">` and lets the viewer render the
//! glyphs, but plotters measures text to lay out labels, and so does this crate (axis label
//! areas, legend boxes). Without a font plotters only guesses from the byte count (a `β` counts
//! twice); its `ttf` feature reads system fonts through `font-kit`, which needs fontconfig and
//! freetype. We use its pure-Rust `ab_glyph` feature instead, with DejaVu Sans Regular registered
//! through `plotters::style::register_font` from the bytes that the `dejavu` crate embeds with
//! `include_bytes!` (the TTF files of DejaVu 2.37, unmodified). DejaVu Sans is the default
//! `sans-serif` of most Linux desktops, so the measured widths match what most viewers draw, and
//! it covers the Greek letters and mathematical signs of the labels. The font's licence is the
//! Bitstream Vera / Arev font licence (free to use, embed and redistribute; DejaVu's changes are
//! in the public domain); its text ships with that crate in `assets/dejavu-fonts-ttf-2.37/LICENSE`.
//! No font is embedded in the SVG files, and no system library is needed.
//!
//! # Modules
//! The public types live in `series`, `chart`, `bars` and `grid`. Behind them: `axis` (ranges,
//! ticks, tick labels), `layout` (margins and plot area), `decimate`, `clip` (shapes clipped to
//! the plot area), `legend`, `render` (the plotters drawing), `text` (font and text widths) and
//! `style` (colours and lengths).

#![warn(missing_docs)]

mod axis;
mod bars;
mod chart;
mod clip;
mod decimate;
mod grid;
mod layout;
mod legend;
mod render;
mod series;
mod style;
mod text;

pub use bars::{BarChart, Bars};
pub use chart::Chart;
pub use grid::{Grid, Panel, grid};
pub use series::{Series, Style};
pub use style::PALETTE;

use plotters::backend::SVGBackend;
use plotters::coord::Shift;
use plotters::drawing::DrawingArea;

/// A closed interval `(min, max)`.
type Range = (f64, f64);

/// Vertices `(x, y)` of a polyline.
type Polyline = Vec<(f64, f64)>;

/// A point `(x, y)`.
type Pt = (f64, f64);

/// A drawing area of the SVG backend, in drawing units (four per pixel).
type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// Helpers of the unit tests: a well-formedness check of the SVG documents, element and attribute
/// extraction, and a sample chart.
#[cfg(test)]
mod test_util {
    use std::collections::BTreeSet;

    use crate::layout::Frame;
    use crate::style::K;
    use crate::{Chart, PALETTE, Pt, Series};

    /// Checks that tags are balanced and properly nested, and that `&` only starts an entity.
    pub(crate) fn assert_well_formed(svg: &str) {
        let body = svg.strip_prefix("<?xml version=\"1.0\" encoding=\"UTF-8\"?>").expect("XML declaration");
        let mut stack: Vec<String> = Vec::new();
        let mut rest = body;
        while let Some(start) = rest.find('<') {
            let text = &rest[..start];
            assert!(!text.contains('>'), "stray '>' in text {text:?}");
            check_entities(text);
            let end = rest[start..].find('>').expect("unterminated tag") + start;
            let tag = &rest[start + 1..end];
            assert!(!tag.contains('<'), "'<' inside tag {tag:?}");
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(stack.pop().as_deref(), Some(name.trim()), "mismatched closing tag");
            } else if !tag.ends_with('/') {
                let name = tag.split_whitespace().next().expect("tag name");
                stack.push(name.to_owned());
            }
            // Attribute values are quoted and contain no raw '&' outside entities.
            assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes in {tag:?}");
            check_entities(tag);
            rest = &rest[end + 1..];
        }
        assert!(rest.trim().is_empty());
        assert!(stack.is_empty(), "unclosed tags {stack:?}");
        assert!(stack.is_empty() && svg.starts_with("<?xml"), "document");
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "non-finite number in the output:\n{svg}");
        assert!(!svg.chars().any(|c| c.is_control() && c != '\n'), "control character in the output");
    }

    pub(crate) fn check_entities(s: &str) {
        for (i, _) in s.match_indices('&') {
            let ent = &s[i..s[i..].find(';').map_or(s.len(), |e| i + e + 1)];
            assert!(["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"].contains(&ent), "bad entity {ent:?}");
        }
    }

    /// The elements `<name …/>` (or `<name …>`) of `svg`, as their attribute text.
    pub(crate) fn elements<'a>(svg: &'a str, name: &str) -> Vec<&'a str> {
        let open = format!("<{name} ");
        svg.match_indices(&open)
            .map(|(i, _)| {
                let rest = &svg[i + open.len()..];
                &rest[..rest.find('>').unwrap_or(rest.len())]
            })
            .collect()
    }

    pub(crate) fn attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
        let key = format!(" {name}=\"");
        let at = format!(" {element}").find(&key)? + key.len() - 1;
        let rest = &element[at..];
        Some(&rest[..rest.find('"')?])
    }

    pub(crate) fn num(element: &str, name: &str) -> f64 {
        attr(element, name).and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("{name} in {element}"))
    }

    /// Vertices of the polylines (or polygons) of colour `color`, as separate pieces.
    pub(crate) fn paths(svg: &str, name: &str, color: &str) -> Vec<Vec<(i32, i32)>> {
        let paint = if name == "polygon" { "fill" } else { "stroke" };
        elements(svg, name)
            .into_iter()
            .filter(|e| attr(e, paint) == Some(color))
            .map(|e| {
                attr(e, "points")
                    .expect("points")
                    .split_whitespace()
                    .map(|p| {
                        let (x, y) = p.split_once(',').expect("x,y");
                        (x.parse().expect("x"), y.parse().expect("y"))
                    })
                    .collect()
            })
            .collect()
    }

    /// The `<text>` elements as (x, y, content).
    pub(crate) fn texts(svg: &str) -> Vec<(i32, i32, String)> {
        svg.match_indices("<text ")
            .map(|(i, _)| {
                let rest = &svg[i..];
                let open_end = rest.find('>').expect("tag end");
                let tag = &rest[6..open_end];
                let content = &rest[open_end + 1..rest.find("</text>").expect("closing tag")];
                (num(tag, "x") as i32, num(tag, "y") as i32, content.trim().to_owned())
            })
            .collect()
    }

    pub(crate) fn sample_chart() -> Chart {
        let t: Vec<f64> = (0..10_000).map(|i| i as f64 * 0.002).collect();
        let truth: Vec<f64> = t.iter().map(|t| t.sin()).collect();
        let mut c = Chart::new("β <&> test", "time [s]", "β [rad]");
        c.add(Series::band(
            "SMF A",
            t.clone(),
            truth.iter().map(|v| v - 0.2).collect(),
            truth.iter().map(|v| v + 0.2).collect(),
            PALETTE[1],
        ));
        c.add(Series::dashed("SMF B", t.clone(), truth.iter().map(|v| v + 0.3).collect(), PALETTE[2]));
        c.add(Series::dashed("SMF B", t.clone(), truth.iter().map(|v| v - 0.3).collect(), PALETTE[2]));
        c.add(Series::line("truth", t.clone(), truth, PALETTE[0]));
        c.add(Series::markers("points", vec![1.0, 2.0], vec![0.5, -0.5], PALETTE[3]));
        c
    }

    /// Deterministic pseudo-random numbers in `[0, 1)`.
    pub(crate) fn rng(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Asserts that the drawn vertices `drawn` lie in the plot area and include, for every pixel
    /// column (the decimation's bucket), the highest and the lowest of the points `(xs, ys)` (to a
    /// drawing unit, for the rounding of the way there and back through the range fractions).
    pub(crate) fn assert_extremes_drawn(f: &Frame, xs: &[f64], ys: &[f64], drawn: &[(i32, i32)], what: &str) {
        for &(x, y) in drawn {
            assert!((f.left..f.left + f.w).contains(&x) && (f.top..f.top + f.h).contains(&y), "({x}, {y}) outside");
        }
        let set: BTreeSet<(i32, i32)> = drawn.iter().copied().collect();
        let near = |(x, y): (i32, i32)| (-1..=1).any(|dx| (-1..=1).any(|dy| set.contains(&(x + dx, y + dy))));
        let cols = f64::from(f.w - 1) / f64::from(K);
        // Per bucket, the lowest and the highest point.
        let mut buckets: std::collections::BTreeMap<i64, (Pt, Pt)> = Default::default();
        for (&x, &y) in xs.iter().zip(ys) {
            let b = ((x - f.x.lo) / (f.x.hi - f.x.lo) * cols).round() as i64;
            let e = buckets.entry(b).or_insert(((x, y), (x, y)));
            if y < e.0.1 {
                e.0 = (x, y);
            }
            if y > e.1.1 {
                e.1 = (x, y);
            }
        }
        assert!(buckets.len() > 200, "{what}: the data spans {} columns", buckets.len());
        for (b, (low, high)) in buckets {
            assert!(near(f.pixel(low)) && near(f.pixel(high)), "{what}, column {b}: {low:?} or {high:?} not drawn");
        }
    }
}
