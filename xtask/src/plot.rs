//! Dependency-free SVG line charts for the figures of the reproduction report.
//!
//! A [`Chart`] holds [`Series`] drawn as lines (solid or dashed), shaded bands (e.g. the interval
//! of a set-membership filter) or markers. Long series are decimated per pixel column, keeping
//! the first, last, lowest and highest sample of every column (for a band, of each edge), so a
//! bound that contains the truth still visibly contains it. Non-finite samples break a line into
//! pieces and never reach the axis ranges.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::Path;

/// Colour-blind-safe palette (Okabe–Ito), ordered for contrast on white; the pale yellow is last.
pub const PALETTE: [&str; 8] = ["#000000", "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442"];

/// How a [`Series`] is drawn.
#[derive(Clone, Debug, PartialEq)]
pub enum Style {
    /// A polyline through the samples.
    Line {
        /// Stroke colour (any SVG colour, e.g. an entry of [`PALETTE`]).
        color: &'static str,
        /// Stroke width in pixels.
        width: f64,
        /// Dashed instead of solid.
        dashed: bool,
    },
    /// A shaded area between `lower` and the series' `y` (the upper edge).
    Band {
        /// Lower edge, one value per sample.
        lower: Vec<f64>,
        /// Fill colour; the edges are stroked in the same colour.
        color: &'static str,
        /// Fill opacity in `[0, 1]`.
        opacity: f64,
    },
    /// A small dot per sample.
    Markers {
        /// Fill colour.
        color: &'static str,
    },
}

/// One data series of a [`Chart`].
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text; empty to leave the series out of the legend.
    pub label: String,
    /// Abscissae (e.g. time in seconds).
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

/// A line chart rendered to a standalone SVG document.
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
}

