//! Measurement records from recordings: [`records_from_bags`] turns bags — recorded from the
//! nodes, simulated by `metrocell sim`, or imported with `bag import` — into a [`RecordSet`]
//! for the shared model, each record with its point, covariance, commanded joints and the
//! `Signals` at its time (built by [`metrocell_model::SignalsBuilder`] from the recorded
//! streams, [`crate::signal_topics`]).
//!
//! Points come from one of two sources (option [`PointSource`]; `Auto` takes
//! `/measured_points` when the bag has it, else `/tracker/measurements`):
//! * `/measured_points` (`metrocell_msgs/MeasuredPoint`: the tracker node's output, `bag
//!   import`'s): `measured` with its covariance, in the frame `header.frame_id`;
//! * `/tracker/measurements` (`metrocell_msgs/TrackerMeasurement`, raw readings as `metrocell
//!   sim` and instrument drivers publish them): `point` with its covariance in the tracker
//!   frame; a reading whose `status` is not `STATUS_OK` is rejected with its flags named. The
//!   station air a reading carries is the air of its record (it is what the instrument applied).
//!
//! Frame (stated once): `header.frame_id` `machine`, `workpiece` or empty means the machine
//! (workpiece) frame → [`RecordFrame::Machine`] (instrument pose identity, fixed); any other
//! name is an instrument frame → [`RecordFrame::Instrument`] (the fit estimates the pose; `bag
//! import` writes `import` unless its mapping names a frame). A tracker reading with an empty
//! frame is in `tracker`. All records of a set share one frame, or it is an error.
//!
//! Commanded joints `q` of a record: `/machine/commanded_joint_states` interpolated at its time
//! (the machine's joint names must all be there). Without that topic, a `MeasuredPoint`'s
//! `nominal` (the commanded tool point, machine frame, as `bag import` and the tracker node
//! write it) gives `q = nominal − tool_offset` on cartesian and delta machines (the inverse of
//! [`metrocell_model::MachineGeometry::nominal_tool_point`]); five-axis machines and arms need
//! the joints (an error says which topic or columns).
//!
//! Checks, in order: a bag that cannot be read is an error naming the file (the bag reader's
//! own, e.g. a truncated MCAP); a signal a declared term needs that the bag does not hold at all
//! is an error naming the term, the signal and the topics / `bag import` columns that would
//! provide it ([`providers`]); per measurement, a non-finite point or covariance, a covariance
//! that is not positive definite, a flagged reading, or a signal the recording cannot give at
//! that instant (before the first temperature sample, inside a gap of the joint stream) rejects
//! that measurement — counted in [`RecordSet::rejected`] with where it was — and the rest
//! proceeds. Signal samples the builder refuses (a time going backwards, a NaN) are reported
//! there too, one entry per topic, with an empty `point_id`.
//!
//! Probe hits (`/probe/hits`) and camera marker poses (`/fiducials`) become records too when the
//! options ask for them ([`RecordingOptions::probe_hits`], [`RecordingOptions::camera_points`]):
//! [`crate::instrument_readings`] says what they measure and how their nominal is found. They are
//! in the frame of their reading (workpiece, camera), so they take no part in the set's frame.
//!
//! Several bags are concatenated; each is its own recording (its own signals and temperature
//! timeline: a lag restarts at each bag's first sample), so bags of different runs may overlap
//! in time.

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};

use metrocell_bagtools::{BagSource, SourcedMessage};
use metrocell_model::{ForwardModel, MachineGeometry, MachineKinematics, SignalsBuilder, SignalsBuilderOptions};
use metrocell_msgs::msg::{FiducialDetectionArray, MeasuredPoint, ProbeHit, TrackerMeasurement};
use metrocell_msgs::RosMessage;
use metrocell_physics::{Axis, EffectKind, SignalKind, Signals};
use nalgebra::{Matrix3, Vector3};

use crate::instrument_readings::{marker_measurements, probe_measurement, record_kind, CameraFeatures, InstrumentMeasurement, InstrumentReading};
use crate::records::{MeasurementRecord, RecordFrame, RecordKind, RecordSet, Rejected};
use crate::residuals::whitening;
use crate::signal_topics::{feed, message_time, SignalTopic, AIR_SENSOR, COMMANDED_JOINTS_TOPIC, LOAD_TOPIC, POWER_ON_TOPIC};

