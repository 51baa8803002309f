//! `report.md` and `report.html`: the scenario, the metrics table of `summary.json`, the
//! figures with a table from figure number to file, and what could not be drawn.
//! The HTML is self-contained (figures as PNG data URIs, the font as a data URI) and
//! XHTML-compatible (well-formed XML).

use std::fmt::Write as _;

use base64::Engine as _;
use serde_json::Value;

use crate::folder::RunFolder;

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
}

/// Formats a metric value compactly (4 significant digits, lists joined).
pub fn fmt_value(v: &Value) -> String {
    match v {
        Value::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) => i.to_string(),
            (None, Some(0.0)) => "0".into(),
            (None, Some(x)) if (1e-3..1e5).contains(&x.abs()) => {
                let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
                format!("{x:.digits$}")
            }
            (None, Some(x)) => format!("{x:.3e}"),
            _ => n.to_string(),
        },
        Value::Array(a) => a.iter().map(fmt_value).collect::<Vec<_>>().join(", "),
        Value::Object(o) => o
            .iter()
            .map(|(k, v)| format!("{k}: {}", fmt_value(v)))
            .collect::<Vec<_>>()
            .join(", "),
        Value::Null => "-".into(),
        Value::String(s) => s.clone(),
        Value::Bool(b) => b.to_string(),
    }
}

/// Metric names in first-seen order over the variants.
fn metric_names(folder: &RunFolder) -> Vec<&str> {
    let mut keys: Vec<&str> = Vec::new();
    for v in &folder.variants {
        for k in v.metrics.keys() {
            if !keys.contains(&k.as_str()) {
                keys.push(k);
            }
        }
    }
    keys
}

fn md_escape(s: &str) -> String {
    s.replace('|', "\\|")
}

