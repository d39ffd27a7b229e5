//! Measurement records from a stream of recorded messages, one message at a time: the engine
//! behind [`crate::records_from_bags`] (messages read from a bag) and the `diagnose` node
//! (messages taken from live DDS, the same `SourcedMessage`s the recorder writes). What is read,
//! which frame a record is in and what is checked are documented on [`crate::recordings`]; this
//! module only adds the streaming: a measurement is held until the signals around its time have
//! arrived ([`SignalsBuilder::ready`]), then resolved into a record or a rejection, so the
//! records come out in time order as the messages go in, with bounded memory.
//!
//! Messages go in in log-time order (a bag's order; a live node's receive order). Each stream
//! (a topic) must go forward in time; streams may interleave as they like. How far the recording
//! has reached is judged on the stamps (the measurements', and the signal samples' as the builder
//! takes them), the time base of every instant a record is asked about — never on the log time:
//! in a bag recorded live from a twin running faster than real time, or a node reading one, the
//! receive clock runs far from the stamps and would declare every measurement ready before the
//! samples bracketing it were read. A measurement waits until some stream's stamps are
//! `max_slow_gap` past it.

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};

use metrocell_bagtools::import::{CHECK_POINTS_TOPIC, REFERENCE_POINTS_TOPIC};
use metrocell_bagtools::SourcedMessage;
use metrocell_model::{ForwardModel, MachineGeometry, MachineKinematics, SignalsBuilder};
use metrocell_msgs::msg::{FiducialDetectionArray, MeasuredPoint, ProbeHit, TrackerMeasurement};
use metrocell_msgs::RosMessage;
use metrocell_physics::{EffectKind, SignalKind, Signals};
use nalgebra::{Matrix3, Vector3};

use crate::instrument_readings::{
    marker_measurements, probe_measurement, record_kind, CameraFeatures, InstrumentMeasurement,
    InstrumentReading,
};
use crate::recording_sources::RecordingSources;
use crate::recordings::{frame_setup, record_frame, PointSource, RecordingError, RecordingOptions};
use crate::signal_topics::{
    feed, message_time, SignalTopic, AIR_SENSOR, COMMANDED_JOINTS_TOPIC, LOAD_TOPIC,
    POWER_ON_TOPIC, TEMPERATURE_PREFIX,
};
use metrocell_estimation::records::{MeasurementRecord, RecordFrame, RecordKind, Rejected};
use metrocell_estimation::residuals::whitening;
use metrocell_msgs::geometry_msgs::msg::WrenchStamped;
use metrocell_msgs::sensor_msgs::msg::{JointState, Temperature, TimeReference};

/// How long (s) a streaming node keeps each temperature's history at full rate beyond the
/// instants it still asks lags about (its window): older history is coarsened to one sample a
/// minute (`SignalsBuilderOptions::temperature_full_rate`), which moves a lag half an hour inside
/// the full-rate span by tens of µK (crates/physics `temperature_timeline.rs`), and keeps a
/// long run's memory flat (the 8-h soak: the diagnose node −0.07 MB per cell hour, BENCHMARKS.md).
pub const LAG_FULL_RATE_MARGIN_S: f64 = 3600.0;

/// What a stream has produced: records by frame (points), instrument records (probe hits,
/// camera points, in the frames of their readings), rejections, and where each input came from.
#[derive(Debug, Default)]
pub struct StreamOutput {
    pub by_frame: Vec<(RecordFrame, Vec<MeasurementRecord>)>,
    pub instrument_records: Vec<MeasurementRecord>,
    /// Points whose role is `check` (`/check_points`): kept out of fits (see [`RecordSet::check`]).
    pub check: Vec<MeasurementRecord>,
    pub rejected: Vec<Rejected>,
    /// (what, topic or column) of every input used, e.g. ("points", "/measured_points (…)").
    pub sources: Vec<(String, String)>,
}

impl StreamOutput {
    /// Every record, points first, each group in time order.
    pub fn records(self) -> impl Iterator<Item = MeasurementRecord> {
        self.by_frame
            .into_iter()
            .flat_map(|(_, r)| r)
            .chain(self.instrument_records)
    }
}

