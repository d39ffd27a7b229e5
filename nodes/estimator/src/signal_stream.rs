//! Signals at a measurement's time from the live streams (commanded joints, temperatures), by
//! interpolation between the samples that bracket it — the online counterpart of building
//! records from a bag. Everything runs on the messages' header stamps (the time the machine or
//! the sensor was in that state, which a recording keeps), so live and replay see the same
//! numbers whatever the arrival interleaving across topics.
//!
//! Conventions (stated once): time in s since the Unix epoch; joints in the machine family's
//! order (`MachineGeometry::joint_names`), m or rad; velocity = the samples' own velocity field
//! when present, else the difference quotient of the bracketing samples; approach direction of a
//! joint = sign of its last non-zero motion at or before the instant (+1 before any motion);
//! temperatures in °C, linear between bracketing readings; a lagged term reads the sensor's
//! history up to the instant from one shared `TemperatureTimeline` (no copy per instant).

use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

use metrocell_physics::{Signals, TemperatureTimeline};

/// Motion smaller than this between two samples is standing still (m or rad): below any
/// commanded step, above the float noise of a recorded position.
const STILL: f64 = 1e-9;

/// One commanded-joint sample with the approach direction in force at it.
#[derive(Debug, Clone, PartialEq)]
struct JointSample {
    time: f64,
    q: Vec<f64>,
    velocity: Option<Vec<f64>>,
    approach: Vec<f64>,
}

/// Why a signal could not be given at an instant.
#[derive(Debug, Clone, PartialEq)]
pub enum SignalGap {
    /// No commanded joint sample at or before the instant.
    NoJoints,
    /// A sensor has no reading at or before the instant.
    NoTemperature(String),
}

impl std::fmt::Display for SignalGap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SignalGap::NoJoints => write!(f, "no commanded joint state at or before it (topic machine/commanded_joint_states)"),
            SignalGap::NoTemperature(s) => write!(f, "no reading of temperature/{s} at or before it"),
        }
    }
}

/// The streams, kept from a little before the oldest instant still to be asked for.
#[derive(Debug, Clone)]
pub struct SignalStream {
    joints: VecDeque<JointSample>,
    joint_count: usize,
    /// Sensor → readings (stamp s, °C), increasing in time.
    temperatures: BTreeMap<String, Vec<(f64, f64)>>,
    /// Sensors whose whole history a term needs (lags); others keep only what interpolation needs.
    keep_history: Vec<String>,
    /// The whole history of the `keep_history` sensors, shared with every instant's signals.
    timeline: Arc<TemperatureTimeline>,
    power_on_time: Option<f64>,
}

impl SignalStream {
    /// `sensors`: every temperature sensor a term reads; `history_sensors`: those read through a
    /// lag; `power_on_time`: when the instrument was switched on (s), if known.
    pub fn new(joint_count: usize, sensors: &[String], history_sensors: &[String], power_on_time: Option<f64>) -> Self {
        Self {
            joints: VecDeque::new(),
            joint_count,
            temperatures: sensors.iter().map(|s| (s.clone(), Vec::new())).collect(),
            keep_history: history_sensors.to_vec(),
            timeline: Arc::new(TemperatureTimeline::new()),
            power_on_time,
        }
    }

    /// Add a commanded joint sample (joint order of the family). Samples not later than the
    /// last are ignored (a stream goes forward), returning false.
    pub fn joints(&mut self, time: f64, q: Vec<f64>, velocity: Option<Vec<f64>>) -> bool {
        if q.len() != self.joint_count || !time.is_finite() || !q.iter().all(|v| v.is_finite()) {
            return false;
        }
        let approach = match self.joints.back() {
            Some(last) if time <= last.time => return false,
            Some(last) => motion_sign(&last.q, &q, &last.approach),
            None => vec![1.0; q.len()],
        };
        self.joints.push_back(JointSample { time, q, velocity: velocity.filter(|v| v.len() == self.joint_count), approach });
        true
    }

