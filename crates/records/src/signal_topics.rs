//! The recorded topics that carry signals, and how each message feeds the signals builder
//! ([`metrocell_model::SignalsBuilder`]): the table records from bags ([`crate::recordings`])
//! read, through [`crate::record_stream`] — from a bag, and in the estimator and diagnose nodes.
//!
//! | topic | type | signal |
//! |---|---|---|
//! | `/machine/commanded_joint_states` | `sensor_msgs/JointState` | commanded joints (`position`), their velocities when `velocity` is filled (`metrocell sim`, `bag import`'s `velocity.<axis>`; NaN = not recorded) |
//! | `/machine/approach_directions` | `sensor_msgs/JointState` | recorded approach directions: `name` = axes (`x`, `y`, `z`), `position` = ±1 (`bag import`'s `approach.<axis>`) |
//! | `/temperature/<sensor>` | `sensor_msgs/Temperature` | temperature of `<sensor>`, °C (its samples also fill the timeline lagged terms read) |
//! | `/temperature/air`, `/weather/temperature` | `sensor_msgs/Temperature` | station air temperature, °C |
//! | `/air/pressure`, `/weather/pressure` | `sensor_msgs/FluidPressure` | station air pressure, Pa |
//! | `/air/humidity`, `/weather/humidity` | `sensor_msgs/RelativeHumidity` | station relative humidity (0..1 on the wire, %RH in `Signals`) |
//! | `/tracker/power_on` | `sensor_msgs/TimeReference` | when the instrument was powered on (`time_ref`) |
//! | `/machine/load` | `geometry_msgs/WrenchStamped` | load force, N, machine frame |
//! | `/machine/tool_offset` | `geometry_msgs/PointStamped` | the active tool's (target's) offset, m, machine frame: a reading's nominal is q plus it, and its difference from the model's `tool_offset` moves the target ([`metrocell_physics::Signals::tool_offset_shift`]) |
//!
//! A tracker reading (`metrocell_msgs/TrackerMeasurement`) also carries the station air it
//! used; see [`crate::recordings`]. Times: a message's `header.stamp`, or its log time when the
//! stamp is zero (a publisher that leaves it unset).

use metrocell_bagtools::SourcedMessage;
use metrocell_model::SignalsBuilder;
use metrocell_msgs::geometry_msgs::msg::{PointStamped, WrenchStamped};
use metrocell_msgs::sensor_msgs::msg::{
    FluidPressure, Imu, JointState, RelativeHumidity, Temperature, TimeReference,
};

/// Accelerometers are read from `/imu/<sensor>` (`sensor_msgs/Imu`, its linear acceleration).
pub const IMU_PREFIX: &str = "/imu/";
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::RosMessage;
use nalgebra::Vector3;

// the names a cell publishes (crates/msgs `topics`), plus the weather station's aliases below
pub use metrocell_msgs::topics::{
    APPROACH as APPROACH_TOPIC, COMMANDED_JOINTS as COMMANDED_JOINTS_TOPIC, LOAD as LOAD_TOPIC,
    POWER_ON as POWER_ON_TOPIC, TEMPERATURE_PREFIX, TOOL_OFFSET as TOOL_OFFSET_TOPIC,
};
/// The temperature sensor whose topic is also the station's air temperature.
pub const AIR_SENSOR: &str = "air";
pub const AIR_PRESSURE_TOPICS: [&str; 2] = ["/air/pressure", "/weather/pressure"];
pub const AIR_HUMIDITY_TOPICS: [&str; 2] = ["/air/humidity", "/weather/humidity"];
pub const WEATHER_TEMPERATURE_TOPIC: &str = "/weather/temperature";

/// What a recorded topic carries.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum SignalTopic {
    CommandedJoints,
    Approach,
    /// A temperature sensor (`/temperature/air` is also the air temperature).
    Temperature(String),
    AirTemperature,
    AirPressure,
    AirHumidity,
    PowerOn,
    Load,
    ToolOffset,
    /// An accelerometer (`/imu/<sensor>`, `sensor_msgs/Imu`: its linear acceleration).
    Accelerometer(String),
}

