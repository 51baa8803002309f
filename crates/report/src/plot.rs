//! Drawing a [`Figure`] to PNG and SVG with plotters, using the font embedded in this
//! crate (`fonts/DejaVuSans-subset.ttf`): the PNG's text is rasterised from it and the SVG
//! carries it as an `@font-face` data URI, so neither depends on the viewer's fonts.

use std::sync::OnceLock;

use base64::Engine as _;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::figures::{Figure, Panel};

/// The font family name the figures and the HTML report use for the embedded font.
pub const FONT_FAMILY: &str = "AdmittanceDejaVuSans";
/// The embedded font: DejaVu Sans reduced to ASCII, Greek and a few symbols
/// (`fonts/LICENSE-DejaVu.txt`; rebuilt by `scripts/subset_font.sh`).
pub static FONT_TTF: &[u8] = include_bytes!("../fonts/DejaVuSans-subset.ttf");

/// Width of every figure (px).
pub const WIDTH: u32 = 1000;
const TITLE_HEIGHT: u32 = 44;
const PANEL_HEIGHT: u32 = 330;
/// Most points drawn per line: longer lines are reduced to the min and max of each of
/// `MAX_POINTS / 2` time buckets, which keeps every peak.
pub const MAX_POINTS: usize = 2400;

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

fn ensure_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            register_font(FONT_FAMILY, FontStyle::Normal, FONT_TTF)
                .map_err(|_| "the embedded font could not be read".to_string())
        })
        .clone()
}

/// Space of the caption, axis labels and margins of a panel (px).
const PANEL_CHROME: u32 = 110;
/// Height of one legend entry (px).
const LEGEND_ENTRY: u32 = 21;

fn legend_entries(p: &Panel) -> usize {
    p.lines.iter().filter(|l| !l.label.is_empty()).count()
        + p.hlines
            .iter()
            .chain(&p.vlines)
            .filter(|m| !m.label.is_empty())
            .count()
}

/// Height of a panel: taller when its legend is long, so the legend leaves the data room.
fn panel_height(p: &Panel) -> u32 {
    PANEL_HEIGHT + LEGEND_ENTRY * (legend_entries(p) as u32).saturating_sub(3)
}

/// The pixel size of a figure.
pub fn size(fig: &Figure) -> (u32, u32) {
    let panels: u32 = fig.panels.iter().map(panel_height).sum();
    (WIDTH, TITLE_HEIGHT + panels.max(PANEL_HEIGHT))
}

/// Indices of the points of `x` to draw within `range`: all of them when few, else the
/// first, the last and the minimum and maximum of `y` in each bucket, in order.
pub fn decimate(x: &[f64], y: &[f64], range: (f64, f64), max_points: usize) -> Vec<usize> {
    let n = x.len().min(y.len());
    // One point either side of the range so that lines reach the axes.
    let start = x[..n].partition_point(|&v| v < range.0).saturating_sub(1);
    let end = (x[..n].partition_point(|&v| v <= range.1) + 1).min(n);
    if start >= end {
        return Vec::new();
    }
    let count = end - start;
    if count <= max_points {
        return (start..end).collect();
    }
    let buckets = (max_points / 2).max(1);
    let mut out = Vec::with_capacity(buckets * 2 + 2);
    for b in 0..buckets {
        let lo = start + count * b / buckets;
        let hi = (start + count * (b + 1) / buckets).max(lo + 1);
        let (mut imin, mut imax) = (lo, lo);
        for k in lo..hi {
            if y[k] < y[imin] || !y[imin].is_finite() {
                imin = k;
            }
            if y[k] > y[imax] || !y[imax].is_finite() {
                imax = k;
            }
        }
        let (a, b2) = if imin <= imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        out.push(a);
        if b2 != a {
            out.push(b2);
        }
    }
    out
}

