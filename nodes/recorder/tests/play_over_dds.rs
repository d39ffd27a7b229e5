//! `metrocell bag play` re-publishes a bag with the recorded spacing ÷ rate, remapped, with
//! /clock; a subscriber in this process receives every message unchanged.
//!
//! Needs the `metrocell` binary next to this package's binary (build it with
//! `cargo build -p metrocell-cli`) or its path in `METROCELL_CLI`.

use std::process::Command;
use std::time::{Duration, Instant};

mod common;

use common::{cli, python, writers_of};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_msgs::RosMessage;
use metrocell_node::{qos, MetrocellNode};

const TYPE: &str = "sensor_msgs/msg/Temperature";

fn payload(i: usize) -> Vec<u8> {
    let v = rosmsg::from_json(
        metrocell_msgs::registry(),
        TYPE,
        &serde_json::json!({"header": {"frame_id": "play"}, "temperature": i as f64}),
    )
    .unwrap();
    rosmsg::encode(metrocell_msgs::registry(), TYPE, &v).unwrap()
}

#[test]
fn play_keeps_spacing_over_rate_and_delivers_every_message() {
    metrocell_node::testing::require_isolated_network();
    let dir = std::env::temp_dir().join(format!("play_it_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // Written with the mcap crate directly, as another tool would: the writer of crates/bag
    // refuses QoS text that is not YAML, but a bag from elsewhere may carry it. Topic
    // /play_test/damaged_qos has such a profile text: it is played with the default QoS, with a
    // warning, instead of stopping the whole playback.
    let _ = std::fs::create_dir_all(&dir);
    let file = dir.join("play_it.mcap");
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&file).unwrap(),
    ))
    .unwrap();
    let def = metrocell_msgs::sensor_msgs::msg::Temperature::DEFINITION;
    let schema = w.add_schema(TYPE, "ros2msg", def.as_bytes()).unwrap();
    let channel = |w: &mut mcap::Writer<_>, topic: &str, qos: &str| {
        let md = [("offered_qos_profiles".to_string(), qos.to_string())]
            .into_iter()
            .collect();
        w.add_channel(schema, topic, "cdr", &md).unwrap()
    };
    let a = channel(&mut w, "/play_test/a", "");
    let damaged = channel(&mut w, "/play_test/damaged_qos", "- reliability: [unclosed");
    let n = 40;
    let spacing_ns = 50_000_000u64; // 50 ms recorded
    let t0 = 1_700_000_000_000_000_000u64;
    let header = |channel_id: u16, sequence: u32, t: u64| mcap::records::MessageHeader {
        channel_id,
        sequence,
        log_time: t,
        publish_time: t,
    };
    w.write_to_known_channel(&header(damaged, 1, t0 + 1), &payload(0))
        .unwrap();
    for i in 0..n {
        let t = t0 + i as u64 * spacing_ns;
        w.write_to_known_channel(&header(a, i as u32 + 1, t), &payload(i))
            .unwrap();
    }
    w.finish().unwrap();
    drop(w);

    let mut node = MetrocellNode::builder("play_test_sub")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let sub = node
        .raw_subscription("/replayed", TYPE, qos::reliable())
        .unwrap();
    let clock = node
        .subscription::<Clock>("/clock", qos::reliable())
        .unwrap();
    let play = Command::new(cli())
        .args([
            "bag",
            "play",
            file.to_str().unwrap(),
            "--rate",
            "2",
            "--delay",
            "2",
            "--remap",
            "/play_test/a:=/replayed",
            "--clock",
            "50",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut got = Vec::new();
    let mut clocks = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    while got.len() < n && Instant::now() < deadline {
        while let Some(m) = sub.take().unwrap() {
            got.push((Instant::now(), m));
        }
        while let Ok(Some((c, _))) = clock.take() {
            clocks.push(c.clock.nanos() as u64);
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let played = play.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&played.stderr);
    assert!(played.status.success(), "{stderr}");
    assert!(
        stderr.contains("offered_qos_profiles of topic /play_test/damaged_qos")
            && stderr.contains("default QoS"),
        "no warning for the damaged QoS text: {stderr}"
    );
    assert_eq!(got.len(), n, "every message received");
    for (i, (_, m)) in got.iter().enumerate() {
        assert_eq!(m.payload, payload(i), "message {i} unchanged and in order");
        // RTPS timestamps have 2^-32 s resolution: equal within 1 ns.
        let stamp = m.source_time_ns.expect("stamped");
        assert!(
            (stamp - (t0 + i as u64 * spacing_ns) as i64).abs() <= 1,
            "source stamp {stamp} = recorded publish time of message {i}"
        );
    }
    // Recorded 39 × 50 ms = 1.95 s at rate 2 → 0.975 s.
    let span = got.last().unwrap().0.duration_since(got[0].0).as_secs_f64();
    assert!(
        (span - 0.975).abs() < 0.1,
        "played span {span:.3} s, expected 0.975 s ± 0.1"
    );
    let gaps: Vec<f64> = got
        .windows(2)
        .map(|w| w[1].0.duration_since(w[0].0).as_secs_f64())
        .collect();
    let median = {
        let mut g = gaps.clone();
        g.sort_by(f64::total_cmp);
        g[g.len() / 2]
    };
    assert!(
        (median - 0.025).abs() < 0.008,
        "median gap {median:.4} s, expected 0.025 s"
    );
    assert!(
        clocks.len() >= 10,
        "/clock published ({} received)",
        clocks.len()
    );
    assert!(
        clocks.iter().all(|c| (t0..=t0 + 2_000_000_000).contains(c)),
        "/clock within the bag's time range"
    );
}

/// A bag written by Python `rosbags` (metadata v9, standard types, a latched topic) is played
/// over DDS: every Temperature and PointStamped arrives with the field values the script wrote,
/// and the latched topic is offered transient-local, so a subscriber that joins after it was
/// published still receives it.
#[test]
fn rosbags_written_bag_plays_with_equal_fields_and_latched_topic_replays_latched() {
    use metrocell_msgs::geometry_msgs::msg::PointStamped;
    use metrocell_msgs::sensor_msgs::msg::Temperature;
    use metrocell_msgs::std_msgs::msg::String as RosString;
    use rustdds::policy::{Durability, Reliability};

    metrocell_node::testing::require_isolated_network();
    let dir = std::env::temp_dir().join(format!("play_rosbags_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let n = 100;
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/py/write_rosbags_std_types.py");
    let out = Command::new(python())
        .arg(&script)
        .arg(&dir)
        .arg(n.to_string())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "rosbags writer failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );

    let mut node = MetrocellNode::builder("play_rosbags_sub")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let temps = node
        .subscription::<Temperature>("/rb/temperature", qos::reliable())
        .unwrap();
    let points = node
        .subscription::<PointStamped>("/rb/point", qos::reliable())
        .unwrap();
    let mut play = Command::new(cli())
        .args(["bag", "play", dir.to_str().unwrap(), "--delay", "2"])
        .spawn()
        .unwrap();

    let (mut got_t, mut got_p, mut late_latched) = (Vec::new(), Vec::new(), Vec::new());
    let mut late = None;
    let mut offers = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(25);
    while (got_t.len() < n || got_p.len() < n || late_latched.is_empty())
        && Instant::now() < deadline
    {
        while let Some((m, _)) = temps.take().unwrap() {
            got_t.push(m);
        }
        while let Some((m, _)) = points.take().unwrap() {
            got_p.push(m);
        }
        // The latched message was published 1 s (bag time) before the first temperature:
        // subscribe only now, and with transient-local durability it must still arrive.
        if late.is_none() && !got_t.is_empty() {
            offers = writers_of(&node, "/rb/latched")
                .into_iter()
                .map(|w| (w.durability, w.reliability))
                .collect();
            late = Some(
                node.subscription::<RosString>("/rb/latched", qos::latched())
                    .unwrap(),
            );
        }
        if let Some(s) = &late {
            while let Some((m, _)) = s.take().unwrap() {
                late_latched.push(m.data);
            }
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(play.wait().unwrap().success());
    assert_eq!(
        (got_t.len(), got_p.len()),
        (n, n),
        "every Temperature and PointStamped received"
    );
    for (i, t) in got_t.iter().enumerate() {
        assert_eq!(
            (t.header.stamp.sec, t.header.stamp.nanosec),
            (1000 + i as i32, i as u32 * 1000),
            "temperature {i} stamp"
        );
        assert_eq!(t.header.frame_id, format!("probe{}", i % 3));
        assert_eq!(
            (t.temperature, t.variance),
            (20.0 + 0.25 * i as f64, 0.01 * i as f64),
            "temperature {i} values"
        );
    }
    for (i, p) in got_p.iter().enumerate() {
        assert_eq!(
            (
                p.header.stamp.sec,
                p.header.stamp.nanosec,
                p.header.frame_id.as_str()
            ),
            (2000 + i as i32, 7, "tracker")
        );
        assert_eq!(
            (p.point.x, p.point.y, p.point.z),
            (0.1 * i as f64, -0.2 * i as f64, 1e-6 * i as f64),
            "point {i}"
        );
    }
    assert!(
        !offers.is_empty(),
        "bag play's /rb/latched writer discovered"
    );
    assert!(
        offers
            .iter()
            .all(|(d, r)| *d == Some(Durability::TransientLocal)
                && matches!(r, Some(Reliability::Reliable { .. }))),
        "offered {offers:?}"
    );
    assert_eq!(
        late_latched,
        ["cell model v3"],
        "late transient-local subscriber got the latched message once"
    );
}
