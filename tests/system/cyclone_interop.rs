//! Interop on the wire with Cyclone DDS (the DDS that ROS 2 ships), through its Python binding:
//! - a Cyclone participant receives metrocell's messages on `rt/<topic>` under the ROS 2 DDS type
//!   name and decodes every field equal to what was sent;
//! - metrocell receives and decodes what Cyclone publishes, typed and through `metrocell topic echo`.

use std::io::{BufRead, BufReader};
use std::time::{Duration, Instant};

use metrocell_msgs::RosMessage;
use metrocell_node::{qos, MetrocellNode};
use system_tests::{
    bin, json_close, piped, python, require_isolated_network, ros2_peer, run, ChildGuard,
};

fn node(name: &str) -> MetrocellNode {
    MetrocellNode::builder(name)
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap()
}

fn sample_json<T: RosMessage>(seed: u64) -> serde_json::Value {
    rosmsg::to_json(&rosmsg::sample_value(metrocell_msgs::registry(), T::ROS_TYPE, seed).unwrap())
}

/// metrocell publishes (typed), Cyclone listens and prints JSON.
fn metrocell_to_cyclone<T: RosMessage>(topic: &str) {
    let expected = sample_json::<T>(3);
    let msg: T = serde_json::from_value(expected.clone()).unwrap();
    let mut listener = ChildGuard::spawn(piped(python()).arg(ros2_peer()).args([
        "listen",
        "--topic",
        topic,
        "--type",
        T::ROS_TYPE,
        "--count",
        "1",
        "--timeout",
        "30",
    ]));
    let mut n = node("to_cyclone");
    let publisher = n.publisher::<T>(topic, qos::reliable()).unwrap();
    let stdout = listener.child().stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = BufReader::new(stdout).read_line(&mut line);
        let _ = tx.send(line);
    });
    let deadline = Instant::now() + Duration::from_secs(30);
    let line = loop {
        publisher.publish(msg.clone()).unwrap();
        if let Ok(line) = rx.recv_timeout(Duration::from_millis(250)) {
            break line;
        }
        assert!(
            Instant::now() < deadline,
            "Cyclone received nothing on {topic}"
        );
    };
    let got: serde_json::Value =
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("Cyclone printed {line:?}: {e}"));
    json_close(&got, &expected, T::ROS_TYPE).unwrap();
}

#[test]
fn cyclone_decodes_what_metrocell_publishes() {
    require_isolated_network();
    metrocell_to_cyclone::<metrocell_msgs::sensor_msgs::msg::Temperature>("/interop/temperature");
    metrocell_to_cyclone::<metrocell_msgs::msg::TrackerMeasurement>("/interop/tracker");
    metrocell_to_cyclone::<metrocell_msgs::msg::FiducialDetectionArray>("/interop/fiducials");
    metrocell_to_cyclone::<metrocell_msgs::msg::ErrorModel>("/interop/error_model");
    metrocell_to_cyclone::<metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped>(
        "/interop/pose",
    );
}

/// Cyclone publishes the JSON sample; metrocell's typed subscription must decode it equal.
fn cyclone_to_metrocell<T: RosMessage>(topic: &str) {
    let json = sample_json::<T>(5);
    let expected: T = serde_json::from_value(json.clone()).unwrap();
    let mut n = node("from_cyclone");
    let sub = n.subscription::<T>(topic, qos::reliable()).unwrap();
    let _publisher = ChildGuard::spawn(piped(python()).arg(ros2_peer()).args([
        "publish",
        "--topic",
        topic,
        "--type",
        T::ROS_TYPE,
        "--json",
        &json.to_string(),
        "--count",
        "50",
        "--rate",
        "10",
        "--timeout",
        "30",
    ]));
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if let Ok(Some((got, _))) = sub.take() {
            assert_eq!(got, expected, "{}: decoded differently", T::ROS_TYPE);
            return;
        }
        assert!(
            Instant::now() < deadline,
            "{}: nothing from Cyclone within 30 s",
            T::ROS_TYPE
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn metrocell_decodes_what_cyclone_publishes() {
    require_isolated_network();
    cyclone_to_metrocell::<metrocell_msgs::sensor_msgs::msg::Temperature>(
        "/interop/from_cyclone/temperature",
    );
    cyclone_to_metrocell::<metrocell_msgs::msg::TrackerMeasurement>(
        "/interop/from_cyclone/tracker",
    );
    cyclone_to_metrocell::<metrocell_msgs::msg::MeasuredPoint>("/interop/from_cyclone/point");
}

#[test]
fn topic_echo_prints_what_cyclone_publishes() {
    require_isolated_network();
    let json = sample_json::<metrocell_msgs::msg::TrackerMeasurement>(9);
    let _publisher = ChildGuard::spawn(piped(python()).arg(ros2_peer()).args([
        "publish",
        "--topic",
        "/interop/echo",
        "--type",
        "metrocell_msgs/msg/TrackerMeasurement",
        "--json",
        &json.to_string(),
        "--count",
        "100",
        "--rate",
        "10",
        "--timeout",
        "30",
    ]));
    // No --type: echo discovers the type from Cyclone's publication.
    let out = run(
        piped(bin("metrocell")).args([
            "topic",
            "echo",
            "/interop/echo",
            "--json",
            "--count",
            "1",
            "--discovery-timeout",
            "20",
        ]),
        Duration::from_secs(40),
    );
    assert!(
        out.status.success(),
        "echo failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = String::from_utf8(out.stdout).unwrap();
    let got: serde_json::Value =
        serde_json::from_str(line.lines().next().expect("one line")).unwrap();
    json_close(&got, &json, "echo").unwrap();
}
