//! A flood on one topic (issue 31, item 2): a publisher sends 64 KiB images best effort as
//! fast as it can while another sends a reliable status at 20 Hz; the recorder node records
//! both. The status loses nothing (the flood does not starve it), the recorder's memory stays
//! bounded (its queues and its cache are bounded: it levels off instead of growing with the
//! flood), and what the flood lost is counted — the recorder's final account (recorded +
//! missing) against what was sent.
//!
//! Run: `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-system-tests --test flood -- --nocapture`

use std::io::{BufRead, BufReader};
use std::process::Stdio;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use metrocell_bag::{BagReader, MessageFilter};
use metrocell_node::{qos, MetrocellNode, RawPublisher};
use system_tests::{bin, interrupt, piped, require_isolated_network, ChildGuard};

const DOMAIN: &str = "95";
const FLOOD_SECONDS: f64 = 8.0;

fn encode(ty: &str, json: serde_json::Value) -> Vec<u8> {
    let reg = metrocell_msgs::registry();
    rosmsg::encode(reg, ty, &rosmsg::from_json(reg, ty, &json).unwrap()).unwrap()
}

fn rss_bytes(pid: i32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

fn wait_matched(p: &RawPublisher) {
    let deadline = Instant::now() + Duration::from_secs(30);
    while p.matched_subscriptions() < 1 {
        assert!(
            Instant::now() < deadline,
            "{}: the recorder did not subscribe within 30 s",
            p.topic()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_flooded_topic_starves_nothing_and_the_recorders_memory_levels_off() {
    require_isolated_network();
    std::env::set_var("ROS_DOMAIN_ID", DOMAIN);
    let dir = std::env::temp_dir().join(format!("flood_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut recorder = ChildGuard::spawn(
        piped(bin("metrocell-recorder"))
            .args(["--ros-args", "-p"])
            .arg(format!("output:={}", dir.display()))
            .args([
                "-p",
                "regex:=/flood_test/.*",
                "-p",
                "scan_interval:=0.2",
                "-p",
                "max_cache_size:=16777216",
            ])
            .env("ROS_DOMAIN_ID", DOMAIN)
            .stderr(Stdio::piped()),
    );
    let pid = recorder.pid();
    let stderr = recorder.child().stderr.take().unwrap();
    let (tx, log) = mpsc::channel::<String>();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            eprintln!("  | {line}");
            let _ = tx.send(line);
        }
    });
    let mut node = MetrocellNode::builder("flood_test_pub")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let blob = node
        .raw_publisher(
            "/flood_test/blob",
            "sensor_msgs/msg/Image",
            qos::sensor_data(),
        )
        .unwrap();
    let status = node
        .raw_publisher("/flood_test/status", "std_msgs/msg/String", qos::reliable())
        .unwrap();
    wait_matched(&blob);
    wait_matched(&status);
    std::thread::sleep(Duration::from_millis(500));
    let image = encode(
        "sensor_msgs/msg/Image",
        serde_json::json!({"height": 128, "width": 512, "encoding": "mono8", "step": 512, "data": vec![7u8; 128 * 512]}),
    );
    let sent = Arc::new(AtomicU64::new(0));
    let stop = Arc::new(AtomicBool::new(false));
    let flood = {
        let (sent, stop) = (sent.clone(), stop.clone());
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                if blob.publish(&image).is_ok() {
                    sent.fetch_add(1, Ordering::Relaxed);
                }
            }
            blob
        })
    };
    let start = Instant::now();
    let mut rss = vec![];
    let mut k = 0u32;
    let mut next = start;
    while start.elapsed().as_secs_f64() < FLOOD_SECONDS {
        status
            .publish(&encode(
                "std_msgs/msg/String",
                serde_json::json!({"data": format!("status {k}")}),
            ))
            .unwrap();
        k += 1;
        if let Some(r) = rss_bytes(pid) {
            rss.push((start.elapsed().as_secs_f64(), r));
        }
        next += Duration::from_millis(50);
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    stop.store(true, Ordering::Relaxed);
    let _blob = flood.join().unwrap();
    let sent = sent.load(Ordering::Relaxed);
    std::thread::sleep(Duration::from_secs(2)); // the reliable status's last repairs
    interrupt(pid);
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut summary = String::new();
    let mut flood_line = String::new();
    while Instant::now() < deadline {
        match log.recv_timeout(Duration::from_millis(200)) {
            Ok(line) if line.contains("finished:") => summary = line,
            Ok(line) if line.contains("/flood_test/blob:") && line.contains("missing") => {
                flood_line = line
            }
            Ok(_) => {}
            Err(_) => {
                if recorder.child().try_wait().unwrap().is_some() {
                    break;
                }
            }
        }
    }
    assert!(
        recorder
            .child()
            .try_wait()
            .unwrap()
            .is_some_and(|s| s.success()),
        "the recorder finishes its bag on SIGINT"
    );
    // what the bag holds
    let reader = BagReader::open(&dir).unwrap();
    let mut statuses = vec![];
    let mut blobs = 0u64;
    for m in reader.read_all(&MessageFilter::default()).unwrap() {
        match m.topic.as_str() {
            "/flood_test/status" => statuses.push(m.data),
            "/flood_test/blob" => blobs += 1,
            _ => {}
        }
    }
    let missing: u64 = flood_line
        .split_whitespace()
        .zip(flood_line.split_whitespace().skip(1))
        .find(|(_, w)| w.starts_with("missing"))
        .and_then(|(n, _)| n.parse().ok())
        .unwrap_or(0);
    let max_rss = rss.iter().map(|r| r.1).max().unwrap_or(0);
    let rss_at = |t: f64| rss.iter().find(|r| r.0 >= t).map(|r| r.1).unwrap_or(0);
    println!(
        "flood: {sent} images of 64 KiB sent in {FLOOD_SECONDS} s ({:.0} MB/s), {blobs} recorded, {missing} counted missing ({} unaccounted); status: {k} sent, {} recorded; recorder RSS {:.0} MB at 2 s, {:.0} MB at 4 s, {:.0} MB at the end, {:.0} MB at most\n{summary}",
        sent as f64 * 65.6e3 / FLOOD_SECONDS / 1e6,
        sent.saturating_sub(blobs + missing),
        statuses.len(),
        rss_at(2.0) as f64 / 1e6,
        rss_at(4.0) as f64 / 1e6,
        rss.last().map(|r| r.1).unwrap_or(0) as f64 / 1e6,
        max_rss as f64 / 1e6
    );
    // nothing of the reliable topic is starved out
    assert_eq!(statuses.len() as u32, k, "every status recorded");
    // memory levels off: its bounded queues and cache, not the flood's length
    assert!(max_rss < 600 << 20, "recorder RSS {max_rss}");
    assert!(
        rss.last().unwrap().1 < rss_at(FLOOD_SECONDS / 2.0) + (64 << 20),
        "the recorder's memory grew through the second half of the flood: {:?}",
        rss.iter()
            .map(|r| (r.0 as u32, r.1 >> 20))
            .collect::<Vec<_>>()
    );
    // the flood's losses are counted: recorded + missing accounts for what was sent but the
    // last samples lost on the wire after the last received one (no later sample shows the gap)
    assert!(blobs + missing <= sent, "{blobs} + {missing} > {sent}");
    assert!(
        sent - (blobs + missing) <= sent / 100 + 1000,
        "{} of {sent} unaccounted",
        sent - blobs - missing
    );
    assert!(blobs > 0);
    let _ = std::fs::remove_dir_all(&dir);
}
