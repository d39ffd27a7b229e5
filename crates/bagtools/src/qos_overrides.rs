//! The QoS overrides file of `ros2 bag record --qos-profile-overrides-path`: a YAML map from
//! topic name to the profile a recorder's reader of that topic uses instead of the one adapted
//! from the publishers' offers, e.g.
//!
//! ```yaml
//! /tracker/measurements:
//!   history: keep_last
//!   depth: 5000
//!   reliability: reliable
//!   durability: transient_local
//! ```
//!
//! `history` (`keep_last`, `keep_all`), `depth`, `reliability` (`reliable`, `best_effort`) and
//! `durability` (`volatile`, `transient_local`) are applied; `system_default` (or leaving a
//! key out) keeps the recorder's own choice. rosbag2's other keys (`deadline`, `lifespan`,
//! `liveliness`, `liveliness_lease_duration`, `avoid_ros_namespace_conventions`) are accepted
//! and listed in [`QosOverride::ignored`], since a recorder's reader gains nothing from them.

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{io, Result, ToolError};

/// History of a reader.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HistoryOverride {
    KeepLast(usize),
    KeepAll,
}

/// One topic's override; `None` = keep the recorder's own choice.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct QosOverride {
    pub history: Option<HistoryOverride>,
    pub reliable: Option<bool>,
    pub transient_local: Option<bool>,
    /// Keys of rosbag2's format that were present but are not applied.
    pub ignored: Vec<String>,
}

const IGNORED_KEYS: [&str; 5] = [
    "deadline",
    "lifespan",
    "liveliness",
    "liveliness_lease_duration",
    "avoid_ros_namespace_conventions",
];

/// Read the overrides file at `path`: topic name → override.
pub fn read_qos_overrides(path: &Path) -> Result<BTreeMap<String, QosOverride>> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    parse_qos_overrides(&text).map_err(|reason| ToolError::Mapping {
        path: path.to_path_buf(),
        reason,
    })
}

/// Parse the overrides YAML; the error names the topic and key at fault.
pub fn parse_qos_overrides(
    text: &str,
) -> std::result::Result<BTreeMap<String, QosOverride>, String> {
    let doc: serde_yaml::Value =
        serde_yaml::from_str(text).map_err(|e| format!("not YAML: {e}"))?;
    let map = match doc {
        serde_yaml::Value::Null => return Ok(BTreeMap::new()),
        serde_yaml::Value::Mapping(m) => m,
        _ => return Err("expected a map from topic names to QoS profiles".into()),
    };
    let mut out = BTreeMap::new();
    for (topic, profile) in map {
        let topic = topic
            .as_str()
            .ok_or("topic names must be strings")?
            .to_string();
        if !topic.starts_with('/') {
            return Err(format!(
                "topic {topic:?}: give the full name, starting with '/'"
            ));
        }
        let serde_yaml::Value::Mapping(profile) = profile else {
            return Err(format!("{topic}: expected a map of QoS policies"));
        };
        let mut o = QosOverride::default();
        let mut keep_all = false;
        let mut depth = None;
        for (key, value) in profile {
            let key = key
                .as_str()
                .ok_or_else(|| format!("{topic}: policy names must be strings"))?;
            let word = || {
                value
                    .as_str()
                    .map(str::to_ascii_lowercase)
                    .ok_or_else(|| format!("{topic}: {key} must be a word, got {value:?}"))
            };
            match key {
                "history" => match word()?.as_str() {
                    "keep_last" => keep_all = false,
                    "keep_all" => keep_all = true,
                    "system_default" => {}
                    other => return Err(format!("{topic}: history '{other}' is not keep_last, keep_all or system_default")),
                },
                "depth" => {
                    let d = value.as_u64().filter(|d| *d >= 1 && *d <= 1_000_000).ok_or_else(|| format!("{topic}: depth must be an integer from 1 to 1000000, got {value:?}"))?;
                    depth = Some(d as usize);
                }
                "reliability" => {
                    o.reliable = match word()?.as_str() {
                        "reliable" => Some(true),
                        "best_effort" => Some(false),
                        "system_default" => None,
                        other => return Err(format!("{topic}: reliability '{other}' is not reliable, best_effort or system_default")),
                    }
                }
                "durability" => {
                    o.transient_local = match word()?.as_str() {
                        "transient_local" => Some(true),
                        "volatile" => Some(false),
                        "system_default" => None,
                        other => return Err(format!("{topic}: durability '{other}' is not volatile, transient_local or system_default")),
                    }
                }
                k if IGNORED_KEYS.contains(&k) => o.ignored.push(k.to_string()),
                other => return Err(format!("{topic}: unknown QoS policy '{other}'")),
            }
        }
        o.history = match (keep_all, depth) {
            (true, _) => Some(HistoryOverride::KeepAll),
            (false, Some(d)) => Some(HistoryOverride::KeepLast(d)),
            (false, None) => None,
        };
        out.insert(topic, o);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rosbag2_overrides_parse_and_errors_name_topic_and_key() {
        let text = "/a:\n  history: keep_last\n  depth: 500\n  reliability: best_effort\n  durability: transient_local\n\
/b:\n  history: keep_all\n  reliability: system_default\n  deadline: {sec: 1, nsec: 0}\n";
        let o = parse_qos_overrides(text).unwrap();
        assert_eq!(
            o["/a"],
            QosOverride {
                history: Some(HistoryOverride::KeepLast(500)),
                reliable: Some(false),
                transient_local: Some(true),
                ignored: vec![]
            }
        );
        assert_eq!(
            o["/b"],
            QosOverride {
                history: Some(HistoryOverride::KeepAll),
                reliable: None,
                transient_local: None,
                ignored: vec!["deadline".into()]
            }
        );
        assert!(parse_qos_overrides("").unwrap().is_empty());
        let e = parse_qos_overrides("/a:\n  reliability: sometimes\n").unwrap_err();
        assert!(e.contains("/a") && e.contains("sometimes"), "{e}");
        let e = parse_qos_overrides("/a:\n  depth: 0\n").unwrap_err();
        assert!(e.contains("/a") && e.contains("depth"), "{e}");
        let e = parse_qos_overrides("/a:\n  colour: red\n").unwrap_err();
        assert!(e.contains("colour"), "{e}");
        assert!(parse_qos_overrides("a:\n  depth: 3\n")
            .unwrap_err()
            .contains("'/'"));
    }
}