pub const MEASURED_POINTS_TOPIC: &str = "/measured_points";
pub const TRACKER_TOPIC: &str = "/tracker/measurements";
pub const PROBE_TOPIC: &str = "/probe/hits";
pub const CAMERA_TOPIC: &str = "/fiducials";

/// Which messages become records.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointSource {
    /// `/measured_points` when the bag has it, else `/tracker/measurements`.
    Auto,
    MeasuredPoints,
    TrackerMeasurements,
}

/// Options of [`records_from_bags`].
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingOptions {
    pub points: PointSource,
    /// Topic of the `MeasuredPoint`s (e.g. `/measured_points/thermal_compensated`).
    pub measured_points_topic: String,
    /// Topic of the raw `TrackerMeasurement`s.
    pub tracker_topic: String,
    /// How signals are interpolated (its `joint_window` is set here, for bounded memory).
    pub signals: SignalsBuilderOptions,
    /// Also make records of the probe hits on `probe_topic` (`metrocell_msgs/ProbeHit`).
    pub probe_hits: bool,
    pub probe_topic: String,
    /// Also make records of the marker poses on `camera_topic`
    /// (`metrocell_msgs/FiducialDetectionArray`), the markers' nominals from `camera_features`.
    pub camera_points: bool,
    pub camera_topic: String,
    pub camera_features: CameraFeatures,
}

impl Default for RecordingOptions {
    fn default() -> Self {
        Self {
            points: PointSource::Auto,
            measured_points_topic: MEASURED_POINTS_TOPIC.into(),
            tracker_topic: TRACKER_TOPIC.into(),
            signals: SignalsBuilderOptions::default(),
            probe_hits: false,
            probe_topic: PROBE_TOPIC.into(),
            camera_points: false,
            camera_topic: CAMERA_TOPIC.into(),
            camera_features: CameraFeatures::default(),
        }
    }
}

/// Why records could not be built.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    #[error("{}: {reason}", path.display())]
    Bag { path: PathBuf, reason: String },
    #[error("{}: no measurements to build records from: the bag has neither {measured} (metrocell_msgs/MeasuredPoint) nor {tracker} (metrocell_msgs/TrackerMeasurement); it holds: {held}", path.display())]
    NoPoints { path: PathBuf, measured: String, tracker: String, held: String },
    #[error("term `{term}` needs the signal {signal}, which {} does not hold: {provide}", path.display())]
    MissingSignal { path: PathBuf, term: String, signal: String, provide: String },
    #[error("{}: the records need the commanded joints of this {family} machine, and the bag has none: {provide}", path.display())]
    NoJoints { path: PathBuf, family: String, provide: String },
    #[error("{}: {topic} {reason}, but the model's machine has joints {joints}: record the commanded joints under the machine's names (bag import: columns joint.<name>)", path.display())]
    JointNames { path: PathBuf, topic: String, reason: String, joints: String },
    #[error("the measurements are in different frames ({frames}); a record set holds one frame: build one set per frame")]
    MixedFrames { frames: String },
}

/// The records of `bags` for `model` (module docs: sources, frames, checks).
pub fn records_from_bags<P: AsRef<Path>>(bags: &[P], model: &ForwardModel, options: &RecordingOptions) -> Result<RecordSet, RecordingError> {
    let needs = declared_signals(model);
    let mut set = RecordSet { frame: RecordFrame::Machine, records: Vec::new(), rejected: Vec::new(), sources: Vec::new() };
    let mut frames: BTreeMap<String, (RecordFrame, usize)> = BTreeMap::new();
    for bag in bags {
        let part = bag_records(bag.as_ref(), model, &needs, options)?;
        for (frame, records) in part.by_frame {
            frames.entry(frame_name(&frame)).or_insert((frame, 0)).1 += records.len();
            set.records.extend(records);
        }
        set.records.extend(part.instrument_records);
        set.rejected.extend(part.rejected);
        for s in part.sources {
            if !set.sources.contains(&s) {
                set.sources.push(s);
            }
        }
    }
    if frames.len() > 1 {
        let frames = frames.iter().map(|(name, (_, n))| format!("{n} in `{name}`")).collect::<Vec<_>>().join(", ");
        return Err(RecordingError::MixedFrames { frames });
    }
    if let Some((_, (frame, _))) = frames.into_iter().next() {
        set.frame = frame;
    }
    Ok(set)
}