/// Turns recorded messages into measurement records for one model (module docs).
pub struct RecordStream<'m, 'a> {
    model: &'m ForwardModel<'a>,
    /// Names the recording in every message (a bag's path, or e.g. `live DDS`).
    source: PathBuf,
    needs: Vec<(String, SignalKind)>,
    /// The points' topic, and whether it carries raw tracker readings (else `MeasuredPoint`s).
    points_topic: Option<String>,
    points_tracker: bool,
    probe_topic: Option<String>,
    camera_topic: Option<String>,
    /// Readings of reference nests (`MeasuredPoint`s the machine did not place), if recorded.
    reference_topic: Option<String>,
    /// `/check_points` when the recording has them, and the index of the next.
    check_topic: Option<String>,
    check_index: u64,
    reference_index: u64,
    camera_features: CameraFeatures,
    signal_topics: BTreeMap<String, SignalTopic>,
    joints: JointSource,
    joint_names: Vec<String>,
    builder: SignalsBuilder,
    pending: VecDeque<Pending>,
    out: StreamOutput,
    feed: SignalFeed,
    point_index: u64,
    instrument_index: u64,
    /// Joints from points' nominals, pushed to the builder once every message of their time
    /// has been read (a velocity-only joint state of the same row may follow the point).
    deferred_joints: VecDeque<(i64, Vec<f64>)>,
    /// Velocities of joint states that carry no positions, by time.
    velocity_only: BTreeMap<i64, (Vec<String>, Vec<f64>)>,
    /// A commanded joint state with the machine's positions was read (they then give the axes).
    commanded_positions: bool,
}

/// The topics (name, ROS type) a live reader of `model`'s records subscribes: the points (as
/// `options.points` says; `Auto` = measured points), the commanded joints, and the topic of
/// every signal a declared term reads (temperatures, power-on time, load). Signals a reader
/// finds later (other sensors) are added with [`RecordStream::add_signal_topic`].
pub fn declared_topics(model: &ForwardModel, options: &RecordingOptions) -> Vec<(String, String)> {
    let points = match options.points {
        PointSource::TrackerMeasurements => {
            (options.tracker_topic.clone(), TrackerMeasurement::ROS_TYPE)
        }
        PointSource::MeasuredPoints | PointSource::Auto => (
            options.measured_points_topic.clone(),
            MeasuredPoint::ROS_TYPE,
        ),
    };
    let mut topics = vec![
        (points.0, points.1.to_string()),
        (
            COMMANDED_JOINTS_TOPIC.to_string(),
            JointState::ROS_TYPE.to_string(),
        ),
        (
            REFERENCE_POINTS_TOPIC.to_string(),
            MeasuredPoint::ROS_TYPE.to_string(),
        ),
        (
            CHECK_POINTS_TOPIC.to_string(),
            MeasuredPoint::ROS_TYPE.to_string(),
        ),
    ];
    if options.probe_hits {
        topics.push((options.probe_topic.clone(), ProbeHit::ROS_TYPE.to_string()));
    }
    for (_, kind) in declared_signals(model) {
        let (name, ty) = match kind {
            SignalKind::Temperature(n) | SignalKind::TemperatureHistory(n) => {
                (format!("{TEMPERATURE_PREFIX}{n}"), Temperature::ROS_TYPE)
            }
            SignalKind::TimeSincePowerOn => (POWER_ON_TOPIC.to_string(), TimeReference::ROS_TYPE),
            SignalKind::LoadForce => (LOAD_TOPIC.to_string(), WrenchStamped::ROS_TYPE),
            _ => continue,
        };
        if !topics.iter().any(|(n, _)| *n == name) {
            topics.push((name, ty.to_string()));
        }
    }
    topics
}

impl<'m, 'a> RecordStream<'m, 'a> {
    /// A stream over a recording that holds `topics` ((name, ROS type) each: a bag's topic list,
    /// a live node's subscriptions). Checks, before any message, that the recording has points
    /// to make records of, commanded joints (or nominals that give them) and every signal a
    /// declared term needs — each an error naming what to record.
    pub fn new(
        source: &Path,
        topics: &[(String, String)],
        model: &'m ForwardModel<'a>,
        options: &RecordingOptions,
    ) -> Result<Self, RecordingError> {
        let sources = RecordingSources::check(source, topics, model, options)?;
        // bounded memory: joints are kept only as long as a held measurement can still ask for them
        let mut signal_options = options.signals.clone();
        let held = options.signals.max_slow_gap + options.signals.max_joint_gap + 60.0;
        signal_options.joint_window = Some(held);
        signal_options.temperature_window = Some(held);
        let mut stream = RecordStream {
            model,
            source: source.to_path_buf(),
            needs: declared_signals(model),
            points_topic: sources.points_topic,
            points_tracker: sources.points_tracker,
            probe_topic: sources.probe_topic,
            camera_topic: sources.camera_topic,
            reference_topic: sources.reference_topic,
            reference_index: 0,
            check_topic: sources.check_topic,
            check_index: 0,
            camera_features: options.camera_features.clone(),
            signal_topics: BTreeMap::new(),
            joints: sources.joints,
            joint_names: model.machine.joint_names(),
            builder: SignalsBuilder::for_machine(model.machine, signal_options),
            pending: VecDeque::new(),
            out: StreamOutput {
                sources: sources.lines,
                ..StreamOutput::default()
            },
            feed: SignalFeed::default(),
            point_index: 0,
            instrument_index: 0,
            deferred_joints: VecDeque::new(),
            velocity_only: BTreeMap::new(),
            commanded_positions: false,
        };
        for (name, which) in sources.signal_topics {
            stream.add_signal_topic(name, which);
        }
        Ok(stream)
    }

