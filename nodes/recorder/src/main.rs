//! `metrocell-recorder`: records DDS topics into a crash-safe rosbag2 MCAP bag.
//!
//! Subscribes every discovered topic (discovery is re-scanned every second, so late publishers
//! are recorded too), or the `topics` list, or those matching `regex`, minus `exclude`. Payloads
//! are stored as received (raw CDR), with the type's full definition from metrocell's registry;
//! a topic whose type metrocell does not know is skipped with a warning naming the type.
//! log_time = receive time, publish_time = the publisher's DDS source timestamp.
//!
//! QoS: every topic is read best-effort (keep-last `queue_depth`, `bulk_queue_depth` for
//! byte-array types such as images). A best-effort reader matches
//! both reliable and best-effort writers, so nothing is left unrecorded for a QoS mismatch;
//! the consequence is that a sample lost on the wire is not retransmitted to the recorder even
//! when its publisher is reliable. Losses show up as `dropped` (gaps in each publisher's
//! sequence numbers) in the diagnostics and the final log line. Each topic's
//! `offered_qos_profiles` holds the QoS its publishers announced in discovery when recording of
//! the topic began, one profile per publisher, as rosbag2 stores them
//! (`metrocell_bagtools::recorded_qos`); `metrocell bag play` and `ros2 bag play` offer that
//! reliability and durability again (a latched topic replays transient-local).
//!
//! Exit: SIGINT/SIGTERM finish the bag (exit 0). A write failure (disk full) logs the file,
//! stops recording, leaves the bag sealed and valid, exits 1.
//!
//!   metrocell-recorder --ros-args -p output:=run42 -p exclude:="/camera/.*" -p compression:=lz4

mod parameters;

use std::collections::BTreeSet;
use std::hash::{Hash, Hasher};
use std::time::{Duration, Instant};

use metrocell_bag::offered_qos_yaml;
use metrocell_bagtools::recorded_qos::offered_qos_of_topic;
use metrocell_node::names::dds_topic_name;
use metrocell_bagtools::Recording;
use metrocell_node::{qos, MetrocellNode, RawSubscription};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-recorder: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn publisher_key(gid: &impl Hash) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    gid.hash(&mut h);
    h.finish()
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args("recorder", parameters::declarations())?;
    let selection = parameters::selection(&node)?;
    let output = match node.param::<String>("output")? {
        o if o.is_empty() => parameters::default_output(),
        o => o,
    };
    let reader_qos = |depth: i64| qos::sensor_data().history(ros2_client::qos::History::KeepLast { depth: depth.clamp(1, 1_000_000) as usize });
    let (depth, bulk_depth) = (node.param::<i64>("queue_depth")?, node.param::<i64>("bulk_queue_depth")?);
    let mut recording = Recording::create(&output, parameters::writer_options(&node)?)?;
    node.info(format!("recording into {output}"));

    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    let mut subscriptions: Vec<RawSubscription> = Vec::new();
    let mut skipped: BTreeSet<String> = BTreeSet::new();
    let mut next_scan = Instant::now();
    let mut failure = None;
    'record: while !token.is_triggered() {
        if Instant::now() >= next_scan {
            next_scan += Duration::from_secs(1);
            // Publishers declare what is sent; a reader may declare another type on the same topic.
            // Their offered QoS is read only when a topic is new (most scans find none).
            let mut writers = None;
            for t in node.discovered_publications() {
                if !selection.matches(&t.name) || recording.has_topic(&t.name) || skipped.contains(&t.name) {
                    continue;
                }
                let writers = writers.get_or_insert_with(|| node.context().domain_participant().discovered_writers());
                let offered = offered_qos_of_topic(writers.iter().map(|w| &w.publication_topic_data), &dds_topic_name(&t.name));
                if !recording.add_topic(&t.name, &t.type_name, &offered_qos_yaml(&offered))? {
                    node.warn(format!("not recording {}: metrocell does not know its type {}", t.name, t.type_name));
                    skipped.insert(t.name);
                    continue;
                }
                let qos = reader_qos(if parameters::is_bulk_type(&t.type_name) { bulk_depth } else { depth });
                subscriptions.push(node.raw_subscription(&t.name, &t.type_name, qos)?);
                node.info(format!("recording {} ({})", t.name, t.type_name));
            }
            for (topic, c) in recording.counts() {
                diagnostics.set_value(&format!("{topic}/messages"), c.messages);
                diagnostics.set_value(&format!("{topic}/dropped"), c.dropped);
            }
            diagnostics.set_value("messages", recording.total_messages());
            diagnostics.set_value("dropped", recording.total_dropped());
        }
        let mut received = 0usize;
        for sub in &subscriptions {
            while let Some(m) = sub.take()? {
                received += 1;
                let log = m.receive_time_ns.max(0) as u64;
                let publish = m.source_time_ns.map_or(log, |t| t.max(0) as u64);
                if let Err(e) = recording.record(sub.topic(), log, publish, &m.payload, publisher_key(&m.publisher_gid), m.sequence_number) {
                    failure = Some(e);
                    break 'record;
                }
            }
        }
        if let Err(e) = recording.tick() {
            failure = Some(e);
            break;
        }
        if received == 0 {
            token.wait_timeout(Duration::from_millis(1));
        }
    }
    let summary = format!("{} messages recorded, {} dropped", recording.total_messages(), recording.total_dropped());
    if let Some(e) = failure {
        let file = recording.current_file().map(|p| p.display().to_string()).unwrap_or_else(|| output.clone());
        node.error(format!("recording stopped: {e} (file {file}); {summary}"));
        diagnostics.error(format!("write failed: {e}"));
        return Err(format!("recording into {file} stopped: {e}").into());
    }
    recording.finish()?;
    node.info(format!("bag {output} finished: {summary}"));
    Ok(())
}
