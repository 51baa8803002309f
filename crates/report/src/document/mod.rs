//! `report.md` and `report.html`: the experiment's claim with this run's headline numbers
//! beside the paper's and any warning ([`opening`]), the metrics tables ([`metrics`]), the
//! figures with a table from figure number to file, and the files of the folder. Both
//! are rendered from one list of blocks ([`blocks`]); the HTML is self-contained (figures
//! as PNG data URIs, the font as a data URI) and XHTML-compatible (well-formed XML).

mod blocks;
mod metrics;
mod opening;
mod warnings;

use admittance_runfolder::files;
use blocks::Block;

use crate::folder::RunFolder;
use crate::plot::Note;

/// The line said when the folder has no `settings.json`.
fn settings_note(folder: &RunFolder) -> Option<String> {
    if folder.settings.is_some() {
        return None;
    }
    let from = if folder.scenario_toml.is_some() {
        "were read from scenario.toml by the plant's rules"
    } else {
        "are not in this folder (no scenario.toml either): the figures show no deadzone band, bound or window"
    };
    Some(format!(
        "this run folder has no `{}` (it was written by an earlier build, or by a plant that does not write it): the deadzone bands, windows and bounds drawn {from}; rerun the scenario to record what the plant applied",
        files::SETTINGS
    ))
}

/// A figure as it appears in the report: its plan and, when drawn, its PNG.
pub struct Entry<'a> {
    /// Number in the report (`"7"`, `"12b"`, `"S1"`).
    pub id: &'a str,
    /// Caption.
    pub caption: &'a str,
    /// The data shown.
    pub data: &'a str,
    /// File stem under `figures/` when drawn.
    pub stem: Option<&'a str>,
    /// The PNG bytes when drawn.
    pub png: Option<&'a [u8]>,
    /// Why it was not drawn.
    pub missing: Option<&'a str>,
    /// What the drawn figure could not show (samples left out, clipped).
    pub notes: &'a [Note],
}

fn figures_section<'a>(entries: &'a [Entry<'a>], out: &mut Vec<Block<'a>>) {
    out.push(Block::Heading("Figures".into()));
    let rows = entries
        .iter()
        .map(|e| {
            let file = match (e.stem, e.missing) {
                (Some(s), _) => format!("`figures/{s}.png`, `.svg`"),
                (None, Some(m)) => format!("not available: {m}"),
                _ => String::new(),
            };
            vec![
                e.id.to_string(),
                e.caption.to_string(),
                e.data.to_string(),
                file,
            ]
        })
        .collect();
    out.push(Block::Table {
        header: ["figure", "caption", "data", "file"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        rows,
    });
    for e in entries {
        if let (Some(stem), Some(png)) = (e.stem, e.png) {
            out.push(Block::Figure {
                id: e.id,
                caption: e.caption,
                stem,
                png,
                notes: e.notes,
            });
        }
    }
}

fn files_section(folder: &RunFolder, recording: Option<&str>) -> Vec<Block<'static>> {
    let mut items = vec![format!(
        "`{}`: the metrics above; `{}`: the scenario as run (every `--set` override applied).",
        files::SUMMARY,
        files::SCENARIO
    )];
    for v in &folder.variants {
        items.push(format!(
            "`{}`: the time series of variant `{}` (columns in docs/outputs.md).",
            files::series(&v.name),
            v.name
        ));
    }
    if let Some(r) = recording {
        items.push(format!(
            "`{}`: {r} Open it in Foxglove (Open local file).",
            files::RECORDING
        ));
    }
    items.push(format!(
        "`{}`: this report as one self-contained page.",
        files::REPORT_HTML
    ));
    vec![
        Block::Heading("Files".into()),
        Block::List(items),
        Block::Paragraph(
            "Regenerate the figures, this report and the recording with `admittance report DIR`, DIR being this folder.".into(),
        ),
    ]
}

fn build<'a>(
    folder: &RunFolder,
    entries: &'a [Entry<'a>],
    recording: Option<&str>,
) -> Vec<Block<'a>> {
    let notes: Vec<(String, String)> = entries
        .iter()
        .flat_map(|e| {
            e.notes
                .iter()
                .filter(|n| n.left_out)
                .map(|n| (e.id.to_string(), n.text.clone()))
        })
        .collect();
    let mut all_warnings = warnings::warnings(folder, &notes);
    all_warnings.extend(settings_note(folder));
    let mut out = opening::blocks(folder, all_warnings);
    out.push(Block::Paragraph(format!(
        "Joints: {}.",
        folder.joints.join(", ")
    )));
    out.extend(metrics::section(folder));
    figures_section(entries, &mut out);
    out.extend(files_section(folder, recording));
    out
}

/// The Markdown report.
pub fn markdown(folder: &RunFolder, entries: &[Entry<'_>], recording: Option<&str>) -> String {
    blocks::markdown(&build(folder, entries, recording))
}

/// The self-contained HTML report.
pub fn html(folder: &RunFolder, entries: &[Entry<'_>], recording: Option<&str>) -> String {
    blocks::html(
        &opening::title(folder).replace('`', ""),
        &build(folder, entries, recording),
    )
}

#[cfg(test)]
mod tests;
