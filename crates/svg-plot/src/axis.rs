//! Axes: ranges (automatic, fixed, widened when degenerate), "nice" tick values and their labels,
//! and the plotters coordinate ([`Ranged`]) that shows exactly these ticks. It is our own rather
//! than plotters' `f64` range with custom key points because it maps values to drawing units by
//! rounding to the nearest unit (`Axis::pixel_of_frac`), the rounding that the clipping and the
//! thinning of points predict through `Frame::pixel`; plotters' own range floors instead.

use std::ops::Range as StdRange;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};

use crate::Range;
use crate::text::clean;

/// One axis: its range, tick values and tick labels. Implements plotters' [`Ranged`] so that the
/// mesh shows exactly these ticks.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Axis {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
    pub(crate) ticks: Vec<f64>,
    pub(crate) labels: Vec<String>,
}

impl Axis {
    pub(crate) fn numeric((lo, hi): Range, target: usize) -> Self {
        let ticks = ticks(lo, hi, target);
        let labels = tick_labels(&ticks);
        Self { lo, hi, ticks, labels }
    }

    pub(crate) fn categories(groups: &[String]) -> Self {
        let n = groups.len();
        Self {
            lo: -0.5,
            hi: n.max(1) as f64 - 0.5,
            ticks: (0..n).map(|g| g as f64).collect(),
            labels: groups.iter().map(|g| clean(g)).collect(),
        }
    }

    /// `v` as a fraction of the range (0 at `lo`, 1 at `hi`), bounded to ±10⁶.
    pub(crate) fn frac(&self, v: f64) -> f64 {
        let f = (v - self.lo) / (self.hi - self.lo);
        if f.is_nan() { 0.0 } else { f.clamp(-1e6, 1e6) }
    }

    /// The value at fraction `f` of the range.
    pub(crate) fn value(&self, f: f64) -> f64 {
        self.lo + f * (self.hi - self.lo)
    }

    /// The position of fraction `f` between the positions `limit.0` (at `lo`) and `limit.1` (at `hi`).
    pub(crate) fn pixel_of_frac(f: f64, limit: (i32, i32)) -> i32 {
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

/// A user-given range, `None` unless both ends are finite; degenerate ranges are widened.
pub(crate) fn fixed_range(a: f64, b: f64) -> Option<(f64, f64)> {
    (a.is_finite() && b.is_finite()).then(|| widen(a.min(b), a.max(b)))
}

/// The data extent plus `margin` (a fraction of the span) on both sides; `(0, 1)` without data.
pub(crate) fn auto_range(extent: Option<(f64, f64)>, margin: f64) -> (f64, f64) {
    let Some((lo, hi)) = extent else { return (0.0, 1.0) };
    let (lo, hi) = widen(lo, hi);
    let pad = (hi - lo) * margin;
    let (a, b) = (lo - pad, hi + pad);
    if a.is_finite() && b.is_finite() { (a, b) } else { (lo, hi) }
}

/// Widens an empty or numerically negligible range `[lo, hi]` around its centre; keeps the span finite.
pub(crate) fn widen(lo: f64, hi: f64) -> (f64, f64) {
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
pub(crate) fn ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
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
pub(crate) fn round_to(v: f64, step: f64) -> f64 {
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
pub(crate) fn tick_labels(ticks: &[f64]) -> Vec<String> {
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
}
