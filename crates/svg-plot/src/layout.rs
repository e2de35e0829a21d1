//! The layout of a panel: margins, the areas of the axis labels and the plot area, with the axes
//! that fit it (tick counts from the space, equal scaling for tracks, crisp pixel alignment).

use crate::axis::Axis;
use crate::render::Spec;
use crate::style::{K, TICK_LEN};
use crate::text::{LABEL_FONT, TICK_FONT, TITLE_FONT, font_units, text_width};
use crate::{Pt, Range};

/// Panel layout in drawing units: margins, label areas and the plot area, with the axes.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Frame {
    pub(crate) margin_top: i32,
    pub(crate) margin_bottom: i32,
    pub(crate) margin_left: i32,
    pub(crate) margin_right: i32,
    /// Height of the x label area (tick marks, tick labels, axis label) below the plot.
    pub(crate) x_area: i32,
    /// Width of the y label area left of the plot.
    pub(crate) y_area: i32,
    /// Plot area: columns `left..left + w`, rows `top..top + h`.
    pub(crate) left: i32,
    pub(crate) top: i32,
    pub(crate) w: i32,
    pub(crate) h: i32,
    pub(crate) x: Axis,
    pub(crate) y: Axis,
}

impl Frame {
    /// The layout of `spec` in a `size` panel keeping `reserve` = (right, below) units free.
    pub(crate) fn layout(spec: &Spec, size: (i32, i32), reserve: (i32, i32)) -> Self {
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
    pub(crate) fn px(&self, u: f64) -> f64 {
        f64::from(self.left) + u * f64::from(self.w - 1)
    }

    /// Panel position (in drawing units) of the fraction `v` of the y range, not rounded.
    pub(crate) fn py(&self, v: f64) -> f64 {
        f64::from(self.top + self.h - 1) - v * f64::from(self.h - 1)
    }

    /// The position (in drawing units) plotters draws the data point `p` at.
    pub(crate) fn pixel(&self, (x, y): Pt) -> (i32, i32) {
        (
            Axis::pixel_of_frac(self.x.frac(x), (self.left, self.left + self.w - 1)),
            Axis::pixel_of_frac(self.y.frac(y), (self.top + self.h - 1, self.top)),
        )
    }
}

/// Scales `parts` down (keeping their proportions) so that they leave at least one unit of `total`.
pub(crate) fn fit(parts: &mut [i32], total: i32) {
    let sum: i32 = parts.iter().sum();
    let room = (total - 1).max(0);
    if sum > room {
        for p in parts.iter_mut() {
            *p = (i64::from(*p) * i64::from(room) / i64::from(sum.max(1))) as i32;
        }
    }
}

/// Ranges widened around their centres so that one unit of data spans as long on both axes.
pub(crate) fn equalize(x: Range, y: Range, w: i32, h: i32) -> (Range, Range) {
    let (pw, ph) = (f64::from((w - 1).max(1)), f64::from((h - 1).max(1)));
    let s = ((x.1 - x.0) / pw).max((y.1 - y.0) / ph);
    let around = |(a, b): Range, pixels: f64| {
        let (mid, half) = (a / 2.0 + b / 2.0, s * pixels / 2.0);
        let r = (mid - half, mid + half);
        if r.0.is_finite() && r.1.is_finite() && r.1 > r.0 { r } else { (a, b) }
    };
    (around(x, pw), around(y, ph))
}
