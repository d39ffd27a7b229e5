//! The node's health as `diagnostic_msgs/DiagnosticArray` on `/diagnostics`: one status named
//! after the node's fully qualified name, a level (OK/WARN/ERROR), a message and key/values the
//! node updates (message counts, last residual, ...). The node runtime publishes it at 1 Hz.

use std::collections::BTreeMap;
use std::fmt::Display;
use std::sync::{Arc, Mutex};

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::diagnostic_msgs::msg::{DiagnosticArray, DiagnosticStatus, KeyValue};
use metrocell_msgs::std_msgs::msg::Header;

/// Levels of `diagnostic_msgs/DiagnosticStatus`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum DiagnosticLevel {
    Ok,
    Warn,
    Error,
}

impl DiagnosticLevel {
    pub fn as_byte(self) -> u8 {
        match self {
            DiagnosticLevel::Ok => DiagnosticStatus::OK,
            DiagnosticLevel::Warn => DiagnosticStatus::WARN,
            DiagnosticLevel::Error => DiagnosticStatus::ERROR,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
struct State {
    level: DiagnosticLevel,
    message: String,
    values: BTreeMap<String, String>,
    counters: BTreeMap<String, u64>,
}

/// Shared, cloneable handle on the node's diagnostic status.
#[derive(Clone, Debug)]
pub struct Diagnostics {
    node_fqn: String,
    hardware_id: String,
    state: Arc<Mutex<State>>,
}

impl Diagnostics {
    pub fn new(node_fqn: &str) -> Diagnostics {
        Diagnostics {
            node_fqn: node_fqn.to_string(),
            hardware_id: String::new(),
            state: Arc::new(Mutex::new(State {
                level: DiagnosticLevel::Ok,
                message: "running".to_string(),
                values: BTreeMap::new(),
                counters: BTreeMap::new(),
            })),
        }
    }

    fn with<R>(&self, f: impl FnOnce(&mut State) -> R) -> R {
        f(&mut self.state.lock().unwrap_or_else(|p| p.into_inner()))
    }

    /// Set level and message.
    pub fn set_status(&self, level: DiagnosticLevel, message: impl Into<String>) {
        let message = message.into();
        self.with(|s| {
            s.level = level;
            s.message = message;
        })
    }
    pub fn ok(&self, message: impl Into<String>) {
        self.set_status(DiagnosticLevel::Ok, message)
    }
    pub fn warn(&self, message: impl Into<String>) {
        self.set_status(DiagnosticLevel::Warn, message)
    }
    pub fn error(&self, message: impl Into<String>) {
        self.set_status(DiagnosticLevel::Error, message)
    }

    /// Set a key/value shown with the status.
    pub fn set_value(&self, key: &str, value: impl Display) {
        let value = value.to_string();
        self.with(|s| s.values.insert(key.to_string(), value));
    }

    /// Add `n` to a counter (e.g. `messages_published`); returns the new count.
    pub fn add_count(&self, key: &str, n: u64) -> u64 {
        self.with(|s| {
            let c = s.counters.entry(key.to_string()).or_insert(0);
            *c += n;
            *c
        })
    }

    pub fn level(&self) -> DiagnosticLevel {
        self.with(|s| s.level)
    }

    /// The message the heartbeat publishes, stamped `stamp_ns` (ns since the Unix epoch).
    pub fn to_message(&self, stamp_ns: i64) -> DiagnosticArray {
        let s = self.with(|s| s.clone());
        let mut values: Vec<KeyValue> = s
            .counters
            .iter()
            .map(|(k, v)| KeyValue {
                key: k.clone(),
                value: v.to_string(),
            })
            .collect();
        values.extend(s.values.iter().map(|(k, v)| KeyValue {
            key: k.clone(),
            value: v.clone(),
        }));
        DiagnosticArray {
            header: Header {
                stamp: Time::from_nanos(stamp_ns),
                frame_id: String::new(),
            },
            status: vec![DiagnosticStatus {
                level: s.level.as_byte(),
                name: self.node_fqn.clone(),
                message: s.message,
                hardware_id: self.hardware_id.clone(),
                values,
            }],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn message_carries_name_level_and_values() {
        let d = Diagnostics::new("/cell/tracker");
        d.add_count("messages_published", 2);
        assert_eq!(d.add_count("messages_published", 3), 5);
        d.set_value("rate_hz", 20.5);
        d.warn("tracker warming up");
        let m = d.to_message(1_500_000_000_250_000_000);
        assert_eq!(
            (m.header.stamp.sec, m.header.stamp.nanosec),
            (1_500_000_000, 250_000_000)
        );
        let s = &m.status[0];
        assert_eq!(
            (s.name.as_str(), s.level, s.message.as_str()),
            ("/cell/tracker", 1, "tracker warming up")
        );
        let kv: Vec<(&str, &str)> = s
            .values
            .iter()
            .map(|k| (k.key.as_str(), k.value.as_str()))
            .collect();
        assert_eq!(kv, vec![("messages_published", "5"), ("rate_hz", "20.5")]);
    }
}
