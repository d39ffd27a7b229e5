//! `metrocell-probe --bag` gives the same outputs as the live node over DDS. The input bag: six
//! triggers along different approach directions, a nominal before four of them, and one trigger
//! missing an axis (rejected: no hit, no count). Live, this test plays the machine: nominal, then
//! trigger, waiting for each hit. ProbeHits and MeasuredPoints must be bit-identical.
//!
//! Run: `tests/isolated cargo test -p metrocell-probe-node --test replay_equals_live`

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_bag::{qos_profiles_yaml, BagWriter, QosProfile, WriterOptions};
use metrocell_bagtools::{encode_cdr, BagSource};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::{Point, PointStamped};
use metrocell_msgs::msg::{MeasuredPoint, ProbeHit};
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::testing::KillOnDrop as Killed;
use metrocell_node::{qos, MetrocellNode};
use rosmsg::RosMessage;

const T0: u64 = 1_700_000_000_000_000_000;
const MS: u64 = 1_000_000;

fn header(ns: u64) -> Header {
    Header {
        stamp: Time::from_nanos(ns as i64),
        frame_id: "machine".into(),
    }
}

fn stamp_ns(h: &Header) -> u64 {
    h.stamp.nanos() as u64
}

enum Input {
    Nominal(PointStamped),
    Trigger(JointState),
}

/// (log time, input) in time order.
fn inputs() -> Vec<(u64, Input)> {
    let mut v = Vec::new();
    for k in 0..6u64 {
        let t = T0 + (k + 1) * 200 * MS;
        let a = k as f64 * 1.1;
        let (x, y, z) = (
            0.1 + 0.01 * a.cos(),
            0.2 + 0.01 * a.sin(),
            0.05 - 0.001 * k as f64,
        );
        if k != 2 && k != 4 {
            v.push((
                t - 50 * MS,
                Input::Nominal(PointStamped {
                    header: header(t - 50 * MS),
                    point: Point { x, y, z },
                }),
            ));
        }
        let mut names = vec!["x".to_string(), "y".into(), "z".into()];
        if k == 3 {
            names[1] = "q".into(); // missing axis y: rejected
        }
        v.push((
            t,
            Input::Trigger(JointState {
                header: header(t),
                name: names,
                position: vec![x + 1e-5, y - 2e-5, z],
                velocity: vec![a.cos(), a.sin(), -0.2],
                effort: vec![],
            }),
        ));
    }
    v
}

fn write_input_bag(dir: &Path, inputs: &[(u64, Input)]) {
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    w.add_topic(
        "/replay/probe/nominal",
        PointStamped::ROS_TYPE,
        PointStamped::DEFINITION,
        &qos,
    )
    .unwrap();
    w.add_topic(
        "/replay/probe/trigger",
        JointState::ROS_TYPE,
        JointState::DEFINITION,
        &qos,
    )
    .unwrap();
    for (t, i) in inputs {
        match i {
            Input::Nominal(n) => w
                .write("/replay/probe/nominal", *t, *t, &encode_cdr(n).unwrap())
                .unwrap(),
            Input::Trigger(j) => w
                .write("/replay/probe/trigger", *t, *t, &encode_cdr(j).unwrap())
                .unwrap(),
        }
    }
    w.finish().unwrap();
}

const ARGS: [&str; 9] = [
    "--ros-args",
    "-r",
    "__ns:=/replay",
    "-p",
    "stylus_radius:=0.002",
    "-p",
    "pretravel:=[8e-6, 2e-6, 0.0, 5e-6]",
    "-p",
    "probe_id:=ts1",
];

