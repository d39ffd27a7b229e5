//! The recorder: records DDS topics into a crash-safe rosbag2 MCAP bag. One implementation,
//! run by the `metrocell-recorder` node binary and in-process by `metrocell bag record`.
//!
//! Subscribes every discovered topic (discovery is re-scanned every `scan_interval`, so late
//! publishers are recorded too), or the `topics` list, or those matching `regex`, minus
//! `exclude`. Payloads are stored as received (raw CDR), with the type's full definition from
//! metrocell's registry; a type metrocell does not know is recorded all the same, raw, with an
//! empty schema (see `metrocell_bag::BagWriter::add_topic_without_definition`).
//! log_time = receive time, publish_time = the publisher's DDS source timestamp.
//!
//! QoS, as rosbag2 adapts it (`metrocell_bagtools::recorded_qos::recording_qos`): a topic is
//! read reliably when every publisher discovered when recording of it began offers reliable
//! (so nothing is lost on the wire: DDS retransmits), best effort otherwise (a best-effort
//! reader matches every publisher); transient-local when every publisher is latched. History
//! keep-last `queue_depth` (`bulk_queue_depth` for byte-array types such as images). The
//! `qos_profile_overrides_path` file replaces these per topic. A publisher that appears later
//! offering best effort on a topic read reliably does not match: a warning names it.
//!
//! A taker thread ([`taker`]) moves samples from the readers into a cache bounded by
//! `max_cache_size` as they arrive, and the recording loop writes them, so a flush or a busy
//! moment of the loop does not leave the readers' queues to overflow.
//!
//! Losses are accounted by cause (`metrocell_bagtools::TopicCounts`): sequence gaps between
//! received samples (`dropped`), samples sent before the recorder's first one from that
//! publisher (`before_subscription`), samples that could not be taken (`unreadable`); each in
//! the diagnostics and, per topic, in the final log line. Gaps are named by time too
//! ([`gap_report`]): each scan logs the gaps found since the last one, and the final line names
//! each topic's largest.
//!
//! Each topic's `offered_qos_profiles` holds the QoS its publishers announced in discovery when
//! recording of the topic began, one profile per publisher, as rosbag2 stores them.

pub mod gap_report;
pub mod parameters;
mod reader_qos;
mod taker;

use std::collections::{BTreeMap, BTreeSet};
use std::hash::{Hash, Hasher};
use std::time::{Duration, Instant};

use metrocell_bag::offered_qos_yaml;
use metrocell_bagtools::recorded_qos::{offered_qos_of_topic, recording_qos};
use metrocell_bagtools::{Recording, TopicCounts, TopicDefinition};
use metrocell_node::names::dds_topic_name;
use metrocell_node::MetrocellNode;
use taker::{Taken, Taker};

pub use parameters::RecorderSettings;

fn publisher_key(gid: &impl Hash) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    gid.hash(&mut h);
    h.finish()
}

/// What a finished (or failed) recording holds.
#[derive(Debug, Clone)]
pub struct RecordingSummary {
    pub output: String,
    pub counts: BTreeMap<String, TopicCounts>,
    /// Per topic: whether it was read reliably, and its reader's keep-last depth (0 = keep all).
    pub readers: BTreeMap<String, (bool, usize)>,
}

impl RecordingSummary {
    pub fn total_messages(&self) -> u64 {
        self.counts.values().map(|c| c.messages).sum()
    }

    pub fn total_missing(&self) -> u64 {
        self.counts.values().map(TopicCounts::missing).sum()
    }

    /// "N messages recorded, M missing" and, for each topic that lost any, how many and why.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "{} messages recorded on {} topics, {} missing",
            self.total_messages(),
            self.counts.len(),
            self.total_missing()
        );
        for (topic, c) in self.counts.iter().filter(|(_, c)| c.missing() > 0) {
            let (reliable, depth) = self.readers.get(topic).copied().unwrap_or((false, 0));
            let mut causes = Vec::new();
            if c.dropped > 0 {
                causes.push(if reliable {
                    format!("{} in sequence gaps (read reliably: overwritten in the reader queue of {depth} before the recorder took them or in the publisher's history, or published while the publisher and the recorder had lost each other: a network cut longer than the DDS lease)", c.dropped)
                } else {
                    format!("{} in sequence gaps (read best effort: lost on the wire or overwritten in the reader queue of {depth})", c.dropped)
                });
                causes.push(gap_report::largest_gaps(&c.gaps, 3));
            }
            if c.before_subscription > 0 {
                causes.push(format!("{} sent before the first sample received from their publisher (before the recorder subscribed, or lost like a gap)", c.before_subscription));
            }
            if c.unreadable > 0 {
                causes.push(format!(
                    "{} samples that could not be taken (not CDR)",
                    c.unreadable
                ));
            }
            s.push_str(&format!(
                "\n  {topic}: {} missing: {}",
                c.missing(),
                causes.join(", ")
            ));
        }
        s
    }
}

/// The error of a recording that stopped early, with what it holds.
#[derive(Debug)]
pub struct RecordingFailed {
    pub message: String,
    pub summary: Option<RecordingSummary>,
}

