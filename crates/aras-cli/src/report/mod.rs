//! Reports for people: one document model rendered to Markdown (figures as
//! SVG files beside it) and to a self-contained HTML page (SVG inline).

pub mod plots;
pub mod run;

use std::fmt::Write;

/// One block of a report.
pub enum Block {
    /// A heading of level 1–3.
    Heading(u8, String),
    /// A paragraph of plain text (Markdown inline syntax allowed: `code`, **bold**).
    Paragraph(String),
    /// A bulleted list.
    List(Vec<String>),
    /// A table with a header row.
    Table {
        /// Column titles.
        header: Vec<String>,
        /// Rows of cells.
        rows: Vec<Vec<String>>,
    },
    /// A figure: an SVG document saved as `file` and embedded in the HTML.
    Figure {
        /// File name of the SVG inside the output directory.
        file: String,
        /// Caption under the figure.
        caption: String,
        /// The SVG document.
        svg: String,
    },
    /// Preformatted text.
    Code(String),
}

/// A report under construction.
pub struct Report {
    title: String,
    blocks: Vec<Block>,
}

impl Report {
    /// An empty report.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    /// Adds a heading.
    pub fn heading(&mut self, level: u8, text: impl Into<String>) -> &mut Self {
        self.blocks
            .push(Block::Heading(level.clamp(1, 3), text.into()));
        self
    }

    /// Adds a paragraph.
    pub fn paragraph(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }

    /// Adds a bulleted list.
    pub fn list(&mut self, items: Vec<String>) -> &mut Self {
        self.blocks.push(Block::List(items));
        self
    }

    /// Adds a table.
    pub fn table(&mut self, header: &[&str], rows: Vec<Vec<String>>) -> &mut Self {
        self.blocks.push(Block::Table {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows,
        });
        self
    }

    /// Adds a figure.
    pub fn figure(
        &mut self,
        file: impl Into<String>,
        caption: impl Into<String>,
        svg: String,
    ) -> &mut Self {
        self.blocks.push(Block::Figure {
            file: file.into(),
            caption: caption.into(),
            svg,
        });
        self
    }

    /// Adds preformatted text.
    pub fn code(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Code(text.into()));
        self
    }

    /// The figures, to be written next to the Markdown file.
    pub fn figures(&self) -> impl Iterator<Item = (&str, &str)> {
        self.blocks.iter().filter_map(|b| match b {
            Block::Figure { file, svg, .. } => Some((file.as_str(), svg.as_str())),
            _ => None,
        })
    }

    /// Markdown rendering; figures are referenced by file name.
    pub fn to_markdown(&self) -> String {
        let mut s = format!("# {}\n\n", self.title);
        for b in &self.blocks {
            match b {
                Block::Heading(l, t) => {
                    let _ = writeln!(s, "{} {t}\n", "#".repeat(*l as usize + 1));
                }
                Block::Paragraph(t) => {
                    let _ = writeln!(s, "{t}\n");
                }
                Block::List(items) => {
                    for i in items {
                        let _ = writeln!(s, "- {i}");
                    }
                    s.push('\n');
                }
                Block::Table { header, rows } => {
                    let _ = writeln!(s, "| {} |", header.join(" | "));
                    let _ = writeln!(s, "|{}", "---|".repeat(header.len()));
                    for r in rows {
                        let _ = writeln!(s, "| {} |", r.join(" | "));
                    }
                    s.push('\n');
                }
                Block::Figure { file, caption, .. } => {
                    let _ = writeln!(s, "![{caption}]({file})\n\n*{caption}*\n");
                }
                Block::Code(t) => {
                    let _ = writeln!(s, "```text\n{t}\n```\n");
                }
            }
        }
        s
    }

    /// Self-contained HTML (no external resources: SVGs inline).
    pub fn to_html(&self) -> String {
        let mut s = String::new();
        let _ = write!(
            s,
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
             <title>{}</title><style>{}</style></head><body><main>\n<h1>{}</h1>\n",
            esc(&plots::plain_title(&self.title)),
            CSS,
            inline(&self.title)
        );
        for b in &self.blocks {
            match b {
                Block::Heading(l, t) => {
                    let _ = writeln!(s, "<h{0}>{1}</h{0}>", l + 1, inline(t));
                }
                Block::Paragraph(t) => {
                    let _ = writeln!(s, "<p>{}</p>", inline(t));
                }
                Block::List(items) => {
                    s.push_str("<ul>");
                    for i in items {
                        let _ = write!(s, "<li>{}</li>", inline(i));
                    }
                    s.push_str("</ul>\n");
                }
                Block::Table { header, rows } => {
                    s.push_str("<table><thead><tr>");
                    for h in header {
                        let _ = write!(s, "<th>{}</th>", inline(h));
                    }
                    s.push_str("</tr></thead><tbody>");
                    for r in rows {
                        s.push_str("<tr>");
                        for c in r {
                            let _ = write!(s, "<td>{}</td>", inline(c));
                        }
                        s.push_str("</tr>");
                    }
                    s.push_str("</tbody></table>\n");
                }
                Block::Figure { caption, svg, .. } => {
                    let body = svg.find("<svg").map(|i| &svg[i..]).unwrap_or(svg);
                    let _ = writeln!(
                        s,
                        "<figure>{body}<figcaption>{}</figcaption></figure>",
                        inline(caption)
                    );
                }
                Block::Code(t) => {
                    let _ = writeln!(s, "<pre>{}</pre>", esc(t));
                }
            }
        }
        s.push_str("</main></body></html>\n");
        s
    }
}

