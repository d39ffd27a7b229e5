//! The node's logic, shared by the live run and the bag replay. Time is the readings' own
//! stamps (and the commanded states'), never the wall clock, so a replay makes the same
//! decisions as the live run that was recorded.
//!
//! Per reading: refraction re-correction and covariance (or a beam break / rejection, counted).
//! Per dwell (consecutive readings of one target): average and standard error, the χ²
//! turbulence test, the warm-up fit when the target is the warm-up nest, the nominal from the
//! commanded joint states at the dwell's mid time, and — once the tracker pose is registered
//! from the first `registration_points` targets — the point in the machine frame.

use std::collections::BTreeMap;

use metrocell_compensation::{to_spherical, AirData};
use metrocell_laser_tracker::dwell::DwellAverage;
use metrocell_laser_tracker::line_protocol::LineReading;
use metrocell_laser_tracker::reading::{RawReading, ReadingError};
use metrocell_laser_tracker::registration::{register, Correspondence, Registration};
use metrocell_laser_tracker::time_alignment::CommandedTrajectory;
use metrocell_laser_tracker::warmup::{WarmupSample, WarmupTracker};
use metrocell_laser_tracker::DwellGrouper;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::sensor_msgs::msg::JointState;
use nalgebra::{Matrix3, Vector3};

use crate::messages;
use crate::parameters::TrackerConfig;

/// What the node publishes.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// `measured_points`
    Point(MeasuredPoint),
    /// `tracker/dwells`: the averaged, flagged reading of a dwell (tracker frame)
    Dwell(TrackerMeasurement),
    /// `/tf_static` and `tracker/pose`, stamped at the mid time of the dwell that completed it
    Pose(Registration, i64),
    /// `tracker/warmup`
    Warmup(ErrorModel),
    /// something to log as a warning (not published)
    Warning(String),
}

/// Counters for `/diagnostics`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Counters {
    pub readings: u64,
    pub beam_breaks: u64,
    pub rejected: u64,
    pub dwells: u64,
    pub short_dwells: u64,
    pub turbulence_flags: u64,
    pub points: u64,
    pub no_nominal: u64,
}

/// Longest a dwell waits, in message time, for the commanded state after its mid time. The
/// readings and the commanded states come through separate DDS readers: a commanded sample lost
/// on the wire is resent only after the writer's next heartbeat, and the readings that close the
/// dwell may be processed first. A minute covers that at any replay speed a twin or bag is played
/// (160× turns 0.4 s of wall clock into a minute); a commanded stream that stopped for good makes
/// dwells fall back to the program's timing, or go without nominal, after this.
const COMMANDED_WAIT_NS: i64 = 60_000_000_000;

/// A dwell averaged and flagged, waiting for the commanded state after its mid time.
#[derive(Debug, Clone)]
struct AwaitingNominal {
    target: String,
    mid_ns: i64,
    point: Vector3<f64>,
    covariance: Matrix3<f64>,
    flagged: bool,
}

/// A dwell waiting for the tracker pose.
#[derive(Debug, Clone)]
struct PendingPoint {
    target: String,
    stamp_ns: i64,
    point: Vector3<f64>,
    covariance: Matrix3<f64>,
    nominal: Vector3<f64>,
}

pub struct TrackerState {
    config: TrackerConfig,
    grouper: DwellGrouper,
    commanded: CommandedTrajectory,
    warmup: WarmupTracker,
    power_on_ns: Option<i64>,
    pose: Option<Registration>,
    collected: BTreeMap<String, Correspondence>,
    /// Dwells per target while the pose is not registered (how many cycles the program ran).
    visits: BTreeMap<String, u64>,
    /// The program came back to a target before `registration_points` distinct ones were
    /// collected, and the node said so.
    registration_stalled: bool,
    pending: Vec<PendingPoint>,
    /// Dwells whose nominal waits for the commanded states (in dwell order).
    awaiting: std::collections::VecDeque<AwaitingNominal>,
    last_warmup: Option<(f64, bool)>,
    station_air: (Option<f64>, Option<f64>, Option<f64>),
    pub counters: Counters,
}