impl SignalTopic {
    /// The signal a topic carries, from its name and type; None for topics that carry none.
    pub fn of(topic: &str, ros_type: &str) -> Option<SignalTopic> {
        let is = |t: &str| ros_type == t;
        Some(match topic {
            COMMANDED_JOINTS_TOPIC if is(JointState::ROS_TYPE) => SignalTopic::CommandedJoints,
            APPROACH_TOPIC if is(JointState::ROS_TYPE) => SignalTopic::Approach,
            WEATHER_TEMPERATURE_TOPIC if is(Temperature::ROS_TYPE) => SignalTopic::AirTemperature,
            t if AIR_PRESSURE_TOPICS.contains(&t) && is(FluidPressure::ROS_TYPE) => {
                SignalTopic::AirPressure
            }
            t if AIR_HUMIDITY_TOPICS.contains(&t) && is(RelativeHumidity::ROS_TYPE) => {
                SignalTopic::AirHumidity
            }
            POWER_ON_TOPIC if is(TimeReference::ROS_TYPE) => SignalTopic::PowerOn,
            LOAD_TOPIC if is(WrenchStamped::ROS_TYPE) => SignalTopic::Load,
            TOOL_OFFSET_TOPIC if is(PointStamped::ROS_TYPE) => SignalTopic::ToolOffset,
            t if t.starts_with(IMU_PREFIX) && is(Imu::ROS_TYPE) => {
                let sensor = t
                    .strip_prefix(IMU_PREFIX)
                    .filter(|s| !s.is_empty() && !s.contains('/'))?;
                SignalTopic::Accelerometer(sensor.to_string())
            }
            t => {
                let sensor = t
                    .strip_prefix(TEMPERATURE_PREFIX)
                    .filter(|s| !s.is_empty() && !s.contains('/'))?;
                if !is(Temperature::ROS_TYPE) {
                    return None;
                }
                SignalTopic::Temperature(sensor.to_string())
            }
        })
    }
}

/// A message's time: its header stamp, or its log time when the stamp is zero.
pub fn message_time(stamp: &Time, log_time_ns: u64) -> i64 {
    match stamp.nanos() {
        0 => log_time_ns as i64,
        ns => ns,
    }
}

/// Push one recorded message of a signal topic into the builder. Errors (a message that does
/// not decode, a sample the builder refuses) are returned with the reason; the caller counts
/// and reports them per topic.
pub fn feed(
    builder: &mut SignalsBuilder,
    which: &SignalTopic,
    m: &SourcedMessage,
) -> Result<(), String> {
    let decode_error = |e: metrocell_bagtools::ToolError| e.to_string();
    match which {
        SignalTopic::CommandedJoints => {
            let js: JointState = m.decode().map_err(decode_error)?;
            builder.push_joints(
                message_time(&js.header.stamp, m.log_time_ns),
                &js.name,
                &js.position,
                &js.velocity,
            )
        }
        SignalTopic::Approach => {
            let js: JointState = m.decode().map_err(decode_error)?;
            let t = message_time(&js.header.stamp, m.log_time_ns);
            for (name, v) in js.name.iter().zip(&js.position) {
                let axis = ["x", "y", "z"]
                    .iter()
                    .position(|a| a == name)
                    .ok_or_else(|| format!("approach of `{name}`: only axes x, y, z have one"))?;
                builder.push_approach(t, axis, *v)?;
            }
            Ok(())
        }
        SignalTopic::Temperature(sensor) => {
            let msg: Temperature = m.decode().map_err(decode_error)?;
            let t = message_time(&msg.header.stamp, m.log_time_ns);
            builder.push_temperature(t, sensor, msg.temperature)?;
            if sensor == AIR_SENSOR {
                builder.push_air_temperature(t, msg.temperature)?;
            }
            Ok(())
        }
        SignalTopic::AirTemperature => {
            let msg: Temperature = m.decode().map_err(decode_error)?;
            builder.push_air_temperature(
                message_time(&msg.header.stamp, m.log_time_ns),
                msg.temperature,
            )
        }
        SignalTopic::AirPressure => {
            let msg: FluidPressure = m.decode().map_err(decode_error)?;
            builder.push_air_pressure(
                message_time(&msg.header.stamp, m.log_time_ns),
                msg.fluid_pressure,
            )
        }
        SignalTopic::AirHumidity => {
            let msg: RelativeHumidity = m.decode().map_err(decode_error)?;
            builder.push_air_humidity(
                message_time(&msg.header.stamp, m.log_time_ns),
                100.0 * msg.relative_humidity,
            )
        }
        SignalTopic::PowerOn => {
            let msg: TimeReference = m.decode().map_err(decode_error)?;
            builder.push_power_on(
                message_time(&msg.header.stamp, m.log_time_ns),
                msg.time_ref.nanos(),
            );
            Ok(())
        }
        SignalTopic::Load => {
            let msg: WrenchStamped = m.decode().map_err(decode_error)?;
            let f = &msg.wrench.force;
            builder.push_load(
                message_time(&msg.header.stamp, m.log_time_ns),
                Vector3::new(f.x, f.y, f.z),
            )
        }
        SignalTopic::ToolOffset => {
            let msg: PointStamped = m.decode().map_err(decode_error)?;
            let p = &msg.point;
            builder.push_tool_offset(
                message_time(&msg.header.stamp, m.log_time_ns),
                Vector3::new(p.x, p.y, p.z),
            )
        }
        SignalTopic::Accelerometer(sensor) => {
            let msg: Imu = m.decode().map_err(decode_error)?;
            let a = &msg.linear_acceleration;
            builder.push_acceleration(
                message_time(&msg.header.stamp, m.log_time_ns),
                sensor,
                Vector3::new(a.x, a.y, a.z),
            )
        }
    }
}