const CSS: &str = "body{font-family:system-ui,sans-serif;margin:0;background:#fafafa;color:#222}\
main{max-width:1000px;margin:auto;padding:1.5em}table{border-collapse:collapse;margin:1em 0}\
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:right}th{background:#eee}\
td:first-child,th:first-child{text-align:left}figure{margin:1em 0}svg{max-width:100%;height:auto}\
figcaption{font-size:.9em;color:#555}pre{background:#f0f0f0;padding:.8em;overflow-x:auto}\
code{background:#eee;padding:0 .2em}";

fn esc(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Escapes HTML and renders the two inline Markdown forms reports use:
/// `code` and **bold**.
fn inline(t: &str) -> String {
    let mut out = String::new();
    let e = esc(t);
    let mut code = false;
    for (i, part) in e.split('`').enumerate() {
        if i > 0 {
            out.push_str(if code { "</code>" } else { "<code>" });
            code = !code;
        }
        if code {
            out.push_str(part);
        } else {
            let mut bold = false;
            for (j, p) in part.split("**").enumerate() {
                if j > 0 {
                    out.push_str(if bold { "</b>" } else { "<b>" });
                    bold = !bold;
                }
                out.push_str(p);
            }
            if bold {
                out.push_str("</b>");
            }
        }
    }
    if code {
        out.push_str("</code>");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_both_formats() {
        let mut r = Report::new("T <1> `x`");
        r.heading(1, "Fit")
            .paragraph("a `b` **c**")
            .table(&["x", "y"], vec![vec!["1".into(), "2".into()]]);
        r.figure("f.svg", "cap", "<?xml?><svg></svg>".into());
        let md = r.to_markdown();
        assert!(md.contains("| x | y |\n|---|---|\n| 1 | 2 |"));
        assert!(md.contains("![cap](f.svg)"));
        let html = r.to_html();
        assert!(
            html.contains("<title>T &lt;1&gt; x</title>"),
            "no markup in the page title"
        );
        assert!(
            html.contains("<h1>T &lt;1&gt; <code>x</code></h1>"),
            "markup rendered in headings"
        );
        assert!(html.contains("a <code>b</code> <b>c</b>"));
        assert!(html.contains("<figure><svg></svg>"));
        assert_eq!(r.figures().count(), 1);
    }
}
