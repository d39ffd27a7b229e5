//! `metrocell-thermal --bag` gives the same numbers as the live node fed by `metrocell bag play`,
//! and much faster than real time.
//!
//! The bag: 1 s of temperatures alone, then 2 s with points every 200 ms. Sensor x_left steps
//! 20 → 21 → 22 °C each second, x_right stays at 21 °C, so every error model value belongs to one
//! of three states and the states last far longer than the model period (50 ms) in both runs.
//! Points fall 50 ms after temperature updates so no point races a temperature change.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_bag::{qos_profiles_yaml, BagWriter, QosProfile, WriterOptions};
use metrocell_bagtools::{encode_cdr, BagSource};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::testing::KillOnDrop as Killed;
use metrocell_node::{qos, MetrocellNode};
use rosmsg::RosMessage;

const T0: u64 = 1_700_000_000_000_000_000;
const MS: u64 = 1_000_000;
const BAG_SECONDS: f64 = 3.0;

fn stamp(ns: u64) -> Time {
    Time::from_nanos(ns as i64)
}

fn write_input_bag(dir: &Path) {
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    for t in ["/rt/temperature/x_left", "/rt/temperature/x_right"] {
        w.add_topic(t, Temperature::ROS_TYPE, Temperature::DEFINITION, &qos)
            .unwrap();
    }
    w.add_topic(
        "/rt/measured_points",
        MeasuredPoint::ROS_TYPE,
        MeasuredPoint::DEFINITION,
        &qos,
    )
    .unwrap();
    let mut events: Vec<(u64, &str, Vec<u8>)> = Vec::new();
    for k in 0..30u64 {
        let t = T0 + k * 100 * MS;
        let header = Header {
            stamp: stamp(t),
            frame_id: "machine".into(),
        };
        let left = Temperature {
            header: header.clone(),
            temperature: 20.0 + (k / 10) as f64,
            variance: 0.01,
        };
        let right = Temperature {
            header,
            temperature: 21.0,
            variance: 0.0025,
        };
        events.push((t, "/rt/temperature/x_left", encode_cdr(&left).unwrap()));
        events.push((t, "/rt/temperature/x_right", encode_cdr(&right).unwrap()));
    }
    for j in 0..10u64 {
        let t = T0 + 1050 * MS + j * 200 * MS;
        let x = 0.08 * j as f64;
        let mut cov = [0.0; 9];
        (cov[0], cov[4], cov[8]) = (1e-10, 2e-10, 3e-10);
        let p = MeasuredPoint {
            header: Header {
                stamp: stamp(t),
                frame_id: "machine".into(),
            },
            point_id: format!("p{j}"),
            source: "tracker".into(),
            nominal: Point { x, y: 0.1, z: 0.2 },
            measured: Point {
                x: x + 1e-5 * j as f64,
                y: 0.1 + 2e-6,
                z: 0.2 - 3e-6,
            },
            covariance: cov,
        };
        events.push((t, "/rt/measured_points", encode_cdr(&p).unwrap()));
    }
    events.sort_by_key(|e| e.0);
    for (t, topic, cdr) in events {
        w.write(topic, t, t, &cdr).unwrap();
    }
    w.finish().unwrap();
}

fn thermal_args() -> Vec<&'static str> {
    vec![
        "--ros-args",
        "-r",
        "__ns:=/rt",
        "-p",
        "sensors:=[x_left, x_right]",
        "-p",
        "sensor_axes:=[x, x]",
        "-p",
        "sensor_positions:=[0.0, 0.8]",
        "-p",
        "publish_period:=0.05",
    ]
}

/// `metrocell` from the same target directory as this test.
fn metrocell_cli() -> PathBuf {
    let thermal = PathBuf::from(env!("CARGO_BIN_EXE_metrocell-thermal"));
    let cli = thermal.with_file_name("metrocell");
    assert!(
        cli.exists(),
        "{} is not built: run `cargo build -p metrocell-cli` in the same target directory first",
        cli.display()
    );
    cli
}

/// Model values as exact bit patterns, so "equal" means the same floating-point numbers.
fn model_key(m: &ErrorModel) -> Vec<(String, u64)> {
    m.parameter_names
        .iter()
        .cloned()
        .zip(m.values.iter().map(|v| v.to_bits()))
        .collect()
}

