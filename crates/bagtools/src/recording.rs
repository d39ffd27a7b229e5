//! A bag being recorded: the writer plus what the recorder reports in its diagnostics —
//! messages and bytes per topic, and the messages that did not make it into the bag, by cause:
//!
//! * `dropped`: gaps in a publisher's DDS sequence numbers (which count consecutively from 1
//!   per writer) between two samples the recorder received — lost on the wire, or overwritten
//!   in a keep-last queue (the writer's or the recorder's reader's) before they were taken;
//! * `before_subscription`: the samples a publisher sent before the recorder's first sample
//!   from it (its first sequence number − 1) — sent before the recorder subscribed, or lost
//!   like a gap before the first sample arrived (the two cannot be told apart);
//! * `unreadable`: samples DDS delivered that could not be taken (not CDR, for example).
//!
//! A gap is also named by time: the log times of the samples either side of it
//! ([`SequenceGap`]), so a cut network link shows as "N messages between 12:00:14.2 and
//! 12:01:14.5" rather than only as a count. Each topic keeps its [`NAMED_GAPS`] largest gaps;
//! [`Recording::take_new_gaps`] hands the recorder each gap once, as it is found.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::path::Path;

use metrocell_bag::{BagMetadata, BagWriter, WriterOptions};

use crate::error::Result;

/// Per-topic bookkeeping.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TopicCounts {
    pub ros_type: String,
    /// The type's definition is not known to metrocell: recorded as raw CDR without it.
    pub without_definition: bool,
    pub messages: u64,
    /// Payload bytes including the 4-byte encapsulation header.
    pub bytes: u64,
    /// Messages the publishers sent that never reached the recorder (sequence-number gaps).
    pub dropped: u64,
    /// Messages the publishers sent before the recorder's first sample from them.
    pub before_subscription: u64,
    /// Samples received that could not be taken (see [`Recording::count_unreadable`]).
    pub unreadable: u64,
    /// The largest sequence gaps (at most [`NAMED_GAPS`], largest first), with their times.
    pub gaps: Vec<SequenceGap>,
}

/// How many gaps each topic names by time; the rest are only counted (in `dropped`).
pub const NAMED_GAPS: usize = 8;

/// How many found gaps wait for [`Recording::take_new_gaps`] at most; beyond, the oldest go
/// (they are still counted, and the largest still named per topic).
const PENDING_GAPS: usize = 1024;

/// Messages missing between two samples one publisher sent on one topic, located in time by
/// the log (receive) times of those two samples, in ns since the Unix epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SequenceGap {
    pub missing: u64,
    /// Log time of the last sample received before the gap.
    pub after_ns: u64,
    /// Log time of the first sample received after it.
    pub until_ns: u64,
}

impl SequenceGap {
    /// "30 messages between 12:00:14.2 and 12:01:14.5 UTC (60.3 s)".
    pub fn describe(&self) -> String {
        format!(
            "{} message{} between {} and {} UTC ({:.1} s)",
            self.missing,
            if self.missing == 1 { "" } else { "s" },
            clock_time(self.after_ns),
            clock_time(self.until_ns),
            self.until_ns.saturating_sub(self.after_ns) as f64 * 1e-9
        )
    }
}

/// Time of day, UTC, to a tenth of a second, of a time in ns since the Unix epoch.
fn clock_time(ns: u64) -> String {
    let tenths = ns / 100_000_000;
    let s = (tenths / 10) % 86_400;
    format!(
        "{:02}:{:02}:{:02}.{}",
        s / 3600,
        s / 60 % 60,
        s % 60,
        tenths % 10
    )
}

impl TopicCounts {
    /// Every message known to be missing from the bag, whatever the cause.
    pub fn missing(&self) -> u64 {
        self.dropped + self.before_subscription + self.unreadable
    }
}

/// How a topic's type went into the bag.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TopicDefinition {
    /// With its full definition from metrocell's registry.
    Known,
    /// metrocell does not know the type: raw CDR with an empty schema (see
    /// [`BagWriter::add_topic_without_definition`]).
    Unknown,
}

pub struct Recording {
    writer: BagWriter,
    topics: BTreeMap<String, TopicCounts>,
    /// (topic, publisher key) → last sequence number seen, and its log time.
    last_sequence: HashMap<(String, u64), (i64, u64)>,
    /// Gaps found since the last [`Recording::take_new_gaps`], by topic.
    new_gaps: VecDeque<(String, SequenceGap)>,
}

impl Recording {
    pub fn create(dir: impl AsRef<Path>, options: WriterOptions) -> Result<Self> {
        Ok(Self {
            writer: BagWriter::create(dir, options)?,
            topics: BTreeMap::new(),
            last_sequence: HashMap::new(),
            new_gaps: VecDeque::new(),
        })
    }