    /// Signal samples refused so far (a time going backwards, a NaN, a message that does not
    /// decode), over every topic.
    pub fn refused_samples(&self) -> u64 {
        self.feed.refused.values().map(|r| r.count).sum()
    }

    /// A signal topic that appeared after the stream was made (a live sensor discovered late):
    /// its messages are read from now on, and measurements wait for its samples.
    pub fn add_signal_topic(&mut self, name: String, which: SignalTopic) {
        // tell the builder which sampled streams will be fed, so a measurement waits for the
        // samples stamped at or after it (see `SignalsBuilder::ready`)
        match &which {
            SignalTopic::CommandedJoints => self.builder.expect_joints(),
            SignalTopic::Temperature(sensor) => {
                self.builder.expect_temperature(sensor);
                if sensor == AIR_SENSOR {
                    self.builder.expect_air(0);
                }
            }
            SignalTopic::AirTemperature => self.builder.expect_air(0),
            SignalTopic::AirPressure => self.builder.expect_air(1),
            SignalTopic::AirHumidity => self.builder.expect_air(2),
            SignalTopic::Approach
            | SignalTopic::PowerOn
            | SignalTopic::Load
            | SignalTopic::ToolOffset
            | SignalTopic::Accelerometer(_) => {}
        }
        self.signal_topics.insert(name, which);
    }

    /// Every topic the stream reads (points, probe hits, camera points, signals).
    pub fn topics(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .points_topic
            .iter()
            .chain(&self.probe_topic)
            .chain(&self.camera_topic)
            .chain(&self.reference_topic)
            .chain(&self.check_topic)
            .cloned()
            .collect();
        out.extend(self.signal_topics.keys().cloned());
        out
    }

    /// Take one message (others' topics are ignored); records whose signals are complete are
    /// resolved. Errors only when the recording cannot give records at all (a commanded joint
    /// state without the machine's joints); a bad message is a rejection, counted.
    pub fn push(&mut self, m: &SourcedMessage) -> Result<(), RecordingError> {
        self.push_deferred_joints(Some(m.log_time_ns as i64));
        let velocity_only = self.joints == JointSource::CommandedOrNominal
            && self.signal_topics.get(&m.topic) == Some(&SignalTopic::CommandedJoints)
            && !self.take_positions(m);
        let source = self.source.display().to_string();
        let at = |topic: &str, index: u64| {
            format!(
                "{source}: {topic} message {index} (log time {:.3} s)",
                m.log_time_ns as f64 / 1e9
            )
        };
        if self.points_topic.as_deref() == Some(m.topic.as_str()) {
            let at = at(&m.topic, self.point_index);
            self.point_index += 1;
            let parsed = if self.points_tracker {
                from_tracker(m, at)
            } else {
                from_measured_point(
                    m,
                    at,
                    self.joints,
                    |t| tool_offset_at(&self.builder, self.model, t),
                    self.commanded_positions,
                )
            };
            match parsed {
                Ok(p) => {
                    self.builder.observe_time(p.t_ns);
                    if let Some(q) = p.q.as_ref().filter(|_| !self.commanded_positions) {
                        // the nominals are the commanded trajectory: they give approach and
                        // velocity too (pushed once the row's other messages are read)
                        if self.deferred_joints.back().is_none_or(|(t, _)| *t < p.t_ns) {
                            self.deferred_joints.push_back((p.t_ns, q.clone()));
                        }
                    }
                    self.pending.push_back(p);
                }
                Err(r) => self.out.rejected.push(r),
            }
        } else if self.check_topic.as_deref() == Some(m.topic.as_str()) {
            let at = at(&m.topic, self.check_index);
            self.check_index += 1;
            match from_measured_point(
                m,
                at,
                self.joints,
                |t| tool_offset_at(&self.builder, self.model, t),
                self.commanded_positions,
            ) {
                Ok(mut p) => {
                    p.check = true;
                    self.builder.observe_time(p.t_ns);
                    let k = self.pending.partition_point(|q| q.t_ns <= p.t_ns);
                    self.pending.insert(k, p);
                }
                Err(r) => self.out.rejected.push(r),
            }
        } else if self.reference_topic.as_deref() == Some(m.topic.as_str()) {
            let at = at(&m.topic, self.reference_index);
            self.reference_index += 1;
            match from_reference_point(m, at) {
                Ok(p) => {
                    self.builder.observe_time(p.t_ns);
                    let k = self.pending.partition_point(|q| q.t_ns <= p.t_ns);
                    self.pending.insert(k, p);
                }
                Err(r) => self.out.rejected.push(r),
            }
        } else if velocity_only {
            // a joint state without the machine's positions: its velocities go with the nominals
        } else if self.probe_topic.as_deref() == Some(m.topic.as_str())
            || self.camera_topic.as_deref() == Some(m.topic.as_str())
        {
            let at = at(&m.topic, self.instrument_index);
            self.instrument_index += 1;
            match instrument_pending(m, at, self.probe_topic.as_deref() == Some(m.topic.as_str())) {
                Ok(ps) => {
                    // a detection array's markers share its time: keep the queue in time order
                    for p in ps {
                        self.builder.observe_time(p.t_ns);
                        let k = self.pending.partition_point(|q| q.t_ns <= p.t_ns);
                        self.pending.insert(k, p);
                    }
                }
                Err(r) => self.out.rejected.push(r),
            }
        } else if let Some(which) = self.signal_topics.get(&m.topic) {
            self.feed.take(
                &mut self.builder,
                which,
                m,
                &self.source,
                self.model.machine,
            )?;
        }
        while self
            .pending
            .front()
            .is_some_and(|p| self.builder.ready(p.t_ns))
        {
            let p = self.pending.pop_front().expect("checked");
            resolve(
                p,
                &self.builder,
                &self.needs,
                self.model,
                &self.camera_features,
                self.commanded_positions && self.joints == JointSource::CommandedOrNominal,
                &mut self.out,
            );
        }
        Ok(())
    }

