//! Interop with Cyclone DDS (the DDS ROS 2 ships), via its Python binding: a metrocell node
//! publishes std_msgs/Header that Cyclone reads, and reads back (typed and raw) what Cyclone writes.
//! Needs the Python from `METROCELL_PYTHON` (or `<workspace>/.venv/bin/python`, made by `tests/run`).

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::{qos, testing::require_isolated_network, MetrocellNode};

fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    assert!(
        venv.exists(),
        "no Python with cyclonedds: set METROCELL_PYTHON or run tests/run (creates .venv)"
    );
    venv
}

#[test]
fn cyclone_dds_reads_and_writes_our_topics() {
    require_isolated_network();
    let script =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/peers/cyclone_header_peer.py");
    let mut peer = Command::new(python())
        .arg(script)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("start python");
    let stdout = peer.stdout.take().unwrap();
    let (line_tx, line_rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            let _ = line_tx.send(line);
        }
    });

    let (b, _) = MetrocellNode::builder("interop_node")
        .handle_signals(false)
        .args(["t"])
        .unwrap();
    let mut node = b.build().unwrap();
    let p = node
        .publisher::<Header>("/metrocell_interop/from_rust", qos::reliable())
        .unwrap();
    let typed = node
        .subscription::<Header>("/metrocell_interop/from_cyclone", qos::reliable())
        .unwrap();
    let raw = node
        .raw_subscription(
            "/metrocell_interop/from_cyclone",
            "std_msgs/msg/Header",
            qos::reliable(),
        )
        .unwrap();

    let sent = Header {
        stamp: Time {
            sec: 41,
            nanosec: 123_456_789,
        },
        frame_id: "tracker_base".into(),
    };
    let start = Instant::now();
    let (mut cyclone_line, mut typed_back, mut raw_back) = (None, None, None);
    while start.elapsed() < Duration::from_secs(20)
        && (cyclone_line.is_none() || typed_back.is_none() || raw_back.is_none())
    {
        if cyclone_line.is_none() {
            p.publish(sent.clone()).unwrap();
        }
        if let Ok(l) = line_rx.try_recv() {
            cyclone_line = Some(l);
        }
        if let Some((m, _)) = typed.take().unwrap() {
            typed_back = Some(m);
        }
        if let Some(m) = raw.take().unwrap() {
            raw_back = Some(m);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = peer.kill();
    let _ = peer.wait();
    assert_eq!(
        cyclone_line.as_deref(),
        Some("GOT 41 123456789 tracker_base")
    );
    let expected = Header {
        stamp: Time {
            sec: 42,
            nanosec: 123_456_789,
        },
        frame_id: "cyclone:tracker_base".into(),
    };
    assert_eq!(typed_back, Some(expected));
    let raw_back = raw_back.expect("raw subscription got nothing from Cyclone");
    let frame = b"cyclone:tracker_base\0";
    assert_eq!(
        &raw_back.payload[..4],
        &[0, 1, 0, 0],
        "Cyclone writes CDR little-endian"
    );
    assert_eq!(&raw_back.payload[4..8], &42i32.to_le_bytes());
    assert_eq!(
        &raw_back.payload[12..16],
        &(frame.len() as u32).to_le_bytes()
    );
    assert_eq!(&raw_back.payload[16..16 + frame.len()], frame);
    assert!(raw_back.source_time_ns.is_some());
}
