//! [`BarChart`]: grouped bars, one group per category and one bar per [`Bars`] series.

use crate::axis::{fixed_range, widen};
use crate::clip::Shape;
use crate::legend::{Swatch, push_entry};
use crate::render::{Figure, Spec, render, render_svg};
use crate::style::{MAX_SIDE, rgb};
use crate::{Area, Range};

/// One series of a [`BarChart`]: one bar per group.
#[derive(Clone, Debug, PartialEq)]
pub struct Bars {
    /// Legend text; empty to leave the series out of the legend.
    pub label: String,
    /// One value per group of the chart (missing or non-finite values draw no bar; values beyond
    /// the last group are ignored).
    pub values: Vec<f64>,
    /// Fill colour: `#rrggbb` or `#rgb` (e.g. an entry of [`PALETTE`](crate::PALETTE)); anything
    /// else is black.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PALETTE;
    use crate::style::K;
    use crate::test_util::*;
    use crate::text::{TICK_FONT, text_width};

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
}