    /// Whether a commanded joint state (in [`JointSource::CommandedOrNominal`]) gives the
    /// machine's positions, to be fed as usual; if not, its velocities are kept for the
    /// nominals of its time.
    fn take_positions(&mut self, m: &SourcedMessage) -> bool {
        let Ok(js) = m.decode::<JointState>() else {
            return true;
        };
        let finite = |name: &String| {
            js.name
                .iter()
                .position(|n| n == name)
                .and_then(|i| js.position.get(i))
                .is_some_and(|v| v.is_finite())
        };
        if self.joint_names.iter().all(finite) {
            self.commanded_positions = true;
            return true;
        }
        if js.velocity.len() == js.name.len() {
            self.velocity_only.insert(
                message_time(&js.header.stamp, m.log_time_ns),
                (js.name, js.velocity),
            );
        }
        false
    }

    /// Push the joints from nominals stamped before `before` (all with None) to the builder,
    /// with the velocities a velocity-only joint state of their time gave.
    fn push_deferred_joints(&mut self, before: Option<i64>) {
        while self
            .deferred_joints
            .front()
            .is_some_and(|(t, _)| before.is_none_or(|b| *t < b))
        {
            let (t, q) = self.deferred_joints.pop_front().expect("checked");
            let velocities: Vec<f64> = match self.velocity_only.remove(&t) {
                Some((names, v)) => self
                    .joint_names
                    .iter()
                    .map(|j| names.iter().position(|n| n == j).map_or(f64::NAN, |i| v[i]))
                    .collect(),
                None => Vec::new(),
            };
            let _ = self
                .builder
                .push_joints(t, &self.joint_names, &q, &velocities);
            // velocities of earlier times no nominal took are not needed any more
            self.velocity_only = self.velocity_only.split_off(&t);
        }
    }

    /// Measurements still waiting for the signals around their time.
    pub fn waiting(&self) -> usize {
        self.pending.len()
    }

    /// The records and rejections resolved so far, taken out (an online user's window); the
    /// signal refusals are reported by [`Self::finish`].
    pub fn drain(&mut self) -> StreamOutput {
        StreamOutput {
            by_frame: std::mem::take(&mut self.out.by_frame),
            instrument_records: std::mem::take(&mut self.out.instrument_records),
            check: std::mem::take(&mut self.out.check),
            rejected: std::mem::take(&mut self.out.rejected),
            sources: self.out.sources.clone(),
        }
    }

