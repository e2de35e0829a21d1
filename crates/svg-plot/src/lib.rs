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
#[cfg(test)]
mod test_util;
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
