//! Text: the embedded font (DejaVu Sans, registered once with plotters), font sizes, text styles
//! and measured widths.

use std::sync::OnceLock;

use plotters::style::{Color, FontDesc, FontFamily, FontStyle, RGBColor, TextStyle, register_font};

use crate::style::K;

// Font sizes in pixels, each one for which plotters' size (the SVG `font-size`, in drawing units,
// times 1.24) divides back exactly: the SVG says `font-size="50"` for 12.5 px, where 13 px would
// come out as `52.00000000000001`.
pub(crate) const TICK_FONT: f64 = 12.0;
pub(crate) const LABEL_FONT: f64 = 12.5;
pub(crate) const TITLE_FONT: f64 = 15.5;
pub(crate) const LEGEND_FONT: f64 = 12.0;

/// Registers the embedded font under the family `sans-serif` (once); `false` if that failed, in
/// which case text widths fall back to an estimate (the SVG backend needs no font to write text).
pub(crate) fn font_ready() -> bool {
    static READY: OnceLock<bool> = OnceLock::new();
    *READY.get_or_init(|| register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular()).is_ok())
}

/// plotters' font size for an SVG `font-size` of `px` (its SVG backend writes the size divided by
/// 1.24), nudged so that the division gives `px` exactly.
pub(crate) fn plotters_size(px: f64) -> f64 {
    let s = px * 1.24;
    (-4i64..=4).map(|k| f64::from_bits(s.to_bits().wrapping_add_signed(k))).find(|c| c / 1.24 == px).unwrap_or(s)
}

/// A sans-serif text style of `px` pixels.
pub(crate) fn text_style(px: f64, bold: bool, color: RGBColor) -> TextStyle<'static> {
    let style = if bold { FontStyle::Bold } else { FontStyle::Normal };
    let mut text = TextStyle::from(FontDesc::new(FontFamily::SansSerif, plotters_size(px * f64::from(K)), style));
    text.color = color.to_backend_color();
    text
}

/// Rendered width of `s` at `px` pixels, in drawing units: measured with the embedded font, or
/// estimated (erring wide).
pub(crate) fn text_width(s: &str, px: f64) -> i32 {
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
pub(crate) fn pixels(font: f64) -> i32 {
    font.ceil() as i32
}

/// The height of a font of `px` pixels, in drawing units.
pub(crate) fn font_units(px: f64) -> i32 {
    pixels(px) * K
}

/// `s` without control characters (which XML forbids).
pub(crate) fn clean(s: &str) -> String {
    s.chars().filter(|c| !c.is_control()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::*;

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
}