    /// Answer every held measurement as the signals stand (the end of a recording; a live
    /// user that stops). The records come out at the next [`Self::drain`].
    pub fn flush(&mut self) {
        self.push_deferred_joints(None);
        while let Some(p) = self.pending.pop_front() {
            resolve(
                p,
                &self.builder,
                &self.needs,
                self.model,
                &self.camera_features,
                self.commanded_positions && self.joints == JointSource::CommandedOrNominal,
                &mut self.out,
            );
        }
    }

    /// The end of the recording: every held measurement is answered as the signals stand, and
    /// the signal samples refused per topic are reported.
    pub fn finish(mut self) -> StreamOutput {
        self.flush();
        self.out
            .rejected
            .extend(self.feed.into_rejected(&self.source));
        self.out
    }
}

/// Feeds signal messages to a builder, counting what it refuses per topic.
#[derive(Default)]
pub(crate) struct SignalFeed {
    refused: BTreeMap<String, Refused>,
}

impl SignalFeed {
    /// Feed one message. A commanded joint state without one of the machine's joints is an
    /// error (nothing could be interpolated); other refusals are counted.
    pub(crate) fn take(
        &mut self,
        builder: &mut SignalsBuilder,
        which: &SignalTopic,
        m: &SourcedMessage,
        path: &Path,
        machine: &MachineGeometry,
    ) -> Result<(), RecordingError> {
        if let Err(reason) = feed(builder, which, m) {
            if *which == SignalTopic::CommandedJoints && reason.starts_with("has no joint") {
                return Err(RecordingError::JointNames {
                    path: path.to_path_buf(),
                    topic: m.topic.clone(),
                    reason,
                    joints: machine.joint_names().join(", "),
                });
            }
            let r = self.refused.entry(m.topic.clone()).or_default();
            r.count += 1;
            r.first.get_or_insert((m.log_time_ns, reason));
        }
        Ok(())
    }

    pub(crate) fn into_rejected(self, path: &Path) -> Vec<Rejected> {
        self.refused
            .into_iter()
            .map(|(topic, r)| {
                let (t, reason) = r.first.unwrap_or_default();
                Rejected {
                    at: format!(
                        "{}: {topic} ({} messages, the first at log time {:.3} s)",
                        path.display(),
                        r.count,
                        t as f64 / 1e9
                    ),
                    point_id: String::new(),
                    reason: format!("signal samples not used: {reason}"),
                }
            })
            .collect()
    }
}

/// (term label, signal) of every declared term whose prediction reads a recorded signal
/// (scatter terms never enter a prediction; ranges and points the model computes itself).
pub(crate) fn declared_signals(model: &ForwardModel) -> Vec<(String, SignalKind)> {
    let mut out = Vec::new();
    for t in model
        .machine_terms
        .terms
        .iter()
        .chain(&model.instrument_terms.terms)
    {
        if t.term.effect() == EffectKind::RangeScatter {
            continue;
        }
        for s in t.term.signals() {
            if !s.is_computed_by_model() {
                out.push((t.term.label(), s));
            }
        }
    }
    out
}

/// Whether the instant's signals hold `kind`.
fn present(s: &Signals, kind: &SignalKind) -> bool {
    match kind {
        SignalKind::AxisPosition(a) => s.axis_position[a.index()].is_some(),
        SignalKind::ApproachDirection(a) => s.approach_direction[a.index()].is_some(),
        SignalKind::AxisVelocity(a) => s.axis_velocity[a.index()].is_some(),
        SignalKind::Temperature(n) => s.temperatures.contains_key(n),
        SignalKind::TemperatureHistory(n) => match (&s.timeline, s.time) {
            (Some(tl), Some(t)) => tl.time_span(n).is_some_and(|(first, _)| first <= t),
            _ => false,
        },
        SignalKind::AirTemperature => s.air_temperature.is_some(),
        SignalKind::AirPressure => s.air_pressure.is_some(),
        SignalKind::AirHumidity => s.air_humidity.is_some(),
        SignalKind::TimeSincePowerOn => s.time_since_power_on.is_some(),
        SignalKind::LoadForce => s.load_force.is_some(),
        SignalKind::RotaryPosition(a) => s.rotary_position[a.index()].is_some(),
        SignalKind::Time => s.time.is_some(),
        // without a base accelerometer the base is taken as level (said by the model's loader)
        SignalKind::Gravity => true,
        k => k.is_computed_by_model(),
    }
}

/// Where the commanded joints of a bag come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum JointSource {
    Commanded,
    /// q = nominal − tool_offset (cartesian and delta).
    Nominal,
    /// Commanded joint states where they give the machine's positions, else the nominals (an
    /// export with velocity columns but no joint columns), with the joint states' velocities.
    CommandedOrNominal,
}

