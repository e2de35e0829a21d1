//! SVG figures for the reproduction report, drawn with [`plotters`] through its SVG backend.
//!
//! Three kinds of panel:
//! - a [`Chart`] of [`Series`] drawn as lines (solid or dashed), shaded bands (e.g. the interval of a
//!   set-membership filter) or markers, against time or any other abscissa; [`Chart::xy`] makes one
//!   for XY tracks ([`Series::track`], e.g. a vehicle's path y against x) with equal axis scaling;
//! - a [`BarChart`] of grouped bars, one label per group and one legend entry per [`Bars`] series;
//! - a [`Grid`] of panels of both kinds in one SVG document ([`grid`] for charts only).
//!
//! Long series are decimated per pixel column before they reach plotters, keeping the first, last,
//! lowest and highest sample of every column (for a band, of each edge; for a track also the
//! leftmost and rightmost), so a bound that contains the truth still visibly contains it and a
//! 10 000-sample chart stays small (about 90 kB). Non-finite samples break a line into pieces and
//! never reach the axis ranges. Everything is clipped to the plot area here, since plotters only
//! clamps out-of-range points to its edges. Nothing here panics on input: empty, all-NaN or
//! mismatched data draws what is drawable, and writing a file returns an [`std::io::Result`].
//!
//! plotters' SVG backend writes whole-number coordinates; we draw in quarter pixels (`K` drawing
//! units per pixel) and give the root `<svg>` the figure's size in pixels with a `viewBox` in
//! drawing units, so that slopes do not turn into stairs when a figure is zoomed.
//!
//! # Text and the embedded font
//! The SVG backend writes text as `<text font-family="sans-serif">` and lets the viewer render the
//! glyphs, but plotters measures text to lay out labels, and so does this module (axis label
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

use std::collections::BTreeSet;
use std::ffi::OsString;
use std::io::Write as _;
use std::ops::Range as StdRange;
use std::path::Path;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use plotters::backend::SVGBackend;
use plotters::chart::ChartBuilder;
use plotters::coord::Shift;
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::drawing::{DrawingArea, IntoDrawingArea};
use plotters::element::{Circle, DashedPathElement, PathElement, Polygon, Rectangle, Text};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color, FontDesc, FontFamily, FontStyle, RGBColor, ShapeStyle, TextStyle, WHITE, register_font};

/// Colour-blind-safe palette (Okabe–Ito), ordered for contrast on white; the pale yellow is last.
pub const PALETTE: [&str; 8] = ["#000000", "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442"];

/// How a [`Series`] is drawn.
#[derive(Clone, Debug, PartialEq)]
pub enum Style {
    /// A polyline through the samples, in their order.
    Line {
        /// Stroke colour: `#rrggbb` or `#rgb` (e.g. an entry of [`PALETTE`]); anything else is black.
        color: &'static str,
        /// Stroke width in pixels, rounded to a quarter pixel (from a quarter to 16 pixels).
        width: f64,
        /// Dashed instead of solid.
        dashed: bool,
    },
    /// A shaded area between `lower` and the series' `y` (the upper edge).
    Band {
        /// Lower edge, one value per sample.
        lower: Vec<f64>,
        /// Fill colour (as for [`Style::Line`]); the edges are stroked in the same colour.
        color: &'static str,
        /// Fill opacity in `[0, 1]`.
        opacity: f64,
    },
    /// A small dot per sample.
    Markers {
        /// Fill colour (as for [`Style::Line`]).
        color: &'static str,
    },
}

/// One data series of a [`Chart`].
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text; empty to leave the series out of the legend.
    pub label: String,
    /// Abscissae (e.g. time in seconds, or a position for a track).
    pub x: Vec<f64>,
    /// Ordinates (the upper edge for [`Style::Band`]).
    pub y: Vec<f64>,
    /// How the series is drawn.
    pub style: Style,
}

impl Series {
    /// A solid line of width 1.5.
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: &'static str) -> Self {
        Self { label: label.into(), x, y, style: Style::Line { color, width: 1.5, dashed: false } }
    }

    /// A dashed line of width 1.2 (e.g. one of a pair of bounds).
    pub fn dashed(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: &'static str) -> Self {
        Self { label: label.into(), x, y, style: Style::Line { color, width: 1.2, dashed: true } }
    }

    /// A band between `lower` and `upper` with fill opacity 0.25.
    pub fn band(label: impl Into<String>, x: Vec<f64>, lower: Vec<f64>, upper: Vec<f64>, color: &'static str) -> Self {
        Self { label: label.into(), x, y: upper, style: Style::Band { lower, color, opacity: 0.25 } }
    }

    /// Dots, one per sample.
    pub fn markers(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: &'static str) -> Self {
        Self { label: label.into(), x, y, style: Style::Markers { color } }
    }

    /// An XY track: a solid line through the points `(x[k], y[k])` in sample order, where `x` need
    /// not increase (e.g. a vehicle's path, north against east). Usually drawn on [`Chart::xy`].
    pub fn track(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: &'static str) -> Self {
        Self::line(label, x, y, color)
    }

    /// The finite samples as `(x, low, high)` (`low == high` except for bands); `None` marks a gap.
    fn samples(&self) -> Vec<Sample> {
        let lower = match &self.style {
            Style::Band { lower, .. } => Some(lower),
            _ => None,
        };
        let n = self.x.len().min(self.y.len()).min(lower.map_or(usize::MAX, Vec::len));
        (0..n)
            .map(|i| {
                let (x, y) = (self.x[i], self.y[i]);
                let l = lower.map_or(y, |l| l[i]);
                (x.is_finite() && y.is_finite() && l.is_finite()).then(|| (x, l.min(y), l.max(y)))
            })
            .collect()
    }
}

/// A sample `(x, low, high)` of a series, or `None` for a gap (a non-finite value).
type Sample = Option<(f64, f64, f64)>;

/// A closed interval `(min, max)`.
type Range = (f64, f64);

/// Vertices `(x, y)` of a polyline.
type Polyline = Vec<(f64, f64)>;

/// A point `(x, y)`.
type Pt = (f64, f64);

/// A drawing area of the SVG backend, in drawing units ([`K`] per pixel).
type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// A chart of line, band and marker series, rendered to a standalone SVG document.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart {
    /// Title above the plot; may be empty.
    pub title: String,
    /// Label of the horizontal axis, with its unit (e.g. `"time [s]"`).
    pub x_label: String,
    /// Label of the vertical axis, with its unit (e.g. `"yaw rate γ [rad/s]"`).
    pub y_label: String,
    /// Series, drawn bands first, then lines, then markers (each group in this order).
    pub series: Vec<Series>,
    /// Width of the whole figure in pixels.
    pub width: u32,
    /// Height of the whole figure in pixels.
    pub height: u32,
    /// Fixed horizontal range; `None` for the finite data's extent.
    pub x_range: Option<(f64, f64)>,
    /// Fixed vertical range; `None` for the finite data's extent plus a 5 % margin.
    pub y_range: Option<(f64, f64)>,
    /// One unit of x as long as one unit of y on screen (for tracks): the ranges are widened
    /// around their centres as needed, and automatic ranges get a 5 % margin on both axes.
    pub equal_axes: bool,
}

// Font sizes in pixels, each one for which plotters' size (the SVG `font-size`, in drawing units,
// times 1.24) divides back exactly: the SVG says `font-size="50"` for 12.5 px, where 13 px would
// come out as `52.00000000000001`.
const TICK_FONT: f64 = 12.0;
const LABEL_FONT: f64 = 12.5;
const TITLE_FONT: f64 = 15.5;
const LEGEND_FONT: f64 = 12.0;
/// Drawing units per pixel. plotters' SVG backend writes integer coordinates, so we draw at four
/// times the size and let the root element's `viewBox` scale it down: coordinates are precise to a
/// quarter of a pixel (whole pixels would turn slopes into visible stairs when a figure is zoomed)
/// and stroke widths come in quarter pixels. All lengths below are in these units.
const K: i32 = 4;
const LEGEND_ROW: i32 = 18 * K;
const LEGEND_PAD: i32 = 7 * K;
const SWATCH: i32 = 26 * K;
const TICK_LEN: i32 = 5 * K;
const MARKER_R: u32 = 3 * K as u32;
/// Width of the band edges, the legend border and the band swatch's border (0.75 px).
const THIN: u32 = 3;
/// Width of the frame, the axes and the grid lines (1 px).
const HAIRLINE: u32 = K as u32;
/// At most this many dashes (each one SVG element) per colour and dash pattern, e.g. for a pair of
/// dashed bounds: longer paths get proportionally longer dashes and gaps.
const MAX_DASHES: f64 = 400.0;
/// Largest side of a figure in pixels (plotters works in `i32` drawing units).
const MAX_SIDE: u32 = 1 << 20;

const TEXT: RGBColor = RGBColor(0x11, 0x11, 0x11);
const TICK_TEXT: RGBColor = RGBColor(0x22, 0x22, 0x22);
const AXIS: RGBColor = RGBColor(0x33, 0x33, 0x33);
const GRID: RGBColor = RGBColor(0xe4, 0xe4, 0xe4);
const ZERO: RGBColor = RGBColor(0xa8, 0xa8, 0xa8);
const LEGEND_BORDER: RGBColor = RGBColor(0x99, 0x99, 0x99);

