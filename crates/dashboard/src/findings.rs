//! Findings from other nodes: every DiagnosticStatus on `/diagnostics` whose name starts with
//! a prefix (`diagnose` by default), newest per name, in the order they first appeared.

use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use serde::Serialize;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    pub name: String,
    /// "OK", "WARN", "ERROR" or "STALE".
    pub level: &'static str,
    pub message: String,
    pub values: Vec<(String, String)>,
    /// Stamp of the array that carried it [s since the epoch].
    pub stamp: f64,
}

pub fn level_name(level: u8) -> &'static str {
    match level {
        0 => "OK",
        1 => "WARN",
        2 => "ERROR",
        3 => "STALE",
        _ => "UNKNOWN",
    }
}

#[derive(Clone, Debug)]
pub struct Findings {
    prefixes: Vec<String>,
    items: Vec<Finding>,
    max_items: usize,
}

impl Findings {
    /// Names are matched without a leading `/` (a node's status is named `/diagnose`).
    pub fn new(prefixes: Vec<String>, max_items: usize) -> Findings {
        Findings {
            prefixes: prefixes
                .into_iter()
                .map(|p| p.trim_start_matches('/').to_string())
                .collect(),
            items: Vec::new(),
            max_items,
        }
    }

    /// Returns how many statuses matched.
    pub fn push(&mut self, a: &DiagnosticArray) -> usize {
        let stamp = crate::stamp_seconds(&a.header.stamp);
        let mut matched = 0;
        for s in &a.status {
            let bare = s.name.trim_start_matches('/');
            if !self.prefixes.iter().any(|p| bare.starts_with(p.as_str())) {
                continue;
            }
            matched += 1;
            let f = Finding {
                name: s.name.clone(),
                level: level_name(s.level),
                message: s.message.clone(),
                values: s
                    .values
                    .iter()
                    .map(|kv| (kv.key.clone(), kv.value.clone()))
                    .collect(),
                stamp,
            };
            if let Some(existing) = self.items.iter_mut().find(|i| i.name == f.name) {
                *existing = f;
            } else if self.items.len() < self.max_items {
                self.items.push(f);
            }
        }
        matched
    }

    pub fn items(&self) -> &[Finding] {
        &self.items
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_msgs::diagnostic_msgs::msg::{DiagnosticStatus, KeyValue};

    fn array(statuses: &[(&str, u8, &str)]) -> DiagnosticArray {
        DiagnosticArray {
            status: statuses
                .iter()
                .map(|(n, l, m)| DiagnosticStatus {
                    name: n.to_string(),
                    level: *l,
                    message: m.to_string(),
                    values: vec![KeyValue {
                        key: "axis".into(),
                        value: "x".into(),
                    }],
                    ..Default::default()
                })
                .collect(),
            ..Default::default()
        }
    }

    #[test]
    fn only_prefixed_statuses_newest_per_name() {
        let mut f = Findings::new(vec!["diagnose".into()], 10);
        assert_eq!(
            f.push(&array(&[
                ("/thermal", 0, "running"),
                ("/diagnose", 1, "thermal_growth suspected")
            ])),
            1
        );
        f.push(&array(&[("diagnose: backlash", 2, "backlash 12 µm on X")]));
        f.push(&array(&[("/diagnose", 2, "thermal_growth fitted")]));
        let items = f.items();
        assert_eq!(items.len(), 2);
        assert_eq!(
            (
                items[0].name.as_str(),
                items[0].level,
                items[0].message.as_str()
            ),
            ("/diagnose", "ERROR", "thermal_growth fitted")
        );
        assert_eq!(items[1].values, vec![("axis".to_string(), "x".to_string())]);
    }
}
