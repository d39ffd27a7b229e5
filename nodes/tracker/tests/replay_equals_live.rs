//! Twin → tracker node over DDS, and the same input offline:
//! * end to end: every dwell of the twin's program appears once on `measured_points` with its
//!   program nominal (after the tracker pose is registered from the first 12 targets);
//! * `metrocell-tracker --bag` gives the same `measured_points`, `tracker/dwells` and
//!   `/tf_static` as the live node, bit for bit.
//!
//! Run: `tests/isolated cargo test -p metrocell-tracker-node --test replay_equals_live`

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_bagtools::BagSource;
use metrocell_msgs::msg::{MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_msgs::tf2_msgs::msg::TFMessage;
use metrocell_msgs::RosMessage;
use metrocell_node::{qos, MetrocellNode};

mod common;
use common::{inputs, record_twin, wait_for_tracker, Input};
use metrocell_node::testing::KillOnDrop as Killed;
use nalgebra::Vector3;

const ARGS: [&str; 5] = [
    "--ros-args",
    "-p",
    "tool_offset:=[0.0, 0.0, -0.1]",
    "-p",
    "registration_points:=12",
];

fn read<T: RosMessage>(bag: &Path, topic: &str) -> Vec<T> {
    let mut s = BagSource::open(bag).unwrap();
    assert!(s.subscribe::<T>(topic).unwrap(), "output has no {topic}");
    s.messages()
        .unwrap()
        .map(|m| m.unwrap().decode::<T>().unwrap())
        .collect()
}

#[test]
fn twin_to_tracker_over_dds_equals_replay_and_measures_every_dwell_once() {
    metrocell_node::testing::require_isolated_network();
    let tmp = std::env::temp_dir().join(format!("metrocell-tracker-live-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let input = tmp.join("input");
    let cell = record_twin(&input);
    let inputs = inputs(&input);
    let program = cell.program.clone();
    let nominal = |i: usize| {
        cell.machine.nominal_tool_point(&Vector3::new(
            program.points[i][0],
            program.points[i][1],
            program.points[i][2],
        ))
    };
    let expected: Vec<(usize, Vector3<f64>)> = program
        .segments
        .iter()
        .filter_map(|s| s.dwell_point)
        .map(|i| (i, nominal(i)))
        .collect();

    // --- live
    let _node = Killed(
        Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
            .args(ARGS)
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let mut machine = MetrocellNode::builder("tracker_test_twin")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let readings = machine
        .publisher::<TrackerMeasurement>("/tracker/measurements", qos::reliable())
        .unwrap();
    let commanded = machine
        .publisher::<JointState>("/machine/commanded_joint_states", qos::sensor_data())
        .unwrap();
    let points_sub = machine
        .subscription::<MeasuredPoint>("/measured_points", qos::reliable())
        .unwrap();
    let dwells_sub = machine
        .subscription::<TrackerMeasurement>("/tracker/dwells", qos::reliable())
        .unwrap();
    let tf_sub = machine
        .subscription::<TFMessage>("/tf_static", qos::latched())
        .unwrap();
    wait_for_tracker(&machine);
    let (mut live_points, mut live_dwells, mut live_tf) =
        (BTreeMap::new(), BTreeMap::new(), Vec::new());
    let collect = |points: &mut BTreeMap<i64, MeasuredPoint>,
                   dwells: &mut BTreeMap<i64, TrackerMeasurement>,
                   tf: &mut Vec<TFMessage>| {
        while let Ok(Some((p, _))) = points_sub.take() {
            assert!(
                points.insert(p.header.stamp.nanos(), p).is_none(),
                "a point published twice"
            );
        }
        while let Ok(Some((d, _))) = dwells_sub.take() {
            dwells.insert(d.header.stamp.nanos(), d);
        }
        while let Ok(Some((t, _))) = tf_sub.take() {
            tf.push(t);
        }
    };
    for i in &inputs {
        match i {
            Input::Reading(m) => {
                let _ = readings.publish(m.clone());
            }
            Input::Commanded(j) => {
                let _ = commanded.publish(j.clone());
            }
        }
        // paced so that the reliable keep-last-10 queue never overflows
        std::thread::sleep(Duration::from_millis(3));
        collect(&mut live_points, &mut live_dwells, &mut live_tf);
    }
    let deadline = Instant::now() + Duration::from_secs(10);
    while live_points.len() < expected.len() && Instant::now() < deadline {
        collect(&mut live_points, &mut live_dwells, &mut live_tf);
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    collect(&mut live_points, &mut live_dwells, &mut live_tf);

    // --- end to end: every dwell once, with its nominal, in program order
    let ids: Vec<(usize, Vector3<f64>)> = live_points
        .values()
        .map(|p| {
            (
                p.point_id.strip_prefix("point_").unwrap().parse().unwrap(),
                Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z),
            )
        })
        .collect();
    assert_eq!(
        ids.len(),
        expected.len(),
        "measured points {:?}",
        ids.iter().map(|x| x.0).collect::<Vec<_>>()
    );
    for ((i, n), (ei, en)) in ids.iter().zip(&expected) {
        assert_eq!(i, ei);
        assert!(
            (n - en).norm() < 1e-12,
            "point_{i}: nominal {n:?} vs {en:?}"
        );
    }
    for p in live_points.values() {
        let d = Vector3::new(
            p.measured.x - p.nominal.x,
            p.measured.y - p.nominal.y,
            p.measured.z - p.nominal.z,
        );
        assert!(
            d.norm() < 100e-6,
            "{}: measured − nominal {d:?} beyond the cell's machine errors",
            p.point_id
        );
    }
    assert_eq!(live_tf.len(), 1, "one registration");

    // --- offline
    let output = tmp.join("output");
    let status = Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(ARGS)
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    let points: BTreeMap<i64, MeasuredPoint> = read::<MeasuredPoint>(&output, "/measured_points")
        .into_iter()
        .map(|p| (p.header.stamp.nanos(), p))
        .collect();
    let dwells: BTreeMap<i64, TrackerMeasurement> =
        read::<TrackerMeasurement>(&output, "/tracker/dwells")
            .into_iter()
            .map(|d| (d.header.stamp.nanos(), d))
            .collect();
    let tf: Vec<TFMessage> = read(&output, "/tf_static");
    assert_eq!(
        live_points, points,
        "live and replay measured_points differ"
    );
    assert_eq!(live_dwells, dwells, "live and replay tracker/dwells differ");
    assert_eq!(live_tf, tf, "live and replay /tf_static differ");
    let _ = std::fs::remove_dir_all(&tmp);
}
