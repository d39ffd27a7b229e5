//! Node runtime for metrocell: what every node and the `metrocell` CLI stand on.
//!
//! * [`ros_args`]: the ROS 2 command line (`--ros-args -r/-p/--params-file/--log-level ... --`).
//! * [`params`]: typed parameter declarations, ROS 2 params files, rcl precedence.
//! * [`environment`] and [`participant`]: `ROS_DOMAIN_ID`, `ROS_AUTOMATIC_DISCOVERY_RANGE`,
//!   `ROS_LOCALHOST_ONLY` → the RustDDS participant.
//! * [`names`]: topic name expansion and remapping, ROS ↔ DDS names.
//! * [`qos`]: rclcpp's named QoS profiles.
//! * [`MetrocellNode`]: typed and raw endpoints, topic discovery, rosout [`Logger`],
//!   [`Diagnostics`] heartbeat, simulated time, [`ShutdownToken`].
//! * [`ReplayArgs`]: `--bag IN [--output OUT]`, the offline-replay switch of every node.
//! * [`testing`]: the guard DDS tests call first.
//!
//! ```no_run
//! use metrocell_node::{qos, MetrocellNode, ParamDecl};
//! use metrocell_msgs::std_msgs::msg::Header;
//! let (mut node, _args) = MetrocellNode::from_env_args("talker", vec![
//!     ParamDecl::new("rate_hz", 10.0, "publish rate").with_range(0.1, 1000.0),
//! ])?;
//! let publisher = node.publisher::<Header>("chatter", qos::reliable())?;
//! let period = std::time::Duration::from_secs_f64(1.0 / node.param::<f64>("rate_hz")?);
//! while !node.shutdown_token().wait_timeout(period) {
//!     let _ = publisher.publish(Header::default());
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod background;
pub mod blocking;
mod builder;
pub mod dds_log;
pub mod diagnostics;
pub mod environment;
pub mod error;
pub mod help;
pub mod logging;
pub mod names;
mod node;
pub mod node_directory;
pub mod offline;
pub mod params;
pub mod participant;
pub mod qos;
pub mod raw;
pub mod replay_args;
pub mod ros_args;
pub mod shutdown;
pub mod testing;
pub mod topics;

pub use background::SimTime;
pub use builder::NodeBuilder;
pub use diagnostics::{DiagnosticLevel, Diagnostics};
pub use environment::{DdsEnvironment, DiscoveryRange, EnvError};
pub use error::NodeError;
pub use logging::Logger;
pub use node::MetrocellNode;
pub use node_directory::NodeDirectory;
pub use offline::{Interrupted, OfflineNode};
pub use params::{
    ParamDecl, ParamError, ParamKind, ParamSource, ParamType, ParamValue, ParamWatch, Parameters,
};
pub use raw::{RawMessage, RawPublisher, RawSubscription};
pub use replay_args::ReplayArgs;
pub use ros_args::{parse_command_line, CommandLine, LogLevel, RosArgs, RosArgsError};
pub use shutdown::ShutdownToken;
pub use topics::TopicInfo;

/// Re-exports so nodes need not depend on ros2-client directly.
pub use blocking::block_on_within;
pub use ros2_client::{MessageInfo, Publisher, QosProfile, ROSTime, Subscription};
