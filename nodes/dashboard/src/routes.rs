//! Which topics feed which part of the dashboard: resolved names and the type each must carry.

use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_msgs::RosMessage;
use metrocell_node::{MetrocellNode, NodeError};

/// What a topic carries for the dashboard. Topics with no role are still forwarded to Foxglove.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Role {
    Points,
    Model,
    Temperature(String),
    Tracker,
    Diagnostics,
    Clock,
    Other,
}

pub struct Routes {
    points: Vec<String>,
    models: Vec<String>,
    /// `/temperature/` (resolved, with the trailing slash).
    temperature_prefix: String,
    tracker: String,
}

impl Routes {
    pub fn from_node(node: &MetrocellNode) -> Result<Routes, Box<dyn std::error::Error>> {
        let resolve_all = |key: &str| -> Result<Vec<String>, Box<dyn std::error::Error>> {
            Ok(node
                .param::<Vec<String>>(key)?
                .iter()
                .map(|t| node.resolve_topic(t))
                .collect::<Result<Vec<_>, NodeError>>()?)
        };
        Ok(Routes {
            points: resolve_all("points_topics")?,
            models: resolve_all("model_topics")?,
            temperature_prefix: format!(
                "{}/",
                node.resolve_topic(&node.param::<String>("temperature_namespace")?)?
                    .trim_end_matches('/')
            ),
            tracker: node.resolve_topic(&node.param::<String>("tracker_topic")?)?,
        })
    }

    /// The role of a published topic; a known name with another type has no role.
    pub fn role(&self, topic: &str, ros_type: &str) -> Role {
        let is = |t: &str| ros_type == t;
        if is(MeasuredPoint::ROS_TYPE) && self.points.iter().any(|p| p == topic) {
            Role::Points
        } else if is(ErrorModel::ROS_TYPE) && self.models.iter().any(|p| p == topic) {
            Role::Model
        } else if is(Temperature::ROS_TYPE) && topic.starts_with(&self.temperature_prefix) {
            Role::Temperature(topic[self.temperature_prefix.len()..].to_string())
        } else if is(TrackerMeasurement::ROS_TYPE) && topic == self.tracker {
            Role::Tracker
        } else if is(DiagnosticArray::ROS_TYPE) && topic == "/diagnostics" {
            Role::Diagnostics
        } else if is(Clock::ROS_TYPE) && topic == "/clock" {
            Role::Clock
        } else {
            Role::Other
        }
    }
}