const TICK_FONT: f64 = 12.0;
const LABEL_FONT: f64 = 13.0;
const TITLE_FONT: f64 = 15.0;
const LEGEND_FONT: f64 = 12.0;
const LEGEND_ROW: f64 = 18.0;
const LEGEND_PAD: f64 = 7.0;
const SWATCH: f64 = 26.0;
const TICK_LEN: f64 = 5.0;
const MARKER_R: f64 = 2.5;

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
        }
    }

    /// Appends a series.
    pub fn add(&mut self, s: Series) -> &mut Self {
        self.series.push(s);
        self
    }

    /// The chart as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let (w, h) = (self.width.max(1), self.height.max(1));
        let mut out = svg_open(w, h);
        out.push_str(&self.body("plot-"));
        out.push_str("</svg>\n");
        out
    }

    /// Writes [`Chart::to_svg`] to `path`, creating missing parent directories.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        std::fs::write(path, self.to_svg())
    }

    /// The drawing of the chart (without the `<svg>` element); `id` prefixes its element ids.
    fn body(&self, id: &str) -> String {
        let entries = self.legend_entries();
        let legend_size = legend_size(&entries);
        let mut frame = self.frame(0.0, 0.0);
        let mut shapes = self.shapes(&frame);
        let mut legend_at = None;
        if let Some((lw, lh)) = legend_size {
            legend_at = free_corner(&frame, &shapes, lw, lh);
            if legend_at.is_none() {
                // Every corner of the plot area holds data: put the legend right of the plot, or
                // below it when that would leave the plot less than 55 % of the figure's width.
                frame = self.frame(lw + 14.0, 0.0);
                if frame.w >= 0.55 * f64::from(self.width.max(1)) {
                    legend_at = Some((frame.left + frame.w + 12.0, frame.top));
                } else {
                    frame = self.frame(0.0, lh + 6.0);
                    legend_at = Some((frame.left, f64::from(self.height.max(1)) - lh - 6.0));
                }
                shapes = self.shapes(&frame);
            }
        }
        let mut s = String::new();
        let (fw, fh) = (f64::from(self.width.max(1)), f64::from(self.height.max(1)));
        let _ = write!(s, r#"<g font-family="sans-serif"><rect width="{}" height="{}" fill="white"/>"#, n(fw), n(fh));
        let (l, t, w, h) = (frame.left, frame.top, frame.w, frame.h);
        let _ = write!(
            s,
            r#"<defs><clipPath id="{id}clip"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath></defs>"#,
            n(l),
            n(t),
            n(w),
            n(h)
        );
        frame.axes_under(&mut s);
        let _ = write!(s, r#"<g clip-path="url(#{id}clip)" stroke-linejoin="round" stroke-linecap="round">"#);
        for shape in &shapes {
            shape.draw(&mut s);
        }
        s.push_str("</g>");
        frame.axes_over(&mut s);
        self.labels(&frame, &mut s);
        if let (Some((lx, ly)), Some((lw, lh))) = (legend_at, legend_size) {
            draw_legend(&entries, lx, ly, lw, lh, &mut s);
        }
        s.push_str("</g>");
        s
    }

    /// Axis ranges, ticks and the plot area, keeping `right` and `below` pixels free for a legend.
    fn frame(&self, right: f64, below: f64) -> Frame {
        let (x_auto, y_auto) = self.data_extent();
        let has_markers = self.series.iter().any(|s| matches!(s.style, Style::Markers { .. }));
        let (x0, x1) = self
            .x_range
            .and_then(|(a, b)| fixed_range(a, b))
            .unwrap_or_else(|| auto_range(x_auto, if has_markers { 0.03 } else { 0.0 }));
        let (y0, y1) = self.y_range.and_then(|(a, b)| fixed_range(a, b)).unwrap_or_else(|| auto_range(y_auto, 0.05));
        let (fw, fh) = (f64::from(self.width.max(1)), f64::from(self.height.max(1)));
        let top = if self.title.is_empty() { 12.0 } else { 14.0 + TITLE_FONT + 10.0 };
        let bottom =
            below + TICK_LEN + 4.0 + TICK_FONT + if self.x_label.is_empty() { 8.0 } else { 8.0 + LABEL_FONT + 8.0 };
        let h = (fh - top - bottom).max(10.0);
        let y_ticks = ticks(y0, y1, ((h / 45.0).round() as usize).clamp(2, 8));
        let y_text = tick_labels(&y_ticks);
        let y_text_w = y_text.iter().map(|t| text_width(t, TICK_FONT)).fold(0.0, f64::max);
        let left = 8.0 + if self.y_label.is_empty() { 0.0 } else { LABEL_FONT + 10.0 } + y_text_w + TICK_LEN + 4.0;
        // Room for half of the last x tick label beyond the plot's right edge.
        let right = right + 14.0;
        let mut w = (fw - left - right).max(10.0);
        let mut x_target = ((w / 90.0).round() as usize).clamp(2, 10);
        let (x_ticks, x_text) = loop {
            let t = ticks(x0, x1, x_target);
            let text = tick_labels(&t);
            let widest = text.iter().map(|t| text_width(t, TICK_FONT)).fold(0.0, f64::max);
            if x_target <= 2 || (widest + 16.0) * (t.len() as f64) <= w {
                break (t, text);
            }
            x_target -= 1;
        };
        // Narrow the plot if the last x tick label would stick out of the figure.
        if let (Some(&last), Some(text)) = (x_ticks.last(), x_text.last()) {
            let overflow = (last - x0) / (x1 - x0) * w + text_width(text, TICK_FONT) / 2.0 + 3.0 - (w + right);
            if overflow > 0.0 {
                w = (w - overflow).max(10.0);
            }
        }
        Frame { left, top, w, h, x0, x1, y0, y1, x_ticks, x_text, y_ticks, y_text }
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

    /// Every series decimated and mapped to pixels, in drawing order.
    fn shapes(&self, f: &Frame) -> Vec<Shape> {
        let bucket = |x: f64| ((x - f.x0) / (f.x1 - f.x0) * f.w).floor().clamp(-1e15, 1e15) as i64;
        let mut bands = Vec::new();
        let mut lines = Vec::new();
        let mut dots = Vec::new();
        for s in &self.series {
            let samples = s.samples();
            match &s.style {
                Style::Band { color, opacity, .. } => {
                    let to_px = |edge: Polyline| edge.into_iter().map(|(x, y)| (f.px(x), f.py(y))).collect();
                    let segs =
                        decimate_band(&samples, bucket).into_iter().map(|(lo, hi)| (to_px(lo), to_px(hi))).collect();
                    bands.push(Shape::Band { segs, color, opacity: *opacity });
                }
                Style::Line { color, width, dashed } => {
                    let segs = decimate_line(&samples, bucket)
                        .into_iter()
                        .map(|seg| seg.into_iter().map(|(x, y)| (f.px(x), f.py(y))).collect())
                        .collect();
                    lines.push(Shape::Line { segs, color, width: *width, dashed: *dashed });
                }
                Style::Markers { color } => {
                    // One dot per half-pixel cell is indistinguishable from all of them.
                    let cells: BTreeSet<(i64, i64)> = samples
                        .iter()
                        .flatten()
                        .map(|&(x, y, _)| {
                            ((f.px(x) * 2.0).round().clamp(-1e15, 1e15) as i64, (f.py(y) * 2.0).round() as i64)
                        })
                        .collect();
                    let pts = cells.into_iter().map(|(a, b)| (a as f64 / 2.0, b as f64 / 2.0)).collect();
                    dots.push(Shape::Dots { pts, color });
                }
            }
        }
        bands.extend(lines);
        bands.extend(dots);
        bands
    }

    /// Legend rows `(label, style)`, skipping empty labels and repeats of an identical row.
    fn legend_entries(&self) -> Vec<(&str, Swatch)> {
        let mut entries: Vec<(&str, Swatch)> = Vec::new();
        for s in &self.series {
            let swatch = match &s.style {
                Style::Line { color, width, dashed } => Swatch::Line { color, width: *width, dashed: *dashed },
                Style::Band { color, opacity, .. } => Swatch::Band { color, opacity: *opacity },
                Style::Markers { color } => Swatch::Dot { color },
            };
            if !s.label.is_empty() && !entries.iter().any(|(l, sw)| *l == s.label && *sw == swatch) {
                entries.push((&s.label, swatch));
            }
        }
        entries
    }

    /// Title and axis labels.
    fn labels(&self, f: &Frame, s: &mut String) {
        let cx = f.left + f.w / 2.0;
        if !self.title.is_empty() {
            let _ = write!(
                s,
                r##"<text x="{}" y="{}" text-anchor="middle" font-size="{TITLE_FONT}" font-weight="bold" fill="#111">{}</text>"##,
                n(cx),
                n(14.0 + TITLE_FONT * 0.8),
                escape(&self.title)
            );
        }
        if !self.x_label.is_empty() {
            let y = f.top + f.h + TICK_LEN + 4.0 + TICK_FONT + 8.0 + LABEL_FONT * 0.8;
            let _ = write!(
                s,
                r##"<text x="{}" y="{}" text-anchor="middle" font-size="{LABEL_FONT}" fill="#111">{}</text>"##,
                n(cx),
                n(y),
                escape(&self.x_label)
            );
        }
        if !self.y_label.is_empty() {
            let (x, y) = (8.0 + LABEL_FONT * 0.8, f.top + f.h / 2.0);
            let _ = write!(
                s,
                r##"<text transform="translate({},{}) rotate(-90)" text-anchor="middle" font-size="{LABEL_FONT}" fill="#111">{}</text>"##,
                n(x),
                n(y),
                escape(&self.y_label)
            );
        }
    }
}

/// Lays `charts` out row by row, `columns` per row, in one SVG document (each cell keeps its
/// chart's size; a row is as tall as its tallest chart).
pub fn grid(charts: &[Chart], columns: usize) -> String {
    let columns = columns.max(1);
    let cell_w = charts.iter().map(|c| c.width.max(1)).max().unwrap_or(1);
    let rows: Vec<&[Chart]> = charts.chunks(columns).collect();
    let row_h: Vec<u32> = rows.iter().map(|r| r.iter().map(|c| c.height.max(1)).max().unwrap_or(1)).collect();
    let total_w = cell_w * columns.min(charts.len().max(1)) as u32;
    let total_h = row_h.iter().sum::<u32>().max(1);
    let mut out = svg_open(total_w, total_h);
    let _ = writeln!(out, r#"<rect width="{total_w}" height="{total_h}" fill="white"/>"#);
    let mut y = 0;
    for (r, row) in rows.iter().enumerate() {
        for (c, chart) in row.iter().enumerate() {
            let (w, h) = (chart.width.max(1), chart.height.max(1));
            let _ = write!(
                out,
                r#"<svg x="{}" y="{y}" width="{w}" height="{h}" viewBox="0 0 {w} {h}">"#,
                c as u32 * cell_w
            );
            out.push_str(&chart.body(&format!("plot{}-", r * columns + c)));
            out.push_str("</svg>\n");
        }
        y += row_h[r];
    }
    out.push_str("</svg>\n");
    out
}

/// The opening of a standalone SVG document of `w` × `h` pixels.
fn svg_open(w: u32, h: u32) -> String {
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" \
         width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\">\n"
    )
}

/// Plot area (pixels), axis ranges and ticks.
struct Frame {
    left: f64,
    top: f64,
    w: f64,
    h: f64,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    x_ticks: Vec<f64>,
    x_text: Vec<String>,
    y_ticks: Vec<f64>,
    y_text: Vec<String>,
}

impl Frame {
    fn px(&self, x: f64) -> f64 {
        let v = self.left + (x - self.x0) / (self.x1 - self.x0) * self.w;
        v.clamp(self.left - 10.0 * self.w, self.left + 11.0 * self.w)
    }

    fn py(&self, y: f64) -> f64 {
        let v = self.top + self.h - (y - self.y0) / (self.y1 - self.y0) * self.h;
        v.clamp(self.top - 10.0 * self.h, self.top + 11.0 * self.h)
    }

    /// Grid lines (the one at zero darker).
    fn axes_under(&self, s: &mut String) {
        let (l, t, w, h) = (self.left, self.top, self.w, self.h);
        let mut grid = String::new();
        let mut zero = String::new();
        for &x in &self.x_ticks {
            let _ = write!(grid, "M{} {}v{}", n(crisp(self.px(x))), n(t), n(h));
        }
        for &y in &self.y_ticks {
            let d = if y == 0.0 { &mut zero } else { &mut grid };
            let _ = write!(d, "M{} {}h{}", n(l), n(crisp(self.py(y))), n(w));
        }
        if !grid.is_empty() {
            let _ = write!(s, r##"<path d="{grid}" stroke="#e4e4e4" stroke-width="1" fill="none"/>"##);
        }
        if !zero.is_empty() {
            let _ = write!(s, r##"<path d="{zero}" stroke="#a8a8a8" stroke-width="1" fill="none"/>"##);
        }
    }

    /// Frame, tick marks and tick labels.
    fn axes_over(&self, s: &mut String) {
        let (l, t, w, h) = (self.left, self.top, self.w, self.h);
        let _ = write!(
            s,
            r##"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="#333" stroke-width="1"/>"##,
            n(crisp(l)),
            n(crisp(t)),
            n((crisp(l + w) - crisp(l)).max(1.0)),
            n((crisp(t + h) - crisp(t)).max(1.0))
        );
        let mut d = String::new();
        for &x in &self.x_ticks {
            let _ = write!(d, "M{} {}v{TICK_LEN}", n(crisp(self.px(x))), n(crisp(t + h)));
        }
        for &y in &self.y_ticks {
            let _ = write!(d, "M{} {}h-{TICK_LEN}", n(crisp(l)), n(crisp(self.py(y))));
        }
        let _ = write!(s, r##"<path d="{d}" stroke="#333" stroke-width="1" fill="none"/>"##);
        let _ = write!(s, r##"<g font-size="{TICK_FONT}" fill="#222">"##);
        for (x, text) in self.x_ticks.iter().zip(&self.x_text) {
            let y = t + h + TICK_LEN + 3.0 + TICK_FONT * 0.8;
            let _ =
                write!(s, r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#, n(self.px(*x)), n(y), escape(text));
        }
        for (y, text) in self.y_ticks.iter().zip(&self.y_text) {
            let (x, y) = (l - TICK_LEN - 3.0, self.py(*y) + TICK_FONT * 0.35);
            let _ = write!(s, r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#, n(x), n(y), escape(text));
        }
        s.push_str("</g>");
    }
}

/// A decimated series in pixel coordinates.
enum Shape {
    /// Pieces of a band as (lower edge, upper edge).
    Band {
        segs: Vec<(Polyline, Polyline)>,
        color: &'static str,
        opacity: f64,
    },
    Line {
        segs: Vec<Polyline>,
        color: &'static str,
        width: f64,
        dashed: bool,
    },
    Dots {
        pts: Vec<(f64, f64)>,
        color: &'static str,
    },
}

impl Shape {
    fn draw(&self, s: &mut String) {
        match self {
            Shape::Band { segs, color, opacity } => {
                let (mut fill, mut edge) = (String::new(), String::new());
                for (lower, upper) in segs {
                    for (k, &(x, y)) in lower.iter().enumerate() {
                        let _ = write!(edge, "{}{} {}", if k == 0 { 'M' } else { 'L' }, n(x), n(y));
                    }
                    for (k, &(x, y)) in upper.iter().enumerate() {
                        let _ = write!(edge, "{}{} {}", if k == 0 { 'M' } else { 'L' }, n(x), n(y));
                        let _ = write!(fill, "{}{} {}", if k == 0 { 'M' } else { 'L' }, n(x), n(y));
                    }
                    for &(x, y) in lower.iter().rev() {
                        let _ = write!(fill, "L{} {}", n(x), n(y));
                    }
                    // A lone sample still shows as a short vertical bar.
                    fill.push('Z');
                }
                if !fill.is_empty() {
                    let _ = write!(
                        s,
                        r#"<path d="{fill}" fill="{color}" fill-opacity="{}" stroke="{color}" stroke-opacity="{}" stroke-width="1"/>"#,
                        n3(opacity.clamp(0.0, 1.0)),
                        n3((opacity * 0.5).clamp(0.0, 1.0)),
                    );
                    let _ = write!(s, r#"<path d="{edge}" fill="none" stroke="{color}" stroke-width="0.8"/>"#);
                }
            }
            Shape::Line { segs, color, width, dashed } => {
                let (mut d, mut lone) = (String::new(), String::new());
                for seg in segs {
                    if let [(x, y)] = seg[..] {
                        // A lone sample (no neighbour to connect to) shows as a dot.
                        let r = n(width.max(1.5) * 1.2);
                        let _ = write!(lone, r#"<circle cx="{}" cy="{}" r="{r}" fill="{color}"/>"#, n(x), n(y));
                        continue;
                    }
                    for (k, &(x, y)) in seg.iter().enumerate() {
                        let _ = write!(d, "{}{} {}", if k == 0 { 'M' } else { 'L' }, n(x), n(y));
                    }
                }
                s.push_str(&lone);
                if !d.is_empty() {
                    let dash = if *dashed {
                        format!(r#" stroke-dasharray="{} {}""#, n(4.0 * width.max(1.0)), n(3.0 * width.max(1.0)))
                    } else {
                        String::new()
                    };
                    let _ =
                        write!(s, r#"<path d="{d}" fill="none" stroke="{color}" stroke-width="{}"{dash}/>"#, n(*width));
                }
            }
            Shape::Dots { pts, color } => {
                let _ = write!(s, r#"<g fill="{color}">"#);
                for &(x, y) in pts {
                    let _ = write!(s, r#"<circle cx="{}" cy="{}" r="{MARKER_R}"/>"#, n(x), n(y));
                }
                s.push_str("</g>");
            }
        }
    }

    /// Marks the vertical pixel extent the shape covers in every pixel column of the plot area.
    fn cover(&self, f: &Frame, cols: &mut [(f64, f64)]) {
        match self {
            Shape::Band { segs, .. } => {
                // Covering both edges covers the pixels between them too.
                for (lower, upper) in segs {
                    cover_path(f, cols, lower.iter().map(|&(x, y)| (x, y, y)));
                    cover_path(f, cols, upper.iter().map(|&(x, y)| (x, y, y)));
                }
            }
            Shape::Line { segs, width, .. } => {
                for seg in segs {
                    cover_path(f, cols, seg.iter().map(|&(x, y)| (x, y - width / 2.0, y + width / 2.0)));
                }
            }
            Shape::Dots { pts, .. } => {
                for &(x, y) in pts {
                    for dx in [-MARKER_R, 0.0, MARKER_R] {
                        cover_path(f, cols, std::iter::once((x + dx, y - MARKER_R, y + MARKER_R)));
                    }
                }
            }
        }
    }
}

/// Legend swatch of a series.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Swatch {
    Line { color: &'static str, width: f64, dashed: bool },
    Band { color: &'static str, opacity: f64 },
    Dot { color: &'static str },
}

/// Width and height of the legend box, `None` without entries.
fn legend_size(entries: &[(&str, Swatch)]) -> Option<(f64, f64)> {
    if entries.is_empty() {
        return None;
    }
    let text = entries.iter().map(|(l, _)| text_width(l, LEGEND_FONT)).fold(0.0, f64::max);
    Some((2.0 * LEGEND_PAD + SWATCH + 6.0 + text, 2.0 * LEGEND_PAD + LEGEND_ROW * entries.len() as f64 - 4.0))
}

/// The first corner of the plot area (top-right, top-left, bottom-right, bottom-left) where a
/// `lw` × `lh` legend box touches no data.
fn free_corner(f: &Frame, shapes: &[Shape], lw: f64, lh: f64) -> Option<(f64, f64)> {
    let inset = 8.0;
    if lw + 2.0 * inset > f.w || lh + 2.0 * inset > f.h {
        return None;
    }
    let mut cols = vec![(f64::INFINITY, f64::NEG_INFINITY); f.w.ceil() as usize];
    for shape in shapes {
        shape.cover(f, &mut cols);
    }
    let (right, left) = (f.left + f.w - inset - lw, f.left + inset);
    let (top, bottom) = (f.top + inset, f.top + f.h - inset - lh);
    [(right, top), (left, top), (right, bottom), (left, bottom)].into_iter().find(|&(x, y)| {
        let gap = 4.0;
        let c0 = ((x - gap - f.left).floor().max(0.0)) as usize;
        let c1 = ((x + lw + gap - f.left).ceil().max(0.0) as usize).min(cols.len());
        cols[c0.min(c1)..c1].iter().all(|&(a, b)| b < y - gap || a > y + lh + gap)
    })
}

/// Adds the pixel extent of the polyline `pts` (`(x, top, bottom)` per vertex) to `cols`.
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
        let x = x - f.left;
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

fn draw_legend(entries: &[(&str, Swatch)], x: f64, y: f64, w: f64, h: f64, s: &mut String) {
    let _ = write!(
        s,
        r##"<g font-size="{LEGEND_FONT}"><rect x="{}" y="{}" width="{}" height="{}" rx="3" fill="white" fill-opacity="0.9" stroke="#999" stroke-width="0.8"/>"##,
        n(crisp(x)),
        n(crisp(y)),
        n(w.round()),
        n(h.round())
    );
    for (k, (label, swatch)) in entries.iter().enumerate() {
        let cy = y + LEGEND_PAD + LEGEND_ROW * k as f64 + (LEGEND_ROW - 4.0) / 2.0;
        let sx = x + LEGEND_PAD;
        match *swatch {
            Swatch::Line { color, width, dashed } => {
                let dash = if dashed {
                    format!(r#" stroke-dasharray="{} {}""#, n(4.0 * width.max(1.0)), n(3.0 * width.max(1.0)))
                } else {
                    String::new()
                };
                let _ = write!(
                    s,
                    r#"<path d="M{} {}h{SWATCH}" stroke="{color}" stroke-width="{}" fill="none"{dash}/>"#,
                    n(sx),
                    n(cy),
                    n(width.max(1.5))
                );
            }
            Swatch::Band { color, opacity } => {
                let _ = write!(
                    s,
                    r#"<rect x="{}" y="{}" width="{SWATCH}" height="10" fill="{color}" fill-opacity="{}" stroke="{color}" stroke-width="0.8"/>"#,
                    n(sx),
                    n(cy - 5.0),
                    n3(opacity.clamp(0.0, 1.0))
                );
            }
            Swatch::Dot { color } => {
                let _ = write!(s, r#"<circle cx="{}" cy="{}" r="3" fill="{color}"/>"#, n(sx + SWATCH / 2.0), n(cy));
            }
        }
        let _ = write!(
            s,
            r##"<text x="{}" y="{}" fill="#111">{}</text>"##,
            n(sx + SWATCH + 6.0),
            n(cy + LEGEND_FONT * 0.35),
            escape(label)
        );
    }
    s.push_str("</g>");
}

/// Line decimation: splits at gaps, and keeps, of every run of consecutive samples falling into
/// the same `bucket`, the first, the last, the lowest and the highest (in their original order).
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
        let (mut imin, mut imax, mut j) = (i, i, i + 1);
        let y = |k: usize| samples[k].map_or(f64::NAN, |s| s.1);
        while let Some(Some((xj, yj, _))) = samples.get(j) {
            if bucket(*xj) != b {
                break;
            }
            if *yj < y(imin) {
                imin = j;
            }
            if *yj > y(imax) {
                imax = j;
            }
            j += 1;
        }
        let mut keep = [i, imin, imax, j - 1];
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

/// Escapes text for SVG/XML content and attribute values.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c if c.is_control() => {}
            c => out.push(c),
        }
    }
    out
}

/// Approximate rendered width of `s` in pixels, erring wide (DejaVu Sans-like metrics).
fn text_width(s: &str, size: f64) -> f64 {
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
    em * size
}

/// A pixel coordinate on the half-pixel grid, so that 1-pixel lines are crisp.
fn crisp(v: f64) -> f64 {
    v.round() + 0.5
}

/// A coordinate with at most one decimal (and no "-0").
fn n(v: f64) -> String {
    let r = (v * 10.0).round() / 10.0;
    if r == r.trunc() && r.abs() < 1e15 { format!("{}", r as i64) } else { format!("{r:.1}") }
}

/// A value in `[0, 1]` with at most three decimals.
fn n3(v: f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    format!("{r}")
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
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "non-finite number in the output:\n{svg}");
    }

    fn check_entities(s: &str) {
        for (i, _) in s.match_indices('&') {
            let ent = &s[i..s[i..].find(';').map_or(s.len(), |e| i + e + 1)];
            assert!(["&amp;", "&lt;", "&gt;", "&quot;", "&#39;"].contains(&ent), "bad entity {ent:?}");
        }
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

    #[test]
    fn svg_is_well_formed() {
        let svg = sample_chart().to_svg();
        assert_well_formed(&svg);
        assert!(svg.contains("viewBox=\"0 0 800 380\""));
        assert!(svg.contains("font-family=\"sans-serif\""));
        assert!(svg.contains("β &lt;&amp;&gt; test"));
        // The duplicated dashed bound appears once in the legend.
        assert_eq!(svg.matches(">SMF B</text>").count(), 1);
        assert!(svg.len() < 200_000, "decimation keeps the file small: {} bytes", svg.len());
        assert_well_formed(&grid(&[sample_chart(), Chart::new("", "", ""), sample_chart()], 2));
    }

    #[test]
    fn escaping() {
        assert_eq!(escape(r#"a<b & c>"d'"#), "a&lt;b &amp; c&gt;&quot;d&#39;");
        assert_eq!(escape("γ [rad/s]"), "γ [rad/s]");
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
            Series::markers("dots", vec![nan, 1e308, -1e308], vec![1.0, 1e308, -1e308], PALETTE[2]),
            Series::line("tiny", vec![0.0, 1e-320], vec![1e-320, 0.0], PALETTE[0]),
        ];
        for s in cases {
            let mut c = Chart::new("t", "x", "y");
            c.add(s.clone());
            assert_well_formed(&c.to_svg());
            c.y_range = Some((nan, 1.0));
            c.x_range = Some((2.0, 2.0));
            assert_well_formed(&c.to_svg());
            c.y_range = Some((1.0, -1.0));
            c.width = 0;
            c.height = 0;
            assert_well_formed(&c.to_svg());
        }
        assert_well_formed(&Chart::new("", "", "").to_svg());
        assert_well_formed(&grid(&[], 0));
    }

    #[test]
    fn decimation_keeps_bucket_extremes() {
        // Deterministic pseudo-random data with gaps.
        let mut state = 12345u64;
        let mut rnd = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
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
}
