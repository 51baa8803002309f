//! The legend of a panel, drawn in a strip below its chart (so that it never hides data
//! nor stretches the y axis): entries in rows, each with a sample drawn as the data are
//! (dashed lines dashed, bands and spans as filled boxes), then the panel's notes.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{font, ink, Style, MARKER_COLOR, PALETTE, SPAN_COLOR};
use crate::figures::Panel;

/// Height of a legend row (px).
pub const ROW: u32 = 21;
/// Width of an entry's sample (px).
const SAMPLE: i32 = 30;
/// Space between entries (px).
const GAP: i32 = 22;
/// Left edge of the legend (px), aligned with the plot area.
pub const LEFT: i32 = 90;
/// Font size of the legend.
const SIZE: f64 = 14.0;

/// What an entry's sample looks like.
#[derive(Clone, Copy, Debug)]
pub enum Sample {
    /// A line of the given style.
    Line(Style),
    /// A filled band or span.
    Fill(RGBColor, f64),
}

/// One legend entry.
#[derive(Clone, Debug)]
pub struct Entry {
    /// What the sample looks like.
    pub sample: Sample,
    /// The text.
    pub label: String,
}

/// The legend entries of a panel, in drawing order: spans, bands, lines, markers.
pub fn entries(p: &Panel) -> Vec<Entry> {
    let mut out = Vec::new();
    for s in p.spans.iter().filter(|s| !s.label.is_empty()) {
        out.push(Entry {
            sample: Sample::Fill(SPAN_COLOR, 0.5),
            label: s.label.clone(),
        });
    }
    for b in p.bands.iter().filter(|b| !b.label.is_empty()) {
        out.push(Entry {
            sample: Sample::Fill(PALETTE[5], 0.3),
            label: b.label.clone(),
        });
    }
    for l in p.lines.iter().filter(|l| !l.label.is_empty()) {
        out.push(Entry {
            sample: Sample::Line(Style::of(l)),
            label: l.label.clone(),
        });
    }
    let marker = Style {
        color: MARKER_COLOR,
        width: 1,
        dashed: true,
    };
    for m in p
        .hlines
        .iter()
        .chain(&p.vlines)
        .filter(|m| !m.label.is_empty())
    {
        out.push(Entry {
            sample: Sample::Line(marker),
            label: m.label.clone(),
        });
    }
    out
}

fn text_width(text: &str) -> i32 {
    font(SIZE)
        .box_size(text)
        .map_or(8 * text.len() as i32, |(w, _)| w as i32)
}

/// Each entry's position (row, x) in a strip `width` px wide.
pub fn layout(entries: &[Entry], width: u32) -> Vec<(u32, i32)> {
    let right = width as i32 - 20;
    let mut row = 0;
    let mut x = LEFT;
    entries
        .iter()
        .map(|e| {
            let w = SAMPLE + 6 + text_width(&e.label);
            if x > LEFT && x + w > right {
                row += 1;
                x = LEFT;
            }
            let at = (row, x);
            x += w + GAP;
            at
        })
        .collect()
}

/// Rows the legend of `entries` and `notes` needs in a strip `width` px wide.
pub fn rows(entries: &[Entry], notes: &[super::Note], width: u32) -> u32 {
    let lines = layout(entries, width).last().map_or(0, |(r, _)| r + 1);
    lines + notes.len() as u32
}

fn draw_sample<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    sample: Sample,
    x: i32,
    y: i32,
) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    match sample {
        Sample::Line(style) => {
            let path = vec![(x, y), (x + SAMPLE, y)];
            let shape = ink(style, style.width.max(2));
            if style.dashed {
                area.draw(&plotters::element::DashedPathElement::new(
                    path, 6, 4, shape,
                ))
                .map_err(err)
            } else {
                area.draw(&PathElement::new(path, shape)).map_err(err)
            }
        }
        Sample::Fill(color, alpha) => area
            .draw(&Rectangle::new(
                [(x, y - 6), (x + SAMPLE, y + 6)],
                color.mix(alpha).filled(),
            ))
            .map_err(err),
    }
}

/// Draws the legend and the notes into `area` (the strip below a chart).
pub fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    notes: &[super::Note],
) -> Result<(), String> {
    let width = area.dim_in_pixel().0;
    let places = layout(entries, width);
    let style = font(SIZE).color(&BLACK);
    for (e, &(row, x)) in entries.iter().zip(&places) {
        let y = (row * ROW) as i32 + ROW as i32 / 2;
        draw_sample(area, e.sample, x, y)?;
        area.draw(&Text::new(
            e.label.clone(),
            (x + SAMPLE + 6, y - 8),
            style.clone(),
        ))
        .map_err(|e| e.to_string())?;
    }
    let first = places.last().map_or(0, |(r, _)| r + 1);
    let note_style = font(SIZE).color(&RGBColor(150, 60, 0));
    for (k, n) in notes.iter().enumerate() {
        let y = ((first + k as u32) * ROW) as i32 + 2;
        area.draw(&Text::new(
            format!("Note: {}", n.text),
            (LEFT, y),
            note_style.clone(),
        ))
        .map_err(|e| e.to_string())?;
    }
    Ok(())
}
