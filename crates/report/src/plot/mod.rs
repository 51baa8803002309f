//! Drawing a [`Figure`] to PNG and SVG with plotters, using the font embedded in this
//! crate (`fonts/DejaVuSans-subset.ttf`): the PNG's text is rasterised from it and the SVG
//! carries it as an `@font-face` data URI, so neither depends on the viewer's fonts.
//!
//! The axes, ticks and visible data are computed here ([`axes`]), not by plotters, so that
//! any data (huge, non-finite, constant, empty) give a figure in bounded time; the legend
//! sits below each chart ([`legend`]).

mod axes;
mod legend;

use axes::tick_label;
pub use axes::Note;

use std::sync::OnceLock;

use base64::Engine as _;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::figures::{Figure, Line, Panel};
use axes::Prepared;

/// The font family name the figures and the HTML report use for the embedded font.
pub const FONT_FAMILY: &str = "AdmittanceDejaVuSans";
/// The embedded font: DejaVu Sans reduced to ASCII, Greek and a few symbols
/// (`fonts/LICENSE-DejaVu.txt`; rebuilt by `scripts/subset_font.sh`).
pub static FONT_TTF: &[u8] = include_bytes!("../../fonts/DejaVuSans-subset.ttf");

/// Width of every figure (px).
pub const WIDTH: u32 = 1000;
const TITLE_HEIGHT: u32 = 44;
/// Height of a chart: its title, plot area and x labels (px).
const CHART_HEIGHT: u32 = 300;

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 92, 180),   // blue
    RGBColor(214, 39, 40),   // red
    RGBColor(44, 160, 44),   // green
    RGBColor(255, 127, 14),  // orange
    RGBColor(148, 103, 189), // purple
    RGBColor(90, 90, 90),    // grey
    RGBColor(140, 86, 75),   // brown
    RGBColor(23, 190, 207),  // cyan
];
/// Markers (bounds, events).
const MARKER_COLOR: RGBColor = RGBColor(60, 60, 60);
/// Shaded spans (contact windows).
const SPAN_COLOR: RGBColor = RGBColor(255, 214, 140);

/// How a line is stroked.
#[derive(Clone, Copy, Debug)]
struct Style {
    color: RGBColor,
    width: u32,
    dashed: bool,
}

impl Style {
    fn of(l: &Line) -> Self {
        Style {
            color: PALETTE[l.color % PALETTE.len()],
            width: if l.thin { 1 } else { 2 },
            dashed: l.dashed,
        }
    }
}

fn ink(style: Style, width: u32) -> ShapeStyle {
    ShapeStyle::from(&style.color).stroke_width(width)
}

fn font(size: f64) -> FontDesc<'static> {
    (FONT_FAMILY, size).into_font()
}

fn ensure_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            register_font(FONT_FAMILY, FontStyle::Normal, FONT_TTF)
                .map_err(|_| "the embedded font could not be read".to_string())
        })
        .clone()
}

/// An axis for plotters with our range and ticks: plotters' own tick search loops forever
/// on huge or degenerate ranges.
struct Ticked {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
}

impl Ticked {
    fn new(a: &axes::Axis) -> Self {
        Ticked {
            lo: a.lo,
            hi: a.hi,
            ticks: a.ticks.clone(),
        }
    }
}

impl plotters::coord::ranged1d::Ranged for Ticked {
    type FormatOption = plotters::coord::ranged1d::NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let share = ((value - self.lo) / (self.hi - self.lo)).clamp(-1.0, 2.0);
        let share = if share.is_finite() { share } else { 0.0 };
        limit.0 + (f64::from(limit.1 - limit.0) * share + 1e-3).floor() as i32
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

impl plotters::coord::ranged1d::ValueFormatter<f64> for Ticked {
    fn format(value: &f64) -> String {
        format!("{value}")
    }
}

/// A figure drawn: PNG, SVG, and what it could not show.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The PNG (8-bit RGB).
    pub png: Vec<u8>,
    /// The SVG, with the font embedded.
    pub svg: String,
    /// Notes on data left out or clipped, prefixed by the panel's title when the figure
    /// has several panels.
    pub notes: Vec<Note>,
}

/// A panel with its prepared data and legend.
struct Laid<'a> {
    panel: &'a Panel,
    prepared: Prepared,
    legend: Vec<legend::Entry>,
    height: u32,
}

fn lay_out(fig: &Figure) -> Vec<Laid<'_>> {
    axes::prepare(&fig.panels, fig.shared_y)
        .into_iter()
        .zip(&fig.panels)
        .map(|(prepared, panel)| {
            let legend = legend::entries(panel);
            let rows = legend::rows(&legend, &prepared.notes, WIDTH);
            let strip = if rows == 0 {
                0
            } else {
                rows * legend::ROW + 10
            };
            Laid {
                panel,
                prepared,
                legend,
                height: CHART_HEIGHT + strip,
            }
        })
        .collect()
}

