//! Which topics of a recording give a [`RecordStream`](crate::RecordStream) its records and
//! signals, checked before any message is read: the points (measured points or raw tracker
//! measurements), probe hits, camera points, reference nests, check points, the commanded
//! joints (or the nominals that give them) and every signal a declared term reads. Each missing
//! piece is an error naming what to record; what was found is listed for the user
//! ([`RecordingSources::lines`]).

use std::collections::BTreeMap;
use std::path::Path;

use metrocell_bagtools::import::{CHECK_POINTS_TOPIC, REFERENCE_POINTS_TOPIC};
use metrocell_model::{ForwardModel, MachineKinematics};
use metrocell_msgs::msg::{FiducialDetectionArray, MeasuredPoint, ProbeHit, TrackerMeasurement};
use metrocell_msgs::RosMessage;
use metrocell_physics::SignalKind;

use crate::record_stream::{declared_signals, family, JointSource};
use crate::recordings::{providers, PointSource, RecordingError, RecordingOptions};
use crate::signal_topics::{
    SignalTopic, AIR_SENSOR, COMMANDED_JOINTS_TOPIC, LOAD_TOPIC, POWER_ON_TOPIC,
};

/// The topics a recording's records come from.
pub(crate) struct RecordingSources {
    /// Points are raw tracker measurements (else measured points).
    pub points_tracker: bool,
    /// The topic points are read from (recorded or not: messages name it).
    pub points_name: String,
    /// The same, when the recording has it.
    pub points_topic: Option<String>,
    pub probe_topic: Option<String>,
    pub camera_topic: Option<String>,
    pub reference_topic: Option<String>,
    pub check_topic: Option<String>,
    pub joints: JointSource,
    /// Every recorded topic that carries a signal, and which.
    pub signal_topics: BTreeMap<String, SignalTopic>,
    /// (what, where from) for the user.
    pub lines: Vec<(String, String)>,
}

/// The recording's topic list, with the type each is recorded as.
struct Held<'t> {
    source: &'t Path,
    topics: &'t [(String, String)],
}

impl Held<'_> {
    fn type_of(&self, name: &str) -> Option<&str> {
        self.topics
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, t)| t.as_str())
    }

    /// Whether `name` is recorded; an error when it is, as another type than `ty`.
    fn typed(&self, name: &str, ty: &str) -> Result<bool, RecordingError> {
        match self.type_of(name) {
            Some(t) if t != ty => Err(RecordingError::Bag {
                path: self.source.to_path_buf(),
                reason: format!("topic {name} is recorded as {t}, but records are read from {ty}"),
            }),
            Some(_) => Ok(true),
            None => Ok(false),
        }
    }

    /// "name (type), …" for error messages.
    fn listed(&self) -> String {
        let held = self
            .topics
            .iter()
            .map(|(n, t)| format!("{n} ({t})"))
            .collect::<Vec<_>>()
            .join(", ");
        if held.is_empty() {
            "no topics".into()
        } else {
            held
        }
    }
}

impl RecordingSources {
    /// Check `topics` of the recording at `source` against what `model` and `options` need.
    pub fn check(
        source: &Path,
        topics: &[(String, String)],
        model: &ForwardModel,
        options: &RecordingOptions,
    ) -> Result<RecordingSources, RecordingError> {
        let held = Held { source, topics };
        let mut s = measurement_topics(&held, options)?;
        let carried = |which: &SignalTopic| s.signal_topics.values().any(|w| w == which);
        s.joints = joint_source(&s, model, &carried, source)?;
        let points = s.points_name.clone();
        let joints_line = match s.joints {
            JointSource::Commanded => COMMANDED_JOINTS_TOPIC.into(),
            JointSource::Nominal => format!("nominal of {points}, minus the tool offset"),
            JointSource::CommandedOrNominal => format!(
                "{COMMANDED_JOINTS_TOPIC} where it gives positions, else the nominal of {points} \
                 minus the tool offset (with the joint states' velocities)"
            ),
        };
        s.lines.push(("commanded joints".into(), joints_line));
        for line in declared_signal_sources(&s, model, &carried, source)? {
            if !s.lines.contains(&line) {
                s.lines.push(line);
            }
        }
        let air = air_line(&s, &points);
        s.lines.extend(air);
        Ok(s)
    }
}

