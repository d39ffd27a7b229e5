//! The recorder binary over DDS (private network namespace): `exclude`, a publisher that
//! appears after the recorder started, splitting by size and by duration, and the loss
//! accounting fed by real DDS sequence gaps.
//!
//! Run: `tests/isolated cargo test -p metrocell-recorder-node --test selection_split_losses`

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_bag::{BagMetadata, BagReader, MessageFilter};
use metrocell_node::{qos, MetrocellNode, RawPublisher};

const TYPE: &str = "sensor_msgs/msg/Temperature";

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("recorder_sel_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn payload(i: usize) -> Vec<u8> {
    let v = rosmsg::from_json(
        metrocell_msgs::registry(),
        TYPE,
        &serde_json::json!({"header": {"frame_id": format!("p{i}")}, "temperature": i as f64}),
    )
    .unwrap();
    rosmsg::encode(metrocell_msgs::registry(), TYPE, &v).unwrap()
}

fn start_recorder(dir: &Path, params: &[&str]) -> Child {
    let mut c = Command::new(env!("CARGO_BIN_EXE_metrocell-recorder"));
    c.args([
        "--ros-args",
        "-p",
        &format!("output:={}", dir.display()),
        "-p",
        "flush_interval:=0.2",
        "-p",
        "scan_interval:=0.2",
    ]);
    for p in params {
        c.args(["-p", p]);
    }
    c.stderr(Stdio::piped()).spawn().unwrap()
}