/// Every signal a bag holds, read whole into a builder (no window): for tools and tests that
/// look at the signals at any instant. Signal samples the builder refused are returned as
/// [`Rejected`] entries, one per topic. [`records_from_bags`] streams instead.
pub fn signals_from_bag(path: &Path, machine: &MachineGeometry, options: &SignalsBuilderOptions) -> Result<(SignalsBuilder, Vec<Rejected>), RecordingError> {
    let mut bag = OpenedBag::open(path)?;
    bag.subscribe_signals();
    let mut builder = SignalsBuilder::for_machine(machine, SignalsBuilderOptions { joint_window: None, ..options.clone() });
    let mut feed = SignalFeed::default();
    for m in bag.source.messages().map_err(|e| bag_error(path, e))? {
        let m = m.map_err(|e| bag_error(path, e))?;
        builder.observe_time(m.log_time_ns as i64);
        if let Some(which) = bag.signal_topics.get(&m.topic) {
            feed.take(&mut builder, which, &m, path, machine)?;
        }
    }
    Ok((builder, feed.into_rejected(path)))
}

fn bag_error(path: &Path, e: metrocell_bagtools::ToolError) -> RecordingError {
    RecordingError::Bag { path: path.to_path_buf(), reason: e.to_string() }
}

/// A bag opened for records: its topics and the ones that carry signals.
struct OpenedBag {
    source: BagSource,
    /// (name, type) of every topic.
    topics: Vec<(String, String)>,
    signal_topics: BTreeMap<String, SignalTopic>,
}

impl OpenedBag {
    fn open(path: &Path) -> Result<Self, RecordingError> {
        let source = BagSource::open(path).map_err(|e| bag_error(path, e))?;
        let topics: Vec<(String, String)> = source.topics().iter().map(|t| (t.name.clone(), t.type_name.clone())).collect();
        let signal_topics = topics.iter().filter_map(|(n, t)| SignalTopic::of(n, t).map(|w| (n.clone(), w))).collect();
        Ok(Self { source, topics, signal_topics })
    }
    fn has(&self, name: &str, ty: &str) -> bool {
        self.topics.iter().any(|(n, t)| n == name && t == ty)
    }
    fn carries(&self, which: &SignalTopic) -> bool {
        self.signal_topics.values().any(|w| w == which)
    }
    fn subscribe_signals(&mut self) {
        for name in self.signal_topics.keys() {
            self.source.subscribe_any(name);
        }
    }
    /// Tell the builder which sampled streams this bag will feed, so a measurement waits for
    /// the samples stamped at or after it (see `SignalsBuilder::ready`).
    fn declare_streams(&self, builder: &mut SignalsBuilder) {
        for which in self.signal_topics.values() {
            match which {
                SignalTopic::CommandedJoints => builder.expect_joints(),
                SignalTopic::Temperature(sensor) => {
                    builder.expect_temperature(sensor);
                    if sensor == AIR_SENSOR {
                        builder.expect_air(0);
                    }
                }
                SignalTopic::AirTemperature => builder.expect_air(0),
                SignalTopic::AirPressure => builder.expect_air(1),
                SignalTopic::AirHumidity => builder.expect_air(2),
                SignalTopic::Approach | SignalTopic::PowerOn | SignalTopic::Load => {}
            }
        }
    }
}

/// Feeds signal messages to a builder, counting what it refuses per topic.
#[derive(Default)]
struct SignalFeed {
    refused: BTreeMap<String, Refused>,
}