#[test]
fn replay_from_bag_equals_live_run_over_dds() {
    metrocell_node::testing::require_isolated_network();
    let tmp = std::env::temp_dir().join(format!("metrocell-probe-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let inputs = inputs();
    let input = tmp.join("input");
    write_input_bag(&input, &inputs);

    // --- live
    let _node = Killed(
        Command::new(env!("CARGO_BIN_EXE_metrocell-probe"))
            .args(ARGS)
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let mut machine = MetrocellNode::builder("replay_test_machine")
        .namespace("/replay")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let nominal_pub = machine
        .publisher::<PointStamped>("probe/nominal", qos::reliable())
        .unwrap();
    let trigger_pub = machine
        .publisher::<JointState>("probe/trigger", qos::reliable())
        .unwrap();
    let hit_sub = machine
        .subscription::<ProbeHit>("probe/hits", qos::reliable())
        .unwrap();
    let point_sub = machine
        .subscription::<MeasuredPoint>("measured_points", qos::reliable())
        .unwrap();
    // Reliable endpoints: wait until the node's subscriptions are matched before publishing.
    let deadline = Instant::now() + Duration::from_secs(20);
    while machine
        .discovered_topics()
        .iter()
        .filter(|t| t.name.ends_with("probe/hits"))
        .count()
        == 0
    {
        assert!(Instant::now() < deadline, "probe node not discovered");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_secs(1));
    let (mut live_hits, mut live_points) = (BTreeMap::new(), BTreeMap::new());
    let collect = |hits: &mut BTreeMap<u64, ProbeHit>,
                   points: &mut BTreeMap<u64, MeasuredPoint>| {
        while let Ok(Some((h, _))) = hit_sub.take() {
            hits.insert(stamp_ns(&h.header), h);
        }
        while let Ok(Some((p, _))) = point_sub.take() {
            points.insert(stamp_ns(&p.header), p);
        }
    };
    for (_, i) in &inputs {
        match i {
            Input::Nominal(n) => {
                let _ = nominal_pub.publish(n.clone());
                // Let the nominal arrive before its trigger, as the bag's order has it.
                std::thread::sleep(Duration::from_millis(100));
            }
            Input::Trigger(j) => {
                let _ = trigger_pub.publish(j.clone());
                let s = stamp_ns(&j.header);
                let wait =
                    Instant::now() + Duration::from_secs(if j.name[1] == "y" { 10 } else { 1 });
                while Instant::now() < wait && !live_hits.contains_key(&s) {
                    collect(&mut live_hits, &mut live_points);
                    std::thread::sleep(Duration::from_millis(5));
                }
            }
        }
    }
    std::thread::sleep(Duration::from_millis(300));
    collect(&mut live_hits, &mut live_points);

    // --- offline
    let output = tmp.join("output");
    let status = Command::new(env!("CARGO_BIN_EXE_metrocell-probe"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(ARGS)
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "metrocell-probe --bag failed: {status}");
    let mut source = BagSource::open(&output).unwrap();
    source.subscribe::<ProbeHit>("/replay/probe/hits").unwrap();
    source
        .subscribe::<MeasuredPoint>("/replay/measured_points")
        .unwrap();
    let (mut hits, mut points) = (BTreeMap::new(), BTreeMap::new());
    for m in source.messages().unwrap() {
        let m = m.unwrap();
        if m.topic.ends_with("hits") {
            let h: ProbeHit = m.decode().unwrap();
            assert_eq!(m.log_time_ns, stamp_ns(&h.header));
            hits.insert(stamp_ns(&h.header), h);
        } else {
            let p: MeasuredPoint = m.decode().unwrap();
            points.insert(stamp_ns(&p.header), p);
        }
    }

    // 6 triggers, one rejected; nominals before triggers 0, 1, 3 (rejected: its nominal goes with
    // it, so trigger 4 has none) and 5.
    assert_eq!(hits.len(), 5, "replay hits at {:?}", hits.keys());
    let ids: Vec<&str> = points.values().map(|p| p.point_id.as_str()).collect();
    assert_eq!(ids, ["ts1_1", "ts1_2", "ts1_5"]);
    // Each point is measured against the nominal stamped 50 ms before its own trigger.
    for p in points.values() {
        let k = inputs
            .iter()
            .position(|(t, i)| matches!(i, Input::Trigger(_)) && *t == stamp_ns(&p.header))
            .unwrap();
        match &inputs[k - 1].1 {
            Input::Nominal(n) => assert_eq!(p.nominal, n.point, "{}", p.point_id),
            Input::Trigger(_) => panic!("{} has a nominal but its trigger had none", p.point_id),
        }
    }
    // Every hit is compensated as documented (nodes/probe/src/compensation.rs), recomputed here
    // from the trigger alone: u = velocity / |velocity|, φ = atan2(u_y, u_x), 3 lobes,
    // pt = (1 − u_z²)(p₀ + a cos 3φ + b sin 3φ) + u_z² p_z, s = axes + (r − pt)·u. The pretravel is
    // a few µm here, so the 1e-12 m tolerance sees it (and its sign).
    let (r, [p0, a, b, pz]) = (0.002, [8e-6, 2e-6, 0.0, 5e-6]);
    for (t, h) in &hits {
        let Some((_, Input::Trigger(j))) = inputs
            .iter()
            .find(|(ti, i)| matches!(i, Input::Trigger(_)) && ti == t)
        else {
            panic!("hit at {t} without a trigger")
        };
        let n = (j.velocity[0].powi(2) + j.velocity[1].powi(2) + j.velocity[2].powi(2)).sqrt();
        let u = [j.velocity[0] / n, j.velocity[1] / n, j.velocity[2] / n];
        let phi = u[1].atan2(u[0]);
        let pt = (1.0 - u[2] * u[2]) * (p0 + a * (3.0 * phi).cos() + b * (3.0 * phi).sin())
            + u[2] * u[2] * pz;
        assert!(
            (h.pretravel - pt).abs() < 1e-15,
            "hit at {t}: pretravel {} m, expected {pt} m",
            h.pretravel
        );
        assert!(
            pt > 1e-6,
            "fixture: pretravel {pt} m is too small to be seen"
        );
        let expect = [0, 1, 2].map(|k| j.position[k] + (r - pt) * u[k]);
        let got = [h.surface_point.x, h.surface_point.y, h.surface_point.z];
        for k in 0..3 {
            assert!(
                (got[k] - expect[k]).abs() < 1e-12,
                "hit at {t}: surface point {got:?}, expected {expect:?}"
            );
        }
    }
    assert_eq!(live_hits, hits, "live and replay ProbeHits differ");
    assert_eq!(live_points, points, "live and replay MeasuredPoints differ");
    let _ = std::fs::remove_dir_all(&tmp);
}

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> std::path::PathBuf {
    let tmp = std::env::temp_dir().join(format!("metrocell-probe-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    tmp
}

/// A bag writer at `dir` with a JointState trigger topic named `topic`.
fn trigger_bag(dir: &Path, topic: &str) -> BagWriter {
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    w.add_topic(topic, JointState::ROS_TYPE, JointState::DEFINITION, &qos)
        .unwrap();
    w
}

/// A trigger at t on x, y, z, approaching along −z.
fn trigger(t: u64) -> JointState {
    JointState {
        header: header(t),
        name: vec!["x".into(), "y".into(), "z".into()],
        position: vec![0.1, 0.2, 0.05],
        velocity: vec![0.0, 0.0, -1.0],
        effort: vec![],
    }
}

/// A malformed trigger in the bag (bytes that are not a JointState) is reported with its topic
/// and log time and skipped; the replay goes on and the output bag holds every valid trigger's hit.
#[test]
fn replay_skips_a_malformed_message_and_keeps_going() {
    let tmp = scratch("replay-bad");
    let input = tmp.join("input");
    let mut w = trigger_bag(&input, "/replay/probe/trigger");
    w.write(
        "/replay/probe/trigger",
        T0,
        T0,
        &encode_cdr(&trigger(T0)).unwrap(),
    )
    .unwrap();
    let bad_time = T0 + 100 * MS;
    w.write(
        "/replay/probe/trigger",
        bad_time,
        bad_time,
        &[0, 1, 0, 0, 0xff, 0xff, 0xff, 0x7f],
    )
    .unwrap();
    w.write(
        "/replay/probe/trigger",
        T0 + 200 * MS,
        T0 + 200 * MS,
        &encode_cdr(&trigger(T0 + 200 * MS)).unwrap(),
    )
    .unwrap();
    w.finish().unwrap();

    let output = tmp.join("output");
    let run = Command::new(env!("CARGO_BIN_EXE_metrocell-probe"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(ARGS)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        run.status.success(),
        "replay stopped on a malformed message: {stderr}"
    );
    assert!(
        stderr.contains("/replay/probe/trigger") && stderr.contains(&bad_time.to_string()),
        "warning does not name topic and log time: {stderr}"
    );
    let mut source = BagSource::open(&output).unwrap();
    source.subscribe::<ProbeHit>("/replay/probe/hits").unwrap();
    let hits: Vec<u64> = source
        .messages()
        .unwrap()
        .map(|m| m.unwrap().log_time_ns)
        .collect();
    assert_eq!(hits, [T0, T0 + 200 * MS]);
    let _ = std::fs::remove_dir_all(&tmp);
}

/// SIGINT during a replay: the node stops between messages, finishes its output bag (readable,
/// every hit it wrote is there, in order, from the first trigger on) and exits non-zero saying
/// where it stopped.
#[test]
fn an_interrupted_replay_finishes_its_output_bag() {
    let tmp = scratch("replay-int");
    let input = tmp.join("input");
    let n = 300_000u64;
    let mut w = trigger_bag(&input, "/replay/probe/trigger");
    for k in 0..n {
        let t = T0 + k * MS;
        w.write(
            "/replay/probe/trigger",
            t,
            t,
            &encode_cdr(&trigger(t)).unwrap(),
        )
        .unwrap();
    }
    w.finish().unwrap();

    let output = tmp.join("output");
    let child = Command::new(env!("CARGO_BIN_EXE_metrocell-probe"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(ARGS)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The output bag is created after the signal handler is installed and before the first message.
    let deadline = Instant::now() + Duration::from_secs(60);
    while !output.exists() {
        assert!(
            Instant::now() < deadline,
            "the replay never created its output"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
    // let it write some hits first (the summary figure below), then interrupt
    std::thread::sleep(Duration::from_millis(150));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let run = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && stderr.contains("interrupted before the message at log time"),
        "{}: {stderr}",
        run.status
    );
    let mut source = BagSource::open(&output)
        .unwrap_or_else(|e| panic!("interrupted output is not a readable bag: {e}"));
    source.subscribe::<ProbeHit>("/replay/probe/hits").unwrap();
    let hits: Vec<u64> = source
        .messages()
        .unwrap()
        .map(|m| m.unwrap().log_time_ns)
        .collect();
    println!("interrupted after {} of {n} triggers", hits.len());
    assert!(
        !hits.is_empty(),
        "no hit was written in the 150 ms before the signal: the output bag holds nothing to check"
    );
    assert!(
        (hits.len() as u64) < n,
        "the replay finished before the signal: make the input longer"
    );
    assert!(
        hits.iter()
            .enumerate()
            .all(|(k, t)| *t == T0 + k as u64 * MS),
        "hits are the first triggers, in order"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}

/// A bag without the node's input topic: the replay says which topic is missing and what the bag
/// holds, writes an empty (readable) output and succeeds.
#[test]
fn a_bag_without_the_input_topic_is_named() {
    let tmp = scratch("replay-missing");
    let input = tmp.join("input");
    trigger_bag(&input, "/machine/probe/trigger")
        .finish()
        .unwrap();
    let output = tmp.join("output");
    let run = Command::new(env!("CARGO_BIN_EXE_metrocell-probe"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(ARGS)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("has no topic /replay/probe/trigger")
            && stderr.contains("/machine/probe/trigger")
            && stderr.contains("-r"),
        "{stderr}"
    );
    assert!(BagSource::open(&output).is_ok());
    let _ = std::fs::remove_dir_all(&tmp);
}