#[test]
fn replay_from_bag_equals_live_run_over_dds() {
    metrocell_node::testing::require_isolated_network();
    let cli = metrocell_cli();
    let tmp = std::env::temp_dir().join(format!("metrocell-thermal-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let input = tmp.join("input");
    write_input_bag(&input);

    // --- live: thermal node + bag play over DDS, outputs taken by this test's own node
    let mut listener = MetrocellNode::builder("replay_test_listener")
        .namespace("/rt")
        .handle_signals(false)
        .build()
        .unwrap();
    let points_sub = listener
        .subscription::<MeasuredPoint>("measured_points/thermal_compensated", qos::reliable())
        .unwrap();
    let model_sub = listener
        .subscription::<ErrorModel>("thermal/error_model", qos::reliable())
        .unwrap();
    let _thermal = Killed(
        Command::new(env!("CARGO_BIN_EXE_metrocell-thermal"))
            .args(thermal_args())
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    std::thread::sleep(Duration::from_secs(3)); // discovery between the node, the listener and the player
    let mut play = Killed(
        Command::new(&cli)
            .args(["bag", "play"])
            .arg(&input)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let mut live_points: BTreeMap<String, MeasuredPoint> = BTreeMap::new();
    let mut live_models: BTreeSet<Vec<(String, u64)>> = BTreeSet::new();
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut play_done_at: Option<Instant> = None;
    while Instant::now() < deadline
        && play_done_at.is_none_or(|t| t.elapsed() < Duration::from_secs(1))
    {
        while let Ok(Some((p, _))) = points_sub.take() {
            live_points.insert(p.point_id.clone(), p);
        }
        while let Ok(Some((m, _))) = model_sub.take() {
            live_models.insert(model_key(&m));
        }
        if play_done_at.is_none() && play.0.try_wait().unwrap().is_some() {
            play_done_at = Some(Instant::now());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(
        play_done_at.is_some(),
        "bag play did not finish within 30 s"
    );

    // --- offline: the same node on the bag
    let output = tmp.join("output");
    let started = Instant::now();
    let status = Command::new(env!("CARGO_BIN_EXE_metrocell-thermal"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(thermal_args())
        .status()
        .unwrap();
    let replay_seconds = started.elapsed().as_secs_f64();
    assert!(status.success(), "metrocell-thermal --bag failed: {status}");

    let mut source = BagSource::open(&output).unwrap();
    source
        .subscribe::<MeasuredPoint>("/rt/measured_points/thermal_compensated")
        .unwrap();
    source
        .subscribe::<ErrorModel>("/rt/thermal/error_model")
        .unwrap();
    let mut replay_points: BTreeMap<String, MeasuredPoint> = BTreeMap::new();
    let mut replay_models: BTreeSet<Vec<(String, u64)>> = BTreeSet::new();
    for m in source.messages().unwrap() {
        let m = m.unwrap();
        if m.topic.ends_with("thermal_compensated") {
            let p: MeasuredPoint = m.decode().unwrap();
            replay_points.insert(p.point_id.clone(), p);
        } else {
            replay_models.insert(model_key(&m.decode::<ErrorModel>().unwrap()));
        }
    }

    // every point compensated offline; the live run may lose none of the reliable points
    assert_eq!(
        replay_points.len(),
        10,
        "replay compensated {:?}",
        replay_points.keys()
    );
    // p9 at x = 0.72 m with x_left at 21 °C: the correction is tens of µm, so equality below is not trivial
    assert!(
        (replay_points["p9"].measured.x - (0.72 + 9e-5)).abs() > 1e-6,
        "p9 was not compensated"
    );
    assert_eq!(
        live_points.len(),
        10,
        "live run compensated {:?}",
        live_points.keys()
    );
    for (id, live) in &live_points {
        assert_eq!(
            live, &replay_points[id],
            "point {id}: live and replay differ"
        );
    }
    // three temperature states → three error models, the same numbers in both runs
    assert_eq!(
        replay_models.len(),
        3,
        "replay error models: {replay_models:?}"
    );
    assert_eq!(
        live_models, replay_models,
        "live and replay error models differ"
    );

    let speedup = BAG_SECONDS / replay_seconds;
    eprintln!("replay of a {BAG_SECONDS} s bag took {replay_seconds:.3} s wall (process start included): {speedup:.0}x real time");
    assert!(speedup > 5.0, "replay only {speedup:.1}x real time");
    let _ = std::fs::remove_dir_all(&tmp);
}