impl SignalFeed {
    /// Feed one message. A commanded joint state without one of the machine's joints is an
    /// error (nothing could be interpolated); other refusals are counted.
    fn take(&mut self, builder: &mut SignalsBuilder, which: &SignalTopic, m: &SourcedMessage, path: &Path, machine: &MachineGeometry) -> Result<(), RecordingError> {
        if let Err(reason) = feed(builder, which, m) {
            if *which == SignalTopic::CommandedJoints && reason.starts_with("has no joint") {
                return Err(RecordingError::JointNames { path: path.to_path_buf(), topic: m.topic.clone(), reason, joints: machine.joint_names().join(", ") });
            }
            let r = self.refused.entry(m.topic.clone()).or_default();
            r.count += 1;
            r.first.get_or_insert((m.log_time_ns, reason));
        }
        Ok(())
    }

    fn into_rejected(self, path: &Path) -> Vec<Rejected> {
        self.refused
            .into_iter()
            .map(|(topic, r)| {
                let (t, reason) = r.first.unwrap_or_default();
                Rejected {
                    at: format!("{}: {topic} ({} messages, the first at log time {:.3} s)", path.display(), r.count, t as f64 / 1e9),
                    point_id: String::new(),
                    reason: format!("signal samples not used: {reason}"),
                }
            })
            .collect()
    }
}

/// The frame a `header.frame_id` names (module docs).
pub fn record_frame(frame_id: &str) -> RecordFrame {
    match frame_id {
        "" | "machine" | "workpiece" => RecordFrame::Machine,
        other => RecordFrame::Instrument(other.to_string()),
    }
}

fn frame_name(f: &RecordFrame) -> String {
    match f {
        RecordFrame::Machine => "machine".into(),
        RecordFrame::Instrument(n) => n.clone(),
    }
}

/// The topics and `bag import` columns that provide a signal (for error messages).
pub fn providers(kind: &SignalKind) -> String {
    let axis = |a: &Axis| format!("{COMMANDED_JOINTS_TOPIC} with joint `{a}`, or on cartesian and delta machines the measured points' nominals (bag import: column joint.{a} or nominal_{a})");
    match kind {
        SignalKind::AxisPosition(a) => format!("record {}", axis(a)),
        SignalKind::ApproachDirection(a) => format!("record {} (the approach is the sign of the last motion), or /machine/approach_directions (bag import: column approach.{a})", axis(a)),
        SignalKind::AxisVelocity(a) => format!("record {} (velocity from its `velocity` field, else from the trajectory; bag import: column velocity.{a})", axis(a)),
        SignalKind::Temperature(s) | SignalKind::TemperatureHistory(s) => format!("record /temperature/{s} (sensor_msgs/Temperature; bag import: column temperature.{s})"),
        SignalKind::AirTemperature => "record /temperature/air or /weather/temperature, or use /tracker/measurements (each reading carries its station air; bag import: column temperature.air)".into(),
        SignalKind::AirPressure => "record /air/pressure or /weather/pressure (sensor_msgs/FluidPressure), or use /tracker/measurements (bag import: column pressure)".into(),
        SignalKind::AirHumidity => "record /air/humidity or /weather/humidity (sensor_msgs/RelativeHumidity), or use /tracker/measurements (bag import: column humidity)".into(),
        SignalKind::TimeSincePowerOn => format!("record {POWER_ON_TOPIC} (sensor_msgs/TimeReference, time_ref = when the instrument was switched on; bag import: column instrument_on_time)"),
        SignalKind::LoadForce => format!("record {LOAD_TOPIC} (geometry_msgs/WrenchStamped, force in N, machine frame)"),
        SignalKind::RotaryPosition(a) => format!("record {COMMANDED_JOINTS_TOPIC} with joint `{}` (bag import: column joint.{})", a.name(), a.name()),
        SignalKind::TrackerRange | SignalKind::ImagePoint | SignalKind::MachinePoint | SignalKind::WorkpiecePoint | SignalKind::TargetPoint | SignalKind::CameraPoint | SignalKind::ProbeDirection => "it is computed by the model".into(),
    }
}

/// (term label, signal) of every declared term whose prediction reads a recorded signal
/// (scatter terms never enter a prediction; ranges and points the model computes itself).
fn declared_signals(model: &ForwardModel) -> Vec<(String, SignalKind)> {
    let mut out = Vec::new();
    for t in model.machine_terms.terms.iter().chain(&model.instrument_terms.terms) {
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
        k => k.is_computed_by_model(),
    }
}

