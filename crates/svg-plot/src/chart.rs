//! [`Chart`]: line, band and marker series (and XY tracks) against one pair of axes.

use crate::axis::{auto_range, fixed_range};
use crate::clip::Shape;
use crate::decimate::{decimate_band, decimate_line};
use crate::layout::Frame;
use crate::legend::{Swatch, push_entry};
use crate::render::{Figure, Spec, render, render_svg};
use crate::series::{Series, Style};
use crate::style::{K, MARKER_R, MAX_SIDE, THIN, clamp_opacity, dash, rgb, stroke_width};
use crate::{Area, Range};

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

    pub(crate) fn spec(&self) -> Spec<'_> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::*;
    use crate::{PALETTE, grid};

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
    }
}
