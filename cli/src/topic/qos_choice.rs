//! The QoS a CLI endpoint asks for.

use metrocell_node::qos;
use ros2_client::QosProfile;

/// Which QoS preset a CLI reader or writer uses.
///
/// A best-effort, volatile reader matches every writer (reliable or not), so it is the default
/// for `echo`/`hz`; `latched` (reliable, transient local) also receives the last message a
/// latched publisher sent before the reader joined, but only matches latched writers.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum QosChoice {
    /// best effort, volatile, keep last 5
    SensorData,
    /// reliable, volatile, keep last 10 (the ROS 2 default)
    Reliable,
    /// reliable, transient local, keep last 1 (error models, calibration results)
    Latched,
}

impl QosChoice {
    pub fn profile(self) -> QosProfile {
        match self {
            QosChoice::SensorData => qos::sensor_data(),
            QosChoice::Reliable => qos::reliable(),
            QosChoice::Latched => qos::latched(),
        }
    }
}