/// The Markdown report.
pub fn markdown(folder: &RunFolder, entries: &[Entry<'_>], recording: Option<&str>) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Scenario `{}`\n", folder.scenario);
    if let Some(d) = folder.description() {
        let _ = writeln!(out, "{d}\n");
    }
    let _ = writeln!(out, "Joints: {}\n", folder.joints.join(", "));
    let _ = writeln!(out, "## Metrics\n\nFrom `summary.json`; metrics are defined in docs/outputs.md. Lists are per joint, in the order above.\n");
    let _ = writeln!(
        out,
        "| metric | {} |",
        folder
            .variants
            .iter()
            .map(|v| format!("`{}`", v.name))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(out, "|---|{}", "---|".repeat(folder.variants.len()));
    for k in metric_names(folder) {
        let cells: Vec<String> = folder
            .variants
            .iter()
            .map(|v| v.metrics.get(k).map(fmt_value).unwrap_or_default())
            .map(|c| md_escape(&c))
            .collect();
        let _ = writeln!(out, "| {k} | {} |", cells.join(" | "));
    }
    let _ = writeln!(
        out,
        "\n## Figures\n\n| figure | paper caption | data | file |\n|---|---|---|---|"
    );
    for e in entries {
        let file = match (e.stem, e.missing) {
            (Some(s), _) => format!("[figures/{s}.png](figures/{s}.png), [svg](figures/{s}.svg)"),
            (None, Some(m)) => format!("not available: {}", md_escape(m)),
            _ => String::new(),
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} |",
            e.id,
            md_escape(e.caption),
            md_escape(e.data),
            file
        );
    }
    for e in entries {
        if let Some(s) = e.stem {
            let _ = writeln!(
                out,
                "\n### Fig. {}\n\n{}\n\n![Fig. {}](figures/{s}.png)",
                e.id, e.caption, e.id
            );
        }
    }
    let _ = writeln!(out, "\n## Files\n");
    let _ = writeln!(out, "- `summary.json`: the metrics above; `scenario.toml`: the scenario as run (without `--set` overrides).");
    for v in &folder.variants {
        let _ = writeln!(
            out,
            "- `{}.csv`: the time series of variant `{}` (columns in docs/outputs.md).",
            v.name, v.name
        );
    }
    if let Some(r) = recording {
        let _ = writeln!(
            out,
            "- `recording.mcap`: {r} Open it in Foxglove (Open local file)."
        );
    }
    let _ = writeln!(
        out,
        "- `report.html`: this report as one self-contained page."
    );
    let _ = writeln!(
        out,
        "\nRegenerate the figures, this report and the recording with `admittance report DIR`, DIR being this folder."
    );
    out
}

/// Escapes text for XML/HTML content and attributes.
pub fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Turns `` `code` `` spans into `<code>` elements (escaping the rest).
fn inline(s: &str) -> String {
    let mut out = String::new();
    for (k, part) in s.split('`').enumerate() {
        if k % 2 == 1 {
            let _ = write!(out, "<code>{}</code>", xml_escape(part));
        } else {
            out.push_str(&xml_escape(part));
        }
    }
    out
}

const CSS: &str = "body{font-family:FONT,sans-serif;max-width:1060px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}\
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}th,td{border:1px solid #ccc;padding:0.25em 0.5em;text-align:left;vertical-align:top}\
th{background:#f2f2f2}code{font-family:FONT,monospace;background:#f4f4f4;padding:0 0.2em}\
figure{margin:2em 0}figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:0.95em;margin-top:0.4em}\
.missing{color:#8a4b00}";

/// The self-contained HTML report.
pub fn html(folder: &RunFolder, entries: &[Entry<'_>], recording: Option<&str>) -> String {
    let b64 = &base64::engine::general_purpose::STANDARD;
    let css = CSS.replace("FONT", &format!("\"{}\"", crate::plot::FONT_FAMILY));
    let mut out = String::new();
    let title = format!("Scenario {}", folder.scenario);
    let _ = write!(
        out,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n<title>{}</title>\n<style>{}{}</style>\n</head>\n<body>\n",
        xml_escape(&title),
        crate::plot::font_face_css(),
        css
    );
    let _ = writeln!(
        out,
        "<h1>Scenario <code>{}</code></h1>",
        xml_escape(&folder.scenario)
    );
    if let Some(d) = folder.description() {
        let _ = writeln!(out, "<p>{}</p>", inline(d));
    }
    let _ = writeln!(
        out,
        "<p>Joints: {}</p>",
        xml_escape(&folder.joints.join(", "))
    );
    let _ = writeln!(out, "<h2>Metrics</h2>\n<p>From <code>summary.json</code>; metrics are defined in docs/outputs.md. Lists are per joint, in the order above.</p>");
    let _ = write!(out, "<table>\n<tr><th>metric</th>");
    for v in &folder.variants {
        let _ = write!(out, "<th><code>{}</code></th>", xml_escape(&v.name));
    }
    let _ = writeln!(out, "</tr>");
    for k in metric_names(folder) {
        let _ = write!(out, "<tr><td>{}</td>", xml_escape(k));
        for v in &folder.variants {
            let cell = v.metrics.get(k).map(fmt_value).unwrap_or_default();
            let _ = write!(out, "<td>{}</td>", xml_escape(&cell));
        }
        let _ = writeln!(out, "</tr>");
    }
    let _ = writeln!(out, "</table>");
    let _ = writeln!(out, "<h2>Figures</h2>\n<table>\n<tr><th>figure</th><th>paper caption</th><th>data</th><th>file</th></tr>");
    for e in entries {
        let file = match (e.stem, e.missing) {
            (Some(s), _) => format!(
                "<a href=\"#fig-{}\">figures/{}.png</a>, figures/{}.svg",
                xml_escape(e.id),
                xml_escape(s),
                xml_escape(s)
            ),
            (None, Some(m)) => format!(
                "<span class=\"missing\">not available: {}</span>",
                inline(m)
            ),
            _ => String::new(),
        };
        let _ = writeln!(
            out,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            xml_escape(e.id),
            inline(e.caption),
            inline(e.data),
            file
        );
    }
    let _ = writeln!(out, "</table>");
    for e in entries {
        if let (Some(_), Some(png)) = (e.stem, e.png) {
            let _ = writeln!(
                out,
                "<figure id=\"fig-{id}\"><img alt=\"Fig. {id}\" src=\"data:image/png;base64,{}\"/><figcaption><b>Fig. {id}.</b> {}</figcaption></figure>",
                b64.encode(png),
                inline(e.caption),
                id = xml_escape(e.id)
            );
        }
    }
    let _ = writeln!(out, "<h2>Files</h2>\n<ul>");
    let _ = writeln!(out, "<li><code>summary.json</code>: the metrics above; <code>scenario.toml</code>: the scenario as run.</li>");
    for v in &folder.variants {
        let _ = writeln!(
            out,
            "<li><code>{0}.csv</code>: the time series of variant <code>{0}</code>.</li>",
            xml_escape(&v.name)
        );
    }
    if let Some(r) = recording {
        let _ = writeln!(
            out,
            "<li><code>recording.mcap</code>: {} Open it in Foxglove (Open local file).</li>",
            inline(r)
        );
    }
    let _ = writeln!(
        out,
        "</ul>\n<p>Regenerate with <code>admittance report DIR</code>, DIR being this folder.</p>\n</body>\n</html>"
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_values() {
        assert_eq!(fmt_value(&serde_json::json!(0.0017234)), "0.001723");
        assert_eq!(fmt_value(&serde_json::json!(12)), "12");
        assert_eq!(fmt_value(&serde_json::json!(2.5634)), "2.563");
        assert_eq!(fmt_value(&serde_json::json!(1.5e-7)), "1.500e-7");
        assert_eq!(fmt_value(&serde_json::json!([1, null])), "1, -");
        assert_eq!(fmt_value(&serde_json::json!({"f": 512})), "f: 512");
    }

    #[test]
    fn escapes_markup() {
        assert_eq!(xml_escape("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
        assert_eq!(inline("x `a<b` y"), "x <code>a&lt;b</code> y");
    }
}