    /// Add a temperature reading; false when the sensor is not read by the model or the stamp is
    /// not later than the previous reading's.
    pub fn temperature(&mut self, sensor: &str, time: f64, celsius: f64) -> bool {
        let Some(h) = self.temperatures.get_mut(sensor) else { return false };
        if !(time.is_finite() && celsius.is_finite()) || h.last().is_some_and(|l| time <= l.0) {
            return false;
        }
        h.push((time, celsius));
        if self.keep_history.iter().any(|s| s == sensor) {
            // the stamp was checked to increase just above, so the timeline accepts it
            self.timeline.push(sensor, time, celsius).expect("increasing, finite sample");
        }
        true
    }

    /// Whether every stream has a sample at or after `time`: then the signals at `time` are
    /// final (no later message can change them).
    pub fn covers(&self, time: f64) -> bool {
        self.joints.back().is_some_and(|j| j.time >= time) && self.temperatures.values().all(|h| h.last().is_some_and(|r| r.0 >= time))
    }

    /// The newest stamp of any stream.
    pub fn newest(&self) -> Option<f64> {
        let j = self.joints.back().map(|j| j.time);
        self.temperatures.values().filter_map(|h| h.last().map(|r| r.0)).chain(j).reduce(f64::max)
    }

    /// Commanded joints, their velocity and approach direction, and the signals at `time`.
    /// After the last sample of a stream its last value holds.
    pub fn at(&self, time: f64) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>, Signals), SignalGap> {
        let (q, velocity, approach) = self.joints_at(time).ok_or(SignalGap::NoJoints)?;
        let mut s = Signals::default();
        for (name, h) in &self.temperatures {
            let t = interpolate(h, time).ok_or_else(|| SignalGap::NoTemperature(name.clone()))?;
            s.temperatures.insert(name.clone(), t);
        }
        if !self.keep_history.is_empty() {
            s.timeline = Some(self.timeline.clone());
            s.time = Some(time);
        }
        s.time_since_power_on = self.power_on_time.map(|t0| time - t0);
        Ok((q, velocity, approach, s))
    }

    fn joints_at(&self, time: f64) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let after = self.joints.partition_point(|j| j.time <= time);
        let a = self.joints.get(after.checked_sub(1)?)?;
        let Some(b) = self.joints.get(after) else {
            let v = a.velocity.clone().unwrap_or_else(|| vec![0.0; a.q.len()]);
            return Some((a.q.clone(), v, a.approach.clone()));
        };
        let f = (time - a.time) / (b.time - a.time);
        let q: Vec<f64> = a.q.iter().zip(&b.q).map(|(x, y)| x + f * (y - x)).collect();
        let velocity = match (&a.velocity, &b.velocity) {
            (Some(va), Some(vb)) => va.iter().zip(vb).map(|(x, y)| x + f * (y - x)).collect(),
            _ => a.q.iter().zip(&b.q).map(|(x, y)| (y - x) / (b.time - a.time)).collect(),
        };
        let approach = motion_sign(&a.q, &q, &a.approach);
        Some((q, velocity, approach))
    }

    /// Forget what no instant at or after `time` needs: joint samples before the one bracketing
    /// it, and readings before theirs (a lagged sensor's whole history stays in the timeline).
    pub fn forget_before(&mut self, time: f64) {
        while self.joints.len() > 1 && self.joints[1].time <= time {
            self.joints.pop_front();
        }
        for h in self.temperatures.values_mut() {
            let keep_from = h.partition_point(|r| r.0 <= time).saturating_sub(1);
            h.drain(..keep_from);
        }
    }
}

/// Sign of the motion from `from` to `to` per joint, or the previous sign where it stood still.
fn motion_sign(from: &[f64], to: &[f64], previous: &[f64]) -> Vec<f64> {
    from.iter()
        .zip(to)
        .zip(previous)
        .map(|((a, b), p)| if (b - a).abs() > STILL { (b - a).signum() } else { *p })
        .collect()
}

