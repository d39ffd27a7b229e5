//! ROS 2 message interfaces without any DDS in them.
//!
//! One source of truth: the `.msg` files. This crate parses them ([`parse`]), keeps them in a
//! [`Registry`] that produces the full ros2msg definition text (what MCAP schemas carry),
//! encodes/decodes CDR (XCDR1, little-endian, 4-byte encapsulation header) dynamically for
//! tools that only learn the type at run time ([`cdr`]), converts YAML/JSON to and from
//! [`Value`] ([`convert`]), and generates the Rust types of `metrocell-msgs` ([`codegen`]).

pub mod cdr;
pub mod codegen;
pub mod convert;
pub mod parse;
pub mod registry;
pub mod sample;
pub mod serde_helpers;
pub mod spec;
pub mod value;

pub use cdr::{decode, default_value, encode, DecodeError, EncodeError};
pub use convert::{
    from_json, from_yaml, from_yaml_str, to_json, to_yaml, to_yaml_string, ConvertError,
};
pub use parse::{parse_message, ParseError};
pub use registry::{Registry, RegistryError, DEFINITION_SEPARATOR};
pub use sample::sample_value;
pub use spec::{ArrayKind, BaseType, Constant, Field, FieldType, MessageSpec, Primitive, TypeName};
pub use value::{StructValue, Value};

/// Implemented by every Rust type generated from a `.msg` file (see `metrocell-msgs`).
///
/// Serialising a value with a CDR serializer (e.g. RustDDS's) yields exactly the bytes
/// ROS 2 puts on the wire, because field order, fixed arrays (no length prefix) and
/// sequences (u32 length prefix) follow the `.msg`.
pub trait RosMessage:
    serde::Serialize
    + serde::de::DeserializeOwned
    + Clone
    + std::fmt::Debug
    + PartialEq
    + Default
    + Send
    + 'static
{
    /// ROS type name, e.g. `metrocell_msgs/msg/TrackerMeasurement`.
    const ROS_TYPE: &'static str;
    /// Package part of the type name, e.g. `metrocell_msgs`.
    const PACKAGE: &'static str;
    /// Bare type name, e.g. `TrackerMeasurement`.
    const NAME: &'static str;
    /// DDS type name, e.g. `metrocell_msgs::msg::dds_::TrackerMeasurement_`.
    const DDS_TYPE: &'static str;
    /// Full ros2msg definition: this type's `.msg` text followed by every dependency,
    /// each introduced by a line of 80 `=` and a line `MSG: pkg/Type` (rosbag2 / MCAP schema data).
    const DEFINITION: &'static str;
}
