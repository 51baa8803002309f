//! A figure as data: panels of lines, bands, markers and shaded spans, independent of
//! how they are drawn (`crate::plot`).

/// One line of a panel.
#[derive(Clone, Debug, Default)]
pub struct Line {
    /// Legend entry (none when empty).
    pub label: String,
    /// x values (time, s).
    pub x: Vec<f64>,
    /// y values.
    pub y: Vec<f64>,
    /// Palette index (0 blue, 1 red, 2 green, 3 orange, 4 purple, 5 grey, 6 brown, 7 cyan).
    pub color: usize,
    /// Drawn thinner, on top of the lines before it (the second of a compared pair).
    pub thin: bool,
    /// Drawn dashed (and dashed in the legend).
    pub dashed: bool,
}

/// A filled band between two curves (e.g. the spread of many lines).
#[derive(Clone, Debug, Default)]
pub struct Band {
    /// Legend entry.
    pub label: String,
    /// x values.
    pub x: Vec<f64>,
    /// Lower edge.
    pub lo: Vec<f64>,
    /// Upper edge.
    pub hi: Vec<f64>,
}

/// A horizontal or vertical marker line (dashed), with a label.
#[derive(Clone, Debug)]
pub struct Marker {
    /// Where (y for horizontal, x for vertical markers).
    pub at: f64,
    /// Legend text (none when empty).
    pub label: String,
}

/// A shaded x interval (e.g. the contact window).
#[derive(Clone, Debug)]
pub struct Span {
    /// Start.
    pub from: f64,
    /// End.
    pub to: f64,
    /// Legend text (none when empty).
    pub label: String,
}

/// One chart: axes, lines, bands, markers and spans.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    /// Title above the chart.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// The lines, drawn in order.
    pub lines: Vec<Line>,
    /// Bands, drawn below the lines.
    pub bands: Vec<Band>,
    /// Horizontal markers (bounds, bands).
    pub hlines: Vec<Marker>,
    /// Vertical markers (events).
    pub vlines: Vec<Marker>,
    /// Shaded x intervals, drawn first.
    pub spans: Vec<Span>,
    /// Shown x range (default: the data's).
    pub x_range: Option<(f64, f64)>,
    /// Size the y axis to the samples at or after this x only (e.g. the evaluation
    /// window, so that a start-up transient does not flatten the rest); earlier samples
    /// beyond the axis are clipped, and the figure says so.
    pub y_fit_from: Option<f64>,
}

/// A figure: a title and panels stacked vertically.
#[derive(Clone, Debug, Default)]
pub struct Figure {
    /// Title.
    pub title: String,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
    /// One y range for every panel (panels compared with each other).
    pub shared_y: bool,
}

/// A figure the report will show, or the reason it cannot.
#[derive(Clone, Debug)]
pub struct Planned {
    /// Its number in the report: the paper's (`"12"`) or a supplementary one (`"12b"`,
    /// `"S1"`, `"H1"`).
    pub id: String,
    /// Base name of its files (`figures/STEM.png`, `figures/STEM.svg`).
    pub stem: String,
    /// Caption.
    pub caption: String,
    /// The data it shows (columns and variants).
    pub data: String,
    /// The figure, or why it is not available.
    pub figure: Result<Figure, String>,
}
