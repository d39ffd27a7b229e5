//! Which topics a recorder records: an explicit list, or an include regex (default: all),
//! minus an exclude regex. Regexes must match the whole topic name (anchored), like
//! `ros2 bag record --regex`'s users expect of `/camera/.*`.

use regex::Regex;

use crate::error::{Result, ToolError};

#[derive(Debug, Clone, Default)]
pub struct TopicSelection {
    /// Explicit topic names; when non-empty, only these are recorded.
    pub topics: Vec<String>,
    include: Option<Regex>,
    exclude: Option<Regex>,
}

fn anchored(pattern: &str) -> Result<Option<Regex>> {
    if pattern.is_empty() {
        return Ok(None);
    }
    Regex::new(&format!("^(?:{pattern})$"))
        .map(Some)
        .map_err(|e| ToolError::Regex { pattern: pattern.to_string(), reason: e.to_string() })
}

impl TopicSelection {
    /// `topics`: explicit names (empty = all); `include`/`exclude`: regexes ("" = none).
    pub fn new(topics: Vec<String>, include: &str, exclude: &str) -> Result<Self> {
        Ok(Self { topics, include: anchored(include)?, exclude: anchored(exclude)? })
    }

    /// Everything.
    pub fn all() -> Self {
        Self::default()
    }

    pub fn matches(&self, topic: &str) -> bool {
        if !self.topics.is_empty() && !self.topics.iter().any(|t| t == topic) {
            return false;
        }
        if let Some(r) = &self.include {
            if !r.is_match(topic) {
                return false;
            }
        }
        !self.exclude.as_ref().is_some_and(|r| r.is_match(topic))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn list_regex_and_exclude_combine() {
        let s = TopicSelection::new(vec![], "/camera/.*|/tracker", "/camera/debug.*").unwrap();
        assert!(s.matches("/camera/image"));
        assert!(s.matches("/tracker"));
        assert!(!s.matches("/tracker/raw"), "regex is anchored");
        assert!(!s.matches("/camera/debug/x"));
        let l = TopicSelection::new(vec!["/a".into()], "", "").unwrap();
        assert!(l.matches("/a") && !l.matches("/b"));
        assert!(TopicSelection::all().matches("/anything"));
        assert!(matches!(TopicSelection::new(vec![], "(", ""), Err(ToolError::Regex { .. })));
    }
}