/// Linear interpolation of (time, value) samples at `t`; the last value after the end; None
/// before the first sample.
fn interpolate(h: &[(f64, f64)], t: f64) -> Option<f64> {
    let after = h.partition_point(|r| r.0 <= t);
    let a = h.get(after.checked_sub(1)?)?;
    Some(match h.get(after) {
        Some(b) => a.1 + (t - a.0) / (b.0 - a.0) * (b.1 - a.1),
        None => a.1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stream() -> SignalStream {
        let mut s = SignalStream::new(3, &["column".into(), "x_left".into()], &["column".into()], Some(100.0));
        // x moves +0.1 m over 1 s, stands, then moves back
        assert!(s.joints(1000.0, vec![0.0, 0.2, 0.1], None));
        assert!(s.joints(1001.0, vec![0.1, 0.2, 0.1], None));
        assert!(s.joints(1002.0, vec![0.1, 0.2, 0.1], None));
        assert!(s.joints(1003.0, vec![0.05, 0.2, 0.1], None));
        for (k, t) in [999.5, 1000.5, 1001.5, 1002.5, 1003.5].iter().enumerate() {
            assert!(s.temperature("column", *t, 20.0 + k as f64));
            assert!(s.temperature("x_left", *t, 21.0));
        }
        s
    }

    #[test]
    fn positions_velocity_and_temperatures_interpolate_between_bracketing_samples() {
        let s = stream();
        let (q, v, approach, sig) = s.at(1000.25).unwrap();
        assert!((q[0] - 0.025).abs() < 1e-15 && q[1] == 0.2);
        assert!((v[0] - 0.1).abs() < 1e-12 && v[1] == 0.0);
        assert_eq!(approach, vec![1.0, 1.0, 1.0]);
        // column: 21 °C at 1000.5, 20 °C at 999.5 → 20.75 at 1000.25
        assert!((sig.temperatures["column"] - 20.75).abs() < 1e-12);
        let timeline = sig.timeline.as_ref().expect("a lagged sensor gives the timeline");
        assert_eq!(sig.time, Some(1000.25));
        assert_eq!(timeline.history("column", sig.time).unwrap().samples, vec![(999.5, 20.0)]);
        assert!(!timeline.contains("x_left"), "only lagged sensors go to the timeline");
        assert_eq!(sig.time_since_power_on, Some(900.25));
    }

    #[test]
    fn approach_is_the_sign_of_the_last_motion_and_holds_while_standing() {
        let s = stream();
        assert_eq!(s.at(1001.5).unwrap().2[0], 1.0, "standing after moving +x");
        assert_eq!(s.at(1002.5).unwrap().2[0], -1.0, "moving back");
        assert_eq!(s.at(1005.0).unwrap().2[0], -1.0, "after the last sample the last direction holds");
    }

    #[test]
    fn coverage_gaps_and_forgetting() {
        let mut s = stream();
        assert!(s.covers(1003.0) && !s.covers(1003.2), "joints end at 1003");
        assert_eq!(s.at(999.0).unwrap_err(), SignalGap::NoJoints);
        let mut t = SignalStream::new(3, &["column".into()], &[], None);
        t.joints(10.0, vec![0.0; 3], None);
        assert_eq!(t.at(10.0).unwrap_err(), SignalGap::NoTemperature("column".into()));
        assert!(!s.joints(1003.0, vec![0.0; 3], None), "a sample not later than the last is ignored");
        assert!(!s.temperature("unknown", 2000.0, 20.0));
        let (q, v, a, sig) = s.at(1002.5).unwrap();
        s.forget_before(1002.5);
        let (q2, v2, a2, sig2) = s.at(1002.5).unwrap();
        assert_eq!((q, v, a, sig.temperatures), (q2, v2, a2, sig2.temperatures), "forgetting keeps what later instants need");
        assert_eq!(s.joints.len(), 2);
        assert_eq!(s.temperatures["x_left"].len(), 2);
        assert_eq!(s.temperatures["column"].len(), 2);
        assert_eq!(s.timeline.sample_count("column"), Some(5), "a lagged sensor keeps its history");
    }
}
