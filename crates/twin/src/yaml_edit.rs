//! Editing a YAML text in place: replace the value of a key, add a key to a mapping, append an
//! item to a sequence — leaving every other byte (comments, blank lines, key order, quoting,
//! the user's flow or block style) as it was. The model writer uses it to put fitted values
//! into the user's own cell file.
//!
//! How: yaml-rust2's event parser gives the start of every node; the end of a node is found
//! from the text (a scalar's last character, a flow collection's closing bracket, a block
//! collection's last content). Edits are byte ranges applied from the end of the text backwards.
//! A replaced value loses the comments inside it (not those after it on its line).

use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::Marker;

/// What kind of node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    Scalar,
    FlowMapping,
    FlowSequence,
    BlockMapping,
    BlockSequence,
}

/// A node of the document with its byte span in the text.
#[derive(Debug, Clone)]
pub struct Node {
    pub style: Style,
    /// Byte offset of the first character and one past the last.
    pub start: usize,
    pub end: usize,
    /// Column (0-based, in characters) of the first character.
    pub column: usize,
    pub content: Content,
}

#[derive(Debug, Clone)]
pub enum Content {
    Scalar(String),
    /// (key text, key node, value node), in document order.
    Mapping(Vec<(String, Node, Node)>),
    Sequence(Vec<Node>),
}

/// Why a text could not be edited.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct EditError(pub String);

struct Collect(Vec<(Event, Marker)>);

impl MarkedEventReceiver for Collect {
    fn on_event(&mut self, ev: Event, mark: Marker) {
        self.0.push((ev, mark));
    }
}

/// Byte offset of each line start, for turning (line, column) markers into bytes.
struct Lines<'t> {
    text: &'t str,
    starts: Vec<usize>,
}

impl<'t> Lines<'t> {
    fn new(text: &'t str) -> Self {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Self { text, starts }
    }
    /// Byte offset of a marker (line 1-based, column 0-based in characters).
    fn byte(&self, m: &Marker) -> usize {
        let line_start = self
            .starts
            .get(m.line().saturating_sub(1))
            .copied()
            .unwrap_or(self.text.len());
        let rest = &self.text[line_start..];
        rest.char_indices()
            .nth(m.col())
            .map(|(i, _)| line_start + i)
            .unwrap_or(line_start + rest.len())
    }
}

/// Parse `text` into nodes with spans. The document's root is returned.
pub fn parse(text: &str) -> Result<Node, EditError> {
    let mut c = Collect(Vec::new());
    let mut parser = Parser::new_from_str(text);
    parser
        .load(&mut c, false)
        .map_err(|e| EditError(format!("YAML: {e}")))?;
    let lines = Lines::new(text);
    let events = c.0;
    let mut at = events
        .iter()
        .position(|(e, _)| matches!(e, Event::DocumentStart))
        .map(|i| i + 1)
        .ok_or_else(|| EditError("YAML: no document".into()))?;
    if matches!(events.get(at), Some((Event::DocumentEnd, _)) | None) {
        return Err(EditError("YAML: the document is empty".into()));
    }
    node(&events, &mut at, &lines, false)
}