/// The topics that give records (points, probe hits, camera points, nests, check points);
/// an error when none does.
fn measurement_topics(
    held: &Held,
    options: &RecordingOptions,
) -> Result<RecordingSources, RecordingError> {
    let points_tracker = match options.points {
        PointSource::MeasuredPoints => false,
        PointSource::TrackerMeasurements => true,
        PointSource::Auto => {
            held.type_of(&options.measured_points_topic) != Some(MeasuredPoint::ROS_TYPE)
        }
    };
    let (points_topic, points_type) = if points_tracker {
        (&options.tracker_topic, TrackerMeasurement::ROS_TYPE)
    } else {
        (&options.measured_points_topic, MeasuredPoint::ROS_TYPE)
    };
    let found = held.typed(points_topic, points_type)?;
    let probes = options.probe_hits && held.typed(&options.probe_topic, ProbeHit::ROS_TYPE)?;
    let references = held.typed(REFERENCE_POINTS_TOPIC, MeasuredPoint::ROS_TYPE)?;
    // check points are points of the program: read where the points are measured points
    let checks = !points_tracker && held.typed(CHECK_POINTS_TOPIC, MeasuredPoint::ROS_TYPE)?;
    let cameras = options.camera_points
        && held.typed(&options.camera_topic, FiducialDetectionArray::ROS_TYPE)?;
    if !(found || probes || cameras) {
        let path = held.source.to_path_buf();
        return Err(if options.points == PointSource::MeasuredPoints {
            RecordingError::NoMeasuredPoints {
                path,
                topic: options.measured_points_topic.clone(),
                held: held.listed(),
            }
        } else {
            RecordingError::NoPoints {
                path,
                measured: options.measured_points_topic.clone(),
                tracker: options.tracker_topic.clone(),
                held: held.listed(),
            }
        });
    }
    let mut lines = Vec::new();
    let mut line = |on: bool, what: &str, from: String| {
        if on {
            lines.push((what.to_string(), from));
        }
    };
    line(found, "points", format!("{points_topic} ({points_type})"));
    line(
        probes,
        "probe hits",
        format!("{} ({})", options.probe_topic, ProbeHit::ROS_TYPE),
    );
    line(
        checks,
        "check points",
        format!(
            "{CHECK_POINTS_TOPIC} ({}), kept out of fits",
            MeasuredPoint::ROS_TYPE
        ),
    );
    line(
        references,
        "reference nests",
        format!("{REFERENCE_POINTS_TOPIC} ({})", MeasuredPoint::ROS_TYPE),
    );
    line(
        cameras,
        "camera points",
        format!(
            "{} ({})",
            options.camera_topic,
            FiducialDetectionArray::ROS_TYPE
        ),
    );
    let signal_topics = held
        .topics
        .iter()
        .filter_map(|(n, t)| SignalTopic::of(n, t).map(|w| (n.clone(), w)))
        .collect();
    Ok(RecordingSources {
        points_tracker,
        points_name: points_topic.clone(),
        points_topic: found.then(|| points_topic.clone()),
        probe_topic: probes.then(|| options.probe_topic.clone()),
        camera_topic: cameras.then(|| options.camera_topic.clone()),
        reference_topic: references.then(|| REFERENCE_POINTS_TOPIC.to_string()),
        check_topic: checks.then(|| CHECK_POINTS_TOPIC.to_string()),
        joints: JointSource::Commanded,
        signal_topics,
        lines,
    })
}

