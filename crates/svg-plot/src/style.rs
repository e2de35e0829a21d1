//! Colours, stroke widths, dash patterns and the fixed lengths of the layout, in drawing units
//! ([`K`] per pixel).

use plotters::style::RGBColor;

/// Colour-blind-safe palette (Okabe–Ito), ordered for contrast on white; the pale yellow is last.
pub const PALETTE: [&str; 8] = ["#000000", "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442"];

/// Drawing units per pixel. plotters' SVG backend writes integer coordinates, so we draw at four
/// times the size and let the root element's `viewBox` scale it down: coordinates are precise to a
/// quarter of a pixel (whole pixels would turn slopes into visible stairs when a figure is zoomed)
/// and stroke widths come in quarter pixels. All lengths below are in these units.
pub(crate) const K: i32 = 4;

pub(crate) const LEGEND_ROW: i32 = 18 * K;
pub(crate) const LEGEND_PAD: i32 = 7 * K;
pub(crate) const SWATCH: i32 = 26 * K;
pub(crate) const TICK_LEN: i32 = 5 * K;
pub(crate) const MARKER_R: u32 = 3 * K as u32;
/// Width of the band edges, the legend border and the band swatch's border (0.75 px).
pub(crate) const THIN: u32 = 3;
/// Width of the frame, the axes and the grid lines (1 px).
pub(crate) const HAIRLINE: u32 = K as u32;

/// At most this many dashes (each one SVG element) per colour and dash pattern, e.g. for a pair of
/// dashed bounds: longer paths get proportionally longer dashes and gaps.
pub(crate) const MAX_DASHES: f64 = 400.0;

/// Largest side of a figure in pixels (plotters works in `i32` drawing units).
pub(crate) const MAX_SIDE: u32 = 1 << 20;

pub(crate) const TEXT: RGBColor = RGBColor(0x11, 0x11, 0x11);
pub(crate) const TICK_TEXT: RGBColor = RGBColor(0x22, 0x22, 0x22);
pub(crate) const AXIS: RGBColor = RGBColor(0x33, 0x33, 0x33);
pub(crate) const GRID: RGBColor = RGBColor(0xe4, 0xe4, 0xe4);
pub(crate) const ZERO: RGBColor = RGBColor(0xa8, 0xa8, 0xa8);
pub(crate) const LEGEND_BORDER: RGBColor = RGBColor(0x99, 0x99, 0x99);

/// A `#rrggbb` or `#rgb` colour; black for anything else.
pub(crate) fn rgb(s: &str) -> RGBColor {
    let hex = s.trim().strip_prefix('#').unwrap_or("");
    let digits: Vec<u8> = hex.chars().filter_map(|c| c.to_digit(16).map(|d| d as u8)).collect();
    match (hex.len(), &digits[..]) {
        (6, &[a, b, c, d, e, f]) => RGBColor(a * 16 + b, c * 16 + d, e * 16 + f),
        (3, &[a, b, c]) => RGBColor(a * 17, b * 17, c * 17),
        _ => RGBColor(0, 0, 0),
    }
}

/// A stroke width of `w` pixels in drawing units (whole quarter pixels), from a quarter to 16 pixels.
pub(crate) fn stroke_width(w: f64) -> u32 {
    ((w * f64::from(K)).round() as u32).clamp(1, 16 * K as u32)
}

/// Dash pattern in drawing units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dash {
    pub(crate) on: f64,
    pub(crate) off: f64,
}

/// The dash pattern of a dashed line `width` units wide.
pub(crate) fn dash(width: u32) -> Dash {
    let w = f64::from(width.max(K as u32));
    Dash { on: 4.0 * w, off: 3.0 * w }
}

/// An opacity in `[0, 1]` (NaN counts as the default 0.25).
pub(crate) fn clamp_opacity(o: f64) -> f64 {
    if o.is_nan() { 0.25 } else { o.clamp(0.0, 1.0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colors_parse() {
        assert_eq!(rgb("#D55E00"), RGBColor(0xd5, 0x5e, 0x00));
        assert_eq!(rgb("#0af"), RGBColor(0x00, 0xaa, 0xff));
        for bad in ["", "red", "#12345", "#gg0000", "#ééé"] {
            assert_eq!(rgb(bad), RGBColor(0, 0, 0), "{bad}");
        }
    }
}
