//! Offline replay: a node reads the topics it subscribes from a bag instead of DDS, in log-time
//! order and as fast as it can process them (`--bag FILE`).
//!
//! ```no_run
//! use metrocell_bagtools::BagSource;
//! use metrocell_msgs::sensor_msgs::msg::Temperature;
//! let mut source = BagSource::open("run42")?;
//! source.subscribe::<Temperature>("/temperature/x_left")?;
//! for m in source.messages()? {
//!     let m = m?;
//!     if m.topic == "/temperature/x_left" {
//!         let t: Temperature = m.decode()?;
//!         // feed the node's library with t, using m.log_time_ns as "now"
//!     }
//! }
//! # Ok::<(), metrocell_bagtools::ToolError>(())
//! ```
//!
//! The node must use the bag's time (`log_time_ns`, the recorder's receive time) wherever it
//! would read the wall clock, so its outputs equal those of a run on the live cell.

use std::path::Path;

use byteorder::{BigEndian, LittleEndian};
use metrocell_bag::{BagReader, MessageFilter};
use rosmsg::RosMessage;

use crate::error::{Result, ToolError};

/// One message read from the bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SourcedMessage {
    pub topic: String,
    /// Receive time at recording [ns since the epoch]; orders replay.
    pub log_time_ns: u64,
    /// Publisher's source timestamp [ns since the epoch].
    pub publish_time_ns: u64,
    /// Encapsulation header + CDR body.
    pub payload: Vec<u8>,
}

impl SourcedMessage {
    /// Decode the payload as `T` with RustDDS's CDR deserializer (the same code that decodes
    /// live DDS samples), honouring the encapsulation header's byte order.
    pub fn decode<T: RosMessage>(&self) -> Result<T> {
        let bad = |reason: String| ToolError::Topic {
            topic: self.topic.clone(),
            reason,
        };
        if self.payload.len() < 4 {
            return Err(bad(format!(
                "payload at log time {} ns is shorter than the CDR header",
                self.log_time_ns
            )));
        }
        let body = &self.payload[4..];
        let decoded = match self.payload[1] {
            0x01 => rustdds::serialization::from_bytes::<T, LittleEndian>(body),
            0x00 => rustdds::serialization::from_bytes::<T, BigEndian>(body),
            other => return Err(bad(format!("message at log time {} ns has encapsulation kind {other:#04x}, which is not plain CDR", self.log_time_ns))),
        };
        decoded.map(|(v, _)| v).map_err(|e| {
            bad(format!(
                "message at log time {} ns is not a valid {}: {e}",
                self.log_time_ns,
                T::ROS_TYPE
            ))
        })
    }
}

/// A bag opened as the message source of a node.
pub struct BagSource {
    reader: BagReader,
    topics: Vec<String>,
}

