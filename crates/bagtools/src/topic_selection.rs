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
    /// The patterns as the user gave them, for messages.
    patterns: (String, String),
}

fn anchored(pattern: &str) -> Result<Option<Regex>> {
    if pattern.is_empty() {
        return Ok(None);
    }
    Regex::new(&format!("^(?:{pattern})$"))
        .map(Some)
        .map_err(|e| ToolError::Regex {
            pattern: pattern.to_string(),
            reason: e.to_string(),
        })
}

impl TopicSelection {
    /// `topics`: explicit names (empty = all); `include`/`exclude`: regexes ("" = none).
    pub fn new(topics: Vec<String>, include: &str, exclude: &str) -> Result<Self> {
        Ok(Self {
            topics,
            include: anchored(include)?,
            exclude: anchored(exclude)?,
            patterns: (include.to_string(), exclude.to_string()),
        })
    }

    /// The selection in words, for messages: "topics /a, /b and regex '/camera/.*', excluding '/camera/debug.*'".
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if !self.topics.is_empty() {
            parts.push(format!("topics {}", self.topics.join(", ")));
        }
        if !self.patterns.0.is_empty() {
            parts.push(format!("regex '{}'", self.patterns.0));
        }
        let mut s = if parts.is_empty() {
            "every topic".to_string()
        } else {
            parts.join(" and ")
        };
        if !self.patterns.1.is_empty() {
            s.push_str(&format!(", excluding '{}'", self.patterns.1));
        }
        s
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
        assert!(matches!(
            TopicSelection::new(vec![], "(", ""),
            Err(ToolError::Regex { .. })
        ));
        assert_eq!(
            s.describe(),
            "regex '/camera/.*|/tracker', excluding '/camera/debug.*'"
        );
        assert_eq!(l.describe(), "topics /a");
    }
}
