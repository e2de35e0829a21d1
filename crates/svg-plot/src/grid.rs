//! [`Grid`]: several panels in one SVG document, row by row.

use plotters::element::Text;
use plotters::style::WHITE;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::Area;
use crate::bars::BarChart;
use crate::chart::Chart;
use crate::render::{Figure, render_svg};
use crate::style::{K, MAX_SIDE, TEXT};
use crate::text::{TITLE_FONT, clean, pixels, text_style};

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
}

/// Lays `charts` out row by row, `columns` per row, in one SVG document (each cell keeps its
/// chart's size; a row is as tall as its tallest chart). See [`Grid`] for titles and bar charts.
pub fn grid(charts: &[Chart], columns: usize) -> String {
    let panels: Vec<&dyn Figure> = charts.iter().map(|c| c as &dyn Figure).collect();
    render_grid("", &panels, columns)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::style::K;
    use crate::test_util::*;
    use crate::{Bars, PALETTE};

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
    fn degenerate_bar_charts_and_grids_do_not_panic() {
        let (nan, inf) = (f64::NAN, f64::INFINITY);
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
}