impl std::fmt::Display for RecordingFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for RecordingFailed {}

fn failed(message: impl std::fmt::Display) -> RecordingFailed {
    RecordingFailed {
        message: message.to_string(),
        summary: None,
    }
}

/// Record until the node's shutdown token triggers (SIGINT/SIGTERM when the node handles
/// signals), then finish the bag. On a write failure (disk full) the bag is left sealed and
/// valid and the error names the file.
pub fn record(
    node: &mut MetrocellNode,
    settings: &RecorderSettings,
) -> Result<RecordingSummary, RecordingFailed> {
    let mut recording = if settings.resume {
        let (recording, recovered) =
            Recording::append(&settings.output, settings.writer_options.clone()).map_err(failed)?;
        if let Some(report) = recovered {
            node.warn(format!(
                "{} held a bag a recorder did not finish: recovered ({} messages kept, {} chunk(s) \
                 dropped); going on in a new split file {}",
                settings.output,
                report.kept_messages(),
                report.dropped_chunks(),
                recording
                    .current_file()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default()
            ));
        }
        recording
    } else {
        Recording::create(&settings.output, settings.writer_options.clone()).map_err(failed)?
    };
    node.info(format!("recording into {}", settings.output));
    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    let taker = Taker::start(settings.max_cache_bytes)
        .map_err(|e| failed(format!("cannot start the taker thread: {e}")))?;
    // The recorded topics in the order the taker knows them (its `topic` index).
    let mut topics: Vec<String> = Vec::new();
    let mut readers: BTreeMap<String, (bool, usize)> = BTreeMap::new();
    // Writers (by GUID) already seen on recorded topics, so a late best-effort one is reported once.
    let mut known_writers: BTreeSet<String> = BTreeSet::new();
    let mut next_scan = Instant::now();
    let mut failure = None;
    let mut stopping = false;
    let mut stop_requested = None;
    loop {
        if token.is_triggered() && !stopping {
            stop_requested = Some(Instant::now());
            // The taker goes on taking what is still arriving (samples in flight or being
            // repaired), then ends; everything it took is recorded below.
            taker.stop();
            stopping = true;
        }
        if !stopping && Instant::now() >= next_scan {
            next_scan += settings.scan_interval;
            if let Err(e) = scan(
                node,
                settings,
                &mut recording,
                &taker,
                &mut topics,
                &mut readers,
                &mut known_writers,
            ) {
                failure = Some(e);
                break;
            }
            for (topic, c) in recording.counts() {
                diagnostics.set_value(&format!("{topic}/messages"), c.messages);
                diagnostics.set_value(&format!("{topic}/dropped"), c.dropped);
                diagnostics.set_value(
                    &format!("{topic}/before_subscription"),
                    c.before_subscription,
                );
                diagnostics.set_value(&format!("{topic}/unreadable"), c.unreadable);
            }
            if let Some(report) = gap_report::describe_new_gaps(&recording.take_new_gaps()) {
                node.warn(report);
            }
            diagnostics.set_value("messages", recording.total_messages());
            diagnostics.set_value("dropped", recording.total_dropped());
            diagnostics.set_value("missing", recording.total_missing());
            diagnostics.set_value("cache_bytes", taker.cached_bytes());
            if taker.take_cache_full() {
                node.warn(format!(
                    "the recorder's cache ({} bytes) is full: writing does not keep up, so samples wait in the DDS readers' queues (parameters max_cache_size, queue_depth)",
                    settings.max_cache_bytes
                ));
            }
        }
        // Record what the taker has handed over, for at most RECORD_SLICE so discovery is
        // still scanned and the bag flushed on time.
        let slice_end = Instant::now() + RECORD_SLICE;
        let mut ended = false;
        while Instant::now() < slice_end {
            match taker.next(Duration::from_millis(1)) {
                Ok(Taken::Message { topic, message: m }) => {
                    let log = m.receive_time_ns.max(0) as u64;
                    let publish = m.source_time_ns.map_or(log, |t| t.max(0) as u64);
                    if let Err(e) = recording.record(
                        &topics[topic],
                        log,
                        publish,
                        &m.payload,
                        publisher_key(&m.publisher_gid),
                        m.sequence_number,
                    ) {
                        failure = Some(e.to_string());
                        break;
                    }
                }
                Ok(Taken::Unreadable { topic, error }) => {
                    recording.count_unreadable(&topics[topic]);
                    node.warn(format!(
                        "{}: a sample could not be taken: {error}",
                        topics[topic]
                    ));
                }
                Err(false) => break,
                Err(true) => {
                    ended = true;
                    break;
                }
            }
        }
        if failure.is_some() {
            break;
        }
        if let Err(e) = recording.tick() {
            failure = Some(e.to_string());
            break;
        }
        if ended {
            break;
        }
    }
    drop(taker);
    let summary = RecordingSummary {
        output: settings.output.clone(),
        counts: recording.counts().clone(),
        readers,
    };
    if let Some(e) = failure {
        let file = recording
            .current_file()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| settings.output.clone());
        node.error(format!(
            "recording stopped: {e} (file {file}); {}",
            summary.describe()
        ));
        diagnostics.error(format!("write failed: {e}"));
        return Err(RecordingFailed {
            message: format!("recording into {file} stopped: {e}"),
            summary: Some(summary),
        });
    }
    let finishing = Instant::now();
    recording.finish().map_err(failed)?;
    if let Some(requested) = stop_requested.filter(|t| t.elapsed() > SLOW_STOP) {
        node.warn(format!(
            "stopping took {:.1} s, {:.1} s of it finishing the bag (its index and metadata \
             written and synced to disk): the disk is slow or busy",
            requested.elapsed().as_secs_f64(),
            finishing.elapsed().as_secs_f64()
        ));
    }
    node.info(format!(
        "bag {} finished: {}",
        settings.output,
        summary.describe()
    ));
    Ok(summary)
}