fn draw_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    d: &Prepared,
) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let (x, y) = (&d.x, &d.y);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, font(16.0))
        .margin(12)
        .margin_right(24)
        .x_label_area_size(44)
        .y_label_area_size(legend::LEFT as u32 - 12)
        .build_cartesian_2d(Ticked::new(x), Ticked::new(y))
        .map_err(err)?;
    let (xs, ys) = (x.step, y.step);
    let x_fmt = move |v: &f64| tick_label(*v, xs);
    let y_fmt = move |v: &f64| tick_label(*v, ys);
    chart
        .configure_mesh()
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .label_style(font(14.0))
        .axis_desc_style(font(15.0))
        .bold_line_style(RGBColor(225, 225, 225))
        .draw()
        .map_err(err)?;
    let spans = d
        .spans
        .iter()
        .flatten()
        .map(|&(a, b)| Rectangle::new([(a, y.lo), (b, y.hi)], SPAN_COLOR.mix(0.5).filled()));
    chart.draw_series(spans).map_err(err)?;
    for polygons in &d.bands {
        let fill = PALETTE[5].mix(0.3).filled();
        chart
            .draw_series(polygons.iter().map(|poly| Polygon::new(poly.clone(), fill)))
            .map_err(err)?;
    }
    for (l, pieces) in p.lines.iter().zip(&d.lines) {
        let style = Style::of(l);
        let shape = ink(style, style.width);
        for piece in pieces {
            if style.dashed {
                chart
                    .draw_series(DashedLineSeries::new(piece.clone(), 8, 5, shape))
                    .map_err(err)?;
            } else {
                chart
                    .draw_series(LineSeries::new(piece.clone(), shape))
                    .map_err(err)?;
            }
        }
    }
    let marker = ShapeStyle::from(&MARKER_COLOR).stroke_width(1);
    let hl = d
        .hlines
        .iter()
        .flatten()
        .map(|&v| vec![(x.lo, v), (x.hi, v)]);
    let vl = d
        .vlines
        .iter()
        .flatten()
        .map(|&v| vec![(v, y.lo), (v, y.hi)]);
    for path in hl.chain(vl) {
        chart
            .draw_series(DashedLineSeries::new(path, 8, 5, marker))
            .map_err(err)?;
    }
    Ok(())
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    fig: &Figure,
    laid: &[Laid<'_>],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let (title, body) = root.split_vertically(TITLE_HEIGHT);
    title
        .draw_text(
            &fig.title,
            &font(20.0).color(&BLACK),
            (16, (TITLE_HEIGHT as i32 - 20) / 2),
        )
        .map_err(|e| e.to_string())?;
    let mut rest = body;
    for l in laid {
        let (area, below) = rest.split_vertically(l.height);
        let (chart, strip) = area.split_vertically(CHART_HEIGHT);
        draw_chart(&chart, l.panel, &l.prepared)?;
        legend::draw(&strip, &l.legend, &l.prepared.notes)?;
        rest = below;
    }
    root.present().map_err(|e| e.to_string())
}

/// The pixel size of a laid-out figure.
fn size(laid: &[Laid<'_>]) -> (u32, u32) {
    let panels: u32 = laid.iter().map(|l| l.height).sum();
    (WIDTH, TITLE_HEIGHT + panels.max(CHART_HEIGHT))
}

fn encode_png(pixels: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Default);
    let mut writer = enc.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(pixels).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(out)
}

/// The `@font-face` rule that declares the embedded font (CSS).
pub fn font_face_css() -> String {
    format!(
        "@font-face{{font-family:\"{FONT_FAMILY}\";src:url(data:font/ttf;base64,{}) format(\"truetype\");}}",
        base64::engine::general_purpose::STANDARD.encode(FONT_TTF)
    )
}

/// Draws the figure as PNG and as SVG (with the embedded font declared inside it).
pub fn render(fig: &Figure) -> Result<Rendered, String> {
    ensure_font()?;
    let laid = lay_out(fig);
    let (w, h) = size(&laid);
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    draw(
        BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area(),
        fig,
        &laid,
    )?;
    let png = encode_png(&pixels, (w, h))?;
    let mut svg = String::new();
    draw(
        SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area(),
        fig,
        &laid,
    )?;
    // Declare the font right after the opening <svg ...> tag.
    let open = svg
        .find("<svg")
        .and_then(|s| svg[s..].find('>').map(|e| s + e + 1))
        .ok_or("plotters wrote no <svg> element")?;
    svg.insert_str(
        open,
        &format!("\n<defs><style>{}</style></defs>", font_face_css()),
    );
    let several = laid.len() > 1;
    let notes = laid
        .iter()
        .flat_map(|l| {
            l.prepared.notes.iter().map(move |n| Note {
                text: if several {
                    format!("{}: {}", l.panel.title, n.text)
                } else {
                    n.text.clone()
                },
                left_out: n.left_out,
            })
        })
        .collect();
    Ok(Rendered { png, svg, notes })
}