/// Where the commanded joints of a bag come from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum JointSource {
    Commanded,
    /// q = nominal − tool_offset (cartesian and delta).
    Nominal,
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
}

struct BagRecords {
    by_frame: Vec<(RecordFrame, Vec<MeasurementRecord>)>,
    /// Probe hits and camera points (in the frames of their readings).
    instrument_records: Vec<MeasurementRecord>,
    rejected: Vec<Rejected>,
    sources: Vec<(String, String)>,
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
    let set: Vec<&str> = names.iter().filter(|(bit, _)| status & bit != 0).map(|(_, n)| *n).collect();
    if set.is_empty() {
        format!("status {status}")
    } else {
        set.join(" | ")
    }
}

fn family(model: &ForwardModel) -> &'static str {
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

fn bag_records(path: &Path, model: &ForwardModel, needs: &[(String, SignalKind)], options: &RecordingOptions) -> Result<BagRecords, RecordingError> {
    let mut bag = OpenedBag::open(path)?;
    let points_tracker = match options.points {
        PointSource::MeasuredPoints => false,
        PointSource::TrackerMeasurements => true,
        PointSource::Auto => !bag.has(&options.measured_points_topic, MeasuredPoint::ROS_TYPE),
    };
    let (points_topic, points_type) = if points_tracker { (&options.tracker_topic, TrackerMeasurement::ROS_TYPE) } else { (&options.measured_points_topic, MeasuredPoint::ROS_TYPE) };
    let found = if points_tracker { bag.source.subscribe::<TrackerMeasurement>(points_topic) } else { bag.source.subscribe::<MeasuredPoint>(points_topic) }.map_err(|e| bag_error(path, e))?;
    let probes = options.probe_hits && bag.source.subscribe::<ProbeHit>(&options.probe_topic).map_err(|e| bag_error(path, e))?;
    let cameras = options.camera_points && bag.source.subscribe::<FiducialDetectionArray>(&options.camera_topic).map_err(|e| bag_error(path, e))?;
    if !(found || probes || cameras) {
        let held = bag.topics.iter().map(|(n, t)| format!("{n} ({t})")).collect::<Vec<_>>().join(", ");
        return Err(RecordingError::NoPoints { path: path.to_path_buf(), measured: options.measured_points_topic.clone(), tracker: options.tracker_topic.clone(), held: if held.is_empty() { "no topics".into() } else { held } });
    }
    let mut sources = Vec::new();
    if found {
        sources.push(("points".to_string(), format!("{points_topic} ({points_type})")));
    }
    if probes {
        sources.push(("probe hits".to_string(), format!("{} ({})", options.probe_topic, ProbeHit::ROS_TYPE)));
    }
    if cameras {
        sources.push(("camera points".to_string(), format!("{} ({})", options.camera_topic, FiducialDetectionArray::ROS_TYPE)));
    }
    bag.subscribe_signals();
    let carried = |which: &SignalTopic| bag.carries(which);
    let joints = if carried(&SignalTopic::CommandedJoints) {
        JointSource::Commanded
    } else if found && !points_tracker && matches!(model.machine.kinematics, MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_)) {
        JointSource::Nominal
    } else {
        let names = model.machine.joint_names();
        let provide = if points_tracker {
            format!("record {COMMANDED_JOINTS_TOPIC} (joints {}) next to {points_topic}", names.join(", "))
        } else {
            format!("record {COMMANDED_JOINTS_TOPIC} (joints {}), or import the CSV with columns {} (the nominal point alone gives the joints only on cartesian and delta machines)", names.join(", "), names.iter().map(|n| format!("joint.{n}")).collect::<Vec<_>>().join(", "))
        };
        return Err(RecordingError::NoJoints { path: path.to_path_buf(), family: family(model).into(), provide });
    };
    sources.push(("commanded joints".into(), match joints {
        JointSource::Commanded => COMMANDED_JOINTS_TOPIC.into(),
        JointSource::Nominal => format!("nominal of {points_topic}, minus the tool offset"),
    }));

    // every declared signal must have a source in this bag
    for (term, kind) in needs {
        let (available, from) = match kind {
            SignalKind::AxisPosition(_) | SignalKind::AxisVelocity(_) => (true, None),
            SignalKind::ApproachDirection(_) => (true, carried(&SignalTopic::Approach).then(|| "/machine/approach_directions".to_string())),
            SignalKind::Temperature(s) | SignalKind::TemperatureHistory(s) => (carried(&SignalTopic::Temperature(s.clone())), Some(format!("/temperature/{s}"))),
            SignalKind::AirTemperature => (points_tracker || carried(&SignalTopic::AirTemperature) || carried(&SignalTopic::Temperature(AIR_SENSOR.into())), None),
            SignalKind::AirPressure => (points_tracker || carried(&SignalTopic::AirPressure), None),
            SignalKind::AirHumidity => (points_tracker || carried(&SignalTopic::AirHumidity), None),
            SignalKind::TimeSincePowerOn => (carried(&SignalTopic::PowerOn), Some(POWER_ON_TOPIC.to_string())),
            SignalKind::LoadForce => (carried(&SignalTopic::Load), Some(LOAD_TOPIC.to_string())),
            _ => (true, None),
        };
        if !available {
            return Err(RecordingError::MissingSignal { path: path.to_path_buf(), term: term.clone(), signal: kind.to_string(), provide: providers(kind) });
        }
        if let Some(topic) = from {
            let entry = (kind.to_string(), topic);
            if !sources.contains(&entry) {
                sources.push(entry);
            }
        }
    }
    if points_tracker {
        sources.push(("air".into(), format!("each reading's own station air ({points_topic})")));
    } else {
        let air: Vec<&str> = bag.signal_topics.iter().filter(|(_, w)| matches!(w, SignalTopic::AirTemperature | SignalTopic::AirPressure | SignalTopic::AirHumidity) || **w == SignalTopic::Temperature(AIR_SENSOR.into())).map(|(n, _)| n.as_str()).collect();
        if !air.is_empty() {
            sources.push(("air".into(), air.join(", ")));
        }
    }

    // read in log-time order; resolve each measurement once the signals around it are read
    let mut signal_options = options.signals.clone();
    signal_options.joint_window = Some(options.signals.max_slow_gap + options.signals.max_joint_gap + 60.0);
    let mut builder = SignalsBuilder::for_machine(model.machine, signal_options);
    bag.declare_streams(&mut builder);
    let mut pending: VecDeque<Pending> = VecDeque::new();
    let mut out = BagRecords { by_frame: Vec::new(), instrument_records: Vec::new(), rejected: Vec::new(), sources };
    let mut instrument_index = 0u64;
    let mut feed = SignalFeed::default();
    let mut point_index = 0u64;
    let joint_names = model.machine.joint_names();
    let tool_offset = model.machine.tool_offset;
    for m in bag.source.messages().map_err(|e| bag_error(path, e))? {
        let m: SourcedMessage = m.map_err(|e| bag_error(path, e))?;
        // The time the recording has reached is taken from the stamps (the points' below, the
        // signal samples' as the builder takes them), the time base of every instant it is asked
        // about, not from the log time: in a bag recorded live from a twin running faster than
        // real time, log time (the wall clock) is far from the stamps (simulated time, from a set day),
        // and, ahead of them, would declare every measurement ready before the samples bracketing
        // it were read.
        if &m.topic == points_topic {
            let at = format!("{}: {} message {point_index} (log time {:.3} s)", path.display(), m.topic, m.log_time_ns as f64 / 1e9);
            point_index += 1;
            let parsed = if points_tracker { from_tracker(&m, at.clone()) } else { from_measured_point(&m, at.clone(), joints, &tool_offset) };
            match parsed {
                Ok(p) => {
                    builder.observe_time(p.t_ns);
                    if let (JointSource::Nominal, Some(q)) = (joints, &p.q) {
                        // the nominals are the commanded trajectory: they give approach and velocity too
                        let _ = builder.push_joints(p.t_ns, &joint_names, q, &[]);
                    }
                    pending.push_back(p);
                }
                Err(r) => out.rejected.push(r),
            }
        } else if (probes && m.topic == options.probe_topic) || (cameras && m.topic == options.camera_topic) {
            let at = format!("{}: {} message {instrument_index} (log time {:.3} s)", path.display(), m.topic, m.log_time_ns as f64 / 1e9);
            instrument_index += 1;
            match instrument_pending(&m, at, m.topic == options.probe_topic) {
                Ok(ps) => {
                    // a detection array's markers share its time: keep the queue in time order
                    for p in ps {
                        let at = pending.partition_point(|q| q.t_ns <= p.t_ns);
                        pending.insert(at, p);
                    }
                }
                Err(r) => out.rejected.push(r),
            }
        } else if let Some(which) = bag.signal_topics.get(&m.topic) {
            feed.take(&mut builder, which, &m, path, model.machine)?;
        }
        while pending.front().is_some_and(|p| builder.ready(p.t_ns)) {
            let p = pending.pop_front().expect("checked");
            resolve(p, &builder, needs, model, &options.camera_features, &mut out);
        }
    }
    while let Some(p) = pending.pop_front() {
        resolve(p, &builder, needs, model, &options.camera_features, &mut out);
    }
    out.rejected.extend(feed.into_rejected(path));
    Ok(out)
}