/// Where the commanded joints come from: the recorded joint states, the points' nominals
/// (cartesian and delta machines), or both; an error saying what to record otherwise.
fn joint_source(
    s: &RecordingSources,
    model: &ForwardModel,
    carried: &dyn Fn(&SignalTopic) -> bool,
    source: &Path,
) -> Result<JointSource, RecordingError> {
    let nominals_give_axes = s.points_topic.is_some()
        && !s.points_tracker
        && matches!(
            model.machine.kinematics,
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_)
        );
    let commanded = carried(&SignalTopic::CommandedJoints);
    Ok(match (commanded, nominals_give_axes) {
        // an export may give velocities without positions: the nominals then give the axes
        (true, true) => JointSource::CommandedOrNominal,
        (true, false) => JointSource::Commanded,
        (false, true) => JointSource::Nominal,
        (false, false) => {
            let names = model.machine.joint_names();
            let points = &s.points_name;
            let provide =
                if s.points_tracker {
                    format!(
                        "record {COMMANDED_JOINTS_TOPIC} (joints {}) next to {points}",
                        names.join(", ")
                    )
                } else {
                    format!(
                    "record {COMMANDED_JOINTS_TOPIC} (joints {}), or import the CSV with columns \
                     {} (the nominal point alone gives the joints only on cartesian and delta \
                     machines)",
                    names.join(", "),
                    names.iter().map(|n| format!("joint.{n}")).collect::<Vec<_>>().join(", ")
                )
                };
            return Err(RecordingError::NoJoints {
                path: source.to_path_buf(),
                family: family(model).into(),
                provide,
            });
        }
    })
}

/// Every declared signal must have a source in this recording: the (signal, topic) lines of the
/// ones that come from a topic, or an error naming the first that has none.
fn declared_signal_sources(
    s: &RecordingSources,
    model: &ForwardModel,
    carried: &dyn Fn(&SignalTopic) -> bool,
    source: &Path,
) -> Result<Vec<(String, String)>, RecordingError> {
    let mut lines = Vec::new();
    for (term, kind) in &declared_signals(model) {
        let (available, from) = match kind {
            SignalKind::AxisPosition(_) | SignalKind::AxisVelocity(_) => (true, None),
            SignalKind::ApproachDirection(_) => (
                true,
                carried(&SignalTopic::Approach).then(|| "/machine/approach_directions".to_string()),
            ),
            SignalKind::Temperature(t) | SignalKind::TemperatureHistory(t) => (
                carried(&SignalTopic::Temperature(t.clone())),
                Some(format!("/temperature/{t}")),
            ),
            SignalKind::AirTemperature => (
                s.points_tracker
                    || carried(&SignalTopic::AirTemperature)
                    || carried(&SignalTopic::Temperature(AIR_SENSOR.into())),
                None,
            ),
            SignalKind::AirPressure => {
                (s.points_tracker || carried(&SignalTopic::AirPressure), None)
            }
            SignalKind::AirHumidity => {
                (s.points_tracker || carried(&SignalTopic::AirHumidity), None)
            }
            SignalKind::TimeSincePowerOn => (
                carried(&SignalTopic::PowerOn),
                Some(POWER_ON_TOPIC.to_string()),
            ),
            SignalKind::LoadForce => (carried(&SignalTopic::Load), Some(LOAD_TOPIC.to_string())),
            _ => (true, None),
        };
        if !available {
            return Err(RecordingError::MissingSignal {
                path: source.to_path_buf(),
                term: term.clone(),
                signal: kind.to_string(),
                provide: providers(kind),
            });
        }
        if let Some(topic) = from {
            lines.push((kind.to_string(), topic));
        }
    }
    Ok(lines)
}

/// Where the air (refraction) comes from, if anywhere.
fn air_line(s: &RecordingSources, points: &str) -> Option<(String, String)> {
    if s.points_tracker {
        return Some((
            "air".into(),
            format!("each reading's own station air ({points})"),
        ));
    }
    let air: Vec<&str> = s
        .signal_topics
        .iter()
        .filter(|(_, w)| {
            matches!(
                w,
                SignalTopic::AirTemperature | SignalTopic::AirPressure | SignalTopic::AirHumidity
            ) || **w == SignalTopic::Temperature(AIR_SENSOR.into())
        })
        .map(|(n, _)| n.as_str())
        .collect();
    (!air.is_empty()).then(|| ("air".into(), air.join(", ")))
}