impl Chart {
    /// An empty 800 × 380 chart with automatic ranges.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>, y_label: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            width: 800,
            height: 380,
            x_range: None,
            y_range: None,
            equal_axes: false,
        }
    }

    /// An empty 600 × 600 chart for XY tracks, with equal axis scaling ([`Chart::equal_axes`]).
    pub fn xy(title: impl Into<String>, x_label: impl Into<String>, y_label: impl Into<String>) -> Self {
        Self { width: 600, height: 600, equal_axes: true, ..Self::new(title, x_label, y_label) }
    }

    /// Appends a series.
    pub fn add(&mut self, s: Series) -> &mut Self {
        self.series.push(s);
        self
    }

    /// The chart as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        render_svg(self.size(), |area| self.draw_on(area))
    }

    /// Writes [`Chart::to_svg`] to `path`, creating missing parent directories; the document is
    /// written to a temporary file in the same directory first and then renamed, so that no
    /// half-written figure is ever left at `path`.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        write_atomic(path, &self.to_svg())
    }

    /// Extents `(min, max)` of the finite x values and of the finite y values (within `x_range`).
    fn data_extent(&self) -> (Option<Range>, Option<Range>) {
        let grow = |e: &mut Option<Range>, lo: f64, hi: f64| {
            *e = Some(e.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
        };
        let window = self.x_range.and_then(|(a, b)| fixed_range(a, b));
        let (mut ex, mut ey) = (None, None);
        for s in &self.series {
            for (x, lo, hi) in s.samples().into_iter().flatten() {
                grow(&mut ex, x, x);
                if window.is_none_or(|(a, b)| a <= x && x <= b) {
                    grow(&mut ey, lo, hi);
                }
            }
        }
        (ex, ey)
    }

    /// The axis ranges before any equal-scaling adjustment.
    fn ranges(&self) -> (Range, Range) {
        let (x_auto, y_auto) = self.data_extent();
        let has_markers = self.series.iter().any(|s| matches!(s.style, Style::Markers { .. }));
        let x_margin = if self.equal_axes {
            0.05
        } else if has_markers {
            0.03
        } else {
            0.0
        };
        let x = self.x_range.and_then(|(a, b)| fixed_range(a, b)).unwrap_or_else(|| auto_range(x_auto, x_margin));
        let y = self.y_range.and_then(|(a, b)| fixed_range(a, b)).unwrap_or_else(|| auto_range(y_auto, 0.05));
        (x, y)
    }

    /// Legend rows `(label, swatch)`, skipping empty labels and repeats of an identical row.
    fn legend_entries(&self) -> Vec<(String, Swatch)> {
        let mut entries: Vec<(String, Swatch)> = Vec::new();
        for s in &self.series {
            let swatch = match &s.style {
                Style::Line { color, width, dashed } => {
                    Swatch::Line { color: rgb(color), width: stroke_width(*width), dashed: *dashed }
                }
                Style::Band { color, opacity, .. } => {
                    Swatch::Band { color: rgb(color), opacity: clamp_opacity(*opacity) }
                }
                Style::Markers { color } => Swatch::Dot { color: rgb(color) },
            };
            push_entry(&mut entries, &s.label, swatch);
        }
        entries
    }

    /// Every series decimated to the pixel columns of `f`, in data coordinates and drawing order.
    fn shapes(&self, f: &Frame) -> Vec<Shape> {
        // One bucket per pixel column.
        let cols = f64::from((f.w - 1).max(1)) / f64::from(K);
        let (x0, x1) = (f.x.lo, f.x.hi);
        let bucket = |x: f64| ((x - x0) / (x1 - x0) * cols).round().clamp(-1e15, 1e15) as i64;
        let mut bands = Vec::new();
        let mut lines = Vec::new();
        let mut dots = Vec::new();
        for s in &self.series {
            let samples = s.samples();
            match &s.style {
                Style::Band { color, opacity, .. } => {
                    let color = rgb(color);
                    for (lower, upper) in decimate_band(&samples, bucket) {
                        if let ([(x, lo)], [(_, hi)]) = (&lower[..], &upper[..]) {
                            // A lone sample still shows as a short vertical bar.
                            bands.push(Shape::Stroke {
                                pts: vec![(*x, *lo), (*x, *hi)],
                                color,
                                width: THIN,
                                dashed: None,
                            });
                            continue;
                        }
                        let mut outline = upper.clone();
                        outline.extend(lower.iter().rev());
                        bands.push(Shape::Fill { pts: outline, color, opacity: clamp_opacity(*opacity) });
                        bands.push(Shape::Stroke { pts: lower, color, width: THIN, dashed: None });
                        bands.push(Shape::Stroke { pts: upper, color, width: THIN, dashed: None });
                    }
                }
                Style::Line { color, width, dashed } => {
                    let (color, width) = (rgb(color), stroke_width(*width));
                    let dashed = dashed.then(|| dash(width));
                    for seg in decimate_line(&samples, bucket) {
                        if let [p] = seg[..] {
                            // A lone sample (no neighbour to connect to) shows as a dot.
                            lines.push(Shape::Dots { pts: vec![p], color, r: width + K as u32 });
                        } else {
                            lines.push(Shape::Stroke { pts: seg, color, width, dashed });
                        }
                    }
                }
                Style::Markers { color } => {
                    let pts = samples.iter().flatten().map(|&(x, y, _)| (x, y)).collect();
                    dots.push(Shape::Dots { pts, color: rgb(color), r: MARKER_R });
                }
            }
        }
        bands.extend(lines);
        bands.extend(dots);
        bands
    }

    fn spec(&self) -> Spec<'_> {
        let (x, y) = self.ranges();
        Spec {
            title: &self.title,
            x_label: &self.x_label,
            y_label: &self.y_label,
            x,
            y,
            categories: None,
            equal_axes: self.equal_axes,
            legend: self.legend_entries(),
        }
    }
}

impl Figure for Chart {
    fn size(&self) -> (u32, u32) {
        (self.width.clamp(1, MAX_SIDE), self.height.clamp(1, MAX_SIDE))
    }

    fn draw_on(&self, area: &Area<'_>) {
        render(area, &self.spec(), &|f| self.shapes(f));
    }
}

/// One series of a [`BarChart`]: one bar per group.
#[derive(Clone, Debug, PartialEq)]
pub struct Bars {
    /// Legend text; empty to leave the series out of the legend.
    pub label: String,
    /// One value per group of the chart (missing or non-finite values draw no bar; values beyond
    /// the last group are ignored).
    pub values: Vec<f64>,
    /// Fill colour: `#rrggbb` or `#rgb` (e.g. an entry of [`PALETTE`]); anything else is black.
    pub color: &'static str,
}

impl Bars {
    /// A bar series.
    pub fn new(label: impl Into<String>, values: Vec<f64>, color: &'static str) -> Self {
        Self { label: label.into(), values, color }
    }
}

/// A chart of grouped bars (e.g. one group per scenario, one bar per estimator), rendered to a
/// standalone SVG document. Bars start at zero (or at the edge of the range nearest to zero).
#[derive(Clone, Debug, PartialEq)]
pub struct BarChart {
    /// Title above the plot; may be empty.
    pub title: String,
    /// Label under the group labels; may be empty.
    pub x_label: String,
    /// Label of the vertical axis, with its unit.
    pub y_label: String,
    /// Group labels, left to right.
    pub groups: Vec<String>,
    /// Series; within a group, their bars stand side by side in this order.
    pub series: Vec<Bars>,
    /// Width of the whole figure in pixels.
    pub width: u32,
    /// Height of the whole figure in pixels.
    pub height: u32,
    /// Fixed vertical range; `None` for zero and the finite values plus a 5 % margin.
    pub y_range: Option<(f64, f64)>,
}

impl BarChart {
    /// An empty 800 × 380 bar chart with one group per entry of `groups`.
    pub fn new<S: Into<String>>(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        groups: impl IntoIterator<Item = S>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            groups: groups.into_iter().map(Into::into).collect(),
            series: Vec::new(),
            width: 800,
            height: 380,
            y_range: None,
        }
    }

    /// Appends a series.
    pub fn add(&mut self, bars: Bars) -> &mut Self {
        self.series.push(bars);
        self
    }

    /// The chart as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        render_svg(self.size(), |area| self.draw_on(area))
    }

    /// Writes [`BarChart::to_svg`] to `path` like [`Chart::write`].
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        write_atomic(path, &self.to_svg())
    }

    /// The values that are drawn: finite, of an existing group.
    fn values(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        let n = self.groups.len();
        self.series.iter().enumerate().flat_map(move |(k, s)| {
            s.values.iter().take(n).enumerate().filter(|(_, v)| v.is_finite()).map(move |(g, &v)| (g, k, v))
        })
    }

    fn y(&self) -> Range {
        if let Some(r) = self.y_range.and_then(|(a, b)| fixed_range(a, b)) {
            return r;
        }
        let (lo, hi) = self.values().fold((0.0f64, 0.0f64), |(a, b), (_, _, v)| (a.min(v), b.max(v)));
        let (lo, hi) = widen(lo, hi);
        let pad = 0.05 * (hi - lo);
        let (a, b) = (if lo < 0.0 { lo - pad } else { lo }, if hi > 0.0 { hi + pad } else { hi });
        if a.is_finite() && b.is_finite() { (a, b) } else { (lo, hi) }
    }

    fn shapes(&self) -> Vec<Shape> {
        let m = self.series.len().max(1) as f64;
        let width = 0.8 / m;
        self.values()
            .map(|(g, k, v)| {
                let x0 = g as f64 - 0.4 + k as f64 * width;
                Shape::Bar { a: (x0, 0.0), b: (x0 + width, v), color: rgb(self.series[k].color) }
            })
            .collect()
    }

    fn spec(&self) -> Spec<'_> {
        let n = self.groups.len().max(1) as f64;
        let mut legend = Vec::new();
        for s in &self.series {
            push_entry(&mut legend, &s.label, Swatch::Bar { color: rgb(s.color) });
        }
        Spec {
            title: &self.title,
            x_label: &self.x_label,
            y_label: &self.y_label,
            x: (-0.5, n - 0.5),
            y: self.y(),
            categories: Some(&self.groups),
            equal_axes: false,
            legend,
        }
    }
}

impl Figure for BarChart {
    fn size(&self) -> (u32, u32) {
        (self.width.clamp(1, MAX_SIDE), self.height.clamp(1, MAX_SIDE))
    }

