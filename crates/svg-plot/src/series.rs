//! Data series of a [`Chart`](crate::Chart): lines, bands, markers and XY tracks.

/// How a [`Series`] is drawn.
#[derive(Clone, Debug, PartialEq)]
pub enum Style {
    /// A polyline through the samples, in their order.
    Line {
        /// Stroke colour: `#rrggbb` or `#rgb` (e.g. an entry of [`PALETTE`](crate::PALETTE)); anything
        /// else is black.
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

/// One data series of a [`Chart`](crate::Chart).
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
    /// not increase (e.g. a vehicle's path, north against east). Usually drawn on [`Chart::xy`](crate::Chart::xy).
    pub fn track(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: &'static str) -> Self {
        Self::line(label, x, y, color)
    }

    /// The finite samples as `(x, low, high)` (`low == high` except for bands); `None` marks a gap.
    pub(crate) fn samples(&self) -> Vec<Sample> {
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
pub(crate) type Sample = Option<(f64, f64, f64)>;
