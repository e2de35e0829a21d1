//! Rendering a panel with plotters: the SVG document (drawn in quarter pixels, sized in pixels),
//! axes and grid through a plotters chart context, the shapes, the frame, the legend and the
//! title.

use plotters::backend::SVGBackend;
use plotters::chart::ChartBuilder;
use plotters::drawing::IntoDrawingArea;
use plotters::element::{Circle, DashedPathElement, PathElement, Polygon, Rectangle, Text};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color, ShapeStyle, WHITE};

use crate::clip::{Shape, clip_shapes};
use crate::layout::Frame;
use crate::legend::{Swatch, draw_legend, free_corner, legend_size};
use crate::style::{AXIS, GRID, HAIRLINE, K, MAX_SIDE, TEXT, TICK_LEN, TICK_TEXT, ZERO};
use crate::text::{LABEL_FONT, TICK_FONT, TITLE_FONT, clean, font_ready, text_style};
use crate::{Area, Range};

/// A panel that can be drawn into a drawing area of its size.
pub(crate) trait Figure {
    /// Width and height in pixels, each in `1..=MAX_SIDE`.
    fn size(&self) -> (u32, u32);
    /// Draws the panel into `area`, ignoring drawing errors (draws what is drawable).
    fn draw_on(&self, area: &Area<'_>);
}

/// What the shared renderer needs to know about a panel.
pub(crate) struct Spec<'a> {
    pub(crate) title: &'a str,
    pub(crate) x_label: &'a str,
    pub(crate) y_label: &'a str,
    /// Ranges before equal scaling.
    pub(crate) x: Range,
    pub(crate) y: Range,
    /// Tick labels at x = 0, 1, … instead of numbers (bar charts).
    pub(crate) categories: Option<&'a [String]>,
    pub(crate) equal_axes: bool,
    pub(crate) legend: Vec<(String, Swatch)>,
}

/// Runs `draw` on an SVG drawing area of `size` pixels (in drawing units: `K` times that) and
/// returns the document.
pub(crate) fn render_svg(size: (u32, u32), draw: impl FnOnce(&Area<'_>)) -> String {
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

/// Draws `spec` into `area`: axes, the shapes that `shapes` makes for the final layout, legend and title.
pub(crate) fn render(area: &Area<'_>, spec: &Spec, shapes: &dyn Fn(&Frame) -> Vec<Shape>) {
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
pub(crate) fn draw_plot(area: &Area<'_>, spec: &Spec, f: &Frame, shapes: &[Shape]) {
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
pub(crate) fn outline([a, b]: [(i32, i32); 2], style: ShapeStyle) -> PathElement<(i32, i32)> {
    PathElement::new(vec![a, (b.0, a.1), b, (a.0, b.1), a], style)
}