/// A measurement waiting until the signals around its time have been read.
struct Pending {
    t_ns: i64,
    at: String,
    point_id: String,
    channel: String,
    frame: RecordFrame,
    measured: Vector3<f64>,
    covariance: Matrix3<f64>,
    /// The reading's own station air (°C, Pa, %RH), for tracker readings.
    air: Option<(f64, f64, f64)>,
    /// The commanded joints from the nominal ([`JointSource::Nominal`]).
    q: Option<Vec<f64>>,
    /// A probe hit's or a marker pose's reading (None: a point record).
    reading: Option<InstrumentReading>,
    /// A reference nest's reading: the nest's position (NaN where not given).
    nest: Option<Vector3<f64>>,
    /// The instrument's placement that read it (`<frame>@<setup>`).
    setup: Option<std::sync::Arc<str>>,
    /// A check point (`/check_points`): kept out of fits.
    check: bool,
}

fn covariance_row_major(c: &[f64; 9]) -> Matrix3<f64> {
    Matrix3::from_row_slice(c)
}

/// Names of a tracker reading's status flags.
fn status_flags(status: u8) -> String {
    let names = [
        (TrackerMeasurement::STATUS_BEAM_BREAK, "BEAM_BREAK"),
        (TrackerMeasurement::STATUS_WARMING_UP, "WARMING_UP"),
        (TrackerMeasurement::STATUS_TURBULENCE, "TURBULENCE"),
        (TrackerMeasurement::STATUS_OUT_OF_RANGE, "OUT_OF_RANGE"),
        (TrackerMeasurement::STATUS_REJECTED, "REJECTED"),
    ];
    let set: Vec<&str> = names
        .iter()
        .filter(|(bit, _)| status & bit != 0)
        .map(|(_, n)| *n)
        .collect();
    if set.is_empty() {
        format!("status {status}")
    } else {
        set.join(" | ")
    }
}

pub(crate) fn family(model: &ForwardModel) -> &'static str {
    match model.machine.kinematics {
        MachineKinematics::Cartesian(_) => "cartesian",
        MachineKinematics::Delta(_) => "delta",
        MachineKinematics::FiveAxis(_) => "five_axis",
        MachineKinematics::SerialArm(_) => "serial_arm",
    }
}

/// Signal samples a topic's messages gave that the builder refused: count and first reason.
#[derive(Default)]
struct Refused {
    count: u64,
    first: Option<(u64, String)>,
}

fn reject(at: String, point_id: &str, reason: impl Into<String>) -> Rejected {
    Rejected {
        at,
        point_id: point_id.to_string(),
        reason: reason.into(),
    }
}

/// Point and covariance checks shared by both sources.
fn check_point(
    at: &str,
    point_id: &str,
    measured: &Vector3<f64>,
    covariance: &Matrix3<f64>,
) -> Result<(), Rejected> {
    if !measured.iter().all(|v| v.is_finite()) {
        return Err(reject(
            at.into(),
            point_id,
            format!(
                "measured point ({}, {}, {}) m is not finite",
                measured.x, measured.y, measured.z
            ),
        ));
    }
    if !covariance.iter().all(|v| v.is_finite()) {
        return Err(reject(at.into(), point_id, "covariance is not finite"));
    }
    if whitening(covariance).is_none() {
        return Err(reject(
            at.into(),
            point_id,
            format!(
                "covariance is not positive definite (diagonal {:.3e}, {:.3e}, {:.3e} m²)",
                covariance[(0, 0)],
                covariance[(1, 1)],
                covariance[(2, 2)]
            ),
        ));
    }
    Ok(())
}

fn from_tracker(m: &SourcedMessage, at: String) -> Result<Pending, Rejected> {
    let r: TrackerMeasurement = m
        .decode()
        .map_err(|e| reject(at.clone(), "", e.to_string()))?;
    let point_id = r.target_id.clone();
    if r.status != TrackerMeasurement::STATUS_OK {
        return Err(reject(
            at,
            &point_id,
            format!("reading flagged {}", status_flags(r.status)),
        ));
    }
    let measured = Vector3::new(r.point.x, r.point.y, r.point.z);
    let covariance = covariance_row_major(&r.covariance);
    check_point(&at, &point_id, &measured, &covariance)?;
    let frame = if r.header.frame_id.is_empty() {
        RecordFrame::Instrument("tracker".into())
    } else {
        record_frame(&r.header.frame_id)
    };
    let air = [r.air_temperature, r.air_pressure, r.air_humidity]
        .iter()
        .all(|v| v.is_finite())
        .then_some((r.air_temperature, r.air_pressure, 100.0 * r.air_humidity));
    Ok(Pending {
        t_ns: message_time(&r.header.stamp, m.log_time_ns),
        at,
        point_id,
        channel: "tracker".into(),
        frame,
        measured,
        covariance,
        air,
        q: None,
        reading: None,
        nest: None,
        setup: frame_setup(&r.header.frame_id),
        check: false,
    })
}

