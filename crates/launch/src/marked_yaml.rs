//! A YAML document tree in which every node remembers the line it starts on, so that every
//! complaint about a launch file can name the file, the line and the key.
//!
//! Built from `yaml-rust2` parser events (which carry a position each); scalars keep their
//! source text and quoting style, because a parameter value `2.0` must reach the node as `2.0`,
//! not as a re-formatted float, and a quoted `'1'` must stay a string.

use std::collections::HashMap;

use yaml_rust2::parser::{Event, MarkedEventReceiver, Parser};
use yaml_rust2::scanner::{Marker, TScalarStyle};

/// One YAML node and where it starts. `line` is 1-based, as editors show it.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkedNode {
    pub value: MarkedValue,
    pub line: usize,
}

/// The shape of a node. Scalars are kept as text; their type is decided by whoever reads them.
#[derive(Clone, Debug, PartialEq)]
pub enum MarkedValue {
    /// `plain` is true for an unquoted scalar (so `true`, `2`, `~` may mean a bool, an int, null).
    Scalar {
        text: String,
        plain: bool,
    },
    Sequence(Vec<MarkedNode>),
    /// Entries in document order (duplicates are rejected while building).
    Mapping(Vec<(MarkedNode, MarkedNode)>),
}

/// What went wrong while reading YAML text; `line`/`column` are 1-based.
#[derive(Clone, Debug, PartialEq)]
pub struct YamlSyntaxError {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl MarkedNode {
    /// The scalar text, if this node is a scalar.
    pub fn as_scalar(&self) -> Option<&str> {
        match &self.value {
            MarkedValue::Scalar { text, .. } => Some(text),
            _ => None,
        }
    }

    /// True for an unquoted `~`, `null`, `Null`, `NULL` or an empty plain scalar.
    pub fn is_null(&self) -> bool {
        matches!(&self.value, MarkedValue::Scalar { text, plain: true }
            if matches!(text.as_str(), "" | "~" | "null" | "Null" | "NULL"))
    }

    /// A short name of the node's kind, for "expected X, found Y" messages.
    pub fn kind_name(&self) -> &'static str {
        match &self.value {
            MarkedValue::Scalar { .. } if self.is_null() => "nothing (null)",
            MarkedValue::Scalar { .. } => "a scalar",
            MarkedValue::Sequence(_) => "a list",
            MarkedValue::Mapping(_) => "a mapping",
        }
    }
}

/// Parse one YAML document. An empty document gives `Ok(None)`.
pub fn parse_marked_yaml(text: &str) -> Result<Option<MarkedNode>, YamlSyntaxError> {
    let mut builder = TreeBuilder::default();
    let mut parser = Parser::new_from_str(text);
    parser
        .load(&mut builder, false)
        .map_err(|e| YamlSyntaxError {
            line: e.marker().line(),
            column: e.marker().col() + 1,
            message: e.info().to_string(),
        })?;
    if let Some(err) = builder.error {
        return Err(err);
    }
    Ok(builder.document)
}

/// A container being filled, with the key waiting for its value when it is a mapping.
enum Open {
    Sequence {
        line: usize,
        anchor: usize,
        items: Vec<MarkedNode>,
    },
    Mapping {
        line: usize,
        anchor: usize,
        entries: Vec<(MarkedNode, MarkedNode)>,
        key: Option<MarkedNode>,
    },
}

#[derive(Default)]
struct TreeBuilder {
    stack: Vec<Open>,
    anchors: HashMap<usize, MarkedNode>,
    document: Option<MarkedNode>,
    error: Option<YamlSyntaxError>,
}

impl TreeBuilder {
    fn finish_node(&mut self, node: MarkedNode, anchor: usize) {
        if anchor != 0 {
            self.anchors.insert(anchor, node.clone());
        }
        match self.stack.last_mut() {
            None => {
                if self.document.is_none() {
                    self.document = Some(node);
                }
            }
            Some(Open::Sequence { items, .. }) => items.push(node),
            Some(Open::Mapping { entries, key, .. }) => match key.take() {
                None => *key = Some(node),
                Some(k) => {
                    let duplicate = k.as_scalar().is_some()
                        && entries
                            .iter()
                            .any(|(existing, _)| existing.as_scalar() == k.as_scalar());
                    if duplicate && self.error.is_none() {
                        self.error = Some(YamlSyntaxError {
                            line: k.line,
                            column: 1,
                            message: format!(
                                "duplicate key '{}'",
                                k.as_scalar().unwrap_or_default()
                            ),
                        });
                    }
                    entries.push((k, node));
                }
            },
        }
    }
}