fn node(
    events: &[(Event, Marker)],
    at: &mut usize,
    lines: &Lines,
    in_flow: bool,
) -> Result<Node, EditError> {
    let (ev, mark) = events
        .get(*at)
        .ok_or_else(|| EditError("YAML: unexpected end".into()))?;
    *at += 1;
    let start = lines.byte(mark);
    let column = mark.col();
    let text = lines.text;
    match ev {
        Event::Scalar(value, ..) => Ok(Node {
            style: Style::Scalar,
            start,
            end: scalar_end(text, start, in_flow),
            column,
            content: Content::Scalar(value.clone()),
        }),
        Event::Alias(_) => Ok(Node {
            style: Style::Scalar,
            start,
            end: scalar_end(text, start, in_flow),
            column,
            content: Content::Scalar(String::new()),
        }),
        Event::MappingStart(..) => {
            let flow = text[start..].starts_with('{');
            let mut entries = Vec::new();
            loop {
                if let Some((Event::MappingEnd, end_mark)) = events.get(*at) {
                    *at += 1;
                    let end = if flow {
                        lines.byte(end_mark) + 1
                    } else {
                        entries
                            .last()
                            .map(|(_, _, v): &(String, Node, Node)| v.end)
                            .unwrap_or(start)
                    };
                    // a block mapping's start event is marked where its first `:` was found:
                    // the mapping starts at its first key
                    let (start, column) = match (flow, entries.first()) {
                        (false, Some((_, k, _))) => (k.start, k.column),
                        _ => (start, column),
                    };
                    return Ok(Node {
                        style: if flow {
                            Style::FlowMapping
                        } else {
                            Style::BlockMapping
                        },
                        start,
                        end,
                        column,
                        content: Content::Mapping(entries),
                    });
                }
                let key = node(events, at, lines, flow || in_flow)?;
                let value = node(events, at, lines, flow || in_flow)?;
                let name = match &key.content {
                    Content::Scalar(s) => s.clone(),
                    _ => String::new(),
                };
                entries.push((name, key, value));
            }
        }
        Event::SequenceStart(..) => {
            let flow = text[start..].starts_with('[');
            let mut items = Vec::new();
            loop {
                if let Some((Event::SequenceEnd, end_mark)) = events.get(*at) {
                    *at += 1;
                    let end = if flow {
                        lines.byte(end_mark) + 1
                    } else {
                        items.last().map(|v: &Node| v.end).unwrap_or(start)
                    };
                    return Ok(Node {
                        style: if flow {
                            Style::FlowSequence
                        } else {
                            Style::BlockSequence
                        },
                        start,
                        end,
                        column,
                        content: Content::Sequence(items),
                    });
                }
                items.push(node(events, at, lines, flow || in_flow)?);
            }
        }
        other => Err(EditError(format!("YAML: unexpected {other:?}"))),
    }
}

/// One past the last character of the scalar starting at `start`.
fn scalar_end(text: &str, start: usize, in_flow: bool) -> usize {
    let rest = &text[start..];
    let mut chars = rest.char_indices();
    match chars.next() {
        Some((_, '"')) => {
            let mut escaped = false;
            for (i, c) in chars {
                match c {
                    '\\' if !escaped => escaped = true,
                    '"' if !escaped => return start + i + 1,
                    _ => escaped = false,
                }
            }
            text.len()
        }
        Some((_, '\'')) => {
            let b = rest.as_bytes();
            let mut i = 1;
            while i < b.len() {
                if b[i] == b'\'' {
                    if b.get(i + 1) == Some(&b'\'') {
                        i += 2;
                        continue;
                    }
                    return start + i + 1;
                }
                i += 1;
            }
            text.len()
        }
        _ => {
            let line_end = rest.find('\n').unwrap_or(rest.len());
            let mut end = line_end;
            if let Some(c) = rest[..line_end].find(" #") {
                end = end.min(c);
            }
            if in_flow {
                if let Some(c) = rest[..line_end].find([',', '}', ']']) {
                    end = end.min(c);
                }
            }
            start + rest[..end].trim_end().len()
        }
    }
}