fn reject(at: String, point_id: &str, reason: impl Into<String>) -> Rejected {
    Rejected { at, point_id: point_id.to_string(), reason: reason.into() }
}

/// Point and covariance checks shared by both sources.
fn check_point(at: &str, point_id: &str, measured: &Vector3<f64>, covariance: &Matrix3<f64>) -> Result<(), Rejected> {
    if !measured.iter().all(|v| v.is_finite()) {
        return Err(reject(at.into(), point_id, format!("measured point ({}, {}, {}) m is not finite", measured.x, measured.y, measured.z)));
    }
    if !covariance.iter().all(|v| v.is_finite()) {
        return Err(reject(at.into(), point_id, "covariance is not finite"));
    }
    if whitening(covariance).is_none() {
        return Err(reject(at.into(), point_id, format!("covariance is not positive definite (diagonal {:.3e}, {:.3e}, {:.3e} m²)", covariance[(0, 0)], covariance[(1, 1)], covariance[(2, 2)])));
    }
    Ok(())
}

fn from_tracker(m: &SourcedMessage, at: String) -> Result<Pending, Rejected> {
    let r: TrackerMeasurement = m.decode().map_err(|e| reject(at.clone(), "", e.to_string()))?;
    let point_id = r.target_id.clone();
    if r.status != TrackerMeasurement::STATUS_OK {
        return Err(reject(at, &point_id, format!("reading flagged {}", status_flags(r.status))));
    }
    let measured = Vector3::new(r.point.x, r.point.y, r.point.z);
    let covariance = covariance_row_major(&r.covariance);
    check_point(&at, &point_id, &measured, &covariance)?;
    let frame = if r.header.frame_id.is_empty() { RecordFrame::Instrument("tracker".into()) } else { record_frame(&r.header.frame_id) };
    let air = [r.air_temperature, r.air_pressure, r.air_humidity].iter().all(|v| v.is_finite()).then_some((r.air_temperature, r.air_pressure, 100.0 * r.air_humidity));
    Ok(Pending { t_ns: message_time(&r.header.stamp, m.log_time_ns), at, point_id, channel: "tracker".into(), frame, measured, covariance, air, q: None, reading: None })
}