impl TrackerState {
    pub fn new(config: TrackerConfig) -> Self {
        Self {
            grouper: DwellGrouper::new(config.dwell_gap_ns),
            // Commanded history, in message time. Live, the readings and the commanded states
            // come through separate reader queues and the readings may be processed well behind
            // the states (a backlog after a stall; a twin or bag played at 100× and more turns a
            // wall-clock second into minutes): a dwell must still find the states around it. Ten
            // minutes (60 000 states at 100 Hz) covers the readings queue (qos::STREAM_DEPTH) at
            // the rates the cells use; one minute did not (dwells without nominal at 240×).
            commanded: CommandedTrajectory::new(600_000_000_000, config.commanded_gap_ns),
            warmup: WarmupTracker::new(),
            power_on_ns: config.power_on_ns,
            pose: None,
            collected: BTreeMap::new(),
            visits: BTreeMap::new(),
            registration_stalled: false,
            pending: Vec::new(),
            awaiting: std::collections::VecDeque::new(),
            last_warmup: None,
            station_air: (None, None, None),
            counters: Counters::default(),
            config,
        }
    }

    pub fn config(&self) -> &TrackerConfig {
        &self.config
    }

    pub fn pose(&self) -> Option<&Registration> {
        self.pose.as_ref()
    }

    /// A `tracker/measurements` message (topic backend, bag replay).
    pub fn measurement(&mut self, m: &TrackerMeasurement) -> Vec<Output> {
        let air = if self.config.air_from_topics {
            self.latest_station_air()
        } else {
            Some(AirData {
                temperature: m.air_temperature,
                pressure: m.air_pressure,
                humidity: m.air_humidity,
            })
        };
        let raw = RawReading {
            time_ns: m.header.stamp.nanos(),
            target: m.target_id.clone(),
            range: m.range,
            azimuth: m.azimuth,
            elevation: m.elevation,
            refractive_index: m.refractive_index,
            air,
            status: m.status,
        };
        self.reading(&raw)
    }

    /// A point of a CSV export imported through the `bag import` layout (tracker frame,
    /// Cartesian, ranges divided by `instrument_refractive_index`), with the latest station air.
    pub fn imported_point(&mut self, p: &MeasuredPoint) -> Vec<Output> {
        let (range, azimuth, elevation) =
            to_spherical(&Vector3::new(p.measured.x, p.measured.y, p.measured.z));
        let air = self.latest_station_air();
        let raw = RawReading {
            time_ns: p.header.stamp.nanos(),
            target: p.point_id.clone(),
            range,
            azimuth,
            elevation,
            refractive_index: self.config.instrument_index,
            air,
            status: 0,
        };
        self.reading(&raw)
    }

    /// The weather station's latest complete air (topics, or an imported export's columns).
    fn latest_station_air(&self) -> Option<AirData> {
        match self.station_air {
            (Some(temperature), Some(pressure), Some(humidity)) => Some(AirData {
                temperature,
                pressure,
                humidity,
            }),
            _ => None,
        }
    }

    /// Weather-station air: temperature (°C), pressure (Pa), relative humidity (0..1); None leaves a value as it was.
    pub fn station_air(
        &mut self,
        temperature: Option<f64>,
        pressure: Option<f64>,
        humidity: Option<f64>,
    ) {
        let a = &mut self.station_air;
        a.0 = temperature.or(a.0);
        a.1 = pressure.or(a.1);
        a.2 = humidity.or(a.2);
    }

    /// A line from the TCP instrument.
    pub fn line(&mut self, l: &LineReading) -> Vec<Output> {
        let raw = l.to_raw(self.config.instrument_index);
        self.reading(&raw)
    }

    pub fn reading(&mut self, raw: &RawReading) -> Vec<Output> {
        self.counters.readings += 1;
        self.power_on_ns
            .get_or_insert(raw.time_ns - self.config.warmup_elapsed_at_first_ns);
        let mut out = Vec::new();
        // dwells that waited their full time for the commanded states go without them; newer
        // ones keep waiting
        self.resolve_awaiting(raw.time_ns - COMMANDED_WAIT_NS, &mut out);
        // a silence closes the open dwell even when this reading is rejected
        if let Some(d) = self.grouper.close_if_stale(raw.time_ns) {
            out.extend(self.dwell(d));
        }
        match self.config.processor.process(raw) {
            Ok(p) => {
                if let Some(d) = self.grouper.push(p) {
                    out.extend(self.dwell(d));
                }
            }
            Err(ReadingError::BeamBreak(_)) => self.counters.beam_breaks += 1,
            Err(e) => {
                self.counters.rejected += 1;
                out.push(Output::Warning(format!(
                    "reading at {} ns rejected: {e}",
                    raw.time_ns
                )));
            }
        }
        out
    }

