//! Offline replay, output side: a node replaying a bag (`--bag FILE --output OUT`) writes what it
//! would publish into a new bag, stamped with the bag time at which it would have published.
//!
//! The pattern for any node (see the crate README):
//! 1. resolve the node's name, remaps and parameters without DDS
//!    (`metrocell_node::NodeBuilder::build_offline`);
//! 2. [`crate::BagSource::subscribe`] every topic the node would subscribe (resolved names);
//! 3. keep the node's logic in a struct whose methods take the message and `now_ns` explicitly —
//!    live: `node.now()`, replay: [`crate::SourcedMessage::log_time_ns`] — so periods and staleness
//!    run on bag time, never on the wall clock;
//! 4. write every output with [`BagSink::write`] at the input's log time.

use std::collections::BTreeSet;
use std::path::Path;

use byteorder::LittleEndian;
use metrocell_bag::{qos_profiles_yaml, BagMetadata, BagWriter, QosProfile, WriterOptions};
use rosmsg::RosMessage;

use crate::error::{Result, ToolError};

/// Typed message → plain CDR (XCDR1, little-endian) with its 4-byte encapsulation header, the
/// bytes a ROS 2 publisher puts on the wire and a rosbag2 recorder stores.
pub fn encode_cdr<T: RosMessage>(m: &T) -> Result<Vec<u8>> {
    let mut v = vec![0, 1, 0, 0];
    let body =
        rustdds::serialization::to_vec::<T, LittleEndian>(m).map_err(|e| ToolError::Topic {
            topic: T::ROS_TYPE.into(),
            reason: format!("cannot serialise: {e}"),
        })?;
    v.extend(body);
    Ok(v)
}

/// A bag receiving a replaying node's outputs.
pub struct BagSink {
    writer: BagWriter,
    topics: BTreeSet<String>,
}

impl BagSink {
    pub fn create(dir: impl AsRef<Path>, options: WriterOptions) -> Result<Self> {
        Ok(Self {
            writer: BagWriter::create(dir, options)?,
            topics: BTreeSet::new(),
        })
    }

    /// Declare output `topic` (resolved name) of type `T`, with its full definition as schema.
    pub fn advertise<T: RosMessage>(&mut self, topic: &str) -> Result<()> {
        if self.topics.insert(topic.to_string()) {
            let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
            self.writer
                .add_topic(topic, T::ROS_TYPE, T::DEFINITION, &qos)?;
        }
        Ok(())
    }

    /// Write `msg` on an advertised `topic` at bag time `time_ns` (log and publish time).
    pub fn write<T: RosMessage>(&mut self, topic: &str, msg: &T, time_ns: u64) -> Result<()> {
        if !self.topics.contains(topic) {
            return Err(ToolError::Topic {
                topic: topic.into(),
                reason: "written before advertise".into(),
            });
        }
        let cdr = encode_cdr(msg)?;
        self.writer.write(topic, time_ns, time_ns, &cdr)?;
        Ok(())
    }

    pub fn finish(self) -> Result<BagMetadata> {
        Ok(self.writer.finish()?)
    }
}
