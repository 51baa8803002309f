//! The report as a list of blocks (headings, paragraphs, tables, figures), rendered once
//! as Markdown and once as self-contained HTML, so that both say the same.
//!
//! Text in blocks uses two inline marks: `` `code` `` and `**bold**`.

use std::fmt::Write as _;

use base64::Engine as _;

/// A block of the report.
pub enum Block<'a> {
    /// The page title (`#`).
    Title(String),
    /// A section heading (`##`).
    Heading(String),
    /// A sub-section heading (`###`).
    Subheading(String),
    /// A paragraph.
    Paragraph(String),
    /// Warnings, highlighted.
    Warnings(Vec<String>),
    /// A bulleted list.
    List(Vec<String>),
    /// A table: header and rows of cells.
    Table {
        /// Header cells.
        header: Vec<String>,
        /// Rows.
        rows: Vec<Vec<String>>,
    },
    /// A drawn figure.
    Figure {
        /// Its number.
        id: &'a str,
        /// Caption.
        caption: &'a str,
        /// File stem under `figures/`.
        stem: &'a str,
        /// The PNG.
        png: &'a [u8],
        /// What the figure could not show.
        notes: &'a [crate::plot::Note],
    },
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

/// Inline marks to HTML: `` `code` `` to `<code>`, `**bold**` to `<b>` (outside code).
pub fn inline(s: &str) -> String {
    let mut out = String::new();
    for (k, part) in s.split('`').enumerate() {
        if k % 2 == 1 {
            let _ = write!(out, "<code>{}</code>", xml_escape(part));
            continue;
        }
        let pieces: Vec<&str> = part.split("**").collect();
        for (b, piece) in pieces.iter().enumerate() {
            if b % 2 == 0 {
                out.push_str(&xml_escape(piece));
            } else if b + 1 < pieces.len() {
                let _ = write!(out, "<b>{}</b>", xml_escape(piece));
            } else {
                // An unmatched `**`: kept as typed.
                let _ = write!(out, "**{}", xml_escape(piece));
            }
        }
    }
    out
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// The blocks as Markdown.
pub fn markdown(blocks: &[Block<'_>]) -> String {
    let mut out = String::new();
    for b in blocks {
        match b {
            Block::Title(t) => {
                let _ = writeln!(out, "# {t}\n");
            }
            Block::Heading(t) => {
                let _ = writeln!(out, "## {t}\n");
            }
            Block::Subheading(t) => {
                let _ = writeln!(out, "### {t}\n");
            }
            Block::Paragraph(t) => {
                let _ = writeln!(out, "{t}\n");
            }
            Block::Warnings(items) => {
                for w in items {
                    let _ = writeln!(out, "> **Warning:** {w}");
                }
                out.push('\n');
            }
            Block::List(items) => {
                for i in items {
                    let _ = writeln!(out, "- {i}");
                }
                out.push('\n');
            }
            Block::Table { header, rows } => {
                let cells = |r: &[String]| r.iter().map(|c| md_cell(c)).collect::<Vec<_>>();
                let _ = writeln!(out, "| {} |", cells(header).join(" | "));
                let _ = writeln!(out, "|{}", "---|".repeat(header.len()));
                for r in rows {
                    let _ = writeln!(out, "| {} |", cells(r).join(" | "));
                }
                out.push('\n');
            }
            Block::Figure {
                id,
                caption,
                stem,
                notes,
                ..
            } => {
                let _ = writeln!(
                    out,
                    "### Fig. {id}\n\n{caption}\n\n![Fig. {id}](figures/{stem}.png)\n"
                );
                for n in notes.iter() {
                    let _ = writeln!(out, "Note: {}\n", n.text);
                }
            }
        }
    }
    out
}

const CSS: &str = "body{font-family:FONT,sans-serif;max-width:1060px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}\
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}th,td{border:1px solid #ccc;padding:0.25em 0.5em;text-align:left;vertical-align:top}\
th{background:#f2f2f2}td.num{text-align:right;font-variant-numeric:tabular-nums}code{font-family:FONT,monospace;background:#f4f4f4;padding:0 0.2em}\
figure{margin:2em 0}figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:0.95em;margin-top:0.4em}\
.warnings{background:#fff4e0;border-left:4px solid #d98200;padding:0.5em 1em;margin:1em 0}.warnings li{margin:0.2em 0}\
.note{color:#8a4b00}";

/// Whether a cell holds a number (right-aligned in HTML).
fn numeric(cell: &str) -> bool {
    let c = cell.trim_end_matches(" %");
    !c.is_empty() && c.parse::<f64>().is_ok()
}

/// The blocks as one self-contained HTML page (figures and font as data URIs).
pub fn html(title: &str, blocks: &[Block<'_>]) -> String {
    let b64 = &base64::engine::general_purpose::STANDARD;
    let css = CSS.replace("FONT", &format!("\"{}\"", crate::plot::FONT_FAMILY));
    let mut out = String::new();
    let _ = write!(
        out,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n<title>{}</title>\n<style>{}{}</style>\n</head>\n<body>\n",
        xml_escape(title),
        crate::plot::font_face_css(),
        css
    );
    for b in blocks {
        match b {
            Block::Title(t) => {
                let _ = writeln!(out, "<h1>{}</h1>", inline(t));
            }
            Block::Heading(t) => {
                let _ = writeln!(out, "<h2>{}</h2>", inline(t));
            }
            Block::Subheading(t) => {
                let _ = writeln!(out, "<h3>{}</h3>", inline(t));
            }
            Block::Paragraph(t) => {
                let _ = writeln!(out, "<p>{}</p>", inline(t));
            }
            Block::Warnings(items) => {
                let _ = writeln!(out, "<div class=\"warnings\"><b>Warnings</b><ul>");
                for w in items {
                    let _ = writeln!(out, "<li>{}</li>", inline(w));
                }
                let _ = writeln!(out, "</ul></div>");
            }
            Block::List(items) => {
                let _ = writeln!(out, "<ul>");
                for i in items {
                    let _ = writeln!(out, "<li>{}</li>", inline(i));
                }
                let _ = writeln!(out, "</ul>");
            }
            Block::Table { header, rows } => {
                let _ = write!(out, "<table>\n<tr>");
                for h in header {
                    let _ = write!(out, "<th>{}</th>", inline(h));
                }
                let _ = writeln!(out, "</tr>");
                for r in rows {
                    let _ = write!(out, "<tr>");
                    for c in r {
                        let class = if numeric(c) { " class=\"num\"" } else { "" };
                        let _ = write!(out, "<td{class}>{}</td>", inline(c));
                    }
                    let _ = writeln!(out, "</tr>");
                }
                let _ = writeln!(out, "</table>");
            }
            Block::Figure {
                id,
                caption,
                png,
                notes,
                ..
            } => {
                let _ = write!(
                    out,
                    "<figure id=\"fig-{id}\"><img alt=\"Fig. {id}\" src=\"data:image/png;base64,{}\"/><figcaption><b>Fig. {id}.</b> {}",
                    b64.encode(png),
                    inline(caption),
                    id = xml_escape(id)
                );
                for n in notes.iter() {
                    let _ = write!(
                        out,
                        "<br/><span class=\"note\">Note: {}</span>",
                        inline(&n.text)
                    );
                }
                let _ = writeln!(out, "</figcaption></figure>");
            }
        }
    }
    let _ = writeln!(out, "</body>\n</html>");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(xml_escape("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
        assert_eq!(inline("x `a<b` y"), "x <code>a&lt;b</code> y");
        assert_eq!(
            inline("**bold** and `**not**`"),
            "<b>bold</b> and <code>**not**</code>"
        );
    }

    #[test]
    fn tables_render_in_both_forms() {
        let blocks = [Block::Table {
            header: vec!["metric".into(), "`a`".into()],
            rows: vec![vec!["x | y".into(), "1.5".into()]],
        }];
        let md = markdown(&blocks);
        assert!(
            md.contains("| metric | `a` |\n|---|---|\n| x \\| y | 1.5 |"),
            "{md}"
        );
        let html = html("t", &blocks);
        assert!(html.contains("<td class=\"num\">1.5</td>"), "{html}");
        assert!(html.contains("<th><code>a</code></th>"), "{html}");
    }
}