    /// A `machine/commanded_joint_states` message.
    pub fn commanded(&mut self, j: &JointState) -> Vec<Output> {
        let t = j.header.stamp.nanos();
        let mut out = Vec::new();
        if let Err(e) = self.commanded.push(t, &j.name, &j.position) {
            out.push(Output::Warning(format!(
                "machine/commanded_joint_states: {e}"
            )));
        }
        self.resolve_awaiting(i64::MIN, &mut out);
        out
    }

    /// The input ended (end of a bag or export, node shutdown): close the open dwell.
    pub fn finish(&mut self) -> Vec<Output> {
        let mut out = match self.grouper.flush() {
            Some(d) => self.dwell(d),
            None => Vec::new(),
        };
        self.resolve_awaiting(i64::MAX, &mut out);
        if self.pose.is_none() && !self.pending.is_empty() {
            out.push(Output::Warning(format!(
                "{} dwells were not written as measured points: the tracker pose was never registered ({}{})",
                self.pending.len(),
                self.registration_shortfall(),
                if self.registration_stalled { "" } else { "; the input ended before the program came back to a target" }
            )));
        }
        out
    }

    /// Why the registration has not happened and what to set.
    fn registration_shortfall(&self) -> String {
        let (needed, got) = (self.config.registration_points, self.collected.len());
        // cycles the program completed: every target it shows visited that often
        let cycles = self.visits.values().copied().min().unwrap_or(0);
        let advice = if got >= 3 {
            format!("set registration_points:={got} (3 distinct targets or more register the pose; more average it better)")
        } else {
            "a registration needs at least 3 distinct, unflagged targets: run a program that visits more".to_string()
        };
        format!(
            "registration needs {needed} distinct targets, the program has visited {got} ({}) after {cycles} cycle{}: {advice}, or give a program with at least {needed} targets",
            self.collected.keys().cloned().collect::<Vec<_>>().join(", "),
            if cycles == 1 { "" } else { "s" }
        )
    }

    /// Forget the pose and register again from the next `registration_points` targets (the
    /// tracker was moved).
    pub fn reregister(&mut self) {
        self.pose = None;
        self.collected.clear();
        self.visits.clear();
        self.registration_stalled = false;
        self.pending.clear();
    }

    /// ((A, B, τ), (σ_A, σ_B, σ_τ), stable at the last dwell, samples) of the warm-up fit.
    pub fn warmup_summary(&self) -> Option<(Vector3<f64>, Vector3<f64>, bool, usize)> {
        let f = self.warmup.fit()?;
        Some((
            Vector3::new(f.a, f.b, f.tau),
            f.sigma(),
            self.last_warmup.is_some_and(|w| w.1),
            f.samples,
        ))
    }

    fn dwell(&mut self, d: DwellAverage) -> Vec<Output> {
        let mut out = Vec::new();
        if d.n < self.config.min_dwell_readings {
            self.counters.short_dwells += 1;
            return out;
        }
        self.counters.dwells += 1;
        let verdict = self
            .config
            .turbulence
            .test(&d.ranges, self.config.processor.radial_sigma(d.range));
        let flagged = verdict.is_some_and(|v| v.flagged);
        if flagged {
            self.counters.turbulence_flags += 1;
        }
        let covariance = d.covariance_given(verdict.as_ref());
        let warming_up = self.warmup_step(&d, flagged, &mut out);
        out.push(Output::Dwell(messages::dwell_measurement(
            &d,
            &covariance,
            &self.config.tracker_frame,
            flagged,
            warming_up,
        )));
        self.awaiting.push_back(AwaitingNominal {
            target: d.target.clone(),
            mid_ns: d.mid_ns(),
            point: d.point,
            covariance,
            flagged,
        });
        self.resolve_awaiting(i64::MIN, &mut out);
        out
    }

    /// Give the waiting dwells, oldest first, their nominal and place them, as long as the
    /// commanded states cover them (a state after the mid time has arrived), there are no
    /// commanded states at all (the program's timing is the only source), or their mid time is
    /// before `expired_before` (ns; `i64::MIN`: none has expired, `i64::MAX`: all have, at the
    /// end of the input).
    fn resolve_awaiting(&mut self, expired_before: i64, out: &mut Vec<Output>) {
        while let Some(a) = self.awaiting.front() {
            let covered = !matches!(self.commanded.latest_ns(), Some(latest) if latest < a.mid_ns);
            if !covered && a.mid_ns >= expired_before {
                break;
            }
            let a = self.awaiting.pop_front().expect("front exists");
            self.place(a, out);
        }
    }

