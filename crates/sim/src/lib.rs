//! # metrocell-simulation (`crates/sim`) — the digital twin as ROS 2 messages
//!
//! The twin ([`metrocell_twin`]) streams typed samples; this crate turns them into the ROS 2
//! messages a real cell would publish, on the topics of one documented [`topic_map`], stamped
//! in deterministic simulated time ([`sim_time`]), and records them as a rosbag2 MCAP bag
//! ([`write_bag`]) or hands them to the live node (`nodes/sim`, binary `metrocell-sim`).
//!
//! | module | what it holds |
//! |---|---|
//! | [`topic_map`] | the topic table: names, types, QoS |
//! | [`sim_time`] | start epoch, stamps, RFC 3339 parsing |
//! | [`convert`] | pure sample → message conversions (field conventions stated there) |
//! | [`message_stream`] | the merged, time-ordered message stream with `/clock` ticks |
//! | [`pacing`] | simulated time vs wall clock for the live node |
//! | [`camera_frame`] | rendering a camera frame request as an image (plate, pose, seed) |
//! | [`cdr`] | CDR bytes with the encapsulation header |
//! | [`cell_options`] | a run's ground tilt (`--ground-tilt`) and default duration |
//! | [`bag`] | [`write_bag`]: a deterministic bag of a simulation |
//! | [`cli`] | [`SimArgs`] and [`run_sim_command`] for `metrocell sim` |
//! | [`workflow_photos`] | the twin's photos of a drilled plate (seed 000) by its workflow camera |
//!
//! Camera frame requests are rendered ([`camera_frame`]) as mono8 images of an ArUco plate on
//! `/camera/image_raw`, next to their `CameraInfo`.

pub mod bag;
pub mod camera_frame;
pub mod camera_intrinsics;
pub mod cdr;
pub mod cell_options;
pub mod cli;
pub mod convert;
pub mod duration_text;
pub mod error;
pub mod message_stream;
pub mod pacing;
pub mod sim_time;
pub mod topic_map;
pub mod workflow_photos;

pub use bag::{write_bag, BagOptions, BagSummary, Progress};
pub use camera_frame::{FramePlate, FrameRenderer, FrameRendering};
pub use camera_intrinsics::CameraIntrinsics;
pub use cli::{run_sim_command, SimArgs};
pub use error::SimError;
pub use message_stream::{MessageConverter, MessageStream, SimMessage, TypedMessage};
pub use pacing::Pacer;
pub use topic_map::{QosKind, TopicMap, TopicRole, TopicSpec};
