//! metrocell's ROS 2 interfaces as Rust types, generated at build time from the same `.msg`
//! files that colcon builds (`msg/` for metrocell's own types, `interfaces/<pkg>/msg/` for the
//! standard ROS 2 types the nodes use, copied verbatim from ROS 2 Jazzy).
//!
//! - `metrocell_msgs::msg::TrackerMeasurement`, ... : metrocell's own types;
//! - `metrocell_msgs::<pkg>::msg::<Type>` for the standard packages, e.g.
//!   [`std_msgs::msg::Header`], [`sensor_msgs::msg::Temperature`];
//! - [`registry()`]: every type's parsed spec (dynamic CDR, YAML/JSON, full definitions);
//! - [`topics`]: the topic names a cell publishes and a recording holds.

use std::sync::OnceLock;

include!(concat!(env!("OUT_DIR"), "/metrocell_msgs.rs"));

mod time;
pub mod topics;

pub use rosmsg::RosMessage;

/// Every message type of this crate, parsed from the embedded `.msg` texts. The build script
/// already parsed and checked the same texts, so building the registry cannot fail.
pub fn registry() -> &'static rosmsg::Registry {
    static REGISTRY: OnceLock<rosmsg::Registry> = OnceLock::new();
    REGISTRY.get_or_init(|| {
        let mut r = rosmsg::Registry::new();
        for (pkg, name, text) in MSG_SOURCES {
            r.add_msg(pkg, name, text)
                .expect("embedded .msg text was parsed by build.rs");
        }
        r.check()
            .expect("embedded .msg set was checked by build.rs");
        r
    })
}

/// ROS 2 names (`pkg/msg/Type`) of every type this crate knows, sorted.
pub fn type_names() -> Vec<String> {
    registry().ros_type_names()
}