/// The tool offset a nominal at `t_ns` is the point of: the recorded active one
/// (`/machine/tool_offset`, published before the readings it applies to), else the model's.
fn tool_offset_at(builder: &SignalsBuilder, model: &ForwardModel, t_ns: i64) -> Vector3<f64> {
    builder
        .tool_offset_at(t_ns)
        .unwrap_or(model.machine.tool_offset)
}

/// `commanded_positions`: the recording's joint states have given the machine's positions (in
/// [`JointSource::CommandedOrNominal`], the nominal then gives none). `tool_offset(t)`: the tool
/// offset the nominal at t includes.
fn from_measured_point(
    m: &SourcedMessage,
    at: String,
    joints: JointSource,
    tool_offset: impl Fn(i64) -> Vector3<f64>,
    commanded_positions: bool,
) -> Result<Pending, Rejected> {
    let p: MeasuredPoint = m
        .decode()
        .map_err(|e| reject(at.clone(), "", e.to_string()))?;
    let measured = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
    let covariance = covariance_row_major(&p.covariance);
    check_point(&at, &p.point_id, &measured, &covariance)?;
    let nominal = Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z);
    let q = match joints {
        JointSource::Commanded => None,
        // a row whose joint state gives positions is read from it (it may come after the point)
        JointSource::CommandedOrNominal
            if commanded_positions || !nominal.iter().all(|v| v.is_finite()) =>
        {
            None
        }
        JointSource::Nominal | JointSource::CommandedOrNominal => {
            if !nominal.iter().all(|v| v.is_finite()) {
                return Err(reject(
                    at,
                    &p.point_id,
                    format!("no commanded position: the point's nominal is not finite and {COMMANDED_JOINTS_TOPIC} gives no axis positions (bag import: columns nominal_x, nominal_y, nominal_z, or joint.x, joint.y, joint.z)"),
                ));
            }
            let q = nominal - tool_offset(message_time(&p.header.stamp, m.log_time_ns));
            Some(vec![q.x, q.y, q.z])
        }
    };
    Ok(Pending {
        t_ns: message_time(&p.header.stamp, m.log_time_ns),
        at,
        point_id: p.point_id,
        channel: p.source,
        frame: record_frame(&p.header.frame_id),
        measured,
        covariance,
        air: None,
        q,
        reading: None,
        nest: None,
        setup: frame_setup(&p.header.frame_id),
        check: false,
    })
}

/// A reference nest's reading (`/reference_points`): its point, no joints.
fn from_reference_point(m: &SourcedMessage, at: String) -> Result<Pending, Rejected> {
    let p: MeasuredPoint = m
        .decode()
        .map_err(|e| reject(at.clone(), "", e.to_string()))?;
    let measured = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
    let covariance = covariance_row_major(&p.covariance);
    check_point(&at, &p.point_id, &measured, &covariance)?;
    let nest = Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z);
    Ok(Pending {
        t_ns: message_time(&p.header.stamp, m.log_time_ns),
        at,
        point_id: p.point_id,
        channel: p.source,
        frame: record_frame(&p.header.frame_id),
        measured,
        covariance,
        air: None,
        q: Some(Vec::new()),
        reading: None,
        nest: Some(nest),
        setup: frame_setup(&p.header.frame_id),
        check: false,
    })
}

/// The measurements of a probe hit (`probe`) or a detection array, checked like points.
fn instrument_pending(
    m: &SourcedMessage,
    at: String,
    probe: bool,
) -> Result<Vec<Pending>, Rejected> {
    let (stamp, frame_id, measurements): (_, String, Vec<InstrumentMeasurement>) = if probe {
        let hit: ProbeHit = m
            .decode()
            .map_err(|e| reject(at.clone(), "", e.to_string()))?;
        let one =
            probe_measurement(&hit).map_err(|reason| reject(at.clone(), &hit.probe_id, reason))?;
        (hit.header.stamp, hit.header.frame_id, vec![one])
    } else {
        let array: FiducialDetectionArray = m
            .decode()
            .map_err(|e| reject(at.clone(), "", e.to_string()))?;
        let all = marker_measurements(&array);
        (array.header.stamp, array.header.frame_id, all)
    };
    let t_ns = message_time(&stamp, m.log_time_ns);
    let mut out = Vec::new();
    for x in measurements {
        check_point(&at, &x.point_id, &x.measured, &x.covariance)?;
        out.push(Pending {
            t_ns,
            at: at.clone(),
            point_id: x.point_id,
            channel: x.channel,
            frame: record_frame(&frame_id),
            measured: x.measured,
            covariance: x.covariance,
            air: None,
            q: None,
            reading: Some(x.reading),
            nest: None,
            setup: frame_setup(&frame_id),
            check: false,
        });
    }
    Ok(out)
}

