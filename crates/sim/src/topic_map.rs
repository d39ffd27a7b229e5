//! The topic map: every stream the simulator publishes, in one place.
//!
//! | topic | type | QoS | content |
//! |---|---|---|---|
//! | `/clock` | `rosgraph_msgs/msg/Clock` | [`QosKind::Clock`] | simulated time, so nodes can run with `use_sim_time` |
//! | `/machine/joint_states` | `sensor_msgs/msg/JointState` | [`QosKind::SensorData`] | **actual** joint values (commanded + the true error terms), names `x y z` (cartesian, delta; m), `x y z b c` (five_axis; m, rad), the arm's joints (serial_arm; rad or m) |
//! | `/machine/commanded_joint_states` | `sensor_msgs/msg/JointState` | [`QosKind::SensorData`] | **commanded** joint values (what the controller was told) and their commanded velocities (`velocity`, m/s or rad/s), same names |
//! | `/machine/load` | `geometry_msgs/msg/WrenchStamped` | [`QosKind::Latched`] | the load acting on the structure (`environment.load_force`), force in N, machine frame (`frame_id = machine`), torque 0; once at t = 0 |
//! | `/temperature/<sensor>` | `sensor_msgs/msg/Temperature` | [`QosKind::Reliable`] | one topic per thermocouple, °C, `variance` = noise² + calibration² (K²) |
//! | `/tracker/measurements` | `metrocell_msgs/msg/TrackerMeasurement` | [`QosKind::Reliable`] | laser-tracker points in the tracker frame, covariance row-major, station air data, applied index; beam breaks as `STATUS_BEAM_BREAK` with NaN point |
//! | `/tracker/power_on` | `sensor_msgs/msg/TimeReference` | [`QosKind::Latched`] | when the tracker was powered on: `time_ref` = start − `powered_on_before_start`, `source = tracker`, stamped at t = 0 (published once) |
//! | `/measured_points` | `metrocell_msgs/msg/MeasuredPoint` | [`QosKind::Reliable`] | a stationing program's fit points: the levelled instrument's reading of the tool point, in its frame at the waypoint's setup (`frame_id` `total_station@<setup>`), covariance diagonal σ², `nominal` the commanded tool point (the arm's base frame), `source = total_station` |
//! | `/check_points` | `metrocell_msgs/msg/MeasuredPoint` | [`QosKind::Reliable`] | its check points, the same way (kept out of every fit by `calibrate` and `diagnose`) |
//! | `/imu/<sensor>` | `sensor_msgs/msg/Imu` | [`QosKind::Reliable`] | one topic per accelerometer of a stationing program: `linear_acceleration` the specific force in the sensor's frame (m/s², +9.81 up at rest), `frame_id` its URDF link, orientation and angular velocity not given (covariance[0] = −1) |
//! | `/probe/hits` | `metrocell_msgs/msg/ProbeHit` | [`QosKind::Reliable`] | touch-probe triggers (workpiece frame) |
//! | `/camera/camera_info` | `sensor_msgs/msg/CameraInfo` | [`QosKind::SensorData`] | one per camera frame request |
//! | `/camera/image_raw` | `sensor_msgs/msg/Image` (mono8) | [`QosKind::SensorData`] | the rendered frame of each request, same stamp as its CameraInfo (see `camera_frame`) |
//!
//! Only the topics whose sensor exists in the cell are in a cell's map, in the order above
//! (thermocouples in file order). A stationing program writes `bag import`'s layout (one row of
//! messages per waypoint, one stamp: commanded and actual joints, the point, the accelerometers,
//! the thermocouples), so `calibrate` and `diagnose` read the twin's recordings and imported
//! ones alike. Joint states exist when the cell has `machine_state` or a stationing program, the
//! load when it has `environment.load_force`, the power-on time with a tracker. The latched
//! topics carry a state rather than a stream: a reader keeps the latest message at or before
//! its time.
//! Why actual positions on `joint_states`: that topic is what the machine's encoders would
//! report and what robot_state_publisher consumes; the command is kept apart so the pair shows
//! the machine's error directly.

use metrocell_msgs::geometry_msgs::msg::WrenchStamped;
use metrocell_msgs::msg::{MeasuredPoint, ProbeHit, TrackerMeasurement};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::sensor_msgs::msg::{
    CameraInfo, Image, Imu, JointState, Temperature, TimeReference,
};
use metrocell_twin::Cell;
use rosmsg::RosMessage;

use crate::error::SimError;