    /// The nominal of a dwell (commanded joint states first; the program's timing, T_v, when they
    /// do not cover it), then the point: published, or held until the tracker pose is fitted.
    fn place(&mut self, a: AwaitingNominal, out: &mut Vec<Output>) {
        let AwaitingNominal {
            target,
            mid_ns,
            point,
            covariance,
            flagged,
        } = a;
        let commanded = self
            .commanded
            .joints_at(mid_ns, &self.config.nominal_joints)
            .map(|q| Vector3::new(q[0], q[1], q[2]));
        let scheduled = || {
            self.config
                .schedule
                .as_ref()
                .and_then(|s| s.point_at(mid_ns))
                .map(|(_, p)| p)
        };
        let nominal = match (commanded, scheduled()) {
            (Ok(q), _) | (Err(_), Some(q)) => q + self.config.tool_offset,
            (Err(e), None) => {
                self.counters.no_nominal += 1;
                out.push(Output::Warning(format!(
                    "dwell of '{target}' at {mid_ns} ns has no nominal: {e}"
                )));
                return;
            }
        };
        let pending = PendingPoint {
            target: target.clone(),
            stamp_ns: mid_ns,
            point,
            covariance,
            nominal,
        };
        match &self.pose {
            Some(pose) => {
                let p = messages::measured_point(
                    pose,
                    &pending.target,
                    pending.stamp_ns,
                    &pending.point,
                    &pending.covariance,
                    &pending.nominal,
                    &self.config.machine_frame,
                );
                self.counters.points += 1;
                out.push(Output::Point(p));
            }
            None => {
                let visits = self.visits.entry(target.clone()).or_default();
                *visits += 1;
                let repeated = *visits > 1;
                if !flagged && !self.collected.contains_key(&target) {
                    self.collected.insert(
                        target,
                        Correspondence {
                            tracker: point,
                            tracker_covariance: covariance,
                            machine: nominal,
                            machine_covariance: Matrix3::zeros(),
                        },
                    );
                }
                self.pending.push(pending);
                if self.collected.len() >= self.config.registration_points {
                    out.extend(self.try_register(mid_ns));
                } else if repeated && !self.registration_stalled {
                    // the program came back to a target: it may never show enough distinct ones
                    self.registration_stalled = true;
                    out.push(Output::Warning(format!(
                        "no measured points yet: {}",
                        self.registration_shortfall()
                    )));
                }
            }
        }
    }

    /// Warm-up bookkeeping for one dwell; returns whether the tracker is still warming up
    /// (false when no warm-up nest is configured).
    fn warmup_step(&mut self, d: &DwellAverage, flagged: bool, out: &mut Vec<Output>) -> bool {
        if self.config.warmup_target.is_empty() {
            return false;
        }
        let t_on = (d.mid_ns() - self.power_on_ns.unwrap_or(d.first_ns)) as f64 * 1e-9;
        if d.target == self.config.warmup_target && !flagged {
            let sigma = self.config.processor.radial_sigma(d.range) / (d.n as f64).sqrt();
            match self.warmup.add(WarmupSample {
                t: t_on,
                value: d.range,
                sigma,
            }) {
                Ok(fit) => out.push(Output::Warmup(messages::warmup_model(
                    fit,
                    d.mid_ns(),
                    &self.config.warmup_target,
                ))),
                Err(e) => out.push(Output::Warning(format!("warm-up: {e}"))),
            }
        }
        let stable = self.warmup.stable_at(t_on);
        self.last_warmup = Some((t_on, stable));
        !stable
    }

    fn try_register(&mut self, stamp_ns: i64) -> Vec<Output> {
        let points: Vec<Correspondence> = self.collected.values().copied().collect();
        match register(&points) {
            Ok(pose) => {
                let mut out = vec![Output::Pose(pose.clone(), stamp_ns)];
                for p in std::mem::take(&mut self.pending) {
                    out.push(Output::Point(messages::measured_point(
                        &pose,
                        &p.target,
                        p.stamp_ns,
                        &p.point,
                        &p.covariance,
                        &p.nominal,
                        &self.config.machine_frame,
                    )));
                    self.counters.points += 1;
                }
                self.pose = Some(pose);
                self.visits.clear();
                self.registration_stalled = false;
                out
            }
            Err(e) => vec![Output::Warning(format!(
                "registration from {} targets failed: {e}; collecting more",
                points.len()
            ))],
        }
    }

