//! The report as a document: a title, sections of paragraphs, tables and figures, rendered to
//! one self-contained HTML page (figures inline as SVG) and written with each figure also as
//! its own `.svg` file.

use std::path::{Path, PathBuf};

/// A table: headers and rows of text cells; cells that read as numbers are right-aligned.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    pub caption: Option<String>,
    pub headers: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new(headers: &[&str]) -> Self {
        Self {
            caption: None,
            headers: headers.iter().map(|h| h.to_string()).collect(),
            rows: vec![],
        }
    }
    pub fn caption(mut self, c: &str) -> Self {
        self.caption = Some(c.into());
        self
    }
    pub fn row(mut self, cells: Vec<String>) -> Self {
        self.rows.push(cells);
        self
    }
    pub fn push(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }
}

/// A figure: an SVG document, a file stem for its own file, a caption.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    pub name: String,
    pub caption: String,
    pub svg: String,
}

/// One piece of a section.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    Paragraph(String),
    /// Pre-formatted text (a command line, a summary as printed).
    Preformatted(String),
    Table(Table),
    Figure(Figure),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    pub heading: String,
    pub blocks: Vec<Block>,
}

impl Section {
    pub fn paragraph(&mut self, text: &str) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }
    pub fn preformatted(&mut self, text: &str) -> &mut Self {
        self.blocks.push(Block::Preformatted(text.into()));
        self
    }
    pub fn table(&mut self, t: Table) -> &mut Self {
        self.blocks.push(Block::Table(t));
        self
    }
    /// A figure; `name` becomes its file name (`figures/NAME.svg`), so it must be unique in the report.
    pub fn figure(&mut self, name: &str, caption: &str, svg: String) -> &mut Self {
        self.blocks.push(Block::Figure(Figure {
            name: name.into(),
            caption: caption.into(),
            svg,
        }));
        self
    }
}

/// A report page.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    pub title: String,
    pub sections: Vec<Section>,
}

/// Escape text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

fn numeric(cell: &str) -> bool {
    let t = cell.trim().trim_start_matches(['+', '-', '−', '±']).trim();
    t.chars().next().is_some_and(|c| c.is_ascii_digit())
}

const STYLE: &str = "body{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em;color:#222}\
table{border-collapse:collapse;margin:1em 0}th,td{border:1px solid #bbb;padding:.25em .6em}\
th{background:#eee}td.n{text-align:right;font-variant-numeric:tabular-nums}caption{text-align:left;font-style:italic}\
figure{margin:1em 0}figcaption{font-style:italic}pre{background:#f6f6f6;padding:.6em;overflow-x:auto}";

impl Report {
    pub fn new(title: &str) -> Self {
        Self {
            title: title.into(),
            sections: vec![],
        }
    }

    /// Start a section and return it to fill.
    pub fn section(&mut self, heading: &str) -> &mut Section {
        self.sections.push(Section {
            heading: heading.into(),
            blocks: vec![],
        });
        self.sections.last_mut().expect("just pushed")
    }

    /// Every figure, in order.
    pub fn figures(&self) -> impl Iterator<Item = &Figure> {
        self.sections
            .iter()
            .flat_map(|s| s.blocks.iter())
            .filter_map(|b| match b {
                Block::Figure(f) => Some(f),
                _ => None,
            })
    }

    /// The page as HTML (figures inline, so the one file is the whole report).
    pub fn to_html(&self) -> String {
        let mut h = format!("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n", escape(&self.title), escape(&self.title));
        for s in &self.sections {
            h += &format!("<section>\n<h2>{}</h2>\n", escape(&s.heading));
            for b in &s.blocks {
                match b {
                    Block::Paragraph(p) => h += &format!("<p>{}</p>\n", escape(p)),
                    Block::Preformatted(p) => h += &format!("<pre>{}</pre>\n", escape(p)),
                    Block::Table(t) => {
                        h += "<table>\n";
                        if let Some(c) = &t.caption {
                            h += &format!("<caption>{}</caption>\n", escape(c));
                        }
                        h += "<tr>";
                        for c in &t.headers {
                            h += &format!("<th>{}</th>", escape(c));
                        }
                        h += "</tr>\n";
                        for r in &t.rows {
                            h += "<tr>";
                            for c in r {
                                h += &if numeric(c) {
                                    format!("<td class=\"n\">{}</td>", escape(c))
                                } else {
                                    format!("<td>{}</td>", escape(c))
                                };
                            }
                            h += "</tr>\n";
                        }
                        h += "</table>\n";
                    }
                    Block::Figure(f) => {
                        // the SVG document inline, without its XML declaration
                        let svg = f.svg.trim_start();
                        let svg = if svg.starts_with("<?xml") {
                            svg.split_once("?>").map(|x| x.1).unwrap_or(svg)
                        } else {
                            svg
                        };
                        h += &format!("<figure id=\"{}\">\n{}\n<figcaption>{} (<a href=\"figures/{}.svg\">SVG</a>)</figcaption>\n</figure>\n", escape(&f.name), svg.trim(), escape(&f.caption), escape(&f.name));
                    }
                }
            }
            h += "</section>\n";
        }
        h + "</body>\n</html>\n"
    }

    /// Write `DIR/index.html` and `DIR/figures/NAME.svg` (creating the directories); returns
    /// the page's path.
    pub fn write_to(&self, dir: &Path) -> std::io::Result<PathBuf> {
        let figures = dir.join("figures");
        std::fs::create_dir_all(&figures)?;
        for f in self.figures() {
            std::fs::write(figures.join(format!("{}.svg", f.name)), &f.svg)?;
        }
        let page = dir.join("index.html");
        std::fs::write(&page, self.to_html())?;
        Ok(page)
    }
}
