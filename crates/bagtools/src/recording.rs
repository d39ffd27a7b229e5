//! A bag being recorded: the writer plus what the recorder reports in its diagnostics —
//! messages and bytes per topic, and messages dropped on the way (gaps in each publisher's
//! DDS sequence numbers, which count consecutively from 1 per writer).

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use metrocell_bag::{BagMetadata, BagWriter, WriterOptions};

use crate::error::Result;

/// Per-topic bookkeeping.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TopicCounts {
    pub ros_type: String,
    pub messages: u64,
    /// Payload bytes including the 4-byte encapsulation header.
    pub bytes: u64,
    /// Messages the publishers sent that never reached the recorder (sequence-number gaps).
    pub dropped: u64,
}

pub struct Recording {
    writer: BagWriter,
    topics: BTreeMap<String, TopicCounts>,
    /// (topic, publisher key) → last sequence number seen.
    last_sequence: HashMap<(String, u64), i64>,
}

impl Recording {
    pub fn create(dir: impl AsRef<Path>, options: WriterOptions) -> Result<Self> {
        Ok(Self { writer: BagWriter::create(dir, options)?, topics: BTreeMap::new(), last_sequence: HashMap::new() })
    }

    pub fn dir(&self) -> &Path {
        self.writer.dir()
    }

    /// The file being written (for error messages).
    pub fn current_file(&self) -> Option<&Path> {
        self.writer.current_file()
    }

    pub fn has_topic(&self, topic: &str) -> bool {
        self.topics.contains_key(topic)
    }

    /// Add `topic` with the full definition of `ros_type` from metrocell's registry.
    /// Returns `Ok(false)` without adding it when metrocell does not know the type: a bag
    /// without the definition could not be decoded by rosbags or Foxglove, so such topics are
    /// skipped (the caller warns, naming the type).
    pub fn add_topic(&mut self, topic: &str, ros_type: &str, qos_yaml: &str) -> Result<bool> {
        if self.topics.contains_key(topic) {
            return Ok(true);
        }
        let Ok(definition) = metrocell_msgs::registry().full_definition(ros_type) else {
            return Ok(false);
        };
        self.writer.add_topic(topic, ros_type, &definition, qos_yaml)?;
        self.topics.insert(topic.to_string(), TopicCounts { ros_type: ros_type.to_string(), ..Default::default() });
        Ok(true)
    }

    /// Record one message. `publisher` identifies the DDS writer (e.g. a hash of its GID) and
    /// `sequence` is its sequence number (≤ 0 = unknown, no drop detection).
    pub fn record(&mut self, topic: &str, log_ns: u64, publish_ns: u64, payload: &[u8], publisher: u64, sequence: i64) -> Result<()> {
        self.writer.write(topic, log_ns, publish_ns, payload)?;
        let counts = self.topics.get_mut(topic).expect("write succeeded, so the topic was added");
        counts.messages += 1;
        counts.bytes += payload.len() as u64;
        if sequence > 0 {
            let last = self.last_sequence.entry((topic.to_string(), publisher)).or_insert(sequence - 1);
            if sequence > *last + 1 {
                counts.dropped += (sequence - *last - 1) as u64;
            }
            *last = (*last).max(sequence);
        }
        Ok(())
    }

    /// Flush if the flush interval has passed; call at least every flush interval.
    pub fn tick(&mut self) -> Result<()> {
        Ok(self.writer.tick()?)
    }

    pub fn counts(&self) -> &BTreeMap<String, TopicCounts> {
        &self.topics
    }

    pub fn total_messages(&self) -> u64 {
        self.topics.values().map(|c| c.messages).sum()
    }

    pub fn total_dropped(&self) -> u64 {
        self.topics.values().map(|c| c.dropped).sum()
    }

    pub fn finish(self) -> Result<BagMetadata> {
        Ok(self.writer.finish()?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_bytes_and_sequence_gaps() {
        let dir = std::env::temp_dir().join(format!("bagtools_recording_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut r = Recording::create(&dir, WriterOptions::default()).unwrap();
        assert!(r.add_topic("/t", "sensor_msgs/msg/Temperature", "").unwrap());
        assert!(!r.add_topic("/u", "unknown_pkg/msg/Nope", "").unwrap());
        let payload = rosmsg::encode(
            metrocell_msgs::registry(),
            "sensor_msgs/msg/Temperature",
            &rosmsg::default_value(metrocell_msgs::registry(), "sensor_msgs/msg/Temperature").unwrap(),
        )
        .unwrap();
        for seq in [1, 2, 5, 6] {
            r.record("/t", seq as u64 * 10, seq as u64, &payload, 7, seq).unwrap();
        }
        r.record("/t", 100, 100, &payload, 8, 3).unwrap(); // another publisher, starting late
        let c = r.counts()["/t"].clone();
        assert_eq!((c.messages, c.bytes, c.dropped), (5, 5 * payload.len() as u64, 2));
        let meta = r.finish().unwrap();
        assert_eq!(meta.message_count, 5);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