// The names themselves are crates/msgs `topics`, shared with `bag import` and the records builder.
pub use metrocell_msgs::topics::{
    CAMERA_IMAGE as CAMERA_IMAGE_TOPIC, CAMERA_INFO as CAMERA_INFO_TOPIC,
    CHECK_POINTS as CHECK_POINTS_TOPIC, CLOCK as CLOCK_TOPIC,
    COMMANDED_JOINTS as COMMANDED_JOINT_STATES_TOPIC, IMU_PREFIX as IMU_TOPIC_PREFIX,
    JOINT_STATES as JOINT_STATES_TOPIC, LOAD as LOAD_TOPIC,
    MEASURED_POINTS as MEASURED_POINTS_TOPIC, POWER_ON as POWER_ON_TOPIC,
    PROBE_HITS as PROBE_TOPIC, TEMPERATURE_PREFIX as TEMPERATURE_TOPIC_PREFIX,
    TRACKER_MEASUREMENTS as TRACKER_TOPIC,
};

/// QoS of a simulated stream, matching rclcpp's named profiles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QosKind {
    /// rclcpp `ClockQoS`: best effort, keep last 1, volatile.
    Clock,
    /// rclcpp `SensorDataQoS`: best effort, keep last 5, volatile (high-rate streams).
    SensorData,
    /// rclcpp default: reliable, keep last 10, volatile (measurements a recorder must not miss).
    Reliable,
    /// Latched (like `/tf_static`): reliable, keep last 1, transient local — a state a late
    /// subscriber still receives.
    Latched,
}

impl QosKind {
    /// The same profile as rosbag2 stores it.
    pub fn bag_profile(self) -> metrocell_bag::QosProfile {
        match self {
            QosKind::Clock => metrocell_bag::QosProfile {
                keep_last: true,
                depth: 1,
                reliable: false,
                transient_local: false,
            },
            QosKind::SensorData => metrocell_bag::QosProfile::sensor_data(),
            QosKind::Reliable => metrocell_bag::QosProfile::default_publisher(),
            QosKind::Latched => metrocell_bag::QosProfile {
                keep_last: true,
                depth: 1,
                reliable: true,
                transient_local: true,
            },
        }
    }
}

/// What a topic carries.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TopicRole {
    Clock,
    JointStates,
    CommandedJointStates,
    /// The load on the structure.
    Load,
    /// Thermocouple by name.
    Temperature(String),
    Tracker,
    /// A stationing program's fit points and its check points.
    MeasuredPoints,
    CheckPoints,
    /// An accelerometer by name.
    Imu(String),
    /// When the tracker was powered on.
    TrackerPowerOn,
    Probe,
    CameraInfo,
    CameraImage,
}

/// One topic of the map.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicSpec {
    pub name: String,
    pub role: TopicRole,
    /// `pkg/msg/Type`.
    pub ros_type: &'static str,
    /// Full ros2msg definition (the type's .msg text and its dependencies).
    pub definition: &'static str,
    pub qos: QosKind,
}

impl TopicSpec {
    fn of<T: RosMessage>(name: impl Into<String>, role: TopicRole, qos: QosKind) -> TopicSpec {
        TopicSpec {
            name: name.into(),
            role,
            ros_type: T::ROS_TYPE,
            definition: T::DEFINITION,
            qos,
        }
    }
}

/// Index of a topic in a [`TopicMap`].
pub type TopicId = usize;

/// The topics of one cell, with fixed ids for the hot path.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicMap {
    pub topics: Vec<TopicSpec>,
    pub clock: TopicId,
    pub joint_states: Option<(TopicId, TopicId)>,
    pub load: Option<TopicId>,
    /// Per thermocouple, in the cell's order.
    pub temperatures: Vec<TopicId>,
    pub tracker: Option<TopicId>,
    /// A stationing program's fit points, check points and accelerometers (in the cell's order).
    pub measured_points: Option<TopicId>,
    pub check_points: Option<TopicId>,
    pub imu: Vec<TopicId>,
    pub power_on: Option<TopicId>,
    pub probe: Option<TopicId>,
    pub camera_info: Option<TopicId>,
    pub camera_image: Option<TopicId>,
}