fn x_range(p: &Panel) -> (f64, f64) {
    if let Some(r) = p.x_range {
        return r;
    }
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for l in &p.lines {
        for &v in l.x.iter().filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if lo.is_finite() && hi > lo {
        (lo, hi)
    } else if lo.is_finite() {
        (lo - 0.5, lo + 0.5)
    } else {
        (0.0, 1.0)
    }
}

fn y_range(p: &Panel, xr: (f64, f64), picks: &[Vec<usize>]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for (l, idx) in p.lines.iter().zip(picks) {
        for &k in idx {
            let (x, y) = (l.x[k], l.y[k]);
            if y.is_finite() && x >= xr.0 && x <= xr.1 {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
    }
    for m in &p.hlines {
        if m.at.is_finite() {
            lo = lo.min(m.at);
            hi = hi.max(m.at);
        }
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    let pad = if span > 1e-12 * (1.0 + lo.abs().max(hi.abs())) {
        0.08 * span
    } else {
        0.5 * (1e-3 + 0.05 * lo.abs())
    };
    // Room at the top for the legend: about 20 px per entry of a 260 px plot area.
    let entries = legend_entries(p) as u32;
    let plot_px = (panel_height(p) - PANEL_CHROME) as f64;
    let top = if entries == 0 {
        0.0
    } else {
        ((LEGEND_ENTRY * entries + 16) as f64 / plot_px).min(0.75)
    };
    let total = (span + 2.0 * pad) / (1.0 - top);
    (lo - pad, lo - pad + total)
}

/// Decimals for tick labels `ticks` apart over a span: enough to tell them apart.
fn tick_decimals(span: f64, ticks: usize) -> usize {
    let step = span / ticks.max(1) as f64;
    if !(step.is_finite() && step > 0.0) {
        return 1;
    }
    (-(step.log10().floor())).clamp(0.0, 8.0) as usize
}

/// A tick label: fixed decimals, no negative zero.
pub fn tick_label(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

fn font(size: f64) -> FontDesc<'static> {
    (FONT_FAMILY, size).into_font()
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<(), String> {
    let xr = x_range(p);
    let picks: Vec<Vec<usize>> = p
        .lines
        .iter()
        .map(|l| decimate(&l.x, &l.y, xr, MAX_POINTS))
        .collect();
    let yr = y_range(p, xr, &picks);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, font(17.0))
        .margin(12)
        .margin_right(24)
        .x_label_area_size(44)
        .y_label_area_size(78)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(|e| e.to_string())?;
    let (xd, yd) = (
        tick_decimals(xr.1 - xr.0, 10),
        tick_decimals(yr.1 - yr.0, 7),
    );
    let x_fmt = move |v: &f64| tick_label(*v, xd);
    let y_fmt = move |v: &f64| tick_label(*v, yd);
    chart
        .configure_mesh()
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .label_style(font(14.0))
        .axis_desc_style(font(15.0))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(210, 210, 210))
        .x_labels(10)
        .y_labels(7)
        .max_light_lines(1)
        .draw()
        .map_err(|e| e.to_string())?;
    let mut labelled = false;
    for (l, idx) in p.lines.iter().zip(&picks) {
        let color = PALETTE[l.color % PALETTE.len()];
        let style = ShapeStyle::from(&color).stroke_width(if l.thin { 1 } else { 2 });
        let points: Vec<(f64, f64)> = idx
            .iter()
            .map(|&k| (l.x[k], l.y[k]))
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        let series = chart
            .draw_series(LineSeries::new(points, style))
            .map_err(|e| e.to_string())?;
        if !l.label.is_empty() {
            labelled = true;
            series.label(l.label.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 22, y)], style.stroke_width(3))
            });
        }
    }
    let marker_color = RGBColor(60, 60, 60);
    for m in &p.hlines {
        let style = ShapeStyle::from(&marker_color).stroke_width(1);
        let s = chart
            .draw_series(DashedLineSeries::new(
                vec![(xr.0, m.at), (xr.1, m.at)],
                8,
                5,
                style,
            ))
            .map_err(|e| e.to_string())?;
        if !m.label.is_empty() {
            labelled = true;
            s.label(m.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 22, y)], style));
        }
    }
    for m in &p.vlines {
        let style = ShapeStyle::from(&PALETTE[3]).stroke_width(1);
        let s = chart
            .draw_series(DashedLineSeries::new(
                vec![(m.at, yr.0), (m.at, yr.1)],
                8,
                5,
                style,
            ))
            .map_err(|e| e.to_string())?;
        if !m.label.is_empty() {
            labelled = true;
            s.label(m.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 22, y)], style));
        }
    }
    if labelled {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.88))
            .border_style(RGBColor(170, 170, 170))
            .label_font(font(14.0))
            .draw()
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), String> {
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
    for p in &fig.panels {
        let (area, below) = rest.split_vertically(panel_height(p));
        draw_panel(&area, p)?;
        rest = below;
    }
    root.present().map_err(|e| e.to_string())
}

/// Draws the figure and encodes it as PNG (8-bit RGB).
pub fn render_png(fig: &Figure) -> Result<Vec<u8>, String> {
    ensure_font()?;
    let (w, h) = size(fig);
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        draw(root, fig)?;
    }
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Default);
        let mut writer = enc.write_header().map_err(|e| e.to_string())?;
        writer
            .write_image_data(&pixels)
            .map_err(|e| e.to_string())?;
    }
    Ok(out)
}

/// The `@font-face` rule that declares the embedded font (CSS).
pub fn font_face_css() -> String {
    format!(
        "@font-face{{font-family:\"{FONT_FAMILY}\";src:url(data:font/ttf;base64,{}) format(\"truetype\");}}",
        base64::engine::general_purpose::STANDARD.encode(FONT_TTF)
    )
}

/// Draws the figure as SVG text with the embedded font declared inside it.
pub fn render_svg(fig: &Figure) -> Result<String, String> {
    ensure_font()?;
    let size = size(fig);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw(root, fig)?;
    }
    // Declare the font right after the opening <svg ...> tag.
    let open = svg
        .find("<svg")
        .and_then(|s| svg[s..].find('>').map(|e| s + e + 1))
        .ok_or("plotters wrote no <svg> element")?;
    svg.insert_str(
        open,
        &format!("\n<defs><style>{}</style></defs>", font_face_css()),
    );
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(-0.0001, 1), "0.0");
        assert_eq!(tick_label(-0.25, 2), "-0.25");
        assert_eq!(tick_decimals(300.0, 7), 0);
        assert_eq!(tick_decimals(2.0, 7), 1);
        assert_eq!(tick_decimals(0.03, 7), 3);
    }

    #[test]
    fn decimation_keeps_extremes_and_order() {
        let x: Vec<f64> = (0..100_000).map(|k| k as f64 * 1e-3).collect();
        let mut y: Vec<f64> = x.iter().map(|t| (t * 3.0).sin()).collect();
        y[54_321] = 7.0;
        let idx = decimate(&x, &y, (0.0, 100.0), 1000);
        assert!(idx.len() <= 1002 && idx.len() > 500, "{}", idx.len());
        assert!(idx.windows(2).all(|w| w[0] < w[1]));
        assert!(idx.contains(&54_321));
        let short = decimate(&x[..10], &y[..10], (0.002, 0.005), 1000);
        assert_eq!(short, vec![1, 2, 3, 4, 5, 6]);
    }
}