fn wait_matched(publishers: &[&RawPublisher]) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while publishers.iter().any(|p| p.matched_subscriptions() == 0) {
        assert!(
            Instant::now() < deadline,
            "recorder did not subscribe within 20 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// SIGINT, wait, return stderr (the recorder's log).
fn stop(recorder: Child) -> String {
    assert!(Command::new("kill")
        .args(["-INT", &recorder.id().to_string()])
        .status()
        .unwrap()
        .success());
    let out = recorder.wait_with_output().unwrap();
    let log = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        out.status.success(),
        "recorder exits 0 on SIGINT; log:\n{log}"
    );
    log
}

fn count(dir: &Path, topic: &str) -> Vec<Vec<u8>> {
    let r = BagReader::open(dir).unwrap();
    r.read_all(&MessageFilter {
        topics: Some(vec![topic.into()]),
        ..Default::default()
    })
    .unwrap()
    .into_iter()
    .map(|m| m.data)
    .collect()
}

fn publisher(name: &str) -> MetrocellNode {
    MetrocellNode::builder(name)
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap()
}

#[test]
fn exclude_drops_matching_topics_and_a_late_publisher_is_recorded_completely() {
    metrocell_node::testing::require_isolated_network();
    let dir = scratch("exclude_late");
    let mut node = publisher("recorder_sel_pub");
    let keep = node
        .raw_publisher("/sel_test/keep", TYPE, qos::reliable())
        .unwrap();
    let skip = node
        .raw_publisher("/sel_test/debug/skip", TYPE, qos::reliable())
        .unwrap();
    let recorder = start_recorder(
        &dir,
        &["regex:=/sel_test/.*", "exclude:=/sel_test/debug/.*"],
    );
    wait_matched(&[&keep]);
    let n = 200;
    for i in 0..n {
        keep.publish(&payload(i)).unwrap();
        skip.publish(&payload(i)).unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    // A publisher that appears 1 s after recording began, on a new topic.
    std::thread::sleep(Duration::from_secs(1));
    let late = node
        .raw_publisher("/sel_test/late", TYPE, qos::reliable())
        .unwrap();
    wait_matched(&[&late]);
    for i in 0..n {
        late.publish(&payload(1000 + i)).unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(
        skip.matched_subscriptions(),
        0,
        "excluded topic never subscribed"
    );
    std::thread::sleep(Duration::from_millis(500));
    stop(recorder);
    let meta = BagMetadata::read_dir(&dir).unwrap();
    let mut topics: Vec<&str> = meta
        .topics_with_message_count
        .iter()
        .map(|t| t.topic_metadata.name.as_str())
        .filter(|t| t.starts_with("/sel_test"))
        .collect();
    topics.sort();
    assert_eq!(
        topics,
        ["/sel_test/keep", "/sel_test/late"],
        "excluded topic absent"
    );
    assert_eq!(
        count(&dir, "/sel_test/keep"),
        (0..n).map(payload).collect::<Vec<_>>()
    );
    assert_eq!(
        count(&dir, "/sel_test/late"),
        (0..n).map(|i| payload(1000 + i)).collect::<Vec<_>>(),
        "late publisher: every message, in order"
    );
}

#[test]
fn splits_by_size_and_by_duration_keep_every_message_once() {
    metrocell_node::testing::require_isolated_network();
    let mut node = publisher("recorder_split_pub");
    let by_size = node
        .raw_publisher("/split_test/size", TYPE, qos::reliable())
        .unwrap();
    let by_time = node
        .raw_publisher("/split_test/time", TYPE, qos::reliable())
        .unwrap();
    let size_dir = scratch("split_size");
    let time_dir = scratch("split_time");
    let size_rec = start_recorder(
        &size_dir,
        &[
            "regex:=/split_test/size",
            "compression:=none",
            "max_bag_size:=40000",
        ],
    );
    let time_rec = start_recorder(
        &time_dir,
        &["regex:=/split_test/time", "max_bag_duration:=1.0"],
    );
    wait_matched(&[&by_size, &by_time]);
    let n = 700;
    let start = Instant::now();
    for i in 0..n {
        by_size.publish(&payload(i)).unwrap();
        by_time.publish(&payload(i)).unwrap();
        // 700 messages over ~3.5 s
        let due = start + Duration::from_millis(5 * (i as u64 + 1));
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
    }
    std::thread::sleep(Duration::from_millis(500));
    stop(size_rec);
    stop(time_rec);

    let all: Vec<Vec<u8>> = (0..n).map(payload).collect();
    let size_meta = BagMetadata::read_dir(&size_dir).unwrap();
    let bytes: u64 = all.iter().map(|p| p.len() as u64 + 30).sum();
    assert!(
        size_meta.files.len() >= (bytes / 40000) as usize,
        "{} files for ≥ {bytes} bytes at 40000 per file",
        size_meta.files.len()
    );
    assert!(size_meta.files.len() >= 2);
    for f in &size_meta.files {
        let len = std::fs::metadata(size_dir.join(&f.path)).unwrap().len();
        // A file is closed at the first message past the limit: one chunk of slack.
        assert!(len < 40000 + 8192, "{} is {len} bytes", f.path);
    }
    assert_eq!(
        count(&size_dir, "/split_test/size"),
        all,
        "size split: every message once, in order"
    );

    let time_meta = BagMetadata::read_dir(&time_dir).unwrap();
    assert!(
        (3..=5).contains(&time_meta.files.len()),
        "3.5 s at 1 s per file: {} files",
        time_meta.files.len()
    );
    for f in &time_meta.files {
        assert!(
            f.duration.nanoseconds <= 1_000_000_000,
            "{} spans {} ns > 1 s",
            f.path,
            f.duration.nanoseconds
        );
    }
    assert_eq!(
        time_meta.files.iter().map(|f| f.message_count).sum::<u64>(),
        n as u64
    );
    assert_eq!(
        count(&time_dir, "/split_test/time"),
        all,
        "duration split: every message once, in order"
    );
}

/// A best-effort burst into a recorder whose reader keeps only the newest sample: the samples
/// overwritten before the recorder took them leave gaps in the publisher's sequence numbers,
/// which the recorder reports as dropped — and recorded + dropped is exactly what was sent.
#[test]
fn dropped_counts_real_sequence_gaps_exactly() {
    metrocell_node::testing::require_isolated_network();
    let dir = scratch("gaps");
    let mut node = publisher("recorder_gap_pub");
    let burst = node
        .raw_publisher("/gap_test/burst", TYPE, qos::sensor_data())
        .unwrap();
    let recorder = start_recorder(&dir, &["regex:=/gap_test/.*", "queue_depth:=1"]);
    wait_matched(&[&burst]);
    // A first sample alone, so the recorder's count for this publisher starts at sequence 1.
    std::thread::sleep(Duration::from_millis(300));
    burst.publish(&payload(0)).unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let n = 20_000;
    for i in 1..n {
        burst.publish(&payload(i)).unwrap();
    }
    // A last sample after a pause, so a gap at the end of the burst is seen too.
    std::thread::sleep(Duration::from_millis(300));
    burst.publish(&payload(n)).unwrap();
    std::thread::sleep(Duration::from_millis(500));
    let log = stop(recorder);
    let recorded = count(&dir, "/gap_test/burst");
    let line = log
        .lines()
        .find(|l| l.trim_start().starts_with("/gap_test/burst:"))
        .unwrap_or_else(|| panic!("per-topic loss line in the log:\n{log}"));
    let gaps: u64 = line
        .split("missing: ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("gap count in {line:?}"));
    assert!(
        line.contains("sequence gaps") && line.contains("best effort"),
        "cause named: {line}"
    );
    assert!(
        line.contains("largest: ") && line.contains(" UTC ("),
        "the largest gaps named by time: {line}"
    );
    assert!(
        log.contains("messages missing from the bag (sequence gaps): /gap_test/burst: "),
        "the gaps reported as they were found:\n{log}"
    );
    assert!(
        gaps > 0,
        "a 20000-sample burst into a queue of 1 loses some: {line}"
    );
    assert_eq!(
        recorded.len() as u64 + gaps,
        n as u64 + 1,
        "recorded {} + dropped {gaps} = sent {}",
        recorded.len(),
        n + 1
    );
    assert_eq!(
        (recorded.first(), recorded.last()),
        (Some(&payload(0)), Some(&payload(n))),
        "first and tail samples recorded"
    );
    assert!(
        log.contains(&format!("{} missing", gaps)),
        "total in the summary: {log}"
    );
}