/// The record of a measurement whose signals are all read, or why it is rejected.
/// `commanded`: the recording's joint states give the machine's positions, which then take
/// precedence over a point's nominal.
fn resolve(
    p: Pending,
    builder: &SignalsBuilder,
    needs: &[(String, SignalKind)],
    model: &ForwardModel,
    features: &CameraFeatures,
    commanded: bool,
    out: &mut StreamOutput,
) {
    // a reference nest has no joints (its q is empty), whatever the joint source
    let q = match p
        .q
        .filter(|q| !commanded || p.nest.is_some() && q.is_empty())
    {
        Some(q) => q,
        None => match builder.joints_at(p.t_ns) {
            Some(m) => m.positions,
            None => {
                let joints = model.machine.joint_names();
                out.rejected.push(reject(
                    p.at,
                    &p.point_id,
                    format!(
                        "no commanded position of {} at or around its time {:.3} s: {COMMANDED_JOINTS_TOPIC} has no sample with those joints' positions there (bag import: columns {})",
                        joints.join(", "),
                        p.t_ns as f64 / 1e9,
                        joints.iter().map(|j| format!("joint.{j}")).collect::<Vec<_>>().join(", ")
                    ),
                ));
                return;
            }
        },
    };
    let mut signals = builder.signals_at(p.t_ns);
    signals.setup = p.setup.clone();
    // a robot's gravity from its base's accelerometer (the ground's tilt)
    if let metrocell_model::MachineKinematics::SerialArm(arm) = &model.machine.kinematics {
        signals.gravity = arm.gravity_from(&signals.accelerations);
    }
    if let Some((t, pa, h)) = p.air {
        (
            signals.air_temperature,
            signals.air_pressure,
            signals.air_humidity,
        ) = (Some(t), Some(pa), Some(h));
    }
    // a probe hit or a camera point reads the machine's terms (and its own instrument's, which
    // read nothing recorded), not a tracker's
    let reads = |term: &str| match (&p.reading, p.nest) {
        // a reference nest: only the instrument's terms act on its reading
        (_, Some(_)) => model
            .instrument_terms
            .terms
            .iter()
            .any(|t| t.term.label() == term),
        (None, None) => true,
        (Some(_), None) => model
            .machine_terms
            .terms
            .iter()
            .any(|t| t.term.label() == term),
    };
    if let Some((term, kind)) = needs
        .iter()
        .find(|(term, k)| reads(term) && !present(&signals, k))
    {
        let why = match kind {
            SignalKind::ApproachDirection(_) => "the axis has not moved yet in the recording, and its approach is the sign of its last motion (set the signals option initial_approach when the homing direction is known)",
            SignalKind::TimeSincePowerOn => "the instrument's power-on time is after it",
            _ => "before its first sample, after its last, or in a gap",
        };
        out.rejected.push(reject(
            p.at,
            &p.point_id,
            format!(
                "term `{term}` needs {kind}, which the recording does not give at {:.3} s: {why}",
                p.t_ns as f64 / 1e9
            ),
        ));
        return;
    }
    let kind = match &p.reading {
        None if p.nest.is_some() => RecordKind::Reference {
            nest: p.nest.expect("checked"),
        },
        None => RecordKind::Point,
        Some(reading) => match record_kind(model, features, reading, &q) {
            Ok(kind) => kind,
            Err(reason) => {
                out.rejected.push(reject(p.at, &p.point_id, reason));
                return;
            }
        },
    };
    let record = MeasurementRecord {
        time: p.t_ns as f64 / 1e9,
        point_id: p.point_id,
        channel: p.channel,
        q,
        measured: p.measured,
        covariance: p.covariance,
        signals,
        kind,
    };
    if p.reading.is_some() {
        out.instrument_records.push(record);
        return;
    }
    if p.check {
        out.check.push(record);
        return;
    }
    match out.by_frame.iter_mut().find(|(f, _)| *f == p.frame) {
        Some((_, v)) => v.push(record),
        None => out.by_frame.push((p.frame, vec![record])),
    }
}
