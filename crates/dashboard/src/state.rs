//! Everything the dashboard shows, fed message by message and read as one JSON snapshot
//! (`/api/state` and each WebSocket push).
//!
//! Time: the cell time is the newest `/clock` when one is received (sim time, `bag play
//! --clock`), otherwise the newest message stamp; series are kept on message stamps. So a bag
//! replay shows the drift of the recorded shift, not of the replay.

use std::collections::BTreeMap;

use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use serde::Serialize;

use crate::alerts::{evaluate, Alert, AlertThresholds};
use crate::error_model::{model_view, ModelView};
use crate::findings::{Finding, Findings};
use crate::temperatures::{SensorSummary, Temperatures};
use crate::tracker::{TrackerStatus, TrackerSummary};
use crate::volumetric::{VolumetricError, VolumetricSummary};
use crate::{stamp_seconds, InputError};

#[derive(Clone, Debug, PartialEq)]
pub struct StateConfig {
    /// Drift window [s] of cell time.
    pub window: f64,
    /// Samples kept per series (memory bound over a long shift).
    pub max_samples: usize,
    /// Points per plotted series in a snapshot.
    pub plot_points: usize,
    pub thresholds: AlertThresholds,
    /// DiagnosticStatus name prefixes shown as findings.
    pub finding_prefixes: Vec<String>,
}

#[derive(Clone, Debug)]
pub struct DashboardState {
    config: StateConfig,
    clock: Option<f64>,
    newest_stamp: Option<f64>,
    temperatures: Temperatures,
    tracker: TrackerStatus,
    models: BTreeMap<String, ModelView>,
    volumetric: BTreeMap<String, VolumetricError>,
    findings: Findings,
    messages: BTreeMap<String, u64>,
    rejected: BTreeMap<String, (u64, String)>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StreamSummary {
    pub topic: String,
    #[serde(flatten)]
    pub summary: VolumetricSummary,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Rejected {
    pub topic: String,
    pub count: u64,
    pub last_error: String,
}

/// The JSON the page and `/api/state` get. SI units throughout (m, m/s, °C, K/s, s).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Snapshot {
    /// Cell time [s since the epoch]: `/clock` or the newest stamp; null before any message.
    pub cell_time: Option<f64>,
    /// Whether cell_time comes from `/clock`.
    pub sim_clock: bool,
    pub volumetric: Vec<StreamSummary>,
    pub temperatures: Vec<SensorSummary>,
    pub tracker: Option<TrackerSummary>,
    pub error_models: Vec<ModelView>,
    pub findings: Vec<Finding>,
    pub alerts: Vec<Alert>,
    pub thresholds: AlertThresholds,
    pub window: f64,
    pub messages: BTreeMap<String, u64>,
    pub rejected: Vec<Rejected>,
}

impl DashboardState {
    pub fn new(config: StateConfig) -> DashboardState {
        DashboardState {
            temperatures: Temperatures::new(config.window, config.max_samples),
            findings: Findings::new(config.finding_prefixes.clone(), 200),
            config,
            clock: None,
            newest_stamp: None,
            tracker: TrackerStatus::default(),
            models: BTreeMap::new(),
            volumetric: BTreeMap::new(),
            messages: BTreeMap::new(),
            rejected: BTreeMap::new(),
        }
    }

    fn seen(&mut self, topic: &str, stamp: f64) {
        *self.messages.entry(topic.to_string()).or_insert(0) += 1;
        // a zero stamp means "not stamped": it must not move the cell time back to 1970
        if stamp > 0.0 && self.newest_stamp.is_none_or(|t| stamp > t) {
            self.newest_stamp = Some(stamp);
        }
    }

    fn checked(&mut self, topic: &str, r: Result<(), InputError>) -> Result<(), InputError> {
        if let Err(e) = &r {
            let entry = self
                .rejected
                .entry(topic.to_string())
                .or_insert((0, String::new()));
            entry.0 += 1;
            entry.1 = e.to_string();
        }
        r
    }

    /// A message of `topic` that could not be decoded at all.
    pub fn undecodable(&mut self, topic: &str, error: &str) {
        let entry = self
            .rejected
            .entry(topic.to_string())
            .or_insert((0, String::new()));
        entry.0 += 1;
        entry.1 = error.to_string();
    }

    pub fn clock(&mut self, topic: &str, nanos: i64) {
        *self.messages.entry(topic.to_string()).or_insert(0) += 1;
        self.clock = Some(crate::nanos_seconds(nanos));
    }

    pub fn measured_point(&mut self, topic: &str, p: &MeasuredPoint) -> Result<(), InputError> {
        self.seen(topic, stamp_seconds(&p.header.stamp));
        let (window, max) = (self.config.window, self.config.max_samples);
        let r = self
            .volumetric
            .entry(topic.to_string())
            .or_insert_with(|| VolumetricError::new(window, max))
            .push(p);
        self.checked(topic, r)
    }

    pub fn temperature(
        &mut self,
        topic: &str,
        sensor: &str,
        t: &Temperature,
    ) -> Result<(), InputError> {
        self.seen(topic, stamp_seconds(&t.header.stamp));
        let r = self.temperatures.push(sensor, t);
        self.checked(topic, r)
    }