impl MarkedEventReceiver for TreeBuilder {
    fn on_event(&mut self, ev: Event, mark: Marker) {
        let line = mark.line();
        match ev {
            Event::Scalar(text, style, anchor, _tag) => {
                let plain = matches!(style, TScalarStyle::Plain);
                self.finish_node(
                    MarkedNode {
                        value: MarkedValue::Scalar { text, plain },
                        line,
                    },
                    anchor,
                );
            }
            Event::Alias(id) => {
                let node = match self.anchors.get(&id) {
                    Some(n) => MarkedNode { line, ..n.clone() },
                    None => {
                        if self.error.is_none() {
                            self.error = Some(YamlSyntaxError {
                                line,
                                column: mark.col() + 1,
                                message: "alias to an unknown anchor".into(),
                            });
                        }
                        MarkedNode {
                            value: MarkedValue::Scalar {
                                text: String::new(),
                                plain: true,
                            },
                            line,
                        }
                    }
                };
                self.finish_node(node, 0);
            }
            Event::SequenceStart(anchor, _) => self.stack.push(Open::Sequence {
                line,
                anchor,
                items: Vec::new(),
            }),
            Event::MappingStart(anchor, _) => self.stack.push(Open::Mapping {
                line,
                anchor,
                entries: Vec::new(),
                key: None,
            }),
            Event::SequenceEnd | Event::MappingEnd => {
                let (node, anchor) = match self.stack.pop() {
                    Some(Open::Sequence {
                        line,
                        anchor,
                        items,
                    }) => (
                        MarkedNode {
                            value: MarkedValue::Sequence(items),
                            line,
                        },
                        anchor,
                    ),
                    Some(Open::Mapping {
                        line,
                        anchor,
                        entries,
                        ..
                    }) => (
                        MarkedNode {
                            value: MarkedValue::Mapping(entries),
                            line,
                        },
                        anchor,
                    ),
                    None => return,
                };
                self.finish_node(node, anchor);
            }
            Event::Nothing
            | Event::StreamStart
            | Event::StreamEnd
            | Event::DocumentStart
            | Event::DocumentEnd => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map_entries(node: &MarkedNode) -> &[(MarkedNode, MarkedNode)] {
        match &node.value {
            MarkedValue::Mapping(e) => e,
            other => panic!("expected a mapping, got {other:?}"),
        }
    }

    #[test]
    fn keys_and_values_carry_their_one_based_lines() {
        let text = "# comment\nlaunch:\n  - node:\n      pkg: a\n      exec: 'b'\n";
        let root = parse_marked_yaml(text).unwrap().unwrap();
        let (launch_key, launch_list) = &map_entries(&root)[0];
        assert_eq!(launch_key.line, 2);
        let MarkedValue::Sequence(items) = &launch_list.value else {
            panic!()
        };
        let (node_key, node_body) = &map_entries(&items[0])[0];
        assert_eq!((node_key.as_scalar(), node_key.line), (Some("node"), 3));
        let body = map_entries(node_body);
        assert_eq!((body[0].0.as_scalar(), body[0].0.line), (Some("pkg"), 4));
        assert_eq!((body[1].1.as_scalar(), body[1].1.line), (Some("b"), 5));
        assert_eq!(
            body[1].1.value,
            MarkedValue::Scalar {
                text: "b".into(),
                plain: false
            }
        );
    }

    #[test]
    fn syntax_error_reports_line() {
        let err = parse_marked_yaml("launch:\n  - node: {pkg: a\n  - x\n").unwrap_err();
        assert!(err.line >= 2, "{err:?}");
    }

    #[test]
    fn duplicate_key_is_an_error_at_its_line() {
        let err = parse_marked_yaml("a: 1\nb: 2\na: 3\n").unwrap_err();
        assert_eq!(err.line, 3);
        assert!(err.message.contains("duplicate key 'a'"));
    }

    #[test]
    fn aliases_copy_the_anchored_node() {
        let root = parse_marked_yaml("a: &x [1, 2]\nb: *x\n").unwrap().unwrap();
        let e = map_entries(&root);
        let MarkedValue::Sequence(items) = &e[1].1.value else {
            panic!()
        };
        assert_eq!(items.len(), 2);
    }

    #[test]
    fn empty_document_is_none() {
        assert_eq!(parse_marked_yaml("# nothing\n").unwrap(), None);
    }
}