    fn draw_on(&self, area: &Area<'_>) {
        render(area, &self.spec(), &|_| self.shapes());
    }
}

/// One panel of a [`Grid`].
#[derive(Clone, Debug, PartialEq)]
pub enum Panel {
    /// A line, band and marker chart (also XY tracks).
    Chart(Chart),
    /// A grouped bar chart.
    Bars(BarChart),
}

impl From<Chart> for Panel {
    fn from(c: Chart) -> Self {
        Panel::Chart(c)
    }
}

impl From<BarChart> for Panel {
    fn from(c: BarChart) -> Self {
        Panel::Bars(c)
    }
}

impl Figure for Panel {
    fn size(&self) -> (u32, u32) {
        match self {
            Panel::Chart(c) => c.size(),
            Panel::Bars(c) => c.size(),
        }
    }

    fn draw_on(&self, area: &Area<'_>) {
        match self {
            Panel::Chart(c) => c.draw_on(area),
            Panel::Bars(c) => c.draw_on(area),
        }
    }
}

/// A multi-panel figure: panels laid out row by row, `columns` per row, in one SVG document. Each
/// cell keeps its panel's size; a column is as wide as the widest panel and a row as tall as its
/// tallest panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Title above all panels; may be empty.
    pub title: String,
    /// Panels per row (0 counts as 1).
    pub columns: usize,
    /// The panels, row by row.
    pub panels: Vec<Panel>,
}

impl Grid {
    /// An empty grid of `columns` panels per row, without title.
    pub fn new(columns: usize) -> Self {
        Self { title: String::new(), columns, panels: Vec::new() }
    }

    /// Appends a panel (a [`Chart`] or a [`BarChart`]).
    pub fn add(&mut self, panel: impl Into<Panel>) -> &mut Self {
        self.panels.push(panel.into());
        self
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let panels: Vec<&dyn Figure> = self.panels.iter().map(|p| p as &dyn Figure).collect();
        render_grid(&self.title, &panels, self.columns)
    }

    /// Writes [`Grid::to_svg`] to `path` like [`Chart::write`].
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        write_atomic(path, &self.to_svg())
    }
}

/// Lays `charts` out row by row, `columns` per row, in one SVG document (each cell keeps its
/// chart's size; a row is as tall as its tallest chart). See [`Grid`] for titles, bar charts and
/// writing to a file.
pub fn grid(charts: &[Chart], columns: usize) -> String {
    let panels: Vec<&dyn Figure> = charts.iter().map(|c| c as &dyn Figure).collect();
    render_grid("", &panels, columns)
}

/// A panel that can be drawn into a drawing area of its size.
trait Figure {
    /// Width and height in pixels, each in `1..=MAX_SIDE`.
    fn size(&self) -> (u32, u32);
    /// Draws the panel into `area`, ignoring drawing errors (draws what is drawable).
    fn draw_on(&self, area: &Area<'_>);
}

fn render_grid(title: &str, panels: &[&dyn Figure], columns: usize) -> String {
    let columns = columns.max(1);
    let cell_w = panels.iter().map(|p| p.size().0).max().unwrap_or(1);
    let row_h: Vec<u32> = panels.chunks(columns).map(|r| r.iter().map(|p| p.size().1).max().unwrap_or(1)).collect();
    let title = clean(title);
    let title_h = if title.is_empty() { 0 } else { pixels(TITLE_FONT) as u32 + 22 };
    let total_w = u64::from(cell_w) * columns.min(panels.len().max(1)) as u64;
    let total_h = u64::from(title_h) + row_h.iter().map(|&h| u64::from(h)).sum::<u64>();
    let size = (total_w.clamp(1, u64::from(MAX_SIDE)) as u32, total_h.clamp(1, u64::from(MAX_SIDE)) as u32);
    render_svg(size, |root| {
        let _ = root.fill(&WHITE);
        if !title.is_empty() {
            let style = text_style(TITLE_FONT, true, TEXT).pos(Pos::new(HPos::Center, VPos::Top));
            let _ = root.draw(&Text::new(title.clone(), (size.0 as i32 * K / 2, 12 * K), style));
        }
        let mut y = u64::from(title_h);
        for (r, row) in panels.chunks(columns).enumerate() {
            for (c, panel) in row.iter().enumerate() {
                let (w, h) = panel.size();
                let x = c as u64 * u64::from(cell_w);
                if x >= u64::from(MAX_SIDE) || y >= u64::from(MAX_SIDE) {
                    continue;
                }
                let cell = root.clone().shrink((x as i32 * K, y as i32 * K), (w as i32 * K, h as i32 * K));
                panel.draw_on(&cell);
            }
            y += u64::from(row_h[r]);
        }
    })
}

/// Runs `draw` on an SVG drawing area of `size` pixels (in drawing units: `K` times that) and
/// returns the document.
fn render_svg(size: (u32, u32), draw: impl FnOnce(&Area<'_>)) -> String {
    let (w, h) = (size.0.clamp(1, MAX_SIDE), size.1.clamp(1, MAX_SIDE));
    let units = (w * K as u32, h * K as u32);
    font_ready();
    let mut svg = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    {
        let root = SVGBackend::with_string(&mut svg, units).into_drawing_area();
        draw(&root);
        let _ = root.present();
    }
    // The figure's size in pixels; the `viewBox` (in drawing units) stays.
    let (from, to) =
        (format!("<svg width=\"{}\" height=\"{}\" ", units.0, units.1), format!("<svg width=\"{w}\" height=\"{h}\" "));
    svg.replacen(&from, &to, 1)
}

/// Writes `contents` to a temporary file next to `path`, then renames it to `path`.
fn write_atomic(path: &Path, contents: &str) -> std::io::Result<()> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        std::io::Error::new(std::io::ErrorKind::InvalidInput, format!("no file name in {}", path.display()))
    })?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let mut tmp_name = OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}-{}.tmp", std::process::id(), COUNTER.fetch_add(1, Ordering::Relaxed)));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(contents.as_bytes())?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Registers the embedded font under the family `sans-serif` (once); `false` if that failed, in
/// which case text widths fall back to an estimate (the SVG backend needs no font to write text).
fn font_ready() -> bool {
    static READY: OnceLock<bool> = OnceLock::new();
    *READY.get_or_init(|| register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular()).is_ok())
}

/// plotters' font size for an SVG `font-size` of `px` (its SVG backend writes the size divided by
/// 1.24), nudged so that the division gives `px` exactly.
fn plotters_size(px: f64) -> f64 {
    let s = px * 1.24;
    (-4i64..=4).map(|k| f64::from_bits(s.to_bits().wrapping_add_signed(k))).find(|c| c / 1.24 == px).unwrap_or(s)
}

/// A sans-serif text style of `px` pixels.
fn text_style(px: f64, bold: bool, color: RGBColor) -> TextStyle<'static> {
    let style = if bold { FontStyle::Bold } else { FontStyle::Normal };
    let mut text = TextStyle::from(FontDesc::new(FontFamily::SansSerif, plotters_size(px * f64::from(K)), style));
    text.color = color.to_backend_color();
    text
}

/// Rendered width of `s` at `px` pixels, in drawing units: measured with the embedded font, or
/// estimated (erring wide).
fn text_width(s: &str, px: f64) -> i32 {
    let size = px * f64::from(K);
    if font_ready() {
        if let Ok((w, _)) = FontDesc::new(FontFamily::SansSerif, plotters_size(size), FontStyle::Normal).box_size(s) {
            return i32::try_from(w).unwrap_or(i32::MAX / 4).min(i32::MAX / 4);
        }
    }
    let em: f64 = s
        .chars()
        .map(|c| match c {
            'i' | 'j' | 'l' | '.' | ',' | ':' | ';' | '\'' | '|' | '!' | ' ' => 0.32,
            'f' | 't' | 'r' | '(' | ')' | '[' | ']' | '/' | '-' => 0.42,
            'm' | 'w' | 'M' | 'W' => 0.95,
            'A'..='Z' => 0.72,
            _ => 0.64,
        })
        .sum();
    (em * size).ceil().min(1e9) as i32
}

/// A font size rounded up to whole pixels.
fn pixels(font: f64) -> i32 {
    font.ceil() as i32
}

/// The height of a font of `px` pixels, in drawing units.
fn font_units(px: f64) -> i32 {
    pixels(px) * K
}

/// `s` without control characters (which XML forbids).
fn clean(s: &str) -> String {
    s.chars().filter(|c| !c.is_control()).collect()
}

/// A `#rrggbb` or `#rgb` colour; black for anything else.
fn rgb(s: &str) -> RGBColor {
    let hex = s.trim().strip_prefix('#').unwrap_or("");
    let digits: Vec<u8> = hex.chars().filter_map(|c| c.to_digit(16).map(|d| d as u8)).collect();
    match (hex.len(), &digits[..]) {
        (6, &[a, b, c, d, e, f]) => RGBColor(a * 16 + b, c * 16 + d, e * 16 + f),
        (3, &[a, b, c]) => RGBColor(a * 17, b * 17, c * 17),
        _ => RGBColor(0, 0, 0),
    }
}

/// A stroke width of `w` pixels in drawing units (whole quarter pixels), from a quarter to 16 pixels.
fn stroke_width(w: f64) -> u32 {
    ((w * f64::from(K)).round() as u32).clamp(1, 16 * K as u32)
}

/// The dash pattern of a dashed line `width` units wide.
fn dash(width: u32) -> Dash {
    let w = f64::from(width.max(K as u32));
    Dash { on: 4.0 * w, off: 3.0 * w }
}

/// An opacity in `[0, 1]` (NaN counts as the default 0.25).
fn clamp_opacity(o: f64) -> f64 {
    if o.is_nan() { 0.25 } else { o.clamp(0.0, 1.0) }
}

/// Legend swatch of a series.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Swatch {
    Line { color: RGBColor, width: u32, dashed: bool },
    Band { color: RGBColor, opacity: f64 },
    Dot { color: RGBColor },
    Bar { color: RGBColor },
}