    pub fn tracker(&mut self, topic: &str, m: &TrackerMeasurement) {
        self.seen(topic, stamp_seconds(&m.header.stamp));
        self.tracker.push(m);
    }

    pub fn error_model(&mut self, topic: &str, m: &ErrorModel) -> Result<(), InputError> {
        self.seen(topic, stamp_seconds(&m.header.stamp));
        let r = model_view(topic, m).map(|v| {
            self.models.insert(topic.to_string(), v);
        });
        self.checked(topic, r)
    }

    pub fn diagnostics(&mut self, topic: &str, a: &DiagnosticArray) {
        *self.messages.entry(topic.to_string()).or_insert(0) += 1;
        self.findings.push(a);
    }

    pub fn cell_time(&self) -> Option<f64> {
        self.clock.or(self.newest_stamp)
    }

    /// The alerts of every measured-point stream, in topic order.
    pub fn alerts(&self) -> Vec<Alert> {
        self.volumetric
            .iter()
            .filter_map(|(topic, v)| Some(evaluate(topic, &v.summary(2)?, &self.config.thresholds)))
            .flatten()
            .collect()
    }

    pub fn snapshot(&self) -> Snapshot {
        let n = self.config.plot_points;
        Snapshot {
            cell_time: self.cell_time(),
            sim_clock: self.clock.is_some(),
            volumetric: self
                .volumetric
                .iter()
                .filter_map(|(topic, v)| {
                    Some(StreamSummary {
                        topic: topic.clone(),
                        summary: v.summary(n)?,
                    })
                })
                .collect(),
            temperatures: self.temperatures.summary(n),
            tracker: self.tracker.summary(),
            error_models: self.models.values().cloned().collect(),
            findings: self.findings.items().to_vec(),
            alerts: self.alerts(),
            thresholds: self.config.thresholds,
            window: self.config.window,
            messages: self.messages.clone(),
            rejected: self
                .rejected
                .iter()
                .map(|(t, (c, e))| Rejected {
                    topic: t.clone(),
                    count: *c,
                    last_error: e.clone(),
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::alerts::Level;
    use crate::volumetric::tests::point;

    fn state() -> DashboardState {
        DashboardState::new(StateConfig {
            window: 3600.0,
            max_samples: 5000,
            plot_points: 100,
            thresholds: AlertThresholds::from_um(20.0, 50.0, 10.0, 30.0, 2.0, 600.0).unwrap(),
            finding_prefixes: vec!["diagnose".into()],
        })
    }

    #[test]
    fn snapshot_tracks_cell_time_streams_and_alerts() {
        let mut s = state();
        assert_eq!(s.snapshot().cell_time, None);
        // raw points drift 40 µm/h on x; compensated points stay at 1 µm
        for k in 0..=120 {
            let t = 1.0e9 + 30.0 * k as f64;
            let h = 30.0 * k as f64 / 3600.0;
            s.measured_point(
                "/measured_points",
                &point(t, [0.5, 0.0, 0.0], [40e-6 * h, 0.0, 0.0]),
            )
            .unwrap();
            s.measured_point(
                "/measured_points/thermal_compensated",
                &point(t, [0.5, 0.0, 0.0], [1e-6, 0.0, 0.0]),
            )
            .unwrap();
        }
        let snap = s.snapshot();
        assert_eq!(snap.cell_time, Some(1.0e9 + 3600.0));
        assert!(!snap.sim_clock);
        assert_eq!(snap.volumetric.len(), 2);
        let levels: Vec<(String, Level)> = snap
            .alerts
            .iter()
            .map(|a| (a.name.clone(), a.level))
            .collect();
        assert_eq!(
            levels,
            vec![
                ("volumetric_error /measured_points".to_string(), Level::Warn),
                ("drift_rate /measured_points".to_string(), Level::Error),
                (
                    "volumetric_error /measured_points/thermal_compensated".to_string(),
                    Level::Ok
                ),
                (
                    "drift_rate /measured_points/thermal_compensated".to_string(),
                    Level::Ok
                ),
            ]
        );
        s.clock("/clock", 1_000_005_000_000_000_000);
        assert_eq!(s.snapshot().cell_time, Some(1.000005e9));
        // the snapshot serialises and carries SI numbers the page reads
        let json = serde_json::to_value(s.snapshot()).unwrap();
        let drift = json["volumetric"][0]["axes"][0]["drift"].as_f64().unwrap();
        assert!((drift * 3600.0 - 40e-6).abs() < 1e-12);
        assert_eq!(json["messages"]["/measured_points"], 121);
    }

    #[test]
    fn bad_messages_are_counted_with_the_reason() {
        let mut s = state();
        let mut p = point(1.0, [0.0; 3], [0.0; 3]);
        p.nominal.z = f64::INFINITY;
        assert!(s.measured_point("/measured_points", &p).is_err());
        s.undecodable("/temperature/x_left", "truncated");
        let r = s.snapshot().rejected;
        assert_eq!(r.len(), 2);
        assert_eq!(
            (r[0].topic.as_str(), r[0].count, r[0].last_error.as_str()),
            ("/measured_points", 1, "nominal.z is inf")
        );
        assert!(s.snapshot().volumetric.is_empty());
    }
}