impl Node {
    /// The value of `key` in a mapping.
    pub fn get(&self, key: &str) -> Option<&Node> {
        match &self.content {
            Content::Mapping(entries) => {
                entries.iter().find(|(k, _, _)| k == key).map(|(_, _, v)| v)
            }
            _ => None,
        }
    }
    /// The key node of `key` in a mapping.
    pub fn key(&self, key: &str) -> Option<&Node> {
        match &self.content {
            Content::Mapping(entries) => {
                entries.iter().find(|(k, _, _)| k == key).map(|(_, k, _)| k)
            }
            _ => None,
        }
    }
    pub fn item(&self, i: usize) -> Option<&Node> {
        match &self.content {
            Content::Sequence(items) => items.get(i),
            _ => None,
        }
    }
    pub fn len(&self) -> usize {
        match &self.content {
            Content::Mapping(e) => e.len(),
            Content::Sequence(i) => i.len(),
            Content::Scalar(_) => 0,
        }
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    pub fn is_flow(&self) -> bool {
        matches!(self.style, Style::FlowMapping | Style::FlowSequence)
    }
    /// The value of a scalar as the YAML parser reads it (quotes and escapes resolved), not
    /// as written.
    pub fn scalar(&self) -> Option<&str> {
        match &self.content {
            Content::Scalar(s) => Some(s),
            _ => None,
        }
    }
    /// The node at a dotted path of keys and `[i]` indices, e.g. `terms[2].params`.
    pub fn at(&self, path: &str) -> Option<&Node> {
        let mut n = self;
        for part in path.split('.').filter(|p| !p.is_empty()) {
            let (key, index) = match part.find('[') {
                Some(b) if part.ends_with(']') => (
                    &part[..b],
                    part[b + 1..part.len() - 1].parse::<usize>().ok(),
                ),
                _ => (part, None),
            };
            if !key.is_empty() {
                n = n.get(key)?;
            }
            if let Some(i) = index {
                n = n.item(i)?;
            }
        }
        Some(n)
    }
}

/// Edits collected against one parse of a text, applied together.
#[derive(Debug, Default)]
pub struct Edits {
    /// (start, end, replacement) byte ranges of the original text.
    changes: Vec<(usize, usize, String)>,
}

/// Indentation (spaces) of the line holding byte `at`.
pub fn line_indent(text: &str, at: usize) -> usize {
    let line_start = text[..at].rfind('\n').map(|i| i + 1).unwrap_or(0);
    text[line_start..].chars().take_while(|c| *c == ' ').count()
}

impl Edits {
    /// Replace the bytes of `node` by `text` (already rendered for its place).
    pub fn replace(&mut self, node: &Node, text: String) {
        self.changes.push((node.start, node.end, text));
    }
    /// Insert `text` at byte `at`.
    pub fn insert(&mut self, at: usize, text: String) {
        self.changes.push((at, at, text));
    }
    /// Apply to the text the nodes were parsed from. Overlapping edits are an error.
    pub fn apply(mut self, text: &str) -> Result<String, EditError> {
        self.changes.sort_by_key(|c| (c.0, c.1));
        for w in self.changes.windows(2) {
            if w[1].0 < w[0].1 {
                return Err(EditError(format!(
                    "overlapping edits at bytes {}..{} and {}..{}",
                    w[0].0, w[0].1, w[1].0, w[1].1
                )));
            }
        }
        let mut out = text.to_string();
        for (s, e, r) in self.changes.into_iter().rev() {
            out.replace_range(s..e, &r);
        }
        Ok(out)
    }
}

/// Replace the items of a sequence by `items` (each rendered for one line, e.g. `12.5 mm`) in
/// the sequence's own style: a flow sequence is rewritten as `[a, b, c]`, a block sequence of
/// as many items has each item replaced where it stands (so `translation:` followed by `- 1 m`
/// lines stays a block list). A block sequence of another length is an error: it cannot be
/// rewritten in place without guessing its layout.
pub fn replace_sequence(edits: &mut Edits, seq: &Node, items: &[String]) -> Result<(), EditError> {
    match (&seq.style, &seq.content) {
        (Style::BlockSequence, Content::Sequence(old)) => {
            if old.len() != items.len() {
                return Err(EditError(format!(
                    "a block list of {} items cannot take {} in place",
                    old.len(),
                    items.len()
                )));
            }
            for (node, item) in old.iter().zip(items) {
                if node.style != Style::Scalar {
                    return Err(EditError("a block list whose items are lists or mappings cannot take scalar items in place".into()));
                }
                edits.replace(node, item.clone());
            }
            Ok(())
        }
        (Style::FlowSequence, _) => {
            edits.replace(seq, format!("[{}]", items.join(", ")));
            Ok(())
        }
        _ => Err(EditError("not a list".into())),
    }
}

/// Add `key: value` (value rendered on one line, e.g. a flow mapping) to a mapping node:
/// inside the braces of a flow mapping, or as a new line after the last entry of a block one.
pub fn add_to_mapping(edits: &mut Edits, text: &str, mapping: &Node, key: &str, value: &str) {
    match &mapping.content {
        Content::Mapping(entries)
            if mapping.style == Style::BlockMapping && !entries.is_empty() =>
        {
            let last = &entries[entries.len() - 1].2;
            let indent = entries[0].1.column;
            let at = text[last.end..]
                .find('\n')
                .map(|i| last.end + i)
                .unwrap_or(text.len());
            edits.insert(at, format!("\n{}{key}: {value}", " ".repeat(indent)));
        }
        _ => {
            // flow mapping: before the closing brace
            let close = mapping.end - 1;
            let sep = if mapping.is_empty() { "" } else { ", " };
            edits.insert(close, format!("{sep}{key}: {value}"));
        }
    }
}

/// Append `item` (lines of YAML for one sequence item, without the `- `, relative indentation)
/// to a block sequence, in the indentation and style of its existing items.
pub fn append_to_block_sequence(edits: &mut Edits, text: &str, seq: &Node, item: &str) {
    let (dash_col, at) = match &seq.content {
        Content::Sequence(items) if !items.is_empty() => {
            let last = &items[items.len() - 1];
            let end_line = text[last.end..]
                .find('\n')
                .map(|i| last.end + i)
                .unwrap_or(text.len());
            // the dash sits two columns before the item's content
            (items[0].column.saturating_sub(2), end_line)
        }
        _ => (
            seq.column,
            text[seq.end..]
                .find('\n')
                .map(|i| seq.end + i)
                .unwrap_or(text.len()),
        ),
    };
    let pad = " ".repeat(dash_col);
    let mut out = String::new();
    for (i, line) in item.lines().enumerate() {
        out.push('\n');
        out.push_str(&pad);
        out.push_str(if i == 0 { "- " } else { "  " });
        out.push_str(line);
    }
    edits.insert(at, out);
}

/// Quote a mapping key when YAML needs it (labels such as `thermal_scale[x]` do in flow context).
pub fn key_text(key: &str) -> String {
    if key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        key.to_string()
    } else {
        format!("\"{}\"", key.replace('\\', "\\\\").replace('"', "\\\""))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "# a comment with µm\nname: x   # trailing\nterms:\n  - id: a\n    params: {c0: 1 um, c1: \"2 um\"}   # keep me\n  - id: b\n    params:\n      r: 8 um\n      s: 2 um\n    # inside\nlast: [1, 2]\n";

    #[test]
    fn spans_cover_exactly_the_values() {
        let root = parse(TEXT).unwrap();
        let p = root.at("terms[0].params").unwrap();
        assert_eq!(&TEXT[p.start..p.end], "{c0: 1 um, c1: \"2 um\"}");
        assert_eq!(
            &TEXT[root.at("terms[0].params.c1").unwrap().start
                ..root.at("terms[0].params.c1").unwrap().end],
            "\"2 um\""
        );
        let b = root.at("terms[1].params").unwrap();
        assert_eq!(&TEXT[b.start..b.end], "r: 8 um\n      s: 2 um");
        assert_eq!(
            &TEXT[root.at("name").unwrap().start..root.at("name").unwrap().end],
            "x"
        );
        assert_eq!(
            &TEXT[root.at("last").unwrap().start..root.at("last").unwrap().end],
            "[1, 2]"
        );
    }

    #[test]
    fn edits_keep_everything_else() {
        let root = parse(TEXT).unwrap();
        let mut e = Edits::default();
        e.replace(
            root.at("terms[0].params").unwrap(),
            "{c0: 3 um, c1: 4 um}".into(),
        );
        add_to_mapping(
            &mut e,
            TEXT,
            root.at("terms[1].params").unwrap(),
            "t",
            "1 um",
        );
        append_to_block_sequence(
            &mut e,
            TEXT,
            root.at("terms").unwrap(),
            "id: c\nparams: {k: 1}",
        );
        let out = e.apply(TEXT).unwrap();
        assert!(
            out.contains("    params: {c0: 3 um, c1: 4 um}   # keep me\n"),
            "{out}"
        );
        assert!(out.contains("      s: 2 um\n      t: 1 um\n"), "{out}");
        assert!(out.contains("  - id: c\n    params: {k: 1}\n"), "{out}");
        assert!(out.starts_with("# a comment with µm\nname: x   # trailing\n"));
        let back = parse(&out).unwrap();
        assert_eq!(back.at("terms").unwrap().len(), 3);
    }
}
