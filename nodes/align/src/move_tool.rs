//! The action a robot driver implements for the align node: `metrocell_msgs/action/MoveTool`
//! (msgs/action/MoveTool.action is its definition). A goal is one pure move of the tool — a
//! translation, or a turn about a base-axes direction through a point given from the tool's
//! origin — and its result says whether the robot made it and has settled there. The align node
//! sends each move and then the move back (the patent's procedure measures displacements from
//! one start pose), so a driver needs no state beyond executing relative moves.
//!
//! Conventions, stated once: the robot's base axes; metres and radians (right-handed).

use metrocell_msgs::geometry_msgs::msg::Vector3;
use serde::{Deserialize, Serialize};

/// `kind` of a translation.
pub const TRANSLATE: u8 = 0;
/// `kind` of a rotation.
pub const ROTATE: u8 = 1;

/// The goal: field order as in the `.action` (it is the CDR order).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MoveToolGoal {
    pub kind: u8,
    pub translation: Vector3,
    pub axis: Vector3,
    pub angle: f64,
    pub through: Vector3,
}
impl ros2_client::Message for MoveToolGoal {}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MoveToolResult {
    pub success: bool,
    pub message: String,
}
impl ros2_client::Message for MoveToolResult {}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MoveToolFeedback {
    pub progress: f32,
}
impl ros2_client::Message for MoveToolFeedback {}

/// The action's name `action` resolved in `node`'s namespace, as ros2-client names it (the
/// namespace and the base name), and as text.
pub fn action_name(
    node: &metrocell_node::MetrocellNode,
    action: &str,
) -> Result<(ros2_client::Name, String), String> {
    let resolved = node.resolve_topic(action).map_err(|e| e.to_string())?;
    let (ns, base) = resolved.rsplit_once('/').unwrap_or(("", &resolved));
    let name = ros2_client::Name::new(if ns.is_empty() { "/" } else { ns }, base)
        .map_err(|e| format!("action name {resolved}: {e:?}"))?;
    Ok((name, resolved))
}

/// The action's type name.
pub fn action_type() -> ros2_client::ActionTypeName {
    ros2_client::ActionTypeName::new("metrocell_msgs", "MoveTool")
}

fn vector(v: &nalgebra::Vector3<f64>) -> Vector3 {
    Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

/// The vector of a message.
pub fn from_msg(v: &Vector3) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(v.x, v.y, v.z)
}

impl MoveToolGoal {
    pub fn translate(v: &nalgebra::Vector3<f64>) -> Self {
        Self {
            kind: TRANSLATE,
            translation: vector(v),
            axis: vector(&nalgebra::Vector3::zeros()),
            angle: 0.0,
            through: vector(&nalgebra::Vector3::zeros()),
        }
    }

    pub fn rotate(
        axis: &nalgebra::Vector3<f64>,
        angle: f64,
        through: &nalgebra::Vector3<f64>,
    ) -> Self {
        Self {
            kind: ROTATE,
            translation: vector(&nalgebra::Vector3::zeros()),
            axis: vector(axis),
            angle,
            through: vector(through),
        }
    }
}

/// Reliable services and feedback, the goal status latched: ROS 2's action defaults.
pub fn client_qos() -> ros2_client::action::ActionClientQosPolicies {
    let r = metrocell_node::qos::reliable();
    ros2_client::action::ActionClientQosPolicies {
        goal_service: r.clone(),
        result_service: r.clone(),
        cancel_service: r.clone(),
        feedback_subscription: r,
        status_subscription: metrocell_node::qos::latched(),
    }
}

/// The server's side of [`client_qos`].
pub fn server_qos() -> ros2_client::action::ActionServerQosPolicies {
    let r = metrocell_node::qos::reliable();
    ros2_client::action::ActionServerQosPolicies {
        goal_service: r.clone(),
        result_service: r.clone(),
        cancel_service: r.clone(),
        feedback_publisher: r,
        status_publisher: metrocell_node::qos::latched(),
    }
}
