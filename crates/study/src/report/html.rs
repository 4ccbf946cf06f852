//! A small HTML page builder for the reports: escaped text, headings,
//! paragraphs, tables and figures with their SVG link.

use std::fmt::Write;

pub use study::output::escape;

/// `text` (escaped) linked to `href` when there is one.
pub fn link(href: Option<&str>, text: &str) -> String {
    match href {
        Some(l) => format!("<a href=\"{l}\">{}</a>", escape(text)),
        None => escape(text),
    }
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1400px;margin:1em auto;padding:0 1em;color:#222}\
img{max-width:100%;border:1px solid #ddd;margin:.3em 0}table{border-collapse:collapse;font-size:13px}\
td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#eee}td.l{text-align:left}\
.blew_up{background:#f8d0d0}.failed{background:#ddd}.kicked{background:#fde3c0}.completed{background:#d8f0d8}\
figure{margin:0 0 1.2em 0}figcaption{font-size:13px;color:#555}\
#verdict{border-left:4px solid #888;padding:0 1em;margin-bottom:1.5em}b.status{padding:0 .3em}";

/// A table cell: right-aligned (numbers) or left-aligned (text); the content is HTML.
pub enum Cell {
    Num(String),
    Text(String),
}

/// The body of a page, built section by section.
#[derive(Default)]
pub struct Page {
    body: String,
}

impl Page {
    pub fn h2(&mut self, text: &str) {
        let _ = writeln!(self.body, "<h2>{}</h2>", escape(text));
    }

    /// Opens `<section id="ID">`; `end_section` closes it.
    pub fn begin_section(&mut self, id: &str) {
        let _ = writeln!(self.body, "<section id=\"{id}\">");
    }

    pub fn end_section(&mut self) {
        self.body.push_str("</section>\n");
    }

    /// A paragraph of HTML (callers escape what they insert).
    pub fn p(&mut self, html: &str) {
        let _ = writeln!(self.body, "<p>{html}</p>");
    }

    /// A PNG figure with its caption and a link to the SVG.
    pub fn figure(&mut self, files: &[String; 2], caption: &str) {
        let _ = writeln!(
            self.body,
            "<figure><img src=\"{0}\" alt=\"{1}\"><figcaption>{1} (<a href=\"{2}\">SVG</a>)</figcaption></figure>",
            files[0],
            escape(caption),
            files[1]
        );
    }

    /// An image without an SVG twin (an animation).
    pub fn image(&mut self, src: &str, alt: &str, caption: &str) {
        let _ = writeln!(
            self.body,
            "<figure><img src=\"{src}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
            escape(alt),
            escape(caption)
        );
    }

    /// A table: `id` (may be empty), header texts, and rows of (class, cells).
    pub fn table(&mut self, id: &str, headers: &[String], rows: &[(String, Vec<Cell>)]) {
        if id.is_empty() {
            self.body.push_str("<table>");
        } else {
            let _ = write!(self.body, "<table id=\"{id}\">");
        }
        if !headers.is_empty() {
            self.body.push_str("<tr>");
            for h in headers {
                let _ = write!(self.body, "<th>{}</th>", escape(h));
            }
            self.body.push_str("</tr>\n");
        }
        for (class, cells) in rows {
            if class.is_empty() {
                self.body.push_str("<tr>");
            } else {
                let _ = write!(self.body, "<tr class=\"{class}\">");
            }
            for c in cells {
                match c {
                    Cell::Num(h) => {
                        let _ = write!(self.body, "<td>{h}</td>");
                    }
                    Cell::Text(h) => {
                        let _ = write!(self.body, "<td class=l>{h}</td>");
                    }
                }
            }
            self.body.push_str("</tr>\n");
        }
        self.body.push_str("</table>\n");
    }

    /// The whole document.
    pub fn finish(self, title: &str) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{0}</title><style>{STYLE}</style></head>\n<body>\n<h1>{0}</h1>\n{1}</body></html>\n",
            escape(title),
            self.body
        )
    }
}
