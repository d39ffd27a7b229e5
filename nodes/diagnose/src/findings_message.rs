//! A diagnosis of the window as `/diagnostics` statuses, and which findings are new.
//!
//! One status per finding, named `diagnose: <term label>` (the dashboard lists statuses whose
//! name starts with `diagnose`), WARN, its message the metrologist's sentence and its values
//! the fitted parameters; one per unexplained structure (`diagnose: unexplained N`, WARN); and
//! a summary status `diagnose` (OK when the window is consistent with noise, WARN otherwise)
//! with the held-out figures before and after.

use std::collections::BTreeSet;

use metrocell_diagnose::Diagnosis;
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::diagnostic_msgs::msg::{DiagnosticArray, DiagnosticStatus, KeyValue};
use metrocell_msgs::std_msgs::msg::Header;

const OK: u8 = 0;
const WARN: u8 = 1;

fn kv(key: &str, value: impl ToString) -> KeyValue {
    KeyValue {
        key: key.into(),
        value: value.to_string(),
    }
}

/// What one run covered.
#[derive(Debug, Clone, PartialEq)]
pub struct RunInfo {
    /// Cell time of the window's first and last record [s since the epoch].
    pub from: f64,
    pub to: f64,
    pub run: u64,
}

/// The statuses of a diagnosis (module docs), stamped `stamp_ns`, from the node `hardware_id`.
pub fn diagnosis_message(
    d: &Diagnosis,
    info: &RunInfo,
    stamp_ns: i64,
    hardware_id: &str,
) -> DiagnosticArray {
    let r = &d.report;
    let mut status = Vec::new();
    let summary_level = if r.findings.is_empty() && r.unexplained.is_empty() && r.explained {
        OK
    } else {
        WARN
    };
    status.push(DiagnosticStatus {
        level: summary_level,
        name: "diagnose".into(),
        message: r.summary.clone(),
        hardware_id: hardware_id.into(),
        values: vec![
            kv("run", info.run),
            kv("window_h", format!("{:.2}", (info.to - info.from) / 3600.0)),
            kv("records_used", r.records.used),
            kv(
                "heldout_rms_before_um",
                format!("{:.2}", r.before.heldout_rms_m * 1e6),
            ),
            kv(
                "heldout_rms_after_um",
                format!("{:.2}", r.after.heldout_rms_m * 1e6),
            ),
            kv("noise_rms_um", format!("{:.2}", r.noise_rms_m * 1e6)),
            kv("explained", r.explained),
        ],
    });
    for f in &r.findings {
        let mut values = vec![kv("term", &f.term), kv("where", &f.location.description)];
        values.extend(f.parameters.iter().map(|(name, p)| {
            kv(
                name,
                match p.sigma {
                    Some(s) => format!("{} ± {} {}", p.value, s, p.unit),
                    None => format!("{} {}", p.value, p.unit),
                },
            )
        }));
        status.push(DiagnosticStatus {
            level: WARN,
            name: format!("diagnose: {}", f.label),
            message: f.statement.clone(),
            hardware_id: hardware_id.into(),
            values,
        });
    }
    for (k, u) in r.unexplained.iter().enumerate() {
        status.push(DiagnosticStatus {
            level: WARN,
            name: format!("diagnose: unexplained {}", k + 1),
            message: u.statement.clone(),
            hardware_id: hardware_id.into(),
            values: vec![kv("where", &u.location.description)],
        });
    }
    DiagnosticArray {
        header: Header {
            stamp: Time::from_nanos(stamp_ns),
            frame_id: String::new(),
        },
        status,
    }
}

/// The findings announced so far, by term label: a finding is new the first time its label
/// appears (a later window re-finding it with other values is not news).
#[derive(Debug, Default)]
pub struct Announced {
    labels: BTreeSet<String>,
}

impl Announced {
    /// The statements of the findings of `d` not announced before; they are announced now.
    pub fn new_findings(&mut self, d: &Diagnosis) -> Vec<String> {
        d.report
            .findings
            .iter()
            .filter(|f| self.labels.insert(f.label.clone()))
            .map(|f| format!("{}: {}", f.label, f.statement))
            .collect()
    }
}

/// The summary status of a window that could not be diagnosed yet (too few records, …).
pub fn waiting_message(message: &str, stamp_ns: i64, hardware_id: &str) -> DiagnosticArray {
    let status = DiagnosticStatus {
        level: OK,
        name: "diagnose".into(),
        message: message.into(),
        hardware_id: hardware_id.into(),
        values: Vec::new(),
    };
    DiagnosticArray {
        header: Header {
            stamp: Time::from_nanos(stamp_ns),
            frame_id: String::new(),
        },
        status: vec![status],
    }
}
