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

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metrocell_bagtools::BagSource;
use metrocell_model::{ForwardModel, MachineGeometry, SignalsBuilder, SignalsBuilderOptions};
use metrocell_physics::{Axis, SignalKind};

use crate::instrument_readings::CameraFeatures;
use crate::record_stream::{RecordStream, SignalFeed, StreamOutput};
use crate::signal_topics::{SignalTopic, COMMANDED_JOINTS_TOPIC, LOAD_TOPIC, POWER_ON_TOPIC};
use metrocell_estimation::records::{RecordFrame, RecordSet, Rejected};

pub const MEASURED_POINTS_TOPIC: &str = "/measured_points";
pub use metrocell_msgs::topics::{
    FIDUCIALS as CAMERA_TOPIC, PROBE_HITS as PROBE_TOPIC, TRACKER_MEASUREMENTS as TRACKER_TOPIC,
};

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
    NoPoints {
        path: PathBuf,
        measured: String,
        tracker: String,
        held: String,
    },
    #[error("{}: no measured points: the records are read from {topic} (metrocell_msgs/MeasuredPoint: points in the machine frame, as the tracker node publishes them), which it does not hold; it holds: {held}. The tracker node makes them from a bag's /tracker/measurements (`metrocell-tracker --bag IN --output POINTS`, Cartesian and delta machines), `metrocell bag merge` joins them to the signals", path.display())]
    NoMeasuredPoints {
        path: PathBuf,
        topic: String,
        held: String,
    },
    #[error("term `{term}` needs the signal {signal}, which {} does not hold: {provide}", path.display())]
    MissingSignal {
        path: PathBuf,
        term: String,
        signal: String,
        provide: String,
    },
    #[error("{}: the records need the commanded joints of this {family} machine, and the bag has none: {provide}", path.display())]
    NoJoints {
        path: PathBuf,
        family: String,
        provide: String,
    },
    #[error("{}: {topic} {reason}, but the model's machine has joints {joints}: record the commanded joints under the machine's names (bag import: columns joint.<name>)", path.display())]
    JointNames {
        path: PathBuf,
        topic: String,
        reason: String,
        joints: String,
    },
    #[error("the measurements are in different frames ({frames}); a record set holds one frame: build one set per frame")]
    MixedFrames { frames: String },
}

/// The records of `bags` for `model` (module docs: sources, frames, checks).
pub fn records_from_bags<P: AsRef<Path>>(
    bags: &[P],
    model: &ForwardModel,
    options: &RecordingOptions,
) -> Result<RecordSet, RecordingError> {
    let mut set = RecordSet {
        check: Vec::new(),
        frame: RecordFrame::Machine,
        records: Vec::new(),
        rejected: Vec::new(),
        sources: Vec::new(),
    };
    let mut frames: BTreeMap<String, (RecordFrame, usize)> = BTreeMap::new();
    for bag in bags {
        let part = bag_records(bag.as_ref(), model, options)?;
        for (frame, records) in part.by_frame {
            frames.entry(frame_name(&frame)).or_insert((frame, 0)).1 += records.len();
            set.records.extend(records);
        }
        set.records.extend(part.instrument_records);
        set.check.extend(part.check);
        set.rejected.extend(part.rejected);
        for s in part.sources {
            if !set.sources.contains(&s) {
                set.sources.push(s);
            }
        }
    }
    if frames.len() > 1 {
        let frames = frames
            .iter()
            .map(|(name, (_, n))| format!("{n} in `{name}`"))
            .collect::<Vec<_>>()
            .join(", ");
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
pub fn signals_from_bag(
    path: &Path,
    machine: &MachineGeometry,
    options: &SignalsBuilderOptions,
) -> Result<(SignalsBuilder, Vec<Rejected>), RecordingError> {
    let mut bag = OpenedBag::open(path)?;
    bag.subscribe_signals();
    let mut builder = SignalsBuilder::for_machine(
        machine,
        SignalsBuilderOptions {
            joint_window: None,
            ..options.clone()
        },
    );
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
    RecordingError::Bag {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
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
        let topics: Vec<(String, String)> = source
            .topics()
            .iter()
            .map(|t| (t.name.clone(), t.type_name.clone()))
            .collect();
        let signal_topics = topics
            .iter()
            .filter_map(|(n, t)| SignalTopic::of(n, t).map(|w| (n.clone(), w)))
            .collect();
        Ok(Self {
            source,
            topics,
            signal_topics,
        })
    }
    fn subscribe_signals(&mut self) {
        for name in self.signal_topics.keys() {
            self.source.subscribe_any(name);
        }
    }
}

/// The frame a `header.frame_id` names (module docs); `<frame>@<setup>` is `<frame>` (see
/// [`frame_setup`]).
pub fn record_frame(frame_id: &str) -> RecordFrame {
    let frame_id = frame_id
        .split_once(metrocell_bagtools::import::SETUP_SEPARATOR)
        .map_or(frame_id, |(f, _)| f);
    match frame_id {
        "" | "machine" | "workpiece" => RecordFrame::Machine,
        other => RecordFrame::Instrument(other.to_string()),
    }
}

/// The placement of the instrument a `header.frame_id` names: `<setup>` of `<frame>@<setup>`
/// (bag import's `setup` column), None without one.
pub fn frame_setup(frame_id: &str) -> Option<std::sync::Arc<str>> {
    frame_id
        .split_once(metrocell_bagtools::import::SETUP_SEPARATOR)
        .map(|(_, s)| std::sync::Arc::from(s))
        .filter(|s: &std::sync::Arc<str>| !s.is_empty())
}

fn frame_name(f: &RecordFrame) -> String {
    match f {
        RecordFrame::Machine => "machine".into(),
        RecordFrame::Instrument(n) => n.clone(),
    }
}

/// The topics and `bag import` columns that provide a signal (for error messages).
pub fn providers(kind: &SignalKind) -> String {
    let axis = |a: &Axis| {
        format!("{COMMANDED_JOINTS_TOPIC} with joint `{a}`, or on cartesian and delta machines the measured points' nominals (bag import: column joint.{a} or nominal_{a})")
    };
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
        SignalKind::Time => "every record carries its time stamp".into(),
        SignalKind::Gravity => "record /imu/<sensor> (sensor_msgs/Imu) of an accelerometer on the robot's base, named with its link in the model's sensors.accelerometers (bag import: columns accel.<sensor>.x|y|z); without one the base is taken as level".into(),
        SignalKind::TrackerRange | SignalKind::ImagePoint | SignalKind::MachinePoint | SignalKind::WorkpiecePoint | SignalKind::TargetPoint | SignalKind::CameraPoint | SignalKind::ProbeDirection => "it is computed by the model".into(),
    }
}

fn bag_records(
    path: &Path,
    model: &ForwardModel,
    options: &RecordingOptions,
) -> Result<StreamOutput, RecordingError> {
    let mut bag = OpenedBag::open(path)?;
    let mut stream = RecordStream::new(path, &bag.topics, model, options)?;
    for topic in stream.topics() {
        bag.source.subscribe_any(&topic);
    }
    for m in bag.source.messages().map_err(|e| bag_error(path, e))? {
        stream.push(&m.map_err(|e| bag_error(path, e))?)?;
    }
    Ok(stream.finish())
}