    /// [`BagWriter::append`]: go on in a bag a recorder left unfinished (recovered first),
    /// with the recovery's report.
    pub fn append(
        dir: impl AsRef<Path>,
        options: WriterOptions,
    ) -> Result<(Self, Option<metrocell_bag::RecoveryReport>)> {
        let (writer, report) = BagWriter::append(dir, options)?;
        Ok((
            Self {
                writer,
                topics: BTreeMap::new(),
                last_sequence: HashMap::new(),
                new_gaps: VecDeque::new(),
            },
            report,
        ))
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

    /// Add `topic` with the full definition of `ros_type` from metrocell's registry, or, when
    /// metrocell does not know the type, without a definition (the payloads are still recorded
    /// byte for byte, as rosbag2 does for a type it has no definition of).
    pub fn add_topic(
        &mut self,
        topic: &str,
        ros_type: &str,
        qos_yaml: &str,
    ) -> Result<TopicDefinition> {
        if let Some(c) = self.topics.get(topic) {
            return Ok(if c.without_definition {
                TopicDefinition::Unknown
            } else {
                TopicDefinition::Known
            });
        }
        let kind = match metrocell_msgs::registry().full_definition(ros_type) {
            Ok(definition) => {
                self.writer
                    .add_topic(topic, ros_type, &definition, qos_yaml)?;
                TopicDefinition::Known
            }
            Err(_) => {
                self.writer
                    .add_topic_without_definition(topic, ros_type, qos_yaml)?;
                TopicDefinition::Unknown
            }
        };
        let counts = TopicCounts {
            ros_type: ros_type.to_string(),
            without_definition: kind == TopicDefinition::Unknown,
            ..Default::default()
        };
        self.topics.insert(topic.to_string(), counts);
        Ok(kind)
    }

    /// Record one message. `publisher` identifies the DDS writer (e.g. a hash of its GID) and
    /// `sequence` is its sequence number (≤ 0 = unknown, no loss accounting).
    pub fn record(
        &mut self,
        topic: &str,
        log_ns: u64,
        publish_ns: u64,
        payload: &[u8],
        publisher: u64,
        sequence: i64,
    ) -> Result<()> {
        self.writer.write(topic, log_ns, publish_ns, payload)?;
        let counts = self
            .topics
            .get_mut(topic)
            .expect("write succeeded, so the topic was added");
        counts.messages += 1;
        counts.bytes += payload.len() as u64;
        if sequence > 0 {
            match self.last_sequence.get_mut(&(topic.to_string(), publisher)) {
                None => {
                    counts.before_subscription += (sequence - 1) as u64;
                    self.last_sequence
                        .insert((topic.to_string(), publisher), (sequence, log_ns));
                }
                Some((last, last_log_ns)) => {
                    if sequence > *last + 1 {
                        let gap = SequenceGap {
                            missing: (sequence - *last - 1) as u64,
                            after_ns: *last_log_ns,
                            until_ns: log_ns,
                        };
                        counts.dropped += gap.missing;
                        name_gap(&mut counts.gaps, gap);
                        // a flood finds gaps faster than they are reported: the oldest go, in O(1)
                        if self.new_gaps.len() == PENDING_GAPS {
                            self.new_gaps.pop_front();
                        }
                        self.new_gaps.push_back((topic.to_string(), gap));
                    }
                    if sequence > *last {
                        *last = sequence;
                        *last_log_ns = log_ns;
                    }
                }
            }
        }
        Ok(())
    }

    /// The gaps found since the last call, in the order found, with their topics.
    pub fn take_new_gaps(&mut self) -> Vec<(String, SequenceGap)> {
        std::mem::take(&mut self.new_gaps).into()
    }

    /// Count a sample of `topic` that DDS delivered but that could not be taken.
    pub fn count_unreadable(&mut self, topic: &str) {
        if let Some(c) = self.topics.get_mut(topic) {
            c.unreadable += 1;
        }
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

    /// Every message known to be missing, all causes, all topics.
    pub fn total_missing(&self) -> u64 {
        self.topics.values().map(TopicCounts::missing).sum()
    }

    pub fn finish(self) -> Result<BagMetadata> {
        Ok(self.writer.finish()?)
    }
}

/// Keep `gap` among a topic's [`NAMED_GAPS`] largest, largest first (an earlier gap first among
/// equals).
fn name_gap(gaps: &mut Vec<SequenceGap>, gap: SequenceGap) {
    let at = gaps.partition_point(|g| g.missing >= gap.missing);
    if at < NAMED_GAPS {
        gaps.insert(at, gap);
        gaps.truncate(NAMED_GAPS);
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
        assert_eq!(
            r.add_topic("/t", "sensor_msgs/msg/Temperature", "")
                .unwrap(),
            TopicDefinition::Known
        );
        let payload = rosmsg::encode(
            metrocell_msgs::registry(),
            "sensor_msgs/msg/Temperature",
            &rosmsg::default_value(metrocell_msgs::registry(), "sensor_msgs/msg/Temperature")
                .unwrap(),
        )
        .unwrap();
        for seq in [1, 2, 5, 6] {
            r.record("/t", seq as u64 * 10, seq as u64, &payload, 7, seq)
                .unwrap();
        }
        r.record("/t", 100, 100, &payload, 8, 3).unwrap(); // another publisher, starting late
        r.count_unreadable("/t");
        let c = r.counts()["/t"].clone();
        assert_eq!(
            (
                c.messages,
                c.bytes,
                c.dropped,
                c.before_subscription,
                c.unreadable
            ),
            (5, 5 * payload.len() as u64, 2, 2, 1)
        );
        assert_eq!((r.total_dropped(), r.total_missing()), (2, 5));
        // the gap of 2 between sequence numbers 2 and 5, at their log times 20 and 50 ns
        let gap = SequenceGap {
            missing: 2,
            after_ns: 20,
            until_ns: 50,
        };
        assert_eq!(c.gaps, vec![gap]);
        assert_eq!(r.take_new_gaps(), vec![("/t".to_string(), gap)]);
        assert!(r.take_new_gaps().is_empty(), "each gap is handed over once");
        let meta = r.finish().unwrap();
        assert_eq!(meta.message_count, 5);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_gaps_waiting_to_be_reported_are_bounded_the_oldest_going() {
        let dir = std::env::temp_dir().join(format!("bagtools_pending_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut r = Recording::create(&dir, WriterOptions::default()).unwrap();
        r.add_topic("/t", "std_msgs/msg/String", "").unwrap();
        let payload = rosmsg::encode(
            metrocell_msgs::registry(),
            "std_msgs/msg/String",
            &rosmsg::default_value(metrocell_msgs::registry(), "std_msgs/msg/String").unwrap(),
        )
        .unwrap();
        // odd sequence numbers only: a gap of one before every sample after the first
        let found = PENDING_GAPS + 5;
        for k in 0..=found as i64 {
            let seq = 2 * k + 1;
            r.record("/t", seq as u64, seq as u64, &payload, 1, seq)
                .unwrap();
        }
        let pending = r.take_new_gaps();
        assert_eq!(pending.len(), PENDING_GAPS);
        // the 5 oldest went: the first kept is the 6th found, after sequence number 11
        assert_eq!(pending[0].1.after_ns, 11);
        assert_eq!(r.counts()["/t"].dropped, found as u64, "all still counted");
        r.finish().unwrap();
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_topic_names_its_largest_gaps_by_time() {
        let mut gaps = Vec::new();
        // gaps of 1..=12 messages found in a shuffled order; the 8 largest are kept
        for (i, missing) in [3u64, 12, 1, 7, 9, 2, 11, 5, 4, 10, 6, 8]
            .into_iter()
            .enumerate()
        {
            let after_ns = i as u64 * 1_000_000_000;
            name_gap(
                &mut gaps,
                SequenceGap {
                    missing,
                    after_ns,
                    until_ns: after_ns + missing * 100_000_000,
                },
            );
        }
        let kept: Vec<u64> = gaps.iter().map(|g| g.missing).collect();
        assert_eq!(kept, vec![12, 11, 10, 9, 8, 7, 6, 5]);
        // a 60.3-s cut that began at 12:00:14.2 UTC on 2026-11-29
        let noon = 1_795_953_600_000_000_000u64;
        let cut = SequenceGap {
            missing: 30,
            after_ns: noon + 14_200_000_000,
            until_ns: noon + 74_500_000_000,
        };
        assert_eq!(
            cut.describe(),
            "30 messages between 12:00:14.2 and 12:01:14.5 UTC (60.3 s)"
        );
    }

    #[test]
    fn a_type_metrocell_does_not_know_is_recorded_raw_without_a_definition() {
        let dir =
            std::env::temp_dir().join(format!("bagtools_recording_raw_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut r = Recording::create(&dir, WriterOptions::default()).unwrap();
        assert_eq!(
            r.add_topic("/u", "unknown_pkg/msg/Nope", "").unwrap(),
            TopicDefinition::Unknown
        );
        let raw = [0u8, 1, 0, 0, 0xde, 0xad, 0xbe, 0xef, 7];
        r.record("/u", 10, 10, &raw, 1, 1).unwrap();
        assert!(r.counts()["/u"].without_definition);
        r.finish().unwrap();
        let reader = metrocell_bag::BagReader::open(&dir).unwrap();
        let t = reader
            .topics()
            .iter()
            .find(|t| t.name == "/u")
            .expect("topic in the bag")
            .clone();
        assert_eq!(
            (
                t.type_name.as_str(),
                t.schema_encoding.as_str(),
                t.definition.as_str()
            ),
            ("unknown_pkg/msg/Nope", "", "")
        );
        let msgs = reader
            .read_all(&metrocell_bag::MessageFilter::default())
            .unwrap();
        assert_eq!(msgs.len(), 1);
        assert_eq!(msgs[0].data, raw, "payload stored byte for byte");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