fn from_measured_point(m: &SourcedMessage, at: String, joints: JointSource, tool_offset: &Vector3<f64>) -> Result<Pending, Rejected> {
    let p: MeasuredPoint = m.decode().map_err(|e| reject(at.clone(), "", e.to_string()))?;
    let measured = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
    let covariance = covariance_row_major(&p.covariance);
    check_point(&at, &p.point_id, &measured, &covariance)?;
    let q = match joints {
        JointSource::Commanded => None,
        JointSource::Nominal => {
            let nominal = Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z);
            if !nominal.iter().all(|v| v.is_finite()) {
                return Err(reject(at, &p.point_id, format!("no commanded position: the nominal is not finite and the bag has no {COMMANDED_JOINTS_TOPIC}")));
            }
            let q = nominal - tool_offset;
            Some(vec![q.x, q.y, q.z])
        }
    };
    Ok(Pending { t_ns: message_time(&p.header.stamp, m.log_time_ns), at, point_id: p.point_id, channel: p.source, frame: record_frame(&p.header.frame_id), measured, covariance, air: None, q, reading: None })
}

/// The measurements of a probe hit (`probe`) or a detection array, checked like points.
fn instrument_pending(m: &SourcedMessage, at: String, probe: bool) -> Result<Vec<Pending>, Rejected> {
    let (stamp, frame_id, measurements): (_, String, Vec<InstrumentMeasurement>) = if probe {
        let hit: ProbeHit = m.decode().map_err(|e| reject(at.clone(), "", e.to_string()))?;
        let one = probe_measurement(&hit).map_err(|reason| reject(at.clone(), &hit.probe_id, reason))?;
        (hit.header.stamp, hit.header.frame_id, vec![one])
    } else {
        let array: FiducialDetectionArray = m.decode().map_err(|e| reject(at.clone(), "", e.to_string()))?;
        let all = marker_measurements(&array);
        (array.header.stamp, array.header.frame_id, all)
    };
    let t_ns = message_time(&stamp, m.log_time_ns);
    let mut out = Vec::new();
    for x in measurements {
        check_point(&at, &x.point_id, &x.measured, &x.covariance)?;
        out.push(Pending { t_ns, at: at.clone(), point_id: x.point_id, channel: x.channel, frame: record_frame(&frame_id), measured: x.measured, covariance: x.covariance, air: None, q: None, reading: Some(x.reading) });
    }
    Ok(out)
}