    /// Key/value pairs for `/diagnostics`.
    pub fn diagnostics(&self) -> Vec<(String, String)> {
        let c = &self.counters;
        let mut v: Vec<(String, String)> = [
            ("readings", c.readings),
            ("beam_breaks", c.beam_breaks),
            ("rejected_readings", c.rejected),
            ("dwells", c.dwells),
            ("short_dwells", c.short_dwells),
            ("turbulence_flags", c.turbulence_flags),
            ("measured_points", c.points),
            ("dwells_without_nominal", c.no_nominal),
        ]
        .into_iter()
        .map(|(k, n)| (k.to_string(), n.to_string()))
        .collect();
        if let Some((p, s, stable, n)) = self.warmup_summary() {
            v.push((
                "warmup_A".into(),
                format!("{:.4} mm ± {:.2} µm", p[0] * 1e3, s[0] * 1e6),
            ));
            v.push((
                "warmup_B".into(),
                format!("{:.2} µm ± {:.2} µm", p[1] * 1e6, s[1] * 1e6),
            ));
            v.push((
                "warmup_tau".into(),
                format!("{:.1} min ± {:.1} min", p[2] / 60.0, s[2] / 60.0),
            ));
            v.push(("warmup_stable".into(), stable.to_string()));
            v.push(("warmup_samples".into(), n.to_string()));
        }
        match &self.pose {
            Some(pose) => v.push((
                "registration_rms".into(),
                format!("{:.1} µm", pose.rms * 1e6),
            )),
            None if self.registration_stalled => {
                v.push(("registration".into(), self.registration_shortfall()))
            }
            None => v.push((
                "registration".into(),
                format!(
                    "collecting: {} of {} distinct targets",
                    self.collected.len(),
                    self.config.registration_points
                ),
            )),
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_compensation::to_spherical;
    use metrocell_msgs::builtin_interfaces::msg::Time;
    use metrocell_msgs::geometry_msgs::msg::Point;
    use metrocell_msgs::std_msgs::msg::Header;
    use nalgebra::Rotation3;

    const AIR: AirData = AirData {
        temperature: 20.0,
        pressure: 101_325.0,
        humidity: 0.5,
    };
    const NOMINALS: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [0.4, 0.0, 0.1],
        [0.4, 0.3, 0.0],
        [0.0, 0.3, 0.2],
    ];

    fn header(t_ns: i64) -> Header {
        Header {
            stamp: Time::from_nanos(t_ns),
            frame_id: String::new(),
        }
    }

    /// The commanded state and the reading at `time` of the i-th reading of the dwell on nominal
    /// k (at `q`), seen from a tracker at pose (r, t); `scatter` (m) alternates on the range; the
    /// 5th reading of the 2nd dwell is a beam break.
    fn inputs_at(
        time: i64,
        k: usize,
        i: usize,
        q: &Vector3<f64>,
        r: &Rotation3<f64>,
        t: &Vector3<f64>,
        scatter: f64,
    ) -> (JointState, TrackerMeasurement) {
        let (range, azimuth, elevation) = to_spherical(&(r.inverse() * (q - t)));
        let j = JointState {
            header: header(time),
            name: vec!["x".into(), "y".into(), "z".into()],
            position: vec![q.x, q.y, q.z],
            velocity: vec![],
            effort: vec![],
        };
        let m = TrackerMeasurement {
            header: header(time),
            target_id: format!("p{k}"),
            point: Point::default(),
            range: range
                + if i.is_multiple_of(2) {
                    scatter
                } else {
                    -scatter
                },
            azimuth,
            elevation,
            covariance: [0.0; 9],
            air_temperature: AIR.temperature,
            air_pressure: AIR.pressure,
            air_humidity: AIR.humidity,
            refractive_index: AIR.refractive_index(),
            status: if k == 1 && i == 4 {
                TrackerMeasurement::STATUS_BEAM_BREAK
            } else {
                0
            },
        };
        (j, m)
    }

    /// Dwells of 10 readings at 10 Hz on each nominal, seen from a tracker at pose (r, t); the
    /// commanded joints say where the machine is. `scatter` (m) alternates on the range.
    fn visit(
        state: &mut TrackerState,
        t0_ns: i64,
        r: &Rotation3<f64>,
        t: &Vector3<f64>,
        scatter: f64,
    ) -> Vec<Output> {
        let mut out = Vec::new();
        let mut time = t0_ns;
        for (k, q) in NOMINALS.iter().enumerate() {
            for i in 0..10 {
                time += 100_000_000;
                let (j, m) = inputs_at(time, k, i, &Vector3::from(*q), r, t, scatter);
                out.extend(state.commanded(&j));
                out.extend(state.measurement(&m));
            }
            time += 2_000_000_000;
        }
        out
    }

    fn points(out: &[Output]) -> Vec<&MeasuredPoint> {
        out.iter()
            .filter_map(|o| {
                if let Output::Point(p) = o {
                    Some(p)
                } else {
                    None
                }
            })
            .collect()
    }

    fn poses(out: &[Output]) -> Vec<&Registration> {
        out.iter()
            .filter_map(|o| {
                if let Output::Pose(p, _) = o {
                    Some(p)
                } else {
                    None
                }
            })
            .collect()
    }

    #[test]
    fn registers_publishes_every_dwell_and_reregisters_when_moved() {
        let mut state = TrackerState::new(TrackerConfig {
            registration_points: 4,
            ..TrackerConfig::defaults()
        });
        let (ra, ta) = (
            Rotation3::from_euler_angles(0.0, 0.0, 0.5),
            Vector3::new(-1.2, 0.2, 0.6),
        );
        let mut out = visit(&mut state, 0, &ra, &ta, 0.0);
        out.extend(state.finish());
        assert_eq!(poses(&out).len(), 1);
        assert!((poses(&out)[0].translation - ta).norm() < 1e-9);
        let ids: Vec<&str> = points(&out).iter().map(|p| p.point_id.as_str()).collect();
        assert_eq!(
            ids,
            ["p0", "p1", "p2", "p3"],
            "held back until registered, then each once"
        );
        for (p, q) in points(&out).iter().zip(NOMINALS) {
            assert_eq!([p.nominal.x, p.nominal.y, p.nominal.z], q);
            assert!(
                (Vector3::new(p.measured.x, p.measured.y, p.measured.z) - Vector3::from(q)).norm()
                    < 1e-9
            );
        }
        assert_eq!(
            (
                state.counters.readings,
                state.counters.beam_breaks,
                state.counters.dwells
            ),
            (40, 1, 4)
        );

        // the tracker is moved: without re-registration the points are off by the move
        let (rb, tb) = (
            Rotation3::from_euler_angles(0.0, 0.0, 0.9),
            Vector3::new(-1.0, -0.4, 0.5),
        );
        let mut moved = visit(&mut state, 60_000_000_000, &rb, &tb, 0.0);
        moved.extend(state.finish());
        assert_eq!(points(&moved).len(), 4);
        assert!(points(&moved)
            .iter()
            .all(|p| (p.measured.x - p.nominal.x).abs() > 1e-3
                || (p.measured.y - p.nominal.y).abs() > 1e-3));
        state.reregister();
        let mut again = visit(&mut state, 120_000_000_000, &rb, &tb, 0.0);
        again.extend(state.finish());
        assert!((poses(&again)[0].translation - tb).norm() < 1e-9);
        assert_eq!(points(&again).len(), 4);
    }

    fn warnings(out: &[Output]) -> Vec<&str> {
        out.iter()
            .filter_map(|o| {
                if let Output::Warning(w) = o {
                    Some(w.as_str())
                } else {
                    None
                }
            })
            .collect()
    }

    /// Issue 32, item 12: the default 12 registration targets on a program of 4 never register;
    /// the node says so, with what to set, once the program comes back to a target, and again
    /// at the end with how many dwells went unwritten.
    #[test]
    fn a_program_with_fewer_targets_than_registration_points_says_what_to_set() {
        let mut state = TrackerState::new(TrackerConfig {
            registration_points: 12,
            ..TrackerConfig::defaults()
        });
        let (r, t) = (
            Rotation3::from_euler_angles(0.0, 0.0, 0.5),
            Vector3::new(-1.2, 0.2, 0.6),
        );
        let mut out = Vec::new();
        for cycle in 0..3 {
            out.extend(visit(&mut state, cycle * 60_000_000_000, &r, &t, 0.0));
        }
        out.extend(state.finish());
        assert!(points(&out).is_empty() && poses(&out).is_empty());
        let w = warnings(&out);
        assert_eq!(
            w.len(),
            2,
            "once when the program repeats, once at the end: {w:?}"
        );
        assert!(
            w[0].starts_with("no measured points yet: registration needs 12 distinct targets, the program has visited 4 (p0, p1, p2, p3) after 1 cycle: set registration_points:=4"),
            "{}",
            w[0]
        );
        assert!(w[1].starts_with("12 dwells were not written as measured points: the tracker pose was never registered (registration needs 12 distinct targets, the program has visited 4"), "{}", w[1]);
        assert!(w[1].contains("after 3 cycles"), "{}", w[1]);
        let diag: BTreeMap<String, String> = state.diagnostics().into_iter().collect();
        assert!(
            diag["registration"].contains("set registration_points:=4"),
            "{diag:?}"
        );
        // as told: 4 registers on the first cycle, and nothing is said
        let mut state = TrackerState::new(TrackerConfig {
            registration_points: 4,
            ..TrackerConfig::defaults()
        });
        let mut out = visit(&mut state, 0, &r, &t, 0.0);
        out.extend(visit(&mut state, 60_000_000_000, &r, &t, 0.0));
        out.extend(state.finish());
        assert!(warnings(&out).is_empty(), "{:?}", warnings(&out));
        assert_eq!(points(&out).len(), 8);
    }

    #[test]
    fn turbulent_dwells_are_flagged_inflated_and_not_used_for_registration() {
        let mut state = TrackerState::new(TrackerConfig {
            registration_points: 4,
            ..TrackerConfig::defaults()
        });
        let (r, t) = (Rotation3::identity(), Vector3::new(-1.5, 0.0, 0.5));
        // ±60 µm on the range against σ ≈ 5.4 µm: every dwell fails the χ² test
        let mut out = visit(&mut state, 0, &r, &t, 60e-6);
        out.extend(state.finish());
        assert_eq!(state.counters.turbulence_flags, 4);
        assert!(
            poses(&out).is_empty() && points(&out).is_empty(),
            "no registration from turbulent dwells"
        );
        let dwells: Vec<&TrackerMeasurement> = out
            .iter()
            .filter_map(|o| {
                if let Output::Dwell(d) = o {
                    Some(d)
                } else {
                    None
                }
            })
            .collect();
        assert_eq!(dwells.len(), 4);
        for d in dwells {
            assert_ne!(d.status & TrackerMeasurement::STATUS_TURBULENCE, 0);
            // covariance of the mean inflated to the scatter: radial σ_mean ≈ 60 µm/√n
            let n = if d.target_id == "p1" { 9.0 } else { 10.0 };
            let u = Vector3::new(d.point.x, d.point.y, d.point.z).normalize();
            let c = nalgebra::Matrix3::from_row_slice(&d.covariance);
            let radial = (u.transpose() * c * u)[(0, 0)].sqrt();
            assert!(
                (radial / (60e-6 / f64::sqrt(n)) - 1.0).abs() < 0.1,
                "{radial}"
            );
        }
    }

    /// Live, the commanded states come through their own reader and can lag the readings (a
    /// sample resent after a loss): a dwell closed before the state after its mid time arrived
    /// waits for it, and gets the same nominal as when the states come first.
    #[test]
    fn a_dwell_waits_for_commanded_states_that_arrive_after_its_readings() {
        let (r, t) = (
            Rotation3::from_euler_angles(0.0, 0.0, 0.5),
            Vector3::new(-1.2, 0.2, 0.6),
        );
        let mut in_order = TrackerState::new(TrackerConfig {
            registration_points: 4,
            ..TrackerConfig::defaults()
        });
        let mut expected = visit(&mut in_order, 0, &r, &t, 0.0);
        expected.extend(in_order.finish());
        // the same inputs, every commanded state held back until all readings are in
        let mut state = TrackerState::new(TrackerConfig {
            registration_points: 4,
            ..TrackerConfig::defaults()
        });
        let mut commanded = Vec::new();
        let mut time = 0;
        for (k, q) in NOMINALS.iter().enumerate() {
            for i in 0..10 {
                time += 100_000_000;
                let (j, m) = inputs_at(time, k, i, &Vector3::from(*q), &r, &t, 0.0);
                commanded.push(j);
                // one early commanded state, so the node knows the stream exists
                if k == 0 && i == 0 {
                    let _ = state.commanded(commanded.last().unwrap());
                }
                assert!(
                    points(&state.measurement(&m)).is_empty(),
                    "no point before its commanded states"
                );
            }
            time += 2_000_000_000;
        }
        let mut out = Vec::new();
        for j in &commanded[1..] {
            out.extend(state.commanded(j));
        }
        out.extend(state.finish());
        assert_eq!(state.counters.no_nominal, 0);
        let got: Vec<_> = points(&out).into_iter().cloned().collect();
        let want: Vec<_> = points(&expected).into_iter().cloned().collect();
        assert_eq!(got.len(), 4);
        assert_eq!(got, want, "same points as with the states in order");
    }

    #[test]
    fn a_dwell_whose_commanded_states_never_come_is_counted_after_the_wait() {
        let mut state = TrackerState::new(TrackerConfig {
            registration_points: 4,
            ..TrackerConfig::defaults()
        });
        let j = |t: i64| JointState {
            header: header(t),
            name: vec!["x".into(), "y".into(), "z".into()],
            position: vec![0.0; 3],
            velocity: vec![],
            effort: vec![],
        };
        let _ = state.commanded(&j(0));
        let m = |t: i64, target: &str| TrackerMeasurement {
            header: header(t),
            target_id: target.into(),
            point: Point::default(),
            range: 2.0,
            azimuth: 0.1,
            elevation: 0.1,
            covariance: [0.0; 9],
            air_temperature: AIR.temperature,
            air_pressure: AIR.pressure,
            air_humidity: AIR.humidity,
            refractive_index: AIR.refractive_index(),
            status: 0,
        };
        for i in 1..=10 {
            let _ = state.measurement(&m(i * 100_000_000, "p0"));
        }
        let _ = state.measurement(&m(1_200_000_000, ""));
        assert_eq!(state.counters.no_nominal, 0, "still waiting");
        let out = state.measurement(&m(1_000_000_000 + COMMANDED_WAIT_NS + 600_000_000, ""));
        assert_eq!(state.counters.no_nominal, 1, "given up after the wait");
        assert!(out
            .iter()
            .any(|o| matches!(o, Output::Warning(w) if w.contains("no nominal"))));
    }

    #[test]
    fn short_dwells_and_missing_nominals_are_counted() {
        let mut state = TrackerState::new(TrackerConfig {
            min_dwell_readings: 11,
            ..TrackerConfig::defaults()
        });
        visit(
            &mut state,
            0,
            &Rotation3::identity(),
            &Vector3::new(-1.5, 0.0, 0.5),
            0.0,
        );
        state.finish();
        assert_eq!((state.counters.short_dwells, state.counters.dwells), (4, 0));
        let mut state = TrackerState::new(TrackerConfig {
            nominal_joints: vec!["a".into(), "b".into(), "c".into()],
            ..TrackerConfig::defaults()
        });
        let out = visit(
            &mut state,
            0,
            &Rotation3::identity(),
            &Vector3::new(-1.5, 0.0, 0.5),
            0.0,
        );
        assert_eq!(state.counters.no_nominal, 3);
        assert!(out
            .iter()
            .any(|o| matches!(o, Output::Warning(w) if w.contains("lacks joint 'a'"))));
    }

    #[test]
    fn weather_station_topics_replace_the_readings_air() {
        let mut state = TrackerState::new(TrackerConfig {
            air_from_topics: true,
            ..TrackerConfig::defaults()
        });
        let m = TrackerMeasurement {
            header: header(1),
            target_id: "p".into(),
            point: Point::default(),
            range: 2.0,
            azimuth: 0.1,
            elevation: 0.1,
            covariance: [0.0; 9],
            air_temperature: 20.0,
            air_pressure: 101_325.0,
            air_humidity: 0.5,
            refractive_index: AIR.refractive_index(),
            status: 0,
        };
        let out = state.measurement(&m);
        assert!(
            out.iter()
                .any(|o| matches!(o, Output::Warning(w) if w.contains("no air data"))),
            "no station air yet: rejected"
        );
        // the station says 1 K warmer than the instrument assumed: the range grows by ~0.95 ppm
        state.station_air(Some(21.0), Some(101_325.0), Some(0.5));
        for k in 0..5 {
            state.measurement(&TrackerMeasurement {
                header: header(2 + k),
                ..m.clone()
            });
        }
        let out = state.finish();
        let d = out
            .iter()
            .find_map(|o| {
                if let Output::Dwell(d) = o {
                    Some(d)
                } else {
                    None
                }
            })
            .unwrap();
        assert!(
            ((d.range - 2.0) / 2.0 * 1e6 - 0.95).abs() < 0.05,
            "{} ppm",
            (d.range - 2.0) / 2.0 * 1e6
        );
        assert_eq!(d.air_temperature, 21.0);
    }
}