/// Appends a legend row unless `label` is empty or the same row is already there.
fn push_entry(entries: &mut Vec<(String, Swatch)>, label: &str, swatch: Swatch) {
    let label = clean(label);
    if !label.trim().is_empty() && !entries.iter().any(|(l, s)| *l == label && *s == swatch) {
        entries.push((label, swatch));
    }
}

/// Dash pattern in drawing units.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Dash {
    on: f64,
    off: f64,
}

/// Something to draw. Produced in data coordinates, then clipped to the plot ranges and rid of
/// points that fall on the position (in drawing units) of their predecessor by [`clip_shapes`].
#[derive(Clone, Debug, PartialEq)]
enum Shape {
    /// A filled polygon (a band).
    Fill { pts: Vec<Pt>, color: RGBColor, opacity: f64 },
    /// A polyline.
    Stroke { pts: Vec<Pt>, color: RGBColor, width: u32, dashed: Option<Dash> },
    /// Dots of radius `r` drawing units.
    Dots { pts: Vec<Pt>, color: RGBColor, r: u32 },
    /// A filled bar between the corners `a` and `b`.
    Bar { a: Pt, b: Pt, color: RGBColor },
}

/// What the shared renderer needs to know about a panel.
struct Spec<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    /// Ranges before equal scaling.
    x: Range,
    y: Range,
    /// Tick labels at x = 0, 1, … instead of numbers (bar charts).
    categories: Option<&'a [String]>,
    equal_axes: bool,
    legend: Vec<(String, Swatch)>,
}

/// One axis: its range, tick values and tick labels. Implements plotters' [`Ranged`] so that the
/// mesh shows exactly these ticks.
#[derive(Clone, Debug, PartialEq)]
struct Axis {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
    labels: Vec<String>,
}

impl Axis {
    fn numeric((lo, hi): Range, target: usize) -> Self {
        let ticks = ticks(lo, hi, target);
        let labels = tick_labels(&ticks);
        Self { lo, hi, ticks, labels }
    }

    fn categories(groups: &[String]) -> Self {
        let n = groups.len();
        Self {
            lo: -0.5,
            hi: n.max(1) as f64 - 0.5,
            ticks: (0..n).map(|g| g as f64).collect(),
            labels: groups.iter().map(|g| clean(g)).collect(),
        }
    }

    /// `v` as a fraction of the range (0 at `lo`, 1 at `hi`), bounded to ±10⁶.
    fn frac(&self, v: f64) -> f64 {
        let f = (v - self.lo) / (self.hi - self.lo);
        if f.is_nan() { 0.0 } else { f.clamp(-1e6, 1e6) }
    }

    /// The value at fraction `f` of the range.
    fn value(&self, f: f64) -> f64 {
        self.lo + f * (self.hi - self.lo)
    }

    /// The position of fraction `f` between the positions `limit.0` (at `lo`) and `limit.1` (at `hi`).
    fn pixel_of_frac(f: f64, limit: (i32, i32)) -> i32 {
        let p = f64::from(limit.0) + f * f64::from(limit.1 - limit.0);
        if p.is_finite() { p.round().clamp(-1e9, 1e9) as i32 } else { limit.0 }
    }
}

impl Ranged for Axis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        Self::pixel_of_frac(self.frac(*value), limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        // Our ticks for the (bold) grid lines and labels; no light grid lines.
        if hint.weight().allow_light_points() { Vec::new() } else { self.ticks.clone() }
    }

    fn range(&self) -> StdRange<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for Axis {
    fn format(value: &f64) -> String {
        format!("{value}")
    }

    fn format_ext(&self, value: &f64) -> String {
        self.ticks.iter().position(|t| t == value).map_or_else(|| Self::format(value), |i| self.labels[i].clone())
    }
}

/// Panel layout in drawing units: margins, label areas and the plot area, with the axes.
#[derive(Clone, Debug, PartialEq)]
struct Frame {
    margin_top: i32,
    margin_bottom: i32,
    margin_left: i32,
    margin_right: i32,
    /// Height of the x label area (tick marks, tick labels, axis label) below the plot.
    x_area: i32,
    /// Width of the y label area left of the plot.
    y_area: i32,
    /// Plot area: columns `left..left + w`, rows `top..top + h`.
    left: i32,
    top: i32,
    w: i32,
    h: i32,
    x: Axis,
    y: Axis,
}

impl Frame {
    /// The layout of `spec` in a `size` panel keeping `reserve` = (right, below) units free.
    fn layout(spec: &Spec, size: (i32, i32), reserve: (i32, i32)) -> Self {
        let mut frame = Self::with_ranges(spec, spec.x, spec.y, size, reserve);
        if spec.equal_axes {
            // The plot size depends (a little) on the tick labels, which depend on the ranges.
            for _ in 0..4 {
                let (x, y) = equalize(spec.x, spec.y, frame.w, frame.h);
                let next = Self::with_ranges(spec, x, y, size, reserve);
                let done = (next.w, next.h) == (frame.w, frame.h);
                frame = next;
                if done {
                    break;
                }
            }
        }
        frame
    }

    fn with_ranges(spec: &Spec, x: Range, y: Range, (fw, fh): (i32, i32), (res_r, res_b): (i32, i32)) -> Self {
        let mut vertical = [
            if spec.title.trim().is_empty() { 12 * K } else { 24 * K + font_units(TITLE_FONT) },
            2 * TICK_LEN
                + font_units(TICK_FONT)
                + 4 * K
                + if spec.x_label.trim().is_empty() { 0 } else { 8 * K + font_units(LABEL_FONT) },
            8 * K + res_b,
        ];
        fit(&mut vertical, fh);
        let [margin_top, x_area, margin_bottom] = vertical;
        let h = fh - vertical.iter().sum::<i32>();
        let y = Axis::numeric(y, ((f64::from(h) / f64::from(45 * K)).round() as usize).clamp(2, 8));
        let y_text = y.labels.iter().map(|t| text_width(t, TICK_FONT)).max().unwrap_or(0);
        let mut horizontal = [
            8 * K,
            y_text
                + 2 * TICK_LEN
                + 2 * K
                + if spec.y_label.trim().is_empty() { 0 } else { font_units(LABEL_FONT) + 8 * K },
            14 * K + res_r,
        ];
        fit(&mut horizontal, fw);
        let [margin_left, y_area, mut margin_right] = horizontal;
        let mut w = fw - horizontal.iter().sum::<i32>();
        let x = match spec.categories {
            Some(groups) => {
                // Label every group if the labels fit side by side, else every second, third, ….
                let mut axis = Axis::categories(groups);
                let widest = axis.labels.iter().map(|t| text_width(t, TICK_FONT)).max().unwrap_or(0);
                let per_group = (w / i32::try_from(groups.len()).unwrap_or(i32::MAX).max(1)).max(1);
                let every = ((widest + 8 * K + per_group - 1) / per_group).max(1) as usize;
                for (g, label) in axis.labels.iter_mut().enumerate() {
                    if g % every != 0 {
                        label.clear();
                    }
                }
                axis
            }
            None => {
                let mut target = ((f64::from(w) / f64::from(90 * K)).round() as usize).clamp(2, 10);
                loop {
                    let axis = Axis::numeric(x, target);
                    let widest = axis.labels.iter().map(|t| text_width(t, TICK_FONT)).max().unwrap_or(0);
                    if target <= 2 || (widest + 16 * K).saturating_mul(axis.ticks.len() as i32) <= w {
                        break axis;
                    }
                    target -= 1;
                }
            }
        };
        // Narrow the plot if the last x tick label would stick out of the figure (or into the legend).
        if let (Some(&last), Some(text)) = (x.ticks.last(), x.labels.last()) {
            let left = margin_left + y_area;
            let end = Axis::pixel_of_frac(x.frac(last), (left, left + w - 1)) + text_width(text, TICK_FONT) / 2 + 3 * K;
            let overflow = end - (fw - res_r);
            if overflow > 0 && w - overflow >= 10 * K {
                w -= overflow;
                margin_right += overflow;
            }
        }
        // Centre the frame and plotters' axis lines (one unit outside the plot area) on pixels so
        // that they are drawn crisp: the plot area starts at K/2 + 1 and spans K - 1 modulo K.
        let (mut margin_top, mut margin_left, mut margin_bottom, mut h) = (margin_top, margin_left, margin_bottom, h);
        if w > 4 * K && h > 4 * K {
            let shift = (K / 2 + 1 - (margin_left + y_area)).rem_euclid(K);
            margin_left += shift;
            w -= shift;
            let trim = (w - (K - 1)).rem_euclid(K);
            w -= trim;
            margin_right += trim;
            let shift = (K / 2 + 1 - margin_top).rem_euclid(K);
            margin_top += shift;
            h -= shift;
            let trim = (h - (K - 1)).rem_euclid(K);
            h -= trim;
            margin_bottom += trim;
        }
        Self {
            margin_top,
            margin_bottom,
            margin_left,
            margin_right,
            x_area,
            y_area,
            left: margin_left + y_area,
            top: margin_top,
            w,
            h,
            x,
            y,
        }
    }

    /// Panel position (in drawing units) of the fraction `u` of the x range, not rounded.
    fn px(&self, u: f64) -> f64 {
        f64::from(self.left) + u * f64::from(self.w - 1)
    }

    /// Panel position (in drawing units) of the fraction `v` of the y range, not rounded.
    fn py(&self, v: f64) -> f64 {
        f64::from(self.top + self.h - 1) - v * f64::from(self.h - 1)
    }

    /// The position (in drawing units) plotters draws the data point `p` at.
    fn pixel(&self, (x, y): Pt) -> (i32, i32) {
        (
            Axis::pixel_of_frac(self.x.frac(x), (self.left, self.left + self.w - 1)),
            Axis::pixel_of_frac(self.y.frac(y), (self.top + self.h - 1, self.top)),
        )
    }
}