/// A stop slower than this is logged with where the time went (a node is expected to stop within
/// a second; a busy disk's fsync has taken 10 s).
const SLOW_STOP: Duration = Duration::from_secs(2);

/// The longest the recording loop spends writing what the taker handed over before it looks at
/// discovery and the flush timer again.
const RECORD_SLICE: Duration = Duration::from_millis(100);

/// Subscribe the selected topics discovery shows that are not recorded yet.
fn scan(
    node: &mut MetrocellNode,
    settings: &RecorderSettings,
    recording: &mut Recording,
    taker: &Taker,
    topics: &mut Vec<String>,
    readers: &mut BTreeMap<String, (bool, usize)>,
    known_writers: &mut BTreeSet<String>,
) -> Result<(), String> {
    let discovered = node.discovered_publications();
    let recorded_wanted = discovered
        .iter()
        .any(|t| settings.selection.matches(&t.name) && !recording.has_topic(&t.name));
    // Reading every discovered writer's QoS costs a copy of discovery: only when a topic is new,
    // or every scan while some topic is read reliably (to name a late best-effort publisher).
    if !recorded_wanted && !readers.values().any(|(reliable, _)| *reliable) {
        return Ok(());
    }
    let writers = node.context().domain_participant().discovered_writers();
    let publications: Vec<_> = writers.iter().map(|w| &w.publication_topic_data).collect();
    for t in discovered {
        if !settings.selection.matches(&t.name) {
            continue;
        }
        let dds = dds_topic_name(&t.name);
        if let Some(&(true, _)) = readers.get(&t.name) {
            for p in publications.iter().filter(|p| p.topic_name == dds) {
                let id = format!("{:?}", p.key);
                if known_writers.insert(id)
                    && matches!(
                        p.reliability,
                        Some(rustdds::policy::Reliability::BestEffort)
                    )
                {
                    node.warn(format!("{}: a publisher appeared offering best effort; the recorder reads this topic reliably, so it does not match and its messages are not recorded (restart the recorder, or give the topic best_effort in a QoS overrides file)", t.name));
                }
            }
            continue;
        }
        if recording.has_topic(&t.name) {
            continue;
        }
        let offered = offered_qos_of_topic(publications.iter().copied(), &dds);
        for p in publications.iter().filter(|p| p.topic_name == dds) {
            known_writers.insert(format!("{:?}", p.key));
        }
        let definition = recording
            .add_topic(&t.name, &t.type_name, &offered_qos_yaml(&offered))
            .map_err(|e| e.to_string())?;
        let depth = if metrocell_bagtools::is_bulk_type(&t.type_name) {
            settings.bulk_queue_depth
        } else {
            settings.queue_depth
        };
        let adapted = recording_qos(&offered);
        let over = settings.qos_overrides.get(&t.name);
        let qos = reader_qos::reader_qos(adapted, depth, over);
        if let Some(o) = over.filter(|o| !o.ignored.is_empty()) {
            node.warn(format!(
                "{}: QoS override keys {} do not apply to a recorder's reader; ignored",
                t.name,
                o.ignored.join(", ")
            ));
        }
        let sub = node
            .raw_subscription(&t.name, &t.type_name, qos.clone())
            .map_err(|e| e.to_string())?;
        taker.add(sub);
        topics.push(t.name.clone());
        let reliable = matches!(
            qos.reliability,
            ros2_client::qos::Reliability::Reliable { .. }
        );
        let kept = match qos.history {
            ros2_client::qos::History::KeepLast { depth } => depth,
            ros2_client::qos::History::KeepAll => 0,
        };
        readers.insert(t.name.clone(), (reliable, kept));
        let how = if reliable { "reliable" } else { "best effort" };
        match definition {
            TopicDefinition::Known => node.info(format!("recording {} ({}, {how})", t.name, t.type_name)),
            TopicDefinition::Unknown => node.warn(format!(
                "recording {} ({}, {how}) as raw CDR without a definition: metrocell does not know this type, so bag readers get the bytes but cannot decode them without it",
                t.name, t.type_name
            )),
        }
    }
    Ok(())
}