impl BagSource {
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Ok(Self {
            reader: BagReader::open(path)?,
            topics: Vec::new(),
        })
    }

    /// Read `topic` (a fully resolved name such as `/temperature/x_left`) as `T`. The bag must
    /// record it with type `T::ROS_TYPE`; a topic absent from the bag is accepted and yields
    /// nothing, as a live subscription with no publisher would. Returns whether the bag holds
    /// the topic, so a node can say when an input it needs is not there.
    pub fn subscribe<T: RosMessage>(&mut self, topic: &str) -> Result<bool> {
        let present = match self.reader.topic(topic) {
            Some(t) if t.type_name != T::ROS_TYPE => {
                return Err(ToolError::Topic {
                    topic: topic.to_string(),
                    reason: format!(
                        "recorded as {} in {}, but the node reads {}",
                        t.type_name,
                        self.reader.path().display(),
                        T::ROS_TYPE
                    ),
                });
            }
            Some(_) => true,
            None => false,
        };
        // only topics the bag holds go into the read filter (the reader rejects others)
        if present && !self.topics.iter().any(|t| t == topic) {
            self.topics.push(topic.to_string());
        }
        Ok(present)
    }

    /// The bag's topics (name, type, count, time range), merged over its files.
    pub fn topics(&self) -> &[metrocell_bag::TopicInfo] {
        self.reader.topics()
    }

    /// The bag's path.
    pub fn path(&self) -> &Path {
        self.reader.path()
    }

    /// Read `topic` whatever its type (the caller decodes by the type [`Self::topics`] lists).
    /// Returns whether the bag holds it.
    pub fn subscribe_any(&mut self, topic: &str) -> bool {
        let present = self.reader.topic(topic).is_some();
        if present && !self.topics.iter().any(|t| t == topic) {
            self.topics.push(topic.to_string());
        }
        present
    }

    /// What to tell a user whose bag lacks `topic`: the bag's path and the topics it does hold.
    pub fn missing_topic_hint(&self, topic: &str) -> String {
        let held: Vec<&str> = self
            .reader
            .topics()
            .iter()
            .map(|t| t.name.as_str())
            .collect();
        format!(
            "{} has no topic {topic}, so this replay has nothing to read from it; the bag holds: {} (remap the node's input with --ros-args -r, or record that topic)",
            self.reader.path().display(),
            if held.is_empty() { "no topics".to_string() } else { held.join(", ") }
        )
    }

    /// The subscribed topics' messages in log-time order.
    pub fn messages(&self) -> Result<impl Iterator<Item = Result<SourcedMessage>> + '_> {
        let filter = MessageFilter {
            topics: Some(self.topics.clone()),
            ..Default::default()
        };
        Ok(self.reader.messages(&filter)?.map(|m| {
            let m = m?;
            Ok(SourcedMessage {
                topic: m.topic,
                log_time_ns: m.log_time,
                publish_time_ns: m.publish_time,
                payload: m.data,
            })
        }))
    }

    /// Feed the subscribed messages to `each` in log-time order, asking `stop` before each one:
    /// a replay told to stop (SIGINT) ends between messages, so the caller can still finish its
    /// output whole. Returns the log time of the message it stopped before, or None at the end
    /// of the bag. An error from `each` or from reading the bag ends the replay with that error.
    pub fn replay<E: From<ToolError>>(
        &self,
        stop: impl Fn() -> bool,
        mut each: impl FnMut(SourcedMessage) -> std::result::Result<(), E>,
    ) -> std::result::Result<Option<u64>, E> {
        for m in self.messages()? {
            let m = m?;
            if stop() {
                return Ok(Some(m.log_time_ns));
            }
            each(m)?;
        }
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_bag::{BagWriter, WriterOptions};
    use metrocell_msgs::sensor_msgs::msg::Temperature;

    #[test]
    fn replay_stops_between_messages_and_says_where() {
        let dir = std::env::temp_dir().join(format!("bagtools_replay_stop_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut w = BagWriter::create(&dir, WriterOptions::default()).unwrap();
        w.add_topic("/t", Temperature::ROS_TYPE, Temperature::DEFINITION, "")
            .unwrap();
        for k in 1..=5u64 {
            w.write(
                "/t",
                k * 10,
                k * 10,
                &crate::encode_cdr(&Temperature {
                    temperature: k as f64,
                    ..Default::default()
                })
                .unwrap(),
            )
            .unwrap();
        }
        w.finish().unwrap();
        let mut source = BagSource::open(&dir).unwrap();
        assert!(source.subscribe::<Temperature>("/t").unwrap());
        let seen = std::cell::RefCell::new(Vec::new());
        let stopped = source.replay::<ToolError>(
            || seen.borrow().len() == 2,
            |m| {
                seen.borrow_mut()
                    .push(m.decode::<Temperature>()?.temperature);
                Ok(())
            },
        );
        assert_eq!(
            stopped.unwrap(),
            Some(30),
            "stopped before the third message"
        );
        assert_eq!(*seen.borrow(), [1.0, 2.0]);
        let all = source.replay::<ToolError>(|| false, |_| Ok(())).unwrap();
        assert_eq!(all, None, "an unstopped replay runs to the end");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