/// Scales `parts` down (keeping their proportions) so that they leave at least one unit of `total`.
fn fit(parts: &mut [i32], total: i32) {
    let sum: i32 = parts.iter().sum();
    let room = (total - 1).max(0);
    if sum > room {
        for p in parts.iter_mut() {
            *p = (i64::from(*p) * i64::from(room) / i64::from(sum.max(1))) as i32;
        }
    }
}

/// Ranges widened around their centres so that one unit of data spans as long on both axes.
fn equalize(x: Range, y: Range, w: i32, h: i32) -> (Range, Range) {
    let (pw, ph) = (f64::from((w - 1).max(1)), f64::from((h - 1).max(1)));
    let s = ((x.1 - x.0) / pw).max((y.1 - y.0) / ph);
    let around = |(a, b): Range, pixels: f64| {
        let (mid, half) = (a / 2.0 + b / 2.0, s * pixels / 2.0);
        let r = (mid - half, mid + half);
        if r.0.is_finite() && r.1.is_finite() && r.1 > r.0 { r } else { (a, b) }
    };
    (around(x, pw), around(y, ph))
}

/// Draws `spec` into `area`: axes, the shapes that `shapes` makes for the final layout, legend and title.
fn render(area: &Area<'_>, spec: &Spec, shapes: &dyn Fn(&Frame) -> Vec<Shape>) {
    let (w, h) = area.dim_in_pixel();
    let size = (w as i32, h as i32);
    let _ = area.fill(&WHITE);
    let legend = legend_size(&spec.legend);
    let mut frame = Frame::layout(spec, size, (0, 0));
    let mut drawn = clip_shapes(shapes(&frame), &frame);
    let mut legend_at = None;
    if let Some((lw, lh)) = legend {
        legend_at = free_corner(&frame, &drawn, lw, lh);
        if legend_at.is_none() {
            // Every corner of the plot area holds data: put the legend right of the plot, or
            // below it when that would leave the plot less than 55 % of the figure's width.
            let right = Frame::layout(spec, size, (lw + 14 * K, 0));
            if f64::from(right.w) >= 0.55 * f64::from(size.0) {
                legend_at = Some((right.left + right.w + 12 * K, right.top));
                frame = right;
            } else {
                frame = Frame::layout(spec, size, (0, lh + 6 * K));
                legend_at = Some((frame.left, size.1 - lh - 6 * K));
            }
            drawn = clip_shapes(shapes(&frame), &frame);
        }
    }
    draw_plot(area, spec, &frame, &drawn);
    if !spec.title.trim().is_empty() {
        let style = text_style(TITLE_FONT, true, TEXT).pos(Pos::new(HPos::Center, VPos::Top));
        let _ = area.draw(&Text::new(clean(spec.title), (frame.left + frame.w / 2, 14 * K), style));
    }
    if let (Some(at), Some(size)) = (legend_at, legend) {
        draw_legend(area, &spec.legend, at, size);
    }
}

/// Axes, grid, the shapes and the frame, through a plotters chart context.
fn draw_plot(area: &Area<'_>, spec: &Spec, f: &Frame, shapes: &[Shape]) {
    let Ok(mut chart) = ChartBuilder::on(area)
        .margin_top(f.margin_top)
        .margin_bottom(f.margin_bottom)
        .margin_left(f.margin_left)
        .margin_right(f.margin_right)
        .x_label_area_size(f.x_area)
        .y_label_area_size(f.y_area)
        .build_cartesian_2d(f.x.clone(), f.y.clone())
    else {
        return;
    };
    let (x_label, y_label) = (clean(spec.x_label), clean(spec.y_label));
    let mut mesh = chart.configure_mesh();
    mesh.bold_line_style(GRID.stroke_width(HAIRLINE))
        .axis_style(AXIS.stroke_width(HAIRLINE))
        .max_light_lines(0)
        .set_all_tick_mark_size(TICK_LEN)
        .label_style(text_style(TICK_FONT, false, TICK_TEXT))
        .axis_desc_style(text_style(LABEL_FONT, false, TEXT));
    if !x_label.trim().is_empty() {
        mesh.x_desc(x_label);
    }
    if !y_label.trim().is_empty() {
        mesh.y_desc(y_label);
    }
    if spec.categories.is_some() {
        mesh.disable_x_mesh();
    }
    let _ = mesh.draw();
    let plot = chart.plotting_area();
    let (x, y) = (&f.x, &f.y);
    if y.lo < 0.0 && 0.0 < y.hi {
        let _ = plot.draw(&PathElement::new(vec![(x.lo, 0.0), (x.hi, 0.0)], ZERO.stroke_width(HAIRLINE)));
    }
    for shape in shapes {
        match shape {
            Shape::Fill { pts, color, opacity } => {
                let _ = plot.draw(&Polygon::new(pts.clone(), color.mix(*opacity).filled()));
            }
            Shape::Stroke { pts, color, width, dashed: None } => {
                let _ = plot.draw(&PathElement::new(pts.clone(), color.stroke_width(*width)));
            }
            Shape::Stroke { pts, color, width, dashed: Some(d) } => {
                let style = color.stroke_width(*width);
                let _ = plot.draw(&DashedPathElement::new(pts.iter().copied(), d.on, d.off, style));
            }
            Shape::Dots { pts, color, r } => {
                for &p in pts {
                    let _ = plot.draw(&Circle::new(p, *r, color.filled()));
                }
            }
            Shape::Bar { a, b, color } => {
                let mut bar = Rectangle::new([*a, *b], color.filled());
                // A pixel of white between neighbouring bars once they are wide enough.
                if (f.pixel(*a).0 - f.pixel(*b).0).abs() > 4 * K {
                    bar.set_margin(0, 0, 0, K as u32);
                }
                let _ = plot.draw(&bar);
            }
        }
    }
    // The frame, on plotters' axis lines (left, bottom) and one unit outside the plot area.
    let frame = [(f.left - 1, f.top - 1), (f.left + f.w, f.top + f.h)];
    let _ = area.draw(&outline(frame, AXIS.stroke_width(HAIRLINE)));
}

/// The outline of the rectangle between the corners `[a, b]` (the SVG backend writes no stroke
/// width for an unfilled `Rectangle`, so that it would always be one unit, a quarter pixel, thin).
fn outline([a, b]: [(i32, i32); 2], style: ShapeStyle) -> PathElement<(i32, i32)> {
    PathElement::new(vec![a, (b.0, a.1), b, (a.0, b.1), a], style)
}

/// Width and height of the legend box, `None` without entries.
fn legend_size(entries: &[(String, Swatch)]) -> Option<(i32, i32)> {
    if entries.is_empty() {
        return None;
    }
    let text = entries.iter().map(|(l, _)| text_width(l, LEGEND_FONT)).max().unwrap_or(0);
    let rows = i32::try_from(entries.len()).unwrap_or(i32::MAX / LEGEND_ROW / 2).min(i32::MAX / LEGEND_ROW / 2);
    Some((2 * LEGEND_PAD + SWATCH + 6 * K + text, 2 * LEGEND_PAD + LEGEND_ROW * rows - 4 * K))
}