impl TopicMap {
    /// The map of a cell (see the module table). Fails when a thermocouple name is not a
    /// valid ROS name token (`[A-Za-z_][A-Za-z0-9_]*`), as it becomes part of a topic name.
    pub fn for_cell(cell: &Cell) -> Result<TopicMap, SimError> {
        for (i, tc) in cell.thermocouples.iter().enumerate() {
            if !is_name_token(&tc.name) {
                return Err(SimError::invalid(
                    format!("sensors.thermocouples[{i}].name {:?}", tc.name),
                    "must be a ROS name token ([A-Za-z_][A-Za-z0-9_]*) because it names the topic /temperature/<name>",
                ));
            }
        }
        let stationing = cell.stationing.as_ref();
        let accelerometers: Vec<&str> = stationing
            .map(|s| s.accelerometers.iter().map(|a| a.name.as_str()).collect())
            .unwrap_or_default();
        for (i, name) in accelerometers.iter().enumerate() {
            if !is_name_token(name) {
                return Err(SimError::invalid(format!("sensors.accelerometers[{i}].name {name:?}"), "must be a ROS name token ([A-Za-z_][A-Za-z0-9_]*) because it names the topic /imu/<name>"));
            }
        }
        let mut topics = vec![TopicSpec::of::<Clock>(
            CLOCK_TOPIC,
            TopicRole::Clock,
            QosKind::Clock,
        )];
        let mut push = |t: TopicSpec| {
            topics.push(t);
            topics.len() - 1
        };
        let joint_states = (cell.machine_state_rate.is_some() || stationing.is_some()).then(|| {
            (
                push(TopicSpec::of::<JointState>(
                    JOINT_STATES_TOPIC,
                    TopicRole::JointStates,
                    QosKind::SensorData,
                )),
                push(TopicSpec::of::<JointState>(
                    COMMANDED_JOINT_STATES_TOPIC,
                    TopicRole::CommandedJointStates,
                    QosKind::SensorData,
                )),
            )
        });
        let load = cell.load_force.map(|_| {
            push(TopicSpec::of::<WrenchStamped>(
                LOAD_TOPIC,
                TopicRole::Load,
                QosKind::Latched,
            ))
        });
        let temperatures = cell
            .thermocouples
            .iter()
            .map(|tc| {
                push(TopicSpec::of::<Temperature>(
                    temperature_topic(&tc.name),
                    TopicRole::Temperature(tc.name.clone()),
                    QosKind::Reliable,
                ))
            })
            .collect();
        let tracker = cell.tracker.as_ref().map(|_| {
            push(TopicSpec::of::<TrackerMeasurement>(
                TRACKER_TOPIC,
                TopicRole::Tracker,
                QosKind::Reliable,
            ))
        });
        let power_on = cell.tracker.as_ref().map(|_| {
            push(TopicSpec::of::<TimeReference>(
                POWER_ON_TOPIC,
                TopicRole::TrackerPowerOn,
                QosKind::Latched,
            ))
        });
        let measured_points = stationing.map(|_| {
            push(TopicSpec::of::<MeasuredPoint>(
                MEASURED_POINTS_TOPIC,
                TopicRole::MeasuredPoints,
                QosKind::Reliable,
            ))
        });
        let check_points = stationing.map(|_| {
            push(TopicSpec::of::<MeasuredPoint>(
                CHECK_POINTS_TOPIC,
                TopicRole::CheckPoints,
                QosKind::Reliable,
            ))
        });
        let imu = accelerometers
            .iter()
            .map(|a| {
                push(TopicSpec::of::<Imu>(
                    format!("{IMU_TOPIC_PREFIX}{a}"),
                    TopicRole::Imu(a.to_string()),
                    QosKind::Reliable,
                ))
            })
            .collect();
        let probe = cell.probe.as_ref().map(|_| {
            push(TopicSpec::of::<ProbeHit>(
                PROBE_TOPIC,
                TopicRole::Probe,
                QosKind::Reliable,
            ))
        });
        let camera_info = cell.camera.as_ref().map(|_| {
            push(TopicSpec::of::<CameraInfo>(
                CAMERA_INFO_TOPIC,
                TopicRole::CameraInfo,
                QosKind::SensorData,
            ))
        });
        let camera_image = cell.camera.as_ref().map(|_| {
            push(TopicSpec::of::<Image>(
                CAMERA_IMAGE_TOPIC,
                TopicRole::CameraImage,
                QosKind::SensorData,
            ))
        });
        Ok(TopicMap {
            topics,
            clock: 0,
            joint_states,
            load,
            temperatures,
            tracker,
            measured_points,
            check_points,
            imu,
            power_on,
            probe,
            camera_info,
            camera_image,
        })
    }

    pub fn get(&self, id: TopicId) -> &TopicSpec {
        &self.topics[id]
    }

    /// Topic id of an accelerometer by name.
    pub fn imu(&self, sensor: &str) -> Option<TopicId> {
        self.imu
            .iter()
            .copied()
            .find(|&i| self.topics[i].role == TopicRole::Imu(sensor.to_string()))
    }

    /// Topic id of a thermocouple by name.
    pub fn temperature(&self, sensor: &str) -> Option<TopicId> {
        self.temperatures
            .iter()
            .copied()
            .find(|&i| self.topics[i].role == TopicRole::Temperature(sensor.to_string()))
    }
}

/// `/temperature/<sensor>`.
pub fn temperature_topic(sensor: &str) -> String {
    format!("{TEMPERATURE_TOPIC_PREFIX}{sensor}")
}

fn is_name_token(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn name_tokens() {
        assert!(is_name_token("x_left"));
        assert!(is_name_token("_t1"));
        assert!(!is_name_token("1t"));
        assert!(!is_name_token("x-left"));
        assert!(!is_name_token(""));
    }
}