/// The record of a measurement whose signals are all read, or why it is rejected.
fn resolve(p: Pending, builder: &SignalsBuilder, needs: &[(String, SignalKind)], model: &ForwardModel, features: &CameraFeatures, out: &mut BagRecords) {
    let q = match p.q {
        Some(q) => q,
        None => match builder.joints_at(p.t_ns) {
            Some(m) => m.positions,
            None => {
                out.rejected.push(reject(p.at, &p.point_id, format!("no commanded joint state at or around its time {:.3} s (a gap in {COMMANDED_JOINTS_TOPIC}, or outside it)", p.t_ns as f64 / 1e9)));
                return;
            }
        },
    };
    let mut signals = builder.signals_at(p.t_ns);
    if let Some((t, pa, h)) = p.air {
        (signals.air_temperature, signals.air_pressure, signals.air_humidity) = (Some(t), Some(pa), Some(h));
    }
    // a probe hit or a camera point reads the machine's terms (and its own instrument's, which
    // read nothing recorded), not a tracker's
    let reads = |term: &str| p.reading.is_none() || model.machine_terms.terms.iter().any(|t| t.term.label() == term);
    if let Some((term, kind)) = needs.iter().find(|(term, k)| reads(term) && !present(&signals, k)) {
        let why = match kind {
            SignalKind::ApproachDirection(_) => "the axis has not moved yet in the recording, and its approach is the sign of its last motion (set the signals option initial_approach when the homing direction is known)",
            SignalKind::TimeSincePowerOn => "the instrument's power-on time is after it",
            _ => "before its first sample, after its last, or in a gap",
        };
        out.rejected.push(reject(p.at, &p.point_id, format!("term `{term}` needs {kind}, which the recording does not give at {:.3} s: {why}", p.t_ns as f64 / 1e9)));
        return;
    }
    let kind = match &p.reading {
        None => RecordKind::Point,
        Some(reading) => match record_kind(model, features, reading, &q) {
            Ok(kind) => kind,
            Err(reason) => {
                out.rejected.push(reject(p.at, &p.point_id, reason));
                return;
            }
        },
    };
    let record = MeasurementRecord { time: p.t_ns as f64 / 1e9, point_id: p.point_id, channel: p.channel, q, measured: p.measured, covariance: p.covariance, signals, kind };
    if p.reading.is_some() {
        out.instrument_records.push(record);
        return;
    }
    match out.by_frame.iter_mut().find(|(f, _)| *f == p.frame) {
        Some((_, v)) => v.push(record),
        None => out.by_frame.push((p.frame, vec![record])),
    }
}
