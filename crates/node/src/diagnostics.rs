//! The node's health as `diagnostic_msgs/DiagnosticArray` on `/diagnostics`: one status named
//! after the node's fully qualified name, a level (OK/WARN/ERROR), a message and key/values the
//! node updates (message counts, last residual, ...). The node runtime publishes it at 1 Hz.
//!
//! Inputs a node watches ([`Diagnostics::watch_input`]) get a status each, named
//! `<node>: <topic>`: OK while messages come, WARN once none came for longer than the input's
//! timeout (wall-clock: a stalled or vanished publisher is a process's problem, whatever the
//! simulated time) — so a silent input is reported within the timeout plus the heartbeat's
//! second, and said to have resumed when it does (`input_stalls` counts the silences).

use std::collections::BTreeMap;
use std::fmt::Display;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

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
    inputs: BTreeMap<String, WatchedInput>,
}

/// A watched input: its timeout, when it was last heard (or watched from), whether it is silent.
#[derive(Clone, Debug, PartialEq)]
struct WatchedInput {
    timeout: Duration,
    last: Instant,
    heard: bool,
    silent: bool,
}

/// Name of the parameter a node that watches its inputs declares ([`input_timeout_param`]).
pub const INPUT_TIMEOUT: &str = "input_timeout";

/// The `input_timeout` parameter: seconds (wall clock) of silence after which an input is
/// reported on `/diagnostics`; 0 (the default) watches nothing.
pub fn input_timeout_param() -> crate::ParamDecl {
    crate::ParamDecl::new(
        INPUT_TIMEOUT,
        0.0,
        "report an input topic on /diagnostics once it is silent for longer than this [s, wall clock]: a stalled or vanished publisher; 0: do not watch",
    )
    .with_range(0.0, 86400.0)
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
                inputs: BTreeMap::new(),
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

    /// Report `topic` when no message came on it for longer than `timeout` (see the module docs).
    pub fn watch_input(&self, topic: &str, timeout: Duration) {
        self.with(|s| {
            s.inputs.insert(
                topic.to_string(),
                WatchedInput {
                    timeout,
                    last: Instant::now(),
                    heard: false,
                    silent: false,
                },
            )
        });
    }

    /// A message came on the watched input `topic` (ignored if it is not watched).
    pub fn input_seen(&self, topic: &str) {
        self.with(|s| {
            if let Some(i) = s.inputs.get_mut(topic) {
                i.last = Instant::now();
                i.heard = true;
            }
        })
    }

    /// One status per watched input as of `now`; counts a new silence in `input_stalls`.
    fn input_statuses(&self, now: Instant) -> Vec<DiagnosticStatus> {
        self.with(|s| {
            let mut out = Vec::new();
            let mut new_stalls = 0;
            for (topic, i) in s.inputs.iter_mut() {
                let quiet = now.saturating_duration_since(i.last);
                let silent = quiet > i.timeout;
                if silent && !i.silent {
                    new_stalls += 1;
                }
                i.silent = silent;
                let (level, message) = if silent {
                    (
                        DiagnosticLevel::Warn,
                        format!(
                            "no message on {topic} for {:.1} s (input_timeout {:.1} s): {}",
                            quiet.as_secs_f64(),
                            i.timeout.as_secs_f64(),
                            if i.heard {
                                "its publisher stalled or went away"
                            } else {
                                "nothing has been published on it yet — is its publisher running, in this ROS domain?"
                            }
                        ),
                    )
                } else {
                    (DiagnosticLevel::Ok, "receiving".to_string())
                };
                out.push(DiagnosticStatus {
                    level: level.as_byte(),
                    name: format!("{}: {topic}", self.node_fqn),
                    message,
                    hardware_id: self.hardware_id.clone(),
                    values: vec![KeyValue {
                        key: "seconds_since_last_message".into(),
                        value: format!("{:.1}", quiet.as_secs_f64()),
                    }],
                });
            }
            if new_stalls > 0 {
                *s.counters.entry("input_stalls".into()).or_insert(0) += new_stalls;
            }
            out
        })
    }

    pub fn level(&self) -> DiagnosticLevel {
        self.with(|s| s.level)
    }

    /// The message the heartbeat publishes, stamped `stamp_ns` (ns since the Unix epoch).
    pub fn to_message(&self, stamp_ns: i64) -> DiagnosticArray {
        let inputs = self.input_statuses(Instant::now());
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
            status: std::iter::once(DiagnosticStatus {
                level: s.level.as_byte(),
                name: self.node_fqn.clone(),
                message: s.message,
                hardware_id: self.hardware_id.clone(),
                values,
            })
            .chain(inputs)
            .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_silent_input_is_warned_once_and_its_return_is_said() {
        let d = Diagnostics::new("/cell/thermal");
        d.watch_input("/measured_points", Duration::from_millis(50));
        let t0 = Instant::now();
        let at = |ms: u64| d.input_statuses(t0 + Duration::from_millis(ms));
        // never heard: silent after the timeout, and said so
        assert_eq!(at(10)[0].level, DiagnosticStatus::OK);
        let s = at(80);
        assert_eq!(s[0].level, DiagnosticStatus::WARN);
        assert!(
            s[0].message.contains("nothing has been published"),
            "{}",
            s[0].message
        );
        assert_eq!(s[0].name, "/cell/thermal: /measured_points");
        // still silent: one stall, not one per heartbeat
        at(120);
        d.input_seen("/measured_points");
        let heard = Instant::now();
        let s = d.input_statuses(heard);
        assert_eq!(
            (s[0].level, s[0].message.as_str()),
            (DiagnosticStatus::OK, "receiving")
        );
        let s = d.input_statuses(heard + Duration::from_millis(60));
        assert!(
            s[0].message.contains("stalled or went away"),
            "{}",
            s[0].message
        );
        let m = d.to_message(0);
        let stalls = m.status[0]
            .values
            .iter()
            .find(|kv| kv.key == "input_stalls")
            .map(|kv| kv.value.clone());
        assert_eq!(stalls.as_deref(), Some("2"));
        assert_eq!(m.status.len(), 2);
    }

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