fn draw_legend(area: &Area<'_>, entries: &[(String, Swatch)], (x, y): (i32, i32), (w, h): (i32, i32)) {
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

/// Clips every shape to the axis ranges of `f` and drops points that land on the same position (in
/// drawing units) as their predecessor (dots: in the same half-pixel cell as any other dot of the shape).
fn clip_shapes(shapes: Vec<Shape>, f: &Frame) -> Vec<Shape> {
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

fn pixel_distance(f: &Frame, a: Pt, b: Pt) -> f64 {
    let (pa, pb) = (f.pixel(a), f.pixel(b));
    f64::from(pa.0 - pb.0).hypot(f64::from(pa.1 - pb.1))
}

/// Whether the point (in fractions of the ranges) is inside the plot.
fn inside((u, v): Pt) -> bool {
    (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)
}

/// The part of the segment `p`–`q` inside the unit square (Liang–Barsky), keeping the ends that are inside.
fn clip_segment(p: Pt, q: Pt) -> Option<(Pt, Pt)> {
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
fn clip_polyline(pts: &[Pt]) -> Vec<Polyline> {
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
fn clip_polygon(mut poly: Vec<Pt>) -> Vec<Pt> {
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

/// The first corner of the plot area (top-right, top-left, bottom-right, bottom-left) where a
/// `lw` × `lh` legend box touches no data.
fn free_corner(f: &Frame, shapes: &[Shape], lw: i32, lh: i32) -> Option<(i32, i32)> {
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
fn cover(f: &Frame, shape: &Shape, cols: &mut [(f64, f64)]) {
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
fn cover_path(f: &Frame, cols: &mut [(f64, f64)], pts: impl Iterator<Item = (f64, f64, f64)>) {
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

/// Line decimation: splits at gaps, and keeps, of every run of consecutive samples falling into
/// the same `bucket`, the first, the last, the lowest and the highest, and for tracks (where x
/// may go back and forth within a bucket) the leftmost and the rightmost, in their original order.
/// When x increases, the leftmost and rightmost are the first and last: at most four per run.
fn decimate_line(samples: &[Sample], bucket: impl Fn(f64) -> i64) -> Vec<Polyline> {
    let mut segs = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut i = 0;
    while i < samples.len() {
        let Some((x, _, _)) = samples[i] else {
            if !cur.is_empty() {
                segs.push(std::mem::take(&mut cur));
            }
            i += 1;
            continue;
        };
        let b = bucket(x);
        let (mut imin, mut imax, mut ileft, mut iright, mut j) = (i, i, i, i, i + 1);
        let at = |k: usize| samples[k].unwrap_or_default();
        while let Some(Some((xj, yj, _))) = samples.get(j) {
            if bucket(*xj) != b {
                break;
            }
            if *yj < at(imin).1 {
                imin = j;
            }
            if *yj > at(imax).1 {
                imax = j;
            }
            if *xj < at(ileft).0 {
                ileft = j;
            }
            if *xj > at(iright).0 {
                iright = j;
            }
            j += 1;
        }
        let mut keep = [i, imin, imax, ileft, iright, j - 1];
        keep.sort_unstable();
        for (k, &idx) in keep.iter().enumerate() {
            if k == 0 || idx != keep[k - 1] {
                let (x, y, _) = samples[idx].unwrap_or_default();
                cur.push((x, y));
            }
        }
        i = j;
    }
    if !cur.is_empty() {
        segs.push(cur);
    }
    segs
}

/// Band decimation: splits at gaps (where either edge is missing) and decimates the lower and
/// the upper edge separately as lines, so every bucket keeps its lowest low and highest high.
/// Returns the pieces as (lower edge, upper edge).
fn decimate_band(samples: &[Sample], bucket: impl Fn(f64) -> i64) -> Vec<(Polyline, Polyline)> {
    let edge = |pick: fn(&(f64, f64, f64)) -> f64| -> Vec<Sample> {
        samples.iter().map(|s| s.map(|s| (s.0, pick(&s), pick(&s)))).collect()
    };
    let lower = decimate_line(&edge(|s| s.1), &bucket);
    let upper = decimate_line(&edge(|s| s.2), &bucket);
    lower.into_iter().zip(upper).collect()
}

/// A user-given range, `None` unless both ends are finite; degenerate ranges are widened.
fn fixed_range(a: f64, b: f64) -> Option<(f64, f64)> {
    (a.is_finite() && b.is_finite()).then(|| widen(a.min(b), a.max(b)))
}

/// The data extent plus `margin` (a fraction of the span) on both sides; `(0, 1)` without data.
fn auto_range(extent: Option<(f64, f64)>, margin: f64) -> (f64, f64) {
    let Some((lo, hi)) = extent else { return (0.0, 1.0) };
    let (lo, hi) = widen(lo, hi);
    let pad = (hi - lo) * margin;
    let (a, b) = (lo - pad, hi + pad);
    if a.is_finite() && b.is_finite() { (a, b) } else { (lo, hi) }
}

/// Widens an empty or numerically negligible range `[lo, hi]` around its centre; keeps the span finite.
fn widen(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = (lo.clamp(-1e300, 1e300), hi.clamp(-1e300, 1e300));
    let mid = lo / 2.0 + hi / 2.0;
    let scale = lo.abs().max(hi.abs());
    if hi - lo > scale * 1e-9 && hi - lo > f64::MIN_POSITIVE * 1e6 {
        (lo, hi)
    } else if scale > 1e-300 {
        (mid - scale * 0.1, mid + scale * 0.1)
    } else {
        (mid - 1.0, mid + 1.0)
    }
}

/// "Nice" tick values (steps of 1, 2 or 5 times a power of ten) inside `[lo, hi]`: the step whose
/// tick count is closest to `target` (erring high) without exceeding 1.6 `target`; empty for a non-finite or
/// empty range.
fn ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return Vec::new();
    }
    let eps = 1e-9;
    let target = target.max(2) as f64;
    let count = |step: f64| (hi / step + eps).floor() - (lo / step - eps).ceil() + 1.0;
    let e = (span / target).log10().floor();
    let mut best: Option<(f64, f64)> = None;
    for de in [-1.0, 0.0, 1.0, 2.0] {
        for m in [1.0, 2.0, 5.0] {
            let step = m * 10f64.powf(e + de);
            let c = count(step);
            if !(step.is_finite() && step > 0.0 && c >= 2.0) {
                continue;
            }
            // Too few ticks is worse than too many, up to the crowding limit.
            let score =
                if c < target { 1.5 * (target - c) } else { c - target } + if c > 1.6 * target { 1e3 + c } else { 0.0 };
            // Ascending steps and `<=`: a tie goes to the coarser step.
            if best.is_none_or(|(s, _)| score <= s) {
                best = Some((score, step));
            }
        }
    }
    let Some((_, step)) = best else { return Vec::new() };
    let (first, last) = ((lo / step - eps).ceil(), (hi / step + eps).floor());
    if !(first.is_finite() && last.is_finite()) || last - first > 100.0 {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut k = first;
    while k <= last {
        // Multiply integers by the step (no accumulated error) and clean the last digits.
        out.push(if k == 0.0 { 0.0 } else { round_to(k * step, step) });
        k += 1.0;
    }
    out
}

/// `v` rounded to a tenth of `step`'s decade (removes 0.30000000000000004-style noise).
fn round_to(v: f64, step: f64) -> f64 {
    let decimals = (-(step.log10() + 1e-9).floor() + 1.0).clamp(0.0, 300.0) as i32;
    if decimals <= 15 {
        let p = 10f64.powi(decimals);
        let r = (v * p).round() / p;
        if r.is_finite() { r } else { v }
    } else {
        v
    }
}

/// Labels for tick values produced by [`ticks`]: fixed-point with as many decimals as the step
/// needs, or `1.5e-4`-style when the step is below 1e-3, all values are below 1e-2 or they reach 1e6.
fn tick_labels(ticks: &[f64]) -> Vec<String> {
    let step = if ticks.len() >= 2 { (ticks[1] - ticks[0]).abs() } else { ticks.first().map_or(1.0, |t| t.abs()) };
    let step = if step > 0.0 && step.is_finite() { step } else { 1.0 };
    let step_exp = (step.log10() + 1e-9).floor();
    let max_abs = ticks.iter().fold(0.0, |m: f64, t| m.max(t.abs()));
    let sci = step_exp < -3.0 || (max_abs > 0.0 && max_abs < 1e-2) || max_abs >= 1e6;
    ticks
        .iter()
        .map(|&t| {
            let text = if sci && t.abs() < step * 1e-6 {
                "0".to_owned()
            } else if sci {
                let digits = ((t.abs().log10() + 1e-9).floor() - step_exp).max(0.0) as usize;
                let text = format!("{t:.digits$e}");
                // Trim trailing zeros of the mantissa: 1.50e-3 -> 1.5e-3, 1.0e-3 -> 1e-3.
                match text.split_once('e') {
                    Some((m, e)) if m.contains('.') => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
                    _ => text,
                }
            } else {
                let t = if t.abs() < step * 1e-6 { 0.0 } else { t };
                format!("{t:.0$}", (-step_exp).max(0.0) as usize)
            };
            // Typographic minus sign for negative values.
            match text.strip_prefix('-') {
                Some(rest) => format!("\u{2212}{rest}"),
                None => text,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks that tags are balanced and properly nested, and that `&` only starts an entity.
    fn assert_well_formed(svg: &str) {
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

    fn check_entities(s: &str) {
        for (i, _) in s.match_indices('&') {
            let ent = &s[i..s[i..].find(';').map_or(s.len(), |e| i + e + 1)];
            assert!(["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"].contains(&ent), "bad entity {ent:?}");
        }
    }

    /// The elements `<name …/>` (or `<name …>`) of `svg`, as their attribute text.
    fn elements<'a>(svg: &'a str, name: &str) -> Vec<&'a str> {
        let open = format!("<{name} ");
        svg.match_indices(&open)
            .map(|(i, _)| {
                let rest = &svg[i + open.len()..];
                &rest[..rest.find('>').unwrap_or(rest.len())]
            })
            .collect()
    }

    fn attr<'a>(element: &'a str, name: &str) -> Option<&'a str> {
        let key = format!(" {name}=\"");
        let at = format!(" {element}").find(&key)? + key.len() - 1;
        let rest = &element[at..];
        Some(&rest[..rest.find('"')?])
    }

    fn num(element: &str, name: &str) -> f64 {
        attr(element, name).and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("{name} in {element}"))
    }

    /// Vertices of the polylines (or polygons) of colour `color`, as separate pieces.
    fn paths(svg: &str, name: &str, color: &str) -> Vec<Vec<(i32, i32)>> {
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
    fn texts(svg: &str) -> Vec<(i32, i32, String)> {
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

    fn sample_chart() -> Chart {
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
    fn rng(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn svg_is_well_formed_and_small() {
        let svg = sample_chart().to_svg();
        assert_well_formed(&svg);
        assert!(svg.contains("<svg width=\"800\" height=\"380\" viewBox=\"0 0 3200 1520\""));
        assert!(svg.contains("font-family=\"sans-serif\""));
        assert!(svg.contains("β &lt;&amp;&gt; test"));
        let labels: Vec<String> = texts(&svg).into_iter().map(|t| t.2).collect();
        // The duplicated dashed bound appears once in the legend.
        assert_eq!(labels.iter().filter(|l| *l == "SMF B").count(), 1, "{labels:?}");
        for l in ["SMF A", "truth", "points", "time [s]", "β [rad]", "\u{2212}1.0", "20"] {
            assert!(labels.iter().any(|t| t == l), "{l} in {labels:?}");
        }
        assert!(svg.len() < 200_000, "decimation keeps the file small: {} bytes", svg.len());
        // Every series is there: band fill, its edges, the dashes, the truth and the dots.
        assert!(!paths(&svg, "polygon", "#0072B2").is_empty());
        assert!(paths(&svg, "polyline", "#0072B2").len() >= 2);
        assert!(paths(&svg, "polyline", "#D55E00").len() > 50, "dashes");
        assert!(!paths(&svg, "polyline", "#000000").is_empty());
        assert_eq!(elements(&svg, "circle").iter().filter(|c| attr(c, "fill") == Some("#009E73")).count(), 3);
        assert_well_formed(&grid(&[sample_chart(), Chart::new("", "", ""), sample_chart()], 2));
    }

    #[test]
    fn font_sizes_are_exact() {
        for px in [TICK_FONT, LABEL_FONT, TITLE_FONT, LEGEND_FONT] {
            let units = px * f64::from(K);
            assert_eq!(plotters_size(units) / 1.24, units);
        }
        let svg = sample_chart().to_svg();
        for e in elements(&svg, "text") {
            let size = attr(e, "font-size").expect("font-size");
            assert!(size.len() <= 4, "font-size {size}");
        }
    }

    #[test]
    fn text_is_measured_with_the_embedded_font() {
        assert!(font_ready());
        let font = FontDesc::new(FontFamily::SansSerif, plotters_size(12.0), FontStyle::Normal);
        let (w, _) = font.box_size("β").expect("the font measures text");
        let (wa, _) = font.box_size("a").expect("the font measures text");
        // plotters' fallback counts bytes: a two-byte β would be twice as wide as an a.
        assert!(w > 0 && w < wa * 3 / 2, "β {w} px, a {wa} px");
        assert!(text_width("WWW", 12.0) > 2 * text_width("iii", 12.0));
    }

    #[test]
    fn ticks_are_nice_and_cover_the_range() {
        for &(lo, hi) in &[
            (0.0, 1.0),
            (-0.37, 0.81),
            (0.0, 20.0),
            (-1.2e-3, 9e-4),
            (1e6, 1.0001e6),
            (-5.0, -4.999),
            (0.1, 0.7),
            (3.0, 1e9),
        ] {
            for target in [2, 3, 5, 8] {
                let t = ticks(lo, hi, target);
                assert!(t.len() >= 2 && t.len() as f64 <= 1.6 * target as f64, "{lo}..{hi}: {t:?}");
                let step = t[1] - t[0];
                let mag = 10f64.powf(step.log10().floor());
                let m = step / mag;
                assert!([1.0, 2.0, 5.0].iter().any(|n| (m - n).abs() < 1e-6), "step {step} of {t:?}");
                assert!(t[0] >= lo - step * 1e-6 && t[0] - lo < step, "{lo}..{hi}: {t:?}");
                assert!(*t.last().unwrap() <= hi + step * 1e-6 && hi - t.last().unwrap() < step, "{t:?}");
                for (k, v) in t.iter().enumerate() {
                    assert!((v - (t[0] + k as f64 * step)).abs() <= step * 1e-6);
                }
            }
        }
        assert!(ticks(1.0, 1.0, 5).is_empty());
        assert!(ticks(f64::NAN, 1.0, 5).is_empty());
        assert!(ticks(0.0, f64::INFINITY, 5).is_empty());
    }

    #[test]
    fn tick_labels_are_compact() {
        assert_eq!(tick_labels(&ticks(0.0, 0.3, 6)), ["0.00", "0.05", "0.10", "0.15", "0.20", "0.25", "0.30"]);
        assert_eq!(tick_labels(&ticks(0.0, 1.0, 5)), ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        assert_eq!(tick_labels(&ticks(0.0, 100.0, 5)), ["0", "20", "40", "60", "80", "100"]);
        assert_eq!(tick_labels(&ticks(-2e-3, 2e-3, 5)), ["\u{2212}2e-3", "\u{2212}1e-3", "0", "1e-3", "2e-3"]);
        assert_eq!(tick_labels(&ticks(0.0, 1.5e-3, 3)), ["0", "5e-4", "1e-3", "1.5e-3"]);
        assert_eq!(tick_labels(&ticks(0.0, 3e-3, 3)), ["0", "1e-3", "2e-3", "3e-3"]);
        assert_eq!(tick_labels(&ticks(0.0, 2e6, 3)), ["0", "1e6", "2e6"]);
        assert_eq!(tick_labels(&ticks(0.0, 0.02, 4)), ["0.000", "0.005", "0.010", "0.015", "0.020"]);
        for l in tick_labels(&ticks(-0.9, 0.9, 9)) {
            assert!(l.len() <= 6, "{l}");
        }
    }

    #[test]
    fn colors_parse() {
        assert_eq!(rgb("#D55E00"), RGBColor(0xd5, 0x5e, 0x00));
        assert_eq!(rgb("#0af"), RGBColor(0x00, 0xaa, 0xff));
        for bad in ["", "red", "#12345", "#gg0000", "#ééé"] {
            assert_eq!(rgb(bad), RGBColor(0, 0, 0), "{bad}");
        }
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let nan = f64::NAN;
        let inf = f64::INFINITY;
        let cases: Vec<Series> = vec![
            Series::line("empty", vec![], vec![], PALETTE[0]),
            Series::line("all not-a-number", vec![nan, nan], vec![nan, nan], PALETTE[0]),
            Series::line("constant", vec![0.0, 1.0, 2.0], vec![3.0; 3], PALETTE[0]),
            Series::line("zero", vec![0.0, 1.0], vec![0.0; 2], PALETTE[0]),
            Series::line("single", vec![5.0], vec![-2.0], PALETTE[0]),
            Series::line("±∞", vec![0.0, inf, 2.0], vec![inf, 1.0, -inf], PALETTE[0]),
            Series::line("mismatched", vec![0.0, 1.0, 2.0], vec![1.0], PALETTE[0]),
            Series::band("band", vec![0.0, 1.0], vec![1.0], vec![2.0, 3.0], PALETTE[1]),
            Series::band("lone band sample", vec![0.0, nan, 2.0], vec![1.0; 3], vec![2.0; 3], PALETTE[1]),
            Series::markers("dots", vec![nan, 1e308, -1e308], vec![1.0, 1e308, -1e308], PALETTE[2]),
            Series::line("huge", vec![-1e308, 1e308], vec![1e308, -1e308], PALETTE[0]),
            Series::line("tiny", vec![0.0, 1e-320], vec![1e-320, 0.0], PALETTE[0]),
            Series::track("\u{0}control\u{7}", vec![0.0, 1.0, 0.0], vec![0.0, 1.0, 1.0], "not a colour"),
            Series {
                label: "odd style".into(),
                x: vec![0.0, 1.0],
                y: vec![0.0, 1.0],
                style: Style::Line { color: PALETTE[4], width: nan, dashed: true },
            },
            Series {
                label: "odd band".into(),
                x: vec![0.0, 1.0],
                y: vec![0.0, 1.0],
                style: Style::Band { lower: vec![-1.0, 0.0], color: PALETTE[4], opacity: nan },
            },
        ];
        for s in cases {
            let mut c = Chart::new("t", "x", "y");
            c.add(s.clone());
            assert_well_formed(&c.to_svg());
            c.equal_axes = true;
            assert_well_formed(&c.to_svg());
            c.y_range = Some((nan, 1.0));
            c.x_range = Some((2.0, 2.0));
            assert_well_formed(&c.to_svg());
            c.y_range = Some((1.0, -1.0));
            c.x_range = Some((-1e308, 1e308));
            for (w, h) in [(0, 0), (1, 1), (30, 20), (60, 2000), (u32::MAX, 3)] {
                c.width = w;
                c.height = h;
                let svg = c.to_svg();
                assert_well_formed(&svg);
            }
        }
        assert_well_formed(&Chart::new("", "", "").to_svg());
        assert_well_formed(&Chart::xy("", "", "").to_svg());
        assert_well_formed(&grid(&[], 0));
        assert_well_formed(&Grid::new(0).to_svg());
        let mut zero = Chart::new("zero-size", "", "");
        zero.width = 0;
        zero.height = 0;
        assert_well_formed(&grid(&[zero.clone(), sample_chart(), zero], 5));

        let no_groups: [&str; 0] = [];
        let mut bars = BarChart::new("bars", "", "", no_groups);
        assert_well_formed(&bars.to_svg());
        bars.add(Bars::new("orphan values", vec![1.0, 2.0], PALETTE[1]));
        assert_well_formed(&bars.to_svg());
        let mut bars = BarChart::new("bars", "g", "v", ["a", "b"]);
        bars.add(Bars::new("nan", vec![nan, inf], PALETTE[1]));
        bars.add(Bars::new("", vec![], PALETTE[2]));
        bars.add(Bars::new("huge", vec![1e308, -1e308, 5.0], "#zzz"));
        assert_well_formed(&bars.to_svg());
        bars.y_range = Some((3.0, 3.0));
        bars.width = 0;
        assert_well_formed(&bars.to_svg());
        let mut g = Grid::new(3);
        g.title = "grid <title>".into();
        g.add(bars).add(Chart::new("", "", ""));
        assert_well_formed(&g.to_svg());
    }

    #[test]
    fn decimation_keeps_bucket_extremes() {
        let mut rnd = rng(12345);
        let samples: Vec<Sample> = (0..10_000)
            .map(|i| {
                let (y, d) = (rnd() - 0.5, rnd());
                (i % 997 != 0).then_some((i as f64 * 0.01, y - d, y + d))
            })
            .collect();
        let bucket = |x: f64| (x / 100.0 * 500.0).floor() as i64;
        let lines: Vec<(f64, f64)> = decimate_line(&samples, bucket).concat();
        let (lower, upper): (Vec<Polyline>, Vec<Polyline>) = decimate_band(&samples, bucket).into_iter().unzip();
        let (lower, upper) = (lower.concat(), upper.concat());
        assert!(lines.len() <= 4 * 520 && lower.len() <= 4 * 520, "{} {}", lines.len(), lower.len());
        for b in 0..500 {
            let raw: Vec<(f64, f64, f64)> = samples.iter().flatten().copied().filter(|s| bucket(s.0) == b).collect();
            let (ymin, ymax) =
                raw.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, c), s| (a.min(s.1), c.max(s.1)));
            let kept: Vec<f64> = lines.iter().filter(|p| bucket(p.0) == b).map(|p| p.1).collect();
            assert!(kept.contains(&ymin) && kept.contains(&ymax), "bucket {b}");
            let lo = raw.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
            let hi = raw.iter().map(|s| s.2).fold(f64::NEG_INFINITY, f64::max);
            assert!(lower.iter().any(|p| bucket(p.0) == b && p.1 == lo), "bucket {b}");
            assert!(upper.iter().any(|p| bucket(p.0) == b && p.1 == hi), "bucket {b}");
        }
        // Gaps split the line; x order is preserved.
        assert_eq!(decimate_line(&samples, bucket).len(), 11);
        assert!(lines.windows(2).all(|w| w[0].0 <= w[1].0));
        // Sparse data is kept as is.
        let few: Vec<Sample> = (0..10).map(|i| Some((i as f64, i as f64, i as f64))).collect();
        assert_eq!(decimate_line(&few, bucket).concat().len(), 10);
    }

    /// Asserts that the drawn vertices `drawn` lie in the plot area and include, for every pixel
    /// column (the decimation's bucket), the highest and the lowest of the points `(xs, ys)` (to a
    /// drawing unit, for the rounding of the way there and back through the range fractions).
    fn assert_extremes_drawn(f: &Frame, xs: &[f64], ys: &[f64], drawn: &[(i32, i32)], what: &str) {
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

    #[test]
    fn drawn_series_keep_every_columns_extremes() {
        // A noisy truth with rare spikes inside a tight band: every column of the SVG must reach
        // the raw data's highest and lowest pixel, for the truth and for both band edges.
        let mut rnd = rng(7);
        let t: Vec<f64> = (0..10_000).map(|i| i as f64 * 0.01).collect();
        let truth: Vec<f64> = (0..10_000).map(|i| if i % 1733 == 0 { 5.0 } else { rnd() - 0.5 }).collect();
        let (lo, hi): (Vec<f64>, Vec<f64>) = truth.iter().map(|v| (v - 0.05, v + 0.05)).unzip();
        let mut c = Chart::new("", "time [s]", "y");
        c.add(Series::band("", t.clone(), lo.clone(), hi.clone(), PALETTE[1]));
        c.add(Series::line("", t.clone(), truth.clone(), PALETTE[0]));
        let svg = c.to_svg();
        assert!(svg.len() < 200_000, "{} bytes", svg.len());
        let f = Frame::layout(&c.spec(), (800 * K, 380 * K), (0, 0));
        // (colour, data, polylines of that colour: the band has two edges)
        for (color, data, lines) in [("#000000", &truth, 1), ("#0072B2", &lo, 2), ("#0072B2", &hi, 2)] {
            let drawn: Vec<(i32, i32)> = paths(&svg, "polyline", color).concat();
            // At most first, last, lowest and highest per column and polyline.
            assert!(drawn.len() <= 4 * lines * (f.w / K + 1) as usize, "{} vertices for {color}", drawn.len());
            assert_extremes_drawn(&f, &t, data, &drawn, color);
        }
        // The spikes reach the top of the plot.
        let spike = f.pixel((t[1733], 5.0));
        assert!(paths(&svg, "polyline", "#000000").iter().flatten().any(|&p| p == spike));
    }

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

    #[test]
    fn xy_tracks_keep_equal_scales() {
        // A wavy circle of radius 10 around (100, -50), 10 000 samples, on a wide chart.
        let a: Vec<f64> = (0..10_000).map(|i| i as f64 / 9_999.0 * std::f64::consts::TAU).collect();
        let mut c = Chart::xy("track", "east [m]", "north [m]");
        c.width = 700;
        c.height = 400;
        c.add(Series::track(
            "",
            a.iter().map(|a| 100.0 + (10.0 + 0.2 * (60.0 * a).sin()) * a.cos()).collect(),
            a.iter().map(|a| -50.0 + (10.0 + 0.2 * (60.0 * a).sin()) * a.sin()).collect(),
            PALETTE[2],
        ));
        let bbox = |c: &Chart| {
            let svg = c.to_svg();
            assert_well_formed(&svg);
            let pts: Vec<(i32, i32)> = paths(&svg, "polyline", "#D55E00").concat();
            assert!(pts.len() > 100 && pts.len() < 5_000, "{} vertices", pts.len());
            let w = pts.iter().map(|p| p.0).max().unwrap() - pts.iter().map(|p| p.0).min().unwrap();
            let h = pts.iter().map(|p| p.1).max().unwrap() - pts.iter().map(|p| p.1).min().unwrap();
            (w, h)
        };
        let (w, h) = bbox(&c);
        assert!((w - h).abs() <= K && h > 200 * K, "a circle drawn {w} × {h} units");
        // Decimated, the path still reaches every column's highest and lowest pixel.
        let f = Frame::layout(&c.spec(), (700 * K, 400 * K), (0, 0));
        let svg = c.to_svg();
        let s = &c.series[0];
        assert_extremes_drawn(&f, &s.x, &s.y, &paths(&svg, "polyline", "#D55E00").concat(), "track");
        c.equal_axes = false;
        let (w, h) = bbox(&c);
        assert!(w > h + 100 * K, "without equal axes the circle fills the wide plot: {w} × {h} units");
        // Equal axes widen fixed ranges too.
        c.equal_axes = true;
        c.x_range = Some((85.0, 115.0));
        c.y_range = Some((-65.0, -35.0));
        let (w, h) = bbox(&c);
        assert!((w - h).abs() <= K, "{w} × {h} units");
    }

    #[test]
    fn bar_charts_draw_grouped_bars_with_labels_and_legend() {
        let mut c = BarChart::new("RMS", "scenario", "error [m]", ["straight", "turn", "dock"]);
        c.add(Bars::new("SMF", vec![1.0, 2.0, -1.0], PALETTE[1]));
        c.add(Bars::new("EKF", vec![0.5, f64::NAN, f64::INFINITY], PALETTE[2]));
        let svg = c.to_svg();
        assert_well_formed(&svg);
        let rects = |color: &str| -> Vec<(i32, i32, i32, i32)> {
            elements(&svg, "rect")
                .into_iter()
                .filter(|e| attr(e, "fill") == Some(color))
                .map(|e| (num(e, "x") as i32, num(e, "y") as i32, num(e, "width") as i32, num(e, "height") as i32))
                .collect()
        };
        let (smf, ekf) = (rects("#0072B2"), rects("#D55E00"));
        // Three SMF bars and one EKF bar (non-finite values draw none), plus a legend swatch each.
        assert_eq!((smf.len(), ekf.len()), (4, 2), "{smf:?} {ekf:?}");
        let (one, two, minus) = (smf[0], smf[1], smf[2]);
        assert!((two.3 - 2 * one.3).abs() <= K, "heights {} and {}", one.3, two.3);
        assert!((minus.3 - one.3).abs() <= K && minus.1 >= one.1 + one.3 - K, "{minus:?} hangs below {one:?}");
        assert!(one.0 < ekf[0].0 && ekf[0].0 < two.0, "groups side by side: {smf:?} {ekf:?}");
        assert!((ekf[0].3 * 2 - one.3).abs() <= K);
        let labels: Vec<String> = texts(&svg).into_iter().map(|t| t.2).collect();
        for l in ["straight", "turn", "dock", "SMF", "EKF", "scenario", "error [m]", "RMS"] {
            assert!(labels.iter().any(|t| t == l), "{l} in {labels:?}");
        }
        // Too many groups for their labels: every other one is labelled, none overlap.
        let groups: Vec<String> = (0..60).map(|g| format!("scenario {g}")).collect();
        let mut many = BarChart::new("", "", "", groups);
        many.add(Bars::new("", (0..60).map(f64::from).collect(), PALETTE[1]));
        let svg = many.to_svg();
        let ticks: Vec<(i32, String)> =
            texts(&svg).into_iter().filter(|t| t.2.starts_with("scenario")).map(|t| (t.0, t.2)).collect();
        assert!(ticks.len() >= 5 && ticks.len() < 30, "{} labels", ticks.len());
        for pair in ticks.windows(2) {
            let half_widths = (text_width(&pair[0].1, TICK_FONT) + text_width(&pair[1].1, TICK_FONT)) / 2;
            assert!(pair[1].0 - pair[0].0 > half_widths, "{pair:?} overlap");
        }
    }

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

    #[test]
    fn grids_lay_panels_out_in_rows() {
        let charts = [sample_chart(), Chart::new("second", "", ""), Chart::new("third", "", "")];
        let svg = grid(&charts, 2);
        assert_well_formed(&svg);
        assert!(svg.contains("width=\"1600\" height=\"760\""));
        let t = texts(&svg);
        let at = |s: &str| t.iter().find(|x| x.2 == s).map(|x| (x.0, x.1)).expect(s);
        let (first, second, third) = (at("β &lt;&amp;&gt; test"), at("second"), at("third"));
        assert!(second.0 > 800 * K && (second.1 - first.1).abs() <= K, "{first:?} {second:?}");
        assert!(third.0 < 800 * K && third.1 > 380 * K, "{third:?}");

        let mut g = Grid::new(1);
        g.title = "Figure".into();
        g.add(Chart::new("a chart", "", "")).add(BarChart::new("a bar chart", "", "", ["x"]));
        let svg = g.to_svg();
        assert_well_formed(&svg);
        let t = texts(&svg);
        assert!(t.iter().any(|x| x.2 == "Figure") && t.iter().any(|x| x.2 == "a bar chart"));
        assert!(svg.contains("width=\"800\" height=\"798\""), "two rows of 380 px below a title row of 38 px");
    }

    #[test]
    fn write_replaces_the_file_whole() {
        let dir = std::env::temp_dir().join(format!("plot-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let path = dir.join("nested").join("fig.svg");
        let chart = sample_chart();
        chart.write(&path).expect("write");
        chart.write(&path).expect("overwrite");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), chart.to_svg());
        let names: Vec<_> =
            std::fs::read_dir(path.parent().unwrap()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["fig.svg"], "no temporary file is left");
        let bars = BarChart::new("", "", "", ["a"]);
        bars.write(&dir.join("bars.svg")).expect("bars");
        Grid::new(2).write(&dir.join("grid.svg")).expect("grid");
        // A parent that is a file, and a path without a file name: errors, not panics.
        assert!(chart.write(&path.join("below-a-file.svg")).is_err());
        assert!(chart.write(Path::new("")).is_err());
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
